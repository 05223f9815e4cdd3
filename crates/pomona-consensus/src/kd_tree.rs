//! A small static 3D kd-tree for k-nearest-neighbour and radius queries.
//!
//! Normal estimation on unorganised clusters needs each point's neighbours. Clusters are built
//! once and queried once per point, so a static tree in one flat array is enough: the points are
//! reordered so that every subtree is a contiguous range whose middle element is the splitting
//! node (split along the widest extent of the range), and ranges of at most [`LEAF_SIZE`] points
//! are scanned linearly. No allocation per query beyond the caller's output vector.

use nalgebra::Point3;

/// Ranges this small are scanned instead of split further.
const LEAF_SIZE: usize = 8;

/// A static kd-tree over the finite points of a slice; results refer to indices of that slice.
#[derive(Debug, Clone)]
pub struct KdTree {
    /// Points in tree order.
    points: Vec<[f64; 3]>,
    /// Original slice index of each tree-ordered point.
    ids: Vec<usize>,
    /// Split dimension of the node at the middle of each range (unused for leaf ranges).
    split_dim: Vec<u8>,
}

impl KdTree {
    /// Builds the tree; non-finite points are left out (they are never returned).
    pub fn build(points: &[Point3<f64>]) -> Self {
        let mut items: Vec<([f64; 3], usize)> = points
            .iter()
            .enumerate()
            .filter(|(_, p)| p.iter().all(|c| c.is_finite()))
            .map(|(i, p)| ([p.x, p.y, p.z], i))
            .collect();
        let mut split_dim = vec![0u8; items.len()];
        build_range(&mut items, &mut split_dim);
        let (points, ids) = items.into_iter().unzip();
        Self {
            points,
            ids,
            split_dim,
        }
    }

    /// Number of (finite) points in the tree.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the tree holds no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Replaces `out` by the `k` points nearest to `query` as `(index, squared distance)`,
    /// nearest first (fewer when the tree is smaller). Ties are broken by index.
    pub fn nearest_k(&self, query: &Point3<f64>, k: usize, out: &mut Vec<(usize, f64)>) {
        out.clear();
        if k == 0 || self.points.is_empty() {
            return;
        }
        let q = [query.x, query.y, query.z];
        let mut search = KnnSearch { k, best: out };
        self.knn_range(0, self.points.len(), &q, &mut search);
    }

    /// Replaces `out` by every point within `radius` of `query` as `(index, squared distance)`,
    /// in no particular order.
    pub fn within_radius(&self, query: &Point3<f64>, radius: f64, out: &mut Vec<(usize, f64)>) {
        out.clear();
        if radius.is_nan() || radius < 0.0 || self.points.is_empty() {
            return;
        }
        let q = [query.x, query.y, query.z];
        self.radius_range(0, self.points.len(), &q, radius * radius, out);
    }

    fn knn_range(&self, lo: usize, hi: usize, q: &[f64; 3], s: &mut KnnSearch<'_>) {
        if hi - lo <= LEAF_SIZE {
            for i in lo..hi {
                s.offer(self.ids[i], dist2(&self.points[i], q));
            }
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let dim = self.split_dim[mid] as usize;
        let diff = q[dim] - self.points[mid][dim];
        s.offer(self.ids[mid], dist2(&self.points[mid], q));
        let (near, far) = if diff < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.knn_range(near.0, near.1, q, s);
        if diff * diff <= s.worst() {
            self.knn_range(far.0, far.1, q, s);
        }
    }

    fn radius_range(
        &self,
        lo: usize,
        hi: usize,
        q: &[f64; 3],
        r2: f64,
        out: &mut Vec<(usize, f64)>,
    ) {
        if hi - lo <= LEAF_SIZE {
            for i in lo..hi {
                let d2 = dist2(&self.points[i], q);
                if d2 <= r2 {
                    out.push((self.ids[i], d2));
                }
            }
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let dim = self.split_dim[mid] as usize;
        let diff = q[dim] - self.points[mid][dim];
        let d2 = dist2(&self.points[mid], q);
        if d2 <= r2 {
            out.push((self.ids[mid], d2));
        }
        if diff <= 0.0 || diff * diff <= r2 {
            self.radius_range(lo, mid, q, r2, out);
        }
        if diff >= 0.0 || diff * diff <= r2 {
            self.radius_range(mid + 1, hi, q, r2, out);
        }
    }
}

fn dist2(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let (dx, dy, dz) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    dx * dx + dy * dy + dz * dz
}

fn build_range(items: &mut [([f64; 3], usize)], split_dim: &mut [u8]) {
    let n = items.len();
    if n <= LEAF_SIZE {
        return;
    }
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for (p, _) in items.iter() {
        for d in 0..3 {
            min[d] = min[d].min(p[d]);
            max[d] = max[d].max(p[d]);
        }
    }
    let dim = (0..3)
        .max_by(|&a, &b| (max[a] - min[a]).total_cmp(&(max[b] - min[b])))
        .unwrap_or(0);
    let mid = n / 2;
    items.select_nth_unstable_by(mid, |a, b| {
        a.0[dim].total_cmp(&b.0[dim]).then(a.1.cmp(&b.1))
    });
    split_dim[mid] = dim as u8;
    let (left, rest) = items.split_at_mut(mid);
    let (left_dims, rest_dims) = split_dim.split_at_mut(mid);
    build_range(left, left_dims);
    build_range(&mut rest[1..], &mut rest_dims[1..]);
}

/// The current k best, sorted ascending by (distance, index).
struct KnnSearch<'a> {
    k: usize,
    best: &'a mut Vec<(usize, f64)>,
}

impl KnnSearch<'_> {
    fn worst(&self) -> f64 {
        if self.best.len() < self.k {
            f64::INFINITY
        } else {
            self.best.last().map_or(f64::INFINITY, |b| b.1)
        }
    }

    fn offer(&mut self, id: usize, d2: f64) {
        let full = self.best.len() >= self.k;
        if full {
            match self.best.last() {
                Some(&(lid, ld)) if (d2, id) >= (ld, lid) => return,
                _ => {}
            }
        }
        let pos = self.best.partition_point(|&(bid, bd)| (bd, bid) < (d2, id));
        self.best.insert(pos, (id, d2));
        if self.best.len() > self.k {
            self.best.pop();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn brute(points: &[Point3<f64>], q: &Point3<f64>, k: usize) -> Vec<(usize, f64)> {
        let mut all: Vec<(usize, f64)> = points
            .iter()
            .enumerate()
            .filter(|(_, p)| p.iter().all(|c| c.is_finite()))
            .map(|(i, p)| (i, (p - q).norm_squared()))
            .collect();
        all.sort_by(|a, b| (a.1, a.0).partial_cmp(&(b.1, b.0)).unwrap());
        all.truncate(k);
        all
    }

    #[test]
    fn knn_matches_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut points: Vec<Point3<f64>> = (0..2000)
            .map(|_| {
                Point3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(0.0..0.1),
                )
            })
            .collect();
        points[17] = Point3::new(f64::NAN, 0.0, 0.0);
        // Duplicates exercise tie-breaking.
        points[18] = points[19];
        let tree = KdTree::build(&points);
        assert_eq!(tree.len(), 1999);
        let mut out = Vec::new();
        for t in 0..300 {
            let q = if t % 3 == 0 {
                points[t + 19]
            } else {
                Point3::new(
                    rng.gen_range(-1.2..1.2),
                    rng.gen_range(-1.2..1.2),
                    rng.gen_range(-0.1..0.2),
                )
            };
            for k in [1, 5, 16] {
                tree.nearest_k(&q, k, &mut out);
                assert_eq!(out, brute(&points, &q, k), "query {t} k {k}");
            }
            tree.within_radius(&q, 0.1, &mut out);
            let mut got: Vec<usize> = out.iter().map(|x| x.0).collect();
            got.sort_unstable();
            let want: Vec<usize> = brute(&points, &q, points.len())
                .into_iter()
                .filter(|x| x.1 <= 0.01)
                .map(|x| x.0)
                .collect::<std::collections::BTreeSet<_>>()
                .into_iter()
                .collect();
            assert_eq!(got, want);
        }
    }

    #[test]
    fn small_and_empty_trees() {
        let tree = KdTree::build(&[]);
        let mut out = vec![(0, 0.0)];
        tree.nearest_k(&Point3::origin(), 3, &mut out);
        assert!(out.is_empty() && tree.is_empty());
        let pts = [Point3::new(1.0, 0.0, 0.0), Point3::new(0.0, 0.0, 0.0)];
        let tree = KdTree::build(&pts);
        tree.nearest_k(&Point3::origin(), 5, &mut out);
        assert_eq!(out, vec![(1, 0.0), (0, 1.0)]);
    }
}
