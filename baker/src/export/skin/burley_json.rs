//! `burley`: the fit itself, as JSON.

use serde_json::{json, Value};

use super::{Provenance, SkinFit, Target};
use crate::export::burley;

fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn max_finite(v: impl Iterator<Item = f64>) -> f64 {
    v.filter(|x| x.is_finite()).fold(f64::NAN, f64::max)
}

/// Median and maximum per channel of a per-entry quantity.
fn stats(fits: &[SkinFit], f: impl Fn(&SkinFit) -> [f64; 3]) -> Value {
    let ch = |c: usize| fits.iter().map(|x| f(x)[c]).collect::<Vec<_>>();
    json!({
        "median": (0..3).map(|c| median(ch(c))).collect::<Vec<_>>(),
        "max": (0..3).map(|c| max_finite(ch(c).into_iter())).collect::<Vec<_>>(),
    })
}

/// JSON: per entry A, d, the mean free paths of the three conventions and the Burley fit error
/// next to the six-Gaussian error (both FORMAT.md's energy-weighted relative L1 error).
pub fn write_burley(fits: &[SkinFit], prov: &Provenance) -> String {
    let entries: Vec<Value> = fits
        .iter()
        .map(|f| {
            let per = |g: fn(f64, f64) -> f64| -> Vec<f64> {
                f.burley.iter().map(|b| g(b.a, b.d_mm)).collect()
            };
            json!({
                "name": f.name,
                "A_rgb": f.a_rgb(),
                "d_mm_rgb": f.d_mm_rgb(),
                "albedo_rgb": f.albedo_rgb,
                "r99_mm": f.r99_mm,
                "burley_error_rgb": f.burley_error_rgb(),
                "gaussian_error_rgb": f.gaussian_error_rgb,
                "mfp_mm_rgb": {
                    "volume_perpendicular": per(burley::volume_mfp_mm),
                    "volume_diffuse_transmission": per(burley::diffuse_transmission_mfp_mm),
                    "dmfp": per(burley::dmfp_mm),
                },
                "eta": f.eta,
                "f0": f.f0,
            })
        })
        .collect();
    let doc = json!({
        "format": "baker-burley-fit",
        "version": 1,
        "generated_by": prov.line(Target::Burley),
        "table": prov.table,
        "baker_version": prov.baker_version,
        "spec_file": prov.spec_file,
        "model": "R_c(r) = A_c (exp(-r/d_c) + exp(-r/(3 d_c))) / (8 pi d_c r), mm^-2; \
                  Christensen & Burley 2015, Pixar Tech Memo #15-04, Eq. 3",
        "annulus_energy": "A (F(b) - F(a)), F(r) = 1 - exp(-r/d)/4 - 3 exp(-r/(3d))/4 (Eq. 11)",
        "error": "energy-weighted relative L1 over annuli with r_edges_mm[k] < r99_mm[c] \
                  (formats/FORMAT.md, 'The sum-of-Gaussians fit'): the same error as \
                  gaussian_error_rgb; A is L1-optimal for each d (weighted median), d by \
                  log-grid scan and golden-section search",
        "units": {"A_rgb": "1", "d_mm_rgb": "mm", "r99_mm": "mm", "mfp_mm_rgb": "mm"},
        "conventions": {
            "volume_perpendicular": "l = d (1.85 - A + 7 |A - 0.8|^3): volume mean free path \
                1/sigma_t, perpendicular illumination (Christensen & Burley 2015); Unreal \
                GetPerpendicularScalingFactor; used for OpenPBR, pbrt-v4 and Mitsuba here",
            "volume_diffuse_transmission": "l = d (1.9 - A + 3.5 (A - 0.8)^2): volume mean \
                free path, diffuse surface transmission (Eq. 6); Cycles bssrdf_burley_fitting, \
                Chiang et al. 2016 random walk",
            "dmfp": "l_d = d (3.5 + 100 (A - 0.33)^4): diffuse mean free path; Unreal \
                GetSearchLightDiffuseScalingFactor (the Burley kernel of SubsurfaceProfile)",
        },
        "summary": {
            "entries": fits.len(),
            "burley_error_rgb": stats(fits, SkinFit::burley_error_rgb),
            "gaussian_error_rgb": stats(fits, |f| f.gaussian_error_rgb),
        },
        "entries": entries,
    });
    serde_json::to_string_pretty(&doc).expect("JSON of numbers and strings") + "\n"
}
