//! MCML input files (`.mci`, Wang, Jacques & Zheng 1995, file version 1.0) for one entry at one
//! wavelength, so users of MCML and its descendants can run our layer stacks.
//!
//! MCML works in cm and cm⁻¹. The thesis transports μs′ with an isotropic phase function, so
//! each layer is written with μs = μs′ and g = 0.

use std::fmt::Write;

use formats::OpticsEntry;

/// Grid and photon settings of the `.mci` run.
#[derive(Debug, Clone)]
pub struct MciRun {
    pub output_file: String,
    pub photons: u64,
    pub dz_mm: f64,
    pub dr_mm: f64,
    pub nz: u32,
    pub nr: u32,
    pub na: u32,
    /// Refractive index above the surface (air) and below the last layer.
    pub n_above: f64,
    pub n_below: f64,
}

impl MciRun {
    pub fn new(output_file: String, photons: u64) -> Self {
        Self {
            output_file,
            photons,
            dz_mm: 0.01,
            dr_mm: 0.01,
            nz: 700,
            nr: 500,
            na: 1,
            n_above: 1.0,
            // Below the hypodermis: tissue of the same index, so light leaving it is lost as
            // transmittance rather than reflected back.
            n_below: 1.44,
        }
    }
}

/// `.mci` text for wavelength index `i` of `e` (λ = `lambda_nm`).
pub fn mci(e: &OpticsEntry, i: usize, lambda_nm: f64, run: &MciRun) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# MCML input written by baker: entry {} at {lambda_nm} nm ({} model)",
        e.name, e.model
    );
    let _ = writeln!(
        s,
        "# mus = reduced scattering musp with g = 0 (thesis ch. 3); units cm, 1/cm"
    );
    s.push_str("1.0\t\t\t# file version\n1\t\t\t# number of runs\n\n");
    s.push_str("#### SPECIFY DATA FOR RUN 1\n#InParm\t\t\t# Input parameters. cm is used.\n");
    let _ = writeln!(s, "{} A\t\t# output file name, ASCII.", run.output_file);
    let _ = writeln!(s, "{}\t\t\t# No. of photons", run.photons);
    let _ = writeln!(
        s,
        "{} {}\t\t# dz, dr [cm]",
        run.dz_mm / 10.0,
        run.dr_mm / 10.0
    );
    let _ = writeln!(
        s,
        "{} {} {}\t\t# No. of dz, dr, da.\n",
        run.nz, run.nr, run.na
    );
    let _ = writeln!(s, "{}\t\t\t# Number of layers", e.layers.len());
    s.push_str("#n\tmua\tmus\tg\td\t# One line for each layer\n");
    let _ = writeln!(s, "{}\t\t\t# n for medium above", run.n_above);
    for l in &e.layers {
        let _ = writeln!(
            s,
            "{}\t{:.6}\t{:.6}\t0\t{:.6}\t# {}",
            l.eta,
            l.mua_per_mm[i] * 10.0,
            l.musp_per_mm[i] * 10.0,
            l.d_mm / 10.0,
            l.name
        );
    }
    let _ = writeln!(s, "{}\t\t\t# n for medium below", run.n_below);
    s
}
