//! What a fiber entry's work units are made of, and their ids and keys.

use crate::fiber::slices::{unit_len, BakeSettings};
use crate::fiber::sweep::{Channels, Variant};
use crate::fiber::symmetry::Symmetry;
use crate::fiber::{AngularGrid, Fiber};
use crate::math::rng::fnv1a;
use crate::pipeline::KeyBuilder;
use crate::spec::fiber::FiberEntry;
use formats::bcsdf::{FLIP_DPHI, FLIP_THETA};

/// The variants of an entry as μa spectra.
pub fn variants_of(e: &FiberEntry, lambda_nm: &[f64]) -> Vec<Variant> {
    e.variants
        .iter()
        .map(|v| Variant {
            name: FiberEntry::variant_name(v.as_ref()),
            mua_per_um: lambda_nm
                .iter()
                .map(|&l| e.variant_mua_per_um(v.as_ref(), l))
                .collect(),
        })
        .collect()
}

/// Typical longest path worth tabulating: 16 bounding diameters.
pub fn typical_path_um(f: &Fiber) -> f64 {
    let s = f.cuticle_slope().map_or(1.0, |c| c.1);
    32.0 * f.section.bound_radius_um() * s
}

/// What an entry's units are made of: the grid, the sections, the stored directions, the
/// channels, and the digest of everything a unit's result depends on besides its directions
/// (pipeline::KeyBuilder).
pub struct EntrySetup {
    pub grid: AngularGrid,
    pub fibers: Vec<Fiber>,
    pub sym: Symmetry,
    pub stored: Vec<usize>,
    pub map: Vec<u32>,
    pub variants: Vec<Variant>,
    pub channels: Channels,
    pub seed_base: u64,
    pub key_base: [u8; 32],
}

impl EntrySetup {
    /// The stored directions (indices into `stored`, ascending) that share their photons
    /// with stored direction `i` under `share_theta` = `k` ([`crate::fiber::tracer::shared`]):
    /// the stored bins of its φ column, in θ order, over which windows of `k` rows slide
    /// ([`crate::fiber::tracer::shared::Windows`]); `[i]` alone for `k` ≤ 1. A function of the
    /// grid and the symmetries alone, so every unit and shard forms the same groups.
    pub fn share_group(&self, i: usize, k: usize) -> Vec<usize> {
        if k <= 1 {
            return vec![i];
        }
        let g = &self.grid;
        let jp = self.stored[i] % g.n_phi;
        (0..g.n_theta)
            .filter_map(|t| {
                let x = t * g.n_phi + jp;
                let s = (self.map[x] & !(FLIP_THETA | FLIP_DPHI)) as usize;
                (self.stored[s] == x).then_some(s)
            })
            .collect()
    }

    /// The work units of a bake with `share_theta` = `k`: lists of stored directions (indices
    /// into `stored`, ascending). Without sharing, consecutive runs of
    /// [`crate::fiber::slices::unit_len`]; with it, whole groups ([`EntrySetup::share_group`],
    /// in the order of their first direction) gathered until a unit holds that many, so a
    /// unit's directions are a run of whole φ columns. A function of the grid
    /// and the symmetries alone (the units, their ids and keys are the same on every machine
    /// and in every shard).
    pub fn units(&self, k: u32) -> Vec<Vec<usize>> {
        let n = self.stored.len();
        let len = unit_len(n);
        if k <= 1 {
            let all: Vec<usize> = (0..n).collect();
            return all.chunks(len).map(<[usize]>::to_vec).collect();
        }
        let (mut units, mut unit) = (Vec::new(), Vec::new());
        for g in self.groups(0..n, k as usize) {
            unit.extend(g);
            if unit.len() >= len {
                unit.sort_unstable();
                units.push(std::mem::take(&mut unit));
            }
        }
        if !unit.is_empty() {
            unit.sort_unstable();
            units.push(unit);
        }
        units
    }

    /// The groups ([`EntrySetup::share_group`] under `share_theta` = `k`) of the stored
    /// directions `dirs`, each once, in the order of the first of `dirs` in each.
    pub fn groups(&self, dirs: impl IntoIterator<Item = usize>, k: usize) -> Vec<Vec<usize>> {
        let mut placed = vec![false; self.stored.len()];
        let mut out = Vec::new();
        for i in dirs {
            if !placed[i] {
                let g = self.share_group(i, k);
                g.iter().for_each(|&m| placed[m] = true);
                out.push(g);
            }
        }
        out
    }

    /// The stored incoming directions' bin centres, (θi, φi) in degrees.
    pub fn wi_deg(&self) -> Vec<[f64; 2]> {
        let g = &self.grid;
        self.stored
            .iter()
            .map(|&b| {
                [
                    g.theta_centre_deg(b / g.n_phi),
                    g.phi_centre_deg(b % g.n_phi),
                ]
            })
            .collect()
    }

    /// The centres of the φ (and Δφ) bins, degrees.
    pub fn phi_centres_deg(&self) -> Vec<f64> {
        (0..self.grid.n_phi)
            .map(|j| self.grid.phi_centre_deg(j))
            .collect()
    }

    /// The projected width of section `f` at the φ bin centres, µm (a table's `area_um`).
    pub fn area_um(&self, f: &Fiber) -> Vec<f64> {
        self.phi_centres_deg()
            .iter()
            .map(|p| f.projected_width_um(p.to_radians()))
            .collect()
    }
}

/// The setup of entry `e` from what the resolver built (its sections and symmetries).
pub fn entry_setup(e: &FiberEntry, st: &BakeSettings) -> anyhow::Result<EntrySetup> {
    let grid = AngularGrid::new(st.res_deg).map_err(anyhow::Error::msg)?;
    let fibers: Vec<Fiber> = e
        .population
        .iter()
        .map(|s| e.fiber_with(s.clone()))
        .collect();
    let sym = e.symmetries;
    let (stored, map) = sym.wi_map(grid.n_theta, grid.n_phi, st.res_deg);
    let variants = variants_of(e, &st.lambda_nm);
    let channels = Channels::new(
        &variants,
        &st.lambda_nm,
        st.channels,
        typical_path_um(&fibers[0]),
    );
    let seed_base = fnv1a(&e.name);
    let key_base =
        crate::pipeline::digest_of(&(&fibers, &channels, st, seed_base, grid.n_theta, grid.n_phi));
    Ok(EntrySetup {
        grid,
        fibers,
        sym,
        stored,
        map,
        variants,
        channels,
        seed_base,
        key_base,
    })
}

/// Id (`<spec>/<entry>/wi<first>-<last>`) and key of the unit of stored directions `chunk`.
pub fn unit_id_key(
    prefix: &str,
    chunk: &[usize],
    stored: &[usize],
    key_base: &[u8; 32],
) -> (String, crate::pipeline::Key) {
    let bins: Vec<usize> = chunk.iter().map(|&i| stored[i]).collect();
    let key = KeyBuilder::new("fiber-slices", crate::data::checksum())
        .digest("entry", key_base)
        .part("bins", &bins)
        .finish();
    let id = format!("{prefix}/wi{}-{}", chunk[0], chunk[chunk.len() - 1]);
    (id, key)
}
