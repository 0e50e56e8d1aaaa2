//! One CSV per entry: λ, then μa and μs′ of every layer; structure and surface in the header.

use std::fmt::Write;

use formats::OpticsEntry;

/// CSV text for `e`. Header lines start with `#`; then one column-name row and nλ rows.
pub fn entry_csv(lambda_nm: &[f64], e: &OpticsEntry) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# baker skin optics: entry {} ({} model)",
        e.name, e.model
    );
    let _ = writeln!(
        s,
        "# units: lambda_nm nm; mua_*, musp_* per mm (musp = reduced scattering, g = 0)"
    );
    for l in &e.layers {
        let _ = writeln!(s, "# layer {:?}: d_mm={} eta={}", l.name, l.d_mm, l.eta);
    }
    let j = &e.junction;
    let _ = writeln!(
        s,
        "# junction (Eq. 1): z_mean_mm={} amplitude_mm={} omega_x_per_mm={} omega_y_per_mm={} phi_x_rad={} phi_y_rad={}",
        j.z_mean_mm, j.amplitude_mm, j.omega_x_per_mm, j.omega_y_per_mm, j.phi_x_rad, j.phi_y_rad
    );
    let f = &e.surface;
    let _ = writeln!(
        s,
        "# surface: rz_um={} sebum_mg_per_10cm2_3h={} beckmann_m={} f0={} eta={}",
        f.rz_um, f.sebum_mg_per_10cm2_3h, f.beckmann_m, f.f0, f.eta
    );
    let keys: Vec<String> = e.layers.iter().map(|l| l.name.replace(' ', "_")).collect();
    s.push_str("lambda_nm");
    for k in &keys {
        let _ = write!(s, ",mua_{k}_per_mm,musp_{k}_per_mm");
    }
    s.push('\n');
    for (i, lam) in lambda_nm.iter().enumerate() {
        let _ = write!(s, "{lam}");
        for l in &e.layers {
            let _ = write!(s, ",{},{}", l.mua_per_mm[i], l.musp_per_mm[i]);
        }
        s.push('\n');
    }
    s
}
