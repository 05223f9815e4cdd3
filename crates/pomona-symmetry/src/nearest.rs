//! Exact single-nearest-neighbour queries over the few hundred points of one box.
//!
//! The symmetry-plane search asks ~1 600 nearest-neighbour queries per box (41 coarse cells × 16
//! points, then 19 × 48 points), almost all for reflected points that land on or near the box's
//! surface. [`PointGrid`] buckets the points in a uniform grid (cells in x-fastest order, points of
//! a cell contiguous and in index order, so an x-row of cells is one contiguous slice) and
//! searches growing Chebyshev shells of cells around the query's cell until no unvisited cell can
//! hold a closer point. A query whose neighbour is more than [`MAX_RINGS`] shells away falls back
//! to a [`KdTree`] built on first use.
//!
//! The result is *exactly* the one `KdTree::nearest_k(q, 1, ..)` gives: same squared distance
//! (same formula, same operand order) and the same tie rule (lowest index among equal squared
//! distances), so swapping it in changes no score, plane or detection.

use std::cell::OnceCell;

use nalgebra::Point3;
use pomona_consensus::KdTree;

/// Shells searched before falling back to the kd-tree.
pub const MAX_RINGS: usize = 2;

/// Largest number of cells along one axis.
const MAX_DIM: usize = 32;

/// Uniform grid over the finite points of a slice; results refer to indices of that slice.
#[derive(Debug)]
pub struct PointGrid<'a> {
    source: &'a [Point3<f64>],
    origin: [f64; 3],
    cell: f64,
    inv_cell: f64,
    dims: [usize; 3],
    /// `cell_start[c]..cell_start[c + 1]` are the points of cell `c` in `points` / `ids`.
    cell_start: Vec<u32>,
    points: Vec<[f64; 3]>,
    ids: Vec<u32>,
    fallback: OnceCell<KdTree>,
}

fn dist2(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let (dx, dy, dz) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    dx * dx + dy * dy + dz * dz
}

impl<'a> PointGrid<'a> {
    /// Buckets the finite points of `source` in cells of side `cell_m` (enlarged when the points
    /// span more than 32 cells along an axis).
    pub fn build(source: &'a [Point3<f64>], cell_m: f64) -> Self {
        Self::build_with(source, |_, _| cell_m)
    }

    /// Buckets the points in cells sized for about `per_cell` points per occupied cell, assuming
    /// the points sample a surface (as a box's points do): side = extent · √(per_cell / n).
    pub fn build_for_surface(source: &'a [Point3<f64>], per_cell: f64) -> Self {
        Self::build_with(source, |extent, n| {
            extent * (per_cell / n.max(1) as f64).sqrt()
        })
    }

    fn build_with(source: &'a [Point3<f64>], cell_m: impl Fn(f64, usize) -> f64) -> Self {
        let finite = |p: &&Point3<f64>| p.iter().all(|c| c.is_finite());
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in source.iter().filter(finite) {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        if lo[0] > hi[0] {
            lo = [0.0; 3];
            hi = [0.0; 3];
        }
        let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
        let cell = cell_m(extent, source.len())
            .max(extent / MAX_DIM as f64)
            .max(1e-9);
        let inv_cell = 1.0 / cell;
        let dims = [0, 1, 2].map(|a| (((hi[a] - lo[a]) * inv_cell) as usize + 1).min(MAX_DIM));
        let mut grid = Self {
            source,
            origin: lo,
            cell,
            inv_cell,
            dims,
            cell_start: vec![0; dims[0] * dims[1] * dims[2] + 1],
            points: Vec::new(),
            ids: Vec::new(),
            fallback: OnceCell::new(),
        };
        let cells: Vec<(usize, usize)> = source
            .iter()
            .enumerate()
            .filter(|(_, p)| finite(p))
            .map(|(i, p)| (i, grid.flat(grid.cell_of(&[p.x, p.y, p.z]))))
            .collect();
        for &(_, c) in &cells {
            grid.cell_start[c + 1] += 1;
        }
        for c in 1..grid.cell_start.len() {
            grid.cell_start[c] += grid.cell_start[c - 1];
        }
        let mut next = grid.cell_start.clone();
        grid.points = vec![[0.0; 3]; cells.len()];
        grid.ids = vec![0; cells.len()];
        for &(i, c) in &cells {
            let slot = next[c] as usize;
            next[c] += 1;
            let p = &source[i];
            grid.points[slot] = [p.x, p.y, p.z];
            grid.ids[slot] = i as u32;
        }
        grid
    }

    /// Cell side (metres).
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    fn cell_of(&self, q: &[f64; 3]) -> [usize; 3] {
        [0, 1, 2].map(|a| {
            let f = ((q[a] - self.origin[a]) * self.inv_cell).floor();
            if f >= 0.0 {
                (f as usize).min(self.dims[a] - 1)
            } else {
                0
            }
        })
    }

    fn flat(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// The point nearest to `query` as `(index, squared distance)`, ties broken by the lowest
    /// index — exactly `KdTree::nearest_k(query, 1, ..)`; `None` when there are no points.
    pub fn nearest(&self, query: &Point3<f64>) -> Option<(usize, f64)> {
        if self.points.is_empty() {
            return None;
        }
        let q = [query.x, query.y, query.z];
        if !q.iter().all(|c| c.is_finite()) {
            return self.kd_nearest(query);
        }
        let c = self.cell_of(&q);
        let mut best = (f64::INFINITY, u32::MAX);
        for r in 0..=MAX_RINGS {
            self.scan_shell(&q, c, r, &mut best);
            // Every unvisited point lies beyond one face of the (2r + 1)³ cube around `c` that
            // does not reach the grid's border; `gap` is the distance from `q` to the nearest one.
            let mut gap = f64::INFINITY;
            for a in 0..3 {
                if c[a] > r {
                    let lo = self.origin[a] + (c[a] - r) as f64 * self.cell;
                    gap = gap.min(q[a] - lo);
                }
                if c[a] + r + 1 < self.dims[a] {
                    let hi = self.origin[a] + (c[a] + r + 1) as f64 * self.cell;
                    gap = gap.min(hi - q[a]);
                }
            }
            if gap == f64::INFINITY {
                return Some((best.1 as usize, best.0));
            }
            // A small safety margin against rounding in the cell assignment.
            let gap = gap - 1e-9 * self.cell;
            if gap > 0.0 && best.0 < gap * gap {
                return Some((best.1 as usize, best.0));
            }
        }
        self.kd_nearest(query)
    }

    fn kd_nearest(&self, query: &Point3<f64>) -> Option<(usize, f64)> {
        let tree = self.fallback.get_or_init(|| KdTree::build(self.source));
        let mut buf = Vec::with_capacity(1);
        tree.nearest_k(query, 1, &mut buf);
        buf.first().copied()
    }

    /// Offers every point of the cells at Chebyshev distance exactly `r` from cell `c`.
    fn scan_shell(&self, q: &[f64; 3], c: [usize; 3], r: usize, best: &mut (f64, u32)) {
        let range = |a: usize| (c[a].saturating_sub(r), (c[a] + r).min(self.dims[a] - 1));
        let (x0, x1) = range(0);
        let (y0, y1) = range(1);
        let (z0, z1) = range(2);
        for z in z0..=z1 {
            let z_edge = z.abs_diff(c[2]) == r;
            for y in y0..=y1 {
                let row = (z * self.dims[1] + y) * self.dims[0];
                if z_edge || y.abs_diff(c[1]) == r {
                    self.scan_cells(q, row + x0, row + x1, best);
                } else {
                    if c[0] >= r {
                        let x = row + c[0] - r;
                        self.scan_cells(q, x, x, best);
                    }
                    if r > 0 && c[0] + r < self.dims[0] {
                        let x = row + c[0] + r;
                        self.scan_cells(q, x, x, best);
                    }
                }
            }
        }
    }

    /// Offers the points of cells `first..=last` (one contiguous slice).
    fn scan_cells(&self, q: &[f64; 3], first: usize, last: usize, best: &mut (f64, u32)) {
        let (s, e) = (
            self.cell_start[first] as usize,
            self.cell_start[last + 1] as usize,
        );
        for (p, &id) in self.points[s..e].iter().zip(&self.ids[s..e]) {
            let d2 = dist2(p, q);
            if d2 < best.0 || (d2 == best.0 && id < best.1) {
                *best = (d2, id);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn matches_the_kd_tree_exactly() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for trial in 0..20 {
            let n = 1 + trial * 37;
            // A bumpy surface patch with some clutter, like a box's points.
            let mut points: Vec<Point3<f64>> = (0..n)
                .map(|_| {
                    let (x, y): (f64, f64) =
                        (rng.gen_range(-0.06..0.06), rng.gen_range(-0.06..0.06));
                    let z = 0.8 + 0.02 * (30.0 * x).sin() + rng.gen_range(-0.003..0.003);
                    Point3::new(x, y, z)
                })
                .collect();
            if n > 3 {
                points[1] = points[0]; // an exact duplicate: tie by index
                points[2] = Point3::new(f64::NAN, 0.0, 0.8);
            }
            let tree = KdTree::build(&points);
            for cell in [0.004, 0.01, 0.03] {
                let grid = PointGrid::build(&points, cell);
                let mut buf = Vec::new();
                for _ in 0..300 {
                    let q = Point3::new(
                        rng.gen_range(-0.12..0.12),
                        rng.gen_range(-0.12..0.12),
                        rng.gen_range(0.65..0.95),
                    );
                    tree.nearest_k(&q, 1, &mut buf);
                    assert_eq!(grid.nearest(&q), buf.first().copied(), "n {n} cell {cell}");
                }
                for p in points.iter().filter(|p| p.x.is_finite()) {
                    tree.nearest_k(p, 1, &mut buf);
                    assert_eq!(grid.nearest(p), buf.first().copied());
                }
            }
        }
        assert_eq!(PointGrid::build(&[], 0.01).nearest(&Point3::origin()), None);
    }
}
