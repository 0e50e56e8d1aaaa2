//! Dye absorption inside a fiber (§5.3.1, "Absorption"): μa = κ·ε with dye concentration
//! κ = ρ·ζ (fiber density ρ, depth of shade ζ) and the dye's extinction per mass ε(λ).
//!
//! Units follow the thesis: ε in l mg⁻¹ cm⁻¹ (its class ranges: reactive 0.005–0.0158,
//! disperse 0.045–0.246 \[174, 102\]), ρ in g/cm³ (= 10⁶ mg/l), so
//! μa [cm⁻¹] = ρ·10⁶·ζ·ε. The thesis applies ε as-is (no ln 10 for decadic data): its Fig. 61
//! quotes μa = 84.68 mm⁻¹ for silk (ρ = 1.34) at ζ = 4 % with ε = 0.0158, which is exactly
//! ρζε; we do the same so that tables match the thesis.

use std::path::Path;

/// Dye classes and the range of peak extinction the thesis gives for each (§5.3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DyeClass {
    /// Reactive dyes (cotton, silk, wool): peak ε 0.005–0.0158 l mg⁻¹ cm⁻¹.
    Reactive,
    /// Disperse dyes (polyester and other synthetics): peak ε 0.045–0.246 l mg⁻¹ cm⁻¹.
    Disperse,
}

impl DyeClass {
    pub const ALL: [(&'static str, DyeClass); 2] = [
        ("reactive", DyeClass::Reactive),
        ("disperse", DyeClass::Disperse),
    ];

    /// Peak extinction range, l mg⁻¹ cm⁻¹ (§5.3.1, \[174, 102\]).
    pub fn peak_range(self) -> (f64, f64) {
        match self {
            DyeClass::Reactive => (0.005, 0.0158),
            DyeClass::Disperse => (0.045, 0.246),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            DyeClass::Reactive => "reactive",
            DyeClass::Disperse => "disperse",
        }
    }
}

/// A Gaussian absorption band: ε(λ) = peak·exp(−4 ln 2 (λ − λp)²/FWHM²).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Band {
    pub peak_nm: f64,
    pub fwhm_nm: f64,
    pub peak_eps_l_per_mg_cm: f64,
}

/// A dye's extinction spectrum.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Spectrum {
    /// Sum of Gaussian bands.
    Bands(Vec<Band>),
    /// Tabulated ε(λ), linearly interpolated, zero outside the table.
    Table {
        lambda_nm: Vec<f64>,
        eps_l_per_mg_cm: Vec<f64>,
    },
}

/// A named dye.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Dye {
    pub name: String,
    pub class: DyeClass,
    pub spectrum: Spectrum,
    /// Where the numbers come from.
    pub source: String,
}

impl Dye {
    /// ε(λ), l mg⁻¹ cm⁻¹.
    pub fn eps_l_per_mg_cm(&self, lambda_nm: f64) -> f64 {
        match &self.spectrum {
            Spectrum::Bands(b) => b
                .iter()
                .map(|b| {
                    let x = (lambda_nm - b.peak_nm) / b.fwhm_nm;
                    b.peak_eps_l_per_mg_cm * (-4.0 * std::f64::consts::LN_2 * x * x).exp()
                })
                .sum(),
            Spectrum::Table {
                lambda_nm: l,
                eps_l_per_mg_cm: e,
            } => {
                if lambda_nm < l[0] || lambda_nm > l[l.len() - 1] {
                    return 0.0;
                }
                let i = l.partition_point(|&x| x <= lambda_nm).clamp(1, l.len() - 1);
                let t = (lambda_nm - l[i - 1]) / (l[i] - l[i - 1]);
                e[i - 1] + t * (e[i] - e[i - 1])
            }
        }
    }

    /// Largest ε over 380–780 nm, l mg⁻¹ cm⁻¹.
    pub fn peak_eps(&self) -> f64 {
        (380..=780)
            .map(|l| self.eps_l_per_mg_cm(l as f64))
            .fold(0.0, f64::max)
    }

    /// μa(λ) of a fiber of density ρ dyed to depth of shade ζ (fraction, 0.001–0.04), per mm.
    pub fn mua_per_mm(&self, lambda_nm: f64, density_g_per_cm3: f64, dos: f64) -> f64 {
        mua_per_mm(density_g_per_cm3, dos, self.eps_l_per_mg_cm(lambda_nm))
    }
}

/// μa = ρ·ζ·ε (§5.3.1): ρ g/cm³ → mg/l (×10⁶), ε l mg⁻¹ cm⁻¹ gives cm⁻¹, /10 for mm⁻¹.
pub fn mua_per_mm(density_g_per_cm3: f64, dos: f64, eps_l_per_mg_cm: f64) -> f64 {
    density_g_per_cm3 * 1e6 * dos * eps_l_per_mg_cm / 10.0
}

/// Depth-of-shade range, fraction: 0.1 % (pale) to 4 % (deep) (§5.3.1, \[166\]).
pub const DOS_RANGE: (f64, f64) = (0.001, 0.04);

const PRESETS_CSV: &str = include_str!("data/dye_presets.csv");

/// The data tables of this module compiled into the binary (for the unit cache keys).
pub const DATA_FILES: &[(&str, &str)] = &[("dye_presets.csv", PRESETS_CSV)];

/// The shipped dye presets (`data/dye_presets.csv`, sources in its header).
pub fn presets() -> Vec<Dye> {
    // The sources are comment lines `# source[n]: text`; the rest is CSV, one row per band.
    let sources: Vec<(String, String)> = PRESETS_CSV
        .lines()
        .filter_map(|l| l.trim().strip_prefix("# source[")?.split_once("]:"))
        .map(|(n, text)| (n.trim().to_string(), text.trim().to_string()))
        .collect();
    let mut dyes: Vec<Dye> = Vec::new();
    let mut header: Option<Vec<String>> = None;
    for row in crate::files::csv_rows::rows(PRESETS_CSV) {
        let row = row.expect("data/dye_presets.csv splits into rows");
        let Some(h) = &header else {
            header = Some(row.fields.iter().map(str::to_string).collect());
            continue;
        };
        let get = |k: &str| -> &str { h.iter().position(|c| c == k).map_or("", |i| row.get(i)) };
        let num = |k: &str| get(k).parse::<f64>().unwrap_or(f64::NAN);
        let band = Band {
            peak_nm: num("peak_nm"),
            fwhm_nm: num("fwhm_nm"),
            peak_eps_l_per_mg_cm: num("peak_eps_l_per_mg_cm"),
        };
        let name = get("name").to_string();
        let cite: Vec<String> = get("sources")
            .split(';')
            .filter_map(|n| {
                sources
                    .iter()
                    .find(|s| s.0 == n.trim())
                    .map(|s| s.1.clone())
            })
            .collect();
        match dyes.iter_mut().find(|d| d.name == name) {
            Some(d) => {
                if let Spectrum::Bands(b) = &mut d.spectrum {
                    b.push(band);
                }
            }
            None => dyes.push(Dye {
                class: if get("class") == "disperse" {
                    DyeClass::Disperse
                } else {
                    DyeClass::Reactive
                },
                name,
                spectrum: Spectrum::Bands(vec![band]),
                source: format!("{} ({})", get("colour_index"), cite.join("; ")),
            }),
        }
    }
    dyes
}

/// Most rows of a dye spectrum CSV (a 0.1 nm grid over 300–2500 nm has 22,001), checked
/// before a row is stored.
pub const MAX_SPECTRUM_ROWS: usize = 100_000;

/// Reads a tabulated spectrum: rows `lambda_nm,eps_l_per_mg_cm` (the dialect of
/// [`crate::files::csv_rows`]), `#` comments and header rows before the first data row
/// allowed, wavelengths strictly increasing, ε ≥ 0, at most [`MAX_SPECTRUM_ROWS`] rows.
/// Messages start `line N:` (the caller names the file).
pub fn spectrum_from_csv(path: &Path) -> Result<Spectrum, String> {
    const EXPECTED: &str = "expected two numbers `lambda_nm,eps_l_per_mg_cm`";
    let text = crate::files::read_text(path, crate::files::MAX_DATA_BYTES, "a dye spectrum CSV")
        .map_err(|e| e.to_string())?;
    let (mut l, mut e) = (Vec::new(), Vec::new());
    for row in crate::files::csv_rows::rows(&text) {
        let row = row.map_err(|e| format!("line {}: {}", e.line, e.message))?;
        let line = row.line;
        let (a, b) = match (row.number(0, "lambda_nm"), row.number(1, "eps_l_per_mg_cm")) {
            (Ok(a), Ok(b)) if row.len() == 2 => (a, b),
            // Headers (and anything else) before the first data row.
            _ if l.is_empty() => continue,
            (Ok(_), Ok(_)) => {
                return Err(format!(
                    "line {line}: {EXPECTED}; got {} columns: {}",
                    row.len(),
                    row.text()
                ))
            }
            (Err(m), _) | (_, Err(m)) => return Err(format!("line {line}: {m}; {EXPECTED}")),
        };
        if !a.is_finite() {
            return Err(format!(
                "line {line}: column 1 (lambda_nm): need a finite wavelength, got {a}"
            ));
        }
        if !(b.is_finite() && b >= 0.0) {
            return Err(format!(
                "line {line}: column 2 (eps_l_per_mg_cm): need a finite ε ≥ 0, got {b}"
            ));
        }
        if let Some(&p) = l.last().filter(|&&p| a <= p) {
            return Err(format!(
                "line {line}: column 1 (lambda_nm): wavelengths must increase ({a} after {p})"
            ));
        }
        if l.len() >= MAX_SPECTRUM_ROWS {
            return Err(format!(
                "line {line}: more than {MAX_SPECTRUM_ROWS} rows, over the limit for a dye \
                 spectrum"
            ));
        }
        l.push(a);
        e.push(b);
    }
    if l.len() < 2 {
        return Err("need at least two rows `lambda_nm,eps_l_per_mg_cm`".into());
    }
    Ok(Spectrum::Table {
        lambda_nm: l,
        eps_l_per_mg_cm: e,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fig_61_deep_shade_silk() {
        // Fig. 61: silk, ζ = 4 %, the reactive class's top ε = 0.0158 → 84.68 mm⁻¹.
        let mua = mua_per_mm(1.34, 0.04, 0.0158);
        assert!((mua - 84.688).abs() < 0.01, "{mua}");
    }

    #[test]
    fn spectrum_csv_rows_and_malformed_rows() {
        let dir = tempfile::tempdir().unwrap();
        let read = |text: &str| {
            let path = dir.path().join("d.csv");
            std::fs::write(&path, text).unwrap();
            spectrum_from_csv(&path)
        };
        let Spectrum::Table {
            lambda_nm,
            eps_l_per_mg_cm,
        } = read("# dye\nlambda_nm,eps_l_per_mg_cm\n400, 0.01\n\n500 ,0.02\r\n").unwrap()
        else {
            panic!()
        };
        assert_eq!(
            (lambda_nm, eps_l_per_mg_cm),
            (vec![400.0, 500.0], vec![0.01, 0.02])
        );
        assert_eq!(
            read("l,e\n400,0.01\n450,x\n").unwrap_err(),
            "line 3: column 2 (eps_l_per_mg_cm): expected a number, got \"x\"; expected two \
             numbers `lambda_nm,eps_l_per_mg_cm`"
        );
        assert_eq!(
            read("400,0.01\n# c\n450,0.02,7\n").unwrap_err(),
            "line 3: expected two numbers `lambda_nm,eps_l_per_mg_cm`; got 3 columns: \
             \"450,0.02,7\""
        );
        assert_eq!(
            read("400,0.01\n390,0.02\n").unwrap_err(),
            "line 2: column 1 (lambda_nm): wavelengths must increase (390 after 400)"
        );
        assert!(read("400,0.01\n450,-1\n")
            .unwrap_err()
            .starts_with("line 2: column 2"));
    }

    #[test]
    fn presets_parse_with_sources_and_bands() {
        let p = presets();
        assert!(p.len() >= 4, "{} presets", p.len());
        for d in &p {
            assert!(!d.source.is_empty(), "{}", d.name);
            let Spectrum::Bands(b) = &d.spectrum else {
                panic!()
            };
            for band in b {
                assert!(band.peak_nm > 300.0 && band.peak_nm < 800.0, "{}", d.name);
                assert!(
                    band.fwhm_nm > 10.0 && band.peak_eps_l_per_mg_cm > 0.0,
                    "{}",
                    d.name
                );
            }
        }
        assert!(p.iter().any(|d| d.class == DyeClass::Reactive));
        assert!(p.iter().any(|d| d.class == DyeClass::Disperse));
    }

    #[test]
    fn band_peaks_where_declared() {
        let d = Dye {
            name: "x".into(),
            class: DyeClass::Reactive,
            spectrum: Spectrum::Bands(vec![Band {
                peak_nm: 520.0,
                fwhm_nm: 100.0,
                peak_eps_l_per_mg_cm: 0.01,
            }]),
            source: String::new(),
        };
        assert!((d.eps_l_per_mg_cm(520.0) - 0.01).abs() < 1e-15);
        assert!((d.eps_l_per_mg_cm(570.0) - 0.005).abs() < 1e-12);
    }
}
