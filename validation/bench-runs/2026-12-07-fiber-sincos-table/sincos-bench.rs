// The table-and-turn sin/cos of 2π·u (baker/src/math/turns.rs, sin_cos_turns) against the
// quadrant polynomials it replaced (sin_cos_quadrant), standalone:
//   rustc -O sincos-bench.rs && ./sincos-bench             # speed, and the largest difference
//   ./sincos-bench dump > d.txt && python3 sincos-accuracy.py   # accuracy against mpmath
// `old` is sin_cos_quadrant, `new` sin_cos_turns (its table built lazily here, in constant
// evaluation in the baker).
use std::f64::consts::{FRAC_PI_2, TAU};
const ROUND_F64: f64 = 6755399441055744.0;
#[inline(always)]
fn estrin<const N: usize>(c: &[f64; N], x: f64) -> f64 {
    let mut v = *c; let (mut n, mut p) = (N, x);
    while n > 1 { let half = n / 2; for i in 0..half { v[i] = v[2*i] + v[2*i+1]*p; }
        n = if n % 2 == 1 { v[half] = v[n-1]; half + 1 } else { half }; p = p*p; }
    v[0]
}
const S: [f64; 7] = [-1.0/6.0, 1.0/120.0, -1.0/5_040.0, 1.0/362_880.0, -1.0/39_916_800.0, 1.0/6_227_020_800.0, -1.0/1_307_674_368_000.0];
const C: [f64; 8] = [-1.0/2.0, 1.0/24.0, -1.0/720.0, 1.0/40_320.0, -1.0/3_628_800.0, 1.0/479_001_600.0, -1.0/87_178_291_200.0, 1.0/20_922_789_888_000.0];
#[inline(never)]
fn old(u: f64) -> (f64, f64) {
    let x = 4.0 * u; let q = (x + ROUND_F64) - ROUND_F64; let r = (x - q) * FRAC_PI_2; let r2 = r * r;
    let sin_r = r + r * (r2 * estrin(&S, r2)); let cos_r = 1.0 + r2 * estrin(&C, r2);
    let qi = q as i64; let swap = qi & 1 != 0;
    let (a, b) = (if swap { cos_r } else { sin_r }, if swap { sin_r } else { cos_r });
    let sign_s = ((qi as u64 >> 1) & 1) << 63; let sign_c = (((qi + 1) as u64 >> 1) & 1) << 63;
    (f64::from_bits(a.to_bits() ^ sign_s), f64::from_bits(b.to_bits() ^ sign_c))
}
const N: usize = 256;
struct T([[f64; 2]; N]);
static TAB: std::sync::LazyLock<T> = std::sync::LazyLock::new(|| T(std::array::from_fn(|k| { let (s, c) = old(k as f64 / N as f64); [s, c] })));
#[inline(never)]
fn new(t: &T, u: f64) -> (f64, f64) {
    let x = N as f64 * u;
    let q = (x + ROUND_F64) - ROUND_F64;
    let r = (x - q) * (TAU / N as f64);
    let r2 = r * r;
    let k = (q as i64 as usize) & (N - 1);
    let [s, c] = t.0[k];
    let sr = r + r * (r2 * (-1.0/6.0 + r2 * (1.0/120.0 + r2 * (-1.0/5_040.0))));
    let cr = 1.0 + r2 * (-0.5 + r2 * (1.0/24.0 + r2 * (-1.0/720.0)));
    (s * cr + c * sr, c * cr - s * sr)
}
fn main() { if std::env::args().count() > 1 { dump(); return; }
    let t = &*TAB;
    let mut s = 88172645463325252u64;
    let us: Vec<f64> = (0..20_000_000).map(|_| { s ^= s << 13; s ^= s >> 7; s ^= s << 17; (s >> 11) as f64 / (1u64 << 53) as f64 }).collect();
    let mut maxe = 0.0f64;
    for &u in us.iter().take(1_000_000) { let a = old(u); let b = new(t, u); maxe = maxe.max((a.0-b.0).abs()/f64::EPSILON).max((a.1-b.1).abs()/f64::EPSILON); }
    println!("max abs diff in eps {maxe}");
    for _ in 0..3 {
    let t0 = std::time::Instant::now(); let mut acc = 0.0; for &u in &us { let (a, b) = old(u); acc += a * b; } let d0 = t0.elapsed();
    let t1 = std::time::Instant::now(); let mut acc2 = 0.0; for &u in &us { let (a, b) = new(t, u); acc2 += a * b; } let d1 = t1.elapsed();
    println!("old {:.2} ns new {:.2} ns ({acc} {acc2})", d0.as_nanos() as f64 / us.len() as f64, d1.as_nanos() as f64 / us.len() as f64);
    }
}
#[allow(dead_code)]
pub fn dump() {
    let t = &*TAB;
    let mut s = 1234567u64;
    for _ in 0..20000 { s ^= s << 13; s ^= s >> 7; s ^= s << 17; let u = (s >> 11) as f64 / (1u64 << 53) as f64;
        let (a, b) = new(t, u); let (c, d) = old(u);
        println!("{:e} {:e} {:e} {:e} {:e}", u, a, b, c, d); }
}
