//! Clusters larger than any fruit, grown again with a smaller depth step (not in seed 002).
//!
//! Region growing joins neighbours whose depths differ by at most a fixed step (the paper's
//! 5 mm). How far apart two neighbouring readings of one surface lie depends on the sensor: its
//! pixel size (a fruit's flank steps less per pixel on a 1920×1080 camera than on a 512×424 one)
//! and its noise (per-pixel time-of-flight or stereo noise against depth that a registration to
//! a colour camera has interpolated). No one step serves every camera: on real Azure Kinect
//! frames 5 mm joins fruit, the leaves touching them and the branch behind into clusters the
//! size of the canopy, while 2 mm shatters a noisy synthetic frame of the same camera into specks.
//!
//! The split lets each cluster say which case it is. A cluster covering more than `max_discs`
//! discs of the largest fruit at its median depth cannot be one fruit, so it is grown again
//! from its own pixels with half the step. When the pieces that pass the size limit still hold
//! at least `min_kept_fraction` of its pixels, the surface was smooth enough to separate: the
//! pieces replace it, and those still too large are split again, up to `max_halvings` times.
//! When they do not, halving the step shattered a noisy surface, and the cluster is kept as it
//! was. Clusters of fruit size are never touched, so on the cameras the step was chosen for
//! the clusters that hold fruit stay what they were.
//!
//! # Where it runs
//! On the clusters the classifier's candidates come from: the colour mask's, or, in a
//! depth-only model, those of every pixel in depth range. Not on a colour model's depth
//! proposals (every pixel in range, for fruit the mask misses): split there, the canopy turns
//! into many more fruit-sized proposals, each screened and fitted, for no fruit more. Measured
//! on the real `ak-apples` frames with the built-in colour model (docs/results.md, "The split
//! on the colour path only"): split in both places 50 → 53 tagged apples at the operating
//! confidence and 10 → 13 other detections, at +25–75 % time a frame; in the colour path only,
//! the same 53 apples with 10 others, at the time of no split; in the proposals only, no apple
//! more.

use serde::{Deserialize, Serialize};

use crate::region_growing::{disc_area_px, grow_regions_over, RegionGrowingParams};

/// When and how far oversized clusters are split.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OversizedSplit {
    /// Radius of the largest expected fruit, metres.
    pub radius_m: f64,
    /// A cluster covering more than this many discs of `radius_m` at its median depth is grown
    /// again (default 2, the depth proposals' `max_fruit_discs`).
    pub max_discs: f64,
    /// Times the step may be halved (default 2: the paper's 5 mm, then 2.5 and 1.25 mm).
    pub max_halvings: u32,
    /// The pieces replace a cluster only when those passing the size limit hold at least this
    /// fraction of its pixels (default 0.5).
    pub min_kept_fraction: f64,
}

impl OversizedSplit {
    /// The split for fruit of radius at most `radius_m`, other settings at their defaults.
    pub fn for_radius(radius_m: f64) -> Self {
        Self {
            radius_m,
            max_discs: 2.0,
            max_halvings: 2,
            min_kept_fraction: 0.5,
        }
    }

    /// Whether `cluster` covers more than `max_discs` discs of `radius_m` at its median depth
    /// (`depth_m`, focal length `fx_px`).
    fn oversized(&self, cluster: &[usize], depth_m: &[f32], fx_px: f64) -> bool {
        disc_area_px(depth_m, fx_px, cluster)
            .is_some_and(|disc_px| cluster.len() as f64 > self.max_discs * disc_px(self.radius_m))
    }

    /// `clusters` (grown with `params`) with every oversized one replaced by its pieces where
    /// the surface separates; clusters keep their order, pieces take their parent's place.
    pub fn apply(
        &self,
        width: usize,
        height: usize,
        fx_px: f64,
        depth_m: &[f32],
        clusters: Vec<Vec<usize>>,
        params: &RegionGrowingParams,
    ) -> Vec<Vec<usize>> {
        let image = DepthImage {
            width,
            height,
            fx_px,
            depth_m,
        };
        let mut out = Vec::with_capacity(clusters.len());
        for cluster in clusters {
            self.split_into(&mut out, &image, cluster, params, 0);
        }
        out
    }

    /// Pushes `cluster`, or the pieces it splits into, onto `out`; `params` grew it, after
    /// `halvings` halvings of the step.
    fn split_into(
        &self,
        out: &mut Vec<Vec<usize>>,
        image: &DepthImage,
        cluster: Vec<usize>,
        params: &RegionGrowingParams,
        halvings: u32,
    ) {
        if halvings >= self.max_halvings || !self.oversized(&cluster, image.depth_m, image.fx_px) {
            out.push(cluster);
            return;
        }
        let finer = RegionGrowingParams {
            max_step_m: params.max_step_m / 2.0,
            rim_px: 0,
            split_oversized: None,
            ..*params
        };
        let pieces = grow_regions_over(
            image.width,
            image.height,
            image.fx_px,
            image.depth_m,
            &cluster,
            &finer,
        );
        let kept: usize = pieces.iter().map(Vec::len).sum();
        if (kept as f64) < self.min_kept_fraction * cluster.len() as f64 {
            out.push(cluster);
            return;
        }
        for piece in pieces {
            self.split_into(out, image, piece, &finer, halvings + 1);
        }
    }
}

/// The depth image the clusters index into.
struct DepthImage<'a> {
    width: usize,
    height: usize,
    fx_px: f64,
    depth_m: &'a [f32],
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grow_regions;

    /// A 24×12 image at 1 m seen with fx 100 px: a 50 mm radius is a 5 px disc (78.5 px²), so
    /// above 2 discs (157 px) a cluster is oversized; each 12×12 half (144 px) is not.
    const W: usize = 24;
    const H: usize = 12;
    const FX: f64 = 100.0;

    fn clusters(depth: &[f32], split: Option<OversizedSplit>) -> Vec<usize> {
        let params = RegionGrowingParams {
            min_pixels: 20,
            reference_focal_px: FX,
            split_oversized: split,
            ..RegionGrowingParams::default()
        };
        let mut sizes: Vec<usize> = grow_regions(W, H, FX, depth, &vec![true; W * H], &params)
            .iter()
            .map(Vec::len)
            .collect();
        sizes.sort_unstable();
        sizes
    }

    fn image(z_mm: impl Fn(usize, usize) -> f32) -> Vec<f32> {
        (0..W * H)
            .map(|i| 1.0 + z_mm(i % W, i / W) / 1000.0)
            .collect()
    }

    #[test]
    fn an_oversized_cluster_of_two_surfaces_is_split_at_their_seam() {
        // Two flat halves 4 mm apart: one cluster at the paper's 5 mm step, two at 2.5 mm.
        let seam = image(|u, _| if u < 12 { 0.0 } else { 4.0 });
        assert_eq!(clusters(&seam, None), vec![288]);
        let split = OversizedSplit::for_radius(0.05);
        assert_eq!(clusters(&seam, Some(split)), vec![144, 144]);
        // A larger fruit makes the pair fruit-sized (288 px < 2 discs of 7 px): left whole.
        assert_eq!(
            clusters(&seam, Some(OversizedSplit::for_radius(0.07))),
            vec![288]
        );
        // No halving allowed: left whole.
        let none = OversizedSplit {
            max_halvings: 0,
            ..split
        };
        assert_eq!(clusters(&seam, Some(none)), vec![288]);
    }

    #[test]
    fn a_surface_that_shatters_at_the_finer_step_is_kept_whole() {
        // Columns alternating by 3.5 mm (a ridged, noisy surface): at 2.5 mm only the 12-px
        // columns hold together, all below the 20-px minimum, so nothing is kept.
        let ridged = image(|u, _| if u % 2 == 0 { 0.0 } else { 3.5 });
        let split = OversizedSplit::for_radius(0.05);
        assert_eq!(clusters(&ridged, Some(split)), vec![288]);
        // The same ridges on one half, the other half flat and 4 mm off: the flat half (144 px,
        // half of the cluster) survives the finer step, so the split is taken and the ridged
        // half's pixels are dropped with its columns.
        let half = image(|u, _| match u {
            0..=11 => 0.0,
            _ if u % 2 == 0 => 4.0,
            _ => 7.5,
        });
        assert_eq!(clusters(&half, None), vec![288]);
        assert_eq!(clusters(&half, Some(split)), vec![144]);
        let stricter = OversizedSplit {
            min_kept_fraction: 0.6,
            ..split
        };
        assert_eq!(clusters(&half, Some(stricter)), vec![288]);
    }
}
