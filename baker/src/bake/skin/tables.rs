//! The skin-profile tables of a bake as groups and datasets (layout: formats/FORMAT.md): the
//! HDF5 and `.bkt` writers of [`crate::output`] write the same numbers from them.

use formats::OpticsEntry;

use crate::bake::request::Request;
use crate::output::tables::{Attr, Dataset, Group, Labels, Tables};
use crate::profile::{RgbProfile, SpectralProfile};
use crate::spec::SkinSpec;
use crate::spectral::ColourMap;

/// Format name and version written as root attributes.
pub const FORMAT: &str = "baker-skin-profiles";
pub const FORMAT_VERSION: u32 = 1;

/// The tables of a profile bake: provenance attributes, the colour group, one group per entry.
pub fn tables(
    spec: &SkinSpec,
    a: &Request,
    entries: &[OpticsEntry],
    spectral: &[SpectralProfile],
    rgb: &[RgbProfile],
    colour: &ColourMap,
) -> anyhow::Result<Tables> {
    let settings = &spec.profiles;
    let photons = a.photons.unwrap_or(settings.photons);
    let mut t = Tables {
        attrs: vec![
            ("format".into(), FORMAT.into()),
            ("format_version".into(), u64::from(FORMAT_VERSION).into()),
            ("spec_file".into(), spec.file.clone().into()),
            ("spec_sha256".into(), spec.sha256.clone().into()),
            ("baker_version".into(), env!("CARGO_PKG_VERSION").into()),
            ("photons".into(), photons.into()),
            ("seed".into(), settings.seed.into()),
            ("gaussians".into(), (settings.gaussians as u64).into()),
            ("max_photon_boost".into(), settings.max_photon_boost.into()),
            ("noise_target".into(), settings.noise_target.into()),
            ("absorption_reuse".into(), (!a.no_reuse).to_string().into()),
            (
                "entries".into(),
                serde_json::to_string(&entries.iter().map(|e| &e.name).collect::<Vec<_>>())?.into(),
            ),
            (
                "source".into(),
                "Rd(r, lambda): white Monte Carlo with absorption reuse, pencil beam at normal \
                 incidence entering at a random point of the junction's period, MCML-class \
                 multi-layer transport with the Eq. 1 junction (thesis 3.5)"
                    .into(),
            ),
        ],
        groups: vec![colour_group(colour)],
    };
    if let Some(c) = crate::output::manifest::created_utc() {
        t.attrs.push(("created_utc".into(), c.into()));
    }
    for ((e, p), r) in entries.iter().zip(spectral).zip(rgb) {
        t.groups.push(entry_group(e, entry_attrs(e, p), p, r));
    }
    Ok(t)
}

/// Attributes of an entry's group: its inputs as JSON and the ones renderers filter by.
fn entry_attrs(e: &OpticsEntry, p: &SpectralProfile) -> Vec<(String, Attr)> {
    let v = &e.inputs;
    let mut attrs: Vec<(String, Attr)> = vec![("params_json".into(), v.to_string().into())];
    for key in ["age_years", "gender", "location", "xi", "model"] {
        match v.get(key) {
            Some(serde_json::Value::String(s)) => attrs.push((key.into(), s.clone().into())),
            Some(x) => {
                if let Some(f) = x.as_f64() {
                    attrs.push((key.into(), f.into()));
                }
            }
            None => {}
        }
    }
    if let Some(t) = v
        .get("melanin")
        .and_then(|m| m.get("skin_type"))
        .and_then(|t| t.as_str())
    {
        attrs.push(("skin_type".into(), t.into()));
    }
    if let Some(f) = e
        .intermediate
        .get("melanosome_fraction")
        .and_then(|f| f.as_f64())
    {
        attrs.push(("melanosome_fraction".into(), f.into()));
    }
    attrs.push(("simulation_group".into(), (p.group as u64).into()));
    attrs
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
        labels: None,
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

/// The group of one entry: profiles, fit, layer optics, junction and surface.
pub fn entry_group(
    e: &OpticsEntry,
    attrs: Vec<(String, Attr)>,
    p: &SpectralProfile,
    rgb: &RgbProfile,
) -> Group {
    let nl = p.lambda_nm.len();
    let centres: Vec<f64> = p
        .r_edges_mm
        .windows(2)
        .map(|w| 0.5 * (w[0] + w[1]))
        .collect();
    let lr = || vec![Some("lambda_nm"), Some("r_mm")];
    let mut d = profile_datasets(p, centres, lr);
    d.extend(rgb_datasets(rgb, p.r_edges_mm.len() - 1));
    d.extend(fit_datasets(rgb));
    d.extend(optics_datasets(e, nl));
    d.extend(junction_surface_datasets(e));
    Group {
        name: e.name.clone(),
        attrs,
        datasets: d,
    }
}

/// The radial grid and the spectral profiles of an entry.
fn profile_datasets(
    p: &SpectralProfile,
    centres: Vec<f64>,
    lr: impl Fn() -> Vec<Option<&'static str>>,
) -> Vec<Dataset> {
    let nl = p.lambda_nm.len();
    let nr = p.r_edges_mm.len() - 1;
    vec![
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
    ]
}

/// The colour of an entry's profile: XYZ, RGB albedo and the RGB profiles.
fn rgb_datasets(rgb: &RgbProfile, nr: usize) -> Vec<Dataset> {
    vec![
        ds(
            "xyz",
            vec![3],
            rgb.xyz.to_vec(),
            "1",
            "CIE XYZ of rd_total_spectral (white Y = 1)",
            vec![None],
        ),
        ds(
            "albedo_rgb",
            vec![3],
            rgb.albedo_rgb.to_vec(),
            "1",
            "linear sRGB total diffuse reflectance",
            vec![None],
        ),
        ds(
            "albedo_rgb_se",
            vec![3],
            rgb.albedo_rgb_se.to_vec(),
            "1",
            "standard error of albedo_rgb",
            vec![None],
        ),
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
    ]
}

/// The sum-of-Gaussians fit of an entry's RGB profile.
fn fit_datasets(rgb: &RgbProfile) -> Vec<Dataset> {
    let ng = rgb.fit.variance_mm2.len();
    vec![
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
    ]
}

/// The layer optics of an entry.
fn optics_datasets(e: &OpticsEntry, nl: usize) -> Vec<Dataset> {
    let mut d = Vec::new();
    let nlay = e.layers.len();
    d.push(Dataset {
        labels: Some(Labels {
            attr: "layers",
            names: e.layers.iter().map(|l| l.name.clone()).collect(),
        }),
        ..ds(
            "optics/d_mm",
            vec![nlay],
            e.layers.iter().map(|l| l.d_mm).collect(),
            "mm",
            "layer thicknesses, top to bottom (names: attribute layers)",
            vec![None],
        )
    });
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
    d
}

/// The junction (Eq. 1) and surface parameters of an entry, one scalar dataset each.
fn junction_surface_datasets(e: &OpticsEntry) -> Vec<Dataset> {
    let mut d = Vec::new();
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
    d
}
