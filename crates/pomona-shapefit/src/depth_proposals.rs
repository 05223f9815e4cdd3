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
//! Pieces of one fruit cut apart by a leaf in front can also be joined into one proposal
//! (`join_pieces`, [`PieceJoining`], opt-in).
//!
//! A proposal's shapes then face a free-space check of their own (`free_space`), stricter than
//! the colour path's: with no colour to vouch for it, a proposal must look like an opaque solid,
//! and a clump of leaves that a sphere fits shows the background through its gaps all over its
//! disc. Proposals made about half of shape-fit's false detections at the operating confidence
//! on `wide` test sets; on the 24 held-out ones the strict check removed 27 of the 131 and no
//! true detection (docs/results.md, "Depth proposals held to what an opaque solid shows").

use pomona_pipeline::FreeSpaceCheck;
use serde::{Deserialize, Serialize};

use crate::PieceJoining;

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
    /// Pairs of depth clusters that may be pieces of one fruit cut apart by a leaf in front are
    /// also proposed as one cluster ([`PieceJoining`]; each union then faces the tests above and
    /// the screen). Off (`None`) by default and in older model files: on the 24 held-out wide
    /// sets `gap_radii` 0.5 gained 0.011 AP for 12–38 % more detection time and a little
    /// precision at the operating point (docs/results.md, "Pieces of one fruit joined");
    /// `--set 'params.depth_proposals.join_pieces={"gap_radii":0.5}'` turns it on.
    pub join_pieces: Option<PieceJoining>,
    /// The free-space check of the proposals' shapes, in place of the model's `free_space`
    /// (`None`: the model's, what older model files mean). A proposal has no colour to say
    /// it is fruit, only its geometry, so it is held to what an opaque solid shows: hardly
    /// any depth reading behind its centre anywhere in the middle of its disc. The colour
    /// path keeps the lenient check, whose room is for real sensors' mixed pixels at a
    /// fruit's rim (see `pomona_pipeline::FreeSpaceCheck`).
    pub free_space: Option<FreeSpaceCheck>,
    /// A depth cluster left to the colour path (`max_color_coverage`) can hold a fruit the
    /// colour mask missed beside one it found — a green guava touching a yellow one, the two
    /// one surface to region growing. With this on, the pixels outside the colour mask of every
    /// such cluster are grown into clusters again and proposed under the same tests (and the
    /// screen); a shape fitted to one counts only when its core and a colour-path shape's are
    /// further apart than the larger radius (closer, it is a piece of that fruit: a leaf's
    /// shadow or an unripe end). Detection only, like the rest of the proposals. Default on;
    /// `false` is the detector before (docs/results.md, "Fruit the colour path's clusters
    /// swallowed").
    pub regrow_covered: bool,
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
            join_pieces: None,
            free_space: Some(FreeSpaceCheck::strict()),
            regrow_covered: true,
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

    /// Whether at least `max_color_coverage` of `cluster`'s pixels are in `color_mask`: the
    /// colour path clustered that surface already.
    pub fn covered(&self, cluster: &[usize], color_mask: &[bool]) -> bool {
        let covered = cluster
            .iter()
            .filter(|&&i| color_mask.get(i).copied().unwrap_or(false))
            .count();
        covered as f64 >= self.max_color_coverage * cluster.len() as f64
    }

    /// Whether a depth-only `cluster` (pixel indices) is proposed: not [`Self::covered`] by
    /// `color_mask`, and [`Self::fruit_sized`].
    pub fn proposes(
        &self,
        cluster: &[usize],
        color_mask: &[bool],
        depth_m: &[f32],
        fx_px: f64,
        radius_range_m: (f64, f64),
    ) -> bool {
        !cluster.is_empty()
            && !self.covered(cluster, color_mask)
            && self.fruit_sized(cluster, depth_m, fx_px, radius_range_m)
    }

    /// Whether `cluster` covers between `min_fruit_discs` discs of radius `min_radius_m` and
    /// `max_fruit_discs` discs of radius `max_radius_m` at its median depth (`depth_m`, focal
    /// length `fx_px`).
    pub fn fruit_sized(
        &self,
        cluster: &[usize],
        depth_m: &[f32],
        fx_px: f64,
        (min_radius_m, max_radius_m): (f64, f64),
    ) -> bool {
        let Some(disc_px) = crate::region_growing::disc_area_px(depth_m, fx_px, cluster) else {
            return false;
        };
        let n = cluster.len() as f64;
        n >= self.min_fruit_discs * disc_px(min_radius_m)
            && n <= self.max_fruit_discs * disc_px(max_radius_m)
    }
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
}
