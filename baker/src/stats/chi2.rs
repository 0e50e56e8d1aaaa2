//! χ² goodness-of-fit test of samples against a density, for every sampler.

use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Histograms `samples` on `bins` equal bins over [lo, hi] (use an odd count so edges miss
/// sharp features), compares with the expected counts from `pdf` (Simpson per bin), pools bins
/// expected below 5, and panics if p < 1e-4. On failure the histograms go to
/// `target/chi2-<name>.csv`.
pub fn chi2_test_1d(
    samples: &[f64],
    lo: f64,
    hi: f64,
    bins: usize,
    pdf: impl Fn(f64) -> f64,
    name: &str,
) {
    let n = samples.len() as f64;
    let w = (hi - lo) / bins as f64;
    let mut observed = vec![0f64; bins];
    for &s in samples {
        let i = (((s - lo) / w) as usize).min(bins - 1);
        observed[i] += 1.0;
    }
    let expected: Vec<f64> = (0..bins)
        .map(|i| {
            let (a, b) = (lo + i as f64 * w, lo + (i + 1) as f64 * w);
            let k = 16;
            let h = (b - a) / k as f64;
            let mut s = pdf(a) + pdf(b);
            for j in 1..k {
                s += pdf(a + j as f64 * h) * if j % 2 == 1 { 4.0 } else { 2.0 };
            }
            n * s * h / 3.0
        })
        .collect();
    let labels: Vec<f64> = (0..bins).map(|i| lo + i as f64 * w).collect();
    chi2_test_bins(&observed, &expected, &labels, name);
}

/// χ² test of `observed` counts against `expected` counts over the same bins (in an order
/// where neighbours are alike: consecutive bins expected below 5 are pooled, and a short last
/// pool joins the one before). Panics if p < 1e-4, writing the histograms to
/// `target/chi2-<name>.csv` (`labels` name the bins there). Returns (χ², degrees of freedom).
pub fn chi2_test_bins(
    observed: &[f64],
    expected: &[f64],
    labels: &[f64],
    name: &str,
) -> (f64, usize) {
    let mut pools: Vec<(f64, f64)> = Vec::new();
    let (mut acc_o, mut acc_e) = (0.0, 0.0);
    for (o, e) in observed.iter().zip(expected) {
        acc_o += o;
        acc_e += e;
        if acc_e >= 5.0 {
            pools.push((acc_o, acc_e));
            acc_o = 0.0;
            acc_e = 0.0;
        }
    }
    if acc_e > 0.0 || acc_o > 0.0 {
        match pools.last_mut() {
            Some(last) if acc_e < 5.0 => {
                last.0 += acc_o;
                last.1 += acc_e;
            }
            _ => pools.push((acc_o, acc_e)),
        }
    }
    let chi2: f64 = pools
        .iter()
        .map(|(o, e)| (o - e) * (o - e) / e.max(1e-300))
        .sum();
    let dof = pools.len();
    let dist = ChiSquared::new((dof.max(2) - 1) as f64).unwrap();
    let p = 1.0 - dist.cdf(chi2);
    if p < 1e-4 {
        let mut csv = String::from("bin,observed,expected\n");
        for i in 0..observed.len() {
            csv += &format!(
                "{},{},{}\n",
                labels.get(i).copied().unwrap_or(i as f64),
                observed[i],
                expected[i]
            );
        }
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target");
        let _ = std::fs::create_dir_all(&dir);
        let _ = std::fs::write(dir.join(format!("chi2-{name}.csv")), csv);
        panic!("χ² test {name} failed: χ² = {chi2:.1} with {dof} bins, p = {p:.2e}");
    }
    (chi2, dof)
}
