//! C ABI of the `formats` readers: skin diffusion profiles ([`formats::ProfileTable`],
//! `profiles.bkt`) and fiber BCSDF tables ([`formats::BcsdfTable`], `.bcsdf`), for renderers
//! written in C or C++ (or anything with a C FFI).
//!
//! # Build and link
//! `cargo build --release -p baker-formats-capi` gives `target/release/libbaker_formats.a`
//! and `libbaker_formats.so`; the header is `formats/capi/include/baker_formats.h`:
//!
//! ```text
//! cc -O2 -std=c99 -Iformats/capi/include app.c target/release/libbaker_formats.a \
//!    -lpthread -ldl -lm -o app
//! ```
//!
//! The header is generated from this file by cbindgen (`build.rs`, configuration
//! `cbindgen.toml`) on every build of this crate and committed; to regenerate it, build the
//! crate and commit `formats/capi/include/baker_formats.h` if it changed.
//!
//! # Conventions
//! - Tables are opaque handles: `bf_*_open` creates one, `bf_*_free` releases it (`NULL` is a
//!   no-op). Queries take a `const` handle and may run on several threads at once; free a
//!   handle only when no thread uses it any more.
//! - Every function that can fail returns an `int`: [`BF_OK`] (0) or one of the `BF_ERR_*`
//!   codes. The text of the last error is [`bf_last_error_message`]: per thread, reset by
//!   every call (empty after a success), valid until the next call on that thread.
//! - Outputs go through caller-owned pointers, written only on success. Null pointers, entry
//!   or variant indices out of range, output buffers too short, non-finite or zero-length
//!   directions and `u1`, `u2` outside [0, 1] are [`BF_ERR_BAD_ARGUMENT`].
//! - No Rust panic crosses the boundary: each entry point runs under
//!   [`std::panic::catch_unwind`] and reports a panic as [`BF_ERR_PANIC`].
//! - Directions are `double[3]` in the fiber frame (axis +z); they need not be normalised.
//!   Values of the BCSDF are `float` (the table's decoded numbers, bit for bit), densities,
//!   areas and profiles `double`.
//! - Strings (entry, variant and channel names) are UTF-8, owned by the table and valid until
//!   it is freed.

use std::cell::RefCell;
use std::ffi::{c_char, c_int, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

use formats::{BcsdfTable, ProfileTable, TableError};

/// Success.
pub const BF_OK: c_int = 0;
/// A file could not be read (missing, unreadable): the message names the path.
pub const BF_ERR_IO: c_int = 1;
/// The bytes are not a valid table: bad magic, truncated, corrupted (CRC-32), inconsistent
/// directory, or a table of another kind.
pub const BF_ERR_FORMAT: c_int = 2;
/// The file's format version is not one this library reads.
pub const BF_ERR_UNSUPPORTED_VERSION: c_int = 3;
/// A null pointer, an index out of range, a buffer too short, a non-finite input.
pub const BF_ERR_BAD_ARGUMENT: c_int = 4;
/// No entry has the name (or parameters) asked for.
pub const BF_ERR_NOT_FOUND: c_int = 5;
/// An internal error (a Rust panic, caught at the boundary); the message says where.
pub const BF_ERR_PANIC: c_int = 6;

/// A skin profile table (`profiles.bkt`, kind `skin_profiles`), opened by
/// [`bf_profile_open`].
pub struct BfProfileTable {
    table: ProfileTable,
    names: Vec<CString>,
}

/// A fiber BCSDF table (`.bcsdf`), opened by [`bf_bcsdf_open`].
pub struct BfBcsdfTable {
    table: BcsdfTable,
    variants: Vec<CString>,
    channels: Vec<CString>,
}

/// An error on its way to C: code and message.
#[derive(Debug)]
struct Error {
    code: c_int,
    message: String,
}

impl Error {
    fn new(code: c_int, message: impl Into<String>) -> Error {
        Error {
            code,
            message: message.into(),
        }
    }

    fn bad(message: impl Into<String>) -> Error {
        Error::new(BF_ERR_BAD_ARGUMENT, message)
    }
}

impl From<TableError> for Error {
    fn from(e: TableError) -> Error {
        let code = match e {
            TableError::Io { .. } => BF_ERR_IO,
            TableError::Format(_) | TableError::Checksum { .. } | TableError::Compression(_) => {
                BF_ERR_FORMAT
            }
            TableError::UnsupportedVersion(_) => BF_ERR_UNSUPPORTED_VERSION,
            TableError::Invalid(_) => BF_ERR_BAD_ARGUMENT,
        };
        Error::new(code, e.to_string())
    }
}

type Result<T> = std::result::Result<T, Error>;

thread_local! {
    /// Message of the last call on this thread (empty after a success).
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(message: &str) {
    // A message cannot hold NUL in C; show it instead of truncating.
    let c = CString::new(message.replace('\0', "\\0")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

fn clear_last_error() {
    LAST_ERROR.with(|e| {
        let mut e = e.borrow_mut();
        if !e.as_bytes().is_empty() {
            *e = CString::default();
        }
    });
}

/// Runs `f`, catching panics, and turns its outcome into a return code and the thread's last
/// error message.
fn guard(f: impl FnOnce() -> Result<()>) -> c_int {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => {
            clear_last_error();
            BF_OK
        }
        Ok(Err(e)) => {
            set_last_error(&e.message);
            e.code
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic payload".into());
            set_last_error(&format!(
                "internal error in libbaker_formats (panic): {what}"
            ));
            BF_ERR_PANIC
        }
    }
}

/// `*p`, or an error naming the argument if `p` is null.
///
/// # Safety
/// `p` is null or valid for reads of `T` for the returned lifetime.
unsafe fn get<'a, T>(p: *const T, name: &str) -> Result<&'a T> {
    // SAFETY: the caller guarantees `p` is null or valid.
    unsafe { p.as_ref() }.ok_or_else(|| Error::bad(format!("argument `{name}` is NULL")))
}

/// Writes `v` through `p`, or fails if `p` is null.
///
/// # Safety
/// `p` is null or valid for a write of `T`.
unsafe fn put<T>(p: *mut T, name: &str, v: T) -> Result<()> {
    if p.is_null() {
        return Err(Error::bad(format!("argument `{name}` is NULL")));
    }
    // SAFETY: non-null and, by the caller's contract, valid for writes.
    unsafe { p.write(v) };
    Ok(())
}

/// Copies `src` to the `len` elements at `dst`.
///
/// # Safety
/// `dst` is null or valid for writes of `len` elements.
unsafe fn put_slice<T: Copy>(dst: *mut T, len: usize, name: &str, src: &[T]) -> Result<()> {
    if dst.is_null() {
        return Err(Error::bad(format!("argument `{name}` is NULL")));
    }
    if len < src.len() {
        return Err(Error::bad(format!(
            "`{name}` holds {len} values, {} are needed",
            src.len()
        )));
    }
    // SAFETY: `dst` is valid for `len ≥ src.len()` elements (caller's contract).
    unsafe { std::ptr::copy_nonoverlapping(src.as_ptr(), dst, src.len()) };
    Ok(())
}

/// The UTF-8 (on Unix: any bytes) path at `p`.
///
/// # Safety
/// `p` is null or a NUL-terminated string.
unsafe fn path_arg(p: *const c_char) -> Result<PathBuf> {
    if p.is_null() {
        return Err(Error::bad("argument `path` is NULL"));
    }
    // SAFETY: non-null and NUL-terminated by the caller's contract.
    let bytes = unsafe { CStr::from_ptr(p) }.to_bytes();
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt as _;
        Ok(PathBuf::from(std::ffi::OsStr::from_bytes(bytes)))
    }
    #[cfg(not(unix))]
    {
        std::str::from_utf8(bytes)
            .map(PathBuf::from)
            .map_err(|_| Error::bad("`path` is not UTF-8"))
    }
}

/// The UTF-8 string at `p`.
///
/// # Safety
/// `p` is null or a NUL-terminated string.
unsafe fn str_arg<'a>(p: *const c_char, name: &str) -> Result<&'a str> {
    if p.is_null() {
        return Err(Error::bad(format!("argument `{name}` is NULL")));
    }
    // SAFETY: non-null and NUL-terminated by the caller's contract.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| Error::bad(format!("`{name}` is not UTF-8")))
}

/// A direction: three finite numbers, not all zero.
///
/// # Safety
/// `p` is null or valid for reads of three doubles.
unsafe fn direction_arg(p: *const f64, name: &str) -> Result<[f64; 3]> {
    if p.is_null() {
        return Err(Error::bad(format!("argument `{name}` is NULL")));
    }
    // SAFETY: valid for three reads by the caller's contract; no alignment beyond f64's.
    let w = unsafe { [*p, *p.add(1), *p.add(2)] };
    if w.iter().any(|x| !x.is_finite()) || w.iter().all(|&x| x == 0.0) {
        return Err(Error::bad(format!(
            "`{name}` = ({}, {}, {}) is not a direction (finite, non-zero)",
            w[0], w[1], w[2]
        )));
    }
    Ok(w)
}

/// Names as C strings; a name with an interior NUL makes the table unusable from C.
fn c_names<'a>(names: impl IntoIterator<Item = &'a String>, what: &str) -> Result<Vec<CString>> {
    names
        .into_iter()
        .map(|n| {
            CString::new(n.as_str()).map_err(|_| {
                Error::new(
                    BF_ERR_FORMAT,
                    format!("{what} name {n:?} contains a NUL byte"),
                )
            })
        })
        .collect()
}

/// Prefixes the path to messages that do not name it already.
fn with_path(e: TableError, path: &std::path::Path) -> Error {
    let mut e = Error::from(e);
    let p = path.display().to_string();
    if !e.message.contains(&p) {
        e.message = format!("{p}: {}", e.message);
    }
    e
}

// ---------------------------------------------------------------------------------------------
// Errors and version

/// The message of the last call on this thread that failed: empty after a success, never
/// NULL. The string belongs to the library and stays valid until the next `bf_*` call on the
/// same thread.
#[no_mangle]
pub extern "C" fn bf_last_error_message() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// A constant name for an error code (`"BF_ERR_IO"`, …; `"unknown"` for other values).
#[no_mangle]
pub extern "C" fn bf_error_name(code: c_int) -> *const c_char {
    let s: &'static CStr = match code {
        BF_OK => c"BF_OK",
        BF_ERR_IO => c"BF_ERR_IO",
        BF_ERR_FORMAT => c"BF_ERR_FORMAT",
        BF_ERR_UNSUPPORTED_VERSION => c"BF_ERR_UNSUPPORTED_VERSION",
        BF_ERR_BAD_ARGUMENT => c"BF_ERR_BAD_ARGUMENT",
        BF_ERR_NOT_FOUND => c"BF_ERR_NOT_FOUND",
        BF_ERR_PANIC => c"BF_ERR_PANIC",
        _ => c"unknown",
    };
    s.as_ptr()
}

/// The library's version (the crate version, e.g. `"0.1.0"`), a constant string.
#[no_mangle]
pub extern "C" fn bf_version() -> *const c_char {
    const V: &str = concat!(env!("CARGO_PKG_VERSION"), "\0");
    V.as_ptr().cast()
}

// ---------------------------------------------------------------------------------------------
// Skin profiles

/// Opens a skin profile table (`profiles.bkt`) and stores its handle in `*out`.
///
/// The directory is read and checked now; an entry's arrays are decoded (and checked) the
/// first time the entry is queried, so a corrupted entry shows as `BF_ERR_FORMAT` then.
///
/// # Safety
/// `path` is NULL or a NUL-terminated string; `out` is NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_profile_open(
    path: *const c_char,
    out: *mut *mut BfProfileTable,
) -> c_int {
    guard(|| {
        if out.is_null() {
            return Err(Error::bad("argument `out` is NULL"));
        }
        // SAFETY: caller's contract.
        let path = unsafe { path_arg(path) }?;
        let table = ProfileTable::open(&path).map_err(|e| with_path(e, &path))?;
        let names = c_names(table.entries().iter().map(|e| &e.name), "entry")?;
        let handle = Box::into_raw(Box::new(BfProfileTable { table, names }));
        // SAFETY: checked non-null above.
        unsafe { out.write(handle) };
        Ok(())
    })
}

/// Releases a table from [`bf_profile_open`]; NULL is ignored. Strings obtained from the
/// table become invalid.
///
/// # Safety
/// `table` is NULL or a handle from `bf_profile_open` not freed yet.
#[no_mangle]
pub unsafe extern "C" fn bf_profile_free(table: *mut BfProfileTable) {
    if !table.is_null() {
        // SAFETY: a live handle from Box::into_raw (caller's contract).
        let b = unsafe { Box::from_raw(table) };
        let _ = catch_unwind(AssertUnwindSafe(move || drop(b)));
    }
}

/// # Safety
/// `t` is NULL or a live handle.
unsafe fn profile<'a>(t: *const BfProfileTable) -> Result<&'a BfProfileTable> {
    // SAFETY: caller's contract.
    unsafe { get(t, "table") }
}

impl BfProfileTable {
    fn entry_name(&self, entry: usize) -> Result<&str> {
        self.table
            .entries()
            .get(entry)
            .map(|e| e.name.as_str())
            .ok_or_else(|| {
                Error::bad(format!(
                    "entry {entry} out of range (the table has {})",
                    self.names.len()
                ))
            })
    }
}

/// Number of entries (skin configurations) in `*out`.
///
/// # Safety
/// `table` is NULL or a live handle; `out` is NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_profile_entry_count(
    table: *const BfProfileTable,
    out: *mut usize,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { profile(table) }?;
        unsafe { put(out, "out", t.names.len()) }
    })
}

/// Name of entry `entry` (0-based, bake order), e.g. `typeIII_age50_xi0.5`, in `*out`; the
/// string belongs to the table.
///
/// # Safety
/// `table` is NULL or a live handle; `out` is NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_profile_entry_name(
    table: *const BfProfileTable,
    entry: usize,
    out: *mut *const c_char,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { profile(table) }?;
        t.entry_name(entry)?;
        unsafe { put(out, "out", t.names[entry].as_ptr()) }
    })
}

/// Index of the entry called `name` in `*out_entry`; `BF_ERR_NOT_FOUND` if there is none.
///
/// # Safety
/// `table` is NULL or a live handle; `name` NULL or NUL-terminated; `out_entry` NULL or valid
/// for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_profile_find(
    table: *const BfProfileTable,
    name: *const c_char,
    out_entry: *mut usize,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { profile(table) }?;
        let name = unsafe { str_arg(name, "name") }?;
        let i = t.table.position(name).ok_or_else(|| {
            Error::new(BF_ERR_NOT_FOUND, format!("no entry {name:?} in the table"))
        })?;
        unsafe { put(out_entry, "out_entry", i) }
    })
}

/// Index of the one entry whose parameters match all `n` pairs `keys[i]` = `values[i]`, in
/// `*out_entry`. Keys are group attributes (`skin_type`, `age_years`, `xi`, `gender`,
/// `location`, `model`, …) or model inputs; values compare as numbers when both parse as
/// numbers (`"50"` matches 50.0). `BF_ERR_NOT_FOUND` unless exactly one entry matches.
///
/// # Safety
/// `table` is NULL or a live handle; `keys` and `values` NULL or arrays of `n` NUL-terminated
/// strings; `out_entry` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_profile_lookup(
    table: *const BfProfileTable,
    keys: *const *const c_char,
    values: *const *const c_char,
    n: usize,
    out_entry: *mut usize,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { profile(table) }?;
        if n > 0 && (keys.is_null() || values.is_null()) {
            return Err(Error::bad("argument `keys` or `values` is NULL"));
        }
        let mut query = Vec::with_capacity(n);
        for i in 0..n {
            // SAFETY: both arrays hold n pointers (caller's contract).
            let (k, v) = unsafe { (*keys.add(i), *values.add(i)) };
            query.push((unsafe { str_arg(k, "keys[i]") }?, unsafe {
                str_arg(v, "values[i]")
            }?));
        }
        let found = t.table.lookup(&query).map_err(|e| match e {
            TableError::Invalid(m) => Error::new(BF_ERR_NOT_FOUND, m),
            other => other.into(),
        })?;
        let i = t
            .table
            .position(&found.name)
            .expect("a found entry has a position");
        unsafe { put(out_entry, "out_entry", i) }
    })
}

/// Rd(r) of `entry` in linear sRGB, mm⁻², into `out_rgb[3]`: linear in r between bin
/// centres, the first bin's value from 0 to its centre, the last bin's value out to the outer
/// edge, 0 beyond (FORMAT.md, "Skin profiles"). `r_mm` must be ≥ 0 and not NaN.
///
/// # Safety
/// `table` is NULL or a live handle; `out_rgb` NULL or valid for 3 writes.
#[no_mangle]
pub unsafe extern "C" fn bf_profile_rd_rgb(
    table: *const BfProfileTable,
    entry: usize,
    r_mm: f64,
    out_rgb: *mut f64,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { profile(table) }?;
        let name = t.entry_name(entry)?;
        if r_mm.is_nan() || r_mm < 0.0 {
            return Err(Error::bad(format!("r_mm = {r_mm} is not a radius (≥ 0)")));
        }
        let v = t.table.rd_rgb(name, r_mm)?;
        unsafe { put_slice(out_rgb, 3, "out_rgb", &v) }
    })
}

/// Total diffuse reflectance of `entry` per channel (linear sRGB) into `out_rgb[3]`.
///
/// # Safety
/// `table` is NULL or a live handle; `out_rgb` NULL or valid for 3 writes.
#[no_mangle]
pub unsafe extern "C" fn bf_profile_albedo_rgb(
    table: *const BfProfileTable,
    entry: usize,
    out_rgb: *mut f64,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { profile(table) }?;
        let v = t.table.albedo_rgb(t.entry_name(entry)?)?;
        unsafe { put_slice(out_rgb, 3, "out_rgb", &v) }
    })
}

/// Number of Gaussians of `entry`'s sum-of-Gaussians fit in `*out` (0 if the table has no
/// fit).
///
/// # Safety
/// `table` is NULL or a live handle; `out` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_profile_gaussian_count(
    table: *const BfProfileTable,
    entry: usize,
    out: *mut usize,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { profile(table) }?;
        let g = t.table.gaussians(t.entry_name(entry)?)?;
        unsafe { put(out, "out", g.variance_mm2.len()) }
    })
}

/// The sum-of-Gaussians fit of `entry`, Rd_c(r) ≈ Σᵢ wᵢc·exp(−r²/2vᵢ)/(2πvᵢ): variances vᵢ
/// (mm², ascending) into `variance_mm2[n]`, weights into `weight_rgb[n × 3]` (row i =
/// Gaussian i, columns R, G, B) and the fit error per channel into `error_rgb[3]` (NaN
/// without a fit), n = [`bf_profile_gaussian_count`]. `capacity` is the number of Gaussians
/// the two arrays have room for; less than n is `BF_ERR_BAD_ARGUMENT`.
///
/// # Safety
/// `table` is NULL or a live handle; the outputs NULL or valid for `capacity`,
/// `3 × capacity` and 3 writes.
#[no_mangle]
pub unsafe extern "C" fn bf_profile_gaussians(
    table: *const BfProfileTable,
    entry: usize,
    capacity: usize,
    variance_mm2: *mut f64,
    weight_rgb: *mut f64,
    error_rgb: *mut f64,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { profile(table) }?;
        let g = t.table.gaussians(t.entry_name(entry)?)?;
        let w: Vec<f64> = g.weight_rgb.iter().flatten().copied().collect();
        unsafe {
            put_slice(variance_mm2, capacity, "variance_mm2", &g.variance_mm2)?;
            put_slice(weight_rgb, capacity.saturating_mul(3), "weight_rgb", &w)?;
            put_slice(error_rgb, 3, "error_rgb", &g.error_rgb)
        }
    })
}

// ---------------------------------------------------------------------------------------------
// Fiber BCSDFs

/// Opens a fiber BCSDF table (`.bcsdf`) and stores its handle in `*out`.
///
/// The header and directory are read and checked now; each stored incoming direction's slice
/// is decompressed, checked (CRC-32) and decoded the first time a query needs it, then kept
/// (a corrupted slice shows as `BF_ERR_FORMAT` then).
///
/// # Safety
/// `path` is NULL or a NUL-terminated string; `out` is NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_open(path: *const c_char, out: *mut *mut BfBcsdfTable) -> c_int {
    guard(|| {
        if out.is_null() {
            return Err(Error::bad("argument `out` is NULL"));
        }
        // SAFETY: caller's contract.
        let path = unsafe { path_arg(path) }?;
        let table = BcsdfTable::open(&path).map_err(|e| with_path(e, &path))?;
        let variants = c_names(&table.dir.variants, "variant")?;
        let channels = c_names(&table.dir.channels, "channel")?;
        let handle = Box::into_raw(Box::new(BfBcsdfTable {
            table,
            variants,
            channels,
        }));
        // SAFETY: checked non-null above.
        unsafe { out.write(handle) };
        Ok(())
    })
}

/// Releases a table from [`bf_bcsdf_open`]; NULL is ignored. Strings obtained from the table
/// become invalid.
///
/// # Safety
/// `table` is NULL or a handle from `bf_bcsdf_open` not freed yet.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_free(table: *mut BfBcsdfTable) {
    if !table.is_null() {
        // SAFETY: a live handle from Box::into_raw (caller's contract).
        let b = unsafe { Box::from_raw(table) };
        let _ = catch_unwind(AssertUnwindSafe(move || drop(b)));
    }
}

/// # Safety
/// `t` is NULL or a live handle.
unsafe fn bcsdf<'a>(t: *const BfBcsdfTable) -> Result<&'a BfBcsdfTable> {
    // SAFETY: caller's contract.
    unsafe { get(t, "table") }
}

impl BfBcsdfTable {
    fn check_variant(&self, variant: usize) -> Result<()> {
        if variant >= self.variants.len() {
            return Err(Error::bad(format!(
                "variant {variant} out of range (the table has {})",
                self.variants.len()
            )));
        }
        Ok(())
    }
}

/// Number of variants (dye × depth of shade, or `undyed`) in `*out`.
///
/// # Safety
/// `table` is NULL or a live handle; `out` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_variant_count(
    table: *const BfBcsdfTable,
    out: *mut usize,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        unsafe { put(out, "out", t.variants.len()) }
    })
}

/// Name of variant `variant` in `*out`; the string belongs to the table.
///
/// # Safety
/// `table` is NULL or a live handle; `out` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_variant_name(
    table: *const BfBcsdfTable,
    variant: usize,
    out: *mut *const c_char,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        t.check_variant(variant)?;
        unsafe { put(out, "out", t.variants[variant].as_ptr()) }
    })
}

/// Number of channels (`R`, `G`, `B`, or wavelengths such as `550nm`) in `*out`: the length
/// of every per-channel output.
///
/// # Safety
/// `table` is NULL or a live handle; `out` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_channel_count(
    table: *const BfBcsdfTable,
    out: *mut usize,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        unsafe { put(out, "out", t.channels.len()) }
    })
}

/// Name of channel `channel` in `*out`; the string belongs to the table.
///
/// # Safety
/// `table` is NULL or a live handle; `out` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_channel_name(
    table: *const BfBcsdfTable,
    channel: usize,
    out: *mut *const c_char,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        let c = t.channels.get(channel).ok_or_else(|| {
            Error::bad(format!(
                "channel {channel} out of range (the table has {})",
                t.channels.len()
            ))
        })?;
        unsafe { put(out, "out", c.as_ptr()) }
    })
}

/// The BCSDF f(ωi, ωo) = Λ(ωi)·f̂(ωi, ωo), sr⁻¹, of `variant`, one value per channel into
/// `out[out_len]` (`out_len` ≥ the channel count).
///
/// # Safety
/// `table` is NULL or a live handle; `wi`, `wo` NULL or valid for 3 reads; `out` NULL or
/// valid for `out_len` writes.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_eval(
    table: *const BfBcsdfTable,
    wi: *const f64,
    wo: *const f64,
    variant: usize,
    out: *mut f32,
    out_len: usize,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        let (wi, wo) = unsafe { (direction_arg(wi, "wi")?, direction_arg(wo, "wo")?) };
        t.check_variant(variant)?;
        let f = t.table.eval(wi, wo, variant)?;
        unsafe { put_slice(out, out_len, "out", &f) }
    })
}

/// The normalised BCSDF f̂(ωi, ωo), sr⁻¹ (Σ f̂·ΔΩ = 1 over the outgoing bins), of `variant`,
/// one value per channel into `out[out_len]`.
///
/// # Safety
/// As [`bf_bcsdf_eval`].
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_eval_normalised(
    table: *const BfBcsdfTable,
    wi: *const f64,
    wo: *const f64,
    variant: usize,
    out: *mut f32,
    out_len: usize,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        let (wi, wo) = unsafe { (direction_arg(wi, "wi")?, direction_arg(wo, "wo")?) };
        t.check_variant(variant)?;
        let f = t.table.eval_normalised(wi, wo, variant)?;
        unsafe { put_slice(out, out_len, "out", &f) }
    })
}

/// Density of [`bf_bcsdf_sample`] at `wo`, sr⁻¹, in `*out_pdf` (0 where the variant
/// scatters nothing).
///
/// # Safety
/// `table` is NULL or a live handle; `wi`, `wo` NULL or valid for 3 reads; `out_pdf` NULL or
/// valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_pdf(
    table: *const BfBcsdfTable,
    wi: *const f64,
    wo: *const f64,
    variant: usize,
    out_pdf: *mut f64,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        let (wi, wo) = unsafe { (direction_arg(wi, "wi")?, direction_arg(wo, "wo")?) };
        t.check_variant(variant)?;
        let p = t.table.pdf(wi, wo, variant)?;
        unsafe { put(out_pdf, "out_pdf", p) }
    })
}

/// Draws ωo from the tabulated density of `variant` with two uniform numbers `u1`, `u2` in
/// [0, 1]: unit vector into `out_wo[3]`, its density (sr⁻¹) into `*out_pdf`. Where the
/// variant scatters nothing the call succeeds with `out_wo` = (0, 0, 0) and `*out_pdf` = 0:
/// an invalid sample (end the path).
///
/// # Safety
/// `table` is NULL or a live handle; `wi` NULL or valid for 3 reads; `out_wo` NULL or valid
/// for 3 writes; `out_pdf` NULL or valid for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_sample(
    table: *const BfBcsdfTable,
    wi: *const f64,
    u1: f64,
    u2: f64,
    variant: usize,
    out_wo: *mut f64,
    out_pdf: *mut f64,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        let wi = unsafe { direction_arg(wi, "wi") }?;
        for (name, u) in [("u1", u1), ("u2", u2)] {
            if !(0.0..=1.0).contains(&u) {
                return Err(Error::bad(format!("{name} = {u} is not in [0, 1]")));
            }
        }
        t.check_variant(variant)?;
        if out_wo.is_null() || out_pdf.is_null() {
            return Err(Error::bad("argument `out_wo` or `out_pdf` is NULL"));
        }
        let (wo, pdf) = match t.table.sample(wi, variant, u1, u2)? {
            Some(s) => (s.wo, s.pdf),
            None => ([0.0; 3], 0.0),
        };
        unsafe {
            put_slice(out_wo, 3, "out_wo", &wo)?;
            put(out_pdf, "out_pdf", pdf)
        }
    })
}

/// Directional albedo Λ(ωi) of `variant`, one value per channel into `out[out_len]`.
///
/// # Safety
/// `table` is NULL or a live handle; `wi` NULL or valid for 3 reads; `out` NULL or valid for
/// `out_len` writes.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_albedo(
    table: *const BfBcsdfTable,
    wi: *const f64,
    variant: usize,
    out: *mut f32,
    out_len: usize,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        let wi = unsafe { direction_arg(wi, "wi") }?;
        t.check_variant(variant)?;
        let a = t.table.albedo(wi, variant)?;
        unsafe { put_slice(out, out_len, "out", &a) }
    })
}

/// Projected area A(ω) of a unit length of fiber seen from `w`, µm (µm² per µm): the
/// projected width at φ times cos θ (thesis Eq. 17), in `*out_um`.
///
/// # Safety
/// `table` is NULL or a live handle; `w` NULL or valid for 3 reads; `out_um` NULL or valid
/// for a write.
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_projected_area(
    table: *const BfBcsdfTable,
    w: *const f64,
    out_um: *mut f64,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        let w = unsafe { direction_arg(w, "w") }?;
        unsafe { put(out_um, "out_um", t.table.projected_area(w)) }
    })
}

/// Projected width of the fiber per unit length seen from azimuth φ of `w`, µm (no cos θ
/// factor), in `*out_um`.
///
/// # Safety
/// As [`bf_bcsdf_projected_area`].
#[no_mangle]
pub unsafe extern "C" fn bf_bcsdf_area_um(
    table: *const BfBcsdfTable,
    w: *const f64,
    out_um: *mut f64,
) -> c_int {
    guard(|| {
        // SAFETY: caller's contract.
        let t = unsafe { bcsdf(table) }?;
        let w = unsafe { direction_arg(w, "w") }?;
        unsafe { put(out_um, "out_um", t.table.area_um(w)) }
    })
}

#[cfg(test)]
mod tests;
