//! `baker plan` (every unit, fits included, and a time estimate) and the phase counts of the
//! JSON progress events (issue 20, item 6).

mod common;

use common::{baker_in as baker, events};

use common::SMALL_SKIN_SPEC as SKIN;

const FIBER: &str = "version: 1
bake: {resolution_deg: 15, photons_per_direction: 2048, seed: 5}
fibers:
  - {name: trilobal, type: polyester, section: {shape: trilobal}}
";

fn plan_json(d: &std::path::Path, spec: &str, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["plan", spec, "--out", "out", "--json"];
    args.extend(extra);
    let o = baker(d, &args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn plan_lists_fits_and_a_positive_estimate() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("skin.yaml"), SKIN).unwrap();
    let p = plan_json(d, "skin.yaml", &[]);
    let units = p["units"].as_array().unwrap();
    let fits: Vec<&str> = units
        .iter()
        .filter(|u| u["kind"] == "fit")
        .map(|u| u["id"].as_str().unwrap())
        .collect();
    assert_eq!(
        fits,
        ["skin/fit/light30", "skin/fit/dark30", "skin/fit/mid80"]
    );
    // 2 scattering groups × 3 wavelengths of transport, each with its pilot (the boost).
    assert_eq!(units.iter().filter(|u| u["kind"] == "transport").count(), 6);
    assert_eq!(units.iter().filter(|u| u["kind"] == "pilot").count(), 6);
    assert_eq!(p["total"], units.len());
    for u in units {
        let e = u["estimate_s"].as_f64().unwrap();
        assert!(e.is_finite() && e > 0.0, "{u}");
    }
    let total = p["estimate_s"].as_f64().unwrap();
    let sum: f64 = units
        .iter()
        .map(|u| u["estimate_s"].as_f64().unwrap())
        .sum();
    assert!(total.is_finite() && total > 0.0);
    assert!((total - sum).abs() <= 1e-9 * sum);

    let p = plan_json(d, "skin.yaml", &["--no-estimate"]);
    assert!(p["estimate_s"].is_null());
    assert!(p["units"]
        .as_array()
        .unwrap()
        .iter()
        .all(|u| u.get("estimate_s").is_none()));

    // The table: one line per unit, photons with SI prefixes, the estimate.
    let o = baker(
        d,
        &["plan", "skin.yaml", "--out", "out", "--photons", "2000000"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let t = String::from_utf8_lossy(&o.stdout);
    assert!(t.contains("skin/fit/mid80"), "{t}");
    assert!(t.contains(" 2.00 M "), "{t}");
    // 6 runs of 2 M photons and 6 pilots of 50 k (the noise target's 2.5 %).
    assert!(t.contains("12.3 M photons to trace (12,300,000)"), "{t}");
    assert!(t.contains("estimated "), "{t}");
}

#[test]
fn fiber_plan_estimates_every_unit() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("fiber.yaml"), FIBER).unwrap();
    let p = plan_json(d, "fiber.yaml", &[]);
    let units = p["units"].as_array().unwrap();
    assert!(!units.is_empty());
    for u in units {
        assert_eq!(u["kind"], "fiber");
        let e = u["estimate_s"].as_f64().unwrap();
        assert!(e.is_finite() && e > 0.0, "{u}");
    }
}

/// Checks the phase counts of one phase's events: indices rise by one, the last done index
/// is the phase's total, and the photons done end at the total.
fn check_phase(ev: &[serde_json::Value], phase: &str) -> u64 {
    let started = ev
        .iter()
        .find(|e| e["event"] == "phase_started" && e["phase"] == phase)
        .unwrap_or_else(|| panic!("no phase_started for {phase}"));
    let total = started["units"].as_u64().unwrap();
    let of = |kinds: &[&str]| -> Vec<&serde_json::Value> {
        ev.iter()
            .filter(|e| e["phase"] == phase && kinds.contains(&e["event"].as_str().unwrap()))
            .collect()
    };
    let done = of(&["unit_finished", "cache_hit"]);
    assert_eq!(done.len() as u64, total, "{phase}");
    let mut last_photons = 0;
    for (k, e) in done.iter().enumerate() {
        assert_eq!(e["index"], k as u64 + 1, "{phase}: {e}");
        assert_eq!(e["total"], total, "{phase}: {e}");
        let p = e["photons_done"].as_u64().unwrap();
        assert!(p >= last_photons, "{phase}: photons_done fell: {e}");
        last_photons = p;
    }
    let last = done.last().unwrap();
    assert_eq!(last["photons_done"], last["photons_total"], "{phase}");
    for (k, e) in of(&["unit_started"]).iter().enumerate() {
        assert_eq!(e["index"], k as u64 + 1, "{phase}: {e}");
        assert_eq!(e["total"], total);
    }
    assert!(ev
        .iter()
        .any(|e| e["event"] == "phase_finished" && e["phase"] == phase && e["units"] == total));
    total
}

#[test]
fn json_events_count_the_units_of_each_phase() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("skin.yaml"), SKIN).unwrap();
    let bake = |extra: &[&str]| {
        let mut args = vec!["bake", "skin.yaml", "--out", "out", "--progress", "json"];
        args.extend(extra);
        let o = baker(d, &args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        events(&o.stderr)
    };
    let ev = bake(&[]);
    assert_eq!(check_phase(&ev, "simulation"), 6);
    assert_eq!(check_phase(&ev, "fitting"), 3);
    let fits = ev
        .iter()
        .filter(|e| e["event"] == "unit_finished" && e["phase"] == "fitting");
    assert!(fits
        .clone()
        .all(|e| e["unit"].as_str().unwrap().contains("/fit/")));
    // The simulation's photons include the boost of cheap wavelengths.
    let sim_done = ev
        .iter()
        .rfind(|e| e["event"] == "unit_finished" && e["phase"] == "simulation")
        .unwrap();
    assert!(sim_done["photons_done"].as_u64().unwrap() >= 6 * 3000);
    // Pilot runs are outside the counts.
    assert!(ev
        .iter()
        .filter(|e| e["unit"].as_str().is_some_and(|u| u.contains("/pilot/")))
        .all(|e| e.get("index").is_none()));

    // All from the cache (an output deleted): the same counts, through cache hits.
    std::fs::remove_file(d.join("out/skin/profiles.bkt")).unwrap();
    let ev = bake(&[]);
    assert_eq!(check_phase(&ev, "simulation"), 6);
    assert_eq!(check_phase(&ev, "fitting"), 3);
    assert!(!ev.iter().any(|e| e["event"] == "unit_started"));

    // --progress none and --quiet keep stderr clean.
    for flags in [["--progress", "none"].as_slice(), ["-q"].as_slice()] {
        let mut args = vec!["bake", "skin.yaml", "--out", "out2", "--photons", "500"];
        args.extend(flags);
        let o = baker(d, &args);
        assert!(o.status.success());
        assert_eq!(String::from_utf8_lossy(&o.stderr), "", "{flags:?}");
    }
}

#[test]
fn fiber_events_count_directions_per_entry() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("fiber.yaml"), FIBER).unwrap();
    let o = baker(
        d,
        &["bake", "fiber.yaml", "--out", "out", "--progress", "json"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ev = events(&o.stderr);
    let n = check_phase(&ev, "tracing");
    let p = plan_json(d, "fiber.yaml", &["--no-estimate"]);
    assert_eq!(p["total"], n);
}
