//! Non-negative least squares for a handful of unknowns, in normal-equation form:
//! minimise ½·wᵀGw − hᵀw subject to w ≥ 0 (Lawson & Hanson 1974, ch. 23, active-set method),
//! with G = BᵀDB and h = BᵀDe for a weighted problem ‖D^½(Bw − e)‖².

// Index loops mirror the formulas (rows, columns, bins); iterator chains would hide them.
#![allow(clippy::needless_range_loop)]

/// Solves `g`·z = `h` on the index set `p` by Gaussian elimination with partial pivoting.
/// Returns `None` when the reduced system is singular.
fn solve_on(g: &[Vec<f64>], h: &[f64], p: &[usize]) -> Option<Vec<f64>> {
    let m = p.len();
    let mut a: Vec<Vec<f64>> = p
        .iter()
        .map(|&i| {
            let mut row: Vec<f64> = p.iter().map(|&j| g[i][j]).collect();
            row.push(h[i]);
            row
        })
        .collect();
    for c in 0..m {
        let piv = (c..m).max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))?;
        if a[piv][c].abs() < 1e-300 {
            return None;
        }
        a.swap(c, piv);
        for r in c + 1..m {
            let f = a[r][c] / a[c][c];
            if f != 0.0 {
                for k in c..=m {
                    a[r][k] -= f * a[c][k];
                }
            }
        }
    }
    let mut z = vec![0.0; m];
    for r in (0..m).rev() {
        let s: f64 = (r + 1..m).map(|k| a[r][k] * z[k]).sum();
        z[r] = (a[r][m] - s) / a[r][r];
    }
    z.iter().all(|v| v.is_finite()).then_some(z)
}

/// Active-set NNLS on the normal equations. `g` is n×n symmetric positive semi-definite.
pub fn nnls_normal(g: &[Vec<f64>], h: &[f64]) -> Vec<f64> {
    let n = h.len();
    // A tiny ridge keeps nearly equal columns (two Gaussians of almost the same variance)
    // solvable without changing any well-posed answer.
    let ridge = 1e-13 * (0..n).map(|i| g[i][i]).sum::<f64>() / n as f64;
    let g: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| g[i][j] + if i == j { ridge } else { 0.0 })
                .collect()
        })
        .collect();
    let scale = h.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    let tol = 1e-12 * scale;
    let mut w = vec![0.0; n];
    let mut passive = vec![false; n];
    for _ in 0..3 * n + 3 {
        let grad: Vec<f64> = (0..n)
            .map(|i| h[i] - (0..n).map(|j| g[i][j] * w[j]).sum::<f64>())
            .collect();
        let Some(j) = (0..n)
            .filter(|&i| !passive[i] && grad[i] > tol)
            .max_by(|&a, &b| grad[a].total_cmp(&grad[b]))
        else {
            break;
        };
        passive[j] = true;
        for _ in 0..3 * n + 3 {
            let p: Vec<usize> = (0..n).filter(|&i| passive[i]).collect();
            let Some(z) = solve_on(&g, h, &p) else {
                passive[j] = false;
                break;
            };
            if z.iter().all(|&v| v > 0.0) {
                for (k, &i) in p.iter().enumerate() {
                    w[i] = z[k];
                }
                break;
            }
            // Step from w towards z until the first passive weight reaches 0.
            let mut alpha = 1.0f64;
            for (k, &i) in p.iter().enumerate() {
                if z[k] <= 0.0 {
                    alpha = alpha.min(w[i] / (w[i] - z[k]));
                }
            }
            for (k, &i) in p.iter().enumerate() {
                w[i] += alpha * (z[k] - w[i]);
                if w[i] <= 1e-15 * scale {
                    w[i] = 0.0;
                    passive[i] = false;
                }
            }
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    fn normal(b: &[Vec<f64>], e: &[f64]) -> (Vec<Vec<f64>>, Vec<f64>) {
        let n = b[0].len();
        let g = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| b.iter().map(|r| r[i] * r[j]).sum())
                    .collect()
            })
            .collect();
        let h = (0..n)
            .map(|i| b.iter().zip(e).map(|(r, e)| r[i] * e).sum())
            .collect();
        (g, h)
    }

    #[test]
    fn recovers_a_positive_solution() {
        let b = vec![
            vec![1.0, 0.0, 0.5],
            vec![0.0, 1.0, 0.5],
            vec![1.0, 1.0, 0.0],
            vec![0.2, 0.3, 1.0],
        ];
        let w_true = [0.7, 0.2, 1.3];
        let e: Vec<f64> = b
            .iter()
            .map(|r| r.iter().zip(&w_true).map(|(a, w)| a * w).sum())
            .collect();
        let (g, h) = normal(&b, &e);
        let w = nnls_normal(&g, &h);
        for (a, b) in w.iter().zip(&w_true) {
            assert!((a - b).abs() < 1e-9, "{w:?}");
        }
    }

    #[test]
    fn clamps_a_negative_coefficient_to_zero() {
        // Unconstrained answer is (−1, 1); the constrained one is (0, 2/5).
        let b = vec![vec![1.0, 1.0], vec![1.0, 2.0]];
        let e = [0.0, 1.0];
        let (g, h) = normal(&b, &e);
        let w = nnls_normal(&g, &h);
        assert_eq!(w[0], 0.0);
        assert!((w[1] - 0.4).abs() < 1e-12, "{w:?}");
    }

    /// The NNLS answer by brute force: every subset of active (positive) unknowns, solved
    /// unconstrained by Cramer-free Gaussian elimination written here, kept if feasible, the
    /// best objective ½wᵀGw − hᵀw wins (a convex problem: the feasible stationary point of the
    /// right subset is the optimum).
    fn brute_force(g: &[Vec<f64>], h: &[f64]) -> (Vec<f64>, f64) {
        let n = h.len();
        let obj = |w: &[f64]| {
            let quad: f64 = (0..n)
                .map(|i| (0..n).map(|j| w[i] * g[i][j] * w[j]).sum::<f64>())
                .sum();
            0.5 * quad - (0..n).map(|i| h[i] * w[i]).sum::<f64>()
        };
        let mut best = (vec![0.0; n], 0.0);
        for mask in 1u32..(1 << n) {
            let p: Vec<usize> = (0..n).filter(|&i| mask & (1 << i) != 0).collect();
            // Gauss–Jordan on the subset.
            let m = p.len();
            let mut a: Vec<Vec<f64>> = p
                .iter()
                .map(|&i| p.iter().map(|&j| g[i][j]).chain([h[i]]).collect())
                .collect();
            let mut ok = true;
            for c in 0..m {
                let piv = (c..m)
                    .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
                    .unwrap();
                if a[piv][c].abs() < 1e-12 {
                    ok = false;
                    break;
                }
                a.swap(c, piv);
                for r in 0..m {
                    if r != c {
                        let f = a[r][c] / a[c][c];
                        for k in 0..=m {
                            a[r][k] -= f * a[c][k];
                        }
                    }
                }
            }
            if !ok {
                continue;
            }
            let mut w = vec![0.0; n];
            for (k, &i) in p.iter().enumerate() {
                w[i] = a[k][m] / a[k][k];
            }
            if w.iter().all(|&x| x >= -1e-12) && obj(&w) < best.1 {
                best = (w.clone(), obj(&w));
            }
        }
        best
    }

    /// Issue 22: 200 random problems of 2–6 unknowns, many with negative unconstrained
    /// solutions, against brute force over all active sets.
    #[test]
    fn matches_brute_force_on_random_problems() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for case in 0..200 {
            let n = 2 + case % 5;
            let rows = n + 3;
            let b: Vec<Vec<f64>> = (0..rows)
                .map(|_| (0..n).map(|_| next()).collect())
                .collect();
            let e: Vec<f64> = (0..rows).map(|_| next()).collect();
            let (g, h) = normal(&b, &e);
            let w = nnls_normal(&g, &h);
            let (want, _) = brute_force(&g, &h);
            for (a, b) in w.iter().zip(&want) {
                assert!((a - b).abs() < 1e-8, "case {case}: {w:?} vs {want:?}");
            }
        }
    }
}
