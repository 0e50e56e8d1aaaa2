//! The fiber writers, and fits of tables named in the environment.

use serde_json::json;

use super::summary::summary;
use super::*;
use crate::export::chiang::{ChiangParams, FitReport};

fn fit() -> FiberFit {
    let params = ChiangParams {
        eta: 1.635,
        sigma_a: vec![0.1, 0.5, 2.0],
        beta_m: 0.2,
        beta_n: 0.35,
        alpha_deg: -2.5,
    };
    FiberFit {
        table: "t.bcsdf".into(),
        variant: "disperse_red_1@1%".into(),
        channels: vec!["R".into(), "G".into(), "B".into()],
        metadata: json!({"diameter_um": 10.0}),
        report: FitReport {
            params: params.clone(),
            eta_fixed: true,
            rel_l1: 0.2,
            rel_l2: 0.3,
            rel_l1_per_channel: vec![0.2; 3],
            rel_l2_per_channel: vec![0.3; 3],
            albedo_table: vec![0.9, 0.5, 0.4],
            albedo_model: vec![0.88, 0.52, 0.41],
            theta_i_deg: vec![-30.0, 30.0],
            phi_i_deg: vec![0.0],
            evaluations: 1,
        },
        noise_l1: Some(0.05),
        tests: vec![],
    }
}

#[test]
fn writers_carry_the_parameters_in_each_engines_units() {
    let f = fit();
    let x = write_mitsuba(&f);
    assert!(x.contains("<bsdf type=\"hair\" id=\"hair_disperse_red_1_1_\">"));
    assert!(x.contains("<float name=\"scale_tilt\" value=\"-2.5\"/>"));
    assert!(x.contains("<rgb name=\"sigma_a\" value=\"0.1, 0.5, 2\"/>"));
    // No "--" inside XML comments.
    let comments: Vec<&str> = x.split("<!--").skip(1).collect();
    assert!(comments
        .iter()
        .all(|c| !c.split("-->").next().unwrap().contains("--")));
    let p = write_pbrt(&f);
    assert!(p.contains("\"rgb sigma_a\" [ 0.1 0.5 2 ]"));
    assert!(p.contains("\"float alpha\" [ -2.5 ]"));
    let b = write_blender(&f);
    // The fit's values exactly (Blender's check compares them with the fit's to 10⁻⁵).
    assert!(b.contains(&format!("OFFSET_RAD = {}", 2.5f64.to_radians())));
    assert!(b.contains("BETA_N = 0.35\n") && b.contains("SIGMA_A = (0.1, 0.5, 2)\n"));
    let j: serde_json::Value = serde_json::from_str(&write_chiang(&f)).unwrap();
    assert_eq!(j["parameters"]["beta_n"], 0.35);
    let mua = j["parameters"]["mua_per_mm"][2].as_f64().unwrap();
    assert!((mua - 2.0 / 0.005).abs() < 1e-9);
}

#[test]
fn writers_carry_the_fit_exactly() {
    // Values 6 decimals would round (β_n = 0.0123456789 by 2.6·10⁻⁵ of itself).
    let mut f = fit();
    let p = &mut f.report.params;
    (p.beta_m, p.beta_n, p.eta, p.alpha_deg) = (0.123456789, 0.0123456789, 1.5432109876, -2.75);
    p.sigma_a = vec![0.1234567, 1.0e-7, 2.0];
    let x = write_mitsuba(&f);
    assert!(x.contains("<float name=\"longitudinal_roughness\" value=\"0.123456789\"/>"));
    assert!(x.contains("<float name=\"azimuthal_roughness\" value=\"0.0123456789\"/>"));
    assert!(x.contains("<float name=\"int_ior\" value=\"1.5432109876\"/>"));
    assert!(x.contains("<rgb name=\"sigma_a\" value=\"0.1234567, 0.0000001, 2\"/>"));
    let p = write_pbrt(&f);
    assert!(p.contains("\"float beta_m\" [ 0.123456789 ]"));
    assert!(p.contains("\"float beta_n\" [ 0.0123456789 ]"));
    assert!(p.contains("\"float eta\" [ 1.5432109876 ]"));
    assert!(p.contains("\"rgb sigma_a\" [ 0.1234567 0.0000001 2 ]"));
    let m = write_mtlx(&f);
    assert_eq!(input_values(&m, "ior"), [1.5432109876]);
    assert_eq!(
        input_values(&m, "absorption_coefficient"),
        [0.1234567, 1.0e-7, 2.0]
    );
    let b = write_blender(&f);
    assert!(b.contains("BETA_N = 0.0123456789\n") && b.contains("IOR = 1.5432109876\n"));
}

/// Fits the tables listed in `BAKER_HAIR_TABLES` (`:`-separated) and prints the result:
/// `BAKER_HAIR_TABLES=a.bcsdf:b.bcsdf cargo test -p baker --lib fit_listed -- --ignored
/// --nocapture`.
#[test]
#[ignore]
fn fit_listed_tables() {
    let list = std::env::var("BAKER_HAIR_TABLES").unwrap_or_default();
    for path in list.split(':').filter(|p| !p.is_empty()) {
        let t = Bcsdf::open(path).unwrap();
        for v in 0..t.dir.variants.len() {
            let start = std::time::Instant::now();
            let f = fit_table(&t, v, path).unwrap();
            eprintln!("{:.1} s", start.elapsed().as_secs_f64());
            for line in summary(&f) {
                eprintln!("  {line}");
            }
        }
    }
}

#[test]
fn spectral_channels_become_spectra() {
    let mut f = fit();
    f.channels = vec!["450nm".into(), "550nm".into(), "650nm".into()];
    assert!(write_mitsuba(&f).contains("value=\"450:0.1, 550:0.5, 650:2\""));
    assert!(write_pbrt(&f).contains("\"spectrum sigma_a\" [ 450 0.1 550 0.5 650 2 ]"));
}

/// The numbers of MaterialX input `name`'s value in document `x`.
fn input_values(x: &str, name: &str) -> Vec<f64> {
    let at = x.find(&format!("<input name=\"{name}\"")).unwrap();
    let v = &x[at..];
    let v = &v[v.find("value=\"").unwrap() + 7..];
    v[..v.find('"').unwrap()]
        .split(", ")
        .map(|t| t.parse().unwrap())
        .collect()
}

#[test]
fn materialx_takes_the_fit_in_its_shaders_units() {
    let f = fit();
    let x = write_mtlx(&f);
    // v and s as MaterialX's mx_chiang_hair_roughness computes them from (beta_m, beta_n).
    let v = (0.726 * 0.2 + 0.812 * 0.04 + 3.7 * 0.2f64.powi(20)).powi(2);
    let s = 0.265 * 0.35 + 1.194 * 0.35f64.powi(2) + 5.372 * 0.35f64.powi(22);
    // The values exactly (6 decimals would be 10⁻⁵ of v off).
    let close = |got: &[f64], want: &[f64]| {
        got.len() == want.len()
            && got
                .iter()
                .zip(want)
                .all(|(g, w)| (g - w).abs() <= 1e-13 * w.abs())
    };
    assert!(close(&input_values(&x, "roughness_R"), &[v, s]));
    assert!(close(&input_values(&x, "roughness_TRT"), &[4.0 * v, s]));
    // alpha = -2.5 deg: the shader's tilt cuticle_angle*pi - pi/2 is +2.5 deg.
    let c = 0.5 + 2.5f64.to_radians() / std::f64::consts::PI;
    assert!(close(&input_values(&x, "cuticle_angle"), &[c]));
    assert!(
        (mtlx::mtlx_cuticle_angle(-2.5) * std::f64::consts::PI
            - std::f64::consts::FRAC_PI_2
            - 2.5f64.to_radians())
        .abs()
            < 1e-12
    );
    assert!(x.contains(
        "<input name=\"absorption_coefficient\" type=\"vector3\" value=\"0.1, 0.5, 2\" />"
    ));
    assert!(x.contains("<surfacematerial name=\"M_disperse_red_1_1_\" type=\"material\">"));
    let comments: Vec<&str> = x.split("<!--").skip(1).collect();
    assert!(comments
        .iter()
        .all(|c| !c.split("-->").next().unwrap().contains("--")));
}
