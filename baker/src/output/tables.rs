//! Tables as one neutral list of groups and datasets, so the HDF5 file ([`super::hdf5`]) and
//! the native `.bkt` file ([`super::bkt`]) of a bake hold exactly the same numbers.

/// One f64 array.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    /// Path inside its group, e.g. `gaussians/variance_mm2`.
    pub name: String,
    pub shape: Vec<usize>,
    pub data: Vec<f64>,
    pub units: &'static str,
    pub description: &'static str,
    /// Per dimension, the dataset of the same group that is its scale (HDF5 dimension scale).
    pub dims: Vec<Option<&'static str>>,
    /// Names of the elements along the first dimension, as an attribute of that name (e.g.
    /// `layers` on `optics/d_mm`): HDF5 writes an array of strings, `.bkt` the names joined
    /// by `,`.
    pub labels: Option<Labels>,
}

/// Names of a dataset's elements along its first dimension.
#[derive(Debug, Clone, PartialEq)]
pub struct Labels {
    /// The attribute's name.
    pub attr: &'static str,
    pub names: Vec<String>,
}

/// An attribute value: HDF5 writes a scalar string, f64 or u64 attribute; `.bkt` a JSON
/// string or number.
#[derive(Debug, Clone, PartialEq)]
pub enum Attr {
    Text(String),
    Float(f64),
    Count(u64),
}

impl From<&str> for Attr {
    fn from(s: &str) -> Self {
        Attr::Text(s.to_string())
    }
}

impl From<String> for Attr {
    fn from(s: String) -> Self {
        Attr::Text(s)
    }
}

impl From<f64> for Attr {
    fn from(x: f64) -> Self {
        Attr::Float(x)
    }
}

impl From<u64> for Attr {
    fn from(n: u64) -> Self {
        Attr::Count(n)
    }
}

impl Attr {
    pub fn to_json(&self) -> serde_json::Value {
        match self {
            Attr::Text(s) => serde_json::Value::String(s.clone()),
            Attr::Float(x) => serde_json::json!(x),
            Attr::Count(n) => serde_json::json!(n),
        }
    }
}

/// A named group of datasets with its attributes (a skin bake: one per entry, and `colour`).
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    pub name: String,
    pub attrs: Vec<(String, Attr)>,
    pub datasets: Vec<Dataset>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Tables {
    pub attrs: Vec<(String, Attr)>,
    pub groups: Vec<Group>,
}
