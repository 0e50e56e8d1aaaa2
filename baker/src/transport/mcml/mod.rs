//! MCML compatibility: read MCML input files (`.mci`, MCML 1.x and MCML 2.0) and write MCML's
//! output format (`.mco`, version 1.2.2 layout, Wang, Jacques & Zheng 1995), so the baker can
//! stand in for MCML in existing scripts. MCML works in cm; the engine in mm.
//!
//! [`mci`] holds what the input formats share, [`mci1`] and [`mci2`] read them, [`grid`]
//! scores MCML's 2D tallies alongside the engine's, [`mco`] writes them with C's number
//! formats (`printf`).

pub mod grid;
pub mod mci;
pub mod mci1;
pub mod mci2;
pub mod mco;
mod printf;

pub use grid::{simulate_grid, McmlGrid};
pub use mci::{resolve_output, McmlRun, MAX_GRID_CELLS, MAX_RUNS};
pub use mco::write_mco;

/// Every run of an `.mci` file: MCML 2.0 when the version line holds `mcmli2.0` (MCML 2.0's
/// CheckFileVersionQ), MCML 1.x otherwise (MCML 1.2.2 does not check the line). Output file
/// names are checked to be relative paths that stay in the output folder, and unique (MCML
/// 2.0's FnameTaken).
pub fn parse_mci(text: &str) -> Result<Vec<McmlRun>, String> {
    let mut lines = mci::DataLines::new(text);
    let (line, version) = lines.next("file version")?;
    let runs = if version.contains("mcmli2.0") {
        mci2::parse(&mut lines)?
    } else if version.contains("mcmli") {
        return Err(format!(
            "line {line}: unsupported file version {version:?} (read: MCML 1.x `1.0`, MCML 2.0 \
             `mcmli2.0`)"
        ));
    } else {
        mci1::parse(&mut lines)?
    };
    for (i, r) in runs.iter().enumerate() {
        if runs[..i].iter().any(|o| o.output_file == r.output_file) {
            return Err(format!(
                "runs {} and {} both write {:?}",
                runs[..i]
                    .iter()
                    .position(|o| o.output_file == r.output_file)
                    .unwrap()
                    + 1,
                i + 1,
                r.output_file
            ));
        }
    }
    Ok(runs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::{Path, PathBuf};

    #[test]
    fn parses_mcml_template_with_two_runs() {
        let mci = "1.0 # file version\n2 # runs\n\ntemp1.mco A\n10\n20E-4 20E-4\n10 20 30\n2\n# n mua mus g d\n1.0\n1.3 20 200 0.70 0.01\n1.4 10 200 0.90 1.0E+8\n1.0\n\
                   temp2.mco\t A\r\n100\n0.01 0.01\n5 5 5\n1\n1.0\n1.37 1 100 0.9 0.1\n1.0\n";
        let runs = parse_mci(mci).unwrap();
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[0].output_file, "temp1.mco");
        assert_eq!(runs[0].photons, 10);
        assert_eq!((runs[0].nz, runs[0].nr, runs[0].na), (10, 20, 30));
        let l = &runs[0].stack.layers[0];
        assert!(
            (l.d_mm - 0.1).abs() < 1e-12
                && (l.mua_per_mm - 2.0).abs() < 1e-12
                && (l.mus_per_mm - 20.0).abs() < 1e-12
        );
        assert_eq!(runs[1].stack.layers.len(), 1);
        assert_eq!(runs[1].threshold_weight, 1e-4);
    }

    /// MCML 1.x's grid spacing must be positive in both directions.
    #[test]
    fn grid_spacings_must_be_positive() {
        let mci = "1.0 # file version\n1 # runs\n\nout.mco A\n10\n20E-4 20E-4\n10 20 30\n1\n1.0\n1.37 1 100 0.9 0.1\n1.0\n";
        assert!(parse_mci(mci).is_ok());
        for bad in ["0 20E-4", "20E-4 0", "-1E-3 20E-4", "20E-4 -1E-3"] {
            let e = parse_mci(&mci.replace("20E-4 20E-4", bad)).unwrap_err();
            assert!(e.contains("line 6: dz and dr must be > 0"), "{bad}: {e}");
        }
    }

    #[test]
    fn reports_the_line_of_a_bad_value() {
        let e = parse_mci("1.0\n1\nout.mco A\nmany\n").unwrap_err();
        assert!(e.contains("line 4"), "{e}");
    }

    #[test]
    fn the_committed_1x_example_still_parses() {
        let runs = parse_mci(include_str!("../../../../tests/stacks/two_runs.mci")).unwrap();
        assert_eq!(runs.len(), 2);
        assert_eq!(
            (runs[0].output_file.as_str(), runs[0].photons),
            ("bench.mco", 20000)
        );
        assert_eq!(runs[1].stack.layers.len(), 2);
    }

    const SAMPLE2: &str = include_str!("../../../../tests/stacks/mcml2/sample2.mci");

    /// MCML 2.0's own sample 2: three layers naming media of the media list, cm → mm.
    #[test]
    fn parses_stock_mcml2_sample2() {
        let runs = parse_mci(SAMPLE2).unwrap();
        assert_eq!(runs.len(), 1);
        let r = &runs[0];
        assert_eq!(r.output_file, "sample2.mco");
        assert_eq!(r.photons, 1_000_000);
        assert_eq!((r.dz_cm, r.dr_cm), (0.01, 0.01));
        assert_eq!((r.nz, r.nr, r.na), (40, 50, 1));
        assert_eq!(r.threshold_weight, 1e-4);
        let s = &r.stack;
        assert_eq!((s.n_above, s.n_below), (1.0, 1.0));
        let got: Vec<(&str, f64, f64, f64, f64, f64)> = s
            .layers
            .iter()
            .map(|l| {
                (
                    l.name.as_str(),
                    l.eta,
                    l.mua_per_mm,
                    l.mus_per_mm,
                    l.g,
                    l.d_mm,
                )
            })
            .collect();
        let want = [
            ("layer_1", 1.37, 0.1, 10.0, 0.9, 1.0),
            ("layer_2", 1.37, 0.1, 1.0, 0.0, 1.0),
            ("layer_3", 1.37, 0.2, 1.0, 0.7, 2.0),
        ];
        assert_eq!(got.len(), want.len());
        for (g, w) in got.iter().zip(&want) {
            assert_eq!(g.0, w.0);
            for (a, b) in [(g.1, w.1), (g.2, w.2), (g.3, w.3), (g.4, w.4), (g.5, w.5)] {
                assert!((a - b).abs() < 1e-12, "{g:?} vs {w:?}");
            }
        }
    }

    #[test]
    fn parses_stock_mcml2_sample1_with_two_runs() {
        let runs = parse_mci(include_str!("../../../../tests/stacks/mcml2/sample1.mci")).unwrap();
        let names: Vec<&str> = runs.iter().map(|r| r.output_file.as_str()).collect();
        assert_eq!(names, ["sample1a.mco", "sample1b.mco"]);
        assert_eq!((runs[0].photons, runs[1].photons), (1_000_000, 100_000));
        assert_eq!((runs[0].nz, runs[0].nr, runs[0].na), (1, 1, 30));
        let l = &runs[1].stack.layers[0];
        assert_eq!(
            (l.name.as_str(), l.eta, l.g, l.d_mm),
            ("mismatched", 1.5, 0.0, 1e9)
        );
    }

    /// SAMPLE2 with `from` replaced by `to` (which must occur).
    fn sample2_with(from: &str, to: &str) -> String {
        assert!(SAMPLE2.contains(from), "{from:?}");
        SAMPLE2.replacen(from, to, 1)
    }

    /// The 1-based line of the first line of `text` that contains `what`.
    fn line_of(text: &str, what: &str) -> usize {
        text.lines().position(|l| l.contains(what)).unwrap() + 1
    }

    #[test]
    fn an_unknown_medium_names_its_line_and_the_known_media() {
        let text = sample2_with("  layer_2\t0.1", "  layer_9\t0.1");
        let e = parse_mci(&text).unwrap_err();
        let line = line_of(&text, "layer_9");
        assert!(e.contains(&format!("line {line}:")), "{e}");
        assert!(
            e.contains("\"layer_9\"") && e.contains("air, layer_1"),
            "{e}"
        );
    }

    #[test]
    fn bad_media_fields_name_the_line_field_and_range() {
        let text = sample2_with("layer_3\t1.37\t2\t10\t0.7", "layer_3\t1.37\t2\t10\t1.7");
        let e = parse_mci(&text).unwrap_err();
        let line = line_of(&text, "layer_3\t1.37");
        assert!(e.contains(&format!("line {line}:")), "{e}");
        assert!(e.contains("g = 1.7") && e.contains("[-1, 1]"), "{e}");
        let e = parse_mci(&sample2_with("layer_1\t1.37\t1", "layer_1\t1.37\t-1")).unwrap_err();
        assert!(e.contains("mua = -1"), "{e}");
        let e = parse_mci(&sample2_with("layer_1\t1.37", "layer_2\t1.37")).unwrap_err();
        assert!(e.contains("listed twice"), "{e}");
    }

    #[test]
    fn long_media_and_layer_lists_are_bounded() {
        let many: String = (0..=mci2::MAX_MEDIA)
            .map(|i| format!("m{i} 1.4 1 10 0.5\n"))
            .collect();
        let e = parse_mci(&sample2_with("end #of media", &format!("{many}end"))).unwrap_err();
        assert!(
            e.contains(&format!("more than {} media", mci2::MAX_MEDIA)),
            "{e}"
        );
        // Exactly MAX_MEDIA media still parse (the bound is not off by one).
        let fits: String = (1..=mci2::MAX_MEDIA - 4)
            .map(|i| format!("m{i} 1.4 1 10 0.5\n"))
            .collect();
        assert!(parse_mci(&sample2_with("end #of media", &format!("{fits}end"))).is_ok());
        let layers = "  layer_1\t0.01\n".repeat(crate::transport::stack::MAX_LAYERS + 1);
        let e = parse_mci(&sample2_with("  layer_1\t0.1\n", &layers)).unwrap_err();
        assert!(e.contains("more than 16 layers"), "{e}");
    }

    #[test]
    fn unsupported_runs_are_refused_with_the_line() {
        for (from, to, says) in [
            (
                "pencil\t",
                "isotropic\t",
                "isotropic sources are not supported",
            ),
            ("pencil\t", "laser\t", "unknown source type \"laser\""),
            (
                "\n0\t\t\t\t\t\t# starting",
                "\n0.1\t\t\t\t\t# starting",
                "must start at z = 0",
            ),
            (
                "\n0\t\t\t\t\t\t# starting",
                "\n0 layer_1\t\t\t\t# starting",
                "must start at z = 0",
            ),
            ("Rd_t A_rz", "Rd_t A_xy", "unknown scored category \"A_xy\""),
            ("1000000\t10:00", "10:00", "a time limit alone"),
            ("1E-4\t", "1.5\t", "threshold weight 1.5 is out of range"),
            ("sample2.mco\tA", "sample2.mco", "format (A or B)"),
            ("sample2.mco\tA", "../sample2.mco\tA", "relative file path"),
            ("0.01\t0.01\t0.1", "0.01\t0\t0.1", "must be > 0"),
            (
                "40\t50\t100\t1",
                "40\t50\t0\t1",
                "nt must be a positive whole number",
            ),
            ("40\t50\t100\t1", "40000\t5000\t1\t1", "grid cells"),
        ] {
            let text = sample2_with(from, to);
            let e = parse_mci(&text).unwrap_err();
            let line = line_of(&text, to.trim_start_matches('\n'));
            assert!(
                e.contains(&format!("line {line}:")) && e.contains(says),
                "{to:?}: {e}"
            );
        }
        // The file must close its runs with `end`.
        let e = parse_mci(&sample2_with("end #of all runs", "")).unwrap_err();
        assert!(e.contains("`end` after the last run"), "{e}");
    }

    #[test]
    fn mcml2_accepts_continued_categories_a_medium_above_and_photons_alone() {
        let text = sample2_with("Rd_t A_rz", "rd_t \\\n a_RZ")
            .replacen("\n0\t\t\t\t\t\t# starting", "\n0 air # starting", 1)
            .replacen("1000000\t10:00", "2.5e3", 1);
        let runs = parse_mci(&text).unwrap();
        assert_eq!(runs[0].photons, 2500);
        let e = parse_mci(&sample2_with("Rd_t A_rz", "Rd_t \\\n A_q")).unwrap_err();
        assert!(e.contains("\"A_q\""), "{e}");
    }

    #[test]
    fn output_names_are_unique_and_a_bad_version_is_named() {
        let s1 = include_str!("../../../../tests/stacks/mcml2/sample1.mci");
        let e = parse_mci(&s1.replacen("sample1b.mco", "sample1a.mco", 1)).unwrap_err();
        assert!(
            e.contains("runs 1 and 2 both write \"sample1a.mco\""),
            "{e}"
        );
        let e = parse_mci(&s1.replacen("mcmli2.0", "mcmli3.0", 1)).unwrap_err();
        assert!(e.contains("unsupported file version"), "{e}");
    }

    #[test]
    fn outputs_resolve_against_the_current_directory_or_the_out_folder() {
        assert_eq!(
            resolve_output("a.mco", None).unwrap(),
            PathBuf::from("a.mco")
        );
        assert_eq!(
            resolve_output("sub/a.mco", Some(Path::new("out"))).unwrap(),
            PathBuf::from("out/sub/a.mco")
        );
        assert_eq!(
            resolve_output("./a.mco", Some(Path::new("/tmp/o"))).unwrap(),
            Path::new("/tmp/o").join("./a.mco")
        );
        for bad in [
            "../a.mco",
            "/etc/a.mco",
            "sub/../../a.mco",
            "a\\b.mco",
            "sub/",
            ".",
            "a\u{1}",
        ] {
            for dir in [None, Some(Path::new("out"))] {
                let e = resolve_output(bad, dir).unwrap_err();
                assert!(e.contains("relative file path"), "{bad:?}: {e}");
            }
        }
    }
}
