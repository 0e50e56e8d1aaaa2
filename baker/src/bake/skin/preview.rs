//! PNG previews of a profile bake: contact sheets of skin swatches (colour = sRGB-encoded
//! total diffuse reflectance) over skin type × age, and one plot per entry of its RGB profile
//! with the sum-of-Gaussians fit.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use plotters::prelude::*;

use crate::fit::gaussian_energy;
use crate::output::plot::{ensure_font, write_png as png};
use crate::profile::RgbProfile;
use crate::spectral::colour::srgb_encode;
use crate::transport::RadialBins;

use crate::bake::job::Job;

/// The previews of a profile bake into `preview/`: the contact sheets and one profile plot
/// per entry. Returns the sheets' paths relative to the spec's folder.
pub fn write(
    job: &Job,
    entries: &[formats::OpticsEntry],
    rgb: &[RgbProfile],
    bins: &RadialBins,
) -> anyhow::Result<Vec<String>> {
    let at = |rel: &str| job.at(rel);
    let sheet: Vec<SheetEntry> = entries
        .iter()
        .zip(rgb)
        .map(|(e, r)| sheet_entry(e, r))
        .collect();
    job.runner.cancel.check()?;
    let sheets = contact_sheets(&at("preview")?, &sheet)?;
    entries.par_iter().zip(rgb).try_for_each(|(e, r)| {
        job.runner.cancel.check()?;
        profile_plot(
            &at(&format!("preview/profiles/{}.png", e.name))?,
            &e.name,
            bins.edges_mm(),
            r,
        )
    })?;
    Ok(sheets
        .iter()
        .map(|s| format!("preview/{}", s.file_name().unwrap().to_string_lossy()))
        .collect())
}

/// Where entry `e` sits on the contact sheets: sheet by gender, location and ξ, rows by skin
/// type, columns by age.
fn sheet_entry(e: &formats::OpticsEntry, r: &RgbProfile) -> SheetEntry {
    let v = &e.inputs;
    let s = |k: &str| {
        v.get(k)
            .map(|x| {
                x.as_str()
                    .map(str::to_string)
                    .unwrap_or_else(|| x.to_string())
            })
            .unwrap_or_default()
    };
    let row = match v.get("melanin") {
        Some(m) if m.get("skin_type").is_some() => {
            format!("type {}", m["skin_type"].as_str().unwrap_or("?"))
        }
        Some(m) => format!(
            "melanin {}",
            m.get("melanosome_fraction")
                .map(|x| x.to_string())
                .unwrap_or_default()
        ),
        None => e.name.clone(),
    };
    let age = v.get("age_years").and_then(|x| x.as_f64()).unwrap_or(0.0);
    let mut sheet = format!("{} {}, xi {}", s("gender"), s("location"), s("xi"));
    if e.model != "five_layer" {
        sheet.push_str(&format!(", {}", e.model));
    }
    SheetEntry {
        sheet,
        row,
        column: (age, format!("age {age}")),
        albedo_rgb: r.albedo_rgb,
    }
}

/// Where an entry sits on a contact sheet.
#[derive(Debug, Clone)]
pub struct SheetEntry {
    /// Entries with the same sheet key share a sheet (e.g. "female forearm, xi 0.5").
    pub sheet: String,
    pub row: String,
    /// Sort key and label of the column (age).
    pub column: (f64, String),
    pub albedo_rgb: [f64; 3],
}

fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes one contact sheet per sheet key into `dir`; returns the files written.
pub fn contact_sheets(dir: &Path, entries: &[SheetEntry]) -> anyhow::Result<Vec<PathBuf>> {
    ensure_font();
    let mut sheets: Vec<&str> = Vec::new();
    for e in entries {
        if !sheets.contains(&e.sheet.as_str()) {
            sheets.push(&e.sheet);
        }
    }
    let mut written = Vec::new();
    for sheet in sheets {
        let members: Vec<&SheetEntry> = entries.iter().filter(|e| e.sheet == sheet).collect();
        let mut rows: Vec<&str> = Vec::new();
        let mut cols: Vec<(f64, &str)> = Vec::new();
        for e in &members {
            if !rows.contains(&e.row.as_str()) {
                rows.push(&e.row);
            }
            if !cols.iter().any(|c| c.1 == e.column.1) {
                cols.push((e.column.0, &e.column.1));
            }
        }
        cols.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (cell, left, top) = (90u32, 150u32, 80u32);
        let w = left + cell * cols.len() as u32 + 20;
        let h = top + cell * rows.len() as u32 + 20;
        let mut buf = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            root.fill(&RGBColor(40, 40, 40))?;
            let text = ("sans-serif", 16).into_font().color(&WHITE);
            root.draw(&Text::new(
                sheet.to_string(),
                (10, 10),
                ("sans-serif", 20).into_font().color(&WHITE),
            ))?;
            for (j, c) in cols.iter().enumerate() {
                root.draw(&Text::new(
                    c.1.to_string(),
                    ((left + cell * j as u32 + 10) as i32, 50),
                    text.clone(),
                ))?;
            }
            for (i, r) in rows.iter().enumerate() {
                let y = (top + cell * i as u32) as i32;
                root.draw(&Text::new(
                    r.to_string(),
                    (10, y + cell as i32 / 2 - 8),
                    text.clone(),
                ))?;
                for (j, c) in cols.iter().enumerate() {
                    let Some(e) = members.iter().find(|e| e.row == *r && e.column.1 == c.1) else {
                        continue;
                    };
                    let [cr, cg, cb] = e.albedo_rgb.map(|v| (srgb_encode(v) * 255.0).round() as u8);
                    let x = (left + cell * j as u32) as i32;
                    root.draw(&Rectangle::new(
                        [(x + 4, y + 4), (x + cell as i32 - 4, y + cell as i32 - 4)],
                        RGBColor(cr, cg, cb).filled(),
                    ))?;
                }
            }
            root.present()?;
        }
        let path = dir.join(format!("contact_sheet_{}.png", file_safe(sheet)));
        png(&path, w, h, buf)?;
        written.push(path);
    }
    Ok(written)
}

const CHANNELS: [RGBColor; 3] = [
    RGBColor(213, 40, 40),
    RGBColor(30, 150, 60),
    RGBColor(40, 80, 220),
];

/// Log–log plot of the RGB profile (solid) and its fit (dashed) of one entry.
pub fn profile_plot(
    path: &Path,
    name: &str,
    r_edges_mm: &[f64],
    p: &RgbProfile,
) -> anyhow::Result<()> {
    ensure_font();
    let (w, h) = (800u32, 560u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let centres: Vec<f64> = r_edges_mm.windows(2).map(|e| 0.5 * (e[0] + e[1])).collect();
    let r_hi = p
        .r99_mm
        .iter()
        .filter(|r| r.is_finite())
        .fold(0.0f64, |a, &b| a.max(b))
        .max(centres[0] * 10.0)
        * 1.5;
    let r_hi = r_hi.min(*r_edges_mm.last().unwrap());
    let shown: Vec<usize> = (0..centres.len()).filter(|&k| centres[k] <= r_hi).collect();
    let pos = shown
        .iter()
        .flat_map(|&k| p.rd_rgb_per_mm2[k].iter().copied())
        .filter(|v| *v > 0.0);
    let y_hi = pos.clone().fold(0.0f64, f64::max).max(1e-12);
    let y_lo = pos.fold(f64::INFINITY, f64::min).max(y_hi * 1e-7);
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(name, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(75)
            .build_cartesian_2d(
                (centres[0]..r_hi).log_scale(),
                (y_lo..y_hi * 2.0).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc("r (mm)")
            .y_desc("Rd(r) (1/mm²), linear sRGB")
            .label_style(("sans-serif", 14))
            .draw()?;
        for (c, color) in CHANNELS.iter().enumerate() {
            let table = shown
                .iter()
                .map(|&k| (centres[k], p.rd_rgb_per_mm2[k][c]))
                .filter(|(_, v)| *v > 0.0);
            chart
                .draw_series(LineSeries::new(table, color.stroke_width(2)))?
                .label(format!(
                    "{} table (fit error {:.1} %)",
                    ["R", "G", "B"][c],
                    100.0 * p.fit.error_rgb[c]
                ))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            let fit = shown.iter().map(|&k| {
                let (a, b) = (r_edges_mm[k], r_edges_mm[k + 1]);
                let area = std::f64::consts::PI * (b * b - a * a);
                let v: f64 = p
                    .fit
                    .variance_mm2
                    .iter()
                    .zip(&p.fit.weight_rgb)
                    .map(|(&v, w)| w[c] * gaussian_energy(v, a, b))
                    .sum::<f64>()
                    / area;
                (centres[k], v.max(y_lo))
            });
            chart.draw_series(DashedLineSeries::new(fit, 6, 4, color.stroke_width(1)))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
        root.present()?;
    }
    png(path, w, h, buf)
}
