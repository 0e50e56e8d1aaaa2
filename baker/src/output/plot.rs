//! PNG plots of μa(λ) and μs′(λ) per layer (like thesis Figs. 35 right and 39 right).

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
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

// ---------------------------------------------------------------------------------------
// Heat maps over a fiber's angular grid (the BCSDF previews, thesis Table 8, and the
// `baker fiber trace --png` slice): one shared plotting path for every such figure.

/// Matplotlib's "inferno" colour map sampled at nine stops (van der Walt & Smith, 2015;
/// perceptually uniform, monotone in lightness, readable in grey).
const INFERNO: [[f64; 3]; 9] = [
    [0.0, 0.0, 4.0],
    [31.0, 12.0, 72.0],
    [85.0, 15.0, 109.0],
    [136.0, 34.0, 106.0],
    [186.0, 54.0, 85.0],
    [227.0, 89.0, 51.0],
    [249.0, 140.0, 10.0],
    [249.0, 201.0, 50.0],
    [252.0, 255.0, 164.0],
];

/// The inferno colour of `t` ∈ [0, 1] (clamped), linearly between the stops.
pub fn inferno(t: f64) -> [u8; 3] {
    let x = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * 8.0;
    let i = (x as usize).min(7);
    let f = x - i as f64;
    let mut c = [0u8; 3];
    for k in 0..3 {
        c[k] = (INFERNO[i][k] + f * (INFERNO[i + 1][k] - INFERNO[i][k])).round() as u8;
    }
    c
}

/// A logarithmic colour scale from `max / 10^decades` (darkest) to `max` (brightest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogScale {
    /// The value drawn brightest (the largest value shown; 0 when there is none).
    pub max: f64,
    pub decades: f64,
}

impl LogScale {
    /// The scale of `values`: their largest finite value, `decades` deep.
    pub fn of(values: impl IntoIterator<Item = f64>, decades: f64) -> Self {
        let max = values
            .into_iter()
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        Self { max, decades }
    }

    /// The colour of `v`: inferno over [max/10^decades, max], clamped below; black for
    /// values ≤ 0 (nothing scattered there) and when the scale is empty.
    pub fn colour(&self, v: f64) -> [u8; 3] {
        if v > 0.0 && self.max > 0.0 {
            inferno(1.0 + (v / self.max).log10() / self.decades)
        } else {
            [0, 0, 0]
        }
    }

    /// log10 of the darkest and the brightest value (−decades…0 for an empty scale).
    pub fn log10_range(&self) -> (f64, f64) {
        let hi = if self.max > 0.0 {
            self.max.log10()
        } else {
            0.0
        };
        (hi - self.decades, hi)
    }
}

/// One panel of an [`AngularFigure`]: its caption and one value per bin, θ rows from −90°
/// (row 0) to 90°, φ columns from −180° (column 0) to 180° (row-major, `n_theta × n_phi`).
#[derive(Debug, Clone)]
pub struct Panel {
    pub caption: String,
    pub values: Vec<f64>,
}

/// A grid of θ × φ heat maps on one shared [`LogScale`]: φ (or Δφ) across from −180° to
/// 180°, θ up from −90° to 90°, tick labels in degrees, axis titles, a caption per panel, a
/// title, and a colour bar with its decades on the right.
#[derive(Debug, Clone)]
pub struct AngularFigure {
    pub title: String,
    /// A second, smaller title line (what is drawn and how).
    pub subtitle: String,
    pub x_desc: String,
    pub y_desc: String,
    /// The colour bar's title (quantity and unit), one short line above the bar.
    pub bar_desc: String,
    pub n_theta: usize,
    pub n_phi: usize,
    pub panels: Vec<Panel>,
    /// Panels per row.
    pub cols: usize,
    /// Size of each panel's map in pixels (360° × 180°, so 2:1 keeps degrees square).
    pub map_px: (u32, u32),
    pub decades: f64,
}

/// Where an [`AngularFigure`] drew: the image size, each panel's map as pixel rectangle
/// `[x0, y0, x1, y1)`, and the colour scale.
#[derive(Debug, Clone)]
pub struct Drawn {
    pub size: (u32, u32),
    pub maps: Vec<[i32; 4]>,
    pub scale: LogScale,
}

const PAD: u32 = 12;
const TITLE_H: u32 = 66;
const CAPTION_H: u32 = 26;
const Y_AREA: u32 = 66;
const X_AREA: u32 = 48;
const CELL_RIGHT: u32 = 22;
const CELL_BOTTOM: u32 = 6;
const BAR_W: u32 = 130;
const BAR_LEFT: u32 = 10;
const BAR_PX: u32 = 28;
const BAR_LABELS: u32 = 60;

impl AngularFigure {
    fn rows(&self) -> usize {
        self.panels.len().div_ceil(self.cols.max(1))
    }

    fn cell(&self) -> (u32, u32) {
        (
            Y_AREA + self.map_px.0 + CELL_RIGHT,
            CAPTION_H + self.map_px.1 + X_AREA + CELL_BOTTOM,
        )
    }

    /// Width and height of the image, pixels: a fixed frame around `cols × rows` maps of
    /// `map_px` each (independent of the table's resolution).
    pub fn size(&self) -> (u32, u32) {
        let (cw, ch) = self.cell();
        (
            PAD + self.cols as u32 * cw + BAR_W,
            TITLE_H + self.rows() as u32 * ch + PAD,
        )
    }
}

/// `10ⁿ` with superscript digits (DejaVu Sans has them).
fn power_of_ten(n: i64) -> String {
    const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::from("10");
    if n < 0 {
        s.push('⁻');
    }
    for d in n.unsigned_abs().to_string().bytes() {
        s.push(SUP[(d - b'0') as usize]);
    }
    s
}

/// A positive value to three significant digits, plainly from 0.001 up to 10⁵ and as
/// `a.bc×10ⁿ` beyond (a true minus sign in the exponent).
fn three_digits(v: f64) -> String {
    let e = v.log10().floor() as i64;
    if (-3..5).contains(&e) {
        format!("{v:.*}", (2 - e).max(0) as usize)
    } else {
        format!("{:.2}×{}", v / 10f64.powi(e as i32), power_of_ten(e))
    }
}

/// Degrees as a tick label, with a true minus sign.
fn degrees(v: &i32) -> String {
    let r = *v;
    if r < 0 {
        format!("−{}°", -r)
    } else {
        format!("{r}°")
    }
}

/// The largest value of the bins that pixel `k` of `n_px` covers along an axis of `n_bins`
/// bins, so a peak narrower than a pixel still shows.
fn bins_of_pixel(k: u32, n_px: u32, n_bins: usize) -> std::ops::Range<usize> {
    let a = (k as usize * n_bins) / n_px as usize;
    let b = ((k as usize + 1) * n_bins).div_ceil(n_px as usize);
    a.min(n_bins - 1)..b.clamp(a + 1, n_bins)
}

/// Draws `f` into the PNG file `path` (written atomically); returns where it drew.
pub fn angular_figure(path: &Path, f: &AngularFigure) -> anyhow::Result<Drawn> {
    anyhow::ensure!(
        !f.panels.is_empty() && f.cols > 0 && f.n_theta > 0 && f.n_phi > 0,
        "a figure needs panels and bins"
    );
    for p in &f.panels {
        anyhow::ensure!(
            p.values.len() == f.n_theta * f.n_phi,
            "panel {:?} has {} values, expected {} × {}",
            p.caption,
            p.values.len(),
            f.n_theta,
            f.n_phi
        );
    }
    ensure_font();
    let scale = LogScale::of(
        f.panels.iter().flat_map(|p| p.values.iter().copied()),
        f.decades,
    );
    let (w, h) = f.size();
    let (cw, ch) = f.cell();
    let (mw, mh) = f.map_px;
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let mut maps = Vec::with_capacity(f.panels.len());
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        root.draw(&Text::new(
            f.title.clone(),
            (PAD as i32, 10),
            ("sans-serif", 24).into_font().color(&BLACK),
        ))?;
        root.draw(&Text::new(
            f.subtitle.clone(),
            (PAD as i32, 42),
            ("sans-serif", 15).into_font().color(&RGBColor(60, 60, 60)),
        ))?;
        // Integer degrees: plotters binds fixed ticks only to coordinates with default labels.
        let x_ticks = vec![-180, -90, 0, 90, 180];
        let y_ticks = vec![-90, -45, 0, 45, 90];
        for (k, p) in f.panels.iter().enumerate() {
            let (r, c) = ((k / f.cols) as u32, (k % f.cols) as u32);
            let (x, y) = (PAD + c * cw, TITLE_H + r * ch);
            let cell = root.clone().shrink((x, y), (cw, ch));
            cell.draw(&Text::new(
                p.caption.clone(),
                (Y_AREA as i32, 3),
                ("sans-serif", 17).into_font().color(&BLACK),
            ))?;
            let mut chart = ChartBuilder::on(&cell)
                .margin_top(CAPTION_H)
                .margin_right(CELL_RIGHT)
                .margin_bottom(CELL_BOTTOM)
                .x_label_area_size(X_AREA)
                .y_label_area_size(Y_AREA)
                .build_cartesian_2d(
                    (-180..180).with_key_points(x_ticks.clone()),
                    (-90..90).with_key_points(y_ticks.clone()),
                )?;
            let (xr, yr) = chart.plotting_area().get_pixel_range();
            let (px, py) = ((xr.end - xr.start) as u32, (yr.end - yr.start) as u32);
            anyhow::ensure!(
                (px, py) == (mw, mh),
                "plot area {px}×{py}, expected {mw}×{mh}"
            );
            for yy in 0..py {
                // Row 0 of the image is the top, θ = 90°.
                let rows = bins_of_pixel(py - 1 - yy, py, f.n_theta);
                for xx in 0..px {
                    let cols = bins_of_pixel(xx, px, f.n_phi);
                    let v = rows
                        .clone()
                        .flat_map(|it| {
                            p.values[it * f.n_phi + cols.start..it * f.n_phi + cols.end].iter()
                        })
                        .copied()
                        .fold(f64::NEG_INFINITY, f64::max);
                    let [cr, cg, cb] = scale.colour(v);
                    root.draw_pixel(
                        (xr.start + xx as i32, yr.start + yy as i32),
                        &RGBColor(cr, cg, cb),
                    )?;
                }
            }
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc(f.x_desc.as_str())
                .y_desc(f.y_desc.as_str())
                .x_label_formatter(&degrees)
                .y_label_formatter(&degrees)
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 15))
                .draw()?;
            maps.push([xr.start, yr.start, xr.end, yr.end]);
        }
        colour_bar(&root, f, &scale, &maps)?;
        root.present()?;
    }
    write_png(path, w, h, buf)?;
    Ok(Drawn {
        size: (w, h),
        maps,
        scale,
    })
}

/// Draws the colour bar of `f` right of its panels, as tall as the maps (`maps`, pixel
/// rectangles) of the first row to the last, with ticks at decades and the largest value.
fn colour_bar(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    f: &AngularFigure,
    scale: &LogScale,
    maps: &[[i32; 4]],
) -> anyhow::Result<()> {
    let cw = f.cell().0;
    // The colour bar, as tall as the maps of the first row to the last.
    let (top, bottom) = (maps[0][1], maps.last().unwrap()[3]);
    let bar_x = (PAD + f.cols as u32 * cw) as i32;
    let bar = root
        .clone()
        .shrink((bar_x, top), (BAR_W as i32, bottom - top + X_AREA as i32));
    // The bar's axis counts hundredths of a decade (integer, for fixed ticks at decades).
    let (lo, hi) = scale.log10_range();
    let (lo, hi) = ((lo * 100.0).round() as i32, (hi * 100.0).round() as i32);
    let mut ticks: Vec<i32> = (lo.div_euclid(100)..=hi.div_euclid(100))
        .map(|n| n * 100)
        .filter(|v| (lo..=hi).contains(v))
        .collect();
    // The top of the bar is the largest value shown: labelled with it unless a decade
    // tick sits within 0.15 decades of it (the labels would overlap).
    if scale.max > 0.0 && ticks.last().is_none_or(|&d| hi - d >= 15) {
        ticks.push(hi);
    }
    let mut chart = ChartBuilder::on(&bar)
        .margin_left(BAR_LEFT)
        .margin_right(BAR_W - BAR_LEFT - BAR_PX - BAR_LABELS)
        .margin_bottom(X_AREA)
        .set_label_area_size(LabelAreaPosition::Right, BAR_LABELS)
        .build_cartesian_2d(
            // No ticks across (`x_labels(0)` overflows in plotters' tick search).
            (0..1).with_key_points(Vec::new()),
            (lo..hi).with_key_points(ticks),
        )?;
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    let n = (yr.end - yr.start).max(2);
    for yy in yr.clone() {
        let t = 1.0 - (yy - yr.start) as f64 / (n - 1) as f64;
        let [cr, cg, cb] = inferno(t);
        for xx in xr.clone() {
            root.draw_pixel((xx, yy), &RGBColor(cr, cg, cb))?;
        }
    }
    chart
        .configure_mesh()
        .disable_mesh()
        .y_label_formatter(&|v: &i32| {
            if v.rem_euclid(100) == 0 {
                power_of_ten(v.div_euclid(100) as i64)
            } else {
                three_digits(scale.max)
            }
        })
        .label_style(("sans-serif", 14))
        .draw()?;
    root.draw(&Text::new(
        f.bar_desc.clone(),
        (bar_x + BAR_LEFT as i32, top - CAPTION_H as i32 + 3),
        ("sans-serif", 17).into_font().color(&BLACK),
    ))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sum of R, G and B: inferno rises in it monotonically, so the brightest pixel of a
    /// map is the one of its largest value.
    fn brightness(c: &image::Rgb<u8>) -> u32 {
        c.0.iter().map(|&v| v as u32).sum()
    }

    #[test]
    fn inferno_rises_from_black_to_pale_yellow() {
        assert_eq!(inferno(0.0), [0, 0, 4]);
        assert_eq!(inferno(1.0), [252, 255, 164]);
        assert_eq!(inferno(f64::NAN), inferno(0.0));
        assert_eq!(inferno(2.0), inferno(1.0));
        let lum: Vec<u32> = (0..=200)
            .map(|k| inferno(k as f64 / 200.0).iter().map(|&v| v as u32).sum())
            .collect();
        assert!(lum.windows(2).all(|w| w[0] <= w[1]), "{lum:?}");
        assert!(lum[0] < lum[100] && lum[100] < lum[200]);
    }

    #[test]
    fn log_scale_spans_its_decades_below_the_maximum() {
        let s = LogScale::of([0.0, 2.0, f64::INFINITY, 0.5, f64::NAN], 5.0);
        assert_eq!(s.max, 2.0);
        assert_eq!(s.colour(2.0), inferno(1.0));
        assert_eq!(s.colour(2e-5), inferno(0.0));
        assert_eq!(s.colour(2e-9), inferno(0.0));
        assert_eq!(s.colour(2.0 * 10f64.powf(-2.5)), inferno(0.5));
        assert_eq!(s.colour(0.0), [0, 0, 0]);
        let (lo, hi) = s.log10_range();
        assert!((hi - 2f64.log10()).abs() < 1e-12 && (hi - lo - 5.0).abs() < 1e-12);
        let empty = LogScale::of([0.0, -1.0], 5.0);
        assert_eq!(
            (empty.colour(1.0), empty.log10_range()),
            ([0, 0, 0], (-5.0, 0.0))
        );
    }

    #[test]
    fn labels_use_true_minus_signs_and_superscripts() {
        assert_eq!(power_of_ten(-12), "10⁻¹²");
        assert_eq!(power_of_ten(0), "10⁰");
        assert_eq!(power_of_ten(3), "10³");
        assert_eq!(degrees(&-90), "−90°");
        assert_eq!(degrees(&180), "180°");
        assert_eq!(three_digits(5.6234), "5.62");
        assert_eq!(three_digits(0.0123456), "0.0123");
        assert_eq!(three_digits(123.4), "123");
        assert_eq!(three_digits(2.5e-5), "2.50×10⁻⁵");
        assert_eq!(three_digits(4.0e7), "4.00×10⁷");
    }

    #[test]
    fn every_bin_is_covered_by_some_pixel() {
        for (n_px, n_bins) in [
            (420, 180),
            (420, 60),
            (210, 90),
            (210, 18),
            (7, 30),
            (30, 7),
        ] {
            let mut seen = vec![false; n_bins];
            for k in 0..n_px {
                let r = bins_of_pixel(k, n_px, n_bins);
                assert!(!r.is_empty() && r.end <= n_bins, "{k} of {n_px}: {r:?}");
                r.for_each(|b| seen[b] = true);
            }
            assert!(seen.iter().all(|&s| s), "{n_px} px, {n_bins} bins");
        }
    }

    const NT: usize = 18;
    const NP: usize = 36;

    /// Two panels on 10° bins: a floor of 10⁻³ with one peak each, a zero bin in the second.
    fn figure() -> AngularFigure {
        let mut a = vec![1e-3; NT * NP];
        a[14 * NP + 27] = 1.0; // θ = 55°, Δφ = 95°
        let mut b = vec![1e-3; NT * NP];
        b[3 * NP + 5] = 0.5; // θ = −55°, Δφ = −125°
        b[9 * NP + 18] = 0.0; // θ = 5°, Δφ = 5°
        AngularFigure {
            title: "test: a title".into(),
            subtitle: "a subtitle".into(),
            x_desc: "Δφ".into(),
            y_desc: "θo".into(),
            bar_desc: "f (sr⁻¹)".into(),
            n_theta: NT,
            n_phi: NP,
            panels: vec![
                Panel {
                    caption: "one".into(),
                    values: a,
                },
                Panel {
                    caption: "two".into(),
                    values: b,
                },
            ],
            cols: 2,
            map_px: (420, 210),
            decades: 5.0,
        }
    }

    /// The bins (θ rows, φ columns) that pixel (x, y) of map `m` overlaps: the θ axis up
    /// from −90° at the bottom edge, φ across from −180° at the left edge.
    fn bins_at(m: [i32; 4], x: u32, y: u32) -> (Vec<usize>, Vec<usize>) {
        let (w, h) = ((m[2] - m[0]) as f64, (m[3] - m[1]) as f64);
        let (dx, dy) = (x as f64 - m[0] as f64, y as f64 - m[1] as f64);
        let over = |a: f64, b: f64, n: usize| -> Vec<usize> {
            (0..n)
                .filter(|&k| (k as f64) < b * n as f64 && ((k + 1) as f64) > a * n as f64)
                .collect()
        };
        let phi = over(dx / w, (dx + 1.0) / w, NP);
        // Bottom edge of the pixel is θ fraction 1 − (dy + 1)/h, its top 1 − dy/h.
        let theta = over(1.0 - (dy + 1.0) / h, 1.0 - dy / h, NT);
        (theta, phi)
    }

    /// The pixels of map `m` of `img` with the largest brightness.
    fn brightest(img: &image::RgbImage, m: [i32; 4]) -> Vec<(u32, u32)> {
        let mut best = (0, Vec::new());
        for y in m[1] as u32..m[3] as u32 {
            for x in m[0] as u32..m[2] as u32 {
                let b = brightness(img.get_pixel(x, y));
                if b > best.0 {
                    best = (b, vec![(x, y)]);
                } else if b == best.0 {
                    best.1.push((x, y));
                }
            }
        }
        best.1
    }

    /// The PNG decodes at the stated size; every pixel of each map shows its bin's colour
    /// with θ up and φ across (so the brightest pixels are exactly those of the peak's bin);
    /// the colour bar runs from the brightest colour (top) to the darkest; text is drawn;
    /// the file is the same byte for byte when drawn again.
    #[test]
    fn heat_map_draws_each_bin_where_its_axes_say() {
        let dir = tempfile::tempdir().unwrap();
        let f = figure();
        let path = dir.path().join("fig.png");
        let drawn = angular_figure(&path, &f).unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), drawn.size);
        assert_eq!(drawn.size, f.size());
        assert!(drawn.size.0 >= 800, "{:?}", drawn.size);
        assert_eq!(drawn.maps.len(), 2);
        assert_eq!(drawn.scale.max, 1.0);
        for (k, &m) in drawn.maps.iter().enumerate() {
            assert_eq!((m[2] - m[0], m[3] - m[1]), (420, 210));
            for y in m[1] as u32..m[3] as u32 {
                for x in m[0] as u32..m[2] as u32 {
                    // A pixel over a bin edge shows the larger value (a peak narrower than
                    // a pixel must not vanish).
                    let (rows, cols) = bins_at(m, x, y);
                    let v = rows
                        .iter()
                        .flat_map(|&it| cols.iter().map(move |&j| it * NP + j))
                        .map(|b| f.panels[k].values[b])
                        .fold(f64::NEG_INFINITY, f64::max);
                    let want = drawn.scale.colour(v);
                    assert_eq!(img.get_pixel(x, y).0, want, "panel {k} at ({x}, {y})");
                }
            }
            let peak = brightest(&img, m);
            let want = if k == 0 { (14, 27) } else { (3, 5) };
            assert!(!peak.is_empty());
            for &(x, y) in &peak {
                let (rows, cols) = bins_at(m, x, y);
                assert!(
                    rows.contains(&want.0) && cols.contains(&want.1),
                    "panel {k}: brightest pixel ({x}, {y}) over bins {rows:?} × {cols:?}"
                );
            }
            // 420 px over 36 bins, 210 over 18: 11.7 pixels per bin each way, 12 or 13
            // touching it.
            assert!((144..=169).contains(&peak.len()), "{}", peak.len());
        }
        // The bar: right of the maps, as tall as them, brightest at the top.
        let (top, bottom) = (drawn.maps[0][1] as u32, drawn.maps[1][3] as u32 - 1);
        let right = drawn.maps[1][2] as u32;
        let bar: Vec<u32> = (right..drawn.size.0)
            .filter(|&x| {
                brightness(img.get_pixel(x, top + 2)) > 640
                    && brightness(img.get_pixel(x, bottom - 2)) < 20
            })
            .collect();
        assert!((20..=40).contains(&bar.len()), "bar columns {bar:?}");
        let column: Vec<u32> = (top..=bottom)
            .map(|y| brightness(img.get_pixel(bar[bar.len() / 2], y)))
            .collect();
        assert!(column.windows(2).all(|w| w[0] >= w[1]), "{column:?}");
        // Text: dark pixels in the title line and under the maps (tick labels, axis titles).
        let dark = |x0: u32, y0: u32, x1: u32, y1: u32| {
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| brightness(img.get_pixel(x, y)) < 200)
                .count()
        };
        assert!(dark(0, 0, drawn.size.0, 36) > 100);
        let m = drawn.maps[0];
        assert!(dark(m[0] as u32, m[3] as u32 + 2, m[2] as u32, m[3] as u32 + 44) > 100);
        assert!(dark(0, m[1] as u32, m[0] as u32 - 2, m[3] as u32) > 100);
        let again = dir.path().join("again.png");
        angular_figure(&again, &f).unwrap();
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(&again).unwrap()
        );
    }

    /// Panels of the wrong size and empty figures are refused.
    #[test]
    fn malformed_figures_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let mut f = figure();
        f.panels[1].values.pop();
        let e = angular_figure(&dir.path().join("x.png"), &f).unwrap_err();
        assert!(e.to_string().contains("has 647 values"), "{e}");
        f.panels.clear();
        assert!(angular_figure(&dir.path().join("x.png"), &f).is_err());
        assert!(!dir.path().join("x.png").exists());
    }
}
