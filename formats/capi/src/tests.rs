//! The C ABI's contract seen from Rust: null pointers, bad paths and files, indices out of
//! range, panics, per-thread messages, and answers equal to the Rust reader's.

use std::ffi::{CStr, CString};
use std::path::{Path, PathBuf};
use std::ptr::{null, null_mut};

use formats::bcsdf::{direction, Directory, Precision, Writer, FLIP_THETA, KIND};
use formats::{Array, TableFile};

use super::*;

fn last_error() -> String {
    // SAFETY: the library returns a valid NUL-terminated string.
    unsafe { CStr::from_ptr(bf_last_error_message()) }
        .to_string_lossy()
        .into_owned()
}

fn c_path(p: &Path) -> CString {
    CString::new(p.to_str().unwrap()).unwrap()
}

/// A `skin_profiles` table with two entries, 4 radial bins, 2 Gaussians for the first entry.
fn profile_file(dir: &Path) -> PathBuf {
    let names = ["typeI_age30_xi0", "typeVI_age80_xi1"];
    let meta = serde_json::json!({
        "entries": serde_json::to_string(&names).unwrap(),
        "groups": {
            "typeI_age30_xi0": {"skin_type": "I", "age_years": 30.0, "xi": 0.0},
            "typeVI_age80_xi1": {"skin_type": "VI", "age_years": 80.0, "xi": 1.0},
        },
    });
    let mut t = TableFile::new("skin_profiles", meta);
    for (k, name) in names.iter().enumerate() {
        let s = (k + 1) as f64;
        let a = |q: &str, shape: Vec<u64>, v: Vec<f64>| {
            Array::new_f64(format!("{name}/{q}"), shape, v).unwrap()
        };
        t.push(a("r_mm", vec![4], vec![0.005, 0.015, 0.03, 0.06]))
            .unwrap();
        t.push(a("r_edges_mm", vec![5], vec![0.0, 0.01, 0.02, 0.04, 0.08]))
            .unwrap();
        let rd: Vec<f64> = (0..12).map(|i| s * (12 - i) as f64).collect();
        t.push(a("rd_rgb_per_mm2", vec![4, 3], rd)).unwrap();
        t.push(a("albedo_rgb", vec![3], vec![0.5 * s, 0.4, 0.3]))
            .unwrap();
        if k == 0 {
            t.push(a("gaussians/variance_mm2", vec![2], vec![0.01, 1.0]))
                .unwrap();
            t.push(a(
                "gaussians/weight_rgb",
                vec![2, 3],
                vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
            ))
            .unwrap();
            t.push(a("gaussians/error_rgb", vec![3], vec![0.01, 0.02, 0.03]))
                .unwrap();
        }
    }
    let p = dir.join("profiles.bkt");
    t.write(&p, 3).unwrap();
    p
}

/// A `.bcsdf` with 30° bins, 2 stored directions (mirror along the axis), variants
/// `undyed` and `black` (no scattering), channels R and G.
fn bcsdf_file(dir: &Path) -> PathBuf {
    let (nt, np) = (6usize, 12usize);
    let mut wi_map = vec![0u32; nt * np];
    for it in 0..nt {
        let (s, flip) = match it {
            0..=2 => (it.min(1) as u32, false),
            _ => ((5 - it).min(1) as u32, true),
        };
        for j in 0..np {
            wi_map[it * np + j] = s | if flip { FLIP_THETA } else { 0 };
        }
    }
    let d = Directory {
        kind: KIND.into(),
        res_deg: 30.0,
        n_theta: nt,
        n_phi: np,
        wi_deg: vec![[-75.0, 15.0], [-45.0, 15.0]],
        wi_map,
        variants: vec!["undyed".into(), "black".into()],
        channels: vec!["R".into(), "G".into()],
        dtype: Precision::F16,
        keep_bits: 10,
        scale: vec![],
        albedo: vec![1.0, 1.0, 0.0, 0.0, 0.9, 0.95, 0.0, 0.0],
        albedo_se: vec![0.0; 8],
        area_um: (0..np).map(|j| 10.0 + j as f64).collect(),
        chunks: vec![],
        metadata: serde_json::json!({"test": true}),
    };
    let mut w = Writer::new(d, 3);
    for s in 0..2 {
        let mut v = vec![0.0; 2 * 2 * nt * np];
        for c in 0..2 {
            for b in 0..nt * np {
                v[c * nt * np + b] = 0.01 + ((b * 7 + s * 3 + c) % 11) as f64 * 0.01;
            }
        }
        w.push(&v).unwrap();
    }
    let p = dir.join("t.bcsdf");
    std::fs::write(&p, w.finish().unwrap()).unwrap();
    p
}

fn open_profile(p: &Path) -> *mut BfProfileTable {
    let mut t = null_mut();
    assert_eq!(
        unsafe { bf_profile_open(c_path(p).as_ptr(), &mut t) },
        BF_OK
    );
    assert!(!t.is_null());
    assert_eq!(last_error(), "");
    t
}

fn open_bcsdf(p: &Path) -> *mut BfBcsdfTable {
    let mut t = null_mut();
    let rc = unsafe { bf_bcsdf_open(c_path(p).as_ptr(), &mut t) };
    assert_eq!(rc, BF_OK, "{}", last_error());
    t
}

#[test]
fn null_pointers_are_bad_arguments_with_the_argument_named() {
    let tmp = tempfile::tempdir().unwrap();
    let (pt, bt) = (
        open_profile(&profile_file(tmp.path())),
        open_bcsdf(&bcsdf_file(tmp.path())),
    );
    let mut n = 0usize;
    let mut out3 = [0f64; 3];
    let mut f2 = [0f32; 2];
    let mut x = 0f64;
    let wi = [1.0, 0.0, 0.0];
    unsafe {
        let mut h = null_mut();
        assert_eq!(bf_profile_open(null(), &mut h), BF_ERR_BAD_ARGUMENT);
        assert!(last_error().contains("`path` is NULL"), "{}", last_error());
        assert!(h.is_null());
        let p = CString::new("x.bkt").unwrap();
        assert_eq!(bf_profile_open(p.as_ptr(), null_mut()), BF_ERR_BAD_ARGUMENT);
        assert!(last_error().contains("`out`"));
        let mut hb = null_mut();
        assert_eq!(bf_bcsdf_open(null(), &mut hb), BF_ERR_BAD_ARGUMENT);
        assert_eq!(bf_profile_entry_count(null(), &mut n), BF_ERR_BAD_ARGUMENT);
        assert!(last_error().contains("`table` is NULL"));
        assert_eq!(bf_profile_entry_count(pt, null_mut()), BF_ERR_BAD_ARGUMENT);
        assert_eq!(
            bf_profile_entry_name(pt, 0, null_mut()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(bf_profile_find(pt, null(), &mut n), BF_ERR_BAD_ARGUMENT);
        assert_eq!(
            bf_profile_lookup(pt, null(), null(), 1, &mut n),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_profile_rd_rgb(pt, 0, 0.1, null_mut()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_profile_rd_rgb(null(), 0, 0.1, out3.as_mut_ptr()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_profile_albedo_rgb(pt, 0, null_mut()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_profile_gaussian_count(pt, 0, null_mut()),
            BF_ERR_BAD_ARGUMENT
        );
        let mut v = [0f64; 2];
        let mut w = [0f64; 6];
        assert_eq!(
            bf_profile_gaussians(pt, 0, 2, v.as_mut_ptr(), null_mut(), out3.as_mut_ptr()),
            BF_ERR_BAD_ARGUMENT
        );
        assert!(last_error().contains("`weight_rgb` is NULL"));
        assert_eq!(
            bf_profile_gaussians(pt, 0, 2, v.as_mut_ptr(), w.as_mut_ptr(), null_mut()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(bf_bcsdf_variant_count(bt, null_mut()), BF_ERR_BAD_ARGUMENT);
        assert_eq!(bf_bcsdf_channel_count(null(), &mut n), BF_ERR_BAD_ARGUMENT);
        assert_eq!(
            bf_bcsdf_variant_name(bt, 0, null_mut()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_bcsdf_channel_name(bt, 0, null_mut()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_bcsdf_eval(bt, null(), wi.as_ptr(), 0, f2.as_mut_ptr(), 2),
            BF_ERR_BAD_ARGUMENT
        );
        assert!(last_error().contains("`wi` is NULL"));
        assert_eq!(
            bf_bcsdf_eval(bt, wi.as_ptr(), null(), 0, f2.as_mut_ptr(), 2),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_bcsdf_eval(bt, wi.as_ptr(), wi.as_ptr(), 0, null_mut(), 2),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_bcsdf_eval_normalised(null(), wi.as_ptr(), wi.as_ptr(), 0, f2.as_mut_ptr(), 2),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_bcsdf_pdf(bt, wi.as_ptr(), wi.as_ptr(), 0, null_mut()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_bcsdf_sample(bt, wi.as_ptr(), 0.5, 0.5, 0, null_mut(), &mut x),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_bcsdf_sample(bt, wi.as_ptr(), 0.5, 0.5, 0, out3.as_mut_ptr(), null_mut()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_bcsdf_albedo(bt, null(), 0, f2.as_mut_ptr(), 2),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_bcsdf_projected_area(bt, wi.as_ptr(), null_mut()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(bf_bcsdf_area_um(bt, null(), &mut x), BF_ERR_BAD_ARGUMENT);
        // Freeing NULL is a no-op.
        bf_profile_free(null_mut());
        bf_bcsdf_free(null_mut());
        bf_profile_free(pt);
        bf_bcsdf_free(bt);
    }
}

#[test]
fn bad_files_give_distinct_codes_and_name_the_path() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let missing = dir.join("missing.bkt");
    let mut h = null_mut();
    let mut hb = null_mut();
    unsafe {
        assert_eq!(
            bf_profile_open(c_path(&missing).as_ptr(), &mut h),
            BF_ERR_IO
        );
        assert!(last_error().contains("missing.bkt"), "{}", last_error());
        assert_eq!(bf_bcsdf_open(c_path(&missing).as_ptr(), &mut hb), BF_ERR_IO);
        assert!(h.is_null() && hb.is_null());

        let junk = dir.join("junk.bin");
        std::fs::write(&junk, vec![b'x'; 100]).unwrap();
        assert_eq!(
            bf_profile_open(c_path(&junk).as_ptr(), &mut h),
            BF_ERR_FORMAT
        );
        assert!(last_error().contains("magic"), "{}", last_error());
        assert!(last_error().contains("junk.bin"), "{}", last_error());
        assert_eq!(
            bf_bcsdf_open(c_path(&junk).as_ptr(), &mut hb),
            BF_ERR_FORMAT
        );
        assert!(last_error().contains("magic"), "{}", last_error());
        assert!(last_error().contains("junk.bin"), "{}", last_error());

        // Each table type refuses the other's file.
        let prof = profile_file(dir);
        let fib = bcsdf_file(dir);
        assert_eq!(
            bf_bcsdf_open(c_path(&prof).as_ptr(), &mut hb),
            BF_ERR_FORMAT
        );
        assert_eq!(
            bf_profile_open(c_path(&fib).as_ptr(), &mut h),
            BF_ERR_FORMAT
        );

        // Another version.
        for (p, is_profile) in [(&prof, true), (&fib, false)] {
            let mut b = std::fs::read(p).unwrap();
            b[8] = 2;
            let q = dir.join("v2.bin");
            std::fs::write(&q, &b).unwrap();
            let rc = if is_profile {
                bf_profile_open(c_path(&q).as_ptr(), &mut h)
            } else {
                bf_bcsdf_open(c_path(&q).as_ptr(), &mut hb)
            };
            assert_eq!(rc, BF_ERR_UNSUPPORTED_VERSION, "{}", last_error());
            assert!(last_error().contains("version 2"), "{}", last_error());
            // Truncated.
            let q = dir.join("short.bin");
            std::fs::write(&q, &std::fs::read(p).unwrap()[..200]).unwrap();
            let rc = if is_profile {
                bf_profile_open(c_path(&q).as_ptr(), &mut h)
            } else {
                bf_bcsdf_open(c_path(&q).as_ptr(), &mut hb)
            };
            assert_eq!(rc, BF_ERR_FORMAT);
        }
        assert!(h.is_null() && hb.is_null());

        // A damaged entry is found when it is first queried.
        let mut b = std::fs::read(&fib).unwrap();
        let n = b.len();
        b[n - 3] ^= 0x5A;
        let q = dir.join("damaged.bcsdf");
        std::fs::write(&q, &b).unwrap();
        let t = open_bcsdf(&q);
        let wi = direction(0.5, 0.2);
        let mut f = [0f32; 2];
        let rc = bf_bcsdf_eval(t, wi.as_ptr(), wi.as_ptr(), 0, f.as_mut_ptr(), 2);
        assert_eq!(rc, BF_ERR_FORMAT, "{}", last_error());
        bf_bcsdf_free(t);
    }
    assert_eq!(
        unsafe { CStr::from_ptr(bf_error_name(BF_ERR_UNSUPPORTED_VERSION)) },
        c"BF_ERR_UNSUPPORTED_VERSION"
    );
    assert_eq!(unsafe { CStr::from_ptr(bf_error_name(99)) }, c"unknown");
}

#[test]
fn profile_queries_match_the_rust_reader() {
    let tmp = tempfile::tempdir().unwrap();
    let p = profile_file(tmp.path());
    let rust = ProfileTable::open(&p).unwrap();
    let t = open_profile(&p);
    unsafe {
        let mut n = 0usize;
        assert_eq!(bf_profile_entry_count(t, &mut n), BF_OK);
        assert_eq!(n, 2);
        let mut s = null();
        assert_eq!(bf_profile_entry_name(t, 1, &mut s), BF_OK);
        assert_eq!(CStr::from_ptr(s), c"typeVI_age80_xi1");
        assert_eq!(bf_profile_entry_name(t, 2, &mut s), BF_ERR_BAD_ARGUMENT);
        assert!(last_error().contains("entry 2 out of range"));

        let name = CString::new("typeVI_age80_xi1").unwrap();
        let mut e = 99usize;
        assert_eq!(bf_profile_find(t, name.as_ptr(), &mut e), BF_OK);
        assert_eq!(e, 1);
        let nope = CString::new("typeIV").unwrap();
        assert_eq!(bf_profile_find(t, nope.as_ptr(), &mut e), BF_ERR_NOT_FOUND);
        assert!(last_error().contains("typeIV"));

        let keys = [c"skin_type".as_ptr(), c"age_years".as_ptr()];
        let vals = [c"VI".as_ptr(), c"80".as_ptr()];
        e = 99;
        assert_eq!(
            bf_profile_lookup(t, keys.as_ptr(), vals.as_ptr(), 2, &mut e),
            BF_OK
        );
        assert_eq!(e, 1);
        assert_eq!(
            bf_profile_lookup(t, keys.as_ptr(), vals.as_ptr(), 0, &mut e),
            BF_ERR_NOT_FOUND
        );
        assert!(last_error().contains("2 entries match"), "{}", last_error());

        let mut rgb = [0f64; 3];
        for (k, entry) in rust.entries().iter().enumerate() {
            for r in [
                0.0,
                0.004,
                0.01,
                0.015,
                0.05,
                0.07,
                0.08,
                0.09,
                f64::INFINITY,
            ] {
                assert_eq!(bf_profile_rd_rgb(t, k, r, rgb.as_mut_ptr()), BF_OK);
                assert_eq!(rgb, rust.rd_rgb(&entry.name, r).unwrap());
            }
            assert_eq!(bf_profile_albedo_rgb(t, k, rgb.as_mut_ptr()), BF_OK);
            assert_eq!(rgb, rust.albedo_rgb(&entry.name).unwrap());
        }
        assert_eq!(
            bf_profile_rd_rgb(t, 0, f64::NAN, rgb.as_mut_ptr()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_profile_rd_rgb(t, 0, -1.0, rgb.as_mut_ptr()),
            BF_ERR_BAD_ARGUMENT
        );
        assert_eq!(
            bf_profile_rd_rgb(t, 5, 0.1, rgb.as_mut_ptr()),
            BF_ERR_BAD_ARGUMENT
        );

        assert_eq!(bf_profile_gaussian_count(t, 0, &mut n), BF_OK);
        assert_eq!(n, 2);
        let (mut v, mut w, mut err) = ([0f64; 2], [0f64; 6], [0f64; 3]);
        assert_eq!(
            bf_profile_gaussians(t, 0, 2, v.as_mut_ptr(), w.as_mut_ptr(), err.as_mut_ptr()),
            BF_OK
        );
        let g = rust.gaussians("typeI_age30_xi0").unwrap();
        assert_eq!(v.to_vec(), g.variance_mm2);
        assert_eq!(w, [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]);
        assert_eq!(err, g.error_rgb);
        assert_eq!(
            bf_profile_gaussians(t, 0, 1, v.as_mut_ptr(), w.as_mut_ptr(), err.as_mut_ptr()),
            BF_ERR_BAD_ARGUMENT
        );
        assert!(
            last_error().contains("holds 1 values, 2 are needed"),
            "{}",
            last_error()
        );
        // No fit: zero Gaussians, NaN errors.
        assert_eq!(bf_profile_gaussian_count(t, 1, &mut n), BF_OK);
        assert_eq!(n, 0);
        assert_eq!(
            bf_profile_gaussians(t, 1, 0, v.as_mut_ptr(), w.as_mut_ptr(), err.as_mut_ptr()),
            BF_OK
        );
        assert!(err.iter().all(|x| x.is_nan()));
        bf_profile_free(t);
    }
}

#[test]
fn bcsdf_queries_match_the_rust_reader() {
    let tmp = tempfile::tempdir().unwrap();
    let p = bcsdf_file(tmp.path());
    let rust = BcsdfTable::open(&p).unwrap();
    let t = open_bcsdf(&p);
    unsafe {
        let (mut nv, mut nc) = (0usize, 0usize);
        assert_eq!(bf_bcsdf_variant_count(t, &mut nv), BF_OK);
        assert_eq!(bf_bcsdf_channel_count(t, &mut nc), BF_OK);
        assert_eq!((nv, nc), (2, 2));
        let mut s = null();
        assert_eq!(bf_bcsdf_variant_name(t, 1, &mut s), BF_OK);
        assert_eq!(CStr::from_ptr(s), c"black");
        assert_eq!(bf_bcsdf_channel_name(t, 1, &mut s), BF_OK);
        assert_eq!(CStr::from_ptr(s), c"G");
        assert_eq!(bf_bcsdf_channel_name(t, 2, &mut s), BF_ERR_BAD_ARGUMENT);

        let mut f = [0f32; 2];
        let mut a = [0f32; 2];
        let (mut pdf, mut x) = (0f64, 0f64);
        let mut wo = [0f64; 3];
        for (ti, pi) in [(-80.0, 20.0), (-50.0, -170.0), (10.0, 95.0), (70.0, 179.0)] {
            let wi = direction(f64::to_radians(ti), f64::to_radians(pi));
            for (to, po) in [(35.0, 120.0), (-5.0, -60.0), (85.0, 0.0)] {
                let wo_q = direction(f64::to_radians(to), f64::to_radians(po));
                for v in 0..2 {
                    assert_eq!(
                        bf_bcsdf_eval(t, wi.as_ptr(), wo_q.as_ptr(), v, f.as_mut_ptr(), 2),
                        BF_OK
                    );
                    assert_eq!(f.to_vec(), rust.eval(wi, wo_q, v).unwrap());
                    let rc = bf_bcsdf_eval_normalised(
                        t,
                        wi.as_ptr(),
                        wo_q.as_ptr(),
                        v,
                        f.as_mut_ptr(),
                        2,
                    );
                    assert_eq!(rc, BF_OK);
                    assert_eq!(f.to_vec(), rust.eval_normalised(wi, wo_q, v).unwrap());
                    assert_eq!(
                        bf_bcsdf_pdf(t, wi.as_ptr(), wo_q.as_ptr(), v, &mut pdf),
                        BF_OK
                    );
                    assert_eq!(pdf, rust.pdf(wi, wo_q, v).unwrap());
                }
            }
            for v in 0..2 {
                assert_eq!(bf_bcsdf_albedo(t, wi.as_ptr(), v, a.as_mut_ptr(), 2), BF_OK);
                assert_eq!(a.to_vec(), rust.albedo(wi, v).unwrap());
                for (u1, u2) in [(0.0, 0.0), (0.3, 0.7), (0.999, 0.5), (1.0, 1.0)] {
                    let rc = bf_bcsdf_sample(t, wi.as_ptr(), u1, u2, v, wo.as_mut_ptr(), &mut pdf);
                    assert_eq!(rc, BF_OK, "{}", last_error());
                    match rust.sample(wi, v, u1, u2).unwrap() {
                        Some(s) => assert_eq!((wo, pdf), (s.wo, s.pdf)),
                        None => assert_eq!((wo, pdf), ([0.0; 3], 0.0)),
                    }
                }
            }
            assert_eq!(bf_bcsdf_projected_area(t, wi.as_ptr(), &mut x), BF_OK);
            assert_eq!(x, rust.projected_area(wi));
            assert_eq!(bf_bcsdf_area_um(t, wi.as_ptr(), &mut x), BF_OK);
            assert_eq!(x, rust.area_um(wi));
        }
        let wi = [0.0, 1.0, 0.2];
        // Bad arguments.
        assert_eq!(
            bf_bcsdf_eval(t, wi.as_ptr(), wi.as_ptr(), 2, f.as_mut_ptr(), 2),
            BF_ERR_BAD_ARGUMENT
        );
        assert!(last_error().contains("variant 2 out of range"));
        assert_eq!(
            bf_bcsdf_eval(t, wi.as_ptr(), wi.as_ptr(), 0, f.as_mut_ptr(), 1),
            BF_ERR_BAD_ARGUMENT
        );
        assert!(last_error().contains("holds 1 values, 2 are needed"));
        for bad in [[0.0; 3], [f64::NAN, 1.0, 0.0], [f64::INFINITY, 0.0, 0.0]] {
            assert_eq!(
                bf_bcsdf_albedo(t, bad.as_ptr(), 0, a.as_mut_ptr(), 2),
                BF_ERR_BAD_ARGUMENT
            );
            assert!(last_error().contains("not a direction"));
        }
        for (u1, u2) in [(-0.1, 0.5), (0.5, 1.5), (f64::NAN, 0.5)] {
            let rc = bf_bcsdf_sample(t, wi.as_ptr(), u1, u2, 0, wo.as_mut_ptr(), &mut pdf);
            assert_eq!(rc, BF_ERR_BAD_ARGUMENT);
        }
        // A success clears the message.
        assert_eq!(bf_bcsdf_projected_area(t, wi.as_ptr(), &mut x), BF_OK);
        assert_eq!(last_error(), "");
        bf_bcsdf_free(t);
    }
}

#[test]
fn panics_are_caught_and_reported() {
    let rc = guard(|| panic!("boom {}", 42));
    assert_eq!(rc, BF_ERR_PANIC);
    assert!(last_error().contains("panic"), "{}", last_error());
    assert!(last_error().contains("boom 42"), "{}", last_error());
    assert_eq!(guard(|| Ok(())), BF_OK);
    assert_eq!(last_error(), "");
}

#[test]
fn error_messages_are_per_thread() {
    let mut n = 0usize;
    unsafe {
        assert_eq!(bf_profile_entry_count(null(), &mut n), BF_ERR_BAD_ARGUMENT);
    }
    let here = last_error();
    let there = std::thread::spawn(|| {
        let before = last_error();
        let rc = unsafe { bf_bcsdf_open(c"/nonexistent/x.bcsdf".as_ptr(), null_mut()) };
        (before, rc, last_error())
    })
    .join()
    .unwrap();
    assert_eq!(there.0, "");
    assert_eq!(there.1, BF_ERR_BAD_ARGUMENT);
    assert!(there.2.contains("`out`"));
    assert_eq!(last_error(), here);
    assert!(here.contains("`table` is NULL"));
}

#[test]
fn the_committed_header_is_current() {
    // build.rs writes the header into OUT_DIR on every build and updates the committed copy.
    let generated = std::fs::read_to_string(concat!(env!("OUT_DIR"), "/baker_formats.h")).unwrap();
    let committed = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/include/baker_formats.h"
    ))
    .unwrap();
    assert_eq!(
        generated, committed,
        "run `cargo build -p baker-formats-capi` and commit the header"
    );
    for f in [
        "bf_last_error_message",
        "bf_profile_open",
        "bf_profile_gaussians",
        "bf_bcsdf_sample",
        "bf_bcsdf_projected_area",
    ] {
        assert!(
            committed.contains(&format!("{f}(")),
            "{f} missing from the header"
        );
    }
    assert!(committed.contains("typedef struct BfProfileTable BfProfileTable;"));
    assert!(committed.contains("#define BF_ERR_PANIC 6"));
}
