//! The population of cross-sections a fiber entry bakes (seeded variants of a generated
//! section, built here so that a bake cannot fail on one), the symmetries they share on the
//! bake's grid, and the size of the entry's tables against `limits.table_gib`.

use super::entry::{FiberEntry, SymmetryMode};
use super::raw::RawFiber;
use super::FiberCx;
use crate::fiber::slices::BakeSettings;
use crate::fiber::symmetry::{self, Symmetry};
use crate::fiber::Fiber;
use crate::spec::check::{count_text, loc};
use crate::spec::limits::Limits;

impl FiberCx {
    /// The population the bake traces, built here so that a bake cannot fail on it.
    pub(super) fn populate(&mut self, r: &RawFiber, e: &mut FiberEntry) -> Option<()> {
        for k in 1..e.sections {
            match e.section_variant(k) {
                Ok(sec) => e.population.push(sec),
                Err(m) => {
                    let at = r.sections.as_ref().map_or(loc(&r.name), loc);
                    self.invalid(at, "fibers.sections", format!("section {k}: {m}"));
                    return None;
                }
            }
        }
        Some(())
    }

    /// The symmetries and stored directions of an entry's population on the bake's grid, and
    /// the size of its tables against `limits.table_gib`.
    pub(super) fn population_costs(
        &mut self,
        at: (u64, u64),
        e: &mut FiberEntry,
        st: &BakeSettings,
        limits: &Limits,
    ) -> Option<()> {
        let fibers: Vec<Fiber> = e
            .population
            .iter()
            .map(|s| e.fiber_with(s.clone()))
            .collect();
        e.symmetries = if e.symmetry == SymmetryMode::None {
            Symmetry::NONE
        } else {
            let mut sym = symmetry::detect(&fibers[0], st.res_deg);
            for f in &fibers[1..] {
                sym = sym.common(&symmetry::detect(f, st.res_deg));
            }
            sym
        };
        let grid = crate::fiber::AngularGrid::new(st.res_deg).ok()?;
        e.stored_directions = e
            .symmetries
            .stored_count(grid.n_theta, grid.n_phi, st.res_deg);
        let tables = fibers.len() + usize::from(fibers.len() > 1);
        let bytes = e.stored_directions as f64
            * tables as f64
            * e.variants.len() as f64
            * st.channels_per_variant() as f64
            * grid.bins() as f64
            * 4.0;
        let gib = bytes / (1u64 << 30) as f64;
        if gib > limits.table_gib {
            self.over_limit(
                at,
                "fibers",
                format!(
                    "{}: {} stored directions × {tables} table(s) × {} variant(s) × {} channel(s) × {} bins \
                     is {gib:.2} GiB of f32 tables",
                    e.name,
                    count_text(e.stored_directions as u64),
                    e.variants.len(),
                    st.channels_per_variant(),
                    count_text(grid.bins() as u64),
                ),
                "table_gib",
                format!("{} GiB", limits.table_gib),
            );
            return None;
        }
        Some(())
    }
}
