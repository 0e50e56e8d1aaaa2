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
    let mut sources: Vec<(String, String)> = Vec::new();
    let mut dyes: Vec<Dye> = Vec::new();
    let mut header: Option<Vec<String>> = None;
    for line in PRESETS_CSV.lines() {
        let line = line.trim();
        if let Some(rest) = line.strip_prefix("# source[") {
            if let Some((n, text)) = rest.split_once("]:") {
                sources.push((n.trim().to_string(), text.trim().to_string()));
            }
            continue;
        }
        if line.starts_with('#') || line.is_empty() {
            continue;
        }
        let cols: Vec<&str> = line.split(',').map(str::trim).collect();
        let Some(h) = &header else {
            header = Some(cols.iter().map(|s| s.to_string()).collect());
            continue;
        };
        let get = |k: &str| -> &str {
            h.iter()
                .position(|c| c == k)
                .and_then(|i| cols.get(i).copied())
                .unwrap_or("")
        };
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

/// Reads a tabulated spectrum: rows `lambda_nm,eps_l_per_mg_cm`, `#` comments and one header
/// row allowed, wavelengths strictly increasing, ε ≥ 0.
pub fn spectrum_from_csv(path: &Path) -> Result<Spectrum, String> {
    let text = crate::files::read_text(path, crate::files::MAX_DATA_BYTES, "a dye spectrum CSV")
        .map_err(|e| e.to_string())?;
    let (mut l, mut e) = (Vec::new(), Vec::new());
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let c: Vec<&str> = line.split(',').map(str::trim).collect();
        match (
            c.first().and_then(|x| x.parse::<f64>().ok()),
            c.get(1).and_then(|x| x.parse::<f64>().ok()),
        ) {
            (Some(a), Some(b)) if c.len() == 2 => {
                if !(a.is_finite() && b.is_finite() && b >= 0.0) {
                    return Err(format!(
                        "line {}: need a finite wavelength and ε ≥ 0",
                        i + 1
                    ));
                }
                if l.last().is_some_and(|&p| a <= p) {
                    return Err(format!("line {}: wavelengths must increase", i + 1));
                }
                l.push(a);
                e.push(b);
            }
            _ if l.is_empty() => continue,
            _ => {
                return Err(format!(
                    "line {}: expected `lambda_nm,eps_l_per_mg_cm`, got {line:?}",
                    i + 1
                ))
            }
        }
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
