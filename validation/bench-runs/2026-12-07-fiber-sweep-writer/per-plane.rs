// Per byte plane of 100 HDF5 chunks of a 20-variant cotton sweep (every 9th stored direction
// of `f_normalised` and `cdf_phi`, dumped as little-endian f32 to /tmp/zb/NAME.bin by h5py):
// zlib-rs ratio and speed at levels 0–3, run-length and Huffman-only strategies.
use std::time::Instant;
use zlib_rs::{compress_slice, DeflateConfig, Strategy};
fn main() {
    for name in ["f_normalised", "cdf_phi"] {
        let raw = std::fs::read(format!("/tmp/zb/{name}.bin")).unwrap();
        let per = if name == "f_normalised" { 20 * 3 * 30 * 60 } else { 20 * 30 * 60 };
        let chunks: Vec<Vec<u8>> = raw
            .chunks(per * 4)
            .map(|c| {
                let mut p = vec![0u8; 4 * per];
                for i in 0..per {
                    for k in 0..4 {
                        p[k * per + i] = c[4 * i + k];
                    }
                }
                p
            })
            .collect();
        println!("{name}: {} chunks", chunks.len());
        let mut out = vec![0u8; 8 * per + 1000];
        let cases = [(1, Strategy::Default, "L1"), (2, Strategy::Default, "L2"), (3, Strategy::Default, "L3"),
                     (2, Strategy::Rle, "RLE"), (2, Strategy::HuffmanOnly, "huff"), (0, Strategy::Default, "L0")];
        for k in 0..4 {
            for (lvl, st, lab) in cases {
                let (mut n, mut raw_n) = (0usize, 0usize);
                let t = Instant::now();
                for _ in 0..3 {
                    (n, raw_n) = (0, 0);
                    for c in &chunks {
                        let plane = &c[k * per..(k + 1) * per];
                        let cfg = DeflateConfig { level: lvl, strategy: st, ..DeflateConfig::default() };
                        let (o, rc) = compress_slice(&mut out, plane, cfg);
                        assert_eq!(rc, zlib_rs::ReturnCode::Ok);
                        n += o.len();
                        raw_n += plane.len();
                    }
                }
                let dt = t.elapsed().as_secs_f64() / 3.0;
                println!("  plane {k} {lab:4}: ratio {:.3} {:6.0} MB/s", n as f64 / raw_n as f64, raw_n as f64 / dt / 1e6);
            }
        }
    }
}
