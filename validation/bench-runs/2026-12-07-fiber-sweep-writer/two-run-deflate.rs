// The two-run stream (run-length strategy for the byte planes below `split`, level 2 for
// the rest; baker/src/output/hdf5.rs `deflate_planes`) on the same 100 chunks as
// per-plane.rs, every stream inflated and checked (its time included).
use zlib_rs::{compress_bound, Deflate, DeflateConfig, DeflateFlush, Strategy, Status};
use std::time::Instant;
fn mixed(planes: &[u8], n: usize, split: usize, out: &mut Vec<u8>) {
    out.clear(); out.resize(compress_bound(planes.len()) + 64, 0);
    out[0] = 0x78; out[1] = 0x5e;
    let mut pos = 2;
    let (lo, hi) = planes.split_at(split * n);
    if !lo.is_empty() {
        let mut a = Deflate::new_with_config(DeflateConfig { level: 2, strategy: Strategy::Rle, window_bits: -15, ..DeflateConfig::default() });
        let st = a.compress(lo, &mut out[pos..], DeflateFlush::SyncFlush).unwrap();
        assert!(a.total_in() as usize == lo.len() && matches!(st, Status::Ok), "{st:?}");
        pos += a.total_out() as usize;
    }
    let mut b = Deflate::new_with_config(DeflateConfig { level: 2, window_bits: -15, ..DeflateConfig::default() });
    let st = b.compress(hi, &mut out[pos..], DeflateFlush::Finish).unwrap();
    assert!(matches!(st, Status::StreamEnd), "{st:?}");
    pos += b.total_out() as usize;
    let ad = zlib_rs::adler32::adler32(1, planes);
    out[pos..pos + 4].copy_from_slice(&ad.to_be_bytes());
    out.truncate(pos + 4);
}
fn main() {
    for name in ["f_normalised", "cdf_phi"] {
        let raw = std::fs::read(format!("/tmp/zb/{name}.bin")).unwrap();
        let per = if name == "f_normalised" { 20*3*30*60 } else { 20*30*60 };
        let chunks: Vec<Vec<u8>> = raw.chunks(per*4).map(|c| {
            let n = per; let mut p = vec![0u8; 4*n];
            for i in 0..n { for k in 0..4 { p[k*n+i] = c[4*i+k]; } }
            p }).collect();
        let mut out = Vec::new();
        for split in [0usize, 1, 2, 3] {
            let t = Instant::now(); let (mut n, mut rn) = (0, 0);
            for _ in 0..3 { n = 0; rn = 0; for c in &chunks {
                mixed(c, per, split, &mut out); n += out.len(); rn += c.len();
                let mut back = vec![0u8; c.len()];
                let (b, rc) = zlib_rs::decompress_slice(&mut back, &out, zlib_rs::InflateConfig::default());
                assert!(rc == zlib_rs::ReturnCode::Ok && b == &c[..]);
            }}
            println!("{name} RLE planes <{split}: ratio {:.4} {:.0} MB/s (incl. check)", n as f64/rn as f64, rn as f64 / (t.elapsed().as_secs_f64()/3.0) / 1e6);
        }
    }
}
