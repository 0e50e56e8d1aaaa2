//! MCML 1.x input files (`.mci`, file version `1.0`; Wang, Jacques & Zheng 1995, MCML 1.2.2
//! manual, mcmlio.c ReadParm): the version line, the number of runs, then per run the output
//! file name (and A/B), photons, `dz dr` (cm), `nz nr na`, the number of layers, n above, one
//! `n mua mus g d` line per layer [cm, 1/cm], n below.

use super::mci::{check_grid, count, nums, output_file_name, DataLines, Line, McmlRun, MAX_RUNS};
use crate::transport::engine::ROULETTE_WEIGHT;
use crate::transport::stack::{Layer, MAX_LAYERS};

/// Every run of a 1.x file whose version line `lines` has already given.
pub(super) fn parse(lines: &mut DataLines<'_>) -> Result<Vec<McmlRun>, String> {
    let l = lines.next("number of runs")?;
    let runs = count(nums(l, 1, "the number of runs")?[0], l.0, "number of runs")?;
    if runs > MAX_RUNS {
        return Err(format!(
            "line {}: number of runs {runs} is over the limit of {MAX_RUNS}",
            l.0
        ));
    }
    let mut out = Vec::new();
    for _ in 0..runs {
        let run = parse_run(lines, out.len() + 1)?;
        out.push(run);
    }
    Ok(out)
}

/// Run number `index` (1-based): output file, photons, grid, layers.
fn parse_run(lines: &mut DataLines<'_>, index: usize) -> Result<McmlRun, String> {
    let output_file = output_file_name(lines.next("output file name")?)?;
    let photons = lines.count("number of photons")? as u64;
    let l = lines.next("dz, dr")?;
    let d = nums(l, 2, "dz dr [cm]")?;
    if !(d[0] > 0.0 && d[1] > 0.0) {
        return Err(format!("line {}: dz and dr must be > 0", l.0));
    }
    let (nz, nr, na) = grid_counts(lines.next("nz, nr, na")?)?;
    let (n_above, layers, n_below) = parse_layers(lines)?;
    let stack = super::mci::run_stack(index, (n_above, layers, n_below), d[1], nr)?;
    Ok(McmlRun {
        output_file,
        photons,
        dz_cm: d[0],
        dr_cm: d[1],
        nz,
        nr,
        na,
        threshold_weight: ROULETTE_WEIGHT,
        stack,
    })
}

/// nz, nr, na, bounded by [`super::mci::MAX_GRID_CELLS`] before the A(r, z) and Rd(r, α) grids are
/// allocated from them.
fn grid_counts(l: Line<'_>) -> Result<(usize, usize, usize), String> {
    let g = nums(l, 3, "nz nr na")?;
    let (nz, nr, na) = (
        count(g[0], l.0, "nz")?,
        count(g[1], l.0, "nr")?,
        count(g[2], l.0, "na")?,
    );
    check_grid(l.0, nz, nr, na)?;
    Ok((nz, nr, na))
}

/// The layer block: number of layers, n above, one `n mua mus g d` line per layer (cm,
/// converted to mm), n below.
fn parse_layers(lines: &mut DataLines<'_>) -> Result<(f64, Vec<Layer>, f64), String> {
    let l = lines.next("number of layers")?;
    let nl = count(
        nums(l, 1, "the number of layers")?[0],
        l.0,
        "number of layers",
    )?;
    if nl > MAX_LAYERS {
        return Err(format!(
            "line {}: at most {MAX_LAYERS} layers are supported",
            l.0
        ));
    }
    let n_above = nums(lines.next("n of the medium above")?, 1, "n above")?[0];
    let mut layers = Vec::new();
    for i in 0..nl {
        let l = lines.next("layer line")?;
        let v = nums(l, 5, "a layer (n mua mus g d)")?;
        layers.push(Layer {
            name: format!("layer {}", i + 1),
            d_mm: v[4] * 10.0,
            eta: v[0],
            mua_per_mm: v[1] / 10.0,
            mus_per_mm: v[2] / 10.0,
            g: v[3],
        });
    }
    let n_below = nums(lines.next("n of the medium below")?, 1, "n below")?[0];
    Ok((n_above, layers, n_below))
}
