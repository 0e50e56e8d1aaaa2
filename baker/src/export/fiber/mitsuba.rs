//! `mitsuba`: a Mitsuba 3 scene file holding one `hair` BSDF.

use super::channels::Channels;
use super::fit::FiberFit;
use super::summary::{exact, exact_list, summary};
use crate::export::xml::xml_comment;

/// An XML id from a variant name.
fn xml_id(variant: &str) -> String {
    let body: String = variant
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("hair_{body}")
}

/// The `mitsuba` target: a Mitsuba 3 scene file with one named `hair` BSDF.
pub fn write_mitsuba(fit: &FiberFit) -> String {
    let p = &fit.report.params;
    let mut s = String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    s += "<!-- Mitsuba 3 hair BSDF written by baker export (target mitsuba).\n";
    for line in summary(fit) {
        s += &format!("     {}\n", xml_comment(&line));
    }
    s += "     Parameters (mitsuba3 src/bsdfs/hair.cpp): the fitted model is this plugin's;\n\
          \x20    int_ior/ext_ior = eta (ext_ior defaults to air, 1.000277, so it is set to 1);\n\
          \x20    sigma_a per unit fiber radius; scale_tilt in degrees.\n\
          \x20    Use: <include filename=\"this file\"/> in a scene, then <ref id=\"ID\"/> in a\n\
          \x20    bsplinecurve shape (its local y, the curve direction, is the fiber's +z). -->\n";
    let id = xml_id(&fit.variant);
    s += "<scene version=\"3.0.0\">\n";
    s += &format!("    <bsdf type=\"hair\" id=\"{id}\">\n");
    s += &format!(
        "        <float name=\"int_ior\" value=\"{}\"/>\n",
        exact(p.eta)
    );
    s += "        <float name=\"ext_ior\" value=\"1.0\"/>\n";
    match Channels::of(&fit.channels) {
        Channels::Spectral(nm) => {
            s += &format!(
                "        <spectrum name=\"sigma_a\" value=\"{}\"/>\n",
                nm.iter()
                    .zip(&p.sigma_a)
                    .map(|(l, &v)| format!("{l}:{}", exact(v)))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
        _ => {
            s += &format!(
                "        <rgb name=\"sigma_a\" value=\"{}\"/>\n",
                exact_list(&p.sigma_a, ", ")
            )
        }
    }
    s += &format!(
        "        <float name=\"longitudinal_roughness\" value=\"{}\"/>\n",
        exact(p.beta_m)
    );
    s += &format!(
        "        <float name=\"azimuthal_roughness\" value=\"{}\"/>\n",
        exact(p.beta_n)
    );
    s += &format!(
        "        <float name=\"scale_tilt\" value=\"{}\"/>\n",
        exact(p.alpha_deg)
    );
    s += "    </bsdf>\n</scene>\n";
    s
}
