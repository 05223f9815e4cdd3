//! Every tunable of the colour-contour detector in one serialisable struct, defaulted to seed
//! 004's values where it gives them and to documented choices where it is silent; stored in the
//! model file (`stage_params`) so a model runs with the parameters it was trained with.

use serde::{Deserialize, Serialize};

use crate::{
    DepthCutParams, DepthSphereParams, EdgeFitParams, HoughCircleParams, MlpParams, PruneRank,
    RayCircleParams,
};

/// The model-file keys (dotted, under `stage_params`) of the circle sources beyond seed 004's
/// edge fit — the ray circles and the Hough circles. Setting each to `null` leaves the paper's
/// circles from contour curvature only; `pomona stereo` does, because its matching pairs the
/// circles' image centres and a circle on a piece of fruit is centred on the piece, differently
/// in the two views. A new circle source adds its key here.
pub const EXTRA_CIRCLE_SOURCE_KEYS: [&str; 2] = ["params.ray_circles", "params.hough_circles"];

/// Parameters of every stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColorContourParams {
    /// The colour perceptron's training (back-propagation; 3-8-1 with the intensity input by
    /// default, the paper's 2-8-1 with `intensity` off).
    pub mlp: MlpParams,
    /// Training pixels drawn per class per frame (seeded; the paper used hand-cut samples of
    /// fruit and of background from 800 images).
    pub pixels_per_class_per_frame: usize,
    /// A pixel is fruit when the network's output is at least this. With
    /// `learn_color_threshold`, training replaces it by the value that maximises pixel F1 over
    /// the training frames (the network sees balanced classes, but fruit are a few per cent of
    /// a frame, so even odds would pass far too much background).
    pub color_threshold: f64,
    /// Whether training chooses `color_threshold` (see above; the paper does not say how its
    /// table was thresholded).
    #[serde(default = "yes")]
    pub learn_color_threshold: bool,
    /// Training on truth that does not list every fruit (`"complete": false` and no instance
    /// mask, like real frames where only tagged fruit are boxed): the fruit left untagged would
    /// be taught as background. With a positive value the model is trained twice: the first
    /// model detects fruit on its training frames, and the pixels within this many radii of
    /// every circle it finds centred outside the tagged fruit's boxes are left out of the second
    /// training and of the learnt threshold (`pomona_pipeline::untagged_fruit_circles`). 0 = off
    /// (every untagged pixel is background, the behaviour before this setting). Frames with
    /// complete truth are not affected. Not in seed 004.
    #[serde(default = "untagged_fruit_disc_scale")]
    pub untagged_fruit_disc_scale: f64,
    /// Hysteresis on the colour table (not in the paper, see [`crate::hysteresis_mask`]): pixels
    /// whose network output is at least this fraction of `color_threshold` are fruit where they
    /// join fruit. 1 = off (the paper's single threshold, and what model files from before this
    /// setting mean); default 0.75, chosen over 0.6–0.9 on orchard scenes (seed 600) and `wide`
    /// D435 oranges (seed 610), docs/results.md.
    #[serde(default = "one")]
    pub color_grow_fraction: f64,
    /// Confident regions smaller than this many pixels do not seed that growth (default 10,
    /// chosen with `color_grow_fraction`; 1 lets every confident pixel seed).
    #[serde(default = "one_px")]
    pub color_grow_seed_px: usize,
    /// Mask components smaller than this many pixels have no contour worth fitting.
    pub min_component_px: usize,
    /// Morphological closing of the fruit mask before the contours, square half-width in
    /// pixels (not in the paper, see [`crate::close_mask`]; default 2, chosen over 0–4 on the
    /// orchard light presets and the `wide` D435 set, docs/results.md; 0 = off, which is what
    /// model files from before it mean).
    #[serde(default)]
    pub mask_closing_px: usize,
    /// In a frame with depth, the cleaned mask is cut where one fruit stands in front of
    /// another ([`crate::cut_at_depth_steps`]; not in the paper), so that the outline stages
    /// see the front fruit's whole outline. On by default (built-in model included); `None`:
    /// no cut (what model files from before this setting mean, `--set params.depth_cut=null`);
    /// colour-only frames are never cut.
    #[serde(default)]
    pub depth_cut: Option<DepthCutParams>,
    /// In a frame with depth, circles of spheres fitted to each mask component's depth
    /// readings are added to the outline's ([`crate::depth_sphere_circles`]; not in the
    /// paper). On by default (built-in model included); `None` (what model files without the
    /// key mean): none.
    #[serde(default)]
    pub depth_spheres: Option<DepthSphereParams>,
    /// The adaptive edge fitting (Eq. 8).
    pub edge_fit: EdgeFitParams,
    /// Circles from rays cast out of the mask's inscribed discs, added to the edge fit's (not
    /// in the paper, see [`crate::ray_circles`]): fruit that touch in a row or overlap, whose
    /// share of the common outline is too short for the edge fit. `None` (default, and what
    /// model files without the key mean) = off, the paper's circles only; `--set
    /// 'params.ray_circles={}'` turns them on with the defaults of [`RayCircleParams`] (chosen
    /// on orchard scenes, seed 700). Off by default because they cost stereo accuracy and
    /// precision on close-up `wide` scenes while they gain on orchard scenes and real apples
    /// (docs/results.md, "Ray circles from inscribed discs").
    #[serde(default)]
    pub ray_circles: Option<RayCircleParams>,
    /// Circles voted for by every outline pixel along its normal, added to the edge fit's (not
    /// in the paper, see [`crate::hough_circles`]): fruit whose outline leaves notch into arcs
    /// shorter than the edge fit's windows, or whose arc runs on into a neighbour's. On by
    /// default with the defaults of [`HoughCircleParams`] (chosen on orchard scenes, seed 700,
    /// and `wide` D435 oranges, seed 610; docs/results.md, "Hough circles from the outline");
    /// `None` (what model files from before this setting mean) = off, the paper's circles only,
    /// also `--set params.hough_circles=null`.
    #[serde(default)]
    pub hough_circles: Option<HoughCircleParams>,
    /// Circles need at least this support (arc spanned over circumference) to be reported.
    pub min_support: f64,
    /// Of two circles sharing more than this fraction of the smaller one's area, the weaker is
    /// dropped (paper: 40 %).
    pub max_overlap: f64,
    /// Which of two overlapping circles is the stronger ([`crate::PruneRank`]): `score`
    /// (support fraction × colour purity; what model files from before this setting mean) or
    /// `arc-length` (arc in pixels × colour purity; default, chosen on orchard scenes (seed 600)
    /// and `wide` D435 oranges (seed 610), docs/results.md).
    #[serde(default)]
    pub prune_rank: PruneRank,
    /// Two overlapping circles are taken for one fruit only when their centres are closer than
    /// this fraction of the larger radius (not in the paper, see [`crate::clash`]; 0 = the
    /// overlap test alone, the paper's rule and what model files from before this setting
    /// mean; default 0.8, chosen over 0.6–1 on the sets of `prune_rank`).
    #[serde(default)]
    pub prune_center_reach: f64,
    /// Allowed fruit radius at the measured depth, metres (paper: 25–55 mm for oranges).
    pub radius_range_m: (f64, f64),
    /// How far a circle's measured radius may stray outside `radius_range_m`, as a fraction:
    /// radii in `[lo / (1 + t), hi · (1 + t)]` pass (not in the paper, whose range is the fruit's;
    /// see [`ColorContourParams::accepted_radius_range_m`]). Absent in older model files: 0, the
    /// paper's test.
    #[serde(default)]
    pub radius_tolerance: f64,
    /// Camera-to-fruit distances, metres, that bound the radius in pixels of a circle without
    /// depth (the paper scales by the known working distance).
    pub working_distance_m: (f64, f64),
    /// Radius assumed to place a circle without depth in 3D, metres (middle of the range).
    pub prior_radius_m: f64,
    /// In a frame that has depth, a circle with none inside it (sky, dark cloth, background
    /// beyond the sensor's range, a sliver of fruit in a hole beside a nearer edge) is kept
    /// only when `prior_radius_m` places it no farther than the far end of
    /// `working_distance_m` (not in the paper, which has no depth). Frames without any depth
    /// (colour-only data) are not affected: there, missing depth says nothing. Absent in older
    /// model files: off (every such circle placed by the prior, the behaviour before).
    #[serde(default)]
    pub depthless_within_reach: bool,
    /// Depth is read from fruit pixels within this fraction of the radius from the centre.
    pub depth_core_fraction: f64,
    /// The 3D centre is refitted to those fruit pixels' points at the measured radius (ours,
    /// see [`crate::sphere_from_depth`]): a circle a few pixels off its fruit puts the centre
    /// beside the fruit, the points do not. `0` turns it off; otherwise points farther than
    /// this from the first refit's sphere are left out of the second, metres. Absent in older
    /// model files: on, 10 mm (a geometric step, nothing learnt).
    #[serde(default = "ten_mm")]
    pub depth_refit_tolerance_m: f64,
}

impl ColorContourParams {
    /// The measured radii, metres, that pass the size test: `radius_range_m` widened by
    /// `radius_tolerance`. The range bounds the fruit's true radius, while a circle fitted to a
    /// partly hidden contour carries its own error (on synthetic oranges the measured diameter
    /// is 0.89–1.08 of the truth between the quartiles, 0.47–1.21 between the 5th and 95th
    /// percentiles), so fruit near the ends of the range fail the paper's test.
    pub fn accepted_radius_range_m(&self) -> (f64, f64) {
        let (lo, hi) = self.radius_range_m;
        let widen = 1.0 + self.radius_tolerance;
        (lo / widen, hi * widen)
    }

    /// The circle radii in pixels a fruit can have for a camera of focal length `focal_px`:
    /// the accepted radii seen from the far and the near end of `working_distance_m`. The size
    /// test of circles without depth, and the cap on merged circles.
    pub fn radius_px_range(&self, focal_px: f64) -> (f64, f64) {
        let (r_lo, r_hi) = self.accepted_radius_range_m();
        let (z_near, z_far) = self.working_distance_m;
        (focal_px * r_lo / z_far, focal_px * r_hi / z_near.max(1e-6))
    }
}

impl Default for ColorContourParams {
    fn default() -> Self {
        Self {
            mlp: MlpParams::default(),
            pixels_per_class_per_frame: 2000,
            color_threshold: 0.5,
            learn_color_threshold: true,
            untagged_fruit_disc_scale: untagged_fruit_disc_scale(),
            color_grow_fraction: 0.75,
            color_grow_seed_px: 10,
            min_component_px: 40,
            mask_closing_px: 2,
            depth_cut: Some(DepthCutParams::default()),
            depth_spheres: Some(DepthSphereParams::default()),
            edge_fit: EdgeFitParams::default(),
            ray_circles: None,
            hough_circles: Some(HoughCircleParams::default()),
            min_support: 0.15,
            max_overlap: 0.4,
            prune_rank: PruneRank::ArcLength,
            prune_center_reach: 0.8,
            radius_range_m: (0.025, 0.055),
            radius_tolerance: 0.1,
            working_distance_m: (0.3, 2.0),
            prior_radius_m: 0.04,
            depthless_within_reach: true,
            depth_core_fraction: 0.8,
            depth_refit_tolerance_m: ten_mm(),
        }
    }
}

fn untagged_fruit_disc_scale() -> f64 {
    1.2
}

fn ten_mm() -> f64 {
    0.01
}

fn one() -> f64 {
    1.0
}

fn one_px() -> usize {
    1
}

fn yes() -> bool {
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_extra_circle_source_keys_name_optional_stage_parameters() {
        let params = serde_json::to_value(ColorContourParams::default()).unwrap();
        for key in EXTRA_CIRCLE_SOURCE_KEYS {
            let field = key.strip_prefix("params.").unwrap();
            assert!(
                params.get(field).is_some(),
                "{key} is not a stage parameter"
            );
            let with = |value: serde_json::Value| -> ColorContourParams {
                let mut p = params.clone();
                p[field] = value;
                serde_json::from_value(p).unwrap()
            };
            assert_ne!(
                with(serde_json::json!({})),
                with(serde_json::Value::Null),
                "{key}: on and off are the same parameters"
            );
        }
    }
}
