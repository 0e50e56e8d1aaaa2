//! RGB diffusion profiles as one OpenEXR image: one row per entry (in bake order), one column
//! per radial bin. Channels `R`, `G`, `B`: linear sRGB Rd(r) in mm⁻² (float32, annulus
//! averages); `r_mm`: the bin centre of each column (the same on every row). Header
//! attribute: `entries` (JSON list of entry names, row order); the bin edges are in the HDF5
//! and `.bkt` files. Scan lines in increasing order, ZIP compression (lossless). The same
//! profiles give the same bytes: the exr crate keeps custom attributes in a hash map, so the
//! header holds exactly one.

use std::path::Path;

use anyhow::Context;
use exr::prelude::*;

use super::atomic;

/// Writes `rows` (one `[nr][3]` profile per entry, all on the same `r_edges_mm`) to `path`.
pub fn write(
    path: &Path,
    names: &[String],
    r_edges_mm: &[f64],
    rows: &[&[[f64; 3]]],
) -> anyhow::Result<()> {
    let nr = r_edges_mm.len() - 1;
    anyhow::ensure!(!rows.is_empty(), "no profiles to write");
    anyhow::ensure!(
        rows.iter().all(|r| r.len() == nr),
        "profiles on different grids"
    );
    let (w, h) = (nr, rows.len());
    let channel = |c: usize| -> Vec<f32> {
        rows.iter()
            .flat_map(|r| r.iter().map(move |v| v[c] as f32))
            .collect()
    };
    let centres: Vec<f32> = r_edges_mm
        .windows(2)
        .map(|e| (0.5 * (e[0] + e[1])) as f32)
        .collect();
    let r_mm: Vec<f32> = (0..h).flat_map(|_| centres.iter().copied()).collect();
    let channels = AnyChannels::sort(smallvec::smallvec![
        AnyChannel::new("R", FlatSamples::F32(channel(0))),
        AnyChannel::new("G", FlatSamples::F32(channel(1))),
        AnyChannel::new("B", FlatSamples::F32(channel(2))),
        AnyChannel::new("r_mm", FlatSamples::F32(r_mm)),
    ]);
    let attrs = LayerAttributes {
        comments: Some(Text::from(
            "baker skin diffusion profiles: row = entry (see 'entries'), column = radial bin \
             (see 'r_mm'); R,G,B = linear sRGB Rd(r) in mm^-2",
        )),
        ..LayerAttributes::default()
    };
    let layer = zip_layer((w, h), attrs, channels);
    let mut image = Image::from_layer(layer);
    image.attributes.other.insert(
        Text::from("entries"),
        AttributeValue::Text(Text::from(serde_json::to_string(names)?.as_str())),
    );
    encode_and_write(path, image)
}

/// Writes a linear RGB float image (`w × h`, rows top to bottom) with a comment, ZIP
/// compressed, atomically.
pub fn write_rgb(
    path: &Path,
    w: usize,
    h: usize,
    rgb: [Vec<f32>; 3],
    comment: &str,
) -> anyhow::Result<()> {
    let [r, g, b] = rgb;
    let channels = AnyChannels::sort(smallvec::smallvec![
        AnyChannel::new("R", FlatSamples::F32(r)),
        AnyChannel::new("G", FlatSamples::F32(g)),
        AnyChannel::new("B", FlatSamples::F32(b)),
    ]);
    let attrs = LayerAttributes {
        comments: Some(Text::from(comment)),
        ..LayerAttributes::default()
    };
    let layer = zip_layer((w, h), attrs, channels);
    let image = Image::from_layer(layer);
    encode_and_write(path, image)
}

/// A scan-line layer with lossless ZIP compression, lines in increasing order.
fn zip_layer(
    size: (usize, usize),
    attrs: LayerAttributes,
    channels: AnyChannels<FlatSamples>,
) -> Layer<AnyChannels<FlatSamples>> {
    Layer::new(
        size,
        attrs,
        Encoding {
            compression: Compression::ZIP16,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        },
        channels,
    )
}

/// Encodes `image` in memory and writes it atomically.
fn encode_and_write(
    path: &Path,
    image: Image<Layer<AnyChannels<FlatSamples>>>,
) -> anyhow::Result<()> {
    let mut buf = std::io::Cursor::new(Vec::new());
    image
        .write()
        .non_parallel()
        .to_buffered(&mut buf)
        .map_err(|e| anyhow::anyhow!("encoding {}: {e}", path.display()))?;
    atomic::write(path, buf.get_ref()).with_context(|| format!("writing {}", path.display()))
}
