//! The tables of one fiber entry being written: per table (each cross-section, and their
//! average) a streaming `.bcsdf` writer and a group of the entry's HDF5 file, filled one
//! incoming direction at a time (layout: formats/FORMAT.md, "Fiber BCSDF tables").

use hdf5_metno as h5;

use super::gamut::ClipStats;
use crate::fiber::slices::{BakeSettings, SliceResult};
use crate::fiber::AngularGrid;
use crate::output::hdf5 as h5out;
use crate::spec::fiber::ZstdLevel;
use formats::bcsdf::{self, Directory, Writer, KIND};

/// The shape of an entry's tables and what every table's directory holds.
pub struct Layout<'a> {
    pub grid: &'a AngularGrid,
    pub st: &'a BakeSettings,
    /// Stored incoming directions, (θi, φi) in degrees.
    pub wi_deg: &'a [[f64; 2]],
    /// Full grid → stored direction (and flips).
    pub map: &'a [u32],
    pub variants: &'a [String],
    /// Channel names of one variant.
    pub channels: &'a [String],
    /// Bin centres of φ (and Δφ), degrees.
    pub phi_centres: &'a [f64],
    /// Rounding error allowed per value, as a fraction of its bin's standard error (0: off).
    pub quantise_to_se: f64,
    pub zstd_level: ZstdLevel,
}

/// `zstd_level: auto`: the level of a slice that took `photons` for `raw_bytes` of stored
/// values. Measured on 2 cores (silk and polyester slices, f16): zstd costs about 0.17, 0.06,
/// 0.009, 0.0035 and 0.0012 µs per raw byte at levels 19, 15, 9, 5 and 1, and tracing at
/// least 0.4 µs per photon (polyester, plain), so each level is taken where it costs at
/// most about 3 % of the slice's tracing. Levels 15–19 save 10–15 % of the size of
/// thesis-noise tables over 9; a wide sweep at few photons gets level 1 (5 % larger than 9,
/// seven times faster). Deterministic: the photons a slice takes do not depend on timing.
pub fn auto_zstd_level(photons: u64, raw_bytes: usize) -> i32 {
    let per_byte = photons as f64 / raw_bytes.max(1) as f64;
    match per_byte {
        r if r >= 13.0 => 19,
        r if r >= 5.0 => 15,
        r if r >= 0.8 => 9,
        r if r >= 0.25 => 5,
        _ => 1,
    }
}

impl Layout<'_> {
    fn n_wi(&self) -> usize {
        self.wi_deg.len()
    }

    /// The streaming `.bcsdf` writer of one table of this layout (its directory without
    /// slices), at the spec's zstd level (`auto` sets it per slice, [`push_slice`]).
    pub fn writer(&self, area_um: Vec<f64>, metadata: serde_json::Value) -> Writer {
        let (grid, st) = (self.grid, self.st);
        let dir = Directory {
            kind: KIND.into(),
            res_deg: st.res_deg,
            n_theta: grid.n_theta,
            n_phi: grid.n_phi,
            wi_deg: self.wi_deg.to_vec(),
            wi_map: self.map.to_vec(),
            variants: self.variants.to_vec(),
            channels: self.channels.to_vec(),
            dtype: st.precision,
            keep_bits: st.keep_bits,
            scale: vec![],
            albedo: vec![],
            albedo_se: vec![],
            area_um,
            chunks: vec![],
            metadata,
        };
        let level = match self.zstd_level {
            ZstdLevel::Level(z) => z,
            ZstdLevel::Auto => 9,
        };
        Writer::new(dir, level)
    }
}

/// One table being written: streaming file and HDF5 group.
pub struct TableOut {
    pub name: String,
    writer: Writer,
    f: h5::Dataset,
    cdf_theta: h5::Dataset,
    cdf_phi: h5::Dataset,
    albedo: Vec<f32>,
    albedo_se: Vec<f32>,
    /// Per stored direction: photons launched, and the slice's noise (median and thesis
    /// relative error; NaN for an average of sections, which has no batches of its own).
    photons: Vec<u64>,
    noise: Vec<[f32; 2]>,
    group: h5::Group,
    quantise_to_se: f64,
    zstd_level: ZstdLevel,
}

/// Writes the file-level attributes of an entry's HDF5 file.
pub fn file_attrs(file: &h5::File, attrs: &[(&str, &str)]) -> anyhow::Result<()> {
    for (k, v) in attrs {
        h5out::text_attr(file, k, v)?;
    }
    h5out::text_attr(
        file,
        "description",
        "Tabulated fiber BCSDFs (Aliaga et al. 2017 / thesis ch. 5). f = albedo * f_normalised, \
         sr^-1; fiber axis +z, theta = asin(w.z), phi = atan2(w.y, w.x), dphi = phi_o - phi_i. \
         Layout: formats/FORMAT.md, section 'Fiber BCSDF tables'.",
    )
}

impl TableOut {
    /// Table `name` with its directory: the group, its chunked datasets and the writer.
    pub fn create(
        file: &h5::File,
        name: &str,
        l: &Layout,
        area_um: Vec<f64>,
        metadata: serde_json::Value,
    ) -> anyhow::Result<TableOut> {
        let grid = l.grid;
        let (n_wi, nv, nc) = (l.n_wi(), l.variants.len(), l.channels.len());
        let (nt, np) = (grid.n_theta, grid.n_phi);
        let g = h5out::group(file, name)?;
        let f = h5out::chunked::<f32>(
            &g,
            "f_normalised",
            &[n_wi, nv, nc, nt, np],
            &[1, nv, nc, nt, np],
        )?;
        h5out::text_attr(&f, "units", "sr^-1")?;
        h5out::text_attr(&f, "description", "BCSDF normalised to one per incoming direction (sum of f * solid angle = 1); decoded values of the .bcsdf file")?;
        let cdf_theta = h5out::chunked::<f32>(&g, "cdf_theta", &[n_wi, nv, nt], &[1, nv, nt])?;
        h5out::text_attr(
            &cdf_theta,
            "description",
            "sampling CDF over theta_o rows (density = mean of channels)",
        )?;
        let cdf_phi = h5out::chunked::<f32>(&g, "cdf_phi", &[n_wi, nv, nt, np], &[1, nv, nt, np])?;
        h5out::text_attr(
            &cdf_phi,
            "description",
            "sampling CDF over dphi within each theta_o row",
        )?;
        Ok(TableOut {
            name: name.to_string(),
            writer: l.writer(area_um, metadata),
            f,
            cdf_theta,
            cdf_phi,
            albedo: vec![f32::NAN; n_wi * nv * nc],
            albedo_se: vec![f32::NAN; n_wi * nv * nc],
            photons: vec![0; n_wi],
            noise: vec![[f32::NAN; 2]; n_wi],
            group: g,
            quantise_to_se: l.quantise_to_se,
            zstd_level: l.zstd_level,
        })
    }

    /// Stored direction `i`'s slice (in any order, each once): encoded into the stream,
    /// decoded values and sampling CDFs into the HDF5 group; what the direction reached
    /// (`photons` launched for it, and the slice's own noise when it was traced, not
    /// averaged) into its records.
    pub fn push(
        &mut self,
        i: usize,
        r: &SliceResult,
        grid: &AngularGrid,
        photons: u64,
        traced: bool,
    ) -> anyhow::Result<()> {
        let (nt, np) = (grid.n_theta, grid.n_phi);
        let nv = self.writer.dir.variants.len();
        let decoded = push_slice_at(
            &mut self.writer,
            i,
            r,
            grid,
            self.quantise_to_se,
            self.zstd_level,
        )?;
        let nvc = r.albedo.len();
        let at = i * nvc..(i + 1) * nvc;
        for (a, &x) in self.albedo[at.clone()].iter_mut().zip(&r.albedo) {
            *a = x as f32;
        }
        for (a, &x) in self.albedo_se[at].iter_mut().zip(&r.albedo_se) {
            *a = x as f32;
        }
        self.photons[i] = photons;
        self.noise[i] = match traced && r.noise.bins > 0 {
            true => [r.noise.median_rel_se as f32, r.noise.thesis_rel_se as f32],
            false => [f32::NAN; 2],
        };
        h5out::write_chunk_f32(&self.f, &[i, 0, 0, 0, 0], &decoded)?;
        let (ct, cp, _) = bcsdf::sampling_cdfs(&self.writer.dir, &decoded);
        let ct: Vec<f32> = ct.iter().flatten().map(|&x| x as f32).collect();
        let cp: Vec<f32> = cp.iter().flatten().map(|&x| x as f32).collect();
        debug_assert_eq!((ct.len(), cp.len()), (nv * nt, nv * nt * np));
        h5out::write_chunk_f32(&self.cdf_theta, &[i, 0, 0], &ct)?;
        h5out::write_chunk_f32(&self.cdf_phi, &[i, 0, 0, 0], &cp)?;
        Ok(())
    }

    /// The axes, albedo, area and map datasets with their scales, and what the RGB gamut
    /// mapping did to the table (`clip`, `None` for spectral tables: in the directory's
    /// metadata and the group's attributes); then the streaming file's bytes.
    pub fn finish(
        mut self,
        l: &Layout,
        clip: Option<&ClipStats>,
    ) -> anyhow::Result<(String, Vec<u8>)> {
        let grid = l.grid;
        let clip = serde_json::to_value(clip)?;
        h5out::text_attr(&self.group, "rgb_gamut_clip", &clip.to_string())?;
        h5out::text_attr(
            &self.group,
            "quantise_to_se",
            &self.quantise_to_se.to_string(),
        )?;
        self.writer.dir.metadata["rgb_gamut_clip"] = clip;
        let (n_wi, nv, nc) = (l.n_wi(), l.variants.len(), l.channels.len());
        let g = &self.group;
        let albedo = h5out::array(g, "albedo", &[n_wi, nv, nc], &self.albedo)?;
        h5out::text_attr(
            &albedo,
            "description",
            "directional albedo Lambda(w_i): fraction of the intercepted power that leaves",
        )?;
        let albedo_se = h5out::array(g, "albedo_se", &[n_wi, nv, nc], &self.albedo_se)?;
        let photons = h5out::array(g, "photons", &[n_wi], &self.photons)?;
        h5out::text_attr(&photons, "description", "photons launched for each stored incoming direction (an average of sections: their sum); adaptive allocation (target_rel_se) sets it per direction")?;
        let median: Vec<f32> = self.noise.iter().map(|n| n[0]).collect();
        let median = h5out::array(g, "median_rel_se", &[n_wi], &median)?;
        h5out::text_attr(&median, "description", "median over the bins with density >= 1 % of the slice's maximum of the per-bin relative standard error of the sampling density (variant 0); NaN for an average of sections")?;
        let thesis: Vec<f32> = self.noise.iter().map(|n| n[1]).collect();
        let thesis = h5out::array(g, "thesis_rel_se", &[n_wi], &thesis)?;
        h5out::text_attr(&thesis, "description", "the same median for plain sampling with 16 M photons (the thesis's noise): a direction reached it where median_rel_se <= thesis_rel_se")?;
        let area = h5out::array(g, "area_um", &[grid.n_phi], &self.writer.dir.area_um)?;
        h5out::text_attr(&area, "units", "um")?;
        h5out::text_attr(&area, "description", "projected width per unit length seen from azimuth phi (A(w) of Eq. 17 before sin(w, w_f))")?;
        let wmap = h5out::array(g, "wi_map", &[grid.n_theta, grid.n_phi], l.map)?;
        h5out::text_attr(&wmap, "description", "full (theta_i, phi_i) grid -> stored index | 2^31 (theta_o flips sign) | 2^30 (dphi flips sign)")?;
        let th_i = h5out::array(
            g,
            "theta_i_deg",
            &[n_wi],
            &l.wi_deg.iter().map(|w| w[0]).collect::<Vec<_>>(),
        )?;
        let ph_i = h5out::array(
            g,
            "phi_i_deg",
            &[n_wi],
            &l.wi_deg.iter().map(|w| w[1]).collect::<Vec<_>>(),
        )?;
        let theta_o: Vec<f64> = (0..grid.n_theta)
            .map(|i| grid.theta_centre_deg(i))
            .collect();
        let th_o = h5out::array(g, "theta_o_deg", &[grid.n_theta], &theta_o)?;
        let dphi = h5out::array(g, "dphi_deg", &[grid.n_phi], l.phi_centres)?;
        let phi = h5out::array(g, "phi_deg", &[grid.n_phi], l.phi_centres)?;
        let var = h5out::strings(g, "variant", l.variants)?;
        let ch = h5out::strings(g, "channel", l.channels)?;
        let (f, ct, cp) = (&self.f, &self.cdf_theta, &self.cdf_phi);
        for (d, u) in [
            (&th_i, "degree"),
            (&ph_i, "degree"),
            (&th_o, "degree"),
            (&dphi, "degree"),
            (&phi, "degree"),
            (&albedo, "1"),
            (&albedo_se, "1"),
            (&photons, "1"),
            (&median, "1"),
            (&thesis, "1"),
            (ct, "1"),
            (cp, "1"),
            (&wmap, "1"),
        ] {
            h5out::text_attr(d, "units", u)?;
        }
        for (scale, name) in [(&th_i, "theta_i_deg"), (&ph_i, "phi_i_deg")] {
            h5out::attach_scale(
                scale,
                name,
                &[
                    (f, 0),
                    (&albedo, 0),
                    (&albedo_se, 0),
                    (&photons, 0),
                    (&median, 0),
                    (&thesis, 0),
                    (ct, 0),
                    (cp, 0),
                ],
            )?;
        }
        h5out::attach_scale(
            &var,
            "variant",
            &[(f, 1), (&albedo, 1), (&albedo_se, 1), (ct, 1), (cp, 1)],
        )?;
        h5out::attach_scale(&ch, "channel", &[(f, 2), (&albedo, 2), (&albedo_se, 2)])?;
        h5out::attach_scale(
            &th_o,
            "theta_o_deg",
            &[(f, 3), (ct, 2), (cp, 2), (&wmap, 0)],
        )?;
        h5out::attach_scale(&dphi, "dphi_deg", &[(f, 4), (cp, 3)])?;
        h5out::attach_scale(&phi, "phi_deg", &[(&area, 0), (&wmap, 1)])?;
        self.writer.dir.albedo = std::mem::take(&mut self.albedo);
        self.writer.dir.albedo_se = std::mem::take(&mut self.albedo_se);
        let bytes = self.writer.finish()?;
        Ok((self.name, bytes))
    }
}

/// Encodes slice `r` into `w` as a table stores it: each value rounded within
/// `quantise_to_se` of its bin's standard error ([`noise_tolerance`]), compressed at
/// `zstd_level` (`auto`: [`auto_zstd_level`] of the photons the slice took). Returns the
/// decoded values.
pub fn push_slice(
    w: &mut Writer,
    r: &SliceResult,
    grid: &AngularGrid,
    quantise_to_se: f64,
    zstd_level: ZstdLevel,
) -> anyhow::Result<Vec<f32>> {
    let next = w.frame_bytes().count();
    push_slice_at(w, next, r, grid, quantise_to_se, zstd_level)
}

/// [`push_slice`] as stored direction `i` (in any order, [`Writer::push_within_at`]).
pub fn push_slice_at(
    w: &mut Writer,
    i: usize,
    r: &SliceResult,
    grid: &AngularGrid,
    quantise_to_se: f64,
    zstd_level: ZstdLevel,
) -> anyhow::Result<Vec<f32>> {
    let nc = w.dir.channels.len();
    let tol = noise_tolerance(r, nc, grid.bins(), quantise_to_se);
    if zstd_level == ZstdLevel::Auto {
        let raw_bytes = w.dir.variants.len() * nc * grid.bins() * w.dir.dtype.size();
        w.set_level(auto_zstd_level(r.launched, raw_bytes));
    }
    Ok(w.push_within_at(i, &r.normalised(grid), tol.as_deref())?)
}

/// The relative rounding tolerance of every bin of `r`'s slice (θo × Δφ): `q` times the
/// bin's relative standard error, that of variant 0's density (its fraction averaged over
/// its `nc` channels, [`SliceResult::density_se`]), shared by every variant and channel of
/// the bin. Zero (full precision) where the density or its error is zero; `None` when `q`
/// is zero or the slice carries no per-bin errors.
pub fn noise_tolerance(r: &SliceResult, nc: usize, bins: usize, q: f64) -> Option<Vec<f64>> {
    if q <= 0.0 || r.density_se.len() != bins {
        return None;
    }
    Some(
        (0..bins)
            .map(|b| {
                let d = (0..nc).map(|c| r.fraction[c * bins + b]).sum::<f64>() / nc as f64;
                let se = r.density_se[b];
                if d > 0.0 && se > 0.0 {
                    q * se / d
                } else {
                    0.0
                }
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fiber::slices::Noise;

    /// q × SE / density of variant 0 (mean of its channels), per bin; exact zeros where
    /// there is no density or no error; nothing when off or without per-bin errors.
    #[test]
    fn tolerance_is_a_fraction_of_variant_0s_relative_error() {
        let bins = 4;
        let r = SliceResult {
            // Variant 0: channels 0, 1; variant 1: channels 2, 3.
            fraction: vec![
                0.2, 0.0, 0.4, 0.1, //
                0.6, 0.0, 0.4, 0.3, //
                9.0, 9.0, 9.0, 9.0, //
                9.0, 9.0, 9.0, 9.0,
            ],
            albedo: vec![0.7, 1.3, 36.0, 36.0],
            albedo_se: vec![0.0; 4],
            density_se: vec![0.04, 0.01, 0.0, 0.02],
            dphi_se: vec![],
            noise: Noise::default(),
            launched: 1,
            intercepted: 1,
            lost_weight: 0.0,
            seconds: 0.0,
        };
        let t = noise_tolerance(&r, 2, bins, 0.25).unwrap();
        let want = [0.25 * 0.04 / 0.4, 0.0, 0.0, 0.25 * 0.02 / 0.2];
        for (a, b) in t.iter().zip(want) {
            assert!((a - b).abs() < 1e-15, "{t:?}");
        }
        assert!(noise_tolerance(&r, 2, bins, 0.0).is_none());
        let old = SliceResult {
            density_se: vec![],
            dphi_se: vec![],
            ..r
        };
        assert!(noise_tolerance(&old, 2, bins, 0.25).is_none());
    }
}
