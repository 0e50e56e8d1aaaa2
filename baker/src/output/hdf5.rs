//! HDF5 writer for [`Tables`]: one group per entry, f64 datasets (shuffle + deflate), `units`
//! and `description` attributes, and HDF5 dimension scales (`r_mm`, `lambda_nm`) so h5py shows
//! `ds.dims[i][0]`. Written to a temporary file and renamed: a reader never sees half a file.
//! Creation times are not recorded, so equal tables give equal files.

use std::ffi::CString;
use std::path::Path;
use std::str::FromStr;

use anyhow::Context;
use hdf5_metno as h5;
use hdf5_metno::types::VarLenUnicode;
use hdf5_metno_sys::h5i::hid_t;

use super::tables::{Attr, Dataset, Tables};

// The HDF5 high-level dimension-scale API (libhdf5_hl); hdf5-metno does not wrap it.
extern "C" {
    fn H5DSset_scale(dsid: hid_t, dimname: *const std::ffi::c_char) -> i32;
    fn H5DSattach_scale(did: hid_t, dsid: hid_t, idx: std::ffi::c_uint) -> i32;
}

// Direct chunk writes (HDF5 ≥ 1.10.3; hdf5-metno does not wrap them): the chunk arrives
// already filtered, `filters` = 0 meaning every filter of the dataset's pipeline was applied.
extern "C" {
    fn H5Dwrite_chunk(
        dset_id: hid_t,
        dxpl_id: hid_t,
        filters: u32,
        offset: *const u64,
        data_size: usize,
        buf: *const std::ffi::c_void,
    ) -> i32;
}

/// The deflate level of [`chunked`] datasets. Their chunks are compressed here by zlib-rs
/// ([`write_chunk_f32`]): at level 2 it packs a fiber table's chunks as tightly as the system
/// zlib at level 4 (within 2 %) 1.8–2.8 times faster (measured on a silk sweep's
/// `f_normalised` and `cdf_phi` chunks: 438 and 182 MB/s against 154 and 104 MB/s).
pub const CHUNK_DEFLATE_LEVEL: i32 = 2;

/// Byte planes of an f32 chunk (of 4, lowest first) deflated with zlib's run-length strategy
/// ([`write_chunk_f32`]); the others at [`CHUNK_DEFLATE_LEVEL`] with its default matching.
/// The low two planes hold the mantissa's low bits: zero where a table was rounded to its
/// noise, noise where it was not (a sampling CDF's sums), so string matching finds little
/// there but runs, and costs most of the time. Measured on 100 chunks of a 20-variant
/// cotton sweep at 6° (`validation/bench-runs/2026-12-07-fiber-sweep-writer`): `cdf_phi`
/// 0.589 of its bytes against 0.602 with every plane matched, 1.5 times faster;
/// `f_normalised` 0.1635 against 0.1653, as fast.
pub const RLE_PLANES: usize = 2;

pub(crate) fn text_attr(loc: &h5::Location, name: &str, value: &str) -> anyhow::Result<()> {
    let v = VarLenUnicode::from_str(value).map_err(|e| anyhow::anyhow!("attribute {name}: {e}"))?;
    loc.new_attr::<VarLenUnicode>()
        .create(name)?
        .write_scalar(&v)?;
    Ok(())
}

fn attr(loc: &h5::Location, name: &str, value: &Attr) -> anyhow::Result<()> {
    match value {
        Attr::Text(s) => text_attr(loc, name, s),
        Attr::Float(x) => Ok(loc.new_attr::<f64>().create(name)?.write_scalar(x)?),
        Attr::Count(n) => Ok(loc.new_attr::<u64>().create(name)?.write_scalar(n)?),
    }
}

fn write_dataset(g: &h5::Group, d: &Dataset) -> anyhow::Result<h5::Dataset> {
    let (parent, leaf) = match d.name.rsplit_once('/') {
        Some((p, l)) => {
            let pg = match g.group(p) {
                Ok(x) => x,
                Err(_) => g.create_group_builder().obj_track_times(false).create(p)?,
            };
            (pg, l)
        }
        None => (g.clone(), d.name.as_str()),
    };
    let ds = if d.shape.is_empty() {
        let ds = parent
            .new_dataset::<f64>()
            .obj_track_times(false)
            .shape(())
            .create(leaf)?;
        ds.write_scalar(&d.data[0])?;
        ds
    } else {
        let b = parent
            .new_dataset::<f64>()
            .obj_track_times(false)
            .shape(d.shape.clone());
        let b = if d.data.len() >= 64 {
            b.shuffle().deflate(6)
        } else {
            b
        };
        let ds = b.create(leaf)?;
        ds.write_raw(&d.data[..])?;
        ds
    };
    text_attr(&ds, "units", d.units)?;
    text_attr(&ds, "description", d.description)?;
    if let Some(l) = &d.labels {
        let v: Vec<VarLenUnicode> = l
            .names
            .iter()
            .map(|s| VarLenUnicode::from_str(s).map_err(|e| anyhow::anyhow!("{}: {e}", l.attr)))
            .collect::<anyhow::Result<_>>()?;
        ds.new_attr::<VarLenUnicode>()
            .shape([v.len()])
            .create(l.attr)?
            .write(&v)?;
    }
    Ok(ds)
}

/// Makes `scale` an HDF5 dimension scale named `name` and attaches it to dimension `dim`
/// of each dataset in `targets`.
pub(crate) fn attach_scale(
    scale: &h5::Dataset,
    name: &str,
    targets: &[(&h5::Dataset, u32)],
) -> anyhow::Result<()> {
    let label = CString::new(name)?;
    let rc = h5::sync::sync(|| unsafe { H5DSset_scale(scale.id(), label.as_ptr()) });
    anyhow::ensure!(rc >= 0, "H5DSset_scale({name}) failed");
    for (ds, dim) in targets {
        let rc = h5::sync::sync(|| unsafe { H5DSattach_scale(ds.id(), scale.id(), *dim) });
        anyhow::ensure!(rc >= 0, "H5DSattach_scale({name}) failed");
    }
    Ok(())
}

/// Writes `t` to `path` atomically.
pub fn write(path: &Path, t: &Tables) -> anyhow::Result<()> {
    super::atomic::write_with(path, |tmp| write_to(tmp, t))
        .with_context(|| format!("writing {}", path.display()))
}

fn write_to(path: &Path, t: &Tables) -> anyhow::Result<()> {
    let f = h5::File::with_options()
        .with_fcpl(|p| p.obj_track_times(false))
        .create(path)?;
    for (k, v) in &t.attrs {
        attr(&f, k, v)?;
    }
    for grp in &t.groups {
        let g = f
            .create_group_builder()
            .obj_track_times(false)
            .create(grp.name.as_str())?;
        for (k, v) in &grp.attrs {
            attr(&g, k, v)?;
        }
        let mut written = Vec::new();
        for d in &grp.datasets {
            written.push((d, write_dataset(&g, d)?));
        }
        // Dimension scales: every dataset some dimension names becomes a scale, once.
        let mut scales: Vec<&str> = written
            .iter()
            .flat_map(|(d, _)| d.dims.iter().flatten().copied())
            .collect();
        scales.sort_unstable();
        scales.dedup();
        for s in &scales {
            let Some((_, sd)) = written.iter().find(|(d, _)| d.name == *s) else {
                continue;
            };
            let label = CString::new(*s)?;
            let rc = h5::sync::sync(|| unsafe { H5DSset_scale(sd.id(), label.as_ptr()) });
            anyhow::ensure!(rc >= 0, "H5DSset_scale({s}) failed");
        }
        for (d, ds) in &written {
            for (i, dim) in d.dims.iter().enumerate() {
                let Some(s) = dim else { continue };
                let Some((_, sd)) = written.iter().find(|(d, _)| d.name == *s) else {
                    continue;
                };
                let rc = h5::sync::sync(|| unsafe { H5DSattach_scale(ds.id(), sd.id(), i as u32) });
                anyhow::ensure!(rc >= 0, "H5DSattach_scale({}, {s}) failed", d.name);
            }
        }
    }
    f.close()?;
    Ok(())
}

/// A new HDF5 file at `path` that records no times (equal contents give equal bytes).
pub fn create_file(path: &Path) -> anyhow::Result<h5::File> {
    Ok(h5::File::with_options()
        .with_fcpl(|p| p.obj_track_times(false))
        .create(path)?)
}

/// A new group `name` of `file`, recording no times.
pub fn group(file: &h5::File, name: &str) -> anyhow::Result<h5::Group> {
    Ok(file
        .create_group_builder()
        .obj_track_times(false)
        .create(name)?)
}

/// A dataset of `shape` in chunks of `chunk`, shuffled and deflated
/// ([`CHUNK_DEFLATE_LEVEL`]), recording no times; written chunk by chunk
/// ([`write_chunk_f32`]).
pub fn chunked<T: h5::H5Type>(
    g: &h5::Group,
    name: &str,
    shape: &[usize],
    chunk: &[usize],
) -> anyhow::Result<h5::Dataset> {
    Ok(g.new_dataset::<T>()
        .obj_track_times(false)
        .shape(shape)
        .chunk(chunk)
        .shuffle()
        .deflate(CHUNK_DEFLATE_LEVEL as u8)
        .create(name)?)
}

/// Writes the whole chunk of `ds` (an f32 dataset made by [`chunked`]) that starts at element
/// `offset`, filtered here as the dataset's pipeline would: the bytes of the little-endian
/// values shuffled into planes (HDF5's shuffle filter: byte k of every value, k = 0..4), then
/// one zlib stream (the deflate filter's format). Readers decode it like any other chunk.
pub fn write_chunk_f32(ds: &h5::Dataset, offset: &[usize], values: &[f32]) -> anyhow::Result<()> {
    let chunk = ds
        .chunk()
        .ok_or_else(|| anyhow::anyhow!("{}: not a chunked dataset", ds.name()))?;
    let shape = ds.shape();
    anyhow::ensure!(
        chunk.iter().product::<usize>() == values.len()
            && offset.len() == shape.len()
            && offset
                .iter()
                .zip(&chunk)
                .zip(&shape)
                .all(|((o, c), n)| o % c == 0 && o < n),
        "{}: {} values at {offset:?} are not a chunk {chunk:?} of {shape:?}",
        ds.name(),
        values.len()
    );
    let n = values.len();
    let mut planes = vec![0u8; 4 * n];
    for (i, v) in values.iter().enumerate() {
        for (k, b) in v.to_le_bytes().into_iter().enumerate() {
            planes[k * n + i] = b;
        }
    }
    let bytes = deflate_planes(&planes, RLE_PLANES * n)?;
    let offset: Vec<u64> = offset.iter().map(|&o| o as u64).collect();
    let rc = h5::sync::sync(|| unsafe {
        H5Dwrite_chunk(
            ds.id(),
            hdf5_metno_sys::h5p::H5P_DEFAULT,
            0,
            offset.as_ptr(),
            bytes.len(),
            bytes.as_ptr().cast(),
        )
    });
    anyhow::ensure!(
        rc >= 0,
        "{}: H5Dwrite_chunk at {offset:?} failed",
        ds.name()
    );
    Ok(())
}

/// One zlib stream (RFC 1950) of `data`: its first `rle` bytes deflated with the run-length
/// strategy and ended by a sync flush (a byte-aligned, non-final empty stored block), the rest
/// as a second run of raw deflate blocks at [`CHUNK_DEFLATE_LEVEL`], ending with the final
/// block; then the Adler-32 of the whole. A deflate stream is a sequence of self-delimiting
/// blocks, so any inflater (HDF5's deflate filter, zlib, h5py) reads the two runs as one;
/// the second run's matches never reach back into the first (its compressor starts empty),
/// which only costs ratio.
fn deflate_planes(data: &[u8], rle: usize) -> anyhow::Result<Vec<u8>> {
    use zlib_rs::{Deflate, DeflateConfig, DeflateFlush, Status, Strategy};
    let (lo, hi) = data.split_at(rle.min(data.len()));
    // Header: CM 8 (deflate), a 32 KiB window, FLEVEL 1 ("fast"), FCHECK making it a
    // multiple of 31; footer: 4 bytes. Each run fits in its bound.
    let mut out =
        vec![0u8; 2 + zlib_rs::compress_bound(lo.len()) + zlib_rs::compress_bound(hi.len()) + 4];
    out[..2].copy_from_slice(&[0x78, 0x5e]);
    let mut at = 2;
    let raw = |level, strategy| DeflateConfig {
        level,
        strategy,
        window_bits: -15,
        ..DeflateConfig::default()
    };
    for (part, strategy, flush, end) in [
        (lo, Strategy::Rle, DeflateFlush::SyncFlush, Status::Ok),
        (
            hi,
            Strategy::Default,
            DeflateFlush::Finish,
            Status::StreamEnd,
        ),
    ] {
        let mut z = Deflate::new_with_config(raw(CHUNK_DEFLATE_LEVEL, strategy));
        let status = z
            .compress(part, &mut out[at..], flush)
            .map_err(|e| anyhow::anyhow!("deflate: {}", e.as_str()))?;
        anyhow::ensure!(
            z.total_in() == part.len() as u64 && status == end,
            "deflate stopped early ({status:?})"
        );
        at += z.total_out() as usize;
    }
    out[at..at + 4].copy_from_slice(&zlib_rs::adler32::adler32(1, data).to_be_bytes());
    out.truncate(at + 4);
    Ok(out)
}

/// A contiguous dataset of `shape` holding `data`, recording no times.
pub fn array<T: h5::H5Type>(
    g: &h5::Group,
    name: &str,
    shape: &[usize],
    data: &[T],
) -> anyhow::Result<h5::Dataset> {
    let d = g
        .new_dataset::<T>()
        .obj_track_times(false)
        .shape(shape)
        .create(name)?;
    d.write_raw(data)?;
    Ok(d)
}

/// A 1-D dataset of variable-length strings.
pub fn strings(g: &h5::Group, name: &str, values: &[String]) -> anyhow::Result<h5::Dataset> {
    let v: Vec<VarLenUnicode> = values
        .iter()
        .map(|s| VarLenUnicode::from_str(s).map_err(|e| anyhow::anyhow!("{name}: {e}")))
        .collect::<anyhow::Result<_>>()?;
    array(g, name, &[values.len()], &v)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Chunks filtered here (shuffle, zlib-rs) read back through HDF5's own pipeline as the
    /// values written, whole and by slices; a misplaced or misshapen chunk is refused.
    #[test]
    fn direct_chunks_read_back_through_the_filters() {
        let dir = tempfile::tempdir().unwrap();
        let file = create_file(&dir.path().join("t.h5")).unwrap();
        let g = group(&file, "g").unwrap();
        let ds = chunked::<f32>(&g, "x", &[3, 2, 5], &[1, 2, 5]).unwrap();
        let value = |i: usize, j: usize, k: usize| {
            // Every byte plane varies: signs, exponents and full mantissas.
            (-1f32).powi(k as i32) * (1.0 + 0.37 * (i * 10 + j * 5 + k) as f32).powf(2.7) / 3.0
        };
        for i in [2, 0, 1] {
            let chunk: Vec<f32> = (0..2)
                .flat_map(|j| (0..5).map(move |k| value(i, j, k)))
                .collect();
            write_chunk_f32(&ds, &[i, 0, 0], &chunk).unwrap();
        }
        let back = ds.read_raw::<f32>().unwrap();
        let want: Vec<f32> = (0..3)
            .flat_map(|i| (0..2).flat_map(move |j| (0..5).map(move |k| value(i, j, k))))
            .collect();
        assert_eq!(back, want);
        let row = ds.read_slice_1d::<f32, _>(ndarray::s![1, 1, ..]).unwrap();
        assert_eq!(row.to_vec(), want[15..20].to_vec());
        assert!(write_chunk_f32(&ds, &[1, 1, 0], &want[..10]).is_err());
        assert!(write_chunk_f32(&ds, &[3, 0, 0], &want[..10]).is_err());
        assert!(write_chunk_f32(&ds, &[1, 0, 0], &want[..9]).is_err());
        assert!(write_chunk_f32(&ds, &[1, 0], &want[..10]).is_err());
    }

    /// The two-run zlib stream inflates to its input for any split (none, all, between) and
    /// any content (runs, noise, both, nothing), and a wrong checksum is caught by the
    /// inflater; large chunks of noise fit the output bound.
    #[test]
    fn two_run_streams_inflate_to_their_input() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut noise = |n: usize| -> Vec<u8> {
            (0..n)
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    (state >> 24) as u8
                })
                .collect()
        };
        let mut inputs = vec![Vec::new(), vec![0u8; 4000], noise(1), noise(300_000)];
        let mut mixed = vec![0u8; 50_000];
        mixed.extend(noise(50_000));
        mixed.extend((0..100_000).map(|i| (i / 700) as u8));
        inputs.push(mixed);
        for data in &inputs {
            for rle in [0, 1, data.len() / 2, data.len(), data.len() + 5] {
                let z = deflate_planes(data, rle).unwrap();
                let mut back = vec![0u8; data.len() + 16];
                let (got, rc) = zlib_rs::decompress_slice(&mut back, &z, Default::default());
                assert_eq!(
                    rc,
                    zlib_rs::ReturnCode::Ok,
                    "{} bytes, rle {rle}",
                    data.len()
                );
                assert_eq!(got, &data[..], "{} bytes, rle {rle}", data.len());
                if !data.is_empty() {
                    let mut bad = z.clone();
                    *bad.last_mut().unwrap() ^= 1;
                    let (_, rc) = zlib_rs::decompress_slice(&mut back, &bad, Default::default());
                    assert_ne!(rc, zlib_rs::ReturnCode::Ok);
                }
            }
        }
    }
}
