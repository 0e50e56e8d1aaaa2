//! Native tables (`.bkt`): named n-dimensional arrays plus JSON metadata, zstd-compressed.
//!
//! The layout is raw little-endian data in zstd frames behind a JSON directory, so a file is
//! readable without Rust (numpy + `zstandard`; see `validation/bkt.py`). `formats/FORMAT.md`,
//! section "Native tables (.bkt)", documents it byte by byte; in short:
//!
//! ```text
//! offset  size  field
//!      0     8  magic b"BAKERTBL"
//!      8     4  format version, u32 LE = 1
//!     12     4  flags, u32 LE = 0 (no flag is defined in version 1)
//!     16     8  directory_compressed_len, u64 LE
//!     24     8  directory_raw_len, u64 LE
//!     32     8  payload_len, u64 LE
//!     40     4  directory_crc32, u32 LE (CRC-32 of the decompressed directory)
//!     44     4  reserved, u32 LE = 0
//!     48     …  directory: one zstd frame holding UTF-8 JSON
//!      …     …  payload: one zstd frame per array, in directory order, back to back
//! ```
//!
//! The directory is `{"kind": …, "metadata": …, "arrays": [{"name", "dtype", "shape",
//! "attrs", "offset", "compressed_bytes", "raw_bytes", "crc32"}, …]}`; `offset` counts from
//! the start of the payload and each frame decompresses to the array's elements, row-major,
//! little-endian. Checksums are CRC-32 (IEEE, as `zlib.crc32`) of the decompressed bytes.
//!
//! Writing is deterministic: the same [`TableFile`] and zstd level give identical bytes (for
//! a given zstd library version — the frames are what libzstd produces).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// The first 8 bytes of every file.
pub const MAGIC: [u8; 8] = *b"BAKERTBL";
/// Current version of the layout.
pub const VERSION: u32 = 1;
/// Size of the fixed header in bytes.
pub const HEADER_LEN: usize = 48;
/// Usual file extension (without the dot).
pub const EXTENSION: &str = "bkt";
/// A reasonable zstd level for [`TableFile::to_bytes`] (zstd accepts its own range; 0 means
/// zstd's default, 3).
pub const DEFAULT_ZSTD_LEVEL: i32 = 9;

/// Element type of an array. Its code is the `dtype` string of the directory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DType {
    /// `"f64"`: IEEE-754 binary64 (numpy `<f8`).
    F64,
    /// `"f32"`: IEEE-754 binary32 (numpy `<f4`).
    F32,
    /// `"u32"`: unsigned 32-bit integer (numpy `<u4`).
    U32,
    /// `"u64"`: unsigned 64-bit integer (numpy `<u8`).
    U64,
}

impl DType {
    /// Every type, in code order.
    pub const ALL: [DType; 4] = [DType::F64, DType::F32, DType::U32, DType::U64];

    /// The code written in the directory: `"f64"`, `"f32"`, `"u32"` or `"u64"`.
    pub fn code(self) -> &'static str {
        match self {
            DType::F64 => "f64",
            DType::F32 => "f32",
            DType::U32 => "u32",
            DType::U64 => "u64",
        }
    }

    /// Inverse of [`DType::code`].
    pub fn from_code(code: &str) -> Option<DType> {
        DType::ALL.into_iter().find(|d| d.code() == code)
    }

    /// Bytes per element.
    pub fn size(self) -> usize {
        match self {
            DType::F64 | DType::U64 => 8,
            DType::F32 | DType::U32 => 4,
        }
    }
}

impl fmt::Display for DType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.code())
    }
}

/// The elements of an array, flat, row-major.
#[derive(Debug, Clone, PartialEq)]
pub enum Data {
    F64(Vec<f64>),
    F32(Vec<f32>),
    U32(Vec<u32>),
    U64(Vec<u64>),
}

impl Data {
    pub fn dtype(&self) -> DType {
        match self {
            Data::F64(_) => DType::F64,
            Data::F32(_) => DType::F32,
            Data::U32(_) => DType::U32,
            Data::U64(_) => DType::U64,
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        match self {
            Data::F64(v) => v.len(),
            Data::F32(v) => v.len(),
            Data::U32(v) => v.len(),
            Data::U64(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The elements as little-endian bytes (what a payload frame decompresses to).
    pub fn to_le_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.len() * self.dtype().size());
        match self {
            Data::F64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Data::F32(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Data::U32(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Data::U64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        }
        out
    }

    /// Inverse of [`Data::to_le_bytes`]; `None` when the length is not a multiple of the
    /// element size.
    pub fn from_le_bytes(dtype: DType, bytes: &[u8]) -> Option<Data> {
        if bytes.len() % dtype.size() != 0 {
            return None;
        }
        Some(match dtype {
            DType::F64 => Data::F64(
                bytes
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                    .collect(),
            ),
            DType::F32 => Data::F32(
                bytes
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
                    .collect(),
            ),
            DType::U32 => Data::U32(
                bytes
                    .chunks_exact(4)
                    .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
                    .collect(),
            ),
            DType::U64 => Data::U64(
                bytes
                    .chunks_exact(8)
                    .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
                    .collect(),
            ),
        })
    }
}

impl From<Vec<f64>> for Data {
    fn from(v: Vec<f64>) -> Self {
        Data::F64(v)
    }
}

impl From<Vec<f32>> for Data {
    fn from(v: Vec<f32>) -> Self {
        Data::F32(v)
    }
}

impl From<Vec<u32>> for Data {
    fn from(v: Vec<u32>) -> Self {
        Data::U32(v)
    }
}

impl From<Vec<u64>> for Data {
    fn from(v: Vec<u64>) -> Self {
        Data::U64(v)
    }
}

/// One named n-dimensional array, row-major (C order).
#[derive(Debug, Clone, PartialEq)]
pub struct Array {
    /// A '/'-separated path, e.g. `female_forearm_typeI_age30_xi0/rd_rgb_per_mm2`: non-empty
    /// segments, no `.` or `..` segment, no control characters; unique within a file.
    pub name: String,
    /// Extent of each dimension; `[]` is a scalar (one element).
    pub shape: Vec<u64>,
    pub data: Data,
    /// Free-form string attributes, e.g. `units` = `mm^-2`.
    pub attrs: BTreeMap<String, String>,
}

impl Array {
    /// An array without attributes; checks the name and that the shape holds `data.len()`
    /// elements.
    pub fn new(
        name: impl Into<String>,
        shape: Vec<u64>,
        data: impl Into<Data>,
    ) -> Result<Array, TableError> {
        let a = Array {
            name: name.into(),
            shape,
            data: data.into(),
            attrs: BTreeMap::new(),
        };
        a.check().map_err(TableError::Invalid)?;
        Ok(a)
    }

    pub fn new_f64(
        name: impl Into<String>,
        shape: Vec<u64>,
        data: Vec<f64>,
    ) -> Result<Array, TableError> {
        Array::new(name, shape, data)
    }

    pub fn new_f32(
        name: impl Into<String>,
        shape: Vec<u64>,
        data: Vec<f32>,
    ) -> Result<Array, TableError> {
        Array::new(name, shape, data)
    }

    pub fn new_u32(
        name: impl Into<String>,
        shape: Vec<u64>,
        data: Vec<u32>,
    ) -> Result<Array, TableError> {
        Array::new(name, shape, data)
    }

    pub fn new_u64(
        name: impl Into<String>,
        shape: Vec<u64>,
        data: Vec<u64>,
    ) -> Result<Array, TableError> {
        Array::new(name, shape, data)
    }

    /// Adds (or replaces) an attribute.
    pub fn with_attr(mut self, key: impl Into<String>, value: impl Into<String>) -> Array {
        self.attrs.insert(key.into(), value.into());
        self
    }

    pub fn attr(&self, key: &str) -> Option<&str> {
        self.attrs.get(key).map(String::as_str)
    }

    pub fn dtype(&self) -> DType {
        self.data.dtype()
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    pub fn as_f64(&self) -> Option<&[f64]> {
        match &self.data {
            Data::F64(v) => Some(v),
            _ => None,
        }
    }

    pub fn as_f32(&self) -> Option<&[f32]> {
        match &self.data {
            Data::F32(v) => Some(v),
            _ => None,
        }
    }

    pub fn as_u32(&self) -> Option<&[u32]> {
        match &self.data {
            Data::U32(v) => Some(v),
            _ => None,
        }
    }

    pub fn as_u64(&self) -> Option<&[u64]> {
        match &self.data {
            Data::U64(v) => Some(v),
            _ => None,
        }
    }

    /// Name rules and shape product == element count.
    fn check(&self) -> Result<(), String> {
        check_name(&self.name)?;
        match element_count(&self.shape) {
            Some(n) if n == self.data.len() as u64 => Ok(()),
            Some(n) => Err(format!(
                "array {:?}: shape {:?} holds {n} elements but the data has {}",
                self.name,
                self.shape,
                self.data.len()
            )),
            None => Err(format!(
                "array {:?}: the element count of shape {:?} overflows u64",
                self.name, self.shape
            )),
        }
    }
}

/// A table file: a kind (what the arrays are, e.g. `skin_profiles`), free JSON metadata and
/// the arrays, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct TableFile {
    pub kind: String,
    pub metadata: serde_json::Value,
    pub arrays: Vec<Array>,
}

/// Why a table could not be read or written.
#[derive(Debug)]
pub enum TableError {
    /// Reading or writing a file failed.
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The bytes are not a valid table (bad magic, truncated, inconsistent directory…).
    Format(String),
    /// The file's format version is not one this reader knows.
    UnsupportedVersion(u32),
    /// Stored and computed CRC-32 differ: the file is corrupted.
    Checksum {
        /// `directory` or `array "name"`.
        part: String,
        stored: u32,
        computed: u32,
    },
    /// The content cannot be written (bad name, shape mismatch, duplicate, bad zstd level).
    Invalid(String),
    /// zstd failed while compressing.
    Compression(String),
}

impl std::error::Error for TableError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            TableError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TableError::Io { path, source } => write!(f, "{}: {source}", path.display()),
            TableError::Format(m) => write!(f, "not a valid baker table: {m}"),
            TableError::UnsupportedVersion(v) => write!(
                f,
                "table format version {v} is not supported (this reader: {VERSION})"
            ),
            TableError::Checksum {
                part,
                stored,
                computed,
            } => write!(
                f,
                "corrupted table: CRC-32 of {part} is {computed:08x}, the file stores \
                 {stored:08x}"
            ),
            TableError::Invalid(m) => write!(f, "invalid table content: {m}"),
            TableError::Compression(m) => write!(f, "zstd compression failed: {m}"),
        }
    }
}

/// Directory entry as written.
#[derive(Serialize)]
struct EntryOut<'a> {
    name: &'a str,
    dtype: &'static str,
    shape: &'a [u64],
    attrs: &'a BTreeMap<String, String>,
    offset: u64,
    compressed_bytes: u64,
    raw_bytes: u64,
    crc32: u32,
}

#[derive(Serialize)]
struct DirectoryOut<'a> {
    kind: &'a str,
    metadata: &'a serde_json::Value,
    arrays: Vec<EntryOut<'a>>,
}

/// Directory entry as read (unknown keys are ignored).
#[derive(Deserialize)]
struct EntryIn {
    name: String,
    dtype: String,
    shape: Vec<u64>,
    #[serde(default)]
    attrs: BTreeMap<String, String>,
    offset: u64,
    compressed_bytes: u64,
    raw_bytes: u64,
    crc32: u32,
}

#[derive(Deserialize)]
struct DirectoryIn {
    kind: String,
    metadata: serde_json::Value,
    arrays: Vec<EntryIn>,
}

impl TableFile {
    /// An empty table.
    pub fn new(kind: impl Into<String>, metadata: serde_json::Value) -> TableFile {
        TableFile {
            kind: kind.into(),
            metadata,
            arrays: Vec::new(),
        }
    }

    /// Appends an array; refuses a name already present.
    pub fn push(&mut self, array: Array) -> Result<(), TableError> {
        array.check().map_err(TableError::Invalid)?;
        if self.get(&array.name).is_some() {
            return Err(TableError::Invalid(format!(
                "duplicate array name {:?}",
                array.name
            )));
        }
        self.arrays.push(array);
        Ok(())
    }

    /// The array called `name`.
    pub fn get(&self, name: &str) -> Option<&Array> {
        self.arrays.iter().find(|a| a.name == name)
    }

    /// Array names, in file order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.arrays.iter().map(|a| a.name.as_str())
    }

    /// What [`TableFile::to_bytes`] requires: non-empty kind, valid and unique names,
    /// shapes matching the data.
    pub fn check(&self) -> Result<(), TableError> {
        if self.kind.is_empty() {
            return Err(TableError::Invalid("the table kind is empty".into()));
        }
        let mut seen = BTreeSet::new();
        for a in &self.arrays {
            a.check().map_err(TableError::Invalid)?;
            if !seen.insert(a.name.as_str()) {
                return Err(TableError::Invalid(format!(
                    "duplicate array name {:?}",
                    a.name
                )));
            }
        }
        Ok(())
    }

    /// Serializes the table (layout in the module documentation). `zstd_level` is any level
    /// zstd accepts (`0` = zstd's default; see [`DEFAULT_ZSTD_LEVEL`]). Deterministic.
    pub fn to_bytes(&self, zstd_level: i32) -> Result<Vec<u8>, TableError> {
        self.check()?;
        let levels = zstd::compression_level_range();
        if !levels.contains(&zstd_level) {
            return Err(TableError::Invalid(format!(
                "zstd level {zstd_level} is outside {}..={}",
                levels.start(),
                levels.end()
            )));
        }
        let mut compressor = new_compressor(zstd_level)?;
        let mut frames = Vec::with_capacity(self.arrays.len());
        let mut entries = Vec::with_capacity(self.arrays.len());
        let mut offset = 0u64;
        for a in &self.arrays {
            let raw = a.data.to_le_bytes();
            let frame = compress(&mut compressor, &raw, &a.name)?;
            entries.push(EntryOut {
                name: &a.name,
                dtype: a.dtype().code(),
                shape: &a.shape,
                attrs: &a.attrs,
                offset,
                compressed_bytes: frame.len() as u64,
                raw_bytes: raw.len() as u64,
                crc32: crc32(&raw),
            });
            offset += frame.len() as u64;
            frames.push(frame);
        }
        let directory = serde_json::to_vec(&DirectoryOut {
            kind: &self.kind,
            metadata: &self.metadata,
            arrays: entries,
        })
        .map_err(|e| TableError::Invalid(format!("metadata cannot be serialized: {e}")))?;
        let dir_frame = compress(&mut compressor, &directory, "the directory")?;

        let mut out = Vec::with_capacity(HEADER_LEN + dir_frame.len() + offset as usize);
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&(dir_frame.len() as u64).to_le_bytes());
        out.extend_from_slice(&(directory.len() as u64).to_le_bytes());
        out.extend_from_slice(&offset.to_le_bytes());
        out.extend_from_slice(&crc32(&directory).to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        debug_assert_eq!(out.len(), HEADER_LEN);
        out.extend_from_slice(&dir_frame);
        for f in &frames {
            out.extend_from_slice(f);
        }
        Ok(out)
    }

    /// Parses and fully validates a table: header, directory, bounds, shapes, checksums.
    /// Never panics on malformed input; allocates at most what the frames actually decode
    /// to (see [`TableIndex`]).
    pub fn from_bytes(b: &[u8]) -> Result<TableFile, TableError> {
        let index = TableIndex::from_bytes(b.to_vec())?;
        let arrays = (0..index.entries.len())
            .map(|i| index.read_at(i))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(TableFile {
            kind: index.kind,
            metadata: index.metadata,
            arrays,
        })
    }

    /// Reads and validates a file.
    pub fn read(path: impl AsRef<Path>) -> Result<TableFile, TableError> {
        let path = path.as_ref();
        let bytes = read_file(path)?;
        TableFile::from_bytes(&bytes).map_err(|e| match e {
            TableError::Format(m) => TableError::Format(format!("{}: {m}", path.display())),
            other => other,
        })
    }

    /// Writes [`TableFile::to_bytes`] to `path`.
    pub fn write(&self, path: impl AsRef<Path>, zstd_level: i32) -> Result<(), TableError> {
        let path = path.as_ref();
        let bytes = self.to_bytes(zstd_level)?;
        std::fs::write(path, bytes).map_err(|source| TableError::Io {
            path: path.to_path_buf(),
            source,
        })
    }
}

/// Product of the extents (`1` for a scalar), `None` on overflow.
fn element_count(shape: &[u64]) -> Option<u64> {
    shape.iter().try_fold(1u64, |acc, &d| acc.checked_mul(d))
}

fn check_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("empty array name".into());
    }
    if name.chars().any(char::is_control) {
        return Err(format!("array name {name:?} contains control characters"));
    }
    if name
        .split('/')
        .any(|s| s.is_empty() || s == "." || s == "..")
    {
        return Err(format!(
            "array name {name:?}: '/'-separated segments must be non-empty and not . or .."
        ));
    }
    Ok(())
}

fn new_compressor(level: i32) -> Result<zstd::bulk::Compressor<'static>, TableError> {
    use zstd::zstd_safe::CParameter;
    let err = |e: std::io::Error| TableError::Compression(e.to_string());
    let mut c = zstd::bulk::Compressor::new(level).map_err(err)?;
    // Pinned rather than left to defaults: frames record their size, carry no zstd checksum
    // (the directory holds CRC-32s) and no dictionary id.
    c.set_parameter(CParameter::ContentSizeFlag(true))
        .map_err(err)?;
    c.set_parameter(CParameter::ChecksumFlag(false))
        .map_err(err)?;
    c.set_parameter(CParameter::DictIdFlag(false))
        .map_err(err)?;
    Ok(c)
}

fn compress(
    c: &mut zstd::bulk::Compressor<'static>,
    raw: &[u8],
    what: &str,
) -> Result<Vec<u8>, TableError> {
    c.compress(raw)
        .map_err(|e| TableError::Compression(format!("{what}: {e}")))
}

/// One array of a [`TableIndex`]: where it lies and what it holds, before decoding.
#[derive(Debug, Clone, PartialEq)]
pub struct IndexEntry {
    pub name: String,
    pub dtype: DType,
    pub shape: Vec<u64>,
    pub attrs: BTreeMap<String, String>,
    offset: u64,
    compressed_bytes: u64,
    raw_bytes: u64,
    crc32: u32,
}

impl IndexEntry {
    /// Decoded size in bytes.
    pub fn raw_bytes(&self) -> u64 {
        self.raw_bytes
    }
}

/// A table whose header and directory are read and checked, with its arrays decoded on
/// demand ([`TableIndex::array`]): what a renderer uses to load one entry of a large table.
///
/// Reading never panics on malformed input. Memory: the file's bytes, plus, per decoded
/// array, at most twice the bytes its zstd frame actually decompresses to (never more than
/// the declared size + 1): a size field alone never causes an allocation.
#[derive(Debug, Clone)]
pub struct TableIndex {
    pub kind: String,
    pub metadata: serde_json::Value,
    entries: Vec<IndexEntry>,
    by_name: BTreeMap<String, usize>,
    /// The whole file; frames are at `payload_start + offset`.
    bytes: Vec<u8>,
    payload_start: usize,
}

impl TableIndex {
    /// Reads a file's header and directory.
    pub fn open(path: impl AsRef<Path>) -> Result<TableIndex, TableError> {
        let path = path.as_ref();
        let bytes = read_file(path)?;
        TableIndex::from_bytes(bytes).map_err(|e| match e {
            TableError::Format(m) => TableError::Format(format!("{}: {m}", path.display())),
            other => other,
        })
    }

    /// Checks the header and directory of a file held in memory (the arrays' frames are
    /// checked when they are decoded).
    pub fn from_bytes(b: Vec<u8>) -> Result<TableIndex, TableError> {
        let header = Header::read(&b)?;
        // Both fit in `b`, hence in usize.
        let dir_end = HEADER_LEN + header.dir_compressed as usize;
        let dir = header.directory(&b[HEADER_LEN..dir_end])?;
        let (entries, by_name) = index_entries(dir.arrays, header.payload_len)?;
        Ok(TableIndex {
            kind: dir.kind,
            metadata: dir.metadata,
            entries,
            by_name,
            bytes: b,
            payload_start: dir_end,
        })
    }

    /// The arrays, in file order.
    pub fn entries(&self) -> &[IndexEntry] {
        &self.entries
    }

    /// The array called `name`, undecoded.
    pub fn entry(&self, name: &str) -> Option<&IndexEntry> {
        self.by_name.get(name).map(|&i| &self.entries[i])
    }

    /// Decodes (and checks) the array called `name`; `Ok(None)` if there is none.
    pub fn array(&self, name: &str) -> Result<Option<Array>, TableError> {
        match self.by_name.get(name) {
            Some(&i) => self.read_at(i).map(Some),
            None => Ok(None),
        }
    }

    /// Decodes every array once (checksums, sizes) without keeping them.
    pub fn verify(&self) -> Result<(), TableError> {
        (0..self.entries.len()).try_for_each(|i| self.read_at(i).map(|_| ()))
    }

    /// Decodes (and checks) array number `i` in file order.
    pub fn read_at(&self, i: usize) -> Result<Array, TableError> {
        let e = self
            .entries
            .get(i)
            .ok_or_else(|| TableError::Invalid(format!("no array #{i}")))?;
        let what = format!("array {:?}", e.name);
        // Bounds were checked against the payload when the directory was read.
        let start = self.payload_start + e.offset as usize;
        let frame = &self.bytes[start..start + e.compressed_bytes as usize];
        let raw = decompress(frame, e.raw_bytes, &what)?;
        let computed = crc32(&raw);
        if computed != e.crc32 {
            return Err(TableError::Checksum {
                part: what,
                stored: e.crc32,
                computed,
            });
        }
        let data = Data::from_le_bytes(e.dtype, &raw)
            .ok_or_else(|| TableError::Format(format!("{what}: ragged element data")))?;
        Ok(Array {
            name: e.name.clone(),
            shape: e.shape.clone(),
            data,
            attrs: e.attrs.clone(),
        })
    }
}

/// The fixed header of a file, checked: magic, version, flags, reserved field, and lengths
/// that add up to the file's size.
struct Header {
    dir_compressed: u64,
    dir_raw: u64,
    payload_len: u64,
    dir_crc: u32,
}

impl Header {
    fn read(b: &[u8]) -> Result<Header, TableError> {
        let fmt_err = TableError::Format;
        if b.len() < HEADER_LEN {
            if !b.is_empty() && !MAGIC.starts_with(&b[..b.len().min(8)]) {
                return Err(fmt_err("bad magic (expected \"BAKERTBL\")".into()));
            }
            return Err(fmt_err(format!(
                "{} bytes is shorter than the {HEADER_LEN}-byte header",
                b.len()
            )));
        }
        if b[..8] != MAGIC {
            return Err(fmt_err("bad magic (expected \"BAKERTBL\")".into()));
        }
        let u32_at = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap());
        let u64_at = |o: usize| u64::from_le_bytes(b[o..o + 8].try_into().unwrap());
        let version = u32_at(8);
        if version != VERSION {
            return Err(TableError::UnsupportedVersion(version));
        }
        let flags = u32_at(12);
        if flags != 0 {
            return Err(fmt_err(format!(
                "unknown flags {flags:#x} (version 1 defines none)"
            )));
        }
        let dir_compressed = u64_at(16);
        let dir_raw = u64_at(24);
        let payload_len = u64_at(32);
        let dir_crc = u32_at(40);
        let reserved = u32_at(44);
        if reserved != 0 {
            return Err(fmt_err(format!(
                "reserved header field is {reserved:#x}, must be 0"
            )));
        }
        let body = (b.len() - HEADER_LEN) as u64;
        let expected = dir_compressed.checked_add(payload_len);
        if expected != Some(body) {
            return Err(fmt_err(format!(
                "header declares a {dir_compressed}-byte directory and a {payload_len}-byte \
                 payload, but {body} bytes follow the header (truncated or trailing data)"
            )));
        }
        Ok(Header {
            dir_compressed,
            dir_raw,
            payload_len,
            dir_crc,
        })
    }

    /// The directory from its zstd frame `frame`, checked against the header's CRC-32.
    fn directory(&self, frame: &[u8]) -> Result<DirectoryIn, TableError> {
        let fmt_err = TableError::Format;
        let dir_bytes = decompress(frame, self.dir_raw, "the directory")?;
        let computed = crc32(&dir_bytes);
        if computed != self.dir_crc {
            return Err(TableError::Checksum {
                part: "directory".into(),
                stored: self.dir_crc,
                computed,
            });
        }
        let dir: DirectoryIn = serde_json::from_slice(&dir_bytes)
            .map_err(|e| fmt_err(format!("directory is not valid JSON of the format: {e}")))?;
        drop(dir_bytes);
        if dir.kind.is_empty() {
            return Err(fmt_err("the table kind is empty".into()));
        }
        Ok(dir)
    }
}

/// The directory's arrays, checked (names, dtypes, sizes, frames back to back filling the
/// `payload_len`-byte payload), and their indices by name.
fn index_entries(
    arrays: Vec<EntryIn>,
    payload_len: u64,
) -> Result<(Vec<IndexEntry>, BTreeMap<String, usize>), TableError> {
    let fmt_err = TableError::Format;
    let mut names = BTreeMap::new();
    let mut next_offset = 0u64;
    let mut entries = Vec::with_capacity(arrays.len().min(1 << 16));
    for (i, e) in arrays.into_iter().enumerate() {
        check_name(&e.name).map_err(|m| fmt_err(format!("array #{i}: {m}")))?;
        if names.insert(e.name.clone(), i).is_some() {
            return Err(fmt_err(format!("duplicate array name {:?}", e.name)));
        }
        let entry = index_entry(e, next_offset)?;
        next_offset = entry
            .offset
            .checked_add(entry.compressed_bytes)
            .filter(|&end| end <= payload_len)
            .ok_or_else(|| {
                fmt_err(format!(
                    "array {:?}: frame at {} + {} bytes runs past the {payload_len}-byte payload",
                    entry.name, entry.offset, entry.compressed_bytes
                ))
            })?;
        entries.push(entry);
    }
    if next_offset != payload_len {
        return Err(fmt_err(format!(
            "the arrays' frames cover {next_offset} bytes of the {payload_len}-byte payload"
        )));
    }
    Ok((entries, names))
}

/// One directory entry, checked: a known dtype, a shape whose size is `raw_bytes`, and a frame
/// right after the previous one (at `next_offset`).
fn index_entry(e: EntryIn, next_offset: u64) -> Result<IndexEntry, TableError> {
    let fmt_err = TableError::Format;
    let what = format!("array {:?}", e.name);
    let dtype = DType::from_code(&e.dtype).ok_or_else(|| {
        fmt_err(format!(
            "{what}: unknown dtype {:?} (expected f64, f32, u32 or u64)",
            e.dtype
        ))
    })?;
    let count = element_count(&e.shape).ok_or_else(|| {
        fmt_err(format!(
            "{what}: element count of shape {:?} overflows",
            e.shape
        ))
    })?;
    if count.checked_mul(dtype.size() as u64) != Some(e.raw_bytes) {
        return Err(fmt_err(format!(
            "{what}: shape {:?} of {dtype} needs {count} × {} bytes, the directory says \
             raw_bytes = {}",
            e.shape,
            dtype.size(),
            e.raw_bytes
        )));
    }
    if e.offset != next_offset {
        return Err(fmt_err(format!(
            "{what}: offset {} but frames must be back to back (expected {next_offset})",
            e.offset
        )));
    }
    Ok(IndexEntry {
        name: e.name,
        dtype,
        shape: e.shape,
        attrs: e.attrs,
        offset: e.offset,
        compressed_bytes: e.compressed_bytes,
        raw_bytes: e.raw_bytes,
        crc32: e.crc32,
    })
}

/// Decompresses exactly one zstd frame that must fill `src` and yield `raw_len` bytes.
///
/// The output grows with what the frame actually yields and stops one byte past `raw_len`,
/// so a corrupted size field cannot make the reader allocate: memory is at most twice the
/// bytes the frame really holds, and never more than about twice `raw_len`.
pub(crate) fn decompress(src: &[u8], raw_len: u64, what: &str) -> Result<Vec<u8>, TableError> {
    use std::io::Read as _;
    use zstd::zstd_safe;
    let bad = |m: String| TableError::Format(format!("{what}: {m}"));
    let frame_len = zstd_safe::find_frame_compressed_size(src).map_err(|code| {
        bad(format!(
            "not a zstd frame ({})",
            zstd_safe::get_error_name(code)
        ))
    })?;
    if frame_len != src.len() {
        return Err(bad(format!(
            "the zstd frame is {frame_len} bytes, the file gives it {}",
            src.len()
        )));
    }
    match zstd_safe::get_frame_content_size(src) {
        Ok(Some(n)) if n != raw_len => {
            return Err(bad(format!(
                "the zstd frame holds {n} bytes, the file declares {raw_len}"
            )))
        }
        Ok(_) => {}
        Err(_) => return Err(bad("unreadable zstd frame header".into())),
    }
    // Start small: a valid frame compresses at most ~32768:1, a corrupted one may lie.
    let first = raw_len.min(4 * src.len() as u64 + 4096) as usize;
    let mut out = Vec::new();
    out.try_reserve_exact(first)
        .map_err(|e| bad(format!("cannot allocate {first} bytes: {e}")))?;
    let decoder = zstd::stream::read::Decoder::with_buffer(src)
        .map_err(|e| bad(format!("cannot create a zstd decompressor: {e}")))?
        .single_frame();
    decoder
        .take(raw_len.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| bad(format!("zstd decompression failed: {e}")))?;
    if out.len() as u64 != raw_len {
        return Err(bad(format!(
            "decompressed to {} bytes, the file declares {raw_len}",
            out.len()
        )));
    }
    Ok(out)
}

/// Reads a whole table file. Only a regular file is read: a directory, device, FIFO or socket
/// is an error naming what it is (reading `/dev/zero` would never end).
pub fn read_file(path: &Path) -> Result<Vec<u8>, TableError> {
    let io = |source| TableError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a device, FIFO or socket)"
        };
        return Err(TableError::Invalid(format!(
            "{}: is {what}; a table is a regular file",
            path.display()
        )));
    }
    std::fs::read(path).map_err(io)
}

/// CRC-32 as in zlib, PNG and Python's `zlib.crc32` (IEEE 802.3 polynomial, reflected
/// `0xEDB88320`, initial value and final xor `0xFFFFFFFF`); `crc32(b"123456789")` is
/// `0xCBF43926`. A thin wrapper of [`crc32fast`], so that every caller (the baker, the C API,
/// the Python module) names one function.
pub fn crc32(bytes: &[u8]) -> u32 {
    crc32fast::hash(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn sample() -> TableFile {
        let mut t = TableFile::new(
            "skin_profiles",
            json!({ "source": "specs/fitzpatrick.yaml", "lambda_nm": [450.0, 550.0, 650.0],
                    "nested": { "b": 1, "a": [true, null] } }),
        );
        let f64s: Vec<f64> = (0..24).map(|i| (i as f64).sqrt() * 0.1).collect();
        t.push(
            Array::new_f64(
                "female_forearm_typeI_age30_xi0/rd_rgb_per_mm2",
                vec![8, 3],
                f64s,
            )
            .unwrap()
            .with_attr("units", "mm^-2"),
        )
        .unwrap();
        let mut special = vec![
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
        ];
        special.push(f64::from_bits(0x7FF8_0000_0000_0001)); // NaN with a payload
        t.push(Array::new_f64("special", vec![6], special).unwrap())
            .unwrap();
        t.push(
            Array::new_f32(
                "grid/r_mm",
                vec![2, 2, 2],
                vec![0.0, 0.25, 0.5, 1e-30, -3.5, f32::MAX, 7.0, 8.0],
            )
            .unwrap(),
        )
        .unwrap();
        t.push(Array::new_u32("counts", vec![4], vec![0, 1, u32::MAX, 42]).unwrap())
            .unwrap();
        t.push(
            Array::new_u64("seeds", vec![], vec![u64::MAX - 1])
                .unwrap()
                .with_attr("note", "scalar"),
        )
        .unwrap();
        t.push(Array::new_u64("empty", vec![0, 5], vec![]).unwrap())
            .unwrap();
        t
    }

    /// Equality that distinguishes -0.0 and NaN payloads.
    fn same_bits(a: &TableFile, b: &TableFile) -> bool {
        a.kind == b.kind
            && a.metadata == b.metadata
            && a.arrays.len() == b.arrays.len()
            && a.arrays.iter().zip(&b.arrays).all(|(x, y)| {
                x.name == y.name
                    && x.shape == y.shape
                    && x.attrs == y.attrs
                    && x.dtype() == y.dtype()
                    && x.data.to_le_bytes() == y.data.to_le_bytes()
            })
    }

    #[test]
    fn crc32_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
        assert_eq!(
            crc32(b"The quick brown fox jumps over the lazy dog"),
            0x414F_A339
        );
        // Against the bitwise definition (the hand-written table this replaced), on lengths
        // that cross crc32fast's SIMD block sizes.
        let bitwise = |bytes: &[u8]| {
            let mut c = !0u32;
            for &b in bytes {
                c ^= b as u32;
                for _ in 0..8 {
                    c = if c & 1 != 0 {
                        0xEDB8_8320 ^ (c >> 1)
                    } else {
                        c >> 1
                    };
                }
            }
            !c
        };
        let data: Vec<u8> = (0..5000u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        for n in [1, 15, 16, 63, 64, 65, 127, 128, 1000, 4099, 5000] {
            assert_eq!(crc32(&data[..n]), bitwise(&data[..n]), "{n} bytes");
        }
    }

    #[test]
    fn round_trip_every_dtype() {
        let t = sample();
        for level in [-5, 0, 1, DEFAULT_ZSTD_LEVEL, 19] {
            let bytes = t.to_bytes(level).unwrap();
            let back = TableFile::from_bytes(&bytes).unwrap();
            assert!(same_bits(&t, &back), "level {level}");
        }
        let back = TableFile::from_bytes(&t.to_bytes(3).unwrap()).unwrap();
        let a = back
            .get("female_forearm_typeI_age30_xi0/rd_rgb_per_mm2")
            .unwrap();
        assert_eq!(a.attr("units"), Some("mm^-2"));
        assert_eq!(a.as_f64().unwrap()[4], 0.2);
        assert!(a.as_f32().is_none());
        assert_eq!(
            back.get("grid/r_mm").unwrap().as_f32().unwrap()[5],
            f32::MAX
        );
        assert_eq!(back.get("counts").unwrap().as_u32().unwrap()[2], u32::MAX);
        assert_eq!(
            back.get("seeds").unwrap().as_u64().unwrap(),
            &[u64::MAX - 1]
        );
        assert!(back.get("empty").unwrap().is_empty());
        assert!(back.get("nope").is_none());
        let names: Vec<&str> = back.names().collect();
        assert_eq!(names[1], "special");
    }

    #[test]
    fn empty_table_round_trips() {
        let t = TableFile::new("nothing", serde_json::Value::Null);
        let back = TableFile::from_bytes(&t.to_bytes(3).unwrap()).unwrap();
        assert_eq!(back, t);
    }

    #[test]
    fn deterministic() {
        let a = sample().to_bytes(DEFAULT_ZSTD_LEVEL).unwrap();
        let b = sample().to_bytes(DEFAULT_ZSTD_LEVEL).unwrap();
        assert_eq!(a, b);
        // Round trip and rewrite: still identical.
        let c = TableFile::from_bytes(&a)
            .unwrap()
            .to_bytes(DEFAULT_ZSTD_LEVEL)
            .unwrap();
        assert_eq!(a, c);
    }

    #[test]
    fn header_layout() {
        let bytes = sample().to_bytes(3).unwrap();
        assert_eq!(&bytes[..8], b"BAKERTBL");
        assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 1);
        assert_eq!(u32::from_le_bytes(bytes[12..16].try_into().unwrap()), 0);
        let dc = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
        let dr = u64::from_le_bytes(bytes[24..32].try_into().unwrap()) as usize;
        let pl = u64::from_le_bytes(bytes[32..40].try_into().unwrap()) as usize;
        assert_eq!(bytes.len(), HEADER_LEN + dc + pl);
        let dir = zstd::bulk::decompress(&bytes[HEADER_LEN..HEADER_LEN + dc], dr).unwrap();
        assert_eq!(
            u32::from_le_bytes(bytes[40..44].try_into().unwrap()),
            crc32(&dir)
        );
        let v: serde_json::Value = serde_json::from_slice(&dir).unwrap();
        assert_eq!(v["kind"], "skin_profiles");
        assert_eq!(v["arrays"][0]["dtype"], "f64");
        assert_eq!(v["arrays"][0]["shape"], json!([8, 3]));
        assert_eq!(v["arrays"][0]["offset"], 0);
        assert_eq!(v["arrays"][0]["raw_bytes"], 24 * 8);
    }

    #[test]
    fn shape_mismatch_rejected() {
        let e = Array::new_f64("a", vec![2, 3], vec![1.0; 5]).unwrap_err();
        assert!(matches!(e, TableError::Invalid(_)), "{e}");
        assert!(e.to_string().contains("6 elements"), "{e}");
        assert!(Array::new_u32("a", vec![u64::MAX, 3], vec![]).is_err());
        assert!(Array::new_u32("s", vec![], vec![]).is_err());
        // Mutated after construction: caught when writing.
        let mut t = sample();
        t.arrays[0].shape = vec![3, 3];
        assert!(matches!(t.to_bytes(3), Err(TableError::Invalid(_))));
    }

    #[test]
    fn bad_names_and_duplicates_rejected() {
        for name in ["", "/a", "a/", "a//b", "a/../b", "./a", "a\nb"] {
            assert!(
                Array::new_f64(name, vec![1], vec![1.0]).is_err(),
                "{name:?}"
            );
        }
        let mut t = sample();
        let dup = t.arrays[0].clone();
        assert!(t.push(dup.clone()).is_err());
        t.arrays.push(dup);
        assert!(matches!(t.to_bytes(3), Err(TableError::Invalid(_))));
        let mut t = sample();
        t.kind.clear();
        assert!(t.to_bytes(3).is_err());
        assert!(sample().to_bytes(1000).is_err());
    }

    #[test]
    fn truncated_or_corrupted_input_is_an_error() {
        let bytes = sample().to_bytes(3).unwrap();
        // Every truncation.
        for n in 0..bytes.len() {
            assert!(
                TableFile::from_bytes(&bytes[..n]).is_err(),
                "truncated to {n}"
            );
        }
        // Trailing data.
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(TableFile::from_bytes(&longer).is_err());
        // Every single-byte corruption, with two patterns: never a panic, never silently
        // different data.
        let original = TableFile::from_bytes(&bytes).unwrap();
        for i in 0..bytes.len() {
            for x in [0x01u8, 0xFF] {
                let mut c = bytes.clone();
                c[i] ^= x;
                // (A flip zstd ignores may decode to the very same data: harmless.)
                if let Ok(t) = TableFile::from_bytes(&c) {
                    assert!(
                        same_bits(&t, &original),
                        "byte {i} ^ {x:#x} changed the data"
                    );
                }
            }
        }
        // Pseudo-random garbage, with and without a valid header prefix.
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        for _ in 0..2000 {
            let len = (next() % 300) as usize;
            let mut g: Vec<u8> = (0..len).map(|_| next() as u8).collect();
            if len >= 16 && next() % 2 == 0 {
                g[..8].copy_from_slice(&MAGIC);
                g[8..12].copy_from_slice(&1u32.to_le_bytes());
                g[12..16].copy_from_slice(&0u32.to_le_bytes());
            }
            assert!(TableFile::from_bytes(&g).is_err());
        }
    }

    #[test]
    fn clear_errors() {
        let bytes = sample().to_bytes(3).unwrap();
        let e = TableFile::from_bytes(b"PK\x03\x04 something else entirely, long enough....")
            .unwrap_err();
        assert!(e.to_string().contains("bad magic"), "{e}");
        let mut v2 = bytes.clone();
        v2[8] = 2;
        let e = TableFile::from_bytes(&v2).unwrap_err();
        assert!(matches!(e, TableError::UnsupportedVersion(2)), "{e}");
        let e = TableFile::from_bytes(&bytes[..bytes.len() - 1]).unwrap_err();
        assert!(e.to_string().contains("truncated"), "{e}");
    }

    /// Rewrites the directory of `bytes` through `edit` (keeping its checksum valid).
    fn with_directory(bytes: &[u8], edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
        let dc = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
        let dr = u64::from_le_bytes(bytes[24..32].try_into().unwrap()) as usize;
        let dir = zstd::bulk::decompress(&bytes[HEADER_LEN..HEADER_LEN + dc], dr).unwrap();
        let mut v: serde_json::Value = serde_json::from_slice(&dir).unwrap();
        edit(&mut v);
        let dir = serde_json::to_vec(&v).unwrap();
        let frame = zstd::bulk::compress(&dir, 3).unwrap();
        let payload = &bytes[HEADER_LEN + dc..];
        let mut out = bytes[..HEADER_LEN].to_vec();
        out[16..24].copy_from_slice(&(frame.len() as u64).to_le_bytes());
        out[24..32].copy_from_slice(&(dir.len() as u64).to_le_bytes());
        out[40..44].copy_from_slice(&crc32(&dir).to_le_bytes());
        out.extend_from_slice(&frame);
        out.extend_from_slice(payload);
        out
    }

    #[test]
    fn checksum_mismatch_detected() {
        let bytes = sample().to_bytes(3).unwrap();
        let c = with_directory(&bytes, |v| {
            let crc = v["arrays"][2]["crc32"].as_u64().unwrap();
            v["arrays"][2]["crc32"] = json!(crc ^ 1);
        });
        match TableFile::from_bytes(&c).unwrap_err() {
            TableError::Checksum {
                part,
                stored,
                computed,
            } => {
                assert_eq!(part, "array \"grid/r_mm\"");
                assert_eq!(stored ^ 1, computed);
            }
            e => panic!("{e}"),
        }
        let mut c = bytes.clone();
        c[40] ^= 0x10;
        assert!(matches!(
            TableFile::from_bytes(&c),
            Err(TableError::Checksum { part, .. }) if part == "directory"
        ));
    }

    #[test]
    fn inconsistent_directory_rejected() {
        let bytes = sample().to_bytes(3).unwrap();
        assert!(TableFile::from_bytes(&with_directory(&bytes, |_| {})).is_ok());
        type Edit = Box<dyn Fn(&mut serde_json::Value)>;
        let cases: Vec<(&str, Edit)> = vec![
            (
                "shape",
                Box::new(|v| v["arrays"][0]["shape"] = json!([3, 8, 1, 2])),
            ),
            (
                "dtype",
                Box::new(|v| v["arrays"][0]["dtype"] = json!("f16")),
            ),
            (
                "raw_bytes",
                Box::new(|v| v["arrays"][0]["dtype"] = json!("f32")),
            ),
            (
                "offset",
                Box::new(|v| v["arrays"][1]["offset"] = json!(1u64 << 62)),
            ),
            (
                "raw_bytes",
                Box::new(|v| v["arrays"][1]["raw_bytes"] = json!(u64::MAX)),
            ),
            (
                "past",
                Box::new(|v| v["arrays"][5]["compressed_bytes"] = json!(u64::MAX)),
            ),
            (
                "duplicate",
                Box::new(|v| v["arrays"][1]["name"] = v["arrays"][0]["name"].clone()),
            ),
            (
                "segments",
                Box::new(|v| v["arrays"][1]["name"] = json!("a//b")),
            ),
            ("kind", Box::new(|v| v["kind"] = json!(""))),
            (
                "JSON",
                Box::new(|v| {
                    v.as_object_mut().unwrap().remove("arrays");
                }),
            ),
            (
                "cover",
                Box::new(|v| {
                    v["arrays"].as_array_mut().unwrap().pop();
                }),
            ),
        ];
        for (needle, edit) in cases {
            let e = TableFile::from_bytes(&with_directory(&bytes, edit)).unwrap_err();
            assert!(matches!(e, TableError::Format(_)), "{e}");
            assert!(e.to_string().contains(needle), "{needle}: {e}");
        }
    }

    /// Writes a sample file for cross-checking with `validation/bkt.py`. With
    /// `BKT_SAMPLE_OUT=/path/sample.bkt` the file is kept there; otherwise it goes to the
    /// temporary directory and is removed.
    ///
    /// Contents: `f64` "profiles/a/rd" shape [4, 5] = sqrt(i) / 8; `f32` "profiles/a/r_mm"
    /// [20] = i * 0.25; `u32` "index/u32" [2, 3] = 7 i; `u64` "index/u64" [3] = i * 2^40 + i,
    /// with i the flat index; `u64` "misc/scalar" shape [] = 2^64 - 1; `f64` "misc/empty"
    /// [0, 3]; kind "interop_sample", metadata {"answer": 42}.
    #[test]
    fn interop_sample_file() {
        let mut t = TableFile::new("interop_sample", json!({ "answer": 42 }));
        t.push(
            Array::new_f64(
                "profiles/a/rd",
                vec![4, 5],
                (0..20).map(|i| (i as f64).sqrt() / 8.0).collect(),
            )
            .unwrap()
            .with_attr("units", "mm^-2"),
        )
        .unwrap();
        t.push(
            Array::new_f32(
                "profiles/a/r_mm",
                vec![20],
                (0..20).map(|i| i as f32 * 0.25).collect(),
            )
            .unwrap(),
        )
        .unwrap();
        t.push(Array::new_u32("index/u32", vec![2, 3], (0..6).map(|i| 7 * i).collect()).unwrap())
            .unwrap();
        t.push(
            Array::new_u64(
                "index/u64",
                vec![3],
                (0..3).map(|i| (i << 40) + i).collect(),
            )
            .unwrap(),
        )
        .unwrap();
        t.push(Array::new_u64("misc/scalar", vec![], vec![u64::MAX]).unwrap())
            .unwrap();
        t.push(Array::new_f64("misc/empty", vec![0, 3], vec![]).unwrap())
            .unwrap();

        let keep = std::env::var_os("BKT_SAMPLE_OUT").map(PathBuf::from);
        let path = keep.clone().unwrap_or_else(|| {
            let nanos = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_nanos())
                .unwrap_or(0);
            std::env::temp_dir().join(format!(
                "formats-bkt-sample-{}-{nanos}.{EXTENSION}",
                std::process::id()
            ))
        });
        t.write(&path, DEFAULT_ZSTD_LEVEL).unwrap();
        let back = TableFile::read(&path).unwrap();
        assert!(same_bits(&t, &back));
        if keep.is_none() {
            std::fs::remove_file(&path).unwrap();
            let e = TableFile::read(&path).unwrap_err();
            assert!(matches!(e, TableError::Io { .. }), "{e}");
            assert!(e.to_string().contains("formats-bkt-sample"), "{e}");
        }
    }
}
