//! Nelder–Mead simplex minimisation, shared by the sum-of-Gaussians fit and the Chiang hair fit.

/// Nelder–Mead minimisation (Lagarias et al. 1998 coefficients) from `x0` with step `step`:
/// stops after `max_eval` evaluations or when the simplex's values agree to `rel_tol`
/// (relative). Returns the best point, its value and the evaluations used.
pub fn nelder_mead(
    f: &mut impl FnMut(&[f64]) -> f64,
    x0: &[f64],
    step: f64,
    max_eval: usize,
    rel_tol: f64,
) -> (Vec<f64>, f64, usize) {
    let n = x0.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    simplex.push((x0.to_vec(), f(x0)));
    for i in 0..n {
        let mut x = x0.to_vec();
        x[i] += step;
        let fx = f(&x);
        simplex.push((x, fx));
    }
    let mut evals = n + 1;
    while evals < max_eval {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (best, worst) = (simplex[0].1, simplex[n].1);
        if (worst - best).abs() <= rel_tol * best.abs().max(1e-12) {
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|j| simplex[..n].iter().map(|p| p.0[j]).sum::<f64>() / n as f64)
            .collect();
        let towards = |t: f64, worst: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|j| centroid[j] + t * (worst[j] - centroid[j]))
                .collect()
        };
        let xr = towards(-1.0, &simplex[n].0);
        let fr = f(&xr);
        evals += 1;
        if fr < simplex[0].1 {
            let xe = towards(-2.0, &simplex[n].0);
            let fe = f(&xe);
            evals += 1;
            simplex[n] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < simplex[n - 1].1 {
            simplex[n] = (xr, fr);
        } else {
            let t = if fr < simplex[n].1 { -0.5 } else { 0.5 };
            let xc = towards(t, &simplex[n].0);
            let fc = f(&xc);
            evals += 1;
            if fc < fr.min(simplex[n].1) {
                simplex[n] = (xc, fc);
            } else {
                // Shrink towards the best point.
                let x0 = simplex[0].0.clone();
                for p in simplex.iter_mut().skip(1) {
                    for (pj, &bj) in p.0.iter_mut().zip(&x0) {
                        *pj = bj + 0.5 * (*pj - bj);
                    }
                    p.1 = f(&p.0);
                }
                evals += n;
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (x, fx) = simplex.swap_remove(0);
    (x, fx, evals)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quadratic bowl: the minimum is found, and the stopping rule (the simplex's values
    /// agree to `rel_tol`) ends the search long before the evaluation budget.
    #[test]
    fn finds_a_quadratic_minimum_and_stops_on_its_tolerance() {
        let mut f =
            |x: &[f64]| 1.0 + (x[0] - 1.0).powi(2) + 4.0 * (x[1] + 2.0).powi(2) + 0.5 * x[2] * x[2];
        let (x, fx, evals) = nelder_mead(&mut f, &[5.0, 5.0, 5.0], 1.0, 20_000, 1e-12);
        assert!(
            (x[0] - 1.0).abs() < 1e-4 && (x[1] + 2.0).abs() < 1e-4 && x[2].abs() < 1e-4,
            "{x:?}"
        );
        assert!((fx - 1.0).abs() < 1e-10);
        assert!(evals < 2_000, "{evals} evaluations");
    }

    /// Expansion: on a slope the simplex must grow geometrically (Lagarias et al.: reflect
    /// by 1, expand by 2), not crawl one step per reflection.
    #[test]
    fn expands_along_a_slope() {
        let mut f = |x: &[f64]| x[0];
        let (x, _, evals) = nelder_mead(&mut f, &[0.0], 1.0, 60, 0.0);
        assert!(evals >= 60);
        assert!(x[0] < -1e6, "{x:?}");
    }

    /// The contraction follows Lagarias et al. (1998): outside (c − ½(w − c)) when the
    /// reflected point beats the worst one, inside (c + ½(w − c)) when it does not. In one
    /// dimension on |x − 0.3| the fourth evaluated point is that contraction.
    #[test]
    fn contracts_outside_or_inside_as_lagarias_et_al() {
        let fourth = |x0: f64, step: f64| {
            let mut seen = Vec::new();
            let mut f = |x: &[f64]| {
                seen.push(x[0]);
                (x[0] - 0.3).abs()
            };
            nelder_mead(&mut f, &[x0], step, 4, 0.0);
            seen[3]
        };
        // Points −1 (1.3) and 0.2 (0.1): reflected 1.4 (1.1 < 1.3), outside contraction 0.8.
        assert!((fourth(-1.0, 1.2) - 0.8).abs() < 1e-12);
        // Points −1 (1.3) and 0.5 (0.2): reflected 2.0 (1.7 ≥ 1.3), inside contraction −0.25.
        assert!((fourth(-1.0, 1.5) + 0.25).abs() < 1e-12);
    }

    /// Contraction and shrink: from a simplex far too large around a narrow minimum of |x|,
    /// the search still closes in on 0.
    #[test]
    fn contracts_onto_a_narrow_minimum() {
        let mut f = |x: &[f64]| x[0].abs() + 10.0 * (x[1] - 0.3).abs();
        let (x, fx, _) = nelder_mead(&mut f, &[7.0, -5.0], 50.0, 5_000, 1e-14);
        assert!(
            x[0].abs() < 1e-6 && (x[1] - 0.3).abs() < 1e-6 && fx < 1e-5,
            "{x:?} {fx}"
        );
    }
}
