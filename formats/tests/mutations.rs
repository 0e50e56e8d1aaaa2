//! Property test: thousands of mutated `.bkt` and `.bcsdf` files must give a typed error (or,
//! where the mutation happens to keep the file valid, a value): never a panic, never a hang,
//! and never an allocation beyond the bound documented in FORMAT.md ("Reading untrusted
//! files"): at most [`ALLOC_FACTOR`] × the file size + [`ALLOC_SLACK`] bytes live at once.
//!
//! Mutations, from a fixed seed: bit flips, byte overwrites, truncation, trailing bytes,
//! absurd header fields (lengths up to 2⁶⁴ − 1, other versions, flags), and *consistent*
//! mutations that rewrite the JSON directory (absurd numbers, wrong lengths, NaN-like values)
//! or a data chunk (random bytes) and then fix every length and checksum, so the readers'
//! semantic checks are reached, not only the CRC.

use std::alloc::{GlobalAlloc, Layout, System};
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use formats::bcsdf::{self, Directory, Precision, Writer};
use formats::table::{crc32, Array, TableFile, TableIndex};
use formats::{Bcsdf, ProfileTable};

/// Documented bound (FORMAT.md): live memory while reading ≤ 64 × file size + 16 MiB.
const ALLOC_FACTOR: usize = 64;
const ALLOC_SLACK: usize = 16 << 20;
/// A mutated file must be answered within this time.
const MAX_TIME: Duration = Duration::from_secs(2);

struct Counting;
static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(l) };
        if !p.is_null() {
            let now = LIVE.fetch_add(l.size(), Ordering::Relaxed) + l.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) };
        LIVE.fetch_sub(l.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, l, new) };
        if !q.is_null() {
            if new >= l.size() {
                let now = LIVE.fetch_add(new - l.size(), Ordering::Relaxed) + new - l.size();
                PEAK.fetch_max(now, Ordering::Relaxed);
            } else {
                LIVE.fetch_sub(l.size() - new, Ordering::Relaxed);
            }
        }
        q
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// SplitMix64: a fixed-seed generator without dependencies.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A small but complete skin profile table: 2 entries with every array the reader uses.
fn profile_table() -> Vec<u8> {
    let names = ["typeI_age30_xi0", "typeVI_age60_xi1"];
    let mut groups = serde_json::Map::new();
    let mut t = TableFile::new("skin_profiles", serde_json::Value::Null);
    for (k, name) in names.iter().enumerate() {
        groups.insert(
            name.to_string(),
            serde_json::json!({"age_years": "30.0", "skin_type": (["I", "VI"][k]), "xi": "0",
                "params_json": "{\"age_years\":30.0}"}),
        );
        let n = 12u64;
        let edges: Vec<f64> = (0..=n).map(|i| 0.01 * (i * i) as f64).collect();
        let centres: Vec<f64> = edges.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
        let rd: Vec<f64> = (0..3 * n)
            .map(|i| (-(i as f64) / (5.0 + k as f64)).exp())
            .collect();
        for a in [
            Array::new_f64(format!("{name}/r_mm"), vec![n], centres),
            Array::new_f64(format!("{name}/r_edges_mm"), vec![n + 1], edges),
            Array::new_f64(format!("{name}/rd_rgb_per_mm2"), vec![n, 3], rd),
            Array::new_f64(format!("{name}/albedo_rgb"), vec![3], vec![0.5, 0.3, 0.2]),
            Array::new_f64(
                format!("{name}/gaussians/variance_mm2"),
                vec![2],
                vec![0.01, 0.5],
            ),
            Array::new_f64(
                format!("{name}/gaussians/weight_rgb"),
                vec![2, 3],
                vec![0.2, 0.1, 0.1, 0.3, 0.2, 0.1],
            ),
            Array::new_f64(
                format!("{name}/gaussians/error_rgb"),
                vec![3],
                vec![0.01; 3],
            ),
        ] {
            t.push(a.unwrap()).unwrap();
        }
    }
    t.metadata = serde_json::json!({
        "entries": serde_json::to_string(&names).unwrap(),
        "groups": groups,
        "seed": 1,
    });
    t.to_bytes(3).unwrap()
}

/// A small fiber table: res 30°, 2 stored ωi, 2 variants, 3 channels, f16 or f32.
fn bcsdf_table(dtype: Precision) -> Vec<u8> {
    let (nt, np) = (6, 12);
    let wi_map = (0..nt * np)
        .map(|b| {
            let it = b / np;
            match it {
                0..=2 => (it.min(1)) as u32,
                _ => (5 - it).min(1) as u32 | bcsdf::FLIP_THETA,
            }
        })
        .collect();
    let dir = Directory {
        kind: bcsdf::KIND.into(),
        res_deg: 30.0,
        n_theta: nt,
        n_phi: np,
        wi_deg: vec![[-75.0, 15.0], [-45.0, 15.0]],
        wi_map,
        variants: vec!["undyed".into(), "red@1%".into()],
        channels: vec!["R".into(), "G".into(), "B".into()],
        dtype,
        keep_bits: dtype.mantissa_bits() - 2,
        scale: vec![],
        albedo: vec![0.9; 12],
        albedo_se: vec![0.01; 12],
        area_um: (0..np).map(|j| 20.0 + j as f64).collect(),
        chunks: vec![],
        metadata: serde_json::json!({"seed": 7}),
    };
    let mut w = Writer::new(dir, 3);
    for s in 0..2 {
        let v: Vec<f64> = (0..6 * nt * np)
            .map(|i| ((i * 13 + s * 5) % 17) as f64 * 0.05)
            .collect();
        w.push(&v).unwrap();
    }
    w.finish().unwrap()
}

fn u64_at(b: &[u8], o: usize) -> u64 {
    u64::from_le_bytes(b[o..o + 8].try_into().unwrap())
}

/// Splits a valid file into (header, directory JSON, payload).
fn split(file: &[u8]) -> (Vec<u8>, serde_json::Value, Vec<u8>) {
    let dc = u64_at(file, 16) as usize;
    let json = zstd::bulk::decompress(&file[48..48 + dc], u64_at(file, 24) as usize).unwrap();
    (
        file[..48].to_vec(),
        serde_json::from_slice(&json).unwrap(),
        file[48 + dc..].to_vec(),
    )
}

/// Reassembles a file with consistent lengths and checksum.
fn join(header: &[u8], dir: &serde_json::Value, payload: &[u8]) -> Vec<u8> {
    let json = serde_json::to_vec(dir).unwrap();
    let frame = zstd::bulk::compress(&json, 1).unwrap();
    let mut out = header[..16].to_vec();
    out.extend_from_slice(&(frame.len() as u64).to_le_bytes());
    out.extend_from_slice(&(json.len() as u64).to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&crc32(&json).to_le_bytes());
    out.extend_from_slice(&header[44..48]);
    out.extend_from_slice(&frame);
    out.extend_from_slice(payload);
    out
}

/// Replaces one random leaf (or array) of a JSON value with something absurd.
fn mutate_json(v: &mut serde_json::Value, rng: &mut Rng) {
    use serde_json::Value as V;
    let absurd = |rng: &mut Rng| -> V {
        match rng.below(12) {
            0 => V::from(0),
            1 => V::from(-1),
            2 => V::from(u64::MAX),
            3 => V::from(1u64 << 40),
            4 => V::from(1e300),
            5 => V::from(-1e-300),
            6 => V::from(1e-9),
            7 => V::String("NaN".into()),
            8 => V::Null,
            9 => V::Array(vec![]),
            10 => V::from(rng.next() % 100_000),
            _ => V::from(rng.unit() * 400.0 - 200.0),
        }
    };
    match v {
        V::Object(m) if !m.is_empty() => {
            let k = m.keys().nth(rng.below(m.len())).unwrap().clone();
            if rng.below(12) == 0 {
                m.remove(&k);
            } else {
                mutate_json(m.get_mut(&k).unwrap(), rng);
            }
        }
        V::Array(a) if !a.is_empty() => match rng.below(6) {
            0 => {
                a.pop();
            }
            1 => {
                let x = a[rng.below(a.len())].clone();
                a.push(x);
            }
            _ => {
                let i = rng.below(a.len());
                mutate_json(&mut a[i], rng);
            }
        },
        V::String(s) if rng.below(2) == 0 => {
            let cut = rng.below(s.len() + 1);
            let mut cut = cut;
            while !s.is_char_boundary(cut) {
                cut -= 1;
            }
            s.truncate(cut);
            s.push_str(["/", "..", "\u{0}", "x", "[", "\"]"][rng.below(6)]);
        }
        leaf => *leaf = absurd(rng),
    }
}

/// Rewrites one bcsdf chunk as a valid zstd frame of random bytes with a correct CRC.
fn craft_chunk(dir: &mut serde_json::Value, payload: &mut Vec<u8>, rng: &mut Rng) {
    let chunks = dir["chunks"].as_array().unwrap().clone();
    let mut out = Vec::new();
    let mut new_chunks = Vec::new();
    let pick = rng.below(chunks.len());
    for (i, c) in chunks.iter().enumerate() {
        let (o, n) = (
            c["offset"].as_u64().unwrap(),
            c["compressed_bytes"].as_u64().unwrap(),
        );
        let raw_len = c["raw_bytes"].as_u64().unwrap() as usize;
        let frame = &payload[o as usize..(o + n) as usize];
        let mut raw = zstd::bulk::decompress(frame, raw_len).unwrap();
        if i == pick {
            for b in raw.iter_mut() {
                if rng.below(3) == 0 {
                    *b = rng.next() as u8;
                }
            }
        }
        let f = zstd::bulk::compress(&raw, 1).unwrap();
        new_chunks.push(
            serde_json::json!({"offset": out.len(), "compressed_bytes": f.len(),
            "raw_bytes": raw.len(), "crc32": crc32(&raw)}),
        );
        out.extend_from_slice(&f);
    }
    dir["chunks"] = serde_json::Value::Array(new_chunks);
    *payload = out;
}

/// Rewrites a zstd frame's header to claim `size` decompressed bytes (an 8-byte
/// Frame_Content_Size field, RFC 8878 §3.1.1.1), keeping its blocks.
fn patch_content_size(frame: &[u8], size: u64) -> Vec<u8> {
    let fhd = frame[4];
    let single = (fhd >> 5) & 1 == 1;
    let dict = [0, 1, 2, 4][(fhd & 3) as usize];
    let fcs = [usize::from(single), 2, 4, 8][(fhd >> 6) as usize];
    let start = 5 + usize::from(!single) + dict;
    let mut out = frame[..4].to_vec();
    // FCS flag 3; a single-segment frame's window is its content size: keep that meaning.
    out.push((fhd & 0x3F) | 0xC0);
    out.extend_from_slice(&frame[5..start]);
    out.extend_from_slice(&size.to_le_bytes());
    out.extend_from_slice(&frame[start + fcs..]);
    out
}

/// A header that lies consistently with the zstd frame about the directory's size, or (.bkt)
/// a directory entry that lies consistently with its frame about an array's size.
fn lie_about_size(file: &[u8], rng: &mut Rng, is_bcsdf: bool) -> Vec<u8> {
    let huge = [1u64 << 33, 1 << 40, u64::MAX / 2, 1 << 28][rng.below(4)];
    let (h, mut d, p) = split(file);
    if is_bcsdf || rng.below(2) == 0 {
        let json = serde_json::to_vec(&d).unwrap();
        let frame = patch_content_size(&zstd::bulk::compress(&json, 1).unwrap(), huge);
        let mut out = h[..16].to_vec();
        out.extend_from_slice(&(frame.len() as u64).to_le_bytes());
        out.extend_from_slice(&huge.to_le_bytes());
        out.extend_from_slice(&(p.len() as u64).to_le_bytes());
        out.extend_from_slice(&crc32(&json).to_le_bytes());
        out.extend_from_slice(&h[44..48]);
        out.extend_from_slice(&frame);
        out.extend_from_slice(&p);
        return out;
    }
    let arrays = d["arrays"].as_array().unwrap().clone();
    let pick = rng.below(arrays.len());
    let mut payload = Vec::new();
    let mut new = Vec::new();
    for (i, a) in arrays.into_iter().enumerate() {
        let (o, n) = (
            a["offset"].as_u64().unwrap(),
            a["compressed_bytes"].as_u64().unwrap(),
        );
        let mut frame = p[o as usize..(o + n) as usize].to_vec();
        let mut a = a;
        if i == pick {
            let count = huge / 8;
            frame = patch_content_size(&frame, count * 8);
            a["shape"] = serde_json::json!([count]);
            a["dtype"] = serde_json::json!("f64");
            a["raw_bytes"] = serde_json::json!(count * 8);
        }
        a["offset"] = serde_json::json!(payload.len());
        a["compressed_bytes"] = serde_json::json!(frame.len());
        payload.extend_from_slice(&frame);
        new.push(a);
    }
    d["arrays"] = serde_json::Value::Array(new);
    join(&h, &d, &payload)
}

fn mutate(file: &[u8], rng: &mut Rng, is_bcsdf: bool) -> Vec<u8> {
    let mut b = file.to_vec();
    match rng.below(11) {
        10 => b = lie_about_size(file, rng, is_bcsdf),
        0..=1 => {
            for _ in 0..1 + rng.below(4) {
                let i = rng.below(b.len());
                b[i] ^= 1 << rng.below(8);
            }
        }
        2 => {
            let i = rng.below(b.len());
            let n = (1 + rng.below(16)).min(b.len() - i);
            for x in &mut b[i..i + n] {
                *x = rng.next() as u8;
            }
        }
        3 => b.truncate(rng.below(b.len())),
        4 => b.extend((0..1 + rng.below(64)).map(|_| rng.next() as u8)),
        5 => {
            // An absurd header field.
            let o = [8, 12, 16, 24, 32, 40, 44][rng.below(7)];
            let v: u64 = [u64::MAX, 1 << 40, 0, 1, 2, rng.next()][rng.below(6)];
            let w = if matches!(o, 8 | 12 | 40 | 44) { 4 } else { 8 };
            b[o..o + w].copy_from_slice(&v.to_le_bytes()[..w]);
        }
        6..=8 => {
            let (h, mut d, p) = split(file);
            for _ in 0..1 + rng.below(3) {
                mutate_json(&mut d, rng);
            }
            b = join(&h, &d, &p);
        }
        _ => {
            let (h, mut d, mut p) = split(file);
            if is_bcsdf {
                craft_chunk(&mut d, &mut p, rng);
            } else {
                mutate_json(&mut d, rng);
            }
            b = join(&h, &d, &p);
        }
    }
    b
}

/// Everything a renderer would do with a file.
fn exercise(bytes: &[u8], rng: &mut Rng) {
    if bytes.starts_with(b"BAKERFIB") {
        let Ok(t) = Bcsdf::from_bytes(bytes.to_vec()) else {
            return;
        };
        let nv = t.dir.variants.len();
        for _ in 0..8 {
            let dir = |rng: &mut Rng| {
                bcsdf::direction(
                    (rng.unit() - 0.5) * std::f64::consts::PI,
                    (rng.unit() - 0.5) * std::f64::consts::TAU,
                )
            };
            let (wi, wo) = (dir(rng), dir(rng));
            let v = rng.below(nv + 1);
            let _ = t.eval(wi, wo, v);
            let _ = t.pdf(wi, wo, v);
            let _ = t.albedo(wi, v);
            let _ = t.sample(wi, v, rng.unit(), rng.unit());
            let _ = t.projected_area(wo);
        }
        for i in 0..t.dir.n_wi() {
            let _ = t.decode(i);
        }
    } else {
        let _ = TableFile::from_bytes(bytes);
        if let Ok(ix) = TableIndex::from_bytes(bytes.to_vec()) {
            for i in 0..ix.entries().len() {
                let _ = ix.read_at(i);
            }
        }
        if let Ok(t) = ProfileTable::from_bytes(bytes.to_vec()) {
            let _ = t.find(&[("skin_type", "I")]);
            for e in t.entries().to_vec() {
                for r in [-1.0, 0.0, 0.003, 0.5, 1.0, 1e9, f64::NAN] {
                    let _ = t.rd_rgb(&e.name, r);
                }
                let _ = t.albedo_rgb(&e.name);
                if let Ok(g) = t.gaussians(&e.name) {
                    let _ = g.eval(0.1);
                }
            }
        }
    }
}

fn run_corpus(name: &str, valid: &[u8], cases: usize, seed: u64) -> Vec<String> {
    // The valid file itself reads.
    exercise(valid, &mut Rng(1));
    let mut rng = Rng(seed);
    let mut failures = Vec::new();
    let mut rejected = 0usize;
    for case in 0..cases {
        let m = mutate(valid, &mut rng, name.starts_with("bcsdf"));
        let base = LIVE.load(Ordering::Relaxed);
        PEAK.store(base, Ordering::Relaxed);
        let t0 = Instant::now();
        let mut erng = Rng(case as u64);
        let r = std::panic::catch_unwind(AssertUnwindSafe(|| exercise(&m, &mut erng)));
        let dt = t0.elapsed();
        let peak = PEAK.load(Ordering::Relaxed).saturating_sub(base);
        let bound = ALLOC_FACTOR * m.len() + ALLOC_SLACK;
        if r.is_err() {
            failures.push(format!("{name} case {case}: panic"));
        } else if peak > bound {
            failures.push(format!("{name} case {case}: {peak} bytes > bound {bound}"));
        } else if dt > MAX_TIME {
            failures.push(format!("{name} case {case}: took {dt:?}"));
        }
        if Bcsdf::from_bytes(m.clone()).is_err() && TableIndex::from_bytes(m).is_err() {
            rejected += 1;
        }
    }
    eprintln!(
        "{name}: {cases} mutated files, {rejected} rejected at open, {} failures",
        failures.len()
    );
    // The test must actually reach the readers' semantic checks, not only the CRC.
    if rejected == cases {
        failures.push(format!("{name}: every mutated file was rejected at open"));
    }
    failures
}

/// One test (the allocation counter is global to this binary, so nothing runs beside it).
#[test]
fn mutated_tables_never_panic_hang_or_overallocate() {
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut failures = run_corpus("bkt", &profile_table(), 3000, 11);
    failures.extend(run_corpus(
        "bcsdf-f16",
        &bcsdf_table(Precision::F16),
        2000,
        12,
    ));
    failures.extend(run_corpus(
        "bcsdf-f32",
        &bcsdf_table(Precision::F32),
        2000,
        13,
    ));
    std::panic::set_hook(default_hook);
    assert!(
        failures.is_empty(),
        "{} failures, first: {:#?}",
        failures.len(),
        &failures[..failures.len().min(10)]
    );
}
