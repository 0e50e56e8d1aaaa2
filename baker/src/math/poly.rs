//! Polynomial evaluation by Estrin's scheme, for the branch-free elementary functions of
//! [`super::exp`] and [`super::turns`].

/// `c[0] + c[1]·x + … + c[N − 1]·x^(N − 1)` by Estrin's scheme: adjacent coefficients pair up
/// as `c[2i] + c[2i + 1]·x`, those pairs pair up with x², then x⁴, … (an odd one out passes to
/// the next level unchanged). Its dependency chain is about 2·log₂ N operations, Horner's
/// 2·N, so loops of evaluations are not bound by add latency. Separate multiplies and adds (no
/// fused multiply-add) in a fixed order: the same bits on every x86-64 machine, and in
/// constant evaluation ([`super::turns`] builds its table with it).
#[inline(always)]
pub const fn estrin<const N: usize>(c: &[f64; N], x: f64) -> f64 {
    let mut v = *c;
    let (mut n, mut p) = (N, x);
    while n > 1 {
        let half = n / 2;
        let mut i = 0;
        while i < half {
            v[i] = v[2 * i] + v[2 * i + 1] * p;
            i += 1;
        }
        n = if n % 2 == 1 {
            v[half] = v[n - 1];
            half + 1
        } else {
            half
        };
        p = p * p;
    }
    v[0]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Equal to Horner's evaluation within rounding, for every length up to 16, and bit for
    /// bit the scheme written out for 12 coefficients (as `exp_neg_f64` wrote it).
    #[test]
    fn estrin_evaluates_the_polynomial() {
        let c: [f64; 16] =
            std::array::from_fn(|k| 1.0 / (k as f64 + 1.0) * if k % 3 == 0 { -1.0 } else { 1.0 });
        for x in [-0.7, -0.1, 0.0, 0.3, 0.9] {
            macro_rules! check {
                ($($n:literal)*) => {$({
                    let cn: [f64; $n] = std::array::from_fn(|k| c[k]);
                    let horner = cn.iter().rev().fold(0.0, |a, &k| a * x + k);
                    let e = estrin(&cn, x);
                    assert!((e - horner).abs() <= 1e-15 * (1.0 + horner.abs()), "{} at {x}: {e} vs {horner}", $n);
                })*};
            }
            check!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
            let c: [f64; 12] = std::array::from_fn(|k| c[k]);
            let (x2, x4) = (x * x, x * x * (x * x));
            let x8 = x4 * x4;
            let q: [f64; 6] = std::array::from_fn(|i| c[2 * i] + c[2 * i + 1] * x);
            let s: [f64; 3] = std::array::from_fn(|i| q[2 * i] + q[2 * i + 1] * x2);
            let written = (s[0] + s[1] * x4) + s[2] * x8;
            assert_eq!(estrin(&c, x).to_bits(), written.to_bits());
        }
    }
}
