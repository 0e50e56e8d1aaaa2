//! The time one cross-section of a fiber takes to bake at the thesis's fidelity (§5.3.2: 2°
//! bins; the noise of 16 M plain photons per incoming direction, [`NoiseTarget::Thesis`]),
//! next to the thesis's own cost (Table 10). `baker fiber bench --thesis` prints it.
//!
//! A full bake at that fidelity takes hours, so a sample of the stored incoming directions
//! (evenly spread over the symmetry-reduced list, the same ones every run) is traced to the
//! target with the spec's estimators, and the mean time per direction is scaled by the number
//! of stored directions. The figure is an estimate of that kind and says so.

use serde::Serialize;

use super::setup::{entry_setup, typical_path_um};
use crate::cancel::Cancel;
use crate::fiber::slices::{incident_of_bin, trace_slice, BakeSettings, NoiseTarget};
use crate::fiber::sweep::{Channels, Variant};
use crate::math::rng::coordinate_seed;
use crate::spec::fiber::FiberEntry;

/// Table 10 of the thesis: average computation time (minutes) and storage of the BCSDF
/// (MB, 32-bit floats, monochromatic) per fiber type.
pub const TABLE_10: [(&str, f64, f64); 4] = [
    ("polyester", 7.0, 2.7),
    ("silk", 360.0, 500.5),
    ("cotton", 420.0, 500.5),
    ("wool", 900.0, 1001.0),
];

/// Table 10's minutes for a fiber type, if it has a row.
pub fn table_10_minutes(fiber_type: &str) -> Option<f64> {
    TABLE_10.iter().find(|r| r.0 == fiber_type).map(|r| r.1)
}

/// One entry measured at the thesis's noise.
#[derive(Debug, Clone, Serialize)]
pub struct ThesisCost {
    pub entry: String,
    pub fiber_type: String,
    /// Incoming directions the table stores after symmetry (2° bins).
    pub stored_directions: usize,
    /// Directions traced here.
    pub measured_directions: usize,
    pub split: u32,
    pub exit_draws: u32,
    pub expected_exits: crate::fiber::slices::ExpectedExits,
    pub sampling: crate::fiber::slices::Sampling,
    /// Mean over the measured directions.
    pub photons_per_direction: f64,
    pub seconds_per_direction: f64,
    /// Mean of each slice's own median relative standard error, and of the thesis's noise.
    pub median_rel_se: f64,
    pub thesis_rel_se: f64,
    /// Directions that hit the photon cap before the target.
    pub capped: usize,
    /// seconds_per_direction × stored_directions.
    pub estimated_seconds: f64,
    pub table_10_minutes: Option<f64>,
}

/// Measures entry `e` (its first cross-section, undyed)
/// with the estimators of `st`, at 2° bins, tracing `directions` of its stored directions to
/// the thesis's noise (at most `st.max_photons` photons each).
pub fn measure(
    e: &FiberEntry,
    st: &BakeSettings,
    directions: usize,
    cancel: &Cancel,
) -> anyhow::Result<ThesisCost> {
    let st = BakeSettings {
        res_deg: 2.0,
        target: Some(NoiseTarget::Thesis),
        ..st.clone()
    };
    let mut s = entry_setup(e, &st)?;
    // The thesis's noise is defined on the undyed fiber, and Table 10 times one monochromatic
    // table: trace the undyed variant alone (a dye sweep adds scoring, [`crate::fiber::sweep`]).
    let undyed = Variant {
        name: FiberEntry::variant_name(None),
        mua_per_um: vec![0.0; st.lambda_nm.len()],
    };
    s.channels = Channels::new(
        &[undyed],
        &st.lambda_nm,
        st.channels,
        typical_path_um(&s.fibers[0]),
    );
    let n = s.stored.len();
    let k = directions.clamp(1, n);
    let (mut secs, mut photons, mut noise, mut thesis, mut capped) = (0.0, 0.0, 0.0, 0.0, 0);
    for i in 0..k {
        let b = s.stored[(2 * i + 1) * n / (2 * k)];
        let inc = incident_of_bin(&s.grid, b / s.grid.n_phi, b % s.grid.n_phi);
        let seed = coordinate_seed(st.seed, &[s.seed_base, 0, b as u64]);
        let r = trace_slice(&s.fibers[0], inc, &s.grid, &s.channels, &st, seed, cancel)?;
        secs += r.seconds;
        photons += r.launched as f64;
        noise += r.noise.median_rel_se;
        thesis += r.noise.thesis_rel_se;
        capped += usize::from(!NoiseTarget::Thesis.met_by(&r.noise));
    }
    let kf = k as f64;
    Ok(ThesisCost {
        entry: e.name.clone(),
        fiber_type: e.fiber_type.name.to_string(),
        stored_directions: n,
        measured_directions: k,
        split: st.split,
        exit_draws: st.exit_draws,
        expected_exits: st.expected_exits,
        sampling: st.sampling,
        photons_per_direction: photons / kf,
        seconds_per_direction: secs / kf,
        median_rel_se: noise / kf,
        thesis_rel_se: thesis / kf,
        capped,
        estimated_seconds: secs / kf * n as f64,
        table_10_minutes: table_10_minutes(e.fiber_type.name),
    })
}
