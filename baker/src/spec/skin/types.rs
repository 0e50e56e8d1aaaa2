//! What a resolved skin spec holds.

use super::profiles::ProfileSettings;
use crate::skin::SkinParams;
use crate::spec::limits::Limits;
use crate::spectral::WavelengthGrid;

/// Age range the model accepts, years: from young adults (the model's base values are adult,
/// §3.4) to 90 (Eq. 4's linear decline stays positive: 1 − 6·(0.06 + 0.10) = 0.04).
pub const AGE_RANGE_YEARS: (f64, f64) = (18.0, 90.0);
/// Wavelengths the embedded spectra cover, nm.
pub const LAMBDA_RANGE_NM: (f64, f64) = (380.0, 780.0);

/// A validated skin spec.
#[derive(Debug, Clone)]
pub struct SkinSpec {
    pub file: String,
    pub wavelengths: WavelengthGrid,
    pub entries: Vec<ResolvedEntry>,
    pub profiles: ProfileSettings,
    pub limits: Limits,
    /// Where `profiles.photons` is set (line 1 when it is not): budget errors point there.
    pub photons_at: (u64, u64),
    /// Simulation groups of entries that share scattering ([`crate::profile::plan`] with
    /// absorption reuse), and the largest group's size.
    pub groups: usize,
    pub largest_group: usize,
    /// SHA-256 of the spec text as read (provenance in every table).
    pub sha256: String,
    /// The layer optics of every entry (in `entries` order), evaluated once by the resolver.
    pub optics: Vec<formats::OpticsEntry>,
}

/// One concrete entry (a listed entry, or one point of a sweep).
#[derive(Debug, Clone)]
pub struct ResolvedEntry {
    pub name: String,
    /// Line of the entry or sweep in the spec.
    pub line: u64,
    pub params: SkinParams,
}
