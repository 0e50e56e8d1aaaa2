//! The measured data tables compiled into the binary, as one checksum: a changed data file
//! changes every work unit's key ([`crate::pipeline::KeyBuilder`]).

use sha2::{Digest, Sha256};

/// SHA-256 over the measured data tables compiled into the binary (spectra, CIE tables, dye
/// presets), each as its name, a NUL, its text and a NUL.
pub fn checksum() -> &'static [u8; 32] {
    static SUM: std::sync::OnceLock<[u8; 32]> = std::sync::OnceLock::new();
    SUM.get_or_init(|| {
        let mut h = Sha256::new();
        for (name, text) in crate::spectral::DATA_FILES
            .iter()
            .chain(crate::fiber::dye::DATA_FILES)
        {
            h.update(name.as_bytes());
            h.update([0]);
            h.update(text.as_bytes());
            h.update([0]);
        }
        h.finalize().into()
    })
}
