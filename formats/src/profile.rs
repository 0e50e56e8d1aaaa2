//! Skin diffusion profiles as a renderer reads them: [`ProfileTable`] over a
//! `profiles.bkt` file (kind `skin_profiles`, layout in `formats/FORMAT.md`, "Skin profiles").
//!
//! The directory is read when the table is opened; an entry's arrays are decoded the first
//! time the entry is asked for, and kept.
//!
//! ```no_run
//! let t = formats::ProfileTable::open("out/fitzpatrick/profiles.bkt")?;
//! let e = t.lookup(&[("skin_type", "III"), ("age_years", "50"), ("xi", "0.5")])?;
//! let rd = t.rd_rgb(&e.name, 0.5)?; // mm⁻², linear sRGB, 0.5 mm from the beam
//! let g = t.gaussians(&e.name)?;    // sum-of-Gaussians fit
//! # Ok::<(), formats::TableError>(())
//! ```

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::OnceLock;

use crate::table::{TableError, TableIndex};

/// The `kind` of a skin profile table.
pub const KIND: &str = "skin_profiles";

/// One entry (one skin configuration) of a [`ProfileTable`].
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileEntry {
    /// Entry name from the spec, e.g. `typeIII_age50_xi0.5`; the arrays' group.
    pub name: String,
    /// The group's attributes as written (`age_years`, `gender`, `location`, `xi`,
    /// `skin_type`, `model`, `melanosome_fraction`, `params_json`, …), all as strings.
    pub attrs: BTreeMap<String, String>,
    /// Every model input (`params_json` parsed; `Null` if absent).
    pub params: serde_json::Value,
}

/// The sum-of-Gaussians fit of one entry: Rd_c(r) ≈ Σᵢ wᵢc·exp(−r²/2vᵢ)/(2πvᵢ) (d'Eon &
/// Luebke, GPU Gems 3 ch. 14).
#[derive(Debug, Clone, PartialEq)]
pub struct Gaussians {
    /// Shared variances vᵢ, mm², ascending.
    pub variance_mm2: Vec<f64>,
    /// Non-negative weights per channel (linear sRGB); Σᵢ wᵢc is the fitted albedo.
    pub weight_rgb: Vec<[f64; 3]>,
    /// Energy-weighted relative L1 error per channel (FORMAT.md, "The sum-of-Gaussians fit").
    pub error_rgb: [f64; 3],
}

impl Gaussians {
    /// The fitted profile at `r_mm`, mm⁻².
    pub fn eval(&self, r_mm: f64) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (v, w) in self.variance_mm2.iter().zip(&self.weight_rgb) {
            let g = (-r_mm * r_mm / (2.0 * v)).exp() / (std::f64::consts::TAU * v);
            for c in 0..3 {
                out[c] += w[c] * g;
            }
        }
        out
    }
}

/// The decoded arrays of one entry.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileData {
    /// Bin centres, mm.
    pub r_mm: Vec<f64>,
    /// Annulus edges, mm (`r_mm.len() + 1` values, the first 0).
    pub r_edges_mm: Vec<f64>,
    /// Annulus-averaged RGB profile per bin, mm⁻².
    pub rd_rgb_per_mm2: Vec<[f64; 3]>,
    /// Total diffuse reflectance per channel.
    pub albedo_rgb: [f64; 3],
    pub gaussians: Gaussians,
}

impl ProfileData {
    /// Rd(r) per channel, mm⁻², by the documented interpolation: linear in r between bin
    /// centres; the first bin's value from r = 0 to its centre; the last bin's value from its
    /// centre to its outer edge; 0 beyond the grid.
    pub fn rd_rgb(&self, r_mm: f64) -> [f64; 3] {
        let (r, v) = (&self.r_mm, &self.rd_rgb_per_mm2);
        let n = r.len();
        if n == 0 || r_mm.is_nan() || r_mm > self.r_edges_mm[n] {
            return [0.0; 3];
        }
        if r_mm <= r[0] {
            return v[0];
        }
        if r_mm >= r[n - 1] {
            return v[n - 1];
        }
        // First centre above r_mm (r is ascending).
        let k = r.partition_point(|&x| x <= r_mm);
        let t = (r_mm - r[k - 1]) / (r[k] - r[k - 1]);
        std::array::from_fn(|c| v[k - 1][c] + t * (v[k][c] - v[k - 1][c]))
    }
}

/// A skin profile table (`profiles.bkt`), entries decoded lazily.
#[derive(Debug)]
pub struct ProfileTable {
    index: TableIndex,
    entries: Vec<ProfileEntry>,
    data: Vec<OnceLock<Result<ProfileData, String>>>,
}

impl ProfileTable {
    /// Opens a `profiles.bkt` file.
    pub fn open(path: impl AsRef<Path>) -> Result<ProfileTable, TableError> {
        Self::from_index(TableIndex::open(path)?)
    }

    /// Reads a table held in memory.
    pub fn from_bytes(bytes: Vec<u8>) -> Result<ProfileTable, TableError> {
        Self::from_index(TableIndex::from_bytes(bytes)?)
    }

    fn from_index(index: TableIndex) -> Result<ProfileTable, TableError> {
        let bad = |m: String| Err(TableError::Format(m));
        if index.kind != KIND {
            return bad(format!("kind {:?}, expected {KIND:?}", index.kind));
        }
        // `entries` is a JSON list, stored as a string attribute (as in HDF5).
        let names: Vec<String> = match index.metadata.get("entries") {
            Some(serde_json::Value::String(s)) => serde_json::from_str(s)
                .map_err(|e| TableError::Format(format!("metadata.entries: {e}")))?,
            _ => return bad("metadata has no `entries` list".into()),
        };
        let groups = index.metadata.get("groups");
        let mut entries = Vec::with_capacity(names.len().min(1 << 16));
        for name in names {
            for q in ["r_mm", "r_edges_mm", "rd_rgb_per_mm2", "albedo_rgb"] {
                if index.entry(&format!("{name}/{q}")).is_none() {
                    return bad(format!("entry {name:?} has no array {q:?}"));
                }
            }
            let attrs: BTreeMap<String, String> = groups
                .and_then(|g| g.get(&name))
                .and_then(|g| g.as_object())
                .map(|o| {
                    o.iter()
                        .map(|(k, v)| {
                            let v = match v {
                                serde_json::Value::String(s) => s.clone(),
                                other => other.to_string(),
                            };
                            (k.clone(), v)
                        })
                        .collect()
                })
                .unwrap_or_default();
            let params = attrs
                .get("params_json")
                .and_then(|p| serde_json::from_str(p).ok())
                .unwrap_or(serde_json::Value::Null);
            entries.push(ProfileEntry {
                name,
                attrs,
                params,
            });
        }
        let data = entries.iter().map(|_| OnceLock::new()).collect();
        Ok(ProfileTable {
            index,
            entries,
            data,
        })
    }

    /// Root metadata: provenance (`spec_sha256`, `baker_version`, `seed`, `photons`, …).
    pub fn metadata(&self) -> &serde_json::Value {
        &self.index.metadata
    }

    /// The underlying `.bkt` index (every array of the file, decoded on demand).
    pub fn index(&self) -> &TableIndex {
        &self.index
    }

    /// The entries, in bake order.
    pub fn entries(&self) -> &[ProfileEntry] {
        &self.entries
    }

    /// Position of the entry called `name`.
    pub fn position(&self, name: &str) -> Option<usize> {
        self.entries.iter().position(|e| e.name == name)
    }

    /// The entries whose parameters match every `(key, value)`: a key is a group attribute
    /// (`skin_type`, `age_years`, `xi`, `gender`, `location`, `model`, …) or a top-level key
    /// of `params`; values compare as numbers when both parse as numbers (`"50"` matches
    /// 50.0), else as strings.
    pub fn find(&self, query: &[(&str, &str)]) -> Vec<&ProfileEntry> {
        self.entries
            .iter()
            .filter(|e| {
                query.iter().all(|(k, want)| {
                    let have = e.attrs.get(*k).cloned().or_else(|| {
                        e.params.get(*k).map(|v| match v {
                            serde_json::Value::String(s) => s.clone(),
                            other => other.to_string(),
                        })
                    });
                    have.is_some_and(|h| same_value(&h, want))
                })
            })
            .collect()
    }

    /// The one entry matching `query` (see [`ProfileTable::find`]); an error names how many
    /// matched.
    pub fn lookup(&self, query: &[(&str, &str)]) -> Result<&ProfileEntry, TableError> {
        let found = self.find(query);
        match found.as_slice() {
            [one] => Ok(one),
            _ => Err(TableError::Invalid(format!(
                "{} entries match {query:?} (expected exactly one)",
                found.len()
            ))),
        }
    }

    /// The decoded arrays of entry `name` (decoded on first use, then kept).
    pub fn data(&self, name: &str) -> Result<&ProfileData, TableError> {
        let i = self
            .position(name)
            .ok_or_else(|| TableError::Invalid(format!("no entry {name:?} in the table")))?;
        self.data[i]
            .get_or_init(|| self.decode(name).map_err(|e| e.to_string()))
            .as_ref()
            .map_err(|e| TableError::Format(e.clone()))
    }

    /// Rd(r) of entry `name` in linear sRGB, mm⁻² (interpolation: [`ProfileData::rd_rgb`]).
    pub fn rd_rgb(&self, name: &str, r_mm: f64) -> Result<[f64; 3], TableError> {
        Ok(self.data(name)?.rd_rgb(r_mm))
    }

    /// Total diffuse reflectance of entry `name` per channel (linear sRGB).
    pub fn albedo_rgb(&self, name: &str) -> Result<[f64; 3], TableError> {
        Ok(self.data(name)?.albedo_rgb)
    }

    /// The sum-of-Gaussians fit of entry `name`.
    pub fn gaussians(&self, name: &str) -> Result<&Gaussians, TableError> {
        Ok(&self.data(name)?.gaussians)
    }

    fn decode(&self, name: &str) -> Result<ProfileData, TableError> {
        let f64s = |q: &str, shape: &[u64]| -> Result<Vec<f64>, TableError> {
            let full = format!("{name}/{q}");
            let a = self
                .index
                .array(&full)?
                .ok_or_else(|| TableError::Format(format!("no array {full:?}")))?;
            if !shape.is_empty() && a.shape != shape {
                return Err(TableError::Format(format!(
                    "{full}: shape {:?}, expected {shape:?}",
                    a.shape
                )));
            }
            match a.data {
                crate::table::Data::F64(v) => Ok(v),
                _ => Err(TableError::Format(format!("{full}: expected f64 values"))),
            }
        };
        let r_mm = f64s("r_mm", &[])?;
        let n = r_mm.len() as u64;
        let r_edges_mm = f64s("r_edges_mm", &[n + 1])?;
        if r_mm
            .windows(2)
            .any(|w| w[0].partial_cmp(&w[1]) != Some(std::cmp::Ordering::Less))
            || r_edges_mm.iter().any(|x| !x.is_finite())
        {
            return Err(TableError::Format(format!(
                "{name}: radii are not finite and ascending"
            )));
        }
        let rgb = |v: Vec<f64>| v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let rd_rgb_per_mm2 = rgb(f64s("rd_rgb_per_mm2", &[n, 3])?);
        let a = f64s("albedo_rgb", &[3])?;
        let gaussians = match self.index.entry(&format!("{name}/gaussians/variance_mm2")) {
            Some(e) => {
                let m = e.shape.first().copied().unwrap_or(0);
                let e = f64s("gaussians/error_rgb", &[3])?;
                Gaussians {
                    variance_mm2: f64s("gaussians/variance_mm2", &[m])?,
                    weight_rgb: rgb(f64s("gaussians/weight_rgb", &[m, 3])?),
                    error_rgb: [e[0], e[1], e[2]],
                }
            }
            None => Gaussians {
                variance_mm2: Vec::new(),
                weight_rgb: Vec::new(),
                error_rgb: [f64::NAN; 3],
            },
        };
        // FORMAT.md: profiles, albedos and fits are finite (variances > 0); only r99_mm may
        // be NaN, and this reader does not use it.
        let finite = |what: &str, v: &[f64]| match v.iter().find(|x| !x.is_finite()) {
            Some(x) => Err(TableError::Invalid(format!(
                "{name}/{what}: holds {x} (values are finite)"
            ))),
            None => Ok(()),
        };
        finite("rd_rgb_per_mm2", rd_rgb_per_mm2.as_flattened())?;
        finite("albedo_rgb", &a)?;
        finite("gaussians/weight_rgb", gaussians.weight_rgb.as_flattened())?;
        if gaussians
            .variance_mm2
            .iter()
            .any(|v| !(v.is_finite() && *v > 0.0))
        {
            return Err(TableError::Invalid(format!(
                "{name}/gaussians/variance_mm2: variances are finite and > 0"
            )));
        }
        Ok(ProfileData {
            r_mm,
            r_edges_mm,
            rd_rgb_per_mm2,
            albedo_rgb: [a[0], a[1], a[2]],
            gaussians,
        })
    }

    /// Decodes every entry (checksums, shapes, finite values) and every other array of the
    /// file: what a converter calls before it writes anything derived from the table.
    pub fn verify(&self) -> Result<(), TableError> {
        self.index.verify()?;
        self.entries
            .iter()
            .try_for_each(|e| self.data(&e.name).map(|_| ()))
    }
}

fn same_value(have: &str, want: &str) -> bool {
    match (have.trim().parse::<f64>(), want.trim().parse::<f64>()) {
        (Ok(a), Ok(b)) => a == b,
        _ => have == want,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::{Array, TableFile};

    fn table() -> ProfileTable {
        let mut t = TableFile::new(KIND, serde_json::Value::Null);
        let names = ["typeI_age30_xi0", "typeIII_age50_xi0.5"];
        let mut groups = serde_json::Map::new();
        for (k, name) in names.iter().enumerate() {
            groups.insert(
                name.to_string(),
                serde_json::json!({"age_years": (["30.0", "50.0"][k]), "skin_type": (["I", "III"][k]),
                    "xi": (["0", "0.5"][k]), "params_json": "{\"gender\":\"female\"}"}),
            );
            let edges = vec![0.0, 0.1, 0.3, 0.6];
            let centres = vec![0.05, 0.2, 0.45];
            let rd = vec![3.0, 2.0, 1.0, 1.5, 1.0, 0.5, 0.3, 0.2, 0.1];
            for a in [
                Array::new_f64(format!("{name}/r_mm"), vec![3], centres),
                Array::new_f64(format!("{name}/r_edges_mm"), vec![4], edges),
                Array::new_f64(format!("{name}/rd_rgb_per_mm2"), vec![3, 3], rd),
                Array::new_f64(format!("{name}/albedo_rgb"), vec![3], vec![0.5, 0.4, 0.3]),
                Array::new_f64(
                    format!("{name}/gaussians/variance_mm2"),
                    vec![1],
                    vec![0.04],
                ),
                Array::new_f64(
                    format!("{name}/gaussians/weight_rgb"),
                    vec![1, 3],
                    vec![0.5, 0.4, 0.3],
                ),
                Array::new_f64(format!("{name}/gaussians/error_rgb"), vec![3], vec![0.1; 3]),
            ] {
                t.push(a.unwrap()).unwrap();
            }
        }
        t.metadata = serde_json::json!({
            "entries": serde_json::to_string(&names).unwrap(), "groups": groups});
        ProfileTable::from_bytes(t.to_bytes(1).unwrap()).unwrap()
    }

    #[test]
    fn interpolation_follows_the_documented_rule() {
        let t = table();
        let n = "typeI_age30_xi0";
        // Constant to the first centre, linear between centres, constant to the last edge.
        assert_eq!(t.rd_rgb(n, 0.0).unwrap(), [3.0, 2.0, 1.0]);
        assert_eq!(t.rd_rgb(n, 0.05).unwrap(), [3.0, 2.0, 1.0]);
        let mid = t.rd_rgb(n, 0.125).unwrap();
        for (c, want) in [2.25, 1.5, 0.75].iter().enumerate() {
            assert!((mid[c] - want).abs() < 1e-12, "{mid:?}");
        }
        assert_eq!(t.rd_rgb(n, 0.5).unwrap(), [0.3, 0.2, 0.1]);
        assert_eq!(t.rd_rgb(n, 0.61).unwrap(), [0.0; 3]);
        assert_eq!(t.rd_rgb(n, f64::NAN).unwrap(), [0.0; 3]);
    }

    #[test]
    fn lookup_by_parameters_and_gaussians() {
        let t = table();
        assert_eq!(t.entries().len(), 2);
        let e = t
            .lookup(&[("skin_type", "III"), ("age_years", "50")])
            .unwrap();
        assert_eq!(e.name, "typeIII_age50_xi0.5");
        assert_eq!(t.find(&[("gender", "female")]).len(), 2);
        assert!(t.lookup(&[("gender", "female")]).is_err());
        assert!(t.lookup(&[("skin_type", "VII")]).is_err());
        assert!(t.rd_rgb("nope", 0.1).is_err());
        let g = t.gaussians(&e.name).unwrap();
        // One Gaussian of weight w integrates to w: check the peak value w/(2πv).
        let peak = g.eval(0.0);
        assert!((peak[0] - 0.5 / (std::f64::consts::TAU * 0.04)).abs() < 1e-12);
        assert_eq!(t.albedo_rgb(&e.name).unwrap(), [0.5, 0.4, 0.3]);
    }
}
