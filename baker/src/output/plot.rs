//! PNG plots of μa(λ) and μs′(λ) per layer (like thesis Figs. 35 right and 39 right).

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use formats::OpticsEntry;

static FONT: Once = Once::new();

/// DejaVu Sans (Bitstream Vera licence, see assets/fonts), embedded so plots need no system fonts.
pub(crate) fn ensure_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
        if register_font("sans-serif", FontStyle::Normal, bytes).is_err() {
            panic!("embedded font failed to load");
        }
    });
}

const COLORS: [RGBColor; 5] = [
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 158, 115),
    RGBColor(213, 94, 0),
    RGBColor(0, 114, 178),
];

/// Which coefficient to draw.
#[derive(Clone, Copy)]
pub enum Quantity {
    Absorption,
    ReducedScattering,
}

/// Renders one plot of `q` for every layer of `e` to the PNG file `path` (written atomically).
pub fn plot(path: &Path, lambda_nm: &[f64], e: &OpticsEntry, q: Quantity) -> anyhow::Result<()> {
    ensure_font();
    let (w, h) = (900u32, 600u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let series: Vec<(&str, &[f64])> = e
            .layers
            .iter()
            .map(|l| {
                let v: &[f64] = match q {
                    Quantity::Absorption => &l.mua_per_mm,
                    Quantity::ReducedScattering => &l.musp_per_mm,
                };
                (l.name.as_str(), v)
            })
            .collect();
        let positive = series
            .iter()
            .flat_map(|s| s.1.iter())
            .copied()
            .filter(|v| *v > 0.0);
        let lo = positive.clone().fold(f64::INFINITY, f64::min).max(1e-6);
        let hi = positive.fold(0.0, f64::max).max(lo * 10.0);
        let (ylo, yhi) = (
            10f64.powf(lo.log10().floor()),
            10f64.powf(hi.log10().ceil()),
        );
        let (x0, x1) = (lambda_nm[0], *lambda_nm.last().unwrap());
        let (title, ylabel) = match q {
            Quantity::Absorption => ("absorption", "μa (1/mm)"),
            Quantity::ReducedScattering => ("reduced scattering", "μs′ (1/mm)"),
        };
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("{} — {title}", e.name), ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1.max(x0 + 1.0), (ylo..yhi).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("wavelength (nm)")
            .y_desc(ylabel)
            .label_style(("sans-serif", 15))
            .draw()?;
        for (k, (name, values)) in series.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            chart
                .draw_series(LineSeries::new(
                    lambda_nm
                        .iter()
                        .zip(values.iter())
                        .map(|(&x, &y)| (x, y.max(ylo))),
                    color.stroke_width(2),
                ))?
                .label(*name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()?;
        root.present()?;
    }
    write_png(path, w, h, buf)
}

/// Encodes an RGB8 buffer of `w`×`h` pixels (what plotters draws with
/// `BitMapBackend::with_buffer`) as PNG with `image` and writes it atomically: every PNG the
/// baker writes goes through here.
pub(crate) fn write_png(path: &Path, w: u32, h: u32, buf: Vec<u8>) -> anyhow::Result<()> {
    let mut png = Vec::new();
    let img = image::RgbImage::from_raw(w, h, buf).expect("buffer size matches");
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)?;
    crate::output::atomic::write(path, &png)?;
    Ok(())
}

/// `<entry>_mua.png` and `<entry>_musp.png` of every entry into `dir`; returns their paths.
pub fn optics_plots(
    dir: &Path,
    lambda_nm: &[f64],
    entries: &[OpticsEntry],
) -> anyhow::Result<Vec<std::path::PathBuf>> {
    use anyhow::Context as _;
    let mut written = Vec::new();
    for e in entries {
        for (q, suffix) in [
            (Quantity::Absorption, "mua"),
            (Quantity::ReducedScattering, "musp"),
        ] {
            let p = dir.join(format!("{}_{suffix}.png", e.name));
            plot(&p, lambda_nm, e, q).with_context(|| format!("plotting {}", p.display()))?;
            written.push(p);
        }
    }
    Ok(written)
}
