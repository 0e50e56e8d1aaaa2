//! The fit's figures in words: the header lines of the text formats and the line on stderr.

use super::fit::FiberFit;

/// `x` exactly: the shortest decimal that reads back as the same double (f64 `Display`, no
/// exponent). What the engine files carry; 6 decimals would move β_n = 0.02 by 2·10⁻⁵ of
/// itself.
pub(super) fn exact(x: f64) -> String {
    format!("{x}")
}

/// [`exact`] values joined by `sep`.
pub(super) fn exact_list(v: &[f64], sep: &str) -> String {
    v.iter().map(|&x| exact(x)).collect::<Vec<_>>().join(sep)
}

/// Values rounded to 6 decimals, for the summary's words.
pub(super) fn list(v: &[f64], sep: &str) -> String {
    v.iter()
        .map(|x| format!("{x:.6}"))
        .collect::<Vec<_>>()
        .join(sep)
}

/// Lines of the fit summary shared by the text formats.
pub(super) fn summary(fit: &FiberFit) -> Vec<String> {
    let r = &fit.report;
    let ch = fit.channels.join(" ");
    vec![
        format!("table {} (variant {})", fit.table, fit.variant),
        format!(
            "Chiang et al. 2016 fit, as Mitsuba 3 hair.cpp evaluates it, averaged over the fiber width: \
             relative L1 error of f over the table's bins {:.4} (L2 {:.4}), per channel {ch}: L1 {}",
            r.rel_l1,
            r.rel_l2,
            list(&r.rel_l1_per_channel, " ")
        ),
        match fit.noise_l1 {
            Some(n) => format!(
                "the table's own Monte Carlo noise accounts for about {n:.4} of that (L1 of \
                 photon-count noise, an estimate)"
            ),
            None => "the table's noise level is unknown (no photon count in its metadata)".into(),
        },
        format!(
            "albedo {ch}: table {}, model {} (mean over θi {} deg; φi averaged: {} samples)",
            list(&r.albedo_table, " "),
            list(&r.albedo_model, " "),
            r.theta_i_deg
                .iter()
                .map(|t| format!("{t:.0}"))
                .collect::<Vec<_>>()
                .join(" "),
            r.phi_i_deg.len()
        ),
        format!(
            "eta {:.4}{}, beta_m {:.4}, beta_n {:.4}, alpha {:.3} deg, sigma_a (per fiber radius) {}",
            r.params.eta,
            if r.eta_fixed {
                " (from the table)"
            } else {
                " (fitted)"
            },
            r.params.beta_m,
            r.params.beta_n,
            r.params.alpha_deg,
            list(&r.params.sigma_a, " ")
        ),
        "fiber axis: the table's +z (the tip for cuticle scales) = the curve direction, first \
         control point to last"
            .to_string(),
    ]
}

/// The line printed on stderr for an export of `table` (the path as given).
pub(super) fn stderr_line(fit: &FiberFit, table: &str) -> String {
    let r = &fit.report;
    format!(
        "{} [{}]: Chiang fit relative L1 {:.3} (L2 {:.3}) over {} θi × {} φi; η {:.4}{}, β_m {:.3}, \
         β_n {:.3}, α {:.2}°, σa {}",
        table,
        fit.variant,
        r.rel_l1,
        r.rel_l2,
        r.theta_i_deg.len(),
        r.phi_i_deg.len(),
        r.params.eta,
        if r.eta_fixed { " (table)" } else { "" },
        r.params.beta_m,
        r.params.beta_n,
        r.params.alpha_deg,
        list(&r.params.sigma_a, ", "),
    )
}
