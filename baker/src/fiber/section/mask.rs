//! Cross-sections from binary mask images (a segmented SEM image of a real fiber): contour
//! extraction by marching squares (the `contour` crate, a port of d3-contour), hole detection,
//! Taubin smoothing of the pixel staircase, and scaling by the image's µm per pixel.

use std::path::Path;

use contour::ContourBuilder;

use super::{Polygon, Section, SectionError};

/// A closed outline, pixel or µm coordinates.
type Loop = Vec<[f64; 2]>;

/// How a mask becomes a section.
#[derive(Debug, Clone, Copy)]
pub struct MaskOptions {
    /// Micrometres per pixel.
    pub um_per_px: f64,
    /// Taubin λ|μ smoothing passes on the outline (0 keeps the marching-squares outline).
    pub smoothing_passes: usize,
    /// Holes smaller than this many pixels are treated as segmentation noise and dropped.
    pub min_hole_px: f64,
    /// Largest image, pixels (width × height, from the file's header, before decoding).
    pub max_pixels: u64,
    /// Largest outline, vertices (outer loop and holes).
    pub max_vertices: u64,
}

/// The largest mask image by default, pixels (4096²; a spec's `limits.mask_pixels`).
pub const DEFAULT_MAX_PIXELS: u64 = 4096 * 4096;
/// The largest outline by default, vertices (a spec's `limits.polygon_vertices`).
pub const DEFAULT_MAX_VERTICES: u64 = 100_000;

impl MaskOptions {
    pub fn new(um_per_px: f64) -> Self {
        Self {
            um_per_px,
            smoothing_passes: 4,
            min_hole_px: 4.0,
            max_pixels: DEFAULT_MAX_PIXELS,
            max_vertices: DEFAULT_MAX_VERTICES,
        }
    }
}

/// What was found in a mask besides the section itself.
#[derive(Debug, Clone)]
pub struct MaskReport {
    /// Foreground components other than the largest (ignored), and dropped tiny holes.
    pub ignored_components: usize,
    pub dropped_holes: usize,
    /// True when the image was inverted because its border was bright (dark fiber on light
    /// background).
    pub inverted: bool,
}

/// Reads the PNG (or any format the `image` crate decodes with its enabled features) at `path`.
/// The fiber is the largest connected foreground region; foreground is the side of the 50 %
/// grey threshold that does not cover most of the image border.
pub fn from_mask(path: &Path, o: &MaskOptions) -> Result<(Section, MaskReport), SectionError> {
    let file = path.display().to_string();
    let err = |message: String| SectionError::Mask {
        file: file.clone(),
        message,
    };
    if !(o.um_per_px.is_finite() && o.um_per_px > 0.0) {
        return Err(err(format!(
            "µm per pixel must be > 0, got {}",
            o.um_per_px
        )));
    }
    let bytes = crate::files::read_bytes(path, crate::files::MAX_DATA_BYTES, "a mask image")
        .map_err(|e| err(e.to_string()))?;
    let reader = image::ImageReader::new(std::io::Cursor::new(&bytes))
        .with_guessed_format()
        .map_err(|e| err(format!("cannot read image: {e}")))?;
    // The size its header declares, checked before a pixel is decoded (a 59 KB PNG can
    // declare 22,000 × 22,000 pixels).
    let (w, h) = reader
        .into_dimensions()
        .map_err(|e| err(format!("cannot read image: {e}")))?;
    let pixels = w as u64 * h as u64;
    if pixels > o.max_pixels {
        return Err(err(format!(
            "{w} × {h} = {pixels} pixels, over the limit of {} (`limits.mask_pixels`)",
            o.max_pixels
        )));
    }
    let mut reader = image::ImageReader::new(std::io::Cursor::new(&bytes))
        .with_guessed_format()
        .map_err(|e| err(format!("cannot read image: {e}")))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    // Decoder buffers: the image at up to 16 bytes per pixel (RGBA f32), plus slack.
    limits.max_alloc = Some(16 * pixels + (16 << 20));
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| err(format!("cannot read image: {e}")))?
        .to_luma8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    from_pixels(w, h, img.as_raw(), o).map_err(|e| match e {
        SectionError::Mask { message, .. } => err(message),
        other => other,
    })
}

/// As [`from_mask`], from 8-bit grey pixels in row-major order.
pub fn from_pixels(
    w: usize,
    h: usize,
    px: &[u8],
    o: &MaskOptions,
) -> Result<(Section, MaskReport), SectionError> {
    let err = |message: String| SectionError::Mask {
        file: "<pixels>".into(),
        message,
    };
    if w < 3 || h < 3 || px.len() != w * h {
        return Err(err(format!("image of {w}×{h} pixels is too small")));
    }
    let border: Vec<u8> = (0..w)
        .flat_map(|x| [px[x], px[(h - 1) * w + x]])
        .chain((0..h).flat_map(|y| [px[y * w], px[y * w + w - 1]]))
        .collect();
    let bright_border = border.iter().filter(|&&v| v >= 128).count() * 2 > border.len();
    // Pad by one background pixel so outlines touching the border close.
    let (pw, ph) = (w + 2, h + 2);
    let mut v = vec![0.0f64; pw * ph];
    for y in 0..h {
        for x in 0..w {
            let fg = (px[y * w + x] >= 128) != bright_border;
            v[(y + 1) * pw + x + 1] = if fg { 1.0 } else { 0.0 };
        }
    }
    // The fiber is the largest foreground region: the rest (dust, other fibers) is removed
    // before contouring, whose cost then follows the fiber's own outline, which is bounded
    // first (marching squares puts one vertex on every foreground/background pixel edge).
    let (removed, edges) = keep_largest_region(&mut v, pw, ph);
    if edges as u64 > o.max_vertices {
        return Err(err(format!(
            "the fiber's outline would have {edges} vertices, over the limit of {} \
             (`limits.polygon_vertices`): is the mask a clean binary image?",
            o.max_vertices
        )));
    }
    let contours = ContourBuilder::new(pw, ph, true)
        .contours(&v, &[0.5])
        .map_err(|e| err(format!("contour extraction failed: {e:?}")))?;
    let mut polys: Vec<(f64, Loop, Vec<Loop>)> = Vec::new();
    for c in &contours {
        for p in c.geometry().0.iter() {
            let outer: Vec<[f64; 2]> = p.exterior().0.iter().map(|c| [c.x, c.y]).collect();
            let holes = p
                .interiors()
                .iter()
                .map(|ls| ls.0.iter().map(|c| [c.x, c.y]).collect())
                .collect();
            let area = super::polygon::signed_area(&outer).abs();
            polys.push((area, outer, holes));
        }
    }
    if polys.is_empty() {
        return Err(err("no foreground region found".into()));
    }
    polys.sort_by(|a, b| b.0.total_cmp(&a.0));
    let (_, outer, holes) = polys.remove(0);
    let n_holes = holes.len();
    let holes: Vec<Vec<[f64; 2]>> = holes
        .into_iter()
        .filter(|hl| super::polygon::signed_area(hl).abs() >= o.min_hole_px)
        .collect();
    let report = MaskReport {
        ignored_components: polys.len() + removed,
        dropped_holes: n_holes - holes.len(),
        inverted: bright_border,
    };
    // Pixel → µm, y up (image rows grow downwards).
    let to_um = |l: Vec<[f64; 2]>| -> Vec<[f64; 2]> {
        let l = taubin(l, o.smoothing_passes);
        l.into_iter()
            .map(|p| [p[0] * o.um_per_px, -p[1] * o.um_per_px])
            .collect()
    };
    let vertices = outer.len() + holes.iter().map(Vec::len).sum::<usize>();
    if vertices as u64 > o.max_vertices {
        return Err(err(format!(
            "the outline has {vertices} vertices, over the limit of {} (`limits.polygon_vertices`)",
            o.max_vertices
        )));
    }
    let poly = Polygon::new(to_um(outer), holes.into_iter().map(to_um).collect())?;
    let c = poly.centroid();
    Ok((Section::Polygon(poly.transformed(c, 1.0)?), report))
}

/// Clears every foreground pixel (value 1) of `v` (`w` × `h`) outside its largest 8-connected
/// foreground region; returns how many regions were cleared and the number of
/// foreground/background pixel edges left (4-neighbours).
fn keep_largest_region(v: &mut [f64], w: usize, h: usize) -> (usize, usize) {
    let mut label = vec![0u32; w * h];
    let mut sizes = vec![0usize]; // label 0: none
    let mut stack = Vec::new();
    for start in 0..w * h {
        if v[start] == 0.0 || label[start] != 0 {
            continue;
        }
        let id = sizes.len() as u32;
        let mut size = 0;
        label[start] = id;
        stack.push(start);
        while let Some(i) = stack.pop() {
            size += 1;
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            for dy in -1..=1isize {
                for dx in -1..=1isize {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                        continue;
                    }
                    let j = ny as usize * w + nx as usize;
                    if v[j] != 0.0 && label[j] == 0 {
                        label[j] = id;
                        stack.push(j);
                    }
                }
            }
        }
        sizes.push(size);
    }
    let keep = (1..sizes.len())
        .max_by_key(|&k| (sizes[k], std::cmp::Reverse(k)))
        .unwrap_or(0);
    for (x, l) in v.iter_mut().zip(&label) {
        if *l != 0 && *l as usize != keep {
            *x = 0.0;
        }
    }
    let mut edges = 0;
    for y in 0..h {
        for x in 0..w {
            let a = v[y * w + x];
            if x + 1 < w && v[y * w + x + 1] != a {
                edges += 1;
            }
            if y + 1 < h && v[(y + 1) * w + x] != a {
                edges += 1;
            }
        }
    }
    (sizes.len().saturating_sub(2), edges)
}

/// Taubin (1995) λ|μ smoothing of a closed loop: removes the pixel staircase without the
/// shrinkage of plain Laplacian smoothing.
fn taubin(mut l: Vec<[f64; 2]>, passes: usize) -> Vec<[f64; 2]> {
    if l.len() > 1 && l[0] == l[l.len() - 1] {
        l.pop();
    }
    let n = l.len();
    if n < 4 {
        return l;
    }
    for _ in 0..passes {
        for k in [0.5, -0.53] {
            let prev = l.clone();
            for i in 0..n {
                let (a, b) = (prev[(i + n - 1) % n], prev[(i + 1) % n]);
                for c in 0..2 {
                    l[i][c] = prev[i][c] + k * (0.5 * (a[c] + b[c]) - prev[i][c]);
                }
            }
        }
    }
    l
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mask rendered with 4×4 supersampling of the indicator of `inside`.
    fn render(w: usize, h: usize, inside: impl Fn(f64, f64) -> bool) -> Vec<u8> {
        let mut px = vec![0u8; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut n = 0;
                for sy in 0..4 {
                    for sx in 0..4 {
                        let (fx, fy) = (
                            x as f64 + (sx as f64 + 0.5) / 4.0,
                            y as f64 + (sy as f64 + 0.5) / 4.0,
                        );
                        n += inside(fx, fy) as u32;
                    }
                }
                px[y * w + x] = (n * 255 / 16) as u8;
            }
        }
        px
    }

    #[test]
    fn ellipse_mask_gives_its_area() {
        let (a, b) = (150.0, 90.0);
        let px = render(400, 260, |x, y| {
            ((x - 200.0) / a).powi(2) + ((y - 130.0) / b).powi(2) < 1.0
        });
        let um = 0.05;
        let (s, rep) = from_pixels(400, 260, &px, &MaskOptions::new(um)).unwrap();
        let want = std::f64::consts::PI * a * b * um * um;
        assert!(
            (s.area_um2() / want - 1.0).abs() < 0.005,
            "{} vs {want}",
            s.area_um2()
        );
        assert_eq!(s.hole_count(), 0);
        assert!(!rep.inverted);
        // Long axis along x: widths 2b (light along x) and 2a.
        assert!((s.projected_width_um(0.0) / (2.0 * b * um) - 1.0).abs() < 0.01);
        assert!(
            (s.projected_width_um(std::f64::consts::FRAC_PI_2) / (2.0 * a * um) - 1.0).abs() < 0.01
        );
    }

    #[test]
    fn ring_mask_has_one_hole_and_inverted_masks_work() {
        let ring = |x: f64, y: f64| {
            let r = ((x - 150.0).powi(2) + (y - 150.0).powi(2)).sqrt();
            (50.0..120.0).contains(&r)
        };
        let px = render(300, 300, ring);
        let inv: Vec<u8> = px.iter().map(|v| 255 - v).collect();
        let want = std::f64::consts::PI * (120.0f64.powi(2) - 50.0f64.powi(2));
        for img in [&px, &inv] {
            let (s, _) = from_pixels(300, 300, img, &MaskOptions::new(1.0)).unwrap();
            assert_eq!(s.hole_count(), 1);
            assert!(
                (s.area_um2() / want - 1.0).abs() < 0.005,
                "{}",
                s.area_um2()
            );
            assert!(!s.contains([0.0, 0.0]) && s.contains([85.0, 0.0]));
        }
    }
}
