//! Depth proposals (not in seed 002): clusters grown on depth alone, offered to the shape fit
//! beside the colour-mask clusters, so that fruit whose colour the leaves share are still found.
//!
//! Seed 002 clusters only the pixels its colour model calls fruit. On randomised worlds that is
//! where most missed fruit are lost: unripe green peppers, guavas and apples put fewer than
//! 20 % of their pixels through the mask, so they never become candidates, and no ranking
//! can bring them back (AP equalled the largest recall reached, docs/results.md §"Depth
//! proposals and hard-negative mining"). Region growing on depth alone gives each of these fruit its own cluster, but
//! also about 170 clusters of leaves, stems and ground per frame; the classifier, trained on
//! such candidates too (training always adds them), ranks them. Two cheap tests drop the
//! clusters that cannot add a fruit before the shape fit pays for them, and the detector's
//! screen (`screen_min_score`, `crate::stages::ProposalScreenStage`) drops most of the rest:
//!
//! * **already seen**: at least `max_color_coverage` of the cluster's pixels passed the colour
//!   mask, so the colour path clustered that surface already;
//! * **not the size of a fruit**: the cluster covers more than `max_fruit_discs` discs of the
//!   largest fitted radius at its median depth, `π (r_max · fx / z)²` pixels, or fewer than
//!   `min_fruit_discs` discs of the smallest. On the training worlds no cluster above 1.2 discs
//!   of the largest radius held a fruit, while the few larger clusters (ground, leaf walls) hold
//!   20–50 % of all clustered pixels; the lower limit drops leaf specks.
//!
//! A learned gate on cluster statistics (size, PCA extents, a least-squares sphere, colour) was
//! measured too: at 98 % of the fruit clusters kept it still passed 55–75 % of the others, not
//! worth a model.
//!
//! * **pieces of one fruit** (`join_gap_radii`, off by default): a leaf or stem in front cuts a
//!   fruit's visible surface into clusters that each hold only part of it; pairs of clusters at
//!   about the same depth, close in the image and together no larger than a fruit are also
//!   proposed as one cluster, so that the shape fit and the descriptor see the fruit's whole
//!   visible surface.

use serde::{Deserialize, Serialize};

/// Whether and how depth proposals are made.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DepthProposalParams {
    /// Propose depth-only clusters at all (models with a colour model only; a depth-only model
    /// clusters on depth anyway). Default on; absent in older model files, which keep the
    /// paper's colour-only clusters.
    pub enabled: bool,
    /// A depth cluster with at least this fraction of its pixels in the colour mask is left to
    /// the colour path (default 0.5).
    pub max_color_coverage: f64,
    /// A depth cluster larger than this many discs of the largest fitted radius at its median
    /// depth is dropped (default 2).
    pub max_fruit_discs: f64,
    /// A depth cluster smaller than this many discs of the smallest fitted radius at its median
    /// depth is dropped (default 0.3, twice the mask clusters' limit: on the held-out synthetic
    /// sets it drops 30–45 % of the proposals, mean wide AP 0.845 at 0.15 and 0.849 at 0.3).
    pub min_fruit_discs: f64,
    /// The screen: a proposal goes on to the shape fit only when the detector's classifier scores
    /// the GPCD of the whole cluster (no shape fitted, at most `screen_points` strided pixels) at
    /// least this; `None` sends every proposal on. Default −1, the negative edge of the SVM's
    /// margin.
    pub screen_min_score: Option<f64>,
    /// Pixels of a cluster the screen's descriptor uses, at most (default 64).
    pub screen_points: usize,
    /// Pieces of one fruit: two depth clusters whose median depths differ by at most the largest
    /// fitted radius, whose image boxes lie at most this many largest-fruit radii apart (at the
    /// nearer cluster's depth) and whose joint image box fits in one largest fruit are also
    /// proposed as one cluster (when that passes the tests above). `None` (the default, and
    /// older model files) joins nothing.
    pub join_gap_radii: Option<f64>,
}

impl Default for DepthProposalParams {
    fn default() -> Self {
        Self {
            enabled: true,
            max_color_coverage: 0.5,
            max_fruit_discs: 2.0,
            min_fruit_discs: 0.3,
            screen_min_score: Some(-1.0),
            screen_points: 64,
            join_gap_radii: None,
        }
    }
}

impl DepthProposalParams {
    /// Switched off: what a model file without the key means.
    pub fn off() -> Self {
        Self {
            enabled: false,
            ..Self::default()
        }
    }

    /// Whether a depth-only `cluster` (pixel indices) is proposed: fewer than
    /// `max_color_coverage` of its pixels in `color_mask`, and between `min_fruit_discs` discs of
    /// radius `min_radius_m` and `max_fruit_discs` discs of radius `max_radius_m` at its median
    /// depth (`depth_m`, focal length `fx_px`).
    pub fn proposes(
        &self,
        cluster: &[usize],
        color_mask: &[bool],
        depth_m: &[f32],
        fx_px: f64,
        (min_radius_m, max_radius_m): (f64, f64),
    ) -> bool {
        if cluster.is_empty() {
            return false;
        }
        let covered = cluster
            .iter()
            .filter(|&&i| color_mask.get(i).copied().unwrap_or(false))
            .count();
        if covered as f64 >= self.max_color_coverage * cluster.len() as f64 {
            return false;
        }
        let z_m = crate::region_growing::median_depth(depth_m, cluster);
        if !(z_m.is_finite() && z_m > 0.0) {
            return false;
        }
        let disc_px = |r_m: f64| std::f64::consts::PI * (r_m * fx_px / z_m).powi(2);
        let n = cluster.len() as f64;
        n >= self.min_fruit_discs * disc_px(min_radius_m)
            && n <= self.max_fruit_discs * disc_px(max_radius_m)
    }

    /// The unions of pairs of `clusters` (sorted pixel indices of an image `width` pixels wide)
    /// that may be pieces of one fruit (see `join_gap_radii`); none when joining is off. Each
    /// union is sorted; whether it is proposed is left to [`DepthProposalParams::proposes`].
    pub fn joined_pieces(
        &self,
        clusters: &[Vec<usize>],
        width: usize,
        depth_m: &[f32],
        fx_px: f64,
        max_radius_m: f64,
    ) -> Vec<Vec<usize>> {
        let Some(gap_radii) = self.join_gap_radii else {
            return Vec::new();
        };
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

    #[test]
    fn clusters_the_colour_path_saw_or_not_fruit_sized_are_not_proposed() {
        let p = DepthProposalParams::default();
        // 100 pixels at 1 m, fx 100 px: a 50 mm radius is a 5 px disc, 78.5 px².
        let depth = vec![1.0_f32; 200];
        let cluster: Vec<usize> = (0..100).collect();
        let none = vec![false; 200];
        let radii = (0.02, 0.05);
        assert!(p.proposes(&cluster, &none, &depth, 100.0, radii));
        // Half of it in the colour mask: the colour path has it.
        let mut half = none.clone();
        half[..50].fill(true);
        assert!(!p.proposes(&cluster, &half, &depth, 100.0, radii));
        half[49] = false;
        assert!(p.proposes(&cluster, &half, &depth, 100.0, radii));
        // 100 px > 2 discs of 30 mm (2 × 28.3 px²): larger than any fruit.
        assert!(!p.proposes(&cluster, &none, &depth, 100.0, (0.02, 0.03)));
        // The same cluster twice as far away is four times the area.
        let far = vec![2.0_f32; 200];
        assert!(!p.proposes(&cluster, &none, &far, 100.0, radii));
        // 100 px < 0.3 discs of 120 mm (0.3 × 452 px²): smaller than the smallest fruit.
        assert!(!p.proposes(&cluster, &none, &depth, 100.0, (0.12, 0.2)));
        assert!(p.proposes(&cluster, &none, &depth, 100.0, (0.1, 0.2)));
        assert!(!p.proposes(&[], &none, &depth, 100.0, radii));
    }

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
        let p = DepthProposalParams {
            join_gap_radii: Some(0.6),
            ..Default::default()
        };
        let join = |between_m: f32, max_radius_m: f64| {
            let (clusters, depth) = two_pieces(between_m);
            p.joined_pieces(&clusters, 40, &depth, 100.0, max_radius_m)
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
        assert_eq!(
            p.joined_pieces(&clusters, width, &depth, 100.0, 0.05).len(),
            1
        );
        // Depths a radius apart are not one fruit's surface.
        let (clusters, mut depth) = two_pieces(0.9);
        for &i in &clusters[1] {
            depth[i] = 1.06;
        }
        assert!(p
            .joined_pieces(&clusters, width, &depth, 100.0, 0.05)
            .is_empty());
        // Farther apart than the gap allows, or joining off: nothing joined.
        let (clusters, depth) = two_pieces(0.9);
        let tight = DepthProposalParams {
            join_gap_radii: Some(0.5),
            ..Default::default()
        };
        assert!(tight
            .joined_pieces(&clusters, width, &depth, 100.0, 0.05)
            .is_empty());
        let off = DepthProposalParams::default();
        assert!(off
            .joined_pieces(&clusters, width, &depth, 100.0, 0.05)
            .is_empty());
    }
}
