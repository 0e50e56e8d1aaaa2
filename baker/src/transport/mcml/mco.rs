//! MCML output files (`.mco`, version 1.2.2 layout): the input parameters, then the tallies
//! scaled as MCML's SumScaleResult does, in cm.

use std::f64::consts::PI;
use std::fmt::Write;

use super::grid::McmlGrid;
use super::mci::McmlRun;
use super::printf::{e4, g4, g6};
use crate::transport::tally::McResult;

/// The `.mco` text of a finished run, scaled as MCML's SumScaleResult does. As in MCML, Rsp is
/// the analytic specular reflectance and Rd everything else that leaves the surface, light
/// reflected back without scattering included. (MCML moves the multiple reflections of a clear
/// first layer into Rsp; here they stay in Rd.)
pub fn write_mco(run: &McmlRun, r: &McResult, g: &McmlGrid) -> String {
    let n = r.photons as f64;
    let mut s = String::new();
    write_input_parameters(&mut s, run, r);
    let sums = Sums1d::new(run, g);
    write_rat(&mut s, r, &sums, n);
    write_1d(&mut s, run, &sums, n);
    write_2d(&mut s, run, g, n);
    s
}

/// The file header and the `InParm` block: the run as MCML read it.
fn write_input_parameters(s: &mut String, run: &McmlRun, r: &McResult) {
    let (nz, nr, na) = (run.nz, run.nr, run.na);
    let (dz, dr) = (run.dz_cm, run.dr_cm);
    let _ = write!(s, "A1 \t# Version number of the file format.\n\n");
    s.push_str("####\n# Data categories include: \n# InParm, RAT, \n# A_l, A_z, Rd_r, Rd_a, Tt_r, Tt_a, \n# A_rz, Rd_ra, Tt_ra \n####\n\n");
    let _ = write!(
        s,
        "# User time: {:>8.0} sec = {:>8.2} hr.   Simulation time of this run.\n\n",
        r.seconds,
        r.seconds / 3600.0
    );
    s.push_str("InParm \t\t\t# Input parameters. cm is used.\n");
    let _ = writeln!(s, "{} \tA\t\t# output file name, ASCII.", run.output_file);
    let _ = writeln!(s, "{} \t\t\t# No. of photons", r.photons);
    let _ = writeln!(s, "{}\t{}\t\t# dz, dr [cm]", g6(dz), g6(dr));
    let _ = write!(s, "{}\t{}\t{}\t# No. of dz, dr, da.\n\n", nz, nr, na);
    let st = &run.stack;
    let _ = writeln!(s, "{}\t\t\t\t\t# Number of layers", st.layers.len());
    s.push_str("#n\tmua\tmus\tg\td\t# One line for each layer\n");
    let _ = writeln!(s, "{}\t\t\t\t\t# n for medium above", g6(st.n_above));
    for (i, l) in st.layers.iter().enumerate() {
        let d_cm = if l.d_mm.is_finite() {
            l.d_mm / 10.0
        } else {
            1e8
        };
        let _ = writeln!(
            s,
            "{}\t{}\t{}\t{}\t{}\t# layer {}",
            g6(l.eta),
            g6(l.mua_per_mm * 10.0),
            g6(l.mus_per_mm * 10.0),
            g6(l.g),
            g6(d_cm),
            i + 1
        );
    }
    let _ = write!(s, "{}\t\t\t\t\t# n for medium below\n\n", g6(st.n_below));
}

/// Sums of the raw 2D arrays (MCML: Sum2DRd, Sum2DA, Sum2DTt), photon weight.
struct Sums1d {
    rd_r: Vec<f64>,
    tt_r: Vec<f64>,
    rd_a: Vec<f64>,
    tt_a: Vec<f64>,
    a_z: Vec<f64>,
    /// Absorption per layer: each depth bin goes to the layer holding its centre.
    a_l: Vec<f64>,
}

impl Sums1d {
    fn new(run: &McmlRun, g: &McmlGrid) -> Self {
        let (nz, nr, na) = (run.nz, run.nr, run.na);
        let dz = run.dz_cm;
        let st = &run.stack;
        let rd_r: Vec<f64> = (0..nr)
            .map(|ir| g.rd_ra[ir * na..(ir + 1) * na].iter().sum())
            .collect();
        let tt_r: Vec<f64> = (0..nr)
            .map(|ir| g.tt_ra[ir * na..(ir + 1) * na].iter().sum())
            .collect();
        let rd_a: Vec<f64> = (0..na)
            .map(|ia| (0..nr).map(|ir| g.rd_ra[ir * na + ia]).sum())
            .collect();
        let tt_a: Vec<f64> = (0..na)
            .map(|ia| (0..nr).map(|ir| g.tt_ra[ir * na + ia]).sum())
            .collect();
        let a_z: Vec<f64> = (0..nz)
            .map(|iz| (0..nr).map(|ir| g.a_rz[ir * nz + iz]).sum())
            .collect();
        let z_bounds = st.boundaries_mm();
        let mut a_l = vec![0.0; st.layers.len()];
        for (iz, a) in a_z.iter().enumerate() {
            let zc_mm = (iz as f64 + 0.5) * dz * 10.0;
            let layer = (1..z_bounds.len())
                .find(|&i| zc_mm < z_bounds[i])
                .map_or(st.layers.len() - 1, |i| i - 1);
            a_l[layer] += a;
        }
        Self {
            rd_r,
            tt_r,
            rd_a,
            tt_a,
            a_z,
            a_l,
        }
    }
}

/// The `RAT` block (totals over `n` photons) and `A_l`.
fn write_rat(s: &mut String, r: &McResult, sums: &Sums1d, n: f64) {
    s.push_str("RAT #Reflectance, absorption, transmission. \n");
    let rd_total: f64 = sums.rd_r.iter().sum::<f64>() / n;
    let a_total: f64 = sums.a_z.iter().sum::<f64>() / n;
    let tt_total: f64 = sums.tt_r.iter().sum::<f64>() / n;
    let _ = writeln!(s, "{:<14} \t#Specular reflectance [-]", g6(r.rsp));
    let _ = writeln!(s, "{:<14} \t#Diffuse reflectance [-]", g6(rd_total));
    let _ = writeln!(s, "{:<14} \t#Absorbed fraction [-]", g6(a_total));
    let _ = write!(s, "{:<14} \t#Transmittance [-]\n\n", g6(tt_total));
    s.push_str("A_l #Absorption as a function of layer. [-]\n");
    for a in &sums.a_l {
        let _ = writeln!(s, "{}", g4(a / n));
    }
    s.push('\n');
}

/// Area of annulus `ir` of width `dr` cm, cm²: 2π·dr²·(ir + ½).
fn ring_cm2(dr: f64, ir: usize) -> f64 {
    2.0 * PI * dr * dr * (ir as f64 + 0.5)
}

/// One 1D array: its header line, then one `%12.4E` value per line, `v[i] / scale(i)`.
fn one_d(s: &mut String, header: &str, v: &[f64], scale: &dyn Fn(usize) -> f64) {
    s.push_str(header);
    for (i, x) in v.iter().enumerate() {
        let _ = writeln!(s, "{}", e4(x / scale(i)));
    }
    s.push('\n');
}

/// The 1D arrays A_z, Rd_r, Rd_a, Tt_r, Tt_a per unit depth, area or solid angle.
fn write_1d(s: &mut String, run: &McmlRun, sums: &Sums1d, n: f64) {
    let (dz, dr) = (run.dz_cm, run.dr_cm);
    let da = 0.5 * PI / run.na as f64;
    one_d(s, "A_z #A[0], [1],..A[nz-1]. [1/cm]\n", &sums.a_z, &|_| {
        n * dz
    });
    one_d(
        s,
        "Rd_r #Rd[0], [1],..Rd[nr-1]. [1/cm2]\n",
        &sums.rd_r,
        &|ir| n * ring_cm2(dr, ir),
    );
    let solid = |ia: usize| n * 2.0 * PI * da * ((ia as f64 + 0.5) * da).sin();
    one_d(
        s,
        "Rd_a #Rd[0], [1],..Rd[na-1]. [sr-1]\n",
        &sums.rd_a,
        &solid,
    );
    one_d(
        s,
        "Tt_r #Tt[0], [1],..Tt[nr-1]. [1/cm2]\n",
        &sums.tt_r,
        &|ir| n * ring_cm2(dr, ir),
    );
    one_d(
        s,
        "Tt_a #Tt[0], [1],..Tt[na-1]. [sr-1]\n",
        &sums.tt_a,
        &solid,
    );
}

/// One 2D array (`n2` columns per row): its header, then `%12.4E ` values five per line,
/// `v[k] / scale(row, column)`.
fn two_d(s: &mut String, header: &str, v: &[f64], n2: usize, scale: &dyn Fn(usize, usize) -> f64) {
    s.push_str(header);
    for (k, x) in v.iter().enumerate() {
        s.push_str(&e4(x / scale(k / n2, k % n2)));
        s.push(' ');
        if (k + 1) % 5 == 0 {
            s.push('\n');
        }
    }
    s.push('\n');
}

/// The 2D arrays A_rz per unit volume, Rd_ra and Tt_ra per unit area and solid angle.
fn write_2d(s: &mut String, run: &McmlRun, g: &McmlGrid, n: f64) {
    let (nz, na) = (run.nz, run.na);
    let (dz, dr) = (run.dz_cm, run.dr_cm);
    let da = 0.5 * PI / na as f64;
    two_d(
        s,
        "# A[r][z]. [1/cm3]\n# A[0][0], [0][1],..[0][nz-1]\n# A[1][0], [1][1],..[1][nz-1]\n# ...\n# A[nr-1][0], [nr-1][1],..[nr-1][nz-1]\nA_rz\n",
        &g.a_rz,
        nz,
        &|ir, _| n * ring_cm2(dr, ir) * dz,
    );
    let ra = |ir: usize, ia: usize| {
        n * 4.0
            * PI
            * PI
            * dr
            * dr
            * (da / 2.0).sin()
            * (ir as f64 + 0.5)
            * (2.0 * (ia as f64 + 0.5) * da).sin()
    };
    two_d(
        s,
        "# Rd[r][angle]. [1/(cm2sr)].\n# Rd[0][0], [0][1],..[0][na-1]\n# Rd[1][0], [1][1],..[1][na-1]\n# ...\n# Rd[nr-1][0], [nr-1][1],..[nr-1][na-1]\nRd_ra\n",
        &g.rd_ra,
        na,
        &ra,
    );
    two_d(
        s,
        "# Tt[r][angle]. [1/(cm2sr)].\n# Tt[0][0], [0][1],..[0][na-1]\n# Tt[1][0], [1][1],..[1][na-1]\n# ...\n# Tt[nr-1][0], [nr-1][1],..[nr-1][na-1]\nTt_ra\n",
        &g.tt_ra,
        na,
        &ra,
    );
}
