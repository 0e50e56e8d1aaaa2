//! Fiber cross-sections (§5.3, "Cross section and longitudinal structure"): closed outlines in
//! micrometres, centred on the fiber axis. A section is an exact conic (circle, ellipse) or a
//! polygon with holes (parametric generators, CSV outlines, segmented SEM masks).

pub mod generate;
pub mod grid;
pub mod mask;
pub mod polygon;

use std::path::Path;

pub use polygon::Polygon;

#[derive(Debug, Clone, thiserror::Error)]
pub enum SectionError {
    #[error("degenerate cross-section: {0}")]
    Degenerate(String),
    #[error("{file}:{line}: {message}")]
    Csv {
        file: String,
        line: usize,
        message: String,
    },
    #[error("{file}: {message}")]
    Mask { file: String, message: String },
}

/// Largest |coordinate| of a polygon outline, µm (1 cm: far beyond any fiber, small enough that
/// areas and moments stay finite in f64).
pub const MAX_COORD_UM: f64 = 1e4;

/// A cross-section in the fiber's xy plane (fiber axis +z), µm.
#[derive(Debug, Clone)]
pub enum Section {
    /// Ellipse with semi-axes `rx_um` along x and `ry_um` along y (a circle when equal),
    /// intersected in closed form.
    Conic {
        rx_um: f64,
        ry_um: f64,
    },
    Polygon(Polygon),
}

/// A 2D ray hit: ray parameter, surface id (edge index; 0 for a conic), outward unit normal,
/// and `c = n·q` at the hit (the line offset that tilts the normal of a scaled section).
#[derive(Debug, Clone, Copy)]
pub struct Hit2 {
    pub t: f64,
    pub id: u32,
    pub n: [f64; 2],
    pub c: f64,
}

impl Section {
    pub fn circle(diameter_um: f64) -> Self {
        Section::Conic {
            rx_um: 0.5 * diameter_um,
            ry_um: 0.5 * diameter_um,
        }
    }

    /// Nearest boundary crossing of o + t·d with 0 < t ≤ t_max. `skip` is the surface the ray
    /// starts on (from the previous hit), which a straight ray leaves without meeting again
    /// except, for a conic, at its far side.
    #[inline]
    pub fn intersect(
        &self,
        o: [f64; 2],
        d: [f64; 2],
        t_max: f64,
        skip: Option<u32>,
    ) -> Option<Hit2> {
        match self {
            Section::Conic { rx_um, ry_um } => {
                let (ox, oy) = (o[0] / rx_um, o[1] / ry_um);
                let (dx, dy) = (d[0] / rx_um, d[1] / ry_um);
                let a = dx * dx + dy * dy;
                if a == 0.0 {
                    return None;
                }
                let b = ox * dx + oy * dy;
                let t = if skip.is_some() {
                    // On the surface: the roots are 0 and −2b/a.
                    -2.0 * b / a
                } else {
                    let c = ox * ox + oy * oy - 1.0;
                    let disc = b * b - a * c;
                    if disc < 0.0 {
                        return None;
                    }
                    let sq = disc.sqrt();
                    if c > 0.0 {
                        (-b - sq) / a
                    } else {
                        (-b + sq) / a
                    }
                };
                if !(t > 0.0 && t <= t_max) {
                    return None;
                }
                let (qx, qy) = (o[0] + t * d[0], o[1] + t * d[1]);
                let (gx, gy) = (qx / (rx_um * rx_um), qy / (ry_um * ry_um));
                let inv = 1.0 / (gx * gx + gy * gy).sqrt();
                let n = [gx * inv, gy * inv];
                Some(Hit2 {
                    t,
                    id: 0,
                    n,
                    c: n[0] * qx + n[1] * qy,
                })
            }
            Section::Polygon(p) => p.intersect(o, d, t_max, skip).map(|h| Hit2 {
                t: h.t,
                id: h.id,
                n: h.n,
                c: h.c,
            }),
        }
    }

    /// True when a ray leaving the material outward through surface `id` (of a hit) can never
    /// meet the section again: always for a conic (convex), for a polygon when the edge lies
    /// on its convex hull ([`Polygon::edge_on_hull`]). The tracer scores such exits without
    /// a ray query.
    #[inline]
    pub fn leaves_freely(&self, id: u32) -> bool {
        match self {
            Section::Conic { .. } => true,
            Section::Polygon(p) => p.edge_on_hull(id),
        }
    }

    /// True inside the material.
    pub fn contains(&self, q: [f64; 2]) -> bool {
        match self {
            Section::Conic { rx_um, ry_um } => {
                let (x, y) = (q[0] / rx_um, q[1] / ry_um);
                x * x + y * y < 1.0
            }
            Section::Polygon(p) => p.contains(q),
        }
    }

    /// (min, max) of q·e over the material, for a unit vector `e`.
    pub fn extent(&self, e: [f64; 2]) -> (f64, f64) {
        match self {
            Section::Conic { rx_um, ry_um } => {
                let h = ((rx_um * e[0]).powi(2) + (ry_um * e[1]).powi(2)).sqrt();
                (-h, h)
            }
            Section::Polygon(p) => p.extent(e),
        }
    }

    /// Width of the shadow cast by light travelling along the xy direction at azimuth
    /// `phi_rad`, µm: the projected area A(ω) per unit fiber length before the cos θ factor
    /// (thesis §5.5, Eq. 17 uses A(ω′)·sin(ω, ω_f) with sin(ω, ω_f) = cos θ).
    pub fn projected_width_um(&self, phi_rad: f64) -> f64 {
        let e = [-phi_rad.sin(), phi_rad.cos()];
        let (lo, hi) = self.extent(e);
        hi - lo
    }

    /// Mean projected width over all azimuths, µm: the diameter a microscope sees on average
    /// (for a convex outline, perimeter/π by Cauchy's formula). This is the "diameter" of
    /// Table 9 that generators size to.
    pub fn mean_width_um(&self) -> f64 {
        let n = 720;
        (0..n)
            .map(|i| self.projected_width_um(std::f64::consts::PI * (i as f64 + 0.5) / n as f64))
            .sum::<f64>()
            / n as f64
    }

    /// Material area, µm².
    pub fn area_um2(&self) -> f64 {
        match self {
            Section::Conic { rx_um, ry_um } => std::f64::consts::PI * rx_um * ry_um,
            Section::Polygon(p) => p.area(),
        }
    }

    /// Radius of a circle about the origin that contains the section, µm.
    pub fn bound_radius_um(&self) -> f64 {
        match self {
            Section::Conic { rx_um, ry_um } => rx_um.max(*ry_um),
            Section::Polygon(p) => p.bound_radius(),
        }
    }

    /// Number of holes (the cotton lumen).
    pub fn hole_count(&self) -> usize {
        match self {
            Section::Conic { .. } => 0,
            Section::Polygon(p) => p.holes().len(),
        }
    }

    /// The outline as loops (outer first, then holes), for plots and files; a conic is sampled
    /// at `n` points.
    pub fn loops(&self, n: usize) -> Vec<Vec<[f64; 2]>> {
        match self {
            Section::Conic { rx_um, ry_um } => vec![(0..n)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / n as f64;
                    [rx_um * a.cos(), ry_um * a.sin()]
                })
                .collect()],
            Section::Polygon(p) => std::iter::once(p.outer().to_vec())
                .chain(p.holes().iter().cloned())
                .collect(),
        }
    }

    /// Reads a polygon CSV: rows `x_um,y_um`; a blank line or a row `hole` starts a hole; `#`
    /// comments and a header row `x_um,y_um` (or `x,y`) are skipped (the dialect of
    /// [`crate::files::csv_rows`]). The outline is moved so that its area centroid is on the
    /// fiber axis. At most `max_vertices` vertices; every coordinate within ±[`MAX_COORD_UM`].
    pub fn from_csv(path: &Path, max_vertices: u64) -> Result<Self, SectionError> {
        use crate::files::csv_rows;
        let file = path.display().to_string();
        let csv_err = |line: usize, message: String| SectionError::Csv {
            file: file.clone(),
            line,
            message,
        };
        let text = crate::files::read_text(path, crate::files::MAX_DATA_BYTES, "a polygon CSV")
            .map_err(|e| csv_err(0, e.to_string()))?;
        const EXPECTED: &str = "expected two numbers `x_um,y_um` (µm), a blank line or `hole`";
        let mut vertices = 0u64;
        let mut loops: Vec<Vec<[f64; 2]>> = vec![Vec::new()];
        for row in csv_rows::rows(&text) {
            let row = row.map_err(|e| csv_err(e.line, e.message))?;
            let line = row.line;
            let hole = row.len() == 1 && row.get(0).eq_ignore_ascii_case("hole");
            if (row.after_blank || hole) && !loops.last().is_some_and(|l| l.is_empty()) {
                loops.push(Vec::new());
            }
            if hole {
                continue;
            }
            // A header: a first line, or a two-column row before any vertex, that is not
            // numbers.
            let header = line == 1 || loops.iter().all(|l| l.is_empty()) && row.len() == 2;
            if row.len() != 2 {
                if header {
                    continue;
                }
                return Err(csv_err(
                    line,
                    format!("{EXPECTED}; got {} columns: {}", row.len(), row.text()),
                ));
            }
            let (x, y) = match (row.number(0, "x_um"), row.number(1, "y_um")) {
                (Ok(x), Ok(y)) => (x, y),
                _ if header => continue,
                (Err(m), _) | (_, Err(m)) => {
                    return Err(csv_err(line, format!("{m}; {EXPECTED}")));
                }
            };
            if let Some((col, v)) = [(1, x), (2, y)]
                .into_iter()
                .find(|(_, v)| !v.is_finite() || v.abs() > MAX_COORD_UM)
            {
                return Err(csv_err(
                    line,
                    format!(
                        "coordinates ({x}, {y}) µm: column {col} ({v}) is out of range; each \
                         must be a finite number within ±{MAX_COORD_UM} µm (a fiber is at most \
                         a few hundred µm across)"
                    ),
                ));
            }
            vertices += 1;
            if vertices > max_vertices {
                return Err(csv_err(
                    line,
                    format!(
                        "more than {max_vertices} vertices, over the limit \
                         (`limits.polygon_vertices`)"
                    ),
                ));
            }
            loops.last_mut().unwrap().push([x, y]);
        }
        loops.retain(|l| !l.is_empty());
        if loops.is_empty() {
            return Err(SectionError::Csv {
                file,
                line: 0,
                message: "no vertices".into(),
            });
        }
        let outer = loops.remove(0);
        let p = Polygon::new(outer, loops).map_err(|e| SectionError::Csv {
            file: file.clone(),
            line: 0,
            message: e.to_string(),
        })?;
        let c = p.centroid();
        Ok(Section::Polygon(p.transformed(c, 1.0)?))
    }

    /// The section scaled so that its mean projected width is `diameter_um`.
    pub fn scaled_to_diameter(&self, diameter_um: f64) -> Result<Self, SectionError> {
        let k = diameter_um / self.mean_width_um();
        Ok(match self {
            Section::Conic { rx_um, ry_um } => Section::Conic {
                rx_um: rx_um * k,
                ry_um: ry_um * k,
            },
            Section::Polygon(p) => Section::Polygon(p.transformed([0.0, 0.0], k)?),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polygon_csv(text: &str) -> Result<Section, SectionError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.csv");
        std::fs::write(&path, text).unwrap();
        Section::from_csv(&path, 100)
    }

    #[test]
    fn polygon_csv_with_header_comments_and_holes() {
        let square = |r: f64| format!("{},{}\n{r},{}\n{r},{r}\n{},{r}\n", -r, -r, -r, -r);
        for sep in ["\n", "\n  \n# inner\n", "hole\n", "\r\n\r\n"] {
            let text = format!(
                "# outline\nx_um , y_um\n{}{sep}{}",
                square(20.0),
                square(5.0)
            );
            let s = polygon_csv(&text).unwrap();
            assert_eq!(s.hole_count(), 1, "{sep:?}");
        }
        let s = polygon_csv(&format!("x,y\r\n{}", square(20.0).replace('\n', "\r\n"))).unwrap();
        assert_eq!(s.hole_count(), 0);
    }

    #[test]
    fn malformed_polygon_rows_name_file_line_and_column() {
        let msg = |text: &str| polygon_csv(text).unwrap_err().to_string();
        let m = msg("x_um,y_um\n# c\n0,0\n10,0\n10,abc\n");
        assert!(
            m.ends_with(
                "p.csv:5: column 2 (y_um): expected a number, got \"abc\"; expected two \
                 numbers `x_um,y_um` (µm), a blank line or `hole`"
            ),
            "{m}"
        );
        let m = msg("0,0\n10,0,5\n");
        assert!(
            m.contains("p.csv:2: ") && m.contains("got 3 columns: \"10,0,5\""),
            "{m}"
        );
        let m = msg("0,0\n\n1e5,0\n");
        assert!(
            m.contains("p.csv:3: ") && m.contains("column 1 (100000) is out of range"),
            "{m}"
        );
        let m = msg("0,0\n1,NaN\n");
        assert!(
            m.contains("p.csv:2: ") && m.contains("finite number within"),
            "{m}"
        );
        let many: String = (0..101).map(|i| format!("{i},{}\n", i % 2)).collect();
        let m = msg(&many);
        assert!(m.contains("p.csv:101: more than 100 vertices"), "{m}");
    }

    #[test]
    fn conic_hits_front_then_back() {
        let s = Section::circle(10.0);
        let h = s
            .intersect([-10.0, 3.0], [1.0, 0.0], f64::INFINITY, None)
            .unwrap();
        assert!((h.t - (10.0 - 4.0)).abs() < 1e-12);
        assert!((h.n[0] + 0.8).abs() < 1e-12 && (h.n[1] - 0.6).abs() < 1e-12);
        let o = [-4.0, 3.0];
        let h2 = s.intersect(o, [1.0, 0.0], f64::INFINITY, Some(0)).unwrap();
        assert!((h2.t - 8.0).abs() < 1e-12);
        assert!((h2.c - 5.0).abs() < 1e-12);
    }

    #[test]
    fn widths_of_an_ellipse() {
        let s = Section::Conic {
            rx_um: 4.0,
            ry_um: 2.0,
        };
        // Light along x (φ = 0) sees the y extent.
        assert!((s.projected_width_um(0.0) - 4.0).abs() < 1e-12);
        assert!((s.projected_width_um(std::f64::consts::FRAC_PI_2) - 8.0).abs() < 1e-12);
        let c = Section::circle(10.0);
        assert!((c.mean_width_um() - 10.0).abs() < 1e-12);
    }
}
