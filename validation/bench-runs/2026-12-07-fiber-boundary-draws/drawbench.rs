//! One boundary draw of a rough fiber surface (silk's η 1.53 at β = 8°), timed: 2·10⁷ draws
//! from outside and from inside, each result feeding a sum. Runs on any build whose
//! `Surface::scatter(d, nf, inside, u)` has this signature:
//!
//!     mkdir -p baker/examples && cp validation/bench-runs/2026-12-07-fiber-boundary-draws/drawbench.rs baker/examples/
//!     cargo run --release --example drawbench; rm -r baker/examples
use baker::fiber::Surface;
use std::time::Instant;

fn main() {
    let s = Surface {
        eta: 1.53,
        alpha: (8.0f64).to_radians().tan(),
    };
    // xorshift64: the draws' uniforms, cheap and the same for every build.
    let mut x: u64 = 0x1234_5678;
    let mut u = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        ((x >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
    };
    for inside in [false, true] {
        let d = if inside {
            [0.3f64, 0.1, 0.948683]
        } else {
            [0.6f64, -0.2, -0.774597]
        };
        let n = [0.0, 0.0, if inside { -1.0 } else { 1.0 }];
        let k = 1.0 / (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let d = [d[0] * k, d[1] * k, d[2] * k];
        let n_iter = 20_000_000;
        let t = Instant::now();
        let mut acc = 0.0;
        for _ in 0..n_iter {
            let r = s.scatter(d, n, inside, &mut u);
            acc += r.dir[0] + r.transmitted as u8 as f64;
        }
        let ns = t.elapsed().as_secs_f64() * 1e9 / n_iter as f64;
        let t = Instant::now();
        let mut acc2 = 0.0;
        for _ in 0..n_iter {
            acc2 += u();
        }
        let ns_u = t.elapsed().as_secs_f64() * 1e9 / n_iter as f64;
        println!("inside {inside}: {ns:.2} ns per draw (the uniforms alone {ns_u:.2} ns) {acc} {acc2}");
    }
}
