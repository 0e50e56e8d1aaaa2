//! Issue 6: the single-fiber tracer. Energy, the specular cone, reciprocity, determinism, the
//! spec and the command line. The closed-form check against a smooth dielectric cylinder
//! (Marschner et al. 2003) runs in CI as `validation/check_fiber_cylinder.py`.

mod common;

use baker::fiber::section::generate::{generate, Shape};
use baker::fiber::{trace, AngularGrid, Cuticle, Fiber, Incident, Section, Surface, TraceOptions};
use common::{baker, repo, stderr};

fn opts(photons: u64, seed: u64, res: f64, mua: &[f64]) -> TraceOptions {
    TraceOptions {
        photons,
        seed,
        grid: AngularGrid::new(res).unwrap(),
        mua_per_um: mua.to_vec(),
        progress: None,
    }
}

fn fiber(section: Section, eta: f64, beta_deg: f64, cuticle: Option<Cuticle>) -> Fiber {
    Fiber {
        section,
        surface: Surface {
            eta,
            alpha: beta_deg.to_radians().tan(),
        },
        cuticle,
    }
}

/// Every default cross-section, rough as in Table 9, without absorption: every intercepted
/// photon leaves (albedo 1: an analogue walk has no weight to lose), none is lost.
#[test]
fn white_furnace_every_fiber_type() {
    let cases = [
        (
            generate(Shape::Circle, 10.0, 1, 0).unwrap(),
            1.635,
            3.1,
            None,
        ),
        (
            generate(Shape::Trilobal, 10.0, 1, 0).unwrap(),
            1.635,
            3.1,
            None,
        ),
        (generate(Shape::Silk, 7.5, 1, 0).unwrap(), 1.5645, 6.5, None),
        (
            generate(Shape::CottonRaw, 18.5, 1, 0).unwrap(),
            1.555,
            15.5,
            None,
        ),
        (
            generate(Shape::CottonMercerised, 18.5, 1, 0).unwrap(),
            1.555,
            15.5,
            None,
        ),
        (
            generate(Shape::Wool, 30.0, 1, 0).unwrap(),
            1.5475,
            5.0,
            Some(Cuticle {
                length_um: 10.0,
                tilt_deg: 3.0,
            }),
        ),
    ];
    for (i, (s, eta, beta, cut)) in cases.into_iter().enumerate() {
        let f = fiber(s, eta, beta, cut);
        for (th, ph) in [(0.0, 0.0), (-45.0, 30.0), (70.0, 100.0)] {
            let r = trace(
                &f,
                Incident::from_deg(th, ph),
                &opts(20_000, 7, 2.0, &[0.0, 0.01]),
            );
            let t = &r.tally;
            assert_eq!(t.lost, 0, "case {i} θi {th}");
            let (a, se) = t.albedo(0);
            assert!(
                (a - 1.0).abs() < 1e-12,
                "case {i} θi {th}: albedo {a} ± {se}"
            );
            let (a_abs, _) = t.albedo(1);
            assert!(a_abs < 1.0 && a_abs > 0.0, "absorption lowers the albedo");
            // The 2D histogram sums to the albedo.
            let (h, _) = t.hist2d(0);
            assert!((h.iter().sum::<f64>() - a).abs() < 1e-9);
            if cut.is_none() {
                assert_eq!(t.intercepted, t.launched, "the beam is exactly the shadow");
                assert!((r.intercepted_width_um().0 - r.projected_width_um).abs() < 1e-9);
            }
        }
    }
}

/// Smooth fibers keep the axial direction component at every event: all energy leaves on
/// the specular cone θo = −θi (thesis Fig. 60), whatever the section.
#[test]
fn smooth_fibers_send_everything_to_the_specular_cone() {
    for s in [
        Section::circle(10.0),
        generate(Shape::Silk, 7.0, 2, 0).unwrap(),
        generate(Shape::CottonRaw, 18.0, 2, 0).unwrap(),
    ] {
        let f = fiber(s, 1.55, 0.0, None);
        for th in [-60.0, -25.0, 0.0, 35.0] {
            let o = opts(20_000, 3, 2.0, &[0.0]);
            // Off the bin edges (2° grid), so that rounding cannot split the cone.
            let th = th + 0.7;
            let r = trace(&f, Incident::from_deg(th, 17.0), &o);
            let (h, _) = r.tally.hist2d(0);
            let row = ((-th + 90.0) / 2.0) as usize;
            let on_cone: f64 = h[row * 180..(row + 1) * 180].iter().sum();
            assert!((on_cone - 1.0).abs() < 1e-12, "θi {th}: {on_cone}");
        }
    }
}

/// Reciprocity of the bin-averaged scattering cross-section per unit length:
/// ∫_A ∫_B W(φi) cos θi p(ωi → ωo) dωi dωo is symmetric in A and B (ωi towards the light, ωo
/// the direction of travel out; reversing a path swaps them). Traced with ωi spread over
/// each bin, so both sides average over the same pairs of bins.
#[test]
fn binned_scattering_is_reciprocal() {
    let f = fiber(
        generate(Shape::Silk, 8.0, 5, 0).unwrap(),
        1.5645,
        12.0,
        None,
    );
    let res = 10.0;
    let grid = AngularGrid::new(res).unwrap();
    // Bins as (θ row, φ centre in degrees).
    // φ centres differ by an odd multiple of res/2: Δφ bins are measured from the incident
    // centre with edges at multiples of res, so the outgoing bin then matches B exactly.
    let pairs = [
        ((-30.0, 40.0), (30.0, -95.0)),
        ((-10.0, 0.0), (20.0, 165.0)),
        ((-50.0, 10.0), (40.0, 35.0)),
    ];
    let photons = 1_500_000;
    for (k, ((ta, pa), (tb, pb))) in pairs.into_iter().enumerate() {
        let one_way = |(t0, p0): (f64, f64), (t1, p1): (f64, f64)| {
            let inc = Incident::from_deg(t0, p0).with_spread_deg(res, res);
            let r = trace(&f, inc, &opts(photons, 11 + k as u64, res, &[0.0]));
            let (h, se) = r.tally.hist2d(0);
            let it = ((t1 + 90.0) / res).floor() as usize;
            let mut dphi = p1 - p0;
            dphi -= 360.0 * ((dphi + 180.0) / 360.0).floor();
            let ip = ((dphi + 180.0) / res).floor() as usize;
            let b = it * grid.n_phi + ip;
            let t0r = t0.to_radians();
            let (h0, h1) = (
                (t0r - 0.5 * res.to_radians()).sin(),
                (t0r + 0.5 * res.to_radians()).sin(),
            );
            let omega_a = res.to_radians() * (h1 - h0);
            let scale = omega_a * f.section.projected_width_um(p0.to_radians()) * t0r.cos();
            (h[b] * scale, se[b] * scale)
        };
        // Bin centres: θ rows of the 10° grid have centres at −85, −75, …; use them.
        let c = |t: f64| ((t + 90.0) / res).floor() * res - 90.0 + 0.5 * res;
        let a = (c(ta), pa);
        let b = (c(tb), pb);
        let (s_ab, e_ab) = one_way(a, b);
        let (s_ba, e_ba) = one_way(b, a);
        let z = (s_ab - s_ba) / (e_ab * e_ab + e_ba * e_ba).sqrt();
        assert!(s_ab > 0.0 && s_ba > 0.0, "pair {k}: no photons in the bins");
        // Šidák for 3 pairs at family-wise 0.001: |z| < 3.4.
        assert!(
            z.abs() < 3.4,
            "pair {k}: {s_ab:.5e} ± {e_ab:.1e} vs {s_ba:.5e} ± {e_ba:.1e} (z {z:.2})"
        );
    }
}

#[test]
fn bit_identical_for_any_thread_count() {
    let f = fiber(
        generate(Shape::CottonRaw, 18.0, 1, 0).unwrap(),
        1.555,
        15.5,
        None,
    );
    let o = opts(150_000, 9, 2.0, &[0.0, 0.02]);
    let run = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(|| trace(&f, Incident::from_deg(-30.0, 20.0), &o).tally)
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a, b);
}

#[test]
fn one_trace_serves_every_absorption() {
    // Scoring μa afterwards equals a trace scored with that μa alone (same photons).
    let f = fiber(generate(Shape::Silk, 8.0, 1, 0).unwrap(), 1.5645, 6.5, None);
    let inc = Incident::from_deg(-20.0, 45.0);
    let all = trace(&f, inc, &opts(50_000, 4, 2.0, &[0.0, 0.01, 0.08])).tally;
    let one = trace(&f, inc, &opts(50_000, 4, 2.0, &[0.08])).tally;
    assert_eq!(all.sum[2], one.sum[0]);
    assert!(all.albedo(1).0 > all.albedo(2).0);
}

#[test]
fn cli_trace_json_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("slice.png");
    let o = baker(&[
        "fiber",
        "trace",
        "specs/fibers.yaml",
        "--entry",
        "silk",
        "--theta-i",
        "-45",
        "--phi-i",
        "10",
        "--photons",
        "50000",
        "--json",
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let a = v["albedo"].as_f64().unwrap();
    let sum: f64 = v["dphi_hist"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .sum();
    // The histogram holds the fractions rounded to f32 (`SliceResult::fraction`), the albedo
    // their full-precision sum: with the entry's split draws the weights are not the short
    // binary fractions of plain tracing, so the two differ by f32 roundings (~10⁻⁹ each).
    assert!(
        (sum - a).abs() < 1e-6 && a < 1.0 && a > 0.5,
        "dyed silk albedo {a}, histogram sum {sum}"
    );
    // The entry's own bins (specs/fibers.yaml bakes at 6°).
    assert_eq!(v["bake"]["resolution_deg"], 6.0);
    assert_eq!(v["hist2d"].as_array().unwrap().len(), 30);
    assert_eq!(v["dphi_edges_deg"].as_array().unwrap().len(), 61);
    assert!(v["photons_per_s"].as_f64().unwrap() > 0.0);
    assert!(image::open(&png).is_ok());
    // Command-line fibers.
    for section in ["circle", "ellipse:0.6", "cotton_mercerised"] {
        let o = baker(&[
            "fiber",
            "trace",
            "--section",
            section,
            "--theta-i",
            "20",
            "--photons",
            "20000",
            "--beta-deg",
            "5",
            "--json",
        ]);
        assert!(o.status.success(), "{section}: {}", stderr(&o));
    }
    let o = baker(&["fiber", "trace", "--section", "hexagon", "--theta-i", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("hexagon"), "{}", stderr(&o));
}

#[test]
fn polygon_csv_and_mask_sections_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    // A square with a square hole, written as CSV.
    let csv = dir.path().join("sq.csv");
    std::fs::write(
        &csv,
        "x_um,y_um\n-5,-5\n5,-5\n5,5\n-5,5\n\n-2,-2\n-2,2\n2,2\n2,-2\n",
    )
    .unwrap();
    let o = baker(&[
        "fiber",
        "trace",
        "--section",
        &format!("polygon:{}", csv.display()),
        "--theta-i",
        "0",
        "--photons",
        "20000",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["section"]["holes"], 1);
    assert!((v["section"]["area_um2"].as_f64().unwrap() - 84.0).abs() < 1e-9);
    assert!((v["projected_width_um"].as_f64().unwrap() - 10.0).abs() < 1e-9);
    // A ring mask (PNG) at 0.1 µm per pixel: outer radius 8 µm, lumen 3 µm.
    let png = dir.path().join("ring.png");
    let img = image::GrayImage::from_fn(200, 200, |x, y| {
        let r = ((x as f64 + 0.5 - 100.0).powi(2) + (y as f64 + 0.5 - 100.0).powi(2)).sqrt();
        image::Luma([if (30.0..80.0).contains(&r) { 255 } else { 0 }])
    });
    img.save(&png).unwrap();
    let o = baker(&[
        "fiber",
        "trace",
        "--section",
        &format!("mask:{}:0.1", png.display()),
        "--theta-i",
        "0",
        "--photons",
        "20000",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["section"]["holes"], 1);
    let want = std::f64::consts::PI * (64.0 - 9.0);
    let area = v["section"]["area_um2"].as_f64().unwrap();
    assert!((area / want - 1.0).abs() < 0.01, "{area} vs {want}");
    let bad = baker(&[
        "fiber",
        "trace",
        "--section",
        &format!("polygon:{}", dir.path().join("none.csv").display()),
        "--theta-i",
        "0",
    ]);
    assert_eq!(bad.status.code(), Some(2));
}

#[test]
fn fiber_spec_validates_and_reports_errors_with_lines() {
    let o = baker(&["validate", "specs/fibers.yaml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.yaml");
    std::fs::write(
        &bad,
        "version: 1\ndyes:\n  - name: loud\n    class: reactive\n    bands: [{peak_nm: 500, fwhm_nm: 80, peak_eps_l_per_mg_cm: 0.2}]\nfibers:\n  - name: a\n    type: nylon\n  - name: b\n    type: silk\n    dye: disperse_red_1\n    depth_of_shade_percent: 9\n  - name: c\n    type: cotton\n    section: {mask: missing.png, um_per_px: 0.1}\n",
    )
    .unwrap();
    let o = baker(&["validate", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    for want in [
        "bad.yaml:4:12: dyes.loud: peak extinction",
        "[0.005, 0.0158]",
        "bad.yaml:8:11: fibers.type = \"nylon\"",
        "one of polyester, silk, cotton, wool",
        "bad.yaml:12:29: fibers.depth_of_shade_percent = 9",
        "[0.1, 4]",
        "bad.yaml:15:21: fibers.section.mask",
    ] {
        assert!(e.contains(want), "missing {want:?} in:\n{e}");
    }
    let _ = repo();
}
