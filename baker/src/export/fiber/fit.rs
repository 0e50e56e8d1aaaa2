//! A fiber table's Chiang fit, with what the exporters print about it.

use formats::bcsdf::Bcsdf;

use crate::export::chiang::{self, Chiang, ChiangFitOptions, FitReport, FitTarget, TestEvaluation};

/// A table, its variant and the fit.
#[derive(Debug, Clone)]
pub struct FiberFit {
    /// The table's path as given.
    pub table: String,
    pub variant: String,
    pub channels: Vec<String>,
    /// The table's provenance (`metadata` of its directory).
    pub metadata: serde_json::Value,
    pub report: FitReport,
    /// The table's own Monte Carlo noise in the fit's error measure
    /// ([`FitTarget::noise_l1`]), when the metadata gives the photon count.
    pub noise_l1: Option<f64>,
    pub tests: Vec<TestEvaluation>,
}

/// Fits variant `variant` of `table` (η from the table's metadata when it has one).
pub fn fit_table(table: &Bcsdf, variant: usize, name: &str) -> Result<FiberFit, chiang::FitError> {
    let eta = table.dir.metadata["eta"]
        .as_f64()
        .filter(|e| e.is_finite() && *e > 1.0);
    let opts = ChiangFitOptions {
        eta,
        ..ChiangFitOptions::default()
    };
    let target = FitTarget::from_table(table, variant, &opts)?;
    let report = chiang::fit(&target, &opts);
    let noise_l1 = table.dir.metadata["photons_per_direction"]
        .as_f64()
        .filter(|n| *n > 0.0)
        .map(|n| target.noise_l1(n));
    let tests = chiang::test_evaluations(&Chiang::new(report.params.clone()));
    Ok(FiberFit {
        table: name.to_string(),
        variant: table.dir.variants[variant].clone(),
        channels: table.dir.channels.clone(),
        metadata: table.dir.metadata.clone(),
        report,
        noise_l1,
        tests,
    })
}
