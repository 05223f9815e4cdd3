//! A static 3D kd-tree with bucket leaves, for k-nearest-neighbour and radius queries.
//!
//! Normal estimation on unorganised clouds needs each point's neighbours; the cloud is built
//! once and queried once per point, so the tree is static and laid out for the cache:
//! * the points are reordered so that every node is a contiguous range of one flat array of
//!   `(position, index)` entries (32 bytes, two per cache line), split at the median along the
//!   range's widest extent until a range holds at most [`LEAF_SIZE`] points — a leaf is one
//!   linear scan;
//! * nodes live in one array (children by index), holding the split plane only;
//! * a query keeps, per axis, its distance to the cell it is visiting, so a far child is skipped
//!   when the whole cell (not just its splitting plane) is farther than the current k-th
//!   neighbour (the incremental distance of Arya & Mount, as in nanoflann, which Open3D uses);
//! * candidates for the k best are appended to the caller's reused vector and cut back to the k
//!   smallest (linear-time selection) whenever 2k have gathered: O(1) amortised per candidate,
//!   no allocation per query, one sort of k at the end;
//! * [`KdTree::tree_order`] lists the points in tree order (spatially coherent), so
//!   consecutive queries touch the same leaves — how `KnnNormals` queries every point.
//!
//! Results are exact and deterministic: the `k` smallest `(squared distance, index)` pairs, the
//! squared distance computed as `dx² + dy² + dz²` in `f64`.

use nalgebra::Point3;

use crate::Positioned;

/// Ranges this small are scanned instead of split further.
const LEAF_SIZE: usize = 12;

/// Marks a leaf in [`Node::left`].
const LEAF: u32 = u32::MAX;

/// A point in tree order with its index in the input slice.
#[derive(Debug, Clone, Copy)]
struct Entry {
    p: [f64; 3],
    id: usize,
}

/// One node: a leaf (`left == LEAF`) owns `entries[lo..hi]`; an inner node splits at `split`
/// along `dim`, its left child holding coordinates `<= split`, its right child `>= split`.
#[derive(Debug, Clone, Copy)]
struct Node {
    lo: u32,
    hi: u32,
    split: f64,
    dim: u8,
    left: u32,
    right: u32,
}

/// A static kd-tree over the finite points of a slice; results refer to indices of that slice.
#[derive(Debug, Clone)]
pub struct KdTree {
    entries: Vec<Entry>,
    nodes: Vec<Node>,
}

impl KdTree {
    /// Builds the tree; non-finite points are left out (they are never returned).
    pub fn build(points: &[Point3<f64>]) -> Self {
        let mut entries: Vec<Entry> = points
            .iter()
            .enumerate()
            .filter(|(_, p)| p.has_finite_position())
            .map(|(id, p)| Entry {
                p: [p.x, p.y, p.z],
                id,
            })
            .collect();
        let mut nodes = Vec::with_capacity(2 * entries.len() / LEAF_SIZE + 1);
        if !entries.is_empty() {
            build_node(&mut entries, 0, &mut nodes);
        }
        Self { entries, nodes }
    }

    /// Number of (finite) points in the tree.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the tree holds no points.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Every point as `(index, position)` in tree order: neighbouring points come close together,
    /// so queries issued in this order reuse the cache.
    pub fn tree_order(&self) -> impl ExactSizeIterator<Item = (usize, Point3<f64>)> + '_ {
        self.entries.iter().map(|e| (e.id, Point3::from(e.p)))
    }

    /// Replaces `out` by the `k` points nearest to `query` as `(index, squared distance)`,
    /// nearest first (fewer when the tree is smaller). Ties are broken by index.
    pub fn nearest_k(&self, query: &Point3<f64>, k: usize, out: &mut Vec<(usize, f64)>) {
        self.nearest_k_within(query, k, f64::INFINITY, out);
    }

    /// As [`KdTree::nearest_k`], among the points within squared distance `bound2` of `query`
    /// only: fewer than `k` when fewer lie that close. A caller that knows a bound on the k-th
    /// distance (for example from a nearby query's result, by the triangle inequality) gets the
    /// same answer as `nearest_k` sooner, and knows the bound was too small when fewer than `k`
    /// come back.
    pub fn nearest_k_within(
        &self,
        query: &Point3<f64>,
        k: usize,
        bound2: f64,
        out: &mut Vec<(usize, f64)>,
    ) {
        out.clear();
        if k == 0 || self.entries.is_empty() || bound2.is_nan() {
            return;
        }
        let q = [query.x, query.y, query.z];
        let mut search = KnnSearch {
            k,
            worst: bound2,
            best: out,
        };
        let mut off = [0.0; 3];
        self.visit(0, &q, &mut off, &mut search);
        search.finish();
    }

    /// Replaces `out` by every point within `radius` of `query` as `(index, squared distance)`,
    /// in no particular order.
    pub fn within_radius(&self, query: &Point3<f64>, radius: f64, out: &mut Vec<(usize, f64)>) {
        out.clear();
        if radius.is_nan() || radius < 0.0 || self.entries.is_empty() {
            return;
        }
        let q = [query.x, query.y, query.z];
        let mut off = [0.0; 3];
        let mut search = RadiusSearch {
            r2: radius * radius,
            found: out,
        };
        self.visit(0, &q, &mut off, &mut search);
    }

    /// Visits every point of the subtree of `node` that lies within the visitor's current bound,
    /// nearer child first. `off` holds, per axis, the squared distance from `q` to the cell being
    /// visited, so a far child is skipped when its whole cell (not just its splitting plane) lies
    /// beyond the bound.
    fn visit<V: Visitor>(&self, node: u32, q: &[f64; 3], off: &mut [f64; 3], v: &mut V) {
        let n = &self.nodes[node as usize];
        if n.left == LEAF {
            for e in &self.entries[n.lo as usize..n.hi as usize] {
                let d2 = dist2(&e.p, q);
                if d2 <= v.bound() {
                    v.accept(e.id, d2);
                }
            }
            return;
        }
        let dim = n.dim as usize;
        let diff = q[dim] - n.split;
        let (near, far) = if diff < 0.0 {
            (n.left, n.right)
        } else {
            (n.right, n.left)
        };
        self.visit(near, q, off, v);
        // The far cell lies beyond the splitting plane: its distance along `dim` is at least
        // |diff|, along the other axes what the enclosing cell already had.
        let saved = off[dim];
        off[dim] = diff * diff;
        if off[0] + off[1] + off[2] <= v.bound() {
            self.visit(far, q, off, v);
        }
        off[dim] = saved;
    }
}

/// What a tree walk does with the points it reaches: [`KnnSearch`] (the bound shrinks as better
/// points arrive) and [`RadiusSearch`] (a fixed bound).
trait Visitor {
    /// Points (and cells) with a larger squared distance are not visited.
    fn bound(&self) -> f64;
    /// A point with squared distance `d2 <= self.bound()`.
    fn accept(&mut self, id: usize, d2: f64);
}

/// Every point within a fixed squared distance.
struct RadiusSearch<'a> {
    r2: f64,
    found: &'a mut Vec<(usize, f64)>,
}

impl Visitor for RadiusSearch<'_> {
    #[inline]
    fn bound(&self) -> f64 {
        self.r2
    }

    #[inline]
    fn accept(&mut self, id: usize, d2: f64) {
        self.found.push((id, d2));
    }
}

fn dist2(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let (dx, dy, dz) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    dx * dx + dy * dy + dz * dz
}

/// Builds the node of `entries` (which start at `offset` in the tree's array) and its subtree;
/// returns the node's index.
fn build_node(entries: &mut [Entry], offset: usize, nodes: &mut Vec<Node>) -> u32 {
    let n = entries.len();
    let index = nodes.len() as u32;
    nodes.push(Node {
        lo: offset as u32,
        hi: (offset + n) as u32,
        split: 0.0,
        dim: 0,
        left: LEAF,
        right: LEAF,
    });
    if n <= LEAF_SIZE {
        return index;
    }
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for e in entries.iter() {
        for d in 0..3 {
            min[d] = min[d].min(e.p[d]);
            max[d] = max[d].max(e.p[d]);
        }
    }
    let dim = (0..3)
        .max_by(|&a, &b| (max[a] - min[a]).total_cmp(&(max[b] - min[b])))
        .unwrap_or(0);
    let mid = n / 2;
    entries.select_nth_unstable_by(mid, |a, b| {
        a.p[dim].total_cmp(&b.p[dim]).then(a.id.cmp(&b.id))
    });
    let split = entries[mid].p[dim];
    let (left, right) = entries.split_at_mut(mid);
    let l = build_node(left, offset, nodes);
    let r = build_node(right, offset + mid, nodes);
    let node = &mut nodes[index as usize];
    node.split = split;
    node.dim = dim as u8;
    node.left = l;
    node.right = r;
    index
}

/// Orders candidates by squared distance, then index: for the non-negative, non-NaN squared
/// distances here the IEEE bit pattern orders like the value, so the key is one integer: the bits, then the index.
#[inline]
fn distance_then_index(c: &(usize, f64)) -> u128 {
    (u128::from(c.1.to_bits()) << 64) | c.0 as u128
}

/// The candidates for the k best, and the squared distance a point must not exceed to enter:
/// the bound until `k` are known, then the k-th distance.
///
/// Candidates are appended unsorted; when `2k` have gathered, the k smallest are selected
/// (linear time) and the rest dropped, which tightens `worst`. Each offer thus costs O(1)
/// amortised instead of an insertion into a sorted list, and [`KnnSearch::finish`] sorts only
/// the k survivors.
struct KnnSearch<'a> {
    k: usize,
    worst: f64,
    best: &'a mut Vec<(usize, f64)>,
}

impl Visitor for KnnSearch<'_> {
    #[inline]
    fn bound(&self) -> f64 {
        self.worst
    }

    #[inline]
    fn accept(&mut self, id: usize, d2: f64) {
        self.best.push((id, d2));
        if self.best.len() >= 2 * self.k {
            self.keep_k();
        }
    }
}

impl KnnSearch<'_> {
    /// Keeps the k smallest candidates (unordered); the k-th becomes the bound.
    fn keep_k(&mut self) {
        let k = self.k;
        if self.best.len() > k {
            self.best
                .select_nth_unstable_by_key(k - 1, distance_then_index);
            self.best.truncate(k);
            // After the selection the k-th smallest sits last.
            self.worst = self.best[k - 1].1;
        }
    }

    /// The k best, nearest first.
    fn finish(mut self) {
        self.keep_k();
        self.best.sort_unstable_by_key(distance_then_index);
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
            .map(|(i, p)| (i, dist2(&[p.x, p.y, p.z], &[q.x, q.y, q.z])))
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
        // A run of points on one grid line: many equal coordinates and equal distances.
        for i in 0..60 {
            points[100 + i] = Point3::new(0.25, (i % 12) as f64 * 0.01, 0.05);
        }
        let tree = KdTree::build(&points);
        assert_eq!(tree.len(), 1999);
        let mut out = Vec::new();
        for t in 0..300 {
            let q = if t % 3 == 0 {
                points[t + 19]
            } else if t % 3 == 1 && t < 100 {
                Point3::new(0.25, 0.055, 0.05)
            } else {
                Point3::new(
                    rng.gen_range(-1.2..1.2),
                    rng.gen_range(-1.2..1.2),
                    rng.gen_range(-0.1..0.2),
                )
            };
            for k in [1, 5, 16, 30] {
                tree.nearest_k(&q, k, &mut out);
                assert_eq!(out, brute(&points, &q, k), "query {t} k {k}");
            }
            tree.within_radius(&q, 0.1, &mut out);
            let mut got: Vec<usize> = out.iter().map(|x| x.0).collect();
            got.sort_unstable();
            let want: Vec<usize> = brute(&points, &q, points.len())
                .into_iter()
                .filter(|x| x.1 <= 0.1 * 0.1)
                .map(|x| x.0)
                .collect::<std::collections::BTreeSet<_>>()
                .into_iter()
                .collect();
            assert_eq!(got, want);
        }
        // Tree order visits every finite point once.
        let mut seen: Vec<usize> = tree.tree_order().map(|(i, _)| i).collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..2000).filter(|&i| i != 17).collect::<Vec<_>>());
    }

    #[test]
    fn small_and_empty_trees() {
        let tree = KdTree::build(&[]);
        let mut out = vec![(0, 0.0)];
        tree.nearest_k(&Point3::origin(), 3, &mut out);
        assert!(out.is_empty() && tree.is_empty());
        tree.within_radius(&Point3::origin(), 1.0, &mut out);
        assert!(out.is_empty());
        let pts = [Point3::new(1.0, 0.0, 0.0), Point3::new(0.0, 0.0, 0.0)];
        let tree = KdTree::build(&pts);
        tree.nearest_k(&Point3::origin(), 5, &mut out);
        assert_eq!(out, vec![(1, 0.0), (0, 1.0)]);
    }
}
