//! A uniform grid over line segments: each cell lists the segments whose bounding box touches
//! it. One structure serves the three queries on outlines: a polygon's ray queries (Amanatides
//! & Woo traversal, [`super::Polygon::intersect`]), the self-crossing check (pairs that share a
//! cell) and the symmetry test (is a point near the outline, [`crate::fiber::symmetry`]).

/// A segment from `.0` to `.1`, µm.
pub type Segment = ([f64; 2], [f64; 2]);

#[derive(Debug, Clone)]
pub struct SegmentGrid {
    /// The padded bounding box of the segments.
    pub min: [f64; 2],
    pub max: [f64; 2],
    /// Cell size, its inverse and the count per axis.
    pub cell: [f64; 2],
    pub inv_cell: [f64; 2],
    pub n: [usize; 2],
    start: Vec<u32>,
    items: Vec<u32>,
}

impl SegmentGrid {
    /// The grid of `segs` with `side` cells along the longer side of their bounding box (padded
    /// by 10⁻⁶ of its size, so points on the box's edge fall inside).
    pub fn new(segs: &[Segment], side: f64) -> SegmentGrid {
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        for (a, b) in segs {
            for p in [a, b] {
                for k in 0..2 {
                    min[k] = min[k].min(p[k]);
                    max[k] = max[k].max(p[k]);
                }
            }
        }
        let pad = 1e-6 * (max[0] - min[0]).max(max[1] - min[1]);
        for k in 0..2 {
            min[k] -= pad;
            max[k] += pad;
        }
        let size = [max[0] - min[0], max[1] - min[1]];
        let longer = size[0].max(size[1]);
        let n = [
            ((side * size[0] / longer).ceil() as usize).max(1),
            ((side * size[1] / longer).ceil() as usize).max(1),
        ];
        let cell = [size[0] / n[0] as f64, size[1] / n[1] as f64];
        let mut g = SegmentGrid {
            min,
            max,
            cell,
            inv_cell: [1.0 / cell[0], 1.0 / cell[1]],
            n,
            start: Vec::new(),
            items: Vec::new(),
        };
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n[0] * n[1]];
        for (i, (a, b)) in segs.iter().enumerate() {
            let lo = g.cell_of([a[0].min(b[0]), a[1].min(b[1])]);
            let hi = g.cell_of([a[0].max(b[0]), a[1].max(b[1])]);
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    lists[y * n[0] + x].push(i as u32);
                }
            }
        }
        g.start.reserve(lists.len() + 1);
        g.start.push(0);
        for l in &lists {
            g.items.extend_from_slice(l);
            g.start.push(g.items.len() as u32);
        }
        g
    }

    /// The cell holding `p`, clamped to the grid.
    pub fn cell_of(&self, p: [f64; 2]) -> [usize; 2] {
        std::array::from_fn(|k| {
            // Truncation is the floor for the non-negative values kept (negatives clamp to 0).
            (((p[k] - self.min[k]) / self.cell[k]).max(0.0) as usize).min(self.n[k] - 1)
        })
    }

    /// The segments listed in cell (`x`, `y`).
    pub fn cell(&self, x: usize, y: usize) -> &[u32] {
        let c = y * self.n[0] + x;
        &self.items[self.start[c] as usize..self.start[c + 1] as usize]
    }

    /// Every cell's list, row by row.
    pub fn cells(&self) -> impl Iterator<Item = &[u32]> {
        self.start
            .windows(2)
            .map(|w| &self.items[w[0] as usize..w[1] as usize])
    }
}
