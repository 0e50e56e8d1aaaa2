//! The wavelength grid a spec asks for.

use serde::Serialize;

/// Wavelengths in nm, strictly increasing.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WavelengthGrid {
    lambda_nm: Vec<f64>,
}

impl WavelengthGrid {
    /// The thesis grid: 400–700 nm every 10 nm (§3.5).
    pub fn thesis_default() -> Self {
        Self::uniform(400.0, 700.0, 10.0)
    }

    /// `start_nm`, `start_nm + step_nm`, … up to and including `stop_nm` (within 1e-9 nm).
    pub fn uniform(start_nm: f64, stop_nm: f64, step_nm: f64) -> Self {
        assert!(step_nm > 0.0 && stop_nm >= start_nm, "invalid grid");
        let n = ((stop_nm - start_nm) / step_nm + 1e-9).floor() as usize + 1;
        Self {
            lambda_nm: (0..n).map(|i| start_nm + i as f64 * step_nm).collect(),
        }
    }

    /// An explicit list; the caller guarantees it is strictly increasing.
    pub fn from_list(lambda_nm: Vec<f64>) -> Self {
        debug_assert!(lambda_nm.windows(2).all(|w| w[0] < w[1]));
        Self { lambda_nm }
    }

    pub fn lambda_nm(&self) -> &[f64] {
        &self.lambda_nm
    }

    pub fn len(&self) -> usize {
        self.lambda_nm.len()
    }

    pub fn is_empty(&self) -> bool {
        self.lambda_nm.is_empty()
    }
}
