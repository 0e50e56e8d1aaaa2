//! The time one cross-section of a fiber takes to bake at the thesis's fidelity (§5.3.2: 2°
//! bins; the noise of 16 M plain photons per incoming direction, [`NoiseTarget::Thesis`]),
//! next to the thesis's own cost (Table 10). `baker fiber bench --thesis` prints it.
//!
//! A full bake at that fidelity takes hours, so a sample of the stored incoming directions
//! (evenly spread over the symmetry-reduced list, the same ones every run) is traced to the
//! target with the spec's estimators, and the mean time per direction is scaled by the number
//! of stored directions. The figure is an estimate of that kind and says so.
//!
//! The table's size is estimated the same way: each measured slice is encoded as a bake
//! stores it (the spec's precision and channels, `quantise_to_se`, `zstd_level`), the mean
//! compressed bytes per direction are scaled by the stored directions, and the directory is
//! built for every stored direction (their scales and albedos repeated from the measured
//! ones) and compressed as a bake compresses it.

use serde::Serialize;

use super::setup::{entry_setup, typical_path_um, EntrySetup};
use super::tables::{push_slice, Layout};
use crate::cancel::Cancel;
use crate::fiber::slices::{incident_of_bin, trace_group, BakeSettings, NoiseTarget, SliceResult};
use crate::fiber::sweep::{Channels, Variant};
use crate::math::rng::coordinate_seed;
use crate::spec::fiber::{FiberEntry, TableStorage};
use formats::bcsdf::{self, Chunk, Directory, Writer};

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

/// Table 10's storage (MB) for a fiber type, if it has a row.
pub fn table_10_mb(fiber_type: &str) -> Option<f64> {
    TABLE_10.iter().find(|r| r.0 == fiber_type).map(|r| r.2)
}

/// One entry measured at the thesis's noise.
#[derive(Debug, Clone, Serialize)]
pub struct ThesisCost {
    pub entry: String,
    pub fiber_type: String,
    /// The variant traced: `undyed`, or the entry's first (`--dyed`).
    pub variant: String,
    /// Incoming directions the table stores after symmetry (2° bins).
    pub stored_directions: usize,
    /// Directions traced here.
    pub measured_directions: usize,
    pub split: u32,
    pub exit_draws: u32,
    pub expected_exits: crate::fiber::slices::ExpectedExits,
    pub sampling: crate::fiber::slices::Sampling,
    /// Directions sharing their photons (`share_theta`).
    pub share_theta: u32,
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
    /// Mean compressed bytes of a measured slice as the spec's tables store it.
    pub bytes_per_direction: f64,
    /// The `.bcsdf` file of one cross-section: bytes_per_direction × stored_directions, plus
    /// the header and the compressed directory of every stored direction.
    pub estimated_bcsdf_bytes: f64,
    pub table_10_mb: Option<f64>,
}

/// Measures entry `e` (its first cross-section, undyed, or `dyed` as its first variant)
/// with the estimators of `st`, at 2° bins, tracing `directions` of its stored directions to
/// the thesis's noise (at most `st.max_photons` photons each), and stores the slices as
/// `storage` says.
pub fn measure(
    e: &FiberEntry,
    st: &BakeSettings,
    storage: &TableStorage,
    dyed: bool,
    directions: usize,
    columns: Option<usize>,
    cancel: &Cancel,
) -> anyhow::Result<ThesisCost> {
    let st = BakeSettings {
        res_deg: 2.0,
        target: Some(NoiseTarget::Thesis),
        ..st.clone()
    };
    let mut s = entry_setup(e, &st)?;
    // The thesis's noise is defined on the undyed fiber, and Table 10 times one monochromatic
    // table: trace the undyed variant alone (a dye sweep adds scoring, [`crate::fiber::sweep`]),
    // or the entry's first variant alone.
    let variant = match s.variants.first() {
        Some(v) if dyed => v.clone(),
        _ => Variant {
            name: FiberEntry::variant_name(None),
            mua_per_um: vec![0.0; st.lambda_nm.len()],
        },
    };
    s.channels = Channels::new(
        std::slice::from_ref(&variant),
        &st.lambda_nm,
        st.channels,
        typical_path_um(&s.fibers[0]),
    );
    let n = s.stored.len();
    let k = directions.clamp(1, n);
    // The stored directions measured: `k` evenly spread, or with `columns` every stored θ
    // row of that many evenly spread φ columns (the same directions whatever `share_theta`).
    let starts: Vec<usize> = match columns {
        None => (0..k).map(|i| (2 * i + 1) * n / (2 * k)).collect(),
        Some(c) => {
            let n_phi = s.grid.n_phi;
            let row0: Vec<usize> = s.stored.iter().copied().filter(|&b| b < n_phi).collect();
            let c = c.clamp(1, row0.len().max(1));
            let mut v = Vec::new();
            for j in 0..c {
                let jp = row0[(2 * j + 1) * row0.len() / (2 * c)];
                v.extend((0..n).filter(|&i| s.stored[i] % n_phi == jp));
            }
            v
        }
    };
    let (mut secs, mut photons, mut noise, mut thesis, mut capped) = (0.0, 0.0, 0.0, 0.0, 0);
    let mut sample = Sample::new(&s, &variant.name, &st, storage);
    // With `share_theta`, each measured direction's whole group (a group's photons serve
    // all of its directions, so its time is theirs together).
    let mut measured = 0;
    for members in s.groups(starts, st.share_theta as usize) {
        let bins: Vec<usize> = members.iter().map(|&m| s.stored[m]).collect();
        let incs: Vec<_> = bins
            .iter()
            .map(|&b| incident_of_bin(&s.grid, b / s.grid.n_phi, b % s.grid.n_phi))
            .collect();
        let seeds: Vec<u64> = bins
            .iter()
            .map(|&b| coordinate_seed(st.seed, &[s.seed_base, 0, b as u64]))
            .collect();
        let rs = trace_group(
            &s.fibers[0],
            &incs,
            &s.grid,
            &s.channels,
            &st,
            &seeds,
            cancel,
        )?;
        for r in &rs {
            secs += r.seconds;
            photons += r.launched as f64;
            noise += r.noise.median_rel_se;
            thesis += r.noise.thesis_rel_se;
            capped += usize::from(!NoiseTarget::Thesis.met_by(&r.noise));
            sample.push(r, &s, storage)?;
            measured += 1;
        }
    }
    let (k, kf) = (measured, measured as f64);
    let bytes_per_direction = sample.bytes_per_direction();
    Ok(ThesisCost {
        entry: e.name.clone(),
        fiber_type: e.fiber_type.name.to_string(),
        variant: variant.name.clone(),
        stored_directions: n,
        measured_directions: k,
        split: st.split,
        exit_draws: st.exit_draws,
        expected_exits: st.expected_exits,
        sampling: st.sampling,
        share_theta: st.share_theta,
        photons_per_direction: photons / kf,
        seconds_per_direction: secs / kf,
        median_rel_se: noise / kf,
        thesis_rel_se: thesis / kf,
        capped,
        estimated_seconds: secs / kf * n as f64,
        table_10_minutes: table_10_minutes(e.fiber_type.name),
        bytes_per_direction,
        estimated_bcsdf_bytes: bytes_per_direction * n as f64 + sample.directory_bytes()? as f64,
        table_10_mb: table_10_mb(e.fiber_type.name),
    })
}

/// A table of every stored direction of `s` holding the measured slices, encoded as a
/// bake encodes them ([`push_slice`]), with their albedos.
struct Sample {
    writer: Writer,
    albedo: Vec<f32>,
    albedo_se: Vec<f32>,
}

impl Sample {
    /// The table of entry setup `s` storing `variant` as the spec's `storage` says.
    fn new(s: &EntrySetup, variant: &str, st: &BakeSettings, storage: &TableStorage) -> Sample {
        let (wi_deg, phi_centres) = (s.wi_deg(), s.phi_centres_deg());
        let variants = [variant.to_string()];
        let layout = Layout {
            grid: &s.grid,
            st,
            wi_deg: &wi_deg,
            map: &s.map,
            variants: &variants,
            channels: &s.channels.channel_names,
            phi_centres: &phi_centres,
            quantise_to_se: storage.quantise_to_se,
            zstd_level: storage.zstd_level,
        };
        Sample {
            writer: layout.writer(s.area_um(&s.fibers[0]), serde_json::Value::Null),
            albedo: vec![],
            albedo_se: vec![],
        }
    }

    fn push(
        &mut self,
        r: &SliceResult,
        s: &EntrySetup,
        storage: &TableStorage,
    ) -> anyhow::Result<()> {
        push_slice(
            &mut self.writer,
            r,
            &s.grid,
            storage.quantise_to_se,
            storage.zstd_level,
        )?;
        self.albedo.extend(r.albedo.iter().map(|&x| x as f32));
        self.albedo_se.extend(r.albedo_se.iter().map(|&x| x as f32));
        Ok(())
    }

    /// Mean compressed bytes of a measured slice.
    fn bytes_per_direction(&self) -> f64 {
        let c = &self.writer.dir.chunks;
        c.iter().map(|c| c.compressed_bytes as f64).sum::<f64>() / c.len().max(1) as f64
    }

    /// The header and compressed directory of the whole table: the measured slices' scales,
    /// albedos and chunk sizes repeated in turn over the stored directions (the metadata, a
    /// few hundred bytes, left out), compressed at the last slice's level as a bake does.
    fn directory_bytes(&self) -> anyhow::Result<usize> {
        let d = &self.writer.dir;
        let (n, k) = (d.wi_deg.len(), d.chunks.len().max(1));
        let per = d.scale.len() / k;
        let cycle = |v: &[f32]| -> Vec<f32> {
            (0..n)
                .flat_map(|i| v[(i % k) * per..(i % k + 1) * per].iter().copied())
                .collect()
        };
        let mut offset = 0;
        let chunks = (0..n)
            .map(|i| {
                let c = Chunk {
                    offset,
                    ..d.chunks[i % k].clone()
                };
                offset += c.compressed_bytes;
                c
            })
            .collect();
        let full = Directory {
            scale: cycle(&d.scale),
            albedo: cycle(&self.albedo),
            albedo_se: cycle(&self.albedo_se),
            chunks,
            ..d.clone()
        };
        let json = serde_json::to_vec(&full)?;
        Ok(bcsdf::HEADER_LEN + zstd::bulk::compress(&json, self.writer.level())?.len())
    }
}
