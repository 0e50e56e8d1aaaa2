//! [`Tables`] in the native zstd format of the `formats` crate (`.bkt`), array names
//! `<group>/<dataset>`, attributes `units` and `description`; root attributes become the
//! file's JSON metadata, group attributes `<group>/@<name>` metadata entries.

use std::path::Path;

use anyhow::Context;
use formats::table::{Array, TableFile, DEFAULT_ZSTD_LEVEL};

use super::atomic;
use super::tables::Tables;

/// The `kind` of a skin-profile table file.
pub const KIND: &str = "skin_profiles";

pub fn to_table_file(t: &Tables) -> anyhow::Result<TableFile> {
    let mut meta = serde_json::Map::new();
    for (k, v) in &t.attrs {
        meta.insert(k.clone(), v.to_json());
    }
    let mut groups = serde_json::Map::new();
    for g in &t.groups {
        let attrs: serde_json::Map<String, serde_json::Value> = g
            .attrs
            .iter()
            .map(|(k, v)| (k.clone(), v.to_json()))
            .collect();
        groups.insert(g.name.clone(), serde_json::Value::Object(attrs));
    }
    meta.insert("groups".into(), serde_json::Value::Object(groups));
    let mut f = TableFile::new(KIND, serde_json::Value::Object(meta));
    for g in &t.groups {
        for d in &g.datasets {
            let a = Array::new_f64(
                format!("{}/{}", g.name, d.name),
                d.shape.iter().map(|&n| n as u64).collect(),
                d.data.clone(),
            )
            .map_err(|e| anyhow::anyhow!("{}/{}: {e}", g.name, d.name))?
            .with_attr("units", d.units)
            .with_attr("description", d.description);
            let a = match &d.labels {
                Some(l) => a.with_attr(l.attr, l.names.join(",")),
                None => a,
            };
            f.push(a).map_err(|e| anyhow::anyhow!("{e}"))?;
        }
    }
    Ok(f)
}

pub fn write(path: &Path, t: &Tables) -> anyhow::Result<()> {
    let bytes = to_table_file(t)?
        .to_bytes(DEFAULT_ZSTD_LEVEL)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    atomic::write(path, &bytes).with_context(|| format!("writing {}", path.display()))
}
