//! Tabulated fiber BCSDFs (`.bcsdf`): the 4D scattering function f(ωi, ωo) of one fiber
//! cross-section (thesis §5.3.2, §5.5), one zstd frame per stored incoming direction so a
//! renderer can stream, plus the directional albedo Λ(ωi) and the projected width A(φ).
//!
//! # Conventions
//! Fiber frame: axis +z. A direction ω (unit vector, pointing away from the fiber for ωo and
//! towards the light for ωi) has θ = asin(ω·z) ∈ [−90°, 90°] and φ = atan2(ω·y, ω·x).
//! Outgoing azimuths are relative: Δφ = φo − φi wrapped to [−180°, 180°). The grid has
//! `n_theta = 180/res` θ bins from −90° and `n_phi = 360/res` φ (or Δφ) bins from −180°
//! ([`AngularGrid`], [`Directory::grid`]).
//!
//! # What is stored
//! Per stored ωi, per variant (dye × depth of shade) and channel (R, G, B or one wavelength):
//! the BCSDF normalised to one, `f̂(ωi, ωo)` in sr⁻¹ (Σ f̂·ΔΩ = 1 over the θo × Δφ bins), and
//! the albedo Λ(ωi), so f = Λ·f̂ (§5.5: "the BCSDFs are normalized to one, with a separated
//! table coding the directionally-varying albedo"). Every (θi, φi) bin of the full grid maps
//! to a stored ωi through `wi_map`, with flags saying whether θo or Δφ change sign there:
//! that is how the symmetries of the fiber (mirror along the axis, rotations and mirrors of
//! the cross-section) shrink the table.
//!
//! The sampling density is p(ωo) = mean over channels of f̂ (renormalised after quantisation),
//! piecewise constant in solid angle over the bins. Its 2D CDFs (marginal over θo, conditional
//! over Δφ) are derived when a slice is decoded, so they always match the stored values.
//!
//! # Byte layout (version 1; formats/FORMAT.md has the full description)
//! ```text
//! offset  size  field
//!      0     8  magic b"BAKERFIB"
//!      8     4  format version, u32 LE = 1
//!     12     4  flags, u32 LE = 0
//!     16     8  directory_compressed_len, u64 LE
//!     24     8  directory_raw_len, u64 LE
//!     32     8  payload_len, u64 LE
//!     40     4  directory_crc32, u32 LE (of the decompressed directory)
//!     44     4  reserved, u32 LE = 0
//!     48     …  directory: one zstd frame holding UTF-8 JSON ([`Directory`])
//!      …     …  payload: one zstd frame per stored ωi, at `chunks[i].offset` from its start
//! ```
//! A chunk decompresses to `n_variants × n_channels × n_theta × n_phi` values (row-major,
//! θo rows, Δφ columns) of `dtype` (`f16` or `f32`, little-endian), **byte-shuffled**: the
//! first byte of every value, then the second byte of every value, and so on (as HDF5's
//! shuffle filter). A value times `scale[i][variant][channel]` is f̂.

use std::f64::consts::PI;
use std::path::Path;
use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

pub use crate::grid::solid_angle;
use crate::grid::AngularGrid;
use crate::table::{crc32, decompress, TableError};

/// The first 8 bytes of every file.
pub const MAGIC: [u8; 8] = *b"BAKERFIB";
/// Current version of the layout.
pub const VERSION: u32 = 1;
/// Size of the fixed header in bytes.
pub const HEADER_LEN: usize = 48;
/// Usual file extension (without the dot).
pub const EXTENSION: &str = "bcsdf";
/// `kind` of the directory.
pub const KIND: &str = "baker-fiber-bcsdf";
/// `wi_map` flag: θo changes sign (mirror z → −z along the fiber).
pub const FLIP_THETA: u32 = 1 << 31;
/// `wi_map` flag: Δφ changes sign (mirror of the cross-section).
pub const FLIP_DPHI: u32 = 1 << 30;
/// `wi_map` mask of the stored index.
pub const INDEX_MASK: u32 = (1 << 30) - 1;

/// Element type of the stored values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// IEEE-754 binary16.
    F16,
    /// IEEE-754 binary32.
    F32,
}

impl Precision {
    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            Precision::F16 => 2,
            Precision::F32 => 4,
        }
    }

    /// Explicit mantissa bits of the type (10 or 23).
    pub fn mantissa_bits(self) -> u32 {
        match self {
            Precision::F16 => 10,
            Precision::F32 => 23,
        }
    }
}

/// Location of one chunk in the payload.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Chunk {
    pub offset: u64,
    pub compressed_bytes: u64,
    pub raw_bytes: u64,
    /// CRC-32 of the decompressed (shuffled) bytes.
    pub crc32: u32,
}

/// The JSON directory of a `.bcsdf` file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Directory {
    /// Always [`KIND`].
    pub kind: String,
    /// Bin width in degrees; `n_theta = 180/res_deg`, `n_phi = 360/res_deg`.
    pub res_deg: f64,
    pub n_theta: usize,
    pub n_phi: usize,
    /// Stored incoming directions, bin centres `[θi, φi]` in degrees.
    pub wi_deg: Vec<[f64; 2]>,
    /// Full grid (θi row-major, `n_theta × n_phi`): stored index | [`FLIP_THETA`] | [`FLIP_DPHI`].
    pub wi_map: Vec<u32>,
    /// Variant names (dye and depth of shade, or `undyed`).
    pub variants: Vec<String>,
    /// Channel names: `R`, `G`, `B` (linear sRGB, D65) or wavelengths such as `550nm`.
    pub channels: Vec<String>,
    pub dtype: Precision,
    /// Mantissa bits kept after rounding (≤ the type's): lossy "bit rounding" that zeroes
    /// bits below the Monte Carlo noise so zstd can compress. An upper bound: a writer may
    /// round a value to fewer bits, within a tolerance of its bin ([`encode_slice`]).
    pub keep_bits: u32,
    /// Per stored ωi, variant, channel: value = stored × scale.
    pub scale: Vec<f32>,
    /// Per stored ωi, variant, channel: directional albedo Λ(ωi).
    pub albedo: Vec<f32>,
    /// Standard error of `albedo`.
    pub albedo_se: Vec<f32>,
    /// Projected width of the fiber per unit length, µm, at the φ bin centres (absolute φ;
    /// A(ω) of Eq. 17 before its sin(ω, ωf) factor).
    pub area_um: Vec<f64>,
    /// One per stored ωi.
    pub chunks: Vec<Chunk>,
    /// Free-form provenance: fiber, section, photons, seed, symmetry, timing, noise.
    pub metadata: serde_json::Value,
}

impl Directory {
    /// Number of stored incoming directions.
    pub fn n_wi(&self) -> usize {
        self.wi_deg.len()
    }

    /// Values per variant and channel in one slice.
    pub fn bins(&self) -> usize {
        self.n_theta * self.n_phi
    }

    /// The θ × φ grid of the stored slices and of `wi_map`.
    pub fn grid(&self) -> AngularGrid {
        AngularGrid {
            res_deg: self.res_deg,
            n_theta: self.n_theta,
            n_phi: self.n_phi,
        }
    }

    fn check(&self) -> Result<(), TableError> {
        let bad = |m: String| Err(TableError::Format(m));
        if self.kind != KIND {
            return bad(format!("kind {:?}, expected {KIND:?}", self.kind));
        }
        let n = 180.0 / self.res_deg;
        if !(n.is_finite() && n >= 1.0 && (n - n.round()).abs() < 1e-9) {
            return bad(format!("res_deg {} does not divide 180°", self.res_deg));
        }
        if self.n_theta != n.round() as usize || self.n_phi != 2 * self.n_theta {
            return bad("n_theta/n_phi disagree with res_deg".into());
        }
        let (w, v, c) = (self.n_wi(), self.variants.len(), self.channels.len());
        if w == 0 || v == 0 || c == 0 {
            return bad("no stored direction, variant or channel".into());
        }
        let finite = |x: &[f32]| x.iter().all(|v| v.is_finite() && *v >= 0.0);
        if !finite(&self.scale) || !finite(&self.albedo) || !finite(&self.albedo_se) {
            return bad("scale or albedo values are negative or not finite".into());
        }
        if self
            .wi_deg
            .iter()
            .flatten()
            .chain(&self.area_um)
            .any(|v| !v.is_finite())
        {
            return bad("wi_deg or area_um values are not finite".into());
        }
        if self.n_theta.checked_mul(self.n_phi).is_none() || self.wi_map.len() != self.bins() {
            return bad(format!(
                "wi_map has {} entries, expected {}",
                self.wi_map.len(),
                self.bins()
            ));
        }
        if self.wi_map.iter().any(|&m| (m & INDEX_MASK) as usize >= w) {
            return bad("wi_map points past the stored directions".into());
        }
        for (name, len) in [
            ("scale", self.scale.len()),
            ("albedo", self.albedo.len()),
            ("albedo_se", self.albedo_se.len()),
        ] {
            if len != w * v * c {
                return bad(format!("{name} has {len} values, expected {}", w * v * c));
            }
        }
        if self.area_um.len() != self.n_phi || self.chunks.len() != w {
            return bad("area_um or chunks have the wrong length".into());
        }
        if self.keep_bits > self.dtype.mantissa_bits() {
            return bad(format!(
                "keep_bits {} exceeds the type's mantissa",
                self.keep_bits
            ));
        }
        let raw = [v, c, self.bins(), self.dtype.size()]
            .iter()
            .try_fold(1u64, |acc, &x| acc.checked_mul(x as u64));
        if self.chunks.iter().any(|k| Some(k.raw_bytes) != raw) {
            return bad("a chunk's raw size disagrees with the grid".into());
        }
        Ok(())
    }
}

/// Rounds the IEEE-754 bits `bits` of a non-negative value (`mant` explicit mantissa bits,
/// `exp` exponent bits) to `keep` bits after its leading one, round half to even: the
/// "bitround" of Klöwer et al., Nature Computational Science 1, 713 (2021). A normal value
/// keeps `keep` mantissa bits; a subnormal keeps `keep` bits after its own leading one, so
/// the relative error is at most 2^−(keep+1) for both. Zero, infinities and NaN are
/// returned as they are.
fn round_significand(bits: u32, mant: u32, exp: u32, keep: u32) -> u32 {
    let exponent = (bits >> mant) & ((1 << exp) - 1);
    if bits == 0 || exponent == (1 << exp) - 1 {
        return bits;
    }
    // Bits after the leading one: all `mant` of a normal value, fewer of a subnormal.
    let after = if exponent == 0 {
        31 - bits.leading_zeros()
    } else {
        mant
    };
    let drop = after.saturating_sub(keep);
    if drop == 0 {
        return bits;
    }
    let half = 1u32 << (drop - 1);
    let r = bits + (half - 1) + ((bits >> drop) & 1);
    (r >> drop) << drop
}

/// Rounds the mantissa of a non-negative f32 to `keep` bits (round half to even, after
/// Klöwer et al. 2021; subnormals keep `keep` bits after their leading one).
pub fn round_f32(x: f32, keep: u32) -> f32 {
    f32::from_bits(round_significand(x.to_bits(), 23, 8, keep))
}

/// f16 counterpart of [`round_f32`] on the raw bits.
fn round_f16_bits(h: u16, keep: u32) -> u16 {
    // A rounded finite f16 fits in 16 bits (the largest rounds up to at most infinity).
    round_significand(u32::from(h), 10, 5, keep) as u16
}

/// Mantissa bits that keep the rounding error of a value within `rel_tol` of it: the
/// smallest k with 2^−(k+1) ≤ `rel_tol` (round to nearest to k bits after the leading one
/// errs by at most half a unit of the k-th bit, 2^(e−k−1) ≤ 2^−(k+1)·x for 2^e ≤ x).
/// A tolerance of zero or one that is not finite and positive keeps every bit (`u32::MAX`).
pub fn bits_for_rel_error(rel_tol: f64) -> u32 {
    if rel_tol.is_nan() || rel_tol <= 0.0 {
        return u32::MAX;
    }
    if rel_tol.is_infinite() {
        return 0;
    }
    (-1.0 - rel_tol.log2()).ceil().clamp(0.0, 64.0) as u32
}

/// Encodes one slice (`v × c × bins` values of f̂ ≥ 0) for `dir`'s type and bit count: returns
/// the per (variant, channel) scales, the shuffled raw bytes, and the values a reader will
/// decode (so writers of other formats can store exactly the same numbers).
///
/// `rel_tol`, when given, holds one relative tolerance per bin (θo × Δφ, shared by every
/// variant and channel): each value is rounded further, after `keep_bits`, to the fewest
/// mantissa bits whose rounding error stays within that fraction of the value
/// ([`bits_for_rel_error`]); `keep_bits` stays the upper bound. Rounding only zeroes low
/// mantissa bits, so readers need not know it was done.
pub fn encode_slice(
    values: &[f64],
    n_vc: usize,
    dtype: Precision,
    keep_bits: u32,
    rel_tol: Option<&[f64]>,
) -> (Vec<f32>, Vec<u8>, Vec<f32>) {
    let bins = values.len() / n_vc.max(1);
    let size = dtype.size();
    let n = values.len();
    let mut raw = vec![0u8; n * size];
    let mut decoded = vec![0f32; n];
    let mut scales = Vec::with_capacity(n_vc);
    // Per bin, shared by every variant and channel.
    let keeps: Option<Vec<u32>> = rel_tol.map(|t| {
        t.iter()
            .map(|&r| bits_for_rel_error(r).min(keep_bits))
            .collect()
    });
    let keep_in = |j: usize| keeps.as_ref().map_or(keep_bits, |k| k[j]);
    // A part's values scaled to f32, and (f16) their halves: converted a slice at a time
    // (`half`'s slice conversions run F16C several values per instruction where the
    // processor has it; one call per value cost a sweep's writer more than the rounding).
    let mut ys = vec![0f32; bins];
    let mut hs = vec![half::f16::ZERO; if dtype == Precision::F16 { bins } else { 0 }];
    for k in 0..n_vc {
        let part = &values[k * bins..(k + 1) * bins];
        let max = part.iter().copied().fold(0.0, f64::max);
        let scale = pow2_scale(max);
        scales.push(scale);
        for (y, &x) in ys.iter_mut().zip(part) {
            *y = (x / scale as f64) as f32;
        }
        let out = &mut decoded[k * bins..(k + 1) * bins];
        match dtype {
            Precision::F16 => {
                use half::slice::HalfFloatSliceExt;
                hs.convert_from_f32_slice(&ys);
                for (j, h) in hs.iter_mut().enumerate() {
                    let i = k * bins + j;
                    // `keep_bits` first (the bytes of an unquantised table), then the bin's
                    // noise.
                    let keep = keep_in(j);
                    let mut b = round_f16_bits(h.to_bits(), keep_bits);
                    if keep < keep_bits {
                        b = round_f16_bits(b, keep);
                    }
                    let [lo, hi] = b.to_le_bytes();
                    raw[i] = lo;
                    raw[n + i] = hi;
                    *h = half::f16::from_bits(b);
                }
                hs.convert_to_f32_slice(out);
                for d in out.iter_mut() {
                    *d *= scale;
                }
            }
            Precision::F32 => {
                for (j, (&y, d)) in ys.iter().zip(out.iter_mut()).enumerate() {
                    let i = k * bins + j;
                    let keep = keep_in(j);
                    let mut r = round_f32(y, keep_bits);
                    if keep < keep_bits {
                        r = round_f32(r, keep);
                    }
                    for (s, byte) in r.to_le_bytes().into_iter().enumerate() {
                        raw[s * n + i] = byte;
                    }
                    *d = r * scale;
                }
            }
        }
    }
    (scales, raw, decoded)
}

/// The scale of a part whose largest value is `max`: the power of two that puts `max` in
/// [½, 1), as a scale of `max` itself would within a factor of two. Dividing by it is exact,
/// so a stored value keeps the bits it was rounded to, and value × scale (what readers and
/// the HDF5 copy hold) keeps f16's zero low mantissa bits in f32, which deflate packs
/// tightly. Values below 2⁻¹⁴ of the scale are f16 subnormals with an absolute step of 2⁻²⁴
/// of it (at most 1.2·10⁻⁷ of the maximum): far below any bin that carries energy, and
/// cheaper to store than full relative precision there. 1 for an all-zero part.
pub fn pow2_scale(max: f64) -> f32 {
    if !(max > 0.0 && max.is_finite()) {
        return 1.0;
    }
    // The unbiased exponent e of the f64: 2^e ≤ max < 2^(e+1) (exact, no log2 rounding).
    let e = ((max.to_bits() >> 52) & 0x7FF) as i32 - 1023;
    // f32's normal range bounds the scale (a slice this faint or bright is not physical).
    2f32.powi((e + 1).clamp(-126, 127))
}

fn decode_values(raw: &[u8], dtype: Precision, scales: &[f32], bins: usize) -> Vec<f32> {
    let size = dtype.size();
    let n = raw.len() / size;
    (0..n)
        .map(|i| {
            let s = scales[i / bins];
            match dtype {
                Precision::F16 => {
                    half::f16::from_bits(u16::from_le_bytes([raw[i], raw[n + i]])).to_f32() * s
                }
                Precision::F32 => {
                    f32::from_le_bytes([raw[i], raw[n + i], raw[2 * n + i], raw[3 * n + i]]) * s
                }
            }
        })
        .collect()
}

/// Builds a file from its directory (without `chunks`) and the raw shuffled slices, pushed
/// in order or at their index ([`Writer::push_within_at`]).
pub struct Writer {
    pub dir: Directory,
    payload: Vec<u8>,
    level: i32,
    /// Slices pushed ahead of the next in order, by index: their chunk (offset unset), scales
    /// and frame, appended when the slices before them arrive.
    ahead: std::collections::BTreeMap<usize, (Chunk, Vec<f32>, Vec<u8>)>,
}

impl Writer {
    /// `dir.chunks`, `dir.scale` may be empty: [`Writer::push`] fills them in order.
    pub fn new(mut dir: Directory, zstd_level: i32) -> Self {
        dir.chunks.clear();
        dir.scale.clear();
        Self {
            dir,
            payload: Vec::new(),
            level: zstd_level,
            ahead: Default::default(),
        }
    }

    /// Appends the next stored ωi's slice: `values` are f̂ for every variant and channel.
    /// Returns the decoded values (what a reader will see).
    pub fn push(&mut self, values: &[f64]) -> Result<Vec<f32>, TableError> {
        self.push_within(values, None)
    }

    /// [`Writer::push`], each value rounded within `rel_tol[bin]` of itself as well
    /// ([`encode_slice`]; one tolerance per θo × Δφ bin).
    pub fn push_within(
        &mut self,
        values: &[f64],
        rel_tol: Option<&[f64]>,
    ) -> Result<Vec<f32>, TableError> {
        let next = self.dir.chunks.len() + self.ahead.len();
        self.push_within_at(next, values, rel_tol)
    }

    /// [`Writer::push_within`] for stored ωi number `i`, in any order: a slice pushed ahead of
    /// the next in order waits (compressed) until the ones before it arrive. Every index
    /// below `n_wi` once; [`Writer::finish`] fails while one is missing.
    pub fn push_within_at(
        &mut self,
        i: usize,
        values: &[f64],
        rel_tol: Option<&[f64]>,
    ) -> Result<Vec<f32>, TableError> {
        let done = self.dir.chunks.len();
        if i < done || i >= self.dir.n_wi() || self.ahead.contains_key(&i) {
            return Err(TableError::Invalid(format!(
                "stored direction {i} pushed twice or beyond the {} stored",
                self.dir.n_wi()
            )));
        }
        let n_vc = self.dir.variants.len() * self.dir.channels.len();
        if values.len() != n_vc * self.dir.bins() {
            return Err(TableError::Invalid(format!(
                "slice has {} values, expected {}",
                values.len(),
                n_vc * self.dir.bins()
            )));
        }
        if let Some(t) = rel_tol.filter(|t| t.len() != self.dir.bins()) {
            return Err(TableError::Invalid(format!(
                "{} tolerances for a slice of {} bins",
                t.len(),
                self.dir.bins()
            )));
        }
        let (scales, raw, decoded) =
            encode_slice(values, n_vc, self.dir.dtype, self.dir.keep_bits, rel_tol);
        let frame = zstd::bulk::compress(&raw, self.level)
            .map_err(|e| TableError::Compression(e.to_string()))?;
        let chunk = Chunk {
            offset: 0,
            compressed_bytes: frame.len() as u64,
            raw_bytes: raw.len() as u64,
            crc32: crc32(&raw),
        };
        self.ahead.insert(i, (chunk, scales, frame));
        while let Some((chunk, scales, frame)) = self.ahead.remove(&self.dir.chunks.len()) {
            self.dir.chunks.push(Chunk {
                offset: self.payload.len() as u64,
                ..chunk
            });
            self.dir.scale.extend(scales);
            self.payload.extend_from_slice(&frame);
        }
        Ok(decoded)
    }

    /// Compressed bytes of the slices pushed so far (in order or ahead).
    pub fn frame_bytes(&self) -> impl Iterator<Item = u64> + '_ {
        let ahead = self.ahead.values().map(|(c, _, _)| c.compressed_bytes);
        self.dir
            .chunks
            .iter()
            .map(|c| c.compressed_bytes)
            .chain(ahead)
    }

    /// The zstd level of the frames pushed from now on (each frame is independent) and of
    /// the directory.
    pub fn set_level(&mut self, level: i32) {
        self.level = level;
    }

    /// The zstd level of the next frame (and of the directory, were the file finished now).
    pub fn level(&self) -> i32 {
        self.level
    }

    /// The whole file.
    pub fn finish(self) -> Result<Vec<u8>, TableError> {
        if let Some(i) = self.ahead.keys().next() {
            return Err(TableError::Invalid(format!(
                "stored direction {} was never pushed (direction {i} was)",
                self.dir.chunks.len()
            )));
        }
        self.dir.check()?;
        let json = serde_json::to_vec(&self.dir).map_err(|e| TableError::Invalid(e.to_string()))?;
        let d = zstd::bulk::compress(&json, self.level)
            .map_err(|e| TableError::Compression(e.to_string()))?;
        let mut out = Vec::with_capacity(HEADER_LEN + d.len() + self.payload.len());
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&(d.len() as u64).to_le_bytes());
        out.extend_from_slice(&(json.len() as u64).to_le_bytes());
        out.extend_from_slice(&(self.payload.len() as u64).to_le_bytes());
        out.extend_from_slice(&crc32(&json).to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&d);
        out.extend_from_slice(&self.payload);
        Ok(out)
    }
}

/// One decoded stored ωi: f̂ for every variant and channel, and per variant the sampling
/// density's CDFs.
#[derive(Debug, Clone)]
pub struct Slice {
    /// `[variant][channel][θo][Δφ]`, sr⁻¹.
    pub values: Vec<f32>,
    /// Per variant: CDF over θo rows (`n_theta` values, last = 1).
    pub cdf_theta: Vec<Vec<f64>>,
    /// Per variant: per θo row, CDF over Δφ (`n_theta × n_phi`, each row ending at 1, or all
    /// zero for an empty row).
    pub cdf_phi: Vec<Vec<f64>>,
    /// Per variant: Σ over bins of p·ΔΩ before normalisation (1 up to quantisation; 0 when
    /// the variant scatters nothing).
    pub norm: Vec<f64>,
}

/// A direction drawn by [`Bcsdf::sample`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Unit vector in the fiber frame.
    pub wo: [f64; 3],
    /// Density of `wo` in sr⁻¹.
    pub pdf: f64,
}

/// θ and φ (radians) of a direction in the fiber frame.
pub fn angles(w: [f64; 3]) -> (f64, f64) {
    let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    ((w[2] / n).clamp(-1.0, 1.0).asin(), w[1].atan2(w[0]))
}

/// A direction must be finite and non-zero (it need not be normalised).
fn check_dir(w: [f64; 3]) -> Result<(), TableError> {
    let n2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    if n2.is_finite() && n2 > 0.0 {
        Ok(())
    } else {
        Err(TableError::Invalid(format!(
            "direction {w:?} is zero or not finite"
        )))
    }
}

/// Unit vector of θ, φ (radians).
pub fn direction(theta: f64, phi: f64) -> [f64; 3] {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    [ct * cp, ct * sp, st]
}

/// A `.bcsdf` file in memory, decoding slices on first use (thread-safe).
pub struct Bcsdf {
    pub dir: Directory,
    payload: Vec<u8>,
    slices: Vec<OnceLock<Result<Slice, String>>>,
}

impl std::fmt::Debug for Bcsdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bcsdf")
            .field("n_wi", &self.dir.n_wi())
            .field("variants", &self.dir.variants)
            .field("channels", &self.dir.channels)
            .finish()
    }
}

fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes(b[o..o + 4].try_into().unwrap())
}

fn u64_at(b: &[u8], o: usize) -> u64 {
    u64::from_le_bytes(b[o..o + 8].try_into().unwrap())
}

impl Bcsdf {
    /// Reads and checks a file.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, TableError> {
        let p = path.as_ref();
        let bytes = crate::table::read_file(p)?;
        Self::from_bytes(bytes).map_err(|e| match e {
            TableError::Format(m) => TableError::Format(format!("{}: {m}", p.display())),
            other => other,
        })
    }

    /// Parses a whole file held in memory.
    pub fn from_bytes(mut b: Vec<u8>) -> Result<Self, TableError> {
        let fmt = |m: &str| TableError::Format(m.to_string());
        if b.len() < HEADER_LEN || b[..8] != MAGIC {
            return Err(fmt(
                "not a .bcsdf file (bad magic or shorter than the header)",
            ));
        }
        let version = u32_at(&b, 8);
        if version != VERSION {
            return Err(TableError::UnsupportedVersion(version));
        }
        if u32_at(&b, 12) != 0 || u32_at(&b, 44) != 0 {
            return Err(fmt("unknown flags or non-zero reserved field"));
        }
        let (dc, dr, pl) = (u64_at(&b, 16), u64_at(&b, 24), u64_at(&b, 32));
        let crc = u32_at(&b, 40);
        let end = (HEADER_LEN as u64)
            .checked_add(dc)
            .and_then(|x| x.checked_add(pl))
            .ok_or_else(|| fmt("lengths overflow"))?;
        if end != b.len() as u64 {
            return Err(fmt("file size disagrees with the header (truncated?)"));
        }
        let dstart = HEADER_LEN + dc as usize;
        let json = decompress(&b[HEADER_LEN..dstart], dr, "directory")?;
        let computed = crc32(&json);
        if computed != crc {
            return Err(TableError::Checksum {
                part: "directory".into(),
                stored: crc,
                computed,
            });
        }
        let dir: Directory = serde_json::from_slice(&json)
            .map_err(|e| TableError::Format(format!("directory: {e}")))?;
        dir.check()?;
        if dir
            .chunks
            .iter()
            .any(|c| c.offset.saturating_add(c.compressed_bytes) > pl)
        {
            return Err(fmt("a chunk lies past the payload"));
        }
        let payload = b.split_off(dstart);
        let slices = (0..dir.n_wi()).map(|_| OnceLock::new()).collect();
        Ok(Self {
            dir,
            payload,
            slices,
        })
    }

    /// Decodes stored slice `i` (without caching).
    pub fn decode(&self, i: usize) -> Result<Slice, TableError> {
        let d = &self.dir;
        let c = d.chunks.get(i).ok_or_else(|| {
            TableError::Invalid(format!("no stored direction {i} (file has {})", d.n_wi()))
        })?;
        let frame = &self.payload[c.offset as usize..(c.offset + c.compressed_bytes) as usize];
        let raw = decompress(frame, c.raw_bytes, &format!("chunk {i}"))?;
        let computed = crc32(&raw);
        if computed != c.crc32 || raw.len() as u64 != c.raw_bytes {
            return Err(TableError::Checksum {
                part: format!("chunk {i}"),
                stored: c.crc32,
                computed,
            });
        }
        let (nv, nc) = (d.variants.len(), d.channels.len());
        let bins = d.bins();
        let values = decode_values(
            &raw,
            d.dtype,
            &d.scale[i * nv * nc..(i + 1) * nv * nc],
            bins,
        );
        // Values are finite (a consistent checksum does not make NaN or ∞ data valid; RGB
        // values can be slightly negative out of gamut, as in the skin profiles).
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(TableError::Invalid(format!(
                "chunk {i}: value {k} is {} (BCSDF values are finite)",
                values[k]
            )));
        }
        let (cdf_theta, cdf_phi, norm) = sampling_cdfs(d, &values);
        Ok(Slice {
            values,
            cdf_theta,
            cdf_phi,
            norm,
        })
    }

    /// Decodes every stored slice once (checksums, sizes, finite values) without keeping
    /// them: what a converter calls before it writes anything derived from the table.
    pub fn verify(&self) -> Result<(), TableError> {
        (0..self.dir.n_wi()).try_for_each(|i| self.decode(i).map(|_| ()))
    }

    /// Stored slice `i`, decoded once and kept.
    pub fn slice(&self, i: usize) -> Result<&Slice, TableError> {
        let cell = self.slices.get(i).ok_or_else(|| {
            TableError::Invalid(format!(
                "no stored direction {i} (file has {})",
                self.dir.n_wi()
            ))
        })?;
        cell.get_or_init(|| self.decode(i).map_err(|e| e.to_string()))
            .as_ref()
            .map_err(|e| TableError::Format(e.clone()))
    }

    fn bin_of(&self, theta: f64, phi: f64) -> (usize, usize) {
        self.dir.grid().cell(theta, phi)
    }

    /// Stored index and flags of incoming direction `wi`, and its φi.
    pub fn locate(&self, wi: [f64; 3]) -> (usize, bool, bool, f64) {
        let (t, p) = angles(wi);
        let (it, jp) = self.bin_of(t, p);
        let m = self.dir.wi_map[it * self.dir.n_phi + jp];
        (
            (m & INDEX_MASK) as usize,
            m & FLIP_THETA != 0,
            m & FLIP_DPHI != 0,
            p,
        )
    }

    /// Bin (θo row × Δφ column) of `wo` in the stored slice of `wi`.
    fn out_bin(&self, flip_t: bool, flip_p: bool, phi_i: f64, wo: [f64; 3]) -> usize {
        let (t, p) = angles(wo);
        let t = if flip_t { -t } else { t };
        let dp = p - phi_i;
        let dp = if flip_p { -dp } else { dp };
        let (it, jp) = self.bin_of(t, dp);
        it * self.dir.n_phi + jp
    }

    fn check_variant(&self, v: usize) -> Result<(), TableError> {
        if v >= self.dir.variants.len() {
            return Err(TableError::Invalid(format!(
                "variant {v} out of range (file has {})",
                self.dir.variants.len()
            )));
        }
        Ok(())
    }

    /// The normalised BCSDF f̂(ωi, ωo), sr⁻¹, per channel of `variant`.
    pub fn eval_normalised(
        &self,
        wi: [f64; 3],
        wo: [f64; 3],
        variant: usize,
    ) -> Result<Vec<f32>, TableError> {
        self.check_variant(variant)?;
        check_dir(wi)?;
        check_dir(wo)?;
        let (s, ft, fp, phi_i) = self.locate(wi);
        let sl = self.slice(s)?;
        let b = self.out_bin(ft, fp, phi_i, wo);
        let (nc, bins) = (self.dir.channels.len(), self.dir.bins());
        Ok((0..nc)
            .map(|k| sl.values[(variant * nc + k) * bins + b])
            .collect())
    }

    /// The BCSDF f(ωi, ωo) = Λ(ωi)·f̂(ωi, ωo), sr⁻¹, per channel: the fraction of the power
    /// the fiber intercepts from ωi that leaves per steradian around ωo.
    pub fn eval(&self, wi: [f64; 3], wo: [f64; 3], variant: usize) -> Result<Vec<f32>, TableError> {
        let a = self.albedo(wi, variant)?;
        let mut f = self.eval_normalised(wi, wo, variant)?;
        for (x, a) in f.iter_mut().zip(a) {
            *x *= a;
        }
        Ok(f)
    }

    /// Directional albedo Λ(ωi) per channel.
    pub fn albedo(&self, wi: [f64; 3], variant: usize) -> Result<Vec<f32>, TableError> {
        self.check_variant(variant)?;
        check_dir(wi)?;
        let (s, ..) = self.locate(wi);
        let nc = self.dir.channels.len();
        let o = (s * self.dir.variants.len() + variant) * nc;
        Ok(self.dir.albedo[o..o + nc].to_vec())
    }

    /// Projected area A(ω) of a unit length of fiber seen from ω, in µm (µm² per µm of
    /// length): the projected width at φ times cos θ (thesis Eq. 17 with the fiber axis +z).
    pub fn projected_area(&self, w: [f64; 3]) -> f64 {
        let (t, _) = angles(w);
        self.area_um(w) * t.cos()
    }

    /// Projected width per unit length of the fiber seen from ω, µm (depends on φ only; the
    /// projected area of a fiber segment of length L is `area_um(ω)·L·cos θ`).
    pub fn area_um(&self, w: [f64; 3]) -> f64 {
        let (_, p) = angles(w);
        let (_, jp) = self.bin_of(0.0, p);
        self.dir.area_um[jp]
    }

    /// Density of [`Bcsdf::sample`] at `wo`, sr⁻¹.
    pub fn pdf(&self, wi: [f64; 3], wo: [f64; 3], variant: usize) -> Result<f64, TableError> {
        self.check_variant(variant)?;
        check_dir(wi)?;
        check_dir(wo)?;
        let (s, ft, fp, phi_i) = self.locate(wi);
        let sl = self.slice(s)?;
        if sl.norm[variant] <= 0.0 {
            return Ok(0.0);
        }
        let b = self.out_bin(ft, fp, phi_i, wo);
        let nc = self.dir.channels.len();
        let bins = self.dir.bins();
        let p: f64 = (0..nc)
            .map(|k| sl.values[(variant * nc + k) * bins + b] as f64)
            .sum::<f64>()
            / nc as f64;
        Ok(p / sl.norm[variant])
    }

    /// Draws ωo from the tabulated density with two uniform numbers in [0, 1): θo row by the
    /// marginal CDF, Δφ column by the conditional CDF, then uniformly in solid angle within
    /// the bin (reusing the numbers' remainders). `None` when the variant scatters nothing.
    pub fn sample(
        &self,
        wi: [f64; 3],
        variant: usize,
        u1: f64,
        u2: f64,
    ) -> Result<Option<Sample>, TableError> {
        self.check_variant(variant)?;
        check_dir(wi)?;
        let (s, ft, fp, phi_i) = self.locate(wi);
        let sl = self.slice(s)?;
        if sl.norm[variant] <= 0.0 {
            return Ok(None);
        }
        let d = &self.dir;
        let ct = &sl.cdf_theta[variant];
        let (it, r1) = pick(ct, u1);
        let row = &sl.cdf_phi[variant][it * d.n_phi..(it + 1) * d.n_phi];
        let (jp, r2) = pick(row, u2);
        let res = d.res_deg.to_radians();
        let t0 = d.grid().theta_lower_rad(it);
        let (s0, s1) = (t0.sin(), (t0 + res).sin());
        let theta = (s0 + (s1 - s0) * r1).clamp(-1.0, 1.0).asin();
        let dphi = -PI + (jp as f64 + r2) * res;
        let theta = if ft { -theta } else { theta };
        let dphi = if fp { -dphi } else { dphi };
        let wo = direction(theta, phi_i + dphi);
        let pdf = self.pdf(wi, wo, variant)?;
        Ok(Some(Sample { wo, pdf }))
    }
}

/// The sampling CDFs of decoded slice values (`[variant][channel][θo][Δφ]`): per variant the
/// marginal CDF over θo rows, the conditional CDFs over Δφ, and the normaliser Σ p·ΔΩ.
pub fn sampling_cdfs(d: &Directory, values: &[f32]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, Vec<f64>) {
    let (nv, nc) = (d.variants.len(), d.channels.len());
    let bins = d.bins();
    let (mut cdf_theta, mut cdf_phi, mut norm) = (Vec::new(), Vec::new(), Vec::new());
    for v in 0..nv {
        let pdf = |b: usize| -> f64 {
            (0..nc)
                .map(|k| values[(v * nc + k) * bins + b] as f64)
                .sum::<f64>()
                / nc as f64
        };
        let mut ct = vec![0.0; d.n_theta];
        let mut cp = vec![0.0; bins];
        let mut acc = 0.0;
        for it in 0..d.n_theta {
            let dw = solid_angle(d.res_deg, it);
            let mut row = 0.0;
            for j in 0..d.n_phi {
                row += pdf(it * d.n_phi + j);
                cp[it * d.n_phi + j] = row;
            }
            if row > 0.0 {
                for j in 0..d.n_phi {
                    cp[it * d.n_phi + j] /= row;
                }
                cp[it * d.n_phi + d.n_phi - 1] = 1.0;
            }
            acc += row * dw;
            ct[it] = acc;
        }
        if acc > 0.0 {
            for x in &mut ct {
                *x /= acc;
            }
            ct[d.n_theta - 1] = 1.0;
        }
        cdf_theta.push(ct);
        cdf_phi.push(cp);
        norm.push(acc);
    }
    (cdf_theta, cdf_phi, norm)
}

/// Index of the first CDF entry above `u` and the remainder of `u` rescaled to [0, 1).
fn pick(cdf: &[f64], u: f64) -> (usize, f64) {
    let i = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
    // Skip zero-width entries (empty bins) so the chosen bin has mass.
    let lo = if i == 0 { 0.0 } else { cdf[i - 1] };
    let w = cdf[i] - lo;
    let r = if w > 0.0 {
        ((u - lo) / w).clamp(0.0, 1.0 - 1e-12)
    } else {
        0.5
    };
    (i, r)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `wi_map` bits are the ones FORMAT.md documents (every other reader decodes by it):
    /// 2³¹ flips θo, 2³⁰ flips Δφ, the 30 bits below hold the stored index.
    #[test]
    fn wi_map_flags_are_the_documented_bits() {
        let doc = include_str!("../FORMAT.md");
        assert!(doc.contains("stored index | 2³¹ if θo changes sign | 2³⁰ if Δφ changes sign"));
        assert_eq!(FLIP_THETA, 2u32.pow(31));
        assert_eq!(FLIP_DPHI, 2u32.pow(30));
        assert_eq!(INDEX_MASK, 2u32.pow(30) - 1);
    }

    /// A small file: res 30°, 2 stored ωi, 1 variant, 2 channels, z-mirror map.
    fn small(dtype: Precision) -> (Vec<u8>, Vec<Vec<f64>>) {
        small_with_total(dtype, 1.0)
    }

    /// [`small`] with Σ f̂·ΔΩ = `total` in every slice and channel instead of 1.
    fn small_with_total(dtype: Precision, total: f64) -> (Vec<u8>, Vec<Vec<f64>>) {
        small_in(dtype, total, false)
    }

    /// [`small_with_total`], its slices pushed last first when `reversed`.
    fn small_in(dtype: Precision, total: f64, reversed: bool) -> (Vec<u8>, Vec<Vec<f64>>) {
        let res = 30.0;
        let (nt, np) = (6, 12);
        let wi_deg = vec![[-75.0, 15.0], [-15.0, 15.0]];
        let mut wi_map = vec![0u32; nt * np];
        for it in 0..nt {
            let (s, flip) = match it {
                0 | 1 => (0, false),
                2 => (1, false),
                3 => (1, true),
                _ => (0, true),
            };
            for j in 0..np {
                wi_map[it * np + j] = s | if flip { FLIP_THETA } else { 0 };
            }
        }
        let dir = Directory {
            kind: KIND.into(),
            res_deg: res,
            n_theta: nt,
            n_phi: np,
            wi_deg,
            wi_map,
            variants: vec!["undyed".into()],
            channels: vec!["R".into(), "G".into()],
            dtype,
            keep_bits: dtype.mantissa_bits(),
            scale: vec![],
            albedo: vec![1.0, 0.9, 0.8, 0.7],
            albedo_se: vec![0.0; 4],
            area_um: (0..np).map(|j| 10.0 + j as f64).collect(),
            chunks: vec![],
            metadata: serde_json::json!({"test": true}),
        };
        let mut w = Writer::new(dir, 3);
        let mut slices = Vec::new();
        for s in 0..2 {
            let mut v = vec![0.0; 2 * nt * np];
            for k in 0..2 {
                let mut tot = 0.0;
                for b in 0..nt * np {
                    let x = ((b * 7 + s * 3 + k) % 11) as f64;
                    v[k * nt * np + b] = x;
                    tot += x * solid_angle(res, b / np);
                }
                for b in 0..nt * np {
                    v[k * nt * np + b] *= total / tot;
                }
            }
            slices.push(v);
        }
        for s in 0..2 {
            let i = if reversed { 1 - s } else { s };
            w.push_within_at(i, &slices[i], None).unwrap();
        }
        (w.finish().unwrap(), slices)
    }

    /// Slices pushed out of order make the same file as in order; a missing slice, one pushed
    /// twice or one beyond the stored directions is an error.
    #[test]
    fn slices_may_arrive_in_any_order() {
        for dtype in [Precision::F16, Precision::F32] {
            assert_eq!(small_in(dtype, 1.0, true).0, small(dtype).0);
        }
        let (bytes, slices) = small(Precision::F16);
        let t = Bcsdf::from_bytes(bytes).unwrap();
        let dir = Directory {
            chunks: vec![],
            scale: vec![],
            ..t.dir.clone()
        };
        let mut w = Writer::new(dir.clone(), 3);
        w.push_within_at(1, &slices[1], None).unwrap();
        assert!(w.push_within_at(1, &slices[1], None).is_err());
        assert!(w.push_within_at(2, &slices[0], None).is_err());
        assert_eq!(w.frame_bytes().count(), 1);
        assert!(w.finish().is_err());
        let mut w = Writer::new(dir, 3);
        w.push_within_at(0, &slices[0], None).unwrap();
        assert!(w.push_within_at(0, &slices[0], None).is_err());
    }

    /// Directions along every axis (and any length) are valid; zero, infinite and NaN
    /// components are refused.
    #[test]
    fn directions_are_checked() {
        for w in [
            [1.0, 0.0, 0.0],
            [0.0, -2.0, 0.0],
            [0.0, 0.0, 1e-3],
            [0.3, -0.4, 0.5],
        ] {
            assert!(check_dir(w).is_ok(), "{w:?}");
        }
        for w in [
            [0.0; 3],
            [f64::INFINITY, 0.0, 0.0],
            [0.0, f64::NAN, 1.0],
            [1e200, 1e200, 0.0],
        ] {
            assert!(check_dir(w).is_err(), "{w:?}");
        }
    }

    /// Sampling draws ωo with the tabulated density: the (θo, Δφ) bins of 40,000 samples
    /// against each bin's p·ΔΩ from `pdf` at its centre (χ², bound dof + 5·√(2·dof)), empty
    /// bins never drawn, for a stored ωi, its z-mirror and an ωi along the x axis.
    #[test]
    fn samples_follow_the_tabulated_density() {
        // Not normalised to 1 (the CDFs must normalise), channels of different shapes.
        let (bytes, _) = small_with_total(Precision::F32, 0.37);
        let f = Bcsdf::from_bytes(bytes).unwrap();
        let g = f.dir.grid();
        let (nt, np) = (f.dir.n_theta, f.dir.n_phi);
        let res = f.dir.res_deg.to_radians();
        let mut state = 12_345u64;
        let mut u = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for wi in [
            direction((-80f64).to_radians(), 20f64.to_radians()),
            direction(80f64.to_radians(), 20f64.to_radians()),
            [1.0, 0.0, 0.0],
        ] {
            let phi_i = angles(wi).1;
            let n = 40_000;
            let mut count = vec![0u32; nt * np];
            // Within its bin a sample is uniform in solid angle: sin θo and Δφ uniform.
            let mut within = [0u32; 16];
            for _ in 0..n {
                let s = f.sample(wi, 0, u(), u()).unwrap().unwrap();
                assert!(s.pdf > 0.0);
                let (t, p) = angles(s.wo);
                let (it, jp) = g.cell(t, p - phi_i);
                count[it * np + jp] += 1;
                let t0 = g.theta_lower_rad(it);
                let a = (t.sin() - t0.sin()) / ((t0 + res).sin() - t0.sin());
                let dphi = (p - phi_i + PI).rem_euclid(2.0 * PI) - PI;
                let b = (dphi + PI) / res - jp as f64;
                within[((a * 4.0) as usize).min(3) * 4 + ((b * 4.0) as usize).min(3)] += 1;
            }
            let e = n as f64 / 16.0;
            let chi2_within: f64 = within.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
            assert!(
                chi2_within < 15.0 + 5.0 * 30f64.sqrt(),
                "within bins: {within:?}"
            );
            let (mut chi2, mut dof, mut total) = (0.0, 0usize, 0.0);
            for it in 0..nt {
                for jp in 0..np {
                    let wo = direction(
                        g.theta_lower_rad(it) + 0.5 * res,
                        phi_i - PI + (jp as f64 + 0.5) * res,
                    );
                    let p = f.pdf(wi, wo, 0).unwrap() * g.solid_angle(it);
                    total += p;
                    let (c, e) = (count[it * np + jp] as f64, p * n as f64);
                    if e == 0.0 {
                        assert_eq!(c, 0.0, "an empty bin was drawn");
                        continue;
                    }
                    chi2 += (c - e).powi(2) / e;
                    dof += 1;
                }
            }
            assert!((total - 1.0).abs() < 1e-6, "Σ p·ΔΩ = {total}");
            let k = (dof - 1) as f64;
            assert!(
                chi2 < k + 5.0 * (2.0 * k).sqrt(),
                "χ² {chi2} over {dof} bins"
            );
        }
    }

    #[test]
    fn roundtrip_eval_albedo_area_and_flags() {
        let (bytes, slices) = small(Precision::F32);
        let f = Bcsdf::from_bytes(bytes).unwrap();
        // θi = −80°, φi = 20° → stored 0; θi = +80° → stored 0 with θo mirrored.
        let wi = direction((-80f64).to_radians(), 20f64.to_radians());
        let wo = direction((35f64).to_radians(), (20f64 + 100.0).to_radians());
        let got = f.eval_normalised(wi, wo, 0).unwrap();
        // θo = 35° → row 4; Δφ = 100° → column 9.
        let b = 4 * 12 + 9;
        assert!((got[0] as f64 - slices[0][b]).abs() < 1e-7 * slices[0][b].max(1.0));
        let wi_m = direction((80f64).to_radians(), 20f64.to_radians());
        let wo_m = direction((-35f64).to_radians(), (20f64 + 100.0).to_radians());
        assert_eq!(f.eval_normalised(wi_m, wo_m, 0).unwrap(), got);
        assert_eq!(f.albedo(wi, 0).unwrap(), vec![1.0, 0.9]);
        let e = f.eval(wi, wo, 0).unwrap();
        assert!((e[1] - 0.9 * got[1]).abs() < 1e-6);
        assert_eq!(f.area_um(direction(0.0, (-170f64).to_radians())), 10.0);
        assert!(f.eval(wi, wo, 1).is_err());
    }

    #[test]
    fn sampler_pdf_matches_density_and_integrates_to_one() {
        let (bytes, _) = small(Precision::F16);
        let f = Bcsdf::from_bytes(bytes).unwrap();
        let wi = direction((-20f64).to_radians(), 50f64.to_radians());
        let mut total = 0.0;
        let g = f.dir.grid();
        for it in 0..6 {
            for j in 0..12 {
                let t = g.theta_centre_deg(it).to_radians();
                let p = 50f64.to_radians() + g.phi_centre_deg(j).to_radians();
                total += f.pdf(wi, direction(t, p), 0).unwrap() * solid_angle(30.0, it);
            }
        }
        assert!((total - 1.0).abs() < 1e-9, "{total}");
        for k in 0..200 {
            let u1 = (k as f64 + 0.5) / 200.0;
            let u2 = ((k * 37) % 200) as f64 / 200.0;
            let s = f.sample(wi, 0, u1, u2).unwrap().unwrap();
            assert!((s.pdf - f.pdf(wi, s.wo, 0).unwrap()).abs() < 1e-12);
            assert!(s.pdf > 0.0);
        }
    }

    #[test]
    fn corruption_and_truncation_are_errors() {
        let (mut bytes, _) = small(Precision::F16);
        let n = bytes.len();
        assert!(Bcsdf::from_bytes(bytes[..n - 1].to_vec()).is_err());
        bytes[n - 5] ^= 0xFF;
        let f = Bcsdf::from_bytes(bytes);
        // Either zstd or the CRC rejects the damaged chunk.
        let f = f.unwrap();
        assert!(f.decode(1).is_err());
    }

    /// Round-to-nearest, ties to even, of a positive normal `x` to `keep` mantissa bits, in f64
    /// arithmetic (independent of the bit tricks): the quantum is 2^(e − keep) for 2^e ≤ x.
    fn nearest_even(x: f64, keep: i32) -> f64 {
        let e = x.log2().floor() as i32;
        let q = 2f64.powi(e - keep);
        let t = x / q;
        let f = t.floor();
        let r = if t - f > 0.5 || (t - f == 0.5 && f % 2.0 == 1.0) {
            f + 1.0
        } else {
            f
        };
        r * q
    }

    /// Bit rounding in f32 and f16 equals round-to-nearest-even at the kept bits, for every
    /// kept-bit count, on random values and on exact ties; `encode_slice` stores what it says
    /// a reader decodes, byte-shuffled, scaled by a power of two that puts each part's
    /// maximum in [½, 1).
    #[test]
    fn bitround_is_round_to_nearest_even() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for keep in 1..23u32 {
            for k in 0..2_000u32 {
                let x = if k % 2 == 0 {
                    f32::from_bits(0x3000_0000 + (next() as u32 % 0x1800_0000))
                } else {
                    // An exact tie: the dropped bits are 1000…0.
                    let m = (next() as u32 & 0x007F_FFFF) >> (23 - keep) << (23 - keep);
                    f32::from_bits(0x3F80_0000 | m | 1 << (22 - keep))
                };
                let want = nearest_even(x as f64, keep as i32) as f32;
                assert_eq!(round_f32(x, keep), want, "f32 {x:e}, {keep} bits");
            }
        }
        for keep in 1..10u32 {
            for h in (0x0400u16..0x7C00).step_by(7) {
                let x = half::f16::from_bits(h).to_f64();
                let want = half::f16::from_f64(nearest_even(x, keep as i32));
                assert_eq!(
                    round_f16_bits(h, keep),
                    want.to_bits(),
                    "f16 {x:e}, {keep} bits"
                );
            }
        }
        let values: Vec<f64> = (0..64).map(|i| ((i * 37) % 29) as f64 * 0.013).collect();
        for dtype in [Precision::F16, Precision::F32] {
            let (scales, raw, decoded) = encode_slice(&values, 2, dtype, 6, None);
            for (k, part) in values.chunks(32).enumerate() {
                let top = part.iter().copied().fold(0.0, f64::max) / scales[k] as f64;
                assert!((0.5..1.0).contains(&top), "{top}");
                assert_eq!(scales[k].to_bits() & 0x007F_FFFF, 0, "a power of two");
            }
            assert_eq!(decode_values(&raw, dtype, &scales, 32), decoded);
            for (x, d) in values.iter().zip(&decoded) {
                assert!((*d as f64 - x).abs() <= 2f64.powi(-7) * x + 1e-9, "{x} {d}");
            }
        }
        // An all-zero part (a fully absorbed channel) stores zeros with scale 1, not 0/0.
        let (scales, _, decoded) = encode_slice(&[0.0; 8], 1, Precision::F16, 6, None);
        assert_eq!((scales, decoded), (vec![1.0], vec![0.0; 8]));
    }

    /// The scale puts the maximum in [½, 1) at and around powers of two, and is 1 for
    /// parts without a positive finite maximum.
    #[test]
    fn pow2_scale_puts_the_maximum_in_half_to_one() {
        for e in -60..60 {
            let p = 2f64.powi(e);
            for max in [p, p * (1.0 - 1e-15), p * (1.0 + 1e-15), p * 1.5] {
                let top = max / pow2_scale(max) as f64;
                assert!((0.5..1.0).contains(&top), "{max:e}: {top}");
            }
        }
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(pow2_scale(bad), 1.0);
        }
    }

    /// Subnormal f16 values (below 6.1e-5 to 1.2e-4 of a slice's maximum) keep `keep` bits after their
    /// own leading one, like normal values: relative error ≤ 2^−(keep+1).
    #[test]
    fn bitround_of_subnormals_keeps_relative_precision() {
        for keep in 0..10u32 {
            for h in 1u16..0x0400 {
                let x = half::f16::from_bits(h).to_f64();
                let r = half::f16::from_bits(round_f16_bits(h, keep)).to_f64();
                assert!(
                    (r - x).abs() <= 2f64.powi(-(keep as i32 + 1)) * x,
                    "f16 subnormal {x:e}, {keep} bits: {r:e}"
                );
            }
        }
        for x in [1e-40f32, 3.3e-42, 7e-45] {
            let r = round_f32(x, 3);
            assert!(((r - x) / x).abs() <= 2f32.powi(-4), "{x:e} {r:e}");
        }
    }

    /// The bit count for a relative tolerance is the smallest whose half-unit is within it.
    #[test]
    fn bits_for_rel_error_is_the_fewest_within_tolerance() {
        assert_eq!(bits_for_rel_error(0.0), u32::MAX);
        assert_eq!(bits_for_rel_error(f64::NAN), u32::MAX);
        assert_eq!(bits_for_rel_error(f64::INFINITY), 0);
        assert_eq!(bits_for_rel_error(0.5), 0);
        assert_eq!(bits_for_rel_error(2f64.powi(-5)), 4);
        for i in 1..2000 {
            let t = 0.7 * 0.993f64.powi(i);
            let k = bits_for_rel_error(t);
            assert!(2f64.powi(-(k as i32 + 1)) <= t, "{t}: {k}");
            assert!(
                k == 0 || 2f64.powi(-(k as i32)) > t,
                "{t}: {k} is not the fewest"
            );
        }
    }

    /// A noisy slice: a smooth density times (1 + relative noise s_b per bin).
    fn noisy_slice(n_vc: usize, bins: usize) -> (Vec<f64>, Vec<f64>) {
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut u = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let rel_se: Vec<f64> = (0..bins)
            .map(|b| 0.02 + 0.5 * (b % 7) as f64 / 7.0)
            .collect();
        let mut values = vec![0.0; n_vc * bins];
        for k in 0..n_vc {
            for b in 0..bins {
                let smooth = (-((b as f64 - 40.0) / 30.0).powi(2)).exp() * (1.0 + k as f64);
                // Box-Muller: a normal deviate of standard deviation s_b.
                let z = (-2.0 * u().max(1e-300).ln()).sqrt() * (2.0 * PI * u()).cos();
                values[k * bins + b] = (smooth * (1.0 + rel_se[b] * z)).max(0.0);
            }
        }
        values[5] = 0.0; // an empty bin
        (values, rel_se)
    }

    /// Rounding to a fraction q of each bin's standard error: every value moves by at most
    /// q·SE from what `keep_bits` alone stores, bins with no tolerance are untouched, the RMS
    /// relative error is far below the noise, and the compressed slice shrinks.
    #[test]
    fn rounding_to_the_noise_stays_within_its_bound_and_compresses() {
        let (n_vc, bins) = (6, 180);
        let (values, rel_se) = noisy_slice(n_vc, bins);
        let q = 0.25;
        let mut tol: Vec<f64> = rel_se.iter().map(|s| q * s).collect();
        tol[11] = 0.0; // no standard error: full precision
        for dtype in [Precision::F16, Precision::F32] {
            for keep in [dtype.mantissa_bits(), 7] {
                let (s0, raw0, plain) = encode_slice(&values, n_vc, dtype, keep, None);
                let (s1, raw1, quant) = encode_slice(&values, n_vc, dtype, keep, Some(&tol));
                assert_eq!(s0, s1);
                assert_eq!(decode_values(&raw1, dtype, &s1, bins), quant);
                let (mut e2, mut noise2, mut n) = (0.0, 0.0, 0.0);
                for (i, (&p, &d)) in plain.iter().zip(&quant).enumerate() {
                    let b = i % bins;
                    let (p, d) = (p as f64, d as f64);
                    // f32 products with the scale: a few ulps of slack.
                    let bound = tol[b] * p + 4.0 * f64::from(f32::EPSILON) * p;
                    assert!(
                        (d - p).abs() <= bound,
                        "{dtype:?} keep {keep} value {i}: {p} → {d}"
                    );
                    if tol[b] == 0.0 {
                        assert_eq!(d, p, "bin {b} has no tolerance");
                    }
                    if p > 0.0 {
                        e2 += ((d - p) / p).powi(2);
                        noise2 += rel_se[b].powi(2);
                        n += 1.0;
                    }
                }
                let (rms, noise) = ((e2 / n).sqrt(), (noise2 / n).sqrt());
                assert!(rms < 0.25 * noise, "{dtype:?}: RMS {rms} vs noise {noise}");
                let z = |r: &[u8]| zstd::bulk::compress(r, 9).unwrap().len();
                let (a, b) = (z(&raw0), z(&raw1));
                assert!(b < a, "{dtype:?} keep {keep}: {b} bytes rounded, {a} not");
            }
        }
    }

    #[test]
    fn bitround_keeps_the_requested_precision() {
        for &x in &[1.0f32, 0.123_456_7, 3.3e-5, 47_000.0] {
            let r = round_f32(x, 7);
            assert!(((r - x) / x).abs() <= 2f32.powi(-8), "{x} {r}");
            assert_eq!(r.to_bits() & ((1 << 16) - 1), 0);
        }
    }
}
