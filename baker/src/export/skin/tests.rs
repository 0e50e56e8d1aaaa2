//! The skin exports end to end, and the engines' conventions.

use serde_json::{json, Value};

use super::format::{identifiers, num, nums};
use super::*;
use crate::error::UsageError;
use crate::export::burley::{self, burley_energy, volume_mfp_mm, BurleyFit};
use crate::export::xml::xml_comment;
use crate::transport::RadialBins;
use formats::{Array, TableFile};
use std::f64::consts::PI;

const A: [f64; 3] = [0.55, 0.3, 0.2];
const D: [f64; 3] = [0.9, 0.25, 0.08];

/// A two-entry skin table whose profiles are exactly Burley (A, d) (entry 2: d × 1.5).
pub(crate) fn synthetic_table(dir: &std::path::Path) -> std::path::PathBuf {
    let edges = RadialBins::fine_then_log(0.01, 1.05, 40.0)
        .edges_mm()
        .to_vec();
    let nr = edges.len() - 1;
    let centres: Vec<f64> = edges.windows(2).map(|e| 0.5 * (e[0] + e[1])).collect();
    let names = ["typeI_age30_xi0.5", "typeVI_age80_xi1"];
    let meta = json!({
        "entries": serde_json::to_string(&names).unwrap(),
        "baker_version": "test",
        "spec_file": "synthetic.yaml",
    });
    let mut t = TableFile::new(formats::profile::KIND, meta);
    for (i, name) in names.iter().enumerate() {
        let d: Vec<f64> = D.iter().map(|d| d * (1.0 + 0.5 * i as f64)).collect();
        let mut rd = Vec::with_capacity(nr * 3);
        for k in 0..nr {
            let area = PI * (edges[k + 1] * edges[k + 1] - edges[k] * edges[k]);
            for c in 0..3 {
                rd.push(A[c] * burley_energy(d[c], edges[k], edges[k + 1]) / area);
            }
        }
        let arr = |q: &str, shape: Vec<u64>, v: Vec<f64>| {
            Array::new_f64(format!("{name}/{q}"), shape, v).unwrap()
        };
        t.push(arr("r_mm", vec![nr as u64], centres.clone()))
            .unwrap();
        t.push(arr("r_edges_mm", vec![nr as u64 + 1], edges.clone()))
            .unwrap();
        t.push(arr("rd_rgb_per_mm2", vec![nr as u64, 3], rd))
            .unwrap();
        t.push(arr("albedo_rgb", vec![3], A.to_vec())).unwrap();
        t.push(arr("surface/eta", vec![], vec![1.5])).unwrap();
        t.push(arr("surface/f0", vec![], vec![0.04])).unwrap();
        if i == 0 {
            t.push(arr("gaussians/variance_mm2", vec![1], vec![1.0]))
                .unwrap();
            t.push(arr("gaussians/weight_rgb", vec![1, 3], A.to_vec()))
                .unwrap();
            t.push(arr("gaussians/error_rgb", vec![3], vec![0.05, 0.04, 0.03]))
                .unwrap();
        }
    }
    let path = dir.join("profiles.bkt");
    t.write(&path, 3).unwrap();
    path
}

fn request(table: &std::path::Path, to: &str, entry: Option<&str>) -> ExportRequest {
    ExportRequest {
        table: table.to_path_buf(),
        to: to.into(),
        entries: entry.map(str::to_string).into_iter().collect(),
        method: None,
    }
}

#[test]
fn burley_export_recovers_the_generating_profile() {
    let dir = tempfile::tempdir().unwrap();
    let table = synthetic_table(dir.path());
    let export = export(&request(&table, "burley", None)).unwrap();
    assert_eq!(export.written.as_deref(), Some("2 entries"));
    assert_eq!(export.target, "burley");
    assert!(export.summary.unwrap().contains("Burley fit of 2 entries"));
    let doc: Value = serde_json::from_str(&export.text).unwrap();
    let entries = doc["entries"].as_array().unwrap();
    assert_eq!(entries.len(), 2);
    for (i, e) in entries.iter().enumerate() {
        for c in 0..3 {
            let a = e["A_rgb"][c].as_f64().unwrap();
            let d = e["d_mm_rgb"][c].as_f64().unwrap();
            let d_true = D[c] * (1.0 + 0.5 * i as f64);
            assert!((a / A[c] - 1.0).abs() < 0.01, "entry {i} ch {c}: A {a}");
            assert!((d / d_true - 1.0).abs() < 0.01, "entry {i} ch {c}: d {d}");
            let mfp = e["mfp_mm_rgb"]["volume_perpendicular"][c].as_f64().unwrap();
            assert!((mfp - volume_mfp_mm(a, d)).abs() < 1e-12);
            assert!(e["burley_error_rgb"][c].as_f64().unwrap() < 1e-6);
        }
    }
    // Gaussian errors are copied from the table; absent ones are null (NaN).
    assert_eq!(entries[0]["gaussian_error_rgb"][2].as_f64(), Some(0.03));
    assert!(entries[1]["gaussian_error_rgb"][0].is_null());
    assert_eq!(doc["summary"]["entries"].as_u64(), Some(2));
}

#[test]
fn every_target_writes_every_entry() {
    let dir = tempfile::tempdir().unwrap();
    let table = synthetic_table(dir.path());
    for t in Target::ALL {
        let text = export(&request(&table, t.name(), None)).unwrap().text;
        for name in ["typeI_age30_xi0", "typeVI_age80_xi1"] {
            assert!(text.contains(name), "{}: no {name}", t.name());
        }
        if matches!(t, Target::Burley | Target::Unity) {
            serde_json::from_str::<Value>(&text).unwrap();
        }
    }
    // --entry keeps one.
    let one = export(&request(&table, "mtlx", Some("typeVI_age80_xi1"))).unwrap();
    assert_eq!(one.written.as_deref(), Some("1 entry"));
    let text = one.text;
    assert_eq!(text.matches("<open_pbr_surface").count(), 1);
    assert!(text.contains("SR_typeVI_age80_xi1"));
}

#[test]
fn unknown_target_and_entry_are_usage_errors_listing_the_choices() {
    let dir = tempfile::tempdir().unwrap();
    let table = synthetic_table(dir.path());
    let e = export(&request(&table, "povray", None)).unwrap_err();
    let u = e.downcast_ref::<UsageError>().expect("usage error");
    assert!(
        u.0.contains("burley, mtlx, blender, unreal, unity, pbrt, mitsuba"),
        "{}",
        u.0
    );
    let e = export(&request(&table, "unreal", Some("typeIV"))).unwrap_err();
    let u = e.downcast_ref::<UsageError>().expect("usage error");
    assert!(
        u.0.contains("typeI_age30_xi0.5, typeVI_age80_xi1"),
        "{}",
        u.0
    );
}

fn fit_of(a: [f64; 3], d: [f64; 3]) -> SkinFit {
    SkinFit {
        name: "skin.1".into(),
        albedo_rgb: a,
        r99_mm: [1.0; 3],
        burley: std::array::from_fn(|c| BurleyFit {
            a: a[c],
            d_mm: d[c],
            error: 0.01,
        }),
        gaussian_error_rgb: [0.02; 3],
        eta: 1.5,
        f0: 0.04,
    }
}

#[test]
fn engine_values_follow_the_stated_conventions() {
    let f = fit_of(A, D);
    let prov = Provenance::default();
    // Unreal: MFP (cm) = 0.06 s_perp(A) d, and back through Unreal's own chain to d.
    let u: Value = serde_json::from_str(&write_unreal(std::slice::from_ref(&f), &prov)).unwrap();
    let p = &u["profiles"][0]["SubsurfaceProfile"];
    let dist = p["MeanFreePathDistance"].as_f64().unwrap();
    for (c, key) in ["R", "G", "B"].iter().enumerate() {
        let mfp = p["MeanFreePathColor"][key].as_f64().unwrap() * dist;
        let d = burley::unreal_d_mm(A[c], mfp);
        assert!((d / D[c] - 1.0).abs() < 1e-12, "{key}: {d}");
        assert_eq!(p["SurfaceAlbedo"][key].as_f64(), Some(A[c]));
    }
    // Unity: colour × multiplier = d.
    let h: Value = serde_json::from_str(&write_unity(std::slice::from_ref(&f), &prov)).unwrap();
    let p = &h["profiles"][0]["DiffusionProfile"];
    let m = p["scatteringDistanceMultiplier"].as_f64().unwrap();
    for (c, key) in ["r", "g", "b"].iter().enumerate() {
        let d = p["scatteringDistance"][key].as_f64().unwrap() * m;
        assert!((d / D[c] - 1.0).abs() < 1e-12);
    }
    // MaterialX: radius × scale = ℓ, colour = A/(1 − F0).
    let x = write_mtlx(std::slice::from_ref(&f), &prov);
    let value = |name: &str| -> Vec<f64> {
        let at = x.find(&format!("name=\"{name}\"")).unwrap();
        let v = &x[at..];
        let v = &v[v.find("value=\"").unwrap() + 7..];
        let row = crate::files::csv_rows::rows(&v[..v.find('"').unwrap()])
            .next()
            .unwrap()
            .unwrap();
        (0..row.len())
            .map(|i| row.number(i, name).unwrap())
            .collect()
    };
    let (radius, scale, colour) = (
        value("subsurface_radius")[0],
        value("subsurface_radius_scale"),
        value("subsurface_color"),
    );
    for c in 0..3 {
        let l = volume_mfp_mm(A[c], D[c]);
        assert!((radius * scale[c] / l - 1.0).abs() < 1e-5);
        assert!((colour[c] - A[c] / 0.96).abs() < 1e-6);
    }
    assert!(x.contains("name=\"SR_skin_1\""), "identifier: {x}");
    // Blender, Christensen–Burley: radius = 4π d.
    let b = blender::write_blender_with(std::slice::from_ref(&f), &prov, blender::Method::Burley);
    assert!(b.contains(&nums(&D.map(|d| 4.0 * PI * d))), "{b}");
    assert!(b.contains("METHOD = \"BURLEY\""), "{b}");
    // Mitsuba: scale × sigma_t = 1/ℓ.
    let m = write_mitsuba(&[f], &prov);
    assert!(
        m.contains("id=\"skin_1_boundary\"")
            && m.contains("<medium type=\"homogeneous\" id=\"skin_1\">")
    );
}

#[test]
fn unreal_small_mean_free_paths_move_into_the_colour() {
    let f = fit_of([0.5, 0.3, 0.2], [0.3, 0.1, 0.05]);
    let u: Value = serde_json::from_str(&write_unreal(&[f], &Provenance::default())).unwrap();
    let p = &u["profiles"][0]["SubsurfaceProfile"];
    assert_eq!(p["MeanFreePathDistance"].as_f64(), Some(0.1));
    let r = p["MeanFreePathColor"]["R"].as_f64().unwrap();
    let want = burley::unreal_mfp_cm(0.5, 0.3) / 0.1;
    assert!(r < 1.0 && (r - want).abs() < 1e-12, "{r} vs {want}");
}

#[test]
fn identifiers_are_valid_and_unique() {
    let mut a = fit_of(A, D);
    a.name = "x0.5".into();
    let mut b = a.clone();
    b.name = "x0_5".into();
    let mut c = a.clone();
    c.name = "9lives".into();
    assert_eq!(identifiers(&[a, b, c]), ["x0_5", "x0_5_2", "_9lives"]);
    assert_eq!(num(0.012345678), "0.01234568");
    assert_eq!(num(1234.56789), "1234.568");
    assert_eq!(xml_comment("a--b"), "a- -b");
}

/// Issue 22: one Unreal and one Unity profile pinned against the engines' own conversion code,
/// transcribed in `validation/engine_reference/engine_sss.py` from Unreal Engine 5.4's
/// `SubsurfaceProfile.cpp` / `BurleyNormalizedSSSCommon.ush` and HDRP's
/// `DiffusionProfileSettings.cs` (repositories, commits and quoted lines in that folder's
/// README.md). The numbers are `pinned.json`'s case 1 and 2: the fields that make each
/// engine render Burley (A, d) exactly, and, for HDRP, the filter radius it computes.
#[test]
fn unreal_and_unity_fields_match_the_engines_own_conversions() {
    struct Case {
        a: [f64; 3],
        d_mm: [f64; 3],
        unreal_color: [f64; 3],
        unreal_distance_cm: f64,
        hdrp_product_mm: [f64; 3],
        hdrp_filter_radius_mm: f64,
    }
    let cases = [
        Case {
            a: [0.85, 0.55, 0.35],
            d_mm: [1.2, 0.6, 0.3],
            unreal_color: [0.72063, 0.507375, 0.3848175],
            unreal_distance_cm: 0.1,
            hdrp_product_mm: [1.2, 0.6, 0.3],
            hdrp_filter_radius_mm: 19.87727850404809,
        },
        Case {
            a: [0.6, 0.3, 0.15],
            d_mm: [0.8, 0.35, 0.2],
            unreal_color: [0.62688, 0.50925, 0.434685],
            unreal_distance_cm: 0.1,
            hdrp_product_mm: [0.8, 0.35, 0.2],
            hdrp_filter_radius_mm: 13.251519002698727,
        },
    ];
    for (k, c) in cases.iter().enumerate() {
        let f = fit_of(c.a, c.d_mm);
        let u: Value = serde_json::from_str(&write_unreal(
            std::slice::from_ref(&f),
            &Provenance::default(),
        ))
        .unwrap();
        let p = &u["profiles"][0]["SubsurfaceProfile"];
        let dist = p["MeanFreePathDistance"].as_f64().unwrap();
        assert!(
            (dist - c.unreal_distance_cm).abs() < 1e-12,
            "case {k}: {dist}"
        );
        for (ch, key) in ["R", "G", "B"].iter().enumerate() {
            let got = p["MeanFreePathColor"][key].as_f64().unwrap();
            assert!(
                (got - c.unreal_color[ch]).abs() < 1e-9,
                "case {k} MeanFreePathColor.{key}: {got} vs Unreal's {}",
                c.unreal_color[ch]
            );
            assert_eq!(p["SurfaceAlbedo"][key].as_f64(), Some(c.a[ch]));
        }
        let h: Value = serde_json::from_str(&write_unity(&[f], &Provenance::default())).unwrap();
        let d = &h["profiles"][0]["DiffusionProfile"];
        let mult = d["scatteringDistanceMultiplier"].as_f64().unwrap();
        for (ch, key) in ["r", "g", "b"].iter().enumerate() {
            let product = d["scatteringDistance"][key].as_f64().unwrap() * mult;
            assert!(
                (product - c.hdrp_product_mm[ch]).abs() < 1e-12,
                "case {k} scatteringDistance.{key} × multiplier: {product}"
            );
        }
        if c.hdrp_filter_radius_mm.is_finite() {
            let r = h["profiles"][0]["derived"]["filter_radius_mm"]
                .as_f64()
                .unwrap();
            assert!(
                (r / c.hdrp_filter_radius_mm - 1.0).abs() < 1e-9,
                "case {k} filter radius {r} vs HDRP's {}",
                c.hdrp_filter_radius_mm
            );
        }
    }
}

/// Blender's random walks: Subsurface Radius = 4π·ℓ (`random-walk`) and ℓ/√(3(1 − α′))
/// (`random-walk-skin`), ℓ = d·(1.9 − C + 3.5(C − 0.8)²), C = A/(1 − F0), α′ Cycles' dipole
/// albedo of C; Base Color = C and IOR = η for every method.
#[test]
fn blender_methods_follow_cycles_conventions() {
    use blender::{blender_parameters, cycles_dipole_alpha_prime, Method};
    let f = fit_of(A, D);
    for m in Method::ALL {
        let p = blender_parameters(&f, m);
        assert_eq!(p.ior, 1.5);
        for c in 0..3 {
            let col = A[c] / 0.96;
            assert!((p.base_color[c] - col).abs() < 1e-12, "{m:?} {c}");
            let l = D[c] * (1.9 - col + 3.5 * (col - 0.8) * (col - 0.8));
            let want = match m {
                Method::Burley => 4.0 * PI * D[c],
                Method::RandomWalk => 4.0 * PI * l,
                Method::RandomWalkSkin => {
                    l / (3.0 * (1.0 - cycles_dipole_alpha_prime(col, 1.5))).sqrt()
                }
            };
            assert!((p.radius_mm[c] / want - 1.0).abs() < 1e-12, "{m:?} {c}");
        }
    }
    // The default is the skin walk, and the script says so.
    let prov = Provenance::default();
    let s = write_blender(std::slice::from_ref(&f), &prov);
    assert!(s.contains("METHOD = \"RANDOM_WALK_SKIN\""), "{s}");
    let skin = blender_parameters(&f, Method::RandomWalkSkin);
    assert!(s.contains(&nums(&skin.radius_mm)), "{s}");
    // Different methods give different radii (a walk's ℓ is not Burley's d).
    let walk = blender_parameters(&f, Method::RandomWalk).radius_mm[0];
    let burley = blender_parameters(&f, Method::Burley).radius_mm[0];
    assert!((walk / burley - 1.0).abs() > 0.05);
}

/// α′ inverts Jensen's dipole reflectance ½α′(1 + e^(−(4/3)A_J·s))e^(−s), s = √(3(1 − α′)),
/// within Cycles' 12 bisection steps (2⁻¹³ of the bracket), at several albedos and IORs,
/// against a 60-step bisection written here; and Cycles' end clamps.
#[test]
fn cycles_dipole_albedo_inverts_the_dipole() {
    use blender::cycles_dipole_alpha_prime;
    for eta in [1.33, 1.4, 1.5] {
        let inv = 1.0 / eta;
        let fdr = -1.44 * inv * inv + 0.71 * inv + 0.668 + 0.0636 * eta;
        let aj = (1.0 + fdr) / (1.0 - fdr);
        let rd = |ap: f64| {
            let s = (3.0 * (1.0 - ap)).sqrt();
            0.5 * ap * (1.0 + (-4.0 / 3.0 * aj * s).exp()) * (-s).exp()
        };
        for c in [0.01, 0.2, 0.45, 0.7, 0.9] {
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if rd(mid) < c {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            let ours = cycles_dipole_alpha_prime(c, eta);
            assert!(
                (ours - lo).abs() <= 1.0 / 4096.0,
                "η {eta} C {c}: {ours} vs {lo}"
            );
        }
    }
    assert_eq!(cycles_dipole_alpha_prime(5e-5, 1.4), 0.0);
    assert_eq!(cycles_dipole_alpha_prime(0.995, 1.4), 0.999999);
    // η is clamped to Cycles' [1.01, 3.8].
    assert_eq!(
        cycles_dipole_alpha_prime(0.3, 1.0),
        cycles_dipole_alpha_prime(0.3, 1.01)
    );
}

/// `--method`: a wrong name lists the methods; on another target or a fiber table, it is
/// refused before any table is read.
#[test]
fn method_is_checked() {
    let req = |to: &str, m: &str, table: &str| ExportRequest {
        table: table.into(),
        to: to.into(),
        entries: Vec::new(),
        method: Some(m.into()),
    };
    let usage = |r: anyhow::Result<crate::export::Export>| {
        let e = r.unwrap_err();
        e.downcast_ref::<UsageError>()
            .unwrap_or_else(|| panic!("not a usage error: {e:#}"))
            .0
            .clone()
    };
    let m = usage(export(&req("blender", "randomwalk", "p.bkt")));
    assert!(m.contains("not a Blender subsurface method"), "{m}");
    assert!(
        m.contains("allowed: burley, random-walk, random-walk-skin"),
        "{m}"
    );
    let m = usage(export(&req("mtlx", "burley", "p.bkt")));
    assert!(m.contains("--to mtlx has no method"), "{m}");
    let m = usage(crate::export::fiber::export(&req(
        "blender", "burley", "a.bcsdf",
    )));
    assert!(m.contains("a.bcsdf is a fiber table"), "{m}");
    // A valid method reaches the table (here: missing, so not a usage error about --method).
    let e = export(&req("blender", "random-walk", "/nowhere/p.bkt")).unwrap_err();
    assert!(!format!("{e:#}").contains("--method"), "{e:#}");
}

/// The exported script with each method, end to end from a table.
#[test]
fn blender_export_writes_the_chosen_method() {
    let dir = tempfile::tempdir().unwrap();
    let table = synthetic_table(dir.path());
    for m in blender::Method::ALL {
        let mut r = request(&table, "blender", None);
        r.method = Some(m.name().into());
        let text = export(&r).unwrap().text;
        assert!(
            text.contains(&format!("METHOD = \"{}\"", m.blender_enum())),
            "{}",
            m.name()
        );
        assert!(text.contains(&format!("--method {}", m.name())));
        assert_eq!(text.matches("    (\"type").count(), 2);
    }
}

#[test]
fn every_skin_export_reports_the_worst_fit_error_per_channel() {
    let dir = tempfile::tempdir().unwrap();
    let table = synthetic_table(dir.path());
    let fits: Vec<SkinFit> = ["typeI_age30_xi0", "typeVI_age80_xi1"]
        .iter()
        .map(|n| {
            let mut f = fit_of(A, D);
            f.name = n.to_string();
            f
        })
        .collect();
    let mut fits = fits;
    fits[1].burley[1].error = 0.25;
    let line = fit_summary(&fits, "p.bkt");
    assert!(
        line.contains("G 0.2500 (typeVI_age80_xi1), median 0.2500"),
        "{line}"
    );
    assert!(line.contains("R 0.0100 ("), "{line}");
    for t in Target::ALL {
        let e = export(&request(&table, t.name(), None)).unwrap();
        let s = e.summary.unwrap_or_default();
        assert!(s.contains("Burley fit of 2 entries"), "{}: {s}", t.name());
    }
}

#[test]
fn unreal_writes_an_editor_script_with_its_json_beside_it() {
    let dir = tempfile::tempdir().unwrap();
    let table = synthetic_table(dir.path());
    let e = export(&request(&table, "unreal", None)).unwrap();
    let crate::export::Layout::WithSide { ext, text, .. } = &e.layout else {
        panic!("{:?}", e.layout)
    };
    assert_eq!(*ext, "json");
    let json: Value = serde_json::from_str(text).unwrap();
    let p = &json["profiles"][1];
    assert_eq!(p["asset"], "SP_typeVI_age80_xi1");
    // The script carries the JSON's numbers exactly, under the Python API's names.
    let s = &e.text;
    assert!(s.contains("unreal.AssetToolsHelpers.get_asset_tools()"));
    assert!(s.contains("unreal.SubsurfaceProfileFactory()"));
    assert!(s.contains("unreal.EditorAssetLibrary.does_asset_exist(path)"));
    let sp = &p["SubsurfaceProfile"];
    let dist = sp["MeanFreePathDistance"].as_f64().unwrap();
    assert!(s.contains(&format!("\"mean_free_path_distance\": {dist:?},")));
    let c = &sp["MeanFreePathColor"];
    let rgb = [
        c["R"].as_f64().unwrap(),
        c["G"].as_f64().unwrap(),
        c["B"].as_f64().unwrap(),
    ];
    assert!(s.contains(&format!(
        "\"mean_free_path_color\": ({:?}, {:?}, {:?}),",
        rgb[0], rgb[1], rgb[2]
    )));
    assert!(s.contains("(\"SP_typeVI_age80_xi1\", \"typeVI_age80_xi1\", {"));
    assert_eq!(s.matches("\"enable_burley\": True").count(), 2);
    // Written with -o X.py: X.json beside it.
    let py = dir.path().join("skin.py");
    crate::export::layout::write(&e, Some(&py)).unwrap();
    assert_eq!(
        std::fs::read_to_string(dir.path().join("skin.json")).unwrap(),
        *text
    );
}

#[test]
fn unity_writes_one_hdrp_asset_and_meta_per_entry() {
    let dir = tempfile::tempdir().unwrap();
    let table = synthetic_table(dir.path());
    let e = export(&request(&table, "unity", None)).unwrap();
    let crate::export::Layout::Folder { files, index, .. } = &e.layout else {
        panic!("{:?}", e.layout)
    };
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names.len(), 5, "{names:?}");
    assert!(
        names.contains(&"typeI_age30_xi0_5.asset")
            && names.contains(&"typeI_age30_xi0_5.asset.meta")
    );
    let idx: Value = serde_json::from_str(&e.text).unwrap();
    assert_eq!(idx["files"].as_array().unwrap().len(), 5);
    assert_eq!(index, "profiles.json");
    let asset = &files
        .iter()
        .find(|(n, _)| n == "typeI_age30_xi0_5.asset")
        .unwrap()
        .1;
    assert!(asset.starts_with("%YAML 1.1\n%TAG !u! tag:unity3d.com,2011:\n--- !u!114 &11400000\n"));
    assert!(asset.contains(
        "  m_Script: {fileID: 11500000, guid: b2686e09ec7aef44bad2843e4416f057, type: 3}\n"
    ));
    assert!(asset.contains("  m_Version: 2\n") && asset.contains("    hash: 0\n"));
    // The colour times the multiplier is d (mm), in single precision.
    let p = &idx["profiles"][0]["DiffusionProfile"];
    let mult = p["scatteringDistanceMultiplier"].as_f64().unwrap();
    assert!(asset.contains(&format!(
        "    scatteringDistanceMultiplier: {}\n",
        mult as f32
    )));
    // The .meta GUID is deterministic (a re-export keeps it) and distinct per entry.
    let meta = |n: &str| files.iter().find(|(f, _)| f == n).unwrap().1.clone();
    let g0 = meta("typeI_age30_xi0_5.asset.meta");
    let g1 = meta("typeVI_age80_xi1.asset.meta");
    assert_ne!(g0, g1);
    let again = export(&request(&table, "unity", None)).unwrap();
    assert_eq!(again.layout, e.layout);
    let guid = g0.lines().find_map(|l| l.strip_prefix("guid: ")).unwrap();
    assert!(
        guid.len() == 32 && guid.chars().all(|c| c.is_ascii_hexdigit()),
        "{guid}"
    );
    assert_eq!(idx["profiles"][0]["guid"], guid);
}
