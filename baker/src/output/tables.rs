//! The skin-profile tables of a bake as one neutral list of groups and datasets, so the HDF5
//! file and the native `.bkt` file hold exactly the same numbers (layout: formats/FORMAT.md).

use formats::OpticsEntry;

use crate::profile::{RgbProfile, SpectralProfile};
use crate::spectral::ColourMap;

/// Format name and version written as root attributes.
pub const FORMAT: &str = "baker-skin-profiles";
pub const FORMAT_VERSION: u32 = 1;

/// One f64 array.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    /// Path inside its group, e.g. `gaussians/variance_mm2`.
    pub name: String,
    pub shape: Vec<usize>,
    pub data: Vec<f64>,
    pub units: &'static str,
    pub description: &'static str,
    /// Per dimension, the dataset of the same group that is its scale (HDF5 dimension scale).
    pub dims: Vec<Option<&'static str>>,
}

/// An attribute value: HDF5 writes a scalar string, f64 or u64 attribute; `.bkt` a JSON
/// string or number.
#[derive(Debug, Clone, PartialEq)]
pub enum Attr {
    Text(String),
    Float(f64),
    Count(u64),
}

impl From<&str> for Attr {
    fn from(s: &str) -> Self {
        Attr::Text(s.to_string())
    }
}

impl From<String> for Attr {
    fn from(s: String) -> Self {
        Attr::Text(s)
    }
}

impl From<f64> for Attr {
    fn from(x: f64) -> Self {
        Attr::Float(x)
    }
}

impl From<u64> for Attr {
    fn from(n: u64) -> Self {
        Attr::Count(n)
    }
}

impl Attr {
    pub fn to_json(&self) -> serde_json::Value {
        match self {
            Attr::Text(s) => serde_json::Value::String(s.clone()),
            Attr::Float(x) => serde_json::json!(x),
            Attr::Count(n) => serde_json::json!(n),
        }
    }
}

/// A group: an entry, or `colour`.
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    pub name: String,
    pub attrs: Vec<(String, Attr)>,
    pub datasets: Vec<Dataset>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Tables {
    pub attrs: Vec<(String, Attr)>,
    pub groups: Vec<Group>,
}

fn ds(
    name: &str,
    shape: Vec<usize>,
    data: Vec<f64>,
    units: &'static str,
    description: &'static str,
    dims: Vec<Option<&'static str>>,
) -> Dataset {
    debug_assert_eq!(shape.iter().product::<usize>(), data.len(), "{name}");
    Dataset {
        name: name.to_string(),
        shape,
        data,
        units,
        description,
        dims,
    }
}

fn flat3(v: &[[f64; 3]]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}

fn flat(v: &[Vec<f64>]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}

pub fn colour_group(c: &ColourMap) -> Group {
    let n = c.lambda_nm.len();
    Group {
        name: "colour".into(),
        attrs: vec![
            ("observer".into(), "CIE 1931 2 degree".into()),
            ("illuminant".into(), "D65".into()),
            (
                "rgb".into(),
                "linear sRGB (IEC 61966-2-1), white diffuser = (1, 1, 1)".into(),
            ),
        ],
        datasets: vec![
            ds(
                "lambda_nm",
                vec![n],
                c.lambda_nm.clone(),
                "nm",
                "wavelengths",
                vec![None],
            ),
            ds(
                "xyz_weights",
                vec![n, 3],
                flat3(&c.xyz_weights),
                "1",
                "XYZ = sum_i R(lambda_i) * xyz_weights[i, :]",
                vec![Some("lambda_nm"), None],
            ),
            ds(
                "rgb_from_xyz",
                vec![3, 3],
                c.rgb_from_xyz.iter().flatten().copied().collect(),
                "1",
                "linear sRGB = rgb_from_xyz @ XYZ / white_rgb",
                vec![None, None],
            ),
            ds(
                "white_rgb",
                vec![3],
                c.white_rgb.to_vec(),
                "1",
                "rgb_from_xyz @ XYZ of the perfect white diffuser on this grid",
                vec![None],
            ),
        ],
    }
}

/// The group of one entry.
pub fn entry_group(
    e: &OpticsEntry,
    attrs: Vec<(String, Attr)>,
    p: &SpectralProfile,
    rgb: &RgbProfile,
) -> Group {
    let nl = p.lambda_nm.len();
    let nr = p.r_edges_mm.len() - 1;
    let ng = rgb.fit.variance_mm2.len();
    let centres: Vec<f64> = p
        .r_edges_mm
        .windows(2)
        .map(|w| 0.5 * (w[0] + w[1]))
        .collect();
    let lr = || vec![Some("lambda_nm"), Some("r_mm")];
    let mut d = vec![
        ds("lambda_nm", vec![nl], p.lambda_nm.clone(), "nm", "wavelengths", vec![None]),
        ds(
            "r_mm",
            vec![nr],
            centres,
            "mm",
            "radial bin centres (r_k + r_k+1)/2; 2*pi*r*dr is the annulus area",
            vec![None],
        ),
        ds(
            "r_edges_mm",
            vec![nr + 1],
            p.r_edges_mm.clone(),
            "mm",
            "annulus edges; bin k is [r_edges_mm[k], r_edges_mm[k+1])",
            vec![None],
        ),
        ds(
            "rd_spectral_per_mm2",
            vec![nl, nr],
            flat(&p.rd_per_mm2),
            "mm^-2",
            "diffuse reflectance per unit area, annulus average, unit pencil beam at normal incidence",
            lr(),
        ),
        ds(
            "rd_spectral_per_mm2_se",
            vec![nl, nr],
            flat(&p.rd_per_mm2_se),
            "mm^-2",
            "standard error of rd_spectral_per_mm2",
            lr(),
        ),
        ds(
            "photons_spectral",
            vec![nl],
            p.photons.iter().map(|&n| n as f64).collect(),
            "1",
            "photon packets traced per wavelength (the spec's count, raised where packets are cheap)",
            vec![Some("lambda_nm")],
        ),
        ds(
            "rd_total_spectral",
            vec![nl],
            p.rd_total.clone(),
            "1",
            "diffuse reflectance of scattered light over the whole plane (beyond the grid included)",
            vec![Some("lambda_nm")],
        ),
        ds(
            "rd_total_spectral_se",
            vec![nl],
            p.rd_total_se.clone(),
            "1",
            "standard error of rd_total_spectral",
            vec![Some("lambda_nm")],
        ),
        ds(
            "rd_unscattered_spectral",
            vec![nl],
            p.rd_unscattered.clone(),
            "1",
            "light returned by inner interfaces without scattering (at r = 0; not in the profiles)",
            vec![Some("lambda_nm")],
        ),
        ds(
            "rsp_spectral",
            vec![nl],
            p.rsp.clone(),
            "1",
            "specular reflectance of the surface at normal incidence (not in the profiles)",
            vec![Some("lambda_nm")],
        ),
        ds(
            "tt_spectral",
            vec![nl],
            p.tt.clone(),
            "1",
            "total transmittance through the bottom of the stack",
            vec![Some("lambda_nm")],
        ),
        ds(
            "tt_spectral_se",
            vec![nl],
            p.tt_se.clone(),
            "1",
            "standard error of tt_spectral",
            vec![Some("lambda_nm")],
        ),
        ds("xyz", vec![3], rgb.xyz.to_vec(), "1", "CIE XYZ of rd_total_spectral (white Y = 1)", vec![None]),
        ds(
            "albedo_rgb",
            vec![3],
            rgb.albedo_rgb.to_vec(),
            "1",
            "linear sRGB total diffuse reflectance",
            vec![None],
        ),
        ds("albedo_rgb_se", vec![3], rgb.albedo_rgb_se.to_vec(), "1", "standard error of albedo_rgb", vec![None]),
        ds(
            "rd_rgb_per_mm2",
            vec![nr, 3],
            flat3(&rgb.rd_rgb_per_mm2),
            "mm^-2",
            "linear sRGB diffusion profile, annulus average",
            vec![Some("r_mm"), None],
        ),
        ds(
            "rd_rgb_per_mm2_se",
            vec![nr, 3],
            flat3(&rgb.rd_rgb_per_mm2_se),
            "mm^-2",
            "standard error of rd_rgb_per_mm2",
            vec![Some("r_mm"), None],
        ),
        ds(
            "r99_mm",
            vec![3],
            rgb.r99_mm.to_vec(),
            "mm",
            "radius holding 99 % of each channel's diffuse energy",
            vec![None],
        ),
        ds(
            "gaussians/variance_mm2",
            vec![ng],
            rgb.fit.variance_mm2.clone(),
            "mm^2",
            "variances v of G(v, r) = exp(-r^2 / 2v) / (2 pi v), ascending",
            vec![None],
        ),
        ds(
            "gaussians/weight_rgb",
            vec![ng, 3],
            flat3(&rgb.fit.weight_rgb),
            "1",
            "per-channel weights: Rd_c(r) ~ sum_i weight_rgb[i, c] * G(variance_mm2[i], r)",
            vec![None, None],
        ),
        ds(
            "gaussians/error_rgb",
            vec![3],
            rgb.fit.error_rgb.to_vec(),
            "1",
            "energy-weighted relative error inside r99: sum|fit - table| A_k / sum table A_k",
            vec![None],
        ),
    ];
    let nlay = e.layers.len();
    d.push(ds(
        "optics/d_mm",
        vec![nlay],
        e.layers.iter().map(|l| l.d_mm).collect(),
        "mm",
        "layer thicknesses, top to bottom (names: attribute layers)",
        vec![None],
    ));
    d.push(ds(
        "optics/eta",
        vec![nlay],
        e.layers.iter().map(|l| l.eta).collect(),
        "1",
        "refractive indices",
        vec![None],
    ));
    d.push(ds(
        "optics/mua_per_mm",
        vec![nlay, nl],
        e.layers.iter().flat_map(|l| l.mua_per_mm.clone()).collect(),
        "mm^-1",
        "absorption coefficients per layer",
        vec![None, Some("lambda_nm")],
    ));
    d.push(ds(
        "optics/musp_per_mm",
        vec![nlay, nl],
        e.layers
            .iter()
            .flat_map(|l| l.musp_per_mm.clone())
            .collect(),
        "mm^-1",
        "reduced scattering coefficients per layer (transported with g = 0)",
        vec![None, Some("lambda_nm")],
    ));
    let j = &e.junction;
    for (name, v, units, description) in [
        (
            "junction/z_mean_mm",
            j.z_mean_mm,
            "mm",
            "mean depth of the dermo-epidermal junction (Eq. 1)",
        ),
        (
            "junction/amplitude_mm",
            j.amplitude_mm,
            "mm",
            "junction amplitude A (Eq. 1)",
        ),
        (
            "junction/omega_x_per_mm",
            j.omega_x_per_mm,
            "mm^-1",
            "junction frequency along x (Eq. 1)",
        ),
        (
            "junction/omega_y_per_mm",
            j.omega_y_per_mm,
            "mm^-1",
            "junction frequency along y (Eq. 1)",
        ),
        (
            "junction/phi_x_rad",
            j.phi_x_rad,
            "rad",
            "junction phase along x (Eq. 1)",
        ),
        (
            "junction/phi_y_rad",
            j.phi_y_rad,
            "rad",
            "junction phase along y (Eq. 1)",
        ),
    ] {
        d.push(ds(
            &format!("optics/{name}"),
            vec![],
            vec![v],
            units,
            description,
            vec![],
        ));
    }
    let s = &e.surface;
    for (name, v, units, description) in [
        (
            "rz_um",
            s.rz_um,
            "um",
            "mean peak-to-valley height Rz of the skin profile (section 3.4.2)",
        ),
        (
            "sebum_mg_per_10cm2_3h",
            s.sebum_mg_per_10cm2_3h,
            "mg/10cm^2/3h",
            "sebum production",
        ),
        (
            "sebum_film_um",
            s.sebum_film_um,
            "um",
            "sebum film thickness s (Eq. 13)",
        ),
        (
            "alpha_sr_rad",
            s.alpha_sr_rad,
            "rad",
            "alpha_sr = arctan(Rz / l_e) (section 3.4.2)",
        ),
        ("psi_s", s.psi_s, "1", "psi_s = 1 - a_s / a_t (Eq. 11)"),
        (
            "beckmann_m",
            s.beckmann_m,
            "1",
            "Beckmann roughness m = psi_s * alpha_sr (Eq. 11)",
        ),
        (
            "eta",
            s.eta,
            "1",
            "refractive index of the outer surface (stratum corneum, Table 1)",
        ),
        (
            "f0",
            s.f0,
            "1",
            "normal-incidence Fresnel reflectance from air",
        ),
    ] {
        d.push(ds(
            &format!("surface/{name}"),
            vec![],
            vec![v],
            units,
            description,
            vec![],
        ));
    }
    Group {
        name: e.name.clone(),
        attrs,
        datasets: d,
    }
}
