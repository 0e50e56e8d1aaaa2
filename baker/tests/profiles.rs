//! Diffusion profiles (thesis §3.5): the trends of Figs. 37–41, absorption reuse against
//! separate simulations, and the `bake` products (byte-identical for any thread count).

mod common;

use std::path::Path;

use baker::profile::{self, RgbProfile, SimOptions, SpectralProfile};
use baker::spec::load_str;
use baker::spectral::ColourMap;
use baker::transport::RadialBins;
use common::{baker, stderr};

struct Baked {
    names: Vec<String>,
    spectral: Vec<SpectralProfile>,
    rgb: Vec<RgbProfile>,
    /// (done, total) of every progress report, in order.
    progress: Vec<(usize, usize)>,
}

/// Bakes every entry of `yaml` in memory, with `reuse` as asked.
fn bake(yaml: &str, photons: u64, reuse: bool, max_boost: u64) -> Baked {
    let o = SimOptions {
        photons,
        seed: 11,
        threads: None,
        max_boost,
        noise: None,
        progress: None,
    };
    bake_with(yaml, reuse, &o)
}

/// Bakes every entry of `yaml` in memory with options `o`.
fn bake_with(yaml: &str, reuse: bool, o: &SimOptions) -> Baked {
    let spec = load_str("test.yaml", yaml).unwrap();
    let lam = spec.wavelengths.lambda_nm();
    let entries: Vec<formats::OpticsEntry> = spec
        .entries
        .iter()
        .map(|e| {
            let o = baker::skin::evaluate(&e.params, &spec.wavelengths).unwrap();
            baker::skin::document::entry(&e.name, &e.params, &o)
        })
        .collect();
    let bins = RadialBins::fine_then_log(0.01, 1.1, 40.0);
    let plan = profile::plan(&entries, lam.len(), reuse);
    let mut progress = Vec::new();
    let spectral = profile::simulate(&entries, lam, &bins, &plan, o, |done, total, _| {
        progress.push((done, total))
    })
    .unwrap();
    // One progress report per (group, wavelength) task, counting 1, 2, … up to the total.
    let total = progress.last().map_or(0, |p| p.1);
    assert!(total > 0);
    assert_eq!(
        progress,
        (1..=total).map(|d| (d, total)).collect::<Vec<_>>()
    );
    let colour = ColourMap::new(lam);
    let rgb = spectral
        .iter()
        .map(|p| profile::rgb_profile(p, &colour, 6, baker::cancel::Cancel::NEVER).unwrap())
        .collect();
    Baked {
        names: entries.iter().map(|e| e.name.clone()).collect(),
        spectral,
        rgb,
        progress,
    }
}

impl Baked {
    fn get(&self, name: &str) -> (&SpectralProfile, &RgbProfile) {
        let k = self.names.iter().position(|n| n == name).unwrap();
        (&self.spectral[k], &self.rgb[k])
    }
}

/// Energy-weighted mean radius of channel `c`, mm (a width of the profile).
fn mean_radius(p: &SpectralProfile, r: &RgbProfile, c: usize) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (k, v) in r.rd_rgb_per_mm2.iter().enumerate() {
        let (a, b) = (p.r_edges_mm[k], p.r_edges_mm[k + 1]);
        let e = v[c] * std::f64::consts::PI * (b * b - a * a);
        num += e * 0.5 * (a + b);
        den += e;
    }
    num / den
}

const TRENDS: &str = r#"
version: 1
wavelengths: {start_nm: 400, stop_nm: 700, step_nm: 25}
defaults: {model: five_layer, gender: female, location: forearm, xi: 0.5}
sweeps:
  - name: "t{skin_type}_a{age}"
    skin_type: [I, II, III, IV, V, VI]
    age: [30, 80]
"#;

/// `a` exceeds `b` by more than three standard errors of the difference.
#[track_caller]
fn clearly_above(a: f64, a_se: f64, b: f64, b_se: f64, what: &str) {
    let z = (a - b) / (a_se * a_se + b_se * b_se).sqrt();
    assert!(z > 3.0, "{what}: {a} vs {b} (z = {z:.1})");
}

#[test]
fn trends_of_figures_37_to_41() {
    let b = bake(TRENDS, 40_000, true, 4);
    // Two simulation groups (one per age) serve the twelve entries.
    assert_eq!(b.spectral.iter().map(|p| p.group).max(), Some(1));
    let types = ["I", "II", "III", "IV", "V", "VI"];
    for age in [30, 80] {
        // Type I → VI: more melanin, monotonically darker in every channel. The six types of
        // an age share one simulation (the same photon paths), so their noise is common-mode:
        // the ordering is asserted strictly, without a noise allowance.
        for w in types.windows(2) {
            let (_, lighter) = b.get(&format!("t{}_a{age}", w[0]));
            let (_, darker) = b.get(&format!("t{}_a{age}", w[1]));
            for c in 0..3 {
                assert!(
                    lighter.albedo_rgb[c] > darker.albedo_rgb[c],
                    "age {age}, type {} vs {} channel {c}: {} vs {}",
                    w[0],
                    w[1],
                    lighter.albedo_rgb[c],
                    darker.albedo_rgb[c]
                );
            }
        }
        // Types two apart also beyond independent-noise error bars.
        for w in types.windows(3) {
            let (_, lighter) = b.get(&format!("t{}_a{age}", w[0]));
            let (_, darker) = b.get(&format!("t{}_a{age}", w[2]));
            for c in 0..3 {
                clearly_above(
                    lighter.albedo_rgb[c],
                    lighter.albedo_rgb_se[c],
                    darker.albedo_rgb[c],
                    darker.albedo_rgb_se[c],
                    &format!("age {age}, type {} vs {} channel {c}", w[0], w[2]),
                );
            }
        }
    }
    for t in types {
        // Older skin: higher albedo (less melanin and blood) and wider profiles (thinner,
        // less absorbing layers let light travel further: more translucent).
        let (p30, young) = b.get(&format!("t{t}_a30"));
        let (p80, old) = b.get(&format!("t{t}_a80"));
        for c in 0..3 {
            clearly_above(
                old.albedo_rgb[c],
                old.albedo_rgb_se[c],
                young.albedo_rgb[c],
                young.albedo_rgb_se[c],
                &format!("type {t} channel {c}: albedo at 80 vs 30"),
            );
        }
        for c in 0..2 {
            let (w80, w30) = (mean_radius(p80, old, c), mean_radius(p30, young, c));
            assert!(
                w80 > 1.05 * w30,
                "type {t} channel {c}: mean radius {w80} at 80 vs {w30} at 30"
            );
        }
    }
}

#[test]
fn absorption_reuse_agrees_with_one_simulation_per_entry() {
    let yaml = r#"
version: 1
wavelengths: {list_nm: [420, 560, 680]}
defaults: {model: five_layer, gender: male, location: face, age: 55}
sweeps:
  - name: "t{skin_type}_xi{xi}"
    skin_type: [II, V]
    xi: [0, 1]
"#;
    let shared = bake(yaml, 30_000, true, 1);
    let separate = bake(yaml, 30_000, false, 1);
    assert!(shared.spectral.iter().all(|p| p.group == 0));
    assert_eq!(separate.spectral.iter().map(|p| p.group).max(), Some(3));
    let mut worst = 0.0f64;
    for (a, b) in shared.spectral.iter().zip(&separate.spectral) {
        for i in 0..3 {
            let z = (a.rd_total[i] - b.rd_total[i])
                / (a.rd_total_se[i].powi(2) + b.rd_total_se[i].powi(2)).sqrt();
            worst = worst.max(z.abs());
            let zt =
                (a.tt[i] - b.tt[i]) / (a.tt_se[i].powi(2) + b.tt_se[i].powi(2)).sqrt().max(1e-300);
            assert!(zt.abs() < 4.5 || a.tt[i] < 1e-9, "Tt z = {zt}");
        }
    }
    // 12 independent comparisons: |z| < 4.5 fails by chance with probability < 1e-4.
    assert!(worst < 4.5, "worst |z| = {worst}");
}

#[test]
fn noise_target_keeps_the_uniform_bakes_noise_and_is_unbiased() {
    // Types I and VI at the junction's age, 415–700 nm: the allocation moves packets between
    // wavelengths; every spectral and RGB bin must agree with the uniform bake (z-scores
    // and χ² over the radial bins) and the RGB bins be no noisier than it (up to the pilots'
    // own error).
    let yaml = r#"
version: 1
wavelengths: {list_nm: [415, 450, 500, 550, 600, 650, 700]}
defaults: {model: five_layer, gender: female, location: face, age: 30, xi: 0}
sweeps:
  - name: "t{skin_type}"
    skin_type: [I, VI]
"#;
    const TARGET: f64 = 0.01;
    let photons = 20_000;
    let uniform = bake_with(
        yaml,
        true,
        &SimOptions {
            photons,
            seed: 6,
            threads: None,
            max_boost: 1,
            noise: None,
            progress: None,
        },
    );
    let allocated = bake_with(
        yaml,
        true,
        &SimOptions {
            photons,
            seed: 5,
            threads: None,
            max_boost: 1,
            noise: profile::NoiseTarget::new(TARGET, photons),
            progress: None,
        },
    );
    let counts = &allocated.spectral[0].photons;
    assert!(
        counts.iter().any(|&n| n != photons),
        "the allocation changed nothing: {counts:?}"
    );
    // Spectral: per entry and wavelength, every bin out to 2 mm.
    for (u, a) in uniform.spectral.iter().zip(&allocated.spectral) {
        for i in 0..u.lambda_nm.len() {
            let (mut chi2, mut dof) = (0.0, 0usize);
            for k in 0..u.r_edges_mm.len() - 1 {
                let (su, sa) = (u.rd_per_mm2_se[i][k], a.rd_per_mm2_se[i][k]);
                if u.r_edges_mm[k + 1] > 2.0 || su == 0.0 || sa == 0.0 {
                    continue;
                }
                let z = (a.rd_per_mm2[i][k] - u.rd_per_mm2[i][k]) / (su * su + sa * sa).sqrt();
                assert!(z.abs() < 5.0, "{} nm, bin {k}: z = {z}", u.lambda_nm[i]);
                chi2 += z * z;
                dof += 1;
            }
            let (mean, tol) = (chi2 / dof as f64, 5.0 * (2.0 / dof as f64).sqrt());
            assert!(
                (mean - 1.0).abs() < tol,
                "{} nm: χ²/dof = {mean} over {dof} bins",
                u.lambda_nm[i]
            );
        }
    }
    // RGB: per channel, the bins inside min(2 mm, r99), where the bake measures noise.
    let (mut chi2, mut dof, mut ratios) = (0.0, 0usize, Vec::new());
    for (u, a) in uniform.rgb.iter().zip(&allocated.rgb) {
        let edges = &uniform.spectral[0].r_edges_mm;
        for c in 0..3 {
            let r_limit = u.r99_mm[c].min(2.0);
            // The worst relative SE of the channel, as the bake's summary reports it.
            let (mut worst_u, mut worst_a) = (0.0f64, 0.0f64);
            for k in 0..edges.len() - 1 {
                if 0.5 * (edges[k] + edges[k + 1]) > r_limit {
                    continue;
                }
                let (mu, su) = (u.rd_rgb_per_mm2[k][c], u.rd_rgb_per_mm2_se[k][c]);
                let (ma, sa) = (a.rd_rgb_per_mm2[k][c], a.rd_rgb_per_mm2_se[k][c]);
                if su == 0.0 || sa == 0.0 {
                    continue;
                }
                let z = (ma - mu) / (su * su + sa * sa).sqrt();
                assert!(z.abs() < 5.0, "channel {c}, bin {k}: z = {z}");
                chi2 += z * z;
                dof += 1;
                ratios.push((sa / ma) / (su / mu).max(TARGET));
                worst_u = worst_u.max(su / mu);
                worst_a = worst_a.max(sa / ma);
            }
            assert!(
                worst_a < 1.2 * worst_u.max(TARGET),
                "channel {c}: worst relative SE {worst_a} against the uniform bake's {worst_u}"
            );
        }
    }
    // χ² over `dof` bins: mean 1 per bin, sd √(2/dof); 5 sd either side.
    let mean = chi2 / dof as f64;
    let tol = 5.0 * (2.0 / dof as f64).sqrt();
    assert!(
        dof > 50 && (mean - 1.0).abs() < tol,
        "χ²/dof = {mean} over {dof} bins"
    );
    // Bin by bin, the relative SE is typically no worse than the uniform bake's (or 1 %); single
    // bins scatter by the SE estimates' own error (±20 % at 20,000 packets in dark skin).
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    assert!(median < 1.05, "median relative SE ratio {median}");
}

#[test]
fn the_profile_integrates_to_the_total_inside_the_grid() {
    let b = bake(
        "version: 1\nwavelengths: {list_nm: [600]}\nentries:\n  - {name: e, age: 40, gender: female, location: forearm, skin_type: III, xi: 0, model: five_layer}\n",
        20_000,
        true,
        1,
    );
    let p = &b.spectral[0];
    let binned: f64 = p.rd_per_mm2[0]
        .iter()
        .enumerate()
        .map(|(k, v)| {
            v * std::f64::consts::PI * (p.r_edges_mm[k + 1].powi(2) - p.r_edges_mm[k].powi(2))
        })
        .sum();
    // 40 mm holds everything but a vanishing tail.
    assert!(
        (binned - p.rd_total[0]).abs() <= 1e-3 * p.rd_total[0],
        "{binned} vs {}",
        p.rd_total[0]
    );
    let r = &b.rgb[0];
    assert!(
        r.r99_mm.iter().all(|v| v.is_finite() && *v < 40.0),
        "{:?}",
        r.r99_mm
    );
    // One progress report per (group, wavelength) task, counting up to the total.
    assert_eq!(b.progress, vec![(1, 1)]);
    // The fit has the Gaussians asked for, and stops when its flag is set.
    let colour = ColourMap::new(&[600.0]);
    let three = profile::rgb_profile(p, &colour, 3, baker::cancel::Cancel::NEVER).unwrap();
    assert_eq!(three.fit.variance_mm2.len(), 3);
    assert_eq!(three.fit.weight_rgb.len(), 3);
    let (flag, cancel) = baker::cancel::Cancel::fresh();
    flag.store(true, std::sync::atomic::Ordering::Relaxed);
    assert!(profile::rgb_profile(p, &colour, 3, cancel).is_err());
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn bake_writes_every_product_identically_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let run = |sub: &str, threads: &str| {
        let out = dir.path().join(sub);
        let o = baker(&[
            "bake",
            "tests/specs/profiles_small.yaml",
            "--photons",
            "3000",
            "--threads",
            threads,
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            o.stderr.is_empty(),
            "--quiet prints nothing: {}",
            stderr(&o)
        );
        out.join("profiles_small")
    };
    let a = run("a", "1");
    let b = run("b", "2");
    for f in [
        "profiles.bkt",
        "profiles_rgb.exr",
        "optics.json",
        "manifest.json",
    ] {
        assert!(
            read(&a.join(f)) == read(&b.join(f)),
            "{f} differs between 1 and 2 threads"
        );
    }
    let t = formats::table::TableFile::read(a.join("profiles.bkt")).unwrap();
    let nr = t.get("typeI_age30_xi0/r_mm").unwrap().shape[0];
    assert!(nr > 50);
    assert_eq!(
        t.get("typeI_age30_xi0/rd_rgb_per_mm2").unwrap().shape,
        vec![nr, 3]
    );
    assert_eq!(
        t.get("typeVI_age80_xi1/rd_spectral_per_mm2").unwrap().shape,
        vec![7, nr]
    );
    assert_eq!(
        t.get("typeI_age30_xi0/gaussians/weight_rgb").unwrap().shape,
        vec![6, 3]
    );
    assert_eq!(
        t.get("typeI_age30_xi0/rd_rgb_per_mm2")
            .unwrap()
            .attr("units"),
        Some("mm^-2")
    );
    assert!(read(&a.join("profiles.h5")).starts_with(b"\x89HDF\r\n\x1a\n"));
    let m: serde_json::Value = serde_json::from_slice(&read(&a.join("manifest.json"))).unwrap();
    assert_eq!(m["entries"].as_array().unwrap().len(), 8);
    for f in m["files"].as_array().unwrap() {
        let bytes = read(&a.join(f["path"].as_str().unwrap()));
        assert_eq!(bytes.len() as u64, f["bytes"].as_u64().unwrap());
    }
    assert!(a.join("preview/profiles/typeVI_age80_xi1.png").exists());
    let sheets = std::fs::read_dir(a.join("preview"))
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("contact_sheet"))
        .count();
    assert_eq!(sheets, 2, "one contact sheet per ξ");
}

/// Every `attribute NAME` a dataset's description of `g` names, checked to exist; returns
/// how many were checked.
fn referenced_attributes_exist(g: &hdf5_metno::Group) -> usize {
    let mut n = 0;
    for d in g.datasets().unwrap() {
        let desc: hdf5_metno::types::VarLenUnicode =
            d.attr("description").unwrap().read_scalar().unwrap();
        let desc = desc.as_str().to_string();
        for (_, rest) in desc
            .match_indices("attribute ")
            .map(|(i, _)| desc.split_at(i + 10))
        {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            assert!(
                d.attr_names().unwrap().contains(&name),
                "{}: the description {desc:?} names attribute {name:?}, which it lacks",
                d.name()
            );
            n += 1;
        }
    }
    for sub in g.groups().unwrap() {
        n += referenced_attributes_exist(&sub);
    }
    n
}

#[test]
fn skin_bake_writes_timing_and_the_attributes_its_descriptions_name() {
    let dir = tempfile::tempdir().unwrap();
    let o = baker(&[
        "bake",
        "tests/specs/profiles_small.yaml",
        "--entry",
        "typeVI_age80_xi1",
        "--photons",
        "2000",
        "--threads",
        "1",
        "--quiet",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a = dir.path().join("profiles_small");
    // profiles.h5: `optics/d_mm` names its layers in attribute `layers`, one per layer.
    let f = hdf5_metno::File::open(a.join("profiles.h5")).unwrap();
    assert!(referenced_attributes_exist(&f.group("/").unwrap()) >= 1);
    let d = f.dataset("typeVI_age80_xi1/optics/d_mm").unwrap();
    let layers: Vec<hdf5_metno::types::VarLenUnicode> =
        d.attr("layers").unwrap().read_raw().unwrap();
    let layers: Vec<&str> = layers.iter().map(|s| s.as_str()).collect();
    assert_eq!(layers.len(), d.size());
    assert_eq!(layers.first(), Some(&"stratum corneum"));
    assert_eq!(layers.last(), Some(&"hypodermis"));
    let t = formats::table::TableFile::read(a.join("profiles.bkt")).unwrap();
    assert_eq!(
        t.get("typeVI_age80_xi1/optics/d_mm")
            .unwrap()
            .attr("layers"),
        Some(layers.join(",").as_str())
    );
    // timing.json: wall seconds per phase, threads and photons, outside the manifest.
    let timing: serde_json::Value = serde_json::from_slice(&read(&a.join("timing.json"))).unwrap();
    let total = timing["seconds"].as_f64().unwrap();
    for phase in ["optics", "transport", "fits", "writing"] {
        let s = timing[format!("{phase}_seconds")].as_f64();
        assert!(
            s.is_some_and(|s| s >= 0.0 && s <= total),
            "{phase}: {timing}"
        );
    }
    assert_eq!(timing["threads"], 1, "{timing}");
    // One entry, one simulation group: the packets its table records per wavelength.
    let traced: f64 = t
        .get("typeVI_age80_xi1/photons_spectral")
        .unwrap()
        .as_f64()
        .unwrap()
        .iter()
        .sum();
    assert!(traced > 0.0);
    assert_eq!(timing["photons"].as_f64(), Some(traced), "{timing}");
    let m: serde_json::Value = serde_json::from_slice(&read(&a.join("manifest.json"))).unwrap();
    let files: Vec<&str> = m["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["path"].as_str().unwrap())
        .collect();
    assert!(!files.contains(&"timing.json"), "{files:?}");
    assert!(
        !m.to_string().contains("seconds"),
        "wall-clock time in the manifest"
    );
}

#[test]
fn bake_subset_and_unknown_entry() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let o = baker(&[
        "bake",
        "tests/specs/profiles_small.yaml",
        "--entry",
        "nobody",
        "--out",
        out,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no entry named \"nobody\""));
    let o = baker(&[
        "bake",
        "tests/specs/profiles_small.yaml",
        "--entry",
        "typeI_age30_xi0",
        "--photons",
        "2000",
        "--out",
        out,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let t =
        formats::table::TableFile::read(dir.path().join("profiles_small/profiles.bkt")).unwrap();
    assert!(t.get("typeI_age30_xi0/albedo_rgb").is_some());
    assert!(t.get("typeVI_age80_xi1/albedo_rgb").is_none());
}

#[test]
fn profile_settings_are_range_checked_with_their_location() {
    let text = "version: 1\nprofiles:\n  photons: 0\n  gaussians: 40\n  radial: {growth: 3}\nentries: []\n";
    let e = load_str("p.yaml", text).unwrap_err().to_string();
    assert!(
        e.contains("p.yaml:3:12") && e.contains("profiles.photons"),
        "{e}"
    );
    assert!(e.contains("p.yaml:4:14") && e.contains("[1, 16]"), "{e}");
    assert!(
        e.contains("profiles.radial.growth") && e.contains("[1.001, 2]"),
        "{e}"
    );
}
