//! `pbrt`: a pbrt-v4 `Material "hair"` statement.

use super::channels::Channels;
use super::fit::FiberFit;
use super::summary::{exact, exact_list, summary};

/// pbrt-v4 `rgb`/`spectrum` value of σa.
fn pbrt_sigma_a(fit: &FiberFit) -> String {
    let s = &fit.report.params.sigma_a;
    match Channels::of(&fit.channels) {
        Channels::Spectral(nm) => format!(
            "\"spectrum sigma_a\" [ {} ]",
            nm.iter()
                .zip(s)
                .map(|(l, &v)| format!("{l} {}", exact(v)))
                .collect::<Vec<_>>()
                .join(" ")
        ),
        _ => format!("\"rgb sigma_a\" [ {} ]", exact_list(s, " ")),
    }
}

/// The `pbrt` target: a pbrt-v4 `Material "hair"` statement.
pub fn write_pbrt(fit: &FiberFit) -> String {
    let p = &fit.report.params;
    let mut s = String::from("# pbrt-v4 hair material written by `baker export --to pbrt`.\n");
    for line in summary(fit) {
        s += &format!("# {line}\n");
    }
    s += "# Parameters (pbrt-v4 src/pbrt/materials.cpp HairMaterial::Create, src/pbrt/bxdfs.cpp HairBxDF):\n\
          #   sigma_a per unit fiber radius (HairBxDF's chord is 2 cos(gamma_t)/cos(theta_t) radii);\n\
          #   beta_m, beta_n as in Chiang et al. 2016; alpha in degrees, the sign HairBxDF uses.\n\
          # Use it on \"curve\" shapes (type \"cylinder\") whose direction is the fiber's +z.\n";
    s += &format!(
        "Material \"hair\"\n    {}\n    \"float eta\" [ {} ]\n    \"float beta_m\" [ {} ]\n    \
         \"float beta_n\" [ {} ]\n    \"float alpha\" [ {} ]\n",
        pbrt_sigma_a(fit),
        exact(p.eta),
        exact(p.beta_m),
        exact(p.beta_n),
        exact(p.alpha_deg)
    );
    s
}
