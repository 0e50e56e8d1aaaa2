//! Spectral reflectance → CIE XYZ → linear sRGB, for tabulated diffusion profiles (§3.5:
//! "Each diffusion profile is then transformed from spectral XYZ tri-stimulus values to sRGB").
//!
//! XYZ = Σᵢ R(λᵢ)·S(λᵢ)·c̄(λᵢ)·Δλᵢ / Σᵢ S(λᵢ)·ȳ(λᵢ)·Δλᵢ, with the CIE 1931 2° observer c̄ and
//! illuminant D65 S sampled at the grid's own wavelengths and Δλᵢ the width of sample i's bin
//! (half-way to each neighbour; the neighbour spacing at either end), constant on uniform grids. Numerator and normaliser use the same bins, so a perfect white diffuser has Y = 1
//! on any grid (this is colour-science's `sd_to_XYZ(…, method="Integration", shape=grid)/100`).
//! Linear sRGB = M·XYZ with the IEC 61966-2-1 matrix, then divided per channel by the white
//! diffuser's M·XYZ, so that R ≡ 1 gives exactly (1, 1, 1) even though the grid truncates the
//! observer's range (400–700 nm holds 99.7 % of D65's luminance).

use std::sync::OnceLock;

use super::table::SpectralTable;

const CIE1931: &str = include_str!("data/cie1931_2deg.csv");
const D65: &str = include_str!("data/illuminant_d65.csv");

/// XYZ → linear sRGB (D65 white), IEC 61966-2-1:1999 §5.2, as colour-science 0.4.7 uses it.
pub const RGB_FROM_XYZ: [[f64; 3]; 3] = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];

struct Tables {
    cmf: [SpectralTable; 3],
    d65: SpectralTable,
}

fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    T.get_or_init(|| {
        let parse = |name: &str, text: &str, col: usize| {
            SpectralTable::parse_csv(name, text, col)
                .unwrap_or_else(|e| panic!("embedded colour table is corrupt: {e}"))
        };
        Tables {
            cmf: [
                parse("cie1931_2deg.csv", CIE1931, 1),
                parse("cie1931_2deg.csv", CIE1931, 2),
                parse("cie1931_2deg.csv", CIE1931, 3),
            ],
            d65: parse("illuminant_d65.csv", D65, 1),
        }
    })
}

/// The linear map from a reflectance spectrum on one wavelength grid to XYZ and linear sRGB.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourMap {
    pub lambda_nm: Vec<f64>,
    /// XYZ = Σᵢ R(λᵢ)·`xyz_weights[i]`.
    pub xyz_weights: Vec<[f64; 3]>,
    pub rgb_from_xyz: [[f64; 3]; 3],
    /// M·XYZ of the perfect white diffuser (R ≡ 1).
    pub white_rgb: [f64; 3],
    /// rgb = Σᵢ R(λᵢ)·`rgb_weights[i]`: the whole map folded into one weight per sample.
    pub rgb_weights: Vec<[f64; 3]>,
}

fn mat_vec(m: &[[f64; 3]; 3], v: &[f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| (0..3).map(|c| m[r][c] * v[c]).sum())
}

impl ColourMap {
    /// The map for `lambda_nm` (strictly increasing, within the tables' 360–830 nm).
    pub fn new(lambda_nm: &[f64]) -> Self {
        let t = tables();
        let n = lambda_nm.len();
        // Bin widths: uniform grids get a constant width (which cancels).
        let width = |i: usize| -> f64 {
            if n == 1 {
                return 1.0;
            }
            let lo = if i == 0 {
                lambda_nm[0]
            } else {
                0.5 * (lambda_nm[i - 1] + lambda_nm[i])
            };
            let hi = if i == n - 1 {
                lambda_nm[n - 1]
            } else {
                0.5 * (lambda_nm[i] + lambda_nm[i + 1])
            };
            let w = hi - lo;
            // End samples get a full step, like interior ones, so a uniform grid is uniform.
            if i == 0 || i == n - 1 {
                2.0 * w
            } else {
                w
            }
        };
        let mut raw = Vec::with_capacity(n);
        let mut norm = 0.0;
        for (i, &l) in lambda_nm.iter().enumerate() {
            let s = t.d65.at(l) * width(i);
            let w: [f64; 3] = std::array::from_fn(|c| s * t.cmf[c].at(l));
            norm += w[1];
            raw.push(w);
        }
        let xyz_weights: Vec<[f64; 3]> = raw
            .iter()
            .map(|w| [w[0] / norm, w[1] / norm, w[2] / norm])
            .collect();
        let white_xyz: [f64; 3] = std::array::from_fn(|c| xyz_weights.iter().map(|w| w[c]).sum());
        let white_rgb = mat_vec(&RGB_FROM_XYZ, &white_xyz);
        let rgb_weights = xyz_weights
            .iter()
            .map(|w| {
                let rgb = mat_vec(&RGB_FROM_XYZ, w);
                [
                    rgb[0] / white_rgb[0],
                    rgb[1] / white_rgb[1],
                    rgb[2] / white_rgb[2],
                ]
            })
            .collect();
        Self {
            lambda_nm: lambda_nm.to_vec(),
            xyz_weights,
            rgb_from_xyz: RGB_FROM_XYZ,
            white_rgb,
            rgb_weights,
        }
    }

    /// CIE XYZ of reflectance `r` (Y = 1 for the white diffuser).
    pub fn xyz(&self, r: &[f64]) -> [f64; 3] {
        assert_eq!(r.len(), self.lambda_nm.len());
        std::array::from_fn(|c| r.iter().zip(&self.xyz_weights).map(|(r, w)| r * w[c]).sum())
    }

    /// Linear sRGB of reflectance `r`, white = (1, 1, 1). Computed as M·XYZ / white so it
    /// matches colour-science to rounding.
    pub fn rgb(&self, r: &[f64]) -> [f64; 3] {
        let rgb = mat_vec(&RGB_FROM_XYZ, &self.xyz(r));
        std::array::from_fn(|c| rgb[c] / self.white_rgb[c])
    }

    /// Standard error of [`Self::rgb`] for independent per-wavelength errors `se`.
    pub fn rgb_se(&self, se: &[f64]) -> [f64; 3] {
        std::array::from_fn(|c| {
            se.iter()
                .zip(&self.rgb_weights)
                .map(|(s, w)| (s * w[c]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
    }
}

/// sRGB transfer function (IEC 61966-2-1), linear [0, 1] → encoded [0, 1], clamped.
pub fn srgb_encode(linear: f64) -> f64 {
    let x = linear.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::WavelengthGrid;

    #[test]
    fn white_is_one_and_y_is_one() {
        for grid in [
            WavelengthGrid::thesis_default(),
            WavelengthGrid::uniform(380.0, 780.0, 5.0),
            WavelengthGrid::from_list(vec![450.0, 500.0, 560.0, 610.0, 700.0]),
        ] {
            let m = ColourMap::new(grid.lambda_nm());
            let ones = vec![1.0; grid.len()];
            let rgb = m.rgb(&ones);
            let xyz = m.xyz(&ones);
            assert!((xyz[1] - 1.0).abs() < 1e-14);
            for c in rgb {
                assert!((c - 1.0).abs() < 1e-14, "{rgb:?}");
            }
        }
    }

    #[test]
    fn full_range_white_is_close_to_d65_white_point() {
        // CIE 15:2004 Table T.3: D65 white point x = 0.31272, y = 0.32903 (1931 2°).
        let g = WavelengthGrid::uniform(360.0, 830.0, 1.0);
        let m = ColourMap::new(g.lambda_nm());
        let xyz = m.xyz(&vec![1.0; g.len()]);
        let s = xyz[0] + xyz[1] + xyz[2];
        assert!((xyz[0] / s - 0.31272).abs() < 5e-5, "x = {}", xyz[0] / s);
        assert!((xyz[1] / s - 0.32903).abs() < 5e-5, "y = {}", xyz[1] / s);
        // With the full range the white's sRGB is (1, 1, 1) before normalisation, to the
        // matrix's 4-digit rounding.
        for c in m.white_rgb {
            assert!((c - 1.0).abs() < 2e-3, "{:?}", m.white_rgb);
        }
    }

    #[test]
    fn folded_weights_equal_the_two_step_map() {
        let g = WavelengthGrid::thesis_default();
        let m = ColourMap::new(g.lambda_nm());
        let r: Vec<f64> = g
            .lambda_nm()
            .iter()
            .map(|l| 0.2 + 0.5 * ((l - 400.0) / 300.0))
            .collect();
        let a = m.rgb(&r);
        let b: [f64; 3] =
            std::array::from_fn(|c| r.iter().zip(&m.rgb_weights).map(|(r, w)| r * w[c]).sum());
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() < 1e-14);
        }
        // A reddish spectrum is redder than it is blue.
        assert!(a[0] > a[2]);
    }

    fn fixture(name: &str) -> Vec<Vec<String>> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/colour")
            .join(name);
        std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#') && !l.is_empty())
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect()
    }

    /// Issue 22: the sRGB transfer function against colour-science's `cctf_encoding` at 197
    /// values (`tests/colour/`, made by `validation/make_colour_fixtures.py`), dense around
    /// the 0.0031308 knee: an exponent of 1/2.2 or a knee of 0.04045 fails.
    #[test]
    fn srgb_encode_matches_colour_science() {
        let rows = fixture("srgb_transfer.csv");
        assert_eq!(rows.len(), 197);
        for r in &rows {
            let (x, want): (f64, f64) = (r[0].parse().unwrap(), r[1].parse().unwrap());
            assert!(
                (srgb_encode(x) - want).abs() < 1e-12,
                "encode({x}) = {} vs {want}",
                srgb_encode(x)
            );
        }
    }

    /// Issue 22: coloured spectra through the whole chain (the 24 ColorChecker patches, two
    /// narrow bands, a step, the white diffuser) against colour-science's XYZ, linear and
    /// encoded sRGB on the 400–700 nm / 10 nm grid: a swapped matrix row fails here although
    /// white stays (1, 1, 1).
    #[test]
    fn coloured_spectra_match_colour_science() {
        let rows = fixture("spectra_srgb.csv");
        assert_eq!(rows.len(), 28);
        let grid: Vec<f64> = (0..31).map(|i| 400.0 + 10.0 * i as f64).collect();
        let map = ColourMap::new(&grid);
        for r in &rows {
            assert_eq!(r.len(), 41);
            let v: Vec<f64> = r[1..].iter().map(|x| x.parse().unwrap()).collect();
            let (refl, want) = v.split_at(31);
            let xyz = map.xyz(refl);
            let rgb = map.rgb(refl);
            for c in 0..3 {
                assert!(
                    (xyz[c] - want[c]).abs() < 1e-12,
                    "{} XYZ[{c}] {} vs {}",
                    r[0],
                    xyz[c],
                    want[c]
                );
                assert!(
                    (rgb[c] - want[3 + c]).abs() < 1e-12,
                    "{} RGB[{c}] {} vs {}",
                    r[0],
                    rgb[c],
                    want[3 + c]
                );
                let enc = srgb_encode(rgb[c]);
                assert!(
                    (enc - want[6 + c]).abs() < 1e-12,
                    "{} encoded[{c}] {enc} vs {}",
                    r[0],
                    want[6 + c]
                );
            }
        }
    }
}
