//! Polygonal cross-sections with holes, and the uniform-grid acceleration structure that makes
//! ray queries against many-edged outlines cheap (§5.3: sections modelled from SEM images).

use super::grid::{Segment, SegmentGrid};
use super::SectionError;

/// One edge of a loop: from `a` to `b`, with the unit normal `n` pointing out of the material
/// and the line offset `c = n·a`.
#[derive(Debug, Clone, Copy)]
struct Edge {
    a: [f64; 2],
    ab: [f64; 2],
    inv_len2: f64,
    len: f64,
    n: [f64; 2],
    c: f64,
}

/// A ray hit on a polygon edge: ray parameter, edge index, outward unit normal, `n·q`.
#[derive(Debug, Clone, Copy)]
pub struct EdgeHit {
    pub t: f64,
    pub id: u32,
    pub n: [f64; 2],
    pub c: f64,
}

/// The convex hull of an outline, for its extent along any direction and the edges on it.
#[derive(Debug, Clone)]
struct Hull {
    /// Per edge of the polygon: it lies on the convex hull of the outline (every vertex is on
    /// its inner side), so a ray leaving outward through it never meets the section again.
    on_hull: Vec<bool>,
    /// Its vertices (counter-clockwise, collinear ones kept): the only ones an extent along
    /// any direction can come from.
    vertices: Vec<[f64; 2]>,
    /// Per hull edge (from `vertices[i]` to `vertices[i + 1]`), the azimuth of its outward
    /// normal, with the edge index, sorted by azimuth: the vertex where v·e is largest sits
    /// between the edges whose normals bracket e's azimuth, so [`Polygon::extent`] (once per
    /// photon of a bake, whose incidence varies within its bin) finds it by bisection.
    normal_az: Vec<(f64, u32)>,
}

/// A closed outline (counter-clockwise) with holes (clockwise), in micrometres.
#[derive(Debug, Clone)]
pub struct Polygon {
    outer: Vec<[f64; 2]>,
    holes: Vec<Vec<[f64; 2]>>,
    edges: Vec<Edge>,
    /// The outer loop's convex hull, for extents ([`Polygon::extent`]) and the edges on it
    /// ([`Polygon::edge_on_hull`]).
    hull: Box<Hull>,
    grid: SegmentGrid,
}

/// Signed area (positive for counter-clockwise loops), shoelace formula.
pub fn signed_area(p: &[[f64; 2]]) -> f64 {
    let mut s = 0.0;
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        s += a[0] * b[1] - b[0] * a[1];
    }
    0.5 * s
}

/// Even–odd point-in-loop test.
fn in_loop(p: &[[f64; 2]], q: [f64; 2]) -> bool {
    let mut inside = false;
    let mut j = p.len() - 1;
    for i in 0..p.len() {
        let (a, b) = (p[i], p[j]);
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = a[0] + (q[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if q[0] < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// Which edges lie on the convex hull of the outer loop: an outer edge whose line has every
/// vertex on its inner side, n·v ≤ c (up to 10⁻⁹ of the outline's size). Holes' edges face
/// the lumen, never the outside. O(E·V), once per section.
fn hull_edges(outer: &[[f64; 2]], edges: &[Edge]) -> Vec<bool> {
    let size = outer
        .iter()
        .map(|v| v[0].abs().max(v[1].abs()))
        .fold(0.0, f64::max);
    let tol = 1e-9 * size.max(1e-300);
    edges
        .iter()
        .enumerate()
        .map(|(i, e)| {
            i < outer.len()
                && outer
                    .iter()
                    .all(|v| e.n[0] * v[0] + e.n[1] * v[1] <= e.c + tol)
        })
        .collect()
}

/// The convex hull of `pts` (Andrew's monotone chain, A. M. Andrew, Inf. Process. Lett. 9(5),
/// 1979), keeping points on its edges: every point where a linear function attains its
/// maximum over `pts` is in it.
fn convex_hull(pts: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut p = pts.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            // Pop only strict right turns: collinear points stay.
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) < 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// Proper intersection of segments p1p2 and p3p4 (shared endpoints do not count).
fn segments_cross(p1: [f64; 2], p2: [f64; 2], p3: [f64; 2], p4: [f64; 2]) -> bool {
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let d1 = orient(p3, p4, p1);
    let d2 = orient(p3, p4, p2);
    let d3 = orient(p1, p2, p3);
    let d4 = orient(p1, p2, p4);
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

impl Polygon {
    /// Builds a section from an outer loop and holes (any orientation; fixed here). Rejects
    /// loops with fewer than 3 vertices, zero area, self-intersections, holes outside the outer
    /// loop and overlapping holes.
    pub fn new(outer: Vec<[f64; 2]>, holes: Vec<Vec<[f64; 2]>>) -> Result<Self, SectionError> {
        let mut outer = clean(outer);
        let mut holes: Vec<Vec<[f64; 2]>> = holes.into_iter().map(clean).collect();
        if outer.len() < 3 || signed_area(&outer).abs() < 1e-12 {
            return Err(SectionError::Degenerate(
                "outer loop needs 3+ vertices and an area".into(),
            ));
        }
        if signed_area(&outer) < 0.0 {
            outer.reverse();
        }
        for (k, h) in holes.iter_mut().enumerate() {
            if h.len() < 3 || signed_area(h).abs() < 1e-12 {
                return Err(SectionError::Degenerate(format!(
                    "hole {k} needs 3+ vertices"
                )));
            }
            if signed_area(h) > 0.0 {
                h.reverse();
            }
        }
        let loops: Vec<&Vec<[f64; 2]>> = std::iter::once(&outer).chain(holes.iter()).collect();
        let mut segs = Vec::new();
        for l in &loops {
            for i in 0..l.len() {
                segs.push((l[i], l[(i + 1) % l.len()]));
            }
        }
        if let Some(i) = first_crossing(&segs)? {
            return Err(SectionError::Degenerate(format!(
                "outline crosses itself near ({:.3}, {:.3}) µm",
                segs[i].0[0], segs[i].0[1]
            )));
        }
        // No loop crosses another, so a hole is wholly inside the outer loop or wholly outside
        // it: one vertex tells which.
        for (k, h) in holes.iter().enumerate() {
            if !in_loop(&outer, h[0]) {
                return Err(SectionError::Degenerate(format!(
                    "hole {k} is not inside the outer loop"
                )));
            }
        }
        Ok(Self::from_checked(outer, holes, &segs))
    }

    /// A polygon from loops already checked by [`Polygon::new`] (oriented, simple).
    fn from_checked(outer: Vec<[f64; 2]>, holes: Vec<Vec<[f64; 2]>>, segs: &[Segment]) -> Self {
        let edges: Vec<Edge> = segs
            .iter()
            .map(|&(a, b)| {
                let ab = [b[0] - a[0], b[1] - a[1]];
                let len2 = ab[0] * ab[0] + ab[1] * ab[1];
                let len = len2.sqrt();
                // Counter-clockwise outer loop, clockwise holes: the right-hand normal points
                // out of the material for both.
                let n = [ab[1] / len, -ab[0] / len];
                Edge {
                    a,
                    ab,
                    inv_len2: 1.0 / len2,
                    len,
                    n,
                    c: n[0] * a[0] + n[1] * a[1],
                }
            })
            .collect();
        // About two edges per occupied cell: √E cells on the longer side of the box.
        let ends: Vec<Segment> = edges
            .iter()
            .map(|e| (e.a, [e.a[0] + e.ab[0], e.a[1] + e.ab[1]]))
            .collect();
        let grid = SegmentGrid::new(&ends, (edges.len() as f64).sqrt().clamp(1.0, 256.0));
        let on_hull = hull_edges(&outer, &edges);
        let hull = convex_hull(&outer);
        let mut normal_az: Vec<(f64, u32)> = (0..hull.len())
            .map(|i| {
                let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
                ((a[0] - b[0]).atan2(b[1] - a[1]), i as u32)
            })
            .collect();
        normal_az.sort_by(|x, y| x.0.total_cmp(&y.0));
        Self {
            outer,
            holes,
            edges,
            hull: Box::new(Hull {
                on_hull,
                vertices: hull,
                normal_az,
            }),
            grid,
        }
    }

    pub fn outer(&self) -> &[[f64; 2]] {
        &self.outer
    }

    pub fn holes(&self) -> &[Vec<[f64; 2]>] {
        &self.holes
    }

    /// True when edge `id` lies on the outline's convex hull: a ray that leaves the material
    /// through it (direction · outward normal > 0) is in the open half-plane beyond the edge's
    /// line, which holds no part of the section, so it never comes back.
    pub fn edge_on_hull(&self, id: u32) -> bool {
        self.hull.on_hull.get(id as usize).copied().unwrap_or(false)
    }

    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Material area, µm² (outer minus holes).
    pub fn area(&self) -> f64 {
        signed_area(&self.outer) + self.holes.iter().map(|h| signed_area(h)).sum::<f64>()
    }

    /// True inside the material (inside the outer loop and outside every hole).
    pub fn contains(&self, q: [f64; 2]) -> bool {
        in_loop(&self.outer, q) && !self.holes.iter().any(|h| in_loop(h, q))
    }

    /// Nearest edge crossed by o + t·d, 0 < t ≤ t_max, ignoring edge `skip` (the one the ray
    /// starts on: a straight ray cannot meet the same flat edge twice).
    pub fn intersect(
        &self,
        o: [f64; 2],
        d: [f64; 2],
        t_max: f64,
        skip: Option<u32>,
    ) -> Option<EdgeHit> {
        let g = &self.grid;
        // Clip the ray to the grid's box (slab method). The two reciprocals serve the
        // traversal's steps too: two divisions per query instead of eight.
        let (mut t0, mut t1) = (0.0f64, t_max);
        let mut inv = [0.0f64; 2];
        for k in 0..2 {
            if d[k] == 0.0 {
                if o[k] < g.min[k] || o[k] > g.max[k] {
                    return None;
                }
            } else {
                inv[k] = 1.0 / d[k];
                let inv = inv[k];
                let (mut ta, mut tb) = ((g.min[k] - o[k]) * inv, (g.max[k] - o[k]) * inv);
                if ta > tb {
                    std::mem::swap(&mut ta, &mut tb);
                }
                t0 = t0.max(ta);
                t1 = t1.min(tb);
            }
        }
        if t0 > t1 {
            return None;
        }
        // Amanatides & Woo (1987) traversal.
        let p = [o[0] + t0 * d[0], o[1] + t0 * d[1]];
        let mut cell = [0usize; 2];
        let mut step = [0isize; 2];
        let mut t_next = [f64::INFINITY; 2];
        let mut t_delta = [f64::INFINITY; 2];
        for k in 0..2 {
            // Truncation is the floor here: negative (and NaN) positions clamp to cell 0.
            let c = (p[k] - g.min[k]) * g.inv_cell[k];
            cell[k] = (c.max(0.0) as usize).min(g.n[k] - 1);
            if d[k] > 0.0 {
                step[k] = 1;
                t_delta[k] = g.cell[k] * inv[k];
                t_next[k] = (g.min[k] + (cell[k] + 1) as f64 * g.cell[k] - o[k]) * inv[k];
            } else if d[k] < 0.0 {
                step[k] = -1;
                t_delta[k] = -g.cell[k] * inv[k];
                t_next[k] = (g.min[k] + cell[k] as f64 * g.cell[k] - o[k]) * inv[k];
            }
        }
        let mut best: Option<EdgeHit> = None;
        // |cross(d, ab)| ≤ |d|·|ab|: ends farther than 10⁻⁹·|d|·|ab| from the line put the
        // crossing more than 10⁻⁹ of the edge beyond an end.
        let eps = 1e-9 * (d[0] * d[0] + d[1] * d[1]).sqrt();
        loop {
            for &e in g.cell(cell[0], cell[1]) {
                if Some(e) == skip {
                    continue;
                }
                let ed = &self.edges[e as usize];
                // The edge's ends on one side of the ray's line, beyond the 10⁻⁹ tolerance of
                // the edge parameter below: no crossing (cheaper than the division).
                let sa = d[0] * (ed.a[1] - o[1]) - d[1] * (ed.a[0] - o[0]);
                let sb = sa + d[0] * ed.ab[1] - d[1] * ed.ab[0];
                if (sa > eps * ed.len && sb > eps * ed.len)
                    || (sa < -eps * ed.len && sb < -eps * ed.len)
                {
                    continue;
                }
                let den = ed.n[0] * d[0] + ed.n[1] * d[1];
                if den == 0.0 {
                    continue;
                }
                let t = (ed.c - ed.n[0] * o[0] - ed.n[1] * o[1]) / den;
                if t <= 0.0 || t > t_max || best.is_some_and(|b| t >= b.t) {
                    continue;
                }
                let h = [o[0] + t * d[0] - ed.a[0], o[1] + t * d[1] - ed.a[1]];
                let s = (h[0] * ed.ab[0] + h[1] * ed.ab[1]) * ed.inv_len2;
                if (-1e-9..=1.0 + 1e-9).contains(&s) {
                    best = Some(EdgeHit {
                        t,
                        id: e,
                        n: ed.n,
                        c: ed.c,
                    });
                }
            }
            let k = if t_next[0] < t_next[1] { 0 } else { 1 };
            let t_exit = t_next[k];
            if best.is_some_and(|b| b.t <= t_exit) || t_exit > t1 {
                return best;
            }
            let nc = cell[k] as isize + step[k];
            if nc < 0 || nc >= g.n[k] as isize {
                return best;
            }
            cell[k] = nc as usize;
            t_next[k] += t_delta[k];
        }
    }

    /// Extent of the material along the unit vector `e`: (min, max) of q·e over the outline.
    pub fn extent(&self, e: [f64; 2]) -> (f64, f64) {
        (-self.support([-e[0], -e[1]]), self.support(e))
    }

    /// max of v·e over the outline's vertices: at the hull vertex between the two edges whose
    /// outward normals bracket e's azimuth (found by bisection), or, where rounding makes a
    /// neighbour tie, at one of its neighbours; all three are compared.
    fn support(&self, e: [f64; 2]) -> f64 {
        let (hull, normal_az) = (&self.hull.vertices, &self.hull.normal_az);
        let n = hull.len();
        if n <= 8 {
            return hull
                .iter()
                .map(|v| v[0] * e[0] + v[1] * e[1])
                .fold(f64::NEG_INFINITY, f64::max);
        }
        let az = e[1].atan2(e[0]);
        // The first edge whose normal azimuth is ≥ e's (wrapping): its start vertex.
        let k = normal_az.partition_point(|x| x.0 < az) % normal_az.len();
        let i = normal_az[k].1 as usize;
        [i + n - 1, i, i + 1]
            .iter()
            .map(|&j| {
                let v = hull[j % n];
                v[0] * e[0] + v[1] * e[1]
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Largest distance of a vertex from the origin, µm.
    pub fn bound_radius(&self) -> f64 {
        self.outer
            .iter()
            .map(|v| v[0].hypot(v[1]))
            .fold(0.0, f64::max)
    }

    /// The same outline scaled by `k > 0` about the origin and shifted by `-shift` first. A
    /// similarity keeps a simple outline simple, so the loops are not checked again.
    pub fn transformed(&self, shift: [f64; 2], k: f64) -> Result<Self, SectionError> {
        if !(k.is_finite() && k > 0.0 && shift.iter().all(|x| x.is_finite())) {
            return Err(SectionError::Degenerate(format!(
                "cannot scale by {k} or shift by ({}, {})",
                shift[0], shift[1]
            )));
        }
        let f = |l: &Vec<[f64; 2]>| -> Vec<[f64; 2]> {
            l.iter()
                .map(|v| [(v[0] - shift[0]) * k, (v[1] - shift[1]) * k])
                .collect()
        };
        let outer = f(&self.outer);
        let holes: Vec<Vec<[f64; 2]>> = self.holes.iter().map(f).collect();
        let mut segs = Vec::with_capacity(self.edges.len());
        for l in std::iter::once(&outer).chain(holes.iter()) {
            for i in 0..l.len() {
                segs.push((l[i], l[(i + 1) % l.len()]));
            }
        }
        Ok(Self::from_checked(outer, holes, &segs))
    }

    /// Area centroid of the material, µm.
    pub fn centroid(&self) -> [f64; 2] {
        let mut cx = 0.0;
        let mut cy = 0.0;
        let mut a = 0.0;
        for l in std::iter::once(&self.outer).chain(self.holes.iter()) {
            for i in 0..l.len() {
                let (p, q) = (l[i], l[(i + 1) % l.len()]);
                let cr = p[0] * q[1] - q[0] * p[1];
                cx += (p[0] + q[0]) * cr;
                cy += (p[1] + q[1]) * cr;
                a += 0.5 * cr;
            }
        }
        [cx / (6.0 * a), cy / (6.0 * a)]
    }
}

/// Most segment pairs [`first_crossing`] tests: far above any real outline (a 100,000-vertex
/// mask outline tests a few million), and a bound on the time a contrived one can take.
const MAX_PAIR_TESTS: u64 = 400_000_000;

/// The first segment (index) that properly crosses another, for any number of segments: pairs
/// are tested only where their bounding boxes share a cell of a uniform grid of about 4
/// segments per occupied cell, so a real outline costs O(n).
fn first_crossing(segs: &[Segment]) -> Result<Option<usize>, SectionError> {
    if segs
        .iter()
        .any(|(a, b)| !a.iter().chain(b).all(|x| x.is_finite()))
    {
        return Err(SectionError::Degenerate(
            "an outline coordinate is not a finite number".into(),
        ));
    }
    let grid = SegmentGrid::new(segs, (0.5 * (segs.len() as f64).sqrt()).clamp(1.0, 2048.0));
    let mut tests = 0u64;
    let mut first: Option<usize> = None;
    for l in grid.cells() {
        tests += (l.len() as u64) * (l.len() as u64).saturating_sub(1) / 2;
        if tests > MAX_PAIR_TESTS {
            return Err(SectionError::Degenerate(format!(
                "the outline ({} segments) is too intricate to check for self-crossings: more \
                 than {MAX_PAIR_TESTS} segment pairs lie close together; simplify it",
                segs.len()
            )));
        }
        for (u, &i) in l.iter().enumerate() {
            for &j in &l[u + 1..] {
                let (p, q) = (segs[i as usize], segs[j as usize]);
                if segments_cross(p.0, p.1, q.0, q.1) {
                    let k = i.min(j) as usize;
                    first = Some(first.map_or(k, |f| f.min(k)));
                }
            }
        }
    }
    Ok(first)
}

/// Drops repeated vertices (including a closing vertex equal to the first).
fn clean(mut l: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    l.dedup_by(|a, b| (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12);
    while l.len() > 1 {
        let (f, b) = (l[0], l[l.len() - 1]);
        if (f[0] - b[0]).abs() < 1e-12 && (f[1] - b[1]).abs() < 1e-12 {
            l.pop();
        } else {
            break;
        }
    }
    l
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ngon(n: usize, r: f64) -> Vec<[f64; 2]> {
        (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                [r * a.cos(), r * a.sin()]
            })
            .collect()
    }

    /// The extent along any direction from the hull's vertices equals the one from every
    /// vertex, bit for bit, on the generated sections (concave silk and cotton, a lumen) and a
    /// square with collinear points on its sides.
    #[test]
    fn hull_extent_equals_every_vertex() {
        use crate::fiber::section::generate::{generate, Shape};
        let mut square: Vec<[f64; 2]> = Vec::new();
        for k in 0..10 {
            let t = k as f64 / 10.0;
            square.extend([[t, 0.0], [1.0, t], [1.0 - t, 1.0], [0.0, 1.0 - t]]);
        }
        square.sort_by(|a, b| {
            (a[1] - 0.5)
                .atan2(a[0] - 0.5)
                .total_cmp(&(b[1] - 0.5).atan2(b[0] - 0.5))
        });
        let mut polys = vec![Polygon::new(square, vec![]).unwrap()];
        for shape in [
            Shape::Silk,
            Shape::CottonRaw,
            Shape::CottonMercerised,
            Shape::Trilobal,
        ] {
            for v in 0..3 {
                if let crate::fiber::Section::Polygon(p) = generate(shape, 12.0, 1, v).unwrap() {
                    polys.push(p);
                }
            }
        }
        assert!(polys.len() > 5);
        for p in &polys {
            eprintln!(
                "hull {} of {} vertices",
                p.hull.vertices.len(),
                p.outer.len()
            );
            for k in 0..3600 {
                let a = std::f64::consts::TAU * k as f64 / 3600.0;
                let e = [a.cos(), a.sin()];
                let brute = p
                    .outer
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |r, v| {
                        let x = v[0] * e[0] + v[1] * e[1];
                        (r.0.min(x), r.1.max(x))
                    });
                assert_eq!(p.extent(e), brute, "direction {a}");
            }
        }
    }

    /// The nearest crossing by testing every edge (`skip` aside): edge and ray parameter.
    fn brute_force(p: &Polygon, o: [f64; 2], d: [f64; 2], skip: Option<u32>) -> Option<(u32, f64)> {
        let mut brute: Option<(u32, f64)> = None;
        for (i, e) in p.edges.iter().enumerate() {
            let den = e.n[0] * d[0] + e.n[1] * d[1];
            let t = (e.c - e.n[0] * o[0] - e.n[1] * o[1]) / den;
            let h = [o[0] + t * d[0] - e.a[0], o[1] + t * d[1] - e.a[1]];
            let s = (h[0] * e.ab[0] + h[1] * e.ab[1]) * e.inv_len2;
            if Some(i as u32) != skip
                && t > 0.0
                && (0.0..=1.0).contains(&s)
                && brute.is_none_or(|b| t < b.1)
            {
                brute = Some((i as u32, t));
            }
        }
        brute
    }

    /// The grid query finds the edge brute force finds, with the same ray parameter bit for
    /// bit: from random points in any direction, and, as the tracer asks, from a point on an
    /// edge (skipped) into the material or out of it, on a polygon with a hole and on a
    /// generated raw cotton section (thin walls around a slit lumen).
    #[test]
    fn grid_query_equals_brute_force() {
        use crate::fiber::section::generate::{generate, Shape};
        let crate::fiber::section::Section::Polygon(cotton) =
            generate(Shape::CottonRaw, 12.0, 7, 0).unwrap()
        else {
            unreachable!("a raw cotton section is a polygon")
        };
        let polygons = [
            Polygon::new(ngon(300, 5.0), vec![ngon(40, 1.5)]).unwrap(),
            cotton,
        ];
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut from_edges, mut hits) = (0, 0);
        for p in &polygons {
            for i in 0..4000 {
                let a = rnd() * std::f64::consts::TAU;
                let d = [a.cos(), a.sin()];
                let (o, skip) = if i % 2 == 0 {
                    ([rnd() * 14.0 - 7.0, rnd() * 14.0 - 7.0], None)
                } else {
                    // A point on a random edge.
                    let id = (rnd() * p.edges.len() as f64) as u32;
                    let (e, f) = (&p.edges[id as usize], rnd());
                    from_edges += 1;
                    ([e.a[0] + f * e.ab[0], e.a[1] + f * e.ab[1]], Some(id))
                };
                let want = brute_force(p, o, d, skip);
                hits += want.is_some() as u32;
                let got = p.intersect(o, d, f64::INFINITY, skip);
                assert_eq!(
                    got.map(|h| (h.id, h.t.to_bits())),
                    want.map(|b| (b.0, b.1.to_bits())),
                    "o={o:?} d={d:?} skip={skip:?}"
                );
                // A shorter ray finds the same edge when it reaches it, none otherwise.
                if let Some((id, t)) = want {
                    let t_max = t * (0.5 + rnd());
                    let short = p.intersect(o, d, t_max, skip).map(|h| h.id);
                    assert_eq!(short, (t <= t_max).then_some(id));
                }
            }
        }
        assert!(from_edges > 3000 && hits > 4000, "{from_edges} {hits}");
    }

    #[test]
    fn area_and_orientation() {
        let mut outer = ngon(4, 2.0);
        outer.reverse();
        let p = Polygon::new(outer, vec![ngon(4, 1.0)]).unwrap();
        assert!((p.area() - (8.0 - 2.0)).abs() < 1e-12);
        assert!(p.contains([1.5 * 0.5f64.sqrt() * 1.2, 0.0]));
        assert!(!p.contains([0.0, 0.0]));
    }

    #[test]
    fn rejects_self_intersection_and_stray_holes() {
        let bow = vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(Polygon::new(bow, vec![]).is_err());
        let stray = vec![[5.0, 5.0], [6.0, 5.0], [6.0, 6.0]];
        assert!(Polygon::new(ngon(8, 1.0), vec![stray]).is_err());
    }

    /// Issue "hardening": the check used to be skipped above 20,000 segments.
    #[test]
    fn self_crossings_are_found_at_any_segment_count() {
        for n in [7, 20_001, 100_000] {
            let mut p = ngon(n, 10.0);
            assert!(Polygon::new(p.clone(), vec![]).is_ok(), "{n}");
            // Swap two neighbouring vertices: one small bow tie on a huge outline.
            p.swap(n / 3, n / 3 + 1);
            let e = Polygon::new(p, vec![]).unwrap_err().to_string();
            assert!(e.contains("crosses itself"), "{n}: {e}");
        }
        // A hole crossing the outer loop.
        let hole: Vec<[f64; 2]> = ngon(50, 3.0).iter().map(|v| [v[0] + 8.5, v[1]]).collect();
        assert!(Polygon::new(ngon(200, 10.0), vec![hole]).is_err());
    }
}
