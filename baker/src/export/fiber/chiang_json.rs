//! `chiang`: everything about the fit, as JSON.

use serde_json::json;

use super::blender::blender_offset_rad;
use super::fit::FiberFit;

/// Fiber radius in mm from the table's `diameter_um`, if any.
fn radius_mm(metadata: &serde_json::Value) -> Option<f64> {
    metadata["diameter_um"]
        .as_f64()
        .filter(|d| d.is_finite() && *d > 0.0)
        .map(|d| 0.5e-3 * d)
}

/// The `chiang` target: everything, as JSON.
pub fn write_chiang(fit: &FiberFit) -> String {
    let r = &fit.report;
    let p = &r.params;
    let mua =
        radius_mm(&fit.metadata).map(|rmm| p.sigma_a.iter().map(|s| s / rmm).collect::<Vec<_>>());
    // The source path in "model" is part of the pinned output (the model is now in
    // baker/src/export/chiang/).
    let doc = json!({
        "format": "baker-chiang-hair-fit",
        "version": 1,
        "model": "Chiang et al. 2016 (Computer Graphics Forum 35(2)), far field: averaged over \
                  the fiber width h, evaluated as Mitsuba 3 src/bsdfs/hair.cpp (baker/src/export/chiang.rs)",
        "table": fit.table,
        "variant": fit.variant,
        "channels": fit.channels,
        "table_metadata": fit.metadata,
        "parameters": {
            "eta": p.eta,
            "eta_fixed": r.eta_fixed,
            "sigma_a": p.sigma_a,
            "sigma_a_units": "per unit fiber radius (dimensionless mu_a * r): the chord length in \
                              hair.cpp, pbrt-v4 bxdfs.cpp and Cycles is 2 cos(gamma_t)/cos(theta_t) radii",
            "mua_per_mm": mua,
            "beta_m": p.beta_m,
            "beta_n": p.beta_n,
            "alpha_deg": p.alpha_deg,
        },
        "fit": {
            "objective": "relative L1 error of f = albedo * f_normalised over the table's bins: \
                          sum |model - table| dOmega / sum table dOmega over the sampled theta_i, \
                          all theta_o x dphi bins and channels; the model is integrated over each bin; \
                          the table is averaged over the sampled phi_i",
            "rel_l1": r.rel_l1,
            "rel_l2": r.rel_l2,
            "rel_l1_per_channel": r.rel_l1_per_channel,
            "rel_l2_per_channel": r.rel_l2_per_channel,
            "noise_l1_estimate": fit.noise_l1,
            "albedo_table": r.albedo_table,
            "albedo_model": r.albedo_model,
            "theta_i_deg": r.theta_i_deg,
            "phi_i_deg": r.phi_i_deg,
            "evaluations": r.evaluations,
        },
        "targets": {
            "mitsuba": {
                "source": "mitsuba3 src/bsdfs/hair.cpp",
                "int_ior": p.eta, "ext_ior": 1.0, "sigma_a": p.sigma_a,
                "longitudinal_roughness": p.beta_m, "azimuthal_roughness": p.beta_n,
                "scale_tilt": p.alpha_deg,
            },
            "pbrt": {
                "source": "pbrt-v4 src/pbrt/materials.cpp HairMaterial::Create, src/pbrt/bxdfs.cpp HairBxDF",
                "sigma_a": p.sigma_a, "eta": p.eta, "beta_m": p.beta_m, "beta_n": p.beta_n,
                "alpha": p.alpha_deg,
            },
            "blender": {
                "source": "Blender intern/cycles/kernel/svm/closure.h, \
                           intern/cycles/kernel/closure/bsdf_principled_hair_chiang.h",
                "model": "Chiang", "parametrization": "Absorption coefficient",
                "Absorption Coefficient": p.sigma_a, "Roughness": p.beta_m,
                "Radial Roughness": p.beta_n, "Coat": 0.0, "IOR": p.eta,
                "Offset_rad": blender_offset_rad(p.alpha_deg), "Random Roughness": 0.0,
            },
        },
        "conventions": {
            "table_frame": "fiber axis +z; theta = asin(w.z), phi = atan2(w.y, w.x), dphi = phi_o - phi_i; \
                            w_i points towards the light",
            "mitsuba_local_frame": "hair.cpp: fiber tangent = local y, surface normal = local z; \
                                    sin(theta) = w.y, phi = atan2(w.z, w.x), h = sin(gamma(w_i)) = -x/sqrt(x^2+z^2); \
                                    table (x, y, z) = local (x, z, y)",
            "roles": "the table's w_i is the engine's wi (Mitsuba si.wi, pbrt wo); by the fiber's \
                      reciprocity that is the radiance a renderer needs",
            "alpha_sign": "Mitsuba/pbrt: R lobe peaks at theta_i + theta_o = +2 alpha; Cycles: at -2 Offset",
            "tests": "near: Mitsuba Hair::eval with si.wi = wi_local (si.sh_frame = identity), wo = wo_local; \
                      far: (1/2) integral over h in [-1, 1] of the near value at wi = (-h cos ti, sin ti, sqrt(1-h^2) cos ti), \
                      wo at theta_o and azimuth phi(wi) + dphi",
        },
        "tests": fit.tests,
    });
    let mut s = serde_json::to_string_pretty(&doc).expect("serialisable");
    s.push('\n');
    s
}
