//! The content-addressed unit cache: `<dir>/units/<k0k1>/<key>.unit`.
//!
//! A unit file is `BAKERUNT` (8 bytes), version u32 LE = 1, the 32-byte key, the payload
//! length u64 LE, the CRC-32 of the payload, then the payload: one zstd frame of the
//! result in `postcard` (a Rust-internal cache format). Files are written to a temporary
//! name, fsynced and renamed, so a killed bake leaves either a whole unit or none; a file that
//! fails any check is treated as missing and recomputed.

use std::path::{Path, PathBuf};

use anyhow::Context;

use super::Key;
use crate::output::atomic;

const MAGIC: &[u8; 8] = b"BAKERUNT";
const VERSION: u32 = 1;
const HEADER: usize = 8 + 4 + 32 + 8 + 4;

/// `--force` recomputes every unit (and overwrites the cache); `Off` neither reads nor writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CacheMode {
    Use,
    Force,
    Off,
}

#[derive(Debug, Clone)]
pub struct Cache {
    pub dir: PathBuf,
    pub mode: CacheMode,
}

impl Cache {
    pub fn new(dir: impl Into<PathBuf>, mode: CacheMode) -> Cache {
        Cache {
            dir: dir.into(),
            mode,
        }
    }

    /// Where the unit of `key` lives.
    pub fn path(&self, key: &Key) -> PathBuf {
        unit_path(&self.dir, key)
    }

    /// The cached result, if present and intact.
    pub fn load<T: serde::de::DeserializeOwned>(&self, key: &Key) -> Option<T> {
        if self.mode != CacheMode::Use {
            return None;
        }
        let bytes = std::fs::read(self.path(key)).ok()?;
        decode(&bytes, key)
    }

    /// Stores a result (atomically).
    pub fn store<T: serde::Serialize>(&self, key: &Key, value: &T) -> anyhow::Result<()> {
        if self.mode == CacheMode::Off {
            return Ok(());
        }
        let raw = postcard::to_stdvec(value).context("serialising a unit result")?;
        let payload = zstd::bulk::compress(&raw, 1).context("compressing a unit result")?;
        let mut out = Vec::with_capacity(HEADER + payload.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&key.0);
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        out.extend_from_slice(&formats::table::crc32(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        let p = self.path(key);
        atomic::write(&p, &out).with_context(|| format!("writing {}", p.display()))
    }

    /// Every unit file under the cache, with its key.
    pub fn list(&self) -> Vec<(Key, PathBuf)> {
        let mut out = Vec::new();
        let Ok(dirs) = std::fs::read_dir(self.dir.join("units")) else {
            return out;
        };
        for d in dirs.flatten() {
            let Ok(files) = std::fs::read_dir(d.path()) else {
                continue;
            };
            for f in files.flatten() {
                let p = f.path();
                let key = p
                    .file_name()
                    .and_then(|n| n.to_str())
                    .and_then(|n| n.strip_suffix(".unit"))
                    .and_then(Key::from_hex);
                if let Some(k) = key {
                    out.push((k, p));
                }
            }
        }
        out.sort();
        out
    }
}

pub fn unit_path(dir: &Path, key: &Key) -> PathBuf {
    let hex = key.hex();
    dir.join("units")
        .join(&hex[..2])
        .join(format!("{hex}.unit"))
}

/// Checks and decodes a unit file; `None` for anything damaged or of another key.
pub fn decode<T: serde::de::DeserializeOwned>(bytes: &[u8], key: &Key) -> Option<T> {
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        return None;
    }
    if u32::from_le_bytes(bytes[8..12].try_into().ok()?) != VERSION || bytes[12..44] != key.0 {
        return None;
    }
    let len = u64::from_le_bytes(bytes[44..52].try_into().ok()?);
    let crc = u32::from_le_bytes(bytes[52..56].try_into().ok()?);
    let payload = &bytes[HEADER..];
    if payload.len() as u64 != len || formats::table::crc32(payload) != crc {
        return None;
    }
    let raw = zstd::stream::decode_all(payload).ok()?;
    postcard::from_bytes(&raw).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_damage_is_a_miss() {
        let dir = tempfile::tempdir().unwrap();
        let c = Cache::new(dir.path(), CacheMode::Use);
        let k = super::super::KeyBuilder::new("test", &[0; 32])
            .part("x", &1.5f64)
            .finish();
        let v = vec![1.0f64, -0.0, f64::MIN_POSITIVE, 3.25];
        c.store(&k, &v).unwrap();
        let back: Vec<f64> = c.load(&k).unwrap();
        assert_eq!(
            back.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(c.list().len(), 1);
        // A flipped byte anywhere, a truncation or another key: treated as missing.
        let p = c.path(&k);
        let good = std::fs::read(&p).unwrap();
        for i in [0, 9, 20, 50, good.len() - 1] {
            let mut b = good.clone();
            b[i] ^= 0x40;
            assert!(decode::<Vec<f64>>(&b, &k).is_none(), "byte {i}");
        }
        assert!(decode::<Vec<f64>>(&good[..good.len() - 3], &k).is_none());
        let other = super::super::KeyBuilder::new("test", &[0; 32])
            .part("x", &2.0f64)
            .finish();
        assert!(decode::<Vec<f64>>(&good, &other).is_none());
        assert!(Cache::new(dir.path(), CacheMode::Force)
            .load::<Vec<f64>>(&k)
            .is_none());
    }
}
