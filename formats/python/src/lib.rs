//! `baker_formats._native`: the Rust readers of the `formats` crate for Python.
//!
//! This layer hands out plain Python values and raw little-endian bytes with their dtype and
//! shape; the pure-Python package `baker_formats` (python/baker_formats/__init__.py) turns
//! them into numpy arrays with `np.frombuffer`, so no numpy crate is needed and every number
//! reaches numpy bit for bit. Errors: I/O failures raise `OSError` (`FileNotFoundError`,
//! `PermissionError`), everything else `ValueError`, with the Rust message.

use std::collections::BTreeMap;
use std::path::PathBuf;

use formats::bcsdf::direction;
use formats::{BcsdfTable, Data, ProfileTable, TableError, TableFile, TableIndex};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyPermissionError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyByteArray;

/// A table error as a Python exception.
fn py_err(e: TableError) -> PyErr {
    let msg = e.to_string();
    match &e {
        TableError::Io { source, .. } => match source.kind() {
            std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(msg),
            std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(msg),
            _ => PyOSError::new_err(msg),
        },
        _ => PyValueError::new_err(msg),
    }
}

/// [`py_err`] with the path in the message where the reader did not put it.
fn py_err_at(e: TableError, path: &std::path::Path) -> PyErr {
    let p = path.display().to_string();
    match e {
        TableError::Io { .. } => py_err(e),
        e if e.to_string().contains(&p) => py_err(e),
        e => value_err(format!("{p}: {e}")),
    }
}

fn value_err(msg: String) -> PyErr {
    PyValueError::new_err(msg)
}

/// An array as `(dtype code, shape, little-endian bytes, attrs)`.
type RawArray<'py> = (
    &'static str,
    Vec<u64>,
    Bound<'py, PyByteArray>,
    BTreeMap<String, String>,
);

fn raw_array<'py>(
    py: Python<'py>,
    data: &Data,
    shape: Vec<u64>,
    attrs: BTreeMap<String, String>,
) -> RawArray<'py> {
    let bytes = PyByteArray::new(py, &data.to_le_bytes());
    (data.dtype().code(), shape, bytes, attrs)
}

fn f64_bytes(v: impl IntoIterator<Item = f64>) -> Vec<u8> {
    v.into_iter().flat_map(f64::to_le_bytes).collect()
}

/// A direction from Python: three finite numbers, not all zero.
fn direction_arg(w: [f64; 3], name: &str) -> PyResult<[f64; 3]> {
    if w.iter().any(|x| !x.is_finite()) || w.iter().all(|&x| x == 0.0) {
        return Err(value_err(format!(
            "{name} = ({}, {}, {}) is not a direction (finite, non-zero)",
            w[0], w[1], w[2]
        )));
    }
    Ok(w)
}

/// Directions from little-endian f64 bytes, three per direction (x, y, z), each checked as
/// [`direction_arg`] does (`name[i]` in the message).
fn directions_arg(bytes: &[u8], name: &str) -> PyResult<Directions> {
    if bytes.len() % 24 != 0 {
        return Err(value_err(format!(
            "{name}: {} bytes are not f64 triples (x, y, z)",
            bytes.len()
        )));
    }
    bytes
        .chunks_exact(24)
        .enumerate()
        .map(|(i, b)| {
            let w = [0, 1, 2].map(|k| f64::from_le_bytes(b[8 * k..8 * k + 8].try_into().unwrap()));
            direction_arg(w, &format!("{name}[{i}]"))
        })
        .collect()
}

/// Directions in the fiber frame, one per query.
type Directions = Vec<[f64; 3]>;

/// `directions_arg` of two equally long arrays.
fn pairs_arg(wi: &[u8], wo: &[u8]) -> PyResult<(Directions, Directions)> {
    let (wi, wo) = (directions_arg(wi, "wi")?, directions_arg(wo, "wo")?);
    if wi.len() != wo.len() {
        return Err(value_err(format!(
            "wi holds {} directions, wo {}",
            wi.len(),
            wo.len()
        )));
    }
    Ok((wi, wo))
}

/// `f(i)` for every i < n, in index order, split over the machine's cores in contiguous
/// chunks (`std::thread::scope`; each result depends on its index only, so the output does
/// not depend on the thread count). The first error wins.
fn par_map<T: Send>(
    n: usize,
    f: impl Fn(usize) -> Result<T, TableError> + Sync,
) -> Result<Vec<T>, TableError> {
    /// Below this many items per thread, threads cost more than they save.
    const MIN_PER_THREAD: usize = 2048;
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .min(n.div_ceil(MIN_PER_THREAD))
        .max(1);
    if threads == 1 {
        return (0..n).map(f).collect();
    }
    let per = n.div_ceil(threads);
    let f = &f;
    let parts: Vec<Result<Vec<T>, TableError>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| s.spawn(move || (t * per..((t + 1) * per).min(n)).map(f).collect()))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a batch worker panicked"))
            .collect()
    });
    let mut out = Vec::with_capacity(n);
    for p in parts {
        out.extend(p?);
    }
    Ok(out)
}

fn f32_bytes(v: impl IntoIterator<Item = f32>) -> Vec<u8> {
    v.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// Every array of any `.bkt` file: `(kind, metadata JSON, [(name, dtype, shape, bytes,
/// attrs)])`, arrays in file order.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn read_table<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<(String, String, Vec<(String, RawArray<'py>)>)> {
    let t = py
        .detach(|| TableFile::read(&path))
        .map_err(|e| py_err_at(e, &path))?;
    let meta = t.metadata.to_string();
    let arrays = t
        .arrays
        .into_iter()
        .map(|a| {
            let raw = raw_array(py, &a.data, a.shape, a.attrs);
            (a.name, raw)
        })
        .collect();
    Ok((t.kind, meta, arrays))
}

/// A skin profile table (`profiles.bkt`) through `formats::ProfileTable`.
#[pyclass(frozen, module = "baker_formats._native")]
struct ProfileTableNative {
    table: ProfileTable,
    /// The same file, for the raw arrays of a group (`ProfileTable` keeps its index private).
    index: TableIndex,
}

impl ProfileTableNative {
    fn name<'a>(&self, entry: &'a str) -> PyResult<&'a str> {
        match self.table.position(entry) {
            Some(_) => Ok(entry),
            None => Err(value_err(format!("no entry {entry:?} in the table"))),
        }
    }
}

#[pymethods]
impl ProfileTableNative {
    #[new]
    fn new(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        py.detach(|| {
            let table = ProfileTable::open(&path)?;
            let index = TableIndex::open(&path)?;
            Ok(ProfileTableNative { table, index })
        })
        .map_err(|e| py_err_at(e, &path))
    }

    fn entries(&self) -> Vec<String> {
        self.table
            .entries()
            .iter()
            .map(|e| e.name.clone())
            .collect()
    }

    fn metadata_json(&self) -> String {
        self.table.metadata().to_string()
    }

    fn attrs(&self, entry: &str) -> PyResult<BTreeMap<String, String>> {
        let i = self.table.position(self.name(entry)?).unwrap_or_default();
        Ok(self.table.entries()[i].attrs.clone())
    }

    fn params_json(&self, entry: &str) -> PyResult<String> {
        let i = self.table.position(self.name(entry)?).unwrap_or_default();
        Ok(self.table.entries()[i].params.to_string())
    }

    /// Every array of the entry's group: `[(quantity, dtype, shape, bytes, attrs)]`, the
    /// quantity without the `entry/` prefix (`r_mm`, `gaussians/weight_rgb`, …).
    #[allow(clippy::type_complexity)]
    fn arrays<'py>(&self, py: Python<'py>, entry: &str) -> PyResult<Vec<(String, RawArray<'py>)>> {
        let prefix = format!("{}/", self.name(entry)?);
        let mut out = Vec::new();
        for e in self.index.entries() {
            if let Some(q) = e.name.strip_prefix(&prefix) {
                let a = self
                    .index
                    .array(&e.name)
                    .map_err(py_err)?
                    .ok_or_else(|| value_err(format!("array {:?} vanished", e.name)))?;
                out.push((q.to_string(), raw_array(py, &a.data, a.shape, a.attrs)));
            }
        }
        Ok(out)
    }

    /// Rd(r) in linear sRGB, mm⁻², for every little-endian f64 radius in `r_mm`: f64 bytes,
    /// three per radius (`ProfileData::rd_rgb`: NaN gives 0).
    fn rd_rgb<'py>(
        &self,
        py: Python<'py>,
        entry: &str,
        r_mm: &[u8],
    ) -> PyResult<Bound<'py, PyByteArray>> {
        if r_mm.len() % 8 != 0 {
            return Err(value_err("r_mm bytes are not f64 values".into()));
        }
        let d = self.table.data(self.name(entry)?).map_err(py_err)?;
        let out = f64_bytes(
            r_mm.chunks_exact(8)
                .flat_map(|b| d.rd_rgb(f64::from_le_bytes(b.try_into().unwrap()))),
        );
        Ok(PyByteArray::new(py, &out))
    }

    fn albedo_rgb(&self, entry: &str) -> PyResult<[f64; 3]> {
        self.table.albedo_rgb(self.name(entry)?).map_err(py_err)
    }

    /// `(variance_mm2, weight_rgb, error_rgb)` of the sum-of-Gaussians fit.
    #[allow(clippy::type_complexity)]
    fn gaussians(&self, entry: &str) -> PyResult<(Vec<f64>, Vec<[f64; 3]>, [f64; 3])> {
        let g = self.table.gaussians(self.name(entry)?).map_err(py_err)?;
        Ok((g.variance_mm2.clone(), g.weight_rgb.clone(), g.error_rgb))
    }

    /// Names of the entries matching every `(key, value)` (`ProfileTable::find`).
    fn find(&self, query: Vec<(String, String)>) -> Vec<String> {
        let q: Vec<(&str, &str)> = query
            .iter()
            .map(|(k, v)| (k.as_str(), v.as_str()))
            .collect();
        self.table
            .find(&q)
            .into_iter()
            .map(|e| e.name.clone())
            .collect()
    }
}

/// A fiber BCSDF table (`.bcsdf`) through `formats::BcsdfTable`.
#[pyclass(frozen, module = "baker_formats._native")]
struct BcsdfTableNative {
    table: BcsdfTable,
}

impl BcsdfTableNative {
    fn variant(&self, v: usize) -> PyResult<usize> {
        let n = self.table.dir.variants.len();
        if v >= n {
            return Err(value_err(format!(
                "variant {v} out of range (the table has {n})"
            )));
        }
        Ok(v)
    }
}

#[pymethods]
impl BcsdfTableNative {
    #[new]
    fn new(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let table = py
            .detach(|| BcsdfTable::open(&path))
            .map_err(|e| py_err_at(e, &path))?;
        Ok(BcsdfTableNative { table })
    }

    /// The directory as JSON (numbers as serde_json prints them; exact values in
    /// [`BcsdfTableNative::directory_arrays`]).
    fn directory_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.table.dir).map_err(|e| value_err(e.to_string()))
    }

    /// The directory's numeric arrays as the reader holds them: `{name: (dtype, shape,
    /// bytes, {})}` for `wi_deg`, `wi_map`, `scale`, `albedo`, `albedo_se`, `area_um`.
    fn directory_arrays<'py>(&self, py: Python<'py>) -> BTreeMap<&'static str, RawArray<'py>> {
        let d = &self.table.dir;
        let (w, v, c) = (
            d.n_wi() as u64,
            d.variants.len() as u64,
            d.channels.len() as u64,
        );
        let mut out = BTreeMap::new();
        let mut put = |name, data: Data, shape: Vec<u64>| {
            out.insert(name, raw_array(py, &data, shape, BTreeMap::new()));
        };
        put(
            "wi_deg",
            Data::F64(d.wi_deg.iter().flatten().copied().collect()),
            vec![w, 2],
        );
        put(
            "wi_map",
            Data::U32(d.wi_map.clone()),
            vec![d.n_theta as u64, d.n_phi as u64],
        );
        put("scale", Data::F32(d.scale.clone()), vec![w, v, c]);
        put("albedo", Data::F32(d.albedo.clone()), vec![w, v, c]);
        put("albedo_se", Data::F32(d.albedo_se.clone()), vec![w, v, c]);
        put(
            "area_um",
            Data::F64(d.area_um.clone()),
            vec![d.n_phi as u64],
        );
        out
    }

    /// Bin centres in degrees: `theta_o_deg` [n_theta], `dphi_deg` and `phi_deg` [n_phi]
    /// (−90 + (i + ½)·res, −180 + (j + ½)·res, as the HDF5 scales), `theta_i_deg`,
    /// `phi_i_deg` [n_wi] (the stored incoming directions).
    fn axes(&self) -> BTreeMap<&'static str, Vec<f64>> {
        let d = &self.table.dir;
        let centres = |n: usize, lo: f64| -> Vec<f64> {
            (0..n).map(|i| lo + (i as f64 + 0.5) * d.res_deg).collect()
        };
        BTreeMap::from([
            ("theta_o_deg", centres(d.n_theta, -90.0)),
            ("dphi_deg", centres(d.n_phi, -180.0)),
            ("phi_deg", centres(d.n_phi, -180.0)),
            ("theta_i_deg", d.wi_deg.iter().map(|w| w[0]).collect()),
            ("phi_i_deg", d.wi_deg.iter().map(|w| w[1]).collect()),
        ])
    }

    /// f̂ of every stored direction, decoded (`Bcsdf::decode`): f32 bytes, shape [n_wi,
    /// n_variants, n_channels, n_theta, n_phi].
    fn f_normalised<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyByteArray>> {
        let t = &self.table;
        let bytes = py
            .detach(|| -> Result<Vec<u8>, TableError> {
                let mut out = Vec::new();
                for i in 0..t.dir.n_wi() {
                    let s = t.decode(i)?;
                    out.extend(s.values.iter().flat_map(|x| x.to_le_bytes()));
                }
                Ok(out)
            })
            .map_err(py_err)?;
        Ok(PyByteArray::new(py, &bytes))
    }

    /// f = Λ·f̂, sr⁻¹, per channel.
    fn eval(&self, wi: [f64; 3], wo: [f64; 3], variant: usize) -> PyResult<Vec<f32>> {
        let (wi, wo) = (direction_arg(wi, "wi")?, direction_arg(wo, "wo")?);
        self.table
            .eval(wi, wo, self.variant(variant)?)
            .map_err(py_err)
    }

    /// f̂, sr⁻¹, per channel.
    fn eval_normalised(&self, wi: [f64; 3], wo: [f64; 3], variant: usize) -> PyResult<Vec<f32>> {
        let (wi, wo) = (direction_arg(wi, "wi")?, direction_arg(wo, "wo")?);
        self.table
            .eval_normalised(wi, wo, self.variant(variant)?)
            .map_err(py_err)
    }

    fn pdf(&self, wi: [f64; 3], wo: [f64; 3], variant: usize) -> PyResult<f64> {
        let (wi, wo) = (direction_arg(wi, "wi")?, direction_arg(wo, "wo")?);
        self.table
            .pdf(wi, wo, self.variant(variant)?)
            .map_err(py_err)
    }

    /// `(wo, pdf)`, or `None` where the variant scatters nothing.
    fn sample(
        &self,
        wi: [f64; 3],
        u1: f64,
        u2: f64,
        variant: usize,
    ) -> PyResult<Option<([f64; 3], f64)>> {
        let wi = direction_arg(wi, "wi")?;
        for (name, u) in [("u1", u1), ("u2", u2)] {
            if !(0.0..=1.0).contains(&u) {
                return Err(value_err(format!("{name} = {u} is not in [0, 1]")));
            }
        }
        let s = self
            .table
            .sample(wi, self.variant(variant)?, u1, u2)
            .map_err(py_err)?;
        Ok(s.map(|s| (s.wo, s.pdf)))
    }

    /// [`BcsdfTableNative::eval`] for n direction pairs: `wi`, `wo` are little-endian f64
    /// bytes, three per direction; returns f32 bytes [n, n_channels].
    fn eval_batch<'py>(
        &self,
        py: Python<'py>,
        wi: &[u8],
        wo: &[u8],
        variant: usize,
    ) -> PyResult<Bound<'py, PyByteArray>> {
        let (wi, wo) = pairs_arg(wi, wo)?;
        let v = self.variant(variant)?;
        let t = &self.table;
        let f = py
            .detach(|| par_map(wi.len(), |i| t.eval(wi[i], wo[i], v)))
            .map_err(py_err)?;
        Ok(PyByteArray::new(py, &f32_bytes(f.into_iter().flatten())))
    }

    /// [`BcsdfTableNative::pdf`] for n direction pairs (as `eval_batch`): f64 bytes [n].
    fn pdf_batch<'py>(
        &self,
        py: Python<'py>,
        wi: &[u8],
        wo: &[u8],
        variant: usize,
    ) -> PyResult<Bound<'py, PyByteArray>> {
        let (wi, wo) = pairs_arg(wi, wo)?;
        let v = self.variant(variant)?;
        let t = &self.table;
        let p = py
            .detach(|| par_map(wi.len(), |i| t.pdf(wi[i], wo[i], v)))
            .map_err(py_err)?;
        Ok(PyByteArray::new(py, &f64_bytes(p)))
    }

    /// `eval_batch` and `pdf_batch` in one pass: `(f32 bytes [n, n_channels], f64 bytes [n])`.
    fn eval_pdf_batch<'py>(
        &self,
        py: Python<'py>,
        wi: &[u8],
        wo: &[u8],
        variant: usize,
    ) -> PyResult<(Bound<'py, PyByteArray>, Bound<'py, PyByteArray>)> {
        let (wi, wo) = pairs_arg(wi, wo)?;
        let v = self.variant(variant)?;
        let t = &self.table;
        let fp = py
            .detach(|| {
                par_map(wi.len(), |i| {
                    Ok((t.eval(wi[i], wo[i], v)?, t.pdf(wi[i], wo[i], v)?))
                })
            })
            .map_err(py_err)?;
        let f = f32_bytes(fp.iter().flat_map(|(f, _)| f.iter().copied()));
        let p = f64_bytes(fp.iter().map(|(_, p)| *p));
        Ok((PyByteArray::new(py, &f), PyByteArray::new(py, &p)))
    }

    /// [`BcsdfTableNative::sample`] for n incoming directions: `wi` as in `eval_batch`, `u`
    /// little-endian f64 bytes, two uniform numbers in [0, 1] per direction. Returns
    /// `(wo f64 bytes [n, 3], pdf f64 bytes [n], f f32 bytes [n, n_channels])`, f = eval(wi,
    /// wo); where the variant scatters nothing, wo = (0, 0, 0) and pdf = f = 0.
    #[allow(clippy::type_complexity)]
    fn sample_batch<'py>(
        &self,
        py: Python<'py>,
        wi: &[u8],
        u: &[u8],
        variant: usize,
    ) -> PyResult<(
        Bound<'py, PyByteArray>,
        Bound<'py, PyByteArray>,
        Bound<'py, PyByteArray>,
    )> {
        let wi = directions_arg(wi, "wi")?;
        if u.len() != 16 * wi.len() {
            return Err(value_err(format!(
                "u holds {} bytes, expected two f64 per direction ({} bytes)",
                u.len(),
                16 * wi.len()
            )));
        }
        let u: Vec<f64> = u
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
            .collect();
        if let Some(i) = u.iter().position(|x| !(0.0..=1.0).contains(x)) {
            return Err(value_err(format!(
                "u[{}][{}] = {} is not in [0, 1]",
                i / 2,
                i % 2,
                u[i]
            )));
        }
        let v = self.variant(variant)?;
        let nc = self.table.dir.channels.len();
        let t = &self.table;
        let s = py
            .detach(|| {
                par_map(wi.len(), |i| {
                    Ok(match t.sample(wi[i], v, u[2 * i], u[2 * i + 1])? {
                        Some(s) => (s.wo, s.pdf, t.eval(wi[i], s.wo, v)?),
                        None => ([0.0; 3], 0.0, vec![0.0; nc]),
                    })
                })
            })
            .map_err(py_err)?;
        let wo = f64_bytes(s.iter().flat_map(|(w, _, _)| w.iter().copied()));
        let pdf = f64_bytes(s.iter().map(|(_, p, _)| *p));
        let f = f32_bytes(s.iter().flat_map(|(_, _, f)| f.iter().copied()));
        Ok((
            PyByteArray::new(py, &wo),
            PyByteArray::new(py, &pdf),
            PyByteArray::new(py, &f),
        ))
    }

    fn albedo(&self, wi: [f64; 3], variant: usize) -> PyResult<Vec<f32>> {
        let wi = direction_arg(wi, "wi")?;
        self.table
            .albedo(wi, self.variant(variant)?)
            .map_err(py_err)
    }

    fn projected_area(&self, w: [f64; 3]) -> PyResult<f64> {
        Ok(self.table.projected_area(direction_arg(w, "w")?))
    }

    fn area_um(&self, w: [f64; 3]) -> PyResult<f64> {
        Ok(self.table.area_um(direction_arg(w, "w")?))
    }
}

/// The unit vector of θ, φ in radians (`formats::bcsdf::direction`).
#[pyfunction]
fn direction_of(theta_rad: f64, phi_rad: f64) -> [f64; 3] {
    direction(theta_rad, phi_rad)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_table, m)?)?;
    m.add_function(wrap_pyfunction!(direction_of, m)?)?;
    m.add_class::<ProfileTableNative>()?;
    m.add_class::<BcsdfTableNative>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
