//! `mitsuba`: a Mitsuba 3 medium per entry.

use std::fmt::Write as _;

use super::format::{identifiers, num, nums, split_max};
use super::{Provenance, SkinFit, Target};
use crate::export::burley;
use crate::export::xml::{xml_comment, xml_escape};

/// Mitsuba 3 XML: per entry a `null` BSDF (`<id>_boundary`) and a `homogeneous` medium (`<id>`)
/// to put inside a closed shape, rendered with the `volpathmis` integrator.
///
/// Mitsuba 3 has no BSSRDF plugin; the closest is volumetric path tracing of the medium the
/// fit describes. Christensen–Burley's perpendicular fit relates d to a medium of isotropic
/// scatterers seen by a normally incident beam: σt = 1/ℓ, ℓ = d·s_perpendicular(A), and the
/// single-scattering albedo is the one whose normal-incidence albedo is A
/// ([`burley::single_scattering_albedo`], Chandrasekhar's H-function), for an index-matched
/// boundary: hence the `null` BSDF. `sigma_t` is an RGB colour in \[0, 1\] (Mitsuba reads it
/// as a reflectance), so it holds σt/max σt and `scale` = max σt in mm⁻¹.
///
/// Measured with Mitsuba 3.9.1 (`scalar_rgb`, uniform white light, a cube face seen head-on,
/// 64k paths per channel), for α = 0.86 and σt in the ratios 0.235 : 0.39 : 1, where the
/// exact normal-incidence albedo is 0.3526: `volpath` renders 0.323, 0.347, 0.343 (it is not
/// made for chromatic media), `volpathmis` 0.351, 0.350, 0.350. Mitsuba's scalar variants are
/// single precision and offset spawned rays by about 1e-4 × the coordinates' magnitude: an
/// index-matched cube 2000 mean free paths across rendered 8 % dark. Keep the object centred
/// near the origin and no larger than a few hundred of its smallest mean free path.
pub fn write_mitsuba(fits: &[SkinFit], prov: &Provenance) -> String {
    let ids = identifiers(fits);
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    let _ = writeln!(
        s,
        "<!--\n  {}\n  Mitsuba 3: per skin entry a null boundary BSDF (id \"<entry>_boundary\") and a \
         homogeneous interior\n  medium (id \"<entry>\"), for a closed shape rendered with volpathmis (volpath gave channel-dependent\n  \
         albedos for chromatic media in our tests; single-precision ray offsets bias objects much\n  \
         larger than a few hundred of the smallest mean free path):\n    \
         <shape ...> <ref id=\"ENTRY_boundary\"/> <ref name=\"interior\" id=\"ENTRY\"/> </shape>\n  \
         Mitsuba 3 has no BSSRDF plugin; this is the medium whose searchlight profile is the fitted \
         Burley (A, d)\n  (Christensen & Burley 2015, Pixar Tech Memo #15-04): sigma_t = 1/l, \
         l = d (1.85 - A + 7|A - 0.8|^3),\n  albedo = the single-scattering albedo whose \
         normal-incidence albedo 1 - H(1) sqrt(1 - albedo) is A\n  (Chandrasekhar's H-function; \
         index-matched boundary, hence the null BSDF; isotropic phase). sigma_t holds sigma_t / max(sigma_t) and \"scale\" = max(sigma_t)\n  in 1/mm: \
         multiply scale by 1000 for a scene in metres. Colours: linear sRGB (use an *_rgb variant).\n-->",
        xml_comment(&prov.line(Target::Mitsuba))
    );
    s.push_str("<scene version=\"3.0.0\">\n");
    for (f, id) in fits.iter().zip(&ids) {
        let alpha = f.a_rgb().map(burley::single_scattering_albedo);
        let (sigma, scale) = split_max(f.volume_mfp_mm_rgb().map(|l| 1.0 / l));
        let _ = writeln!(
            s,
            "    <!-- {}: A = ({}), d = ({}) mm, Burley fit error ({}) -->\n    \
             <bsdf type=\"null\" id=\"{id}_boundary\"/>\n    \
             <medium type=\"homogeneous\" id=\"{id}\">\n        \
             <rgb name=\"albedo\" value=\"{}\"/>\n        \
             <rgb name=\"sigma_t\" value=\"{}\"/>\n        \
             <float name=\"scale\" value=\"{}\"/>\n        \
             <phase type=\"isotropic\"/>\n    \
             </medium>",
            xml_comment(&xml_escape(&f.name)),
            nums(&f.a_rgb()),
            nums(&f.d_mm_rgb()),
            nums(&f.burley_error_rgb()),
            nums(&alpha),
            nums(&sigma),
            num(scale),
        );
    }
    s.push_str("</scene>\n");
    s
}
