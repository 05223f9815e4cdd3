//! Pieces of one fruit (not in seed 002): a leaf or stem in front of a fruit cuts its visible
//! surface into clusters that each hold only part of it, and a part is a poor sphere to fit and
//! a descriptor that looks more like a leaf than a fruit (on the 40-frame near set, 10 of the 13
//! fruit clusters the proposal screen dropped were such pieces). Region growing cannot bridge
//! the occluder, so pairs of clusters that may be one fruit are offered again as one cluster,
//! beside the pieces themselves:
//!
//! * at about the same depth: median depths at most the largest fruit radius apart;
//! * close in the image: boxes at most `gap_radii` largest-fruit radii apart (at the nearer
//!   piece's depth), and together no wider than a largest fruit;
//! * with something *in front* between them: of the pixels on the segment between their
//!   centroids that belong to neither, at least half are valid and 1 cm nearer than both (or
//!   there are none: the pieces touch, one surface that region growing split at a depth step).
//!   Two leaves side by side, or a leaf beside a fruit, are separated by background or by a
//!   surface at their own depth; a fruit cut by a leaf is separated by that leaf.
//!
//! Used on the depth proposals (`DepthProposalParams::join_pieces`), whose unions then face the
//! proposal tests and the screen like any cluster. Joining the colour mask's clusters as well
//! was measured and not kept (no gain on held-out sets). Only pairs: three or more pieces are
//! rare, and the pairs already cost an eighth to a third more detection time
//! (docs/results.md, "Pieces of one fruit joined").

use serde::{Deserialize, Serialize};

/// Joining pairs of clusters that may be pieces of one fruit (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PieceJoining {
    /// Largest gap between the two pieces' image boxes, in radii of the largest fruit at the
    /// nearer piece's depth (0.5 measured best).
    pub gap_radii: f64,
}

impl PieceJoining {
    /// The unions of the pairs of `clusters` (sorted pixel indices of an image `width` pixels
    /// wide with depths `depth_m`, focal length `fx_px`) that may be pieces of one fruit no
    /// larger than `max_radius_m` (see the module docs), each sorted. Clusters with pixels
    /// outside the image are not of this image: then nothing is joined.
    pub fn joined(
        &self,
        clusters: &[Vec<usize>],
        width: usize,
        depth_m: &[f32],
        fx_px: f64,
        max_radius_m: f64,
    ) -> Vec<Vec<usize>> {
        let gap_radii = self.gap_radii;
        if clusters.iter().flatten().any(|&p| p >= depth_m.len()) {
            return Vec::new();
        }
        let pieces: Vec<Piece> = clusters
            .iter()
            .map(|c| Piece::of(c, width, depth_m))
            .collect();
        let mut owner = vec![u32::MAX; depth_m.len()];
        for (k, c) in clusters.iter().enumerate() {
            for &p in c {
                owner[p] = k as u32;
            }
        }
        let mut unions = Vec::new();
        for (i, a) in pieces.iter().enumerate() {
            for (j, b) in pieces.iter().enumerate().skip(i + 1) {
                let z = a.z_m.min(b.z_m);
                if !(z > 0.0 && (a.z_m - b.z_m).abs() <= max_radius_m) {
                    continue; // also NaN depths
                }
                let r_px = max_radius_m * fx_px / z;
                let gap = |lo_a: usize, hi_a: usize, lo_b: usize, hi_b: usize| {
                    lo_b.saturating_sub(hi_a).max(lo_a.saturating_sub(hi_b)) as f64
                };
                let near = gap(a.u.0, a.u.1, b.u.0, b.u.1).max(gap(a.v.0, a.v.1, b.v.0, b.v.1))
                    <= gap_radii * r_px;
                let extent = (a.u.1.max(b.u.1) - a.u.0.min(b.u.0))
                    .max(a.v.1.max(b.v.1) - a.v.0.min(b.v.0)) as f64;
                if near
                    && extent <= 2.0 * r_px
                    && cut_by_something_in_front(a, b, (i, j), &owner, width, depth_m)
                {
                    unions.push(merge_sorted(&clusters[i], &clusters[j]));
                }
            }
        }
        unions
    }
}

/// Nearer than both pieces by this much, metres, a pixel between them is in front of them.
const IN_FRONT_M: f32 = 0.01;

/// Whether what separates pieces `a` and `b` (cluster numbers `ia`, `ib` in `owner`) on the
/// image is in front of them: of the pixels on the segment between their centroids that belong
/// to neither, at least half have a valid depth nearer than both pieces by [`IN_FRONT_M`] (or
/// there are none: the pieces touch, one surface that region growing split at a depth step).
/// Two leaves side by side, or a leaf beside a fruit, are separated by background or by another
/// surface at their own depth; a fruit cut by a leaf or stem is separated by that leaf.
fn cut_by_something_in_front(
    a: &Piece,
    b: &Piece,
    (ia, ib): (usize, usize),
    owner: &[u32],
    width: usize,
    depth_m: &[f32],
) -> bool {
    let limit = (a.z_m.min(b.z_m)) as f32 - IN_FRONT_M;
    let (du, dv) = (b.centroid.0 - a.centroid.0, b.centroid.1 - a.centroid.1);
    let steps = du.abs().max(dv.abs()).ceil().max(1.0) as usize;
    let (mut between, mut in_front) = (0usize, 0usize);
    for s in 0..=steps {
        let t = s as f64 / steps as f64;
        let (u, v) = (
            (a.centroid.0 + t * du).round() as usize,
            (a.centroid.1 + t * dv).round() as usize,
        );
        let p = v * width + u;
        let Some(&k) = owner.get(p) else { continue };
        if k as usize == ia || k as usize == ib {
            continue;
        }
        between += 1;
        let d = depth_m[p];
        in_front += usize::from(d.is_finite() && d > 0.0 && d < limit);
    }
    2 * in_front >= between
}

/// What the joining test reads of a cluster: its image box (inclusive column and row ranges),
/// centroid (column, row) and median depth.
struct Piece {
    u: (usize, usize),
    v: (usize, usize),
    centroid: (f64, f64),
    z_m: f64,
}

impl Piece {
    fn of(cluster: &[usize], width: usize, depth_m: &[f32]) -> Self {
        let (mut u, mut v) = ((usize::MAX, 0), (usize::MAX, 0));
        let (mut su, mut sv) = (0.0, 0.0);
        for &i in cluster {
            let (x, y) = (i % width, i / width);
            u = (u.0.min(x), u.1.max(x));
            v = (v.0.min(y), v.1.max(y));
            su += x as f64;
            sv += y as f64;
        }
        let n = cluster.len().max(1) as f64;
        Self {
            u,
            v,
            centroid: (su / n, sv / n),
            z_m: crate::region_growing::median_depth(depth_m, cluster),
        }
    }
}

/// The union of two sorted, disjoint index lists, sorted.
fn merge_sorted(a: &[usize], b: &[usize]) -> Vec<usize> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        if a[i] < b[j] {
            out.push(a[i]);
            i += 1;
        } else {
            out.push(b[j]);
            j += 1;
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two 3×6 px pieces at 1 m, columns 10–12 and 15–17 of a 40 px wide image (fx 100 px, so a
    /// 50 mm radius is 5 px), with columns 13–14 between them at `between_m`.
    fn two_pieces(between_m: f32) -> (Vec<Vec<usize>>, Vec<f32>) {
        let width = 40;
        let mut depth = vec![f32::NAN; width * 20];
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for v in 5..11 {
            for u in 10..18 {
                let i = v * width + u;
                depth[i] = if (13..15).contains(&u) {
                    between_m
                } else {
                    1.0
                };
                match u {
                    10..=12 => a.push(i),
                    15..=17 => b.push(i),
                    _ => {}
                }
            }
        }
        (vec![a, b], depth)
    }

    #[test]
    fn pieces_cut_apart_by_something_in_front_are_joined() {
        // The pieces' boxes are 3 px apart (column 12 to column 15): 0.6 radii of 5 px.
        let p = PieceJoining { gap_radii: 0.6 };
        let join = |between_m: f32, max_radius_m: f64| {
            let (clusters, depth) = two_pieces(between_m);
            p.joined(&clusters, 40, &depth, 100.0, max_radius_m)
        };
        // A leaf 10 cm in front: one fruit seen in two pieces.
        let joined = join(0.9, 0.05);
        assert_eq!(joined.len(), 1);
        let (clusters, _) = two_pieces(0.9);
        assert_eq!(joined[0].len(), clusters[0].len() + clusters[1].len());
        assert!(joined[0].windows(2).all(|w| w[0] < w[1]));
        // Background behind the gap, or no depth there: two things side by side.
        assert!(join(1.5, 0.05).is_empty());
        assert!(join(f32::NAN, 0.05).is_empty());
        // Together wider than the largest fruit (a 30 mm radius is 3 px: 8 px > 6 px).
        assert!(join(0.9, 0.03).is_empty());
        // Pieces touching (the gap belongs to neither but is absent): one surface split at a
        // depth step.
        let (mut clusters, depth) = two_pieces(1.0);
        let width = 40;
        for v in 5..11 {
            clusters[0].extend([v * width + 13, v * width + 14]);
        }
        clusters[0].sort_unstable();
        assert_eq!(p.joined(&clusters, width, &depth, 100.0, 0.05).len(), 1);
        // Depths a radius apart are not one fruit's surface.
        let (clusters, mut depth) = two_pieces(0.9);
        for &i in &clusters[1] {
            depth[i] = 1.06;
        }
        assert!(p.joined(&clusters, width, &depth, 100.0, 0.05).is_empty());
        // Clusters of another image (pixels beyond this one's): nothing joined, no panic.
        let (mut clusters, depth) = two_pieces(0.9);
        clusters[1].push(depth.len());
        assert!(p.joined(&clusters, width, &depth, 100.0, 0.05).is_empty());
        // Farther apart than the gap allows: nothing joined.
        let (clusters, depth) = two_pieces(0.9);
        let tight = PieceJoining { gap_radii: 0.5 };
        assert!(tight
            .joined(&clusters, width, &depth, 100.0, 0.05)
            .is_empty());
    }
}
