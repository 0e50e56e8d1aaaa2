//! BCSDF tables end to end: `baker bake` on small fiber specs, read back through the
//! renderer's reader (`formats::bcsdf`) and the HDF5 file.

mod common;

use common::bake_spec as bake;
use formats::bcsdf::{direction, Bcsdf};
use statrs::distribution::{ChiSquared, ContinuousCDF};

const WHITE: &str = "version: 1
bake: {resolution_deg: 10, photons_per_direction: 8192, seed: 5}
fibers:
  - {name: trilobal, type: polyester, section: {shape: trilobal}}
  - {name: silk, type: silk, section: {shape: silk}, seed: 2, sections: 2}
  - {name: wool, type: wool, diameter_um: 20}
";

#[test]
fn white_fibers_have_unit_albedo_and_the_sampler_passes_chi2() {
    let tmp = tempfile::tempdir().unwrap();
    let out = bake(tmp.path(), "white", WHITE, 2);
    for (entry, table) in [
        ("trilobal", "section-00"),
        ("silk", "average"),
        ("wool", "section-00"),
    ] {
        let t = Bcsdf::open(out.join(entry).join(format!("{table}.bcsdf"))).unwrap();
        // Without absorption every intercepted photon leaves: Λ = 1 (up to lost photons).
        for (i, a) in t.dir.albedo.iter().enumerate() {
            assert!((a - 1.0).abs() < 1e-5, "{entry}: Λ[{i}] = {a}");
        }
        // χ² of 200 000 samples against the pdf on an unaligned 13 × 17 grid of (θo, Δφ).
        for wi_deg in [[-40.0, 10.0], [-85.0, 77.0], [12.0, -130.0]] {
            let phi_i = f64::to_radians(wi_deg[1]);
            let wi = direction(f64::to_radians(wi_deg[0]), phi_i);
            chi2_sampler(&t, wi, phi_i, &format!("{entry} {wi_deg:?}"));
        }
    }
}

/// Exact expected counts: the pdf is constant on each table bin, a rectangle in (sin θ, Δφ).
fn chi2_sampler(t: &Bcsdf, wi: [f64; 3], phi_i: f64, what: &str) {
    use std::f64::consts::PI;
    let (nt, np) = (t.dir.n_theta, t.dir.n_phi);
    let r = t.dir.res_deg.to_radians();
    let (ct, cp) = (13usize, 17usize);
    let n = 200_000usize;
    let mut expected = vec![0.0; ct * cp];
    for it in 0..nt {
        for j in 0..np {
            let (t0, t1) = (-PI / 2.0 + it as f64 * r, -PI / 2.0 + (it + 1) as f64 * r);
            let (p0, p1) = (-PI + j as f64 * r, -PI + (j + 1) as f64 * r);
            let wo = direction(0.5 * (t0 + t1), phi_i + 0.5 * (p0 + p1));
            let p = t.pdf(wi, wo, 0).unwrap();
            if p == 0.0 {
                continue;
            }
            for a in 0..ct {
                let (a0, a1) = (
                    -PI / 2.0 + a as f64 * PI / ct as f64,
                    -PI / 2.0 + (a + 1) as f64 * PI / ct as f64,
                );
                let ds = (t1.min(a1).sin() - t0.max(a0).sin()).max(0.0);
                if ds == 0.0 {
                    continue;
                }
                for b in 0..cp {
                    let (b0, b1) = (
                        -PI + b as f64 * 2.0 * PI / cp as f64,
                        -PI + (b + 1) as f64 * 2.0 * PI / cp as f64,
                    );
                    let dp = (p1.min(b1) - p0.max(b0)).max(0.0);
                    expected[a * cp + b] += n as f64 * p * ds * dp;
                }
            }
        }
    }
    let mut observed = vec![0.0; ct * cp];
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let mut u = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..n {
        let s = t.sample(wi, 0, u(), u()).unwrap().unwrap();
        assert!(s.pdf > 0.0);
        let th = s.wo[2].clamp(-1.0, 1.0).asin();
        let mut dp = s.wo[1].atan2(s.wo[0]) - phi_i;
        dp -= 2.0 * PI * ((dp + PI) / (2.0 * PI)).floor();
        let a = (((th + PI / 2.0) / PI * ct as f64) as usize).min(ct - 1);
        let b = (((dp + PI) / (2.0 * PI) * cp as f64) as usize).min(cp - 1);
        observed[a * cp + b] += 1.0;
    }
    let (mut chi2, mut dof, mut ao, mut ae) = (0.0, 0usize, 0.0, 0.0);
    for k in 0..ct * cp {
        ao += observed[k];
        ae += expected[k];
        if ae >= 5.0 {
            chi2 += (ao - ae) * (ao - ae) / ae;
            dof += 1;
            ao = 0.0;
            ae = 0.0;
        }
    }
    assert!(
        ao == 0.0 || ae > 0.0,
        "{what}: samples where the pdf is zero"
    );
    let p = 1.0 - ChiSquared::new((dof - 1) as f64).unwrap().cdf(chi2);
    assert!(
        p > 1e-4,
        "{what}: χ² = {chi2:.1} on {dof} cells, p = {p:.2e}"
    );
}

#[test]
fn sweep_matches_direct_traces_and_is_thread_independent() {
    let tmp = tempfile::tempdir().unwrap();
    let sweep = "version: 1
bake: {resolution_deg: 10, photons_per_direction: 16384, seed: 3}
fibers:
  - name: sweep
    type: cotton
    section: {shape: cotton_mercerised}
    sweep: {dyes: [reactive_blue_19, disperse_red_1], depth_of_shade_percent: [0.5, 3]}
";
    let direct = "version: 1
bake: {resolution_deg: 10, photons_per_direction: 16384, seed: 4}
fibers:
  - name: direct
    type: cotton
    section: {shape: cotton_mercerised}
    dye: disperse_red_1
    depth_of_shade_percent: 3
";
    let a =
        Bcsdf::open(bake(tmp.path(), "sweep", sweep, 2).join("sweep/section-00.bcsdf")).unwrap();
    let b =
        Bcsdf::open(bake(tmp.path(), "direct", direct, 2).join("direct/section-00.bcsdf")).unwrap();
    assert_eq!(a.dir.variants.len(), 4);
    let v = a
        .dir
        .variants
        .iter()
        .position(|n| n == "disperse_red_1@3%")
        .unwrap();
    // Albedo per direction and channel: z-scores of the difference.
    let (nv, nc) = (a.dir.variants.len(), a.dir.channels.len());
    let mut z2 = Vec::new();
    for i in 0..a.dir.n_wi() {
        for c in 0..nc {
            let (x, sx) = (
                a.dir.albedo[(i * nv + v) * nc + c],
                a.dir.albedo_se[(i * nv + v) * nc + c],
            );
            let (y, sy) = (b.dir.albedo[i * nc + c], b.dir.albedo_se[i * nc + c]);
            let z = (x - y) as f64 / ((sx * sx + sy * sy) as f64).sqrt().max(1e-12);
            z2.push(z * z);
        }
    }
    let n = z2.len() as f64;
    let max = z2.iter().copied().fold(0.0, f64::max).sqrt();
    let mean = z2.iter().sum::<f64>() / n;
    // Šidák bound for ~1000 comparisons at 1e-3 overall: |z| < 4.9; the mean of z² near 1.
    assert!(
        max < 4.9 && (0.6..1.6).contains(&mean),
        "max |z| {max:.2}, mean z² {mean:.2}"
    );
    // The absorbing variant is darker than the light one in its absorption band (green).
    let light = a
        .dir
        .variants
        .iter()
        .position(|n| n == "disperse_red_1@0.5%")
        .unwrap();
    assert!(a.dir.albedo[v * nc + 1] < a.dir.albedo[light * nc + 1]);
    // One thread gives the same bytes.
    let one = bake(tmp.path(), "sweep", sweep, 1).join("sweep/section-00.bcsdf");
    let two = tmp.path().join("out-sweep-2/sweep/sweep/section-00.bcsdf");
    assert_eq!(std::fs::read(one).unwrap(), std::fs::read(two).unwrap());
}

#[test]
fn f16_tables_stay_within_half_a_percent_of_f32_and_hdf5_holds_the_same_numbers() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = |p: &str| {
        format!(
            "version: 1
bake: {{resolution_deg: 5, photons_per_direction: 8192, precision: {p}, quantise_to_se: 0}}
fibers:
  - {{name: silk, type: silk, section: {{shape: silk}}, seed: 3, dye: reactive_blue_19, depth_of_shade_percent: 1}}
"
        )
    };
    let d16 = bake(tmp.path(), "f16", &spec("f16"), 2).join("silk");
    let d32 = bake(tmp.path(), "f32", &spec("f32"), 2).join("silk");
    let a = Bcsdf::open(d16.join("section-00.bcsdf")).unwrap();
    let b = Bcsdf::open(d32.join("section-00.bcsdf")).unwrap();
    let (mut s2, mut n) = (0.0, 0usize);
    for i in 0..a.dir.n_wi() {
        let (x, y) = (a.decode(i).unwrap(), b.decode(i).unwrap());
        let bins = a.dir.bins();
        for c in 0..a.dir.channels.len() {
            let ys = &y.values[c * bins..(c + 1) * bins];
            let max = ys.iter().copied().fold(0.0, f32::max);
            for (k, &yk) in ys.iter().enumerate() {
                if yk > 0.01 * max {
                    let r = (x.values[c * bins + k] - yk) as f64 / yk as f64;
                    s2 += r * r;
                    n += 1;
                }
            }
        }
    }
    let rms = (s2 / n as f64).sqrt();
    assert!(rms < 0.005, "f16 vs f32 RMS relative error {rms}");
    let (sa, sb) = (
        std::fs::metadata(d16.join("section-00.bcsdf"))
            .unwrap()
            .len(),
        std::fs::metadata(d32.join("section-00.bcsdf"))
            .unwrap()
            .len(),
    );
    assert!(sa < sb, "f16 {sa} bytes, f32 {sb} bytes");
    // The HDF5 file holds exactly the decoded values, the albedo and the sampling CDFs.
    let h = hdf5_metno::File::open(d16.join("silk.h5")).unwrap();
    let g = h.group("section-00").unwrap();
    let f: Vec<f32> = g.dataset("f_normalised").unwrap().read_raw().unwrap();
    let per = a.dir.bins() * a.dir.channels.len();
    for i in [0, a.dir.n_wi() / 2, a.dir.n_wi() - 1] {
        assert_eq!(&f[i * per..(i + 1) * per], &a.decode(i).unwrap().values[..]);
    }
    let alb: Vec<f32> = g.dataset("albedo").unwrap().read_raw().unwrap();
    assert_eq!(alb, a.dir.albedo);
    let cdf: Vec<f32> = g.dataset("cdf_theta").unwrap().read_raw().unwrap();
    let s = a.decode(1).unwrap();
    let nt = a.dir.n_theta;
    for k in 0..nt {
        assert_eq!(cdf[nt + k], s.cdf_theta[0][k] as f32);
    }
}
