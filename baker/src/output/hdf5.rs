//! HDF5 writer for [`Tables`]: one group per entry, f64 datasets (shuffle + deflate), `units`
//! and `description` attributes, and HDF5 dimension scales (`r_mm`, `lambda_nm`) so h5py shows
//! `ds.dims[i][0]`. Written to a temporary file and renamed: a reader never sees half a file.
//! Creation times are not recorded, so equal tables give equal files.

use std::ffi::CString;
use std::path::Path;
use std::str::FromStr;

use anyhow::Context;
use hdf5_metno as h5;
use hdf5_metno::types::VarLenUnicode;
use hdf5_metno_sys::h5i::hid_t;

use super::tables::{Attr, Dataset, Tables};

// The HDF5 high-level dimension-scale API (libhdf5_hl); hdf5-metno does not wrap it.
extern "C" {
    fn H5DSset_scale(dsid: hid_t, dimname: *const std::ffi::c_char) -> i32;
    fn H5DSattach_scale(did: hid_t, dsid: hid_t, idx: std::ffi::c_uint) -> i32;
}

pub(crate) fn text_attr(loc: &h5::Location, name: &str, value: &str) -> anyhow::Result<()> {
    let v = VarLenUnicode::from_str(value).map_err(|e| anyhow::anyhow!("attribute {name}: {e}"))?;
    loc.new_attr::<VarLenUnicode>()
        .create(name)?
        .write_scalar(&v)?;
    Ok(())
}

fn attr(loc: &h5::Location, name: &str, value: &Attr) -> anyhow::Result<()> {
    match value {
        Attr::Text(s) => text_attr(loc, name, s),
        Attr::Float(x) => Ok(loc.new_attr::<f64>().create(name)?.write_scalar(x)?),
        Attr::Count(n) => Ok(loc.new_attr::<u64>().create(name)?.write_scalar(n)?),
    }
}

fn write_dataset(g: &h5::Group, d: &Dataset) -> anyhow::Result<h5::Dataset> {
    let (parent, leaf) = match d.name.rsplit_once('/') {
        Some((p, l)) => {
            let pg = match g.group(p) {
                Ok(x) => x,
                Err(_) => g.create_group_builder().obj_track_times(false).create(p)?,
            };
            (pg, l)
        }
        None => (g.clone(), d.name.as_str()),
    };
    let ds = if d.shape.is_empty() {
        let ds = parent
            .new_dataset::<f64>()
            .obj_track_times(false)
            .shape(())
            .create(leaf)?;
        ds.write_scalar(&d.data[0])?;
        ds
    } else {
        let b = parent
            .new_dataset::<f64>()
            .obj_track_times(false)
            .shape(d.shape.clone());
        let b = if d.data.len() >= 64 {
            b.shuffle().deflate(6)
        } else {
            b
        };
        let ds = b.create(leaf)?;
        ds.write_raw(&d.data[..])?;
        ds
    };
    text_attr(&ds, "units", d.units)?;
    text_attr(&ds, "description", d.description)?;
    if let Some(l) = &d.labels {
        let v: Vec<VarLenUnicode> = l
            .names
            .iter()
            .map(|s| VarLenUnicode::from_str(s).map_err(|e| anyhow::anyhow!("{}: {e}", l.attr)))
            .collect::<anyhow::Result<_>>()?;
        ds.new_attr::<VarLenUnicode>()
            .shape([v.len()])
            .create(l.attr)?
            .write(&v)?;
    }
    Ok(ds)
}

/// Makes `scale` an HDF5 dimension scale named `name` and attaches it to dimension `dim`
/// of each dataset in `targets`.
pub(crate) fn attach_scale(
    scale: &h5::Dataset,
    name: &str,
    targets: &[(&h5::Dataset, u32)],
) -> anyhow::Result<()> {
    let label = CString::new(name)?;
    let rc = h5::sync::sync(|| unsafe { H5DSset_scale(scale.id(), label.as_ptr()) });
    anyhow::ensure!(rc >= 0, "H5DSset_scale({name}) failed");
    for (ds, dim) in targets {
        let rc = h5::sync::sync(|| unsafe { H5DSattach_scale(ds.id(), scale.id(), *dim) });
        anyhow::ensure!(rc >= 0, "H5DSattach_scale({name}) failed");
    }
    Ok(())
}

/// Writes `t` to `path` atomically.
pub fn write(path: &Path, t: &Tables) -> anyhow::Result<()> {
    super::atomic::write_with(path, |tmp| write_to(tmp, t))
        .with_context(|| format!("writing {}", path.display()))
}

fn write_to(path: &Path, t: &Tables) -> anyhow::Result<()> {
    let f = h5::File::with_options()
        .with_fcpl(|p| p.obj_track_times(false))
        .create(path)?;
    for (k, v) in &t.attrs {
        attr(&f, k, v)?;
    }
    for grp in &t.groups {
        let g = f
            .create_group_builder()
            .obj_track_times(false)
            .create(grp.name.as_str())?;
        for (k, v) in &grp.attrs {
            attr(&g, k, v)?;
        }
        let mut written = Vec::new();
        for d in &grp.datasets {
            written.push((d, write_dataset(&g, d)?));
        }
        // Dimension scales: every dataset some dimension names becomes a scale, once.
        let mut scales: Vec<&str> = written
            .iter()
            .flat_map(|(d, _)| d.dims.iter().flatten().copied())
            .collect();
        scales.sort_unstable();
        scales.dedup();
        for s in &scales {
            let Some((_, sd)) = written.iter().find(|(d, _)| d.name == *s) else {
                continue;
            };
            let label = CString::new(*s)?;
            let rc = h5::sync::sync(|| unsafe { H5DSset_scale(sd.id(), label.as_ptr()) });
            anyhow::ensure!(rc >= 0, "H5DSset_scale({s}) failed");
        }
        for (d, ds) in &written {
            for (i, dim) in d.dims.iter().enumerate() {
                let Some(s) = dim else { continue };
                let Some((_, sd)) = written.iter().find(|(d, _)| d.name == *s) else {
                    continue;
                };
                let rc = h5::sync::sync(|| unsafe { H5DSattach_scale(ds.id(), sd.id(), i as u32) });
                anyhow::ensure!(rc >= 0, "H5DSattach_scale({}, {s}) failed", d.name);
            }
        }
    }
    f.close()?;
    Ok(())
}

/// A new HDF5 file at `path` that records no times (equal contents give equal bytes).
pub fn create_file(path: &Path) -> anyhow::Result<h5::File> {
    Ok(h5::File::with_options()
        .with_fcpl(|p| p.obj_track_times(false))
        .create(path)?)
}

/// A new group `name` of `file`, recording no times.
pub fn group(file: &h5::File, name: &str) -> anyhow::Result<h5::Group> {
    Ok(file
        .create_group_builder()
        .obj_track_times(false)
        .create(name)?)
}

/// A dataset of `shape` in chunks of `chunk`, shuffled and deflated (level 4), recording no
/// times; written slice by slice.
pub fn chunked<T: h5::H5Type>(
    g: &h5::Group,
    name: &str,
    shape: &[usize],
    chunk: &[usize],
) -> anyhow::Result<h5::Dataset> {
    Ok(g.new_dataset::<T>()
        .obj_track_times(false)
        .shape(shape)
        .chunk(chunk)
        .shuffle()
        .deflate(4)
        .create(name)?)
}

/// A contiguous dataset of `shape` holding `data`, recording no times.
pub fn array<T: h5::H5Type>(
    g: &h5::Group,
    name: &str,
    shape: &[usize],
    data: &[T],
) -> anyhow::Result<h5::Dataset> {
    let d = g
        .new_dataset::<T>()
        .obj_track_times(false)
        .shape(shape)
        .create(name)?;
    d.write_raw(data)?;
    Ok(d)
}

/// A 1-D dataset of variable-length strings.
pub fn strings(g: &h5::Group, name: &str, values: &[String]) -> anyhow::Result<h5::Dataset> {
    let v: Vec<VarLenUnicode> = values
        .iter()
        .map(|s| VarLenUnicode::from_str(s).map_err(|e| anyhow::anyhow!("{name}: {e}")))
        .collect::<anyhow::Result<_>>()?;
    array(g, name, &[values.len()], &v)
}
