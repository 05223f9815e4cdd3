//! Every tunable of the two detectors, in one serde struct stored in the model's `stage_params`
//! so that a model file alone reproduces its detector.
//!
//! Where the seeds give a value it is the default (V/S threshold t = 0.8, "up" = −y, 50 mm
//! matching tolerance used for the NMS radius). The seeds give no numbers for the box size,
//! stride, bin counts, plane grid or the weight `w` of Eq. 14; the defaults below are our
//! choices for sweet peppers (70–105 mm wide, 80–120 mm long) and are documented per field.

use pomona_consensus::WindowNormalParams;
use pomona_learn::{MinMaxScaler, RbfSvm, SvmClassifier};
use pomona_pipeline::{DoubleCurvatureCheck, FreeSpaceCheck};
use serde::{Deserialize, Serialize};

use crate::error::{check_at_least, check_positive, SymmetryError};
use crate::{CentreRefinement, CentreRefinementParams};

/// Which reference frame a box's features are expressed in (the swappable stage).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FrameKind {
    /// Best reflection-symmetry plane through the box centre (seed 000 §3.3).
    Symmetry,
    /// A fixed camera-aligned frame: the "without symmetry" ablation of seed 000 Table 1.
    Fixed,
    /// Viewer-based frame from the box centre and the viewing direction (seed 001 §2.1).
    Viewer,
}

/// How overlapping positive boxes become one detection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MergeKind {
    /// Greedy 3D non-maximum suppression (seed 000).
    Nms,
    /// Mean-shift mode seeking over positive box centres (seed 001).
    MeanShift,
}

/// Highlight-based pruning (seed 000 §3.1, Eqs. 1–6). The seed gives only `t = 0.8`; the other
/// defaults were tuned on synthetic peppers (`examples/benchmark.rs` prints the mask's coverage
/// of fruit centres), where highlights are only a few pixels wide, so one agreeing circle
/// (`Th = 0`) is enough.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HighlightParams {
    /// Whether pruning runs at all (it is skipped, with a flag, on frames without colour).
    pub enabled: bool,
    /// Threshold `t` on V/S (Eq. 1); the paper's 0.8.
    pub ratio_threshold: f64,
    /// Pixels darker than this value V (0–1) are never candidates (keeps dark noise out).
    pub min_value: f64,
    /// σ of the Gaussian integrating the second-moment matrix (Eq. 2), pixels.
    pub sigma_px: f64,
    /// Radii of the concentric circles of the pinwheel model, pixels.
    pub radii_px: Vec<f64>,
    /// Orientation samples per circle.
    pub samples_per_circle: usize,
    /// `Tα`: orientations agree when their complex distance (Eq. 3) is below this (Eq. 4).
    pub t_alpha: f64,
    /// `Ts`: a circle supports the pixel when more than this fraction agrees (Eq. 5).
    pub t_s: f64,
    /// `Th`: a pixel is a highlight when more than this many circles support it (Eq. 6).
    pub t_h: usize,
    /// Largest fruit size in the scene, metres (sets the dilation radius).
    pub max_fruit_size_m: f64,
    /// Nearest working distance, metres (sets the dilation radius).
    pub min_distance_m: f64,
}

impl Default for HighlightParams {
    fn default() -> Self {
        Self {
            enabled: true,
            ratio_threshold: 0.8,
            min_value: 0.45,
            sigma_px: 1.5,
            radii_px: vec![2.0, 3.5, 5.0],
            samples_per_circle: 16,
            t_alpha: 0.6,
            t_s: 0.5,
            t_h: 0,
            max_fruit_size_m: 0.12,
            min_distance_m: 0.4,
        }
    }
}

/// The 3D sliding box.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SlidingBoxParams {
    /// Edge of the cubic box, metres (12 cm holds the largest pepper).
    pub box_size_m: f64,
    /// Spacing of box centres, metres.
    pub stride_m: f64,
    /// Boxes with fewer points are skipped.
    pub min_points: usize,
    /// Box centres nearer than this are skipped, metres.
    pub min_range_m: f64,
    /// Box centres farther than this are skipped (working range), metres.
    pub max_range_m: f64,
    /// Early rejection: a box is kept only when its centre lies behind the surface seen through
    /// it (at most this far in front of it, for noise) and at most half a box behind it, metres.
    /// A fruit's centre is always behind its visible skin, so boxes floating in front of surfaces
    /// or buried deep behind them are skipped before any work is done.
    pub max_in_front_m: f64,
    /// Early rejection: the centre must also be at least this far behind the observed surface,
    /// metres (a pepper's centre is 35–50 mm behind its skin; 0 disables).
    pub min_behind_m: f64,
    /// Early rejection of flat boxes: a box whose unit normals have a mean resultant length
    /// `‖Σ n‖ / N` above this is a plane (leaf, backdrop) rather than a fruit, whose visible
    /// normals spread over a hemisphere (1 disables).
    pub max_normal_coherence: f64,
    /// Feature points per box are thinned (by pixel step) to at most this many.
    pub max_points: usize,
    /// Normals are estimated only on pixels whose row and column are multiples of this, and box
    /// points are read on that lattice (boxes are thinned anyway: a 12 cm box spans 3–6 pixels
    /// per kept point on a Kinect v2), which cuts normal estimation by its square.
    #[serde(default = "one")]
    pub pixel_lattice: usize,
    /// On cameras of at least this focal length, px, a box's samples start on multiples of its
    /// thinning step (on the image, not at the box's own corner), so overlapping boxes of the
    /// same step read the same pixels and share their normals (the normal stage of a 1920×1080
    /// Azure Kinect frame, 917 px, takes a quarter of the time). Each box still reads every
    /// step-th pixel of its rectangle, from at most one step further on. Default `None` (each
    /// box from its own corner, on every camera): on five 40-frame synthetic Azure Kinect sets
    /// the shared lattice cost symmetry 0.04–0.05 AP on each of three pepper sets (and gained as
    /// much on two apple sets); the real 1080p frame takes about 80 ms without it (criterion, one
    /// thread). `730` aligns on the Azure Kinect only (the speed setting the built-in models had
    /// before). See docs/results.md, "Symmetry boxes on a shared lattice" and "The 1080p
    /// sampling settings on five sets".
    #[serde(default)]
    pub align_samples_min_focal_px: Option<f64>,
}

fn one() -> usize {
    1
}

impl Default for SlidingBoxParams {
    fn default() -> Self {
        Self {
            box_size_m: 0.12,
            stride_m: 0.03,
            min_points: 50,
            min_range_m: 0.2,
            max_range_m: 1.6,
            max_in_front_m: 0.01,
            min_behind_m: 0.02,
            max_normal_coherence: 1.0,
            max_points: 400,
            pixel_lattice: 1,
            align_samples_min_focal_px: None,
        }
    }
}

/// Symmetry plane search (seed 000 §3.3, Eqs. 10–14).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SymmetryPlaneParams {
    /// Azimuth steps of the coarse plane-normal grid over 180°.
    pub azimuth_steps: usize,
    /// Elevation steps of the coarse grid over (−90°, 90°) (plus the pole).
    pub elevation_steps: usize,
    /// Refinement rounds around the best coarse normal (each halves the step).
    pub refinements: usize,
    /// Points scored per refined candidate plane (evenly thinned box points).
    pub score_points: usize,
    /// Points scored per coarse-grid plane (a cheaper first pass; the best `coarse_keep` coarse
    /// planes are re-scored with `score_points` before refinement).
    pub coarse_points: usize,
    /// Coarse planes re-scored with all `score_points`.
    pub coarse_keep: usize,
    /// Weight `w` of the normal angle in Eq. 14, metres per radian.
    pub angle_weight_m: f64,
    /// Partner distances are clamped to this, metres (robustness to clutter).
    pub max_distance_m: f64,
    /// A plane needs at least this fraction of scored points contributing.
    pub min_contributing: f64,
}

impl Default for SymmetryPlaneParams {
    fn default() -> Self {
        Self {
            azimuth_steps: 8,
            elevation_steps: 6,
            refinements: 2,
            score_points: 48,
            coarse_points: 16,
            coarse_keep: 3,
            angle_weight_m: 0.02,
            max_distance_m: 0.03,
            min_contributing: 0.3,
        }
    }
}

/// Spatio-angular bins and normal histograms (seed 000 §3.2, seed 001 §2.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HistogramParams {
    /// Bins of distance from the frame's plane, over `[0, box_size/2]`.
    pub distance_bins: usize,
    /// Bins of the angle from the frame's reference vector, over `[0, π]`.
    pub angle_bins: usize,
    /// Bins of the first normal angle (θ, or angle to `u`), over `[0, π]`.
    pub first_bins: usize,
    /// Bins of the second normal angle (φ over `[0, 2π)`, or angle to the point ray over `[0, π]`).
    pub second_bins: usize,
}

impl Default for HistogramParams {
    fn default() -> Self {
        Self {
            distance_bins: 3,
            angle_bins: 4,
            first_bins: 6,
            second_bins: 8,
        }
    }
}

impl HistogramParams {
    /// Length of the feature vector.
    pub fn feature_len(&self) -> usize {
        self.distance_bins * self.angle_bins * (self.first_bins + self.second_bins)
    }
}

/// Merging of positive boxes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MergeParams {
    /// Boxes scoring below this are dropped before merging (the main SVM's decision value, plus
    /// the weighted cascade value when `cascade.score_weight` > 0). −0.5 by default; −1.5 for
    /// `symmetry`, whose boxes carry the cascade's value as well, so that fruit the two SVMs
    /// both doubt still come out at a low rank rather than not at all.
    pub min_score: f64,
    /// NMS: a box is suppressed by a better one closer than this, metres (about the smallest
    /// pepper's width: two fruit centres are never closer).
    pub nms_radius_m: f64,
    /// Mean-shift: flat-kernel bandwidth, metres.
    pub bandwidth_m: f64,
    /// Mean-shift: iterations per seed at most.
    pub max_iterations: usize,
}

impl Default for MergeParams {
    fn default() -> Self {
        Self {
            min_score: -0.5,
            nms_radius_m: 0.07,
            bandwidth_m: 0.06,
            max_iterations: 30,
        }
    }
}

/// Training-sample selection.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrainingParams {
    /// Fruit less visible than this are not used as positives.
    pub min_visibility: f64,
    /// Extra positives per fruit with the centre jittered by up to half a stride per axis.
    pub positive_jitters: usize,
    /// Random negative boxes per frame.
    pub negatives_per_frame: usize,
    /// Negative box centres are at least this far from every fruit centre, metres.
    pub negative_min_distance_m: f64,
    /// Extra "hard" negatives per frame drawn among accepted boxes between one and two
    /// `negative_min_distance_m` from a fruit centre (boxes that overlap a fruit off-centre and
    /// would otherwise become duplicate detections beyond the merging radius). Off by default:
    /// it did not raise AP on the synthetic benchmark.
    #[serde(default)]
    pub hard_negatives_per_frame: usize,
    /// Rounds of hard-negative mining (bootstrapping, as in Dalal–Triggs and Felzenszwalb et
    /// al.): after each fit the detector scores every box of every training frame with complete
    /// truth, the boxes scoring ≥ 0 whose centre is at least `negative_min_distance_m` from every
    /// truth fruit centre become extra negatives (at most `max_hard_negatives_per_frame` per frame
    /// and round, best first), and the SVMs are refitted. 0 is the training without mining; a
    /// model file trained with 0 does not carry the two mining keys (so it is byte-identical to
    /// one trained before mining existed), and a model file without them reads as 0.
    #[serde(default)]
    pub hard_negative_rounds: usize,
    /// Mined negatives per frame and round at most (the highest-scoring first).
    #[serde(default = "default_max_hard_negatives_per_frame")]
    pub max_hard_negatives_per_frame: usize,
    /// Whether training widens the sliding box's working range to the annotated fruit (see
    /// [`WorkingRange`]).
    #[serde(default)]
    pub working_range: WorkingRange,
}

/// How training sets the sliding box's working range (`boxes.max_range_m`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WorkingRange {
    /// Widened to the distance of the farthest annotated fruit centre when that lies beyond
    /// the configured range (ours, as `shape-fit` widens its depth limit): a
    /// camera that sees fruit at 1.9 m needs boxes centred there. Never narrowed.
    #[default]
    FromTruth,
    /// The configured `boxes.max_range_m` as it is.
    Fixed,
}

/// Default of [`TrainingParams::max_hard_negatives_per_frame`].
fn default_max_hard_negatives_per_frame() -> usize {
    20
}

impl Default for TrainingParams {
    fn default() -> Self {
        Self {
            min_visibility: 0.3,
            positive_jitters: 2,
            negatives_per_frame: 40,
            negative_min_distance_m: 0.06,
            hard_negatives_per_frame: 0,
            hard_negative_rounds: 1,
            max_hard_negatives_per_frame: default_max_hard_negatives_per_frame(),
            working_range: WorkingRange::default(),
        }
    }
}

/// The detection cascade (ours; first for speed, then for ranking): every box is first scored by a
/// second SVM on its *fixed-frame* features, which cost no plane search, and only boxes scoring
/// at least `min_score` get their own frame (the symmetry search, or the viewer frame), features
/// and the main SVM, whose decision value the cascade's is added to (`score_weight`). Training
/// fits that SVM on the fixed-frame features of the same training boxes and stores it here, so
/// the model file stays self-contained. `enabled: false` is seeds 000's and 001's detectors
/// (every box judged by the main SVM alone); the crate README gives the speed and AP of both
/// settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CascadeParams {
    /// Whether the fixed-frame pre-filter runs (ignored for the fixed frame, whose main SVM
    /// reads the same features). On for `symmetry` and, since 6 December, `viewer-pose`
    /// (docs/results.md, "Two classifiers, one score"); off in files from before.
    pub enabled: bool,
    /// Boxes whose fixed-frame decision value is below this go no further. 0 (the SVM's own
    /// boundary) when the cascade was only for speed (chosen on SR4000 splits 1–2 among −1,
    /// −0.5, 0 and 0.5, see the README); −0.5 for `symmetry` and −1 for `viewer-pose` since the
    /// weighted score ranks what comes through (chosen on tuning sets of our generator,
    /// docs/results.md).
    pub min_score: f64,
    /// Weight of the cascade's decision value in a box's score: a box that reaches the main
    /// SVM scores `main + score_weight × cascade` (ours; 0 = the main SVM's value alone, as
    /// models from before this key load). The two SVMs judge different descriptions of the
    /// box (its own frame, symmetry or viewer; the fixed frame), and a box the cascade only just
    /// lets through is less likely a fruit than the main SVM alone says: on twelve tuning sets
    /// of our generator, weight 1 with `min_score` −0.5 kept more fruit than threshold 0 and
    /// ranked them better (docs/results.md, "Two classifiers, one score").
    #[serde(default)]
    pub score_weight: f64,
    /// Bins of the cascade's fixed-frame features (the cascade's cost is mostly its SVM, in
    /// proportion to the feature length).
    #[serde(default)]
    pub histogram: HistogramParams,
    /// The fixed-frame classifier, filled in by training.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub classifier: Option<CascadeClassifier>,
}

impl Default for CascadeParams {
    /// Off (the paper's behaviour; also what models from before the cascade load as).
    fn default() -> Self {
        Self {
            enabled: false,
            min_score: 0.0,
            score_weight: 0.0,
            histogram: HistogramParams::default(),
            classifier: None,
        }
    }
}

/// The cascade's fixed-frame SVM (as in a model file: optional scaler, RBF SVM).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CascadeClassifier {
    /// Feature scaling learnt in training.
    pub scaler: Option<MinMaxScaler>,
    /// The SVM.
    pub svm: RbfSvm,
}

impl CascadeClassifier {
    /// Stores a trained classifier.
    pub fn from_classifier(c: &SvmClassifier) -> Self {
        Self {
            scaler: c.scaler.clone(),
            svm: c.svm.clone(),
        }
    }

    /// The classifier back.
    pub fn classifier(&self) -> SvmClassifier {
        SvmClassifier {
            scaler: self.scaler.clone(),
            svm: self.svm.clone(),
            info: None,
        }
    }
}

/// Focal length, px, whose 5×5 normal window the defaults reproduce on finer cameras: the
/// Kinect v2's, the camera of most built-in training frames.
const REFERENCE_FOCAL_PX: f64 = 365.0;

/// Finest camera of the built-in training frames (the D435, 615 px): cameras up to it keep the
/// window the classifiers were trained with.
const FINEST_TRAINED_FOCAL_PX: f64 = 615.0;

/// All stage parameters of a `symmetry` or `viewer-pose` detector.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageParams {
    /// Reference frame of the features.
    pub frame: FrameKind,
    /// Merging of positive boxes.
    pub merge: MergeKind,
    /// Highlight pruning.
    pub highlight: HighlightParams,
    /// PCA normals over image windows (pomona-consensus). The defaults keep the 5×5 window on
    /// every camera up to the D435's 615 px and scale it to a Kinect v2's patch (365 px) on
    /// finer ones (`reference_focal_px`, `keep_sample_count`, `scale_above_focal_px`): the
    /// built-in models never saw such a camera, and a fixed window there reads a patch too
    /// small for its depth noise. Older files, without these keys, keep the window everywhere.
    pub normals: WindowNormalParams,
    /// Sliding box.
    pub boxes: SlidingBoxParams,
    /// Symmetry plane search.
    pub symmetry: SymmetryPlaneParams,
    /// Bins and histograms.
    pub histogram: HistogramParams,
    /// Merging.
    pub merging: MergeParams,
    /// Training samples.
    pub training: TrainingParams,
    /// Fixed-frame pre-filter before the symmetry search (absent in older models: off).
    #[serde(default)]
    pub cascade: CascadeParams,
    /// Centre refinement and diameter of merged detections (absent in older models: off, as
    /// they ran). On for both pipelines; training learns its radius calibration. It was off for
    /// `viewer-pose`, whose mean-shift centres are already off the grid, until the calibration:
    /// with it the built-in model's real Azure Kinect apples moved from 18.5 to 12.1 mm centre
    /// error at the same AP (docs/results.md).
    #[serde(default = "CentreRefinementParams::disabled")]
    pub refinement: CentreRefinementParams,
    /// Merged detections whose centre the camera sees through are dropped (not in the seeds;
    /// see [`FreeSpaceCheck`]). Detection-time only; absent in older models: on, strict
    /// ([`FreeSpaceCheck::strict`]: the detectors are colour-blind, so a detection's geometry
    /// is its only evidence of an opaque fruit). A model file whose `free_space` lacks the
    /// see-through keys gets the lenient ones of [`FreeSpaceCheck::default`] (the built-in
    /// files carry the strict values).
    #[serde(default = "FreeSpaceCheck::strict")]
    pub free_space: FreeSpaceCheck,
    /// Merged detections on a surface that does not bend away from the camera in both
    /// directions (a leaf folded or flat) are dropped (not in the seeds; see
    /// [`DoubleCurvatureCheck`]). Detection-time only; on for `symmetry` (the built-in file carries
    /// it), off for `viewer-pose`, whose mean-shift centres on real apples often sit beside
    /// the fruit, where the patch sees leaves and neighbours (it lost 4 of 78 real
    /// `ak-apples` in leave-one-out); absent in older models: off, as they ran.
    #[serde(default = "DoubleCurvatureCheck::off")]
    pub double_curvature: DoubleCurvatureCheck,
}

impl StageParams {
    /// Seed 000: symmetry frame, highlight pruning, NMS.
    pub fn symmetry() -> Self {
        Self {
            frame: FrameKind::Symmetry,
            merge: MergeKind::Nms,
            highlight: HighlightParams::default(),
            normals: WindowNormalParams {
                reference_focal_px: Some(REFERENCE_FOCAL_PX),
                keep_sample_count: true,
                scale_above_focal_px: Some(FINEST_TRAINED_FOCAL_PX),
                ..WindowNormalParams::default()
            },
            boxes: SlidingBoxParams::default(),
            symmetry: SymmetryPlaneParams::default(),
            histogram: HistogramParams::default(),
            merging: MergeParams {
                min_score: -1.5,
                ..MergeParams::default()
            },
            training: TrainingParams::default(),
            cascade: CascadeParams {
                enabled: true,
                min_score: -0.5,
                score_weight: 1.0,
                ..CascadeParams::default()
            },
            refinement: CentreRefinementParams::default(),
            free_space: FreeSpaceCheck::strict(),
            double_curvature: DoubleCurvatureCheck::default(),
        }
    }

    /// Seed 001: viewer frame, highlight pruning ("dark areas with no highlights"), mean-shift.
    pub fn viewer_pose() -> Self {
        Self {
            frame: FrameKind::Viewer,
            merge: MergeKind::MeanShift,
            merging: MergeParams::default(),
            cascade: CascadeParams {
                enabled: true,
                min_score: -1.0,
                score_weight: 1.0,
                ..CascadeParams::default()
            },
            refinement: CentreRefinementParams::default(),
            double_curvature: DoubleCurvatureCheck::off(),
            ..Self::symmetry()
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`SymmetryError::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<(), SymmetryError> {
        validate_highlight(&self.highlight)?;
        validate_boxes(&self.boxes)?;
        validate_symmetry(&self.symmetry)?;
        let names = [
            "histogram.distance_bins",
            "histogram.angle_bins",
            "histogram.first_bins",
            "histogram.second_bins",
        ];
        validate_histogram(&self.histogram, names)?;
        let names = [
            "cascade.histogram.distance_bins",
            "cascade.histogram.angle_bins",
            "cascade.histogram.first_bins",
            "cascade.histogram.second_bins",
        ];
        validate_histogram(&self.cascade.histogram, names)?;
        if let Some((name, value, reason)) = self
            .free_space
            .invalid_reason()
            .or_else(|| self.double_curvature.invalid_reason())
        {
            return Err(SymmetryError::InvalidParameter {
                name,
                value,
                reason,
            });
        }
        if self.cascade.min_score.is_nan() {
            return Err(SymmetryError::InvalidParameter {
                name: "cascade.min_score",
                value: self.cascade.min_score,
                reason: "must not be NaN",
            });
        }
        let weight = self.cascade.score_weight;
        if !(weight.is_finite() && weight >= 0.0) {
            return Err(SymmetryError::InvalidParameter {
                name: "cascade.score_weight",
                value: weight,
                reason: "must be finite and at least 0",
            });
        }
        let m = &self.merging;
        if m.min_score.is_nan() {
            return Err(SymmetryError::InvalidParameter {
                name: "merging.min_score",
                value: m.min_score,
                reason: "must not be NaN",
            });
        }
        check_positive("merging.nms_radius_m", m.nms_radius_m)?;
        check_positive("merging.bandwidth_m", m.bandwidth_m)?;
        check_at_least("merging.max_iterations", m.max_iterations, 1)?;
        let t = &self.training;
        check_positive(
            "training.negative_min_distance_m",
            t.negative_min_distance_m,
        )?;
        if !(0.0..=1.0).contains(&t.min_visibility) {
            return Err(SymmetryError::InvalidParameter {
                name: "training.min_visibility",
                value: t.min_visibility,
                reason: "must be in [0, 1]",
            });
        }
        if t.hard_negative_rounds > 0 {
            check_at_least(
                "training.max_hard_negatives_per_frame",
                t.max_hard_negatives_per_frame,
                1,
            )?;
        }
        if self.cascade.min_score.is_nan() {
            return Err(SymmetryError::InvalidParameter {
                name: "cascade.min_score",
                value: self.cascade.min_score,
                reason: "must not be NaN",
            });
        }
        self.normals.check()?;
        CentreRefinement::new(self.refinement)?;
        Ok(())
    }
}

/// Every bin count of `g` is at least 1; `names` are the four counts' keys in the order
/// distance, angle, first, second.
fn validate_histogram(g: &HistogramParams, names: [&'static str; 4]) -> Result<(), SymmetryError> {
    let counts = [g.distance_bins, g.angle_bins, g.first_bins, g.second_bins];
    for (name, n) in names.into_iter().zip(counts) {
        check_at_least(name, n, 1)?;
    }
    Ok(())
}

/// The checks of [`StageParams::validate`] on the highlight parameters.
fn validate_highlight(h: &HighlightParams) -> Result<(), SymmetryError> {
    check_positive("highlight.ratio_threshold", h.ratio_threshold)?;
    check_positive("highlight.sigma_px", h.sigma_px)?;
    check_positive("highlight.t_alpha", h.t_alpha)?;
    check_positive("highlight.max_fruit_size_m", h.max_fruit_size_m)?;
    check_positive("highlight.min_distance_m", h.min_distance_m)?;
    check_at_least("highlight.samples_per_circle", h.samples_per_circle, 4)?;
    check_at_least("highlight.radii_px", h.radii_px.len(), 1)?;
    for &r in &h.radii_px {
        check_positive("highlight.radii_px", r)?;
    }
    if !(0.0..=1.0).contains(&h.t_s) || !(0.0..=1.0).contains(&h.min_value) {
        return Err(SymmetryError::InvalidParameter {
            name: "highlight.t_s",
            value: h.t_s,
            reason: "t_s and min_value must be in [0, 1]",
        });
    }
    Ok(())
}

/// The checks of [`StageParams::validate`] on the sliding box.
fn validate_boxes(b: &SlidingBoxParams) -> Result<(), SymmetryError> {
    check_positive("boxes.box_size_m", b.box_size_m)?;
    check_positive("boxes.stride_m", b.stride_m)?;
    check_positive("boxes.max_range_m", b.max_range_m)?;
    check_positive("boxes.max_in_front_m", b.max_in_front_m)?;
    check_positive("boxes.max_normal_coherence", b.max_normal_coherence)?;
    check_at_least("boxes.min_points", b.min_points, 3)?;
    check_at_least("boxes.pixel_lattice", b.pixel_lattice, 1)?;
    if let Some(focal) = b.align_samples_min_focal_px {
        check_positive("boxes.align_samples_min_focal_px", focal)?;
    }
    if !(b.min_behind_m.is_finite() && b.min_behind_m < 0.5 * b.box_size_m) {
        return Err(SymmetryError::InvalidParameter {
            name: "boxes.min_behind_m",
            value: b.min_behind_m,
            reason: "must be finite and below half the box",
        });
    }
    check_at_least("boxes.max_points", b.max_points, b.min_points)?;
    if !(b.min_range_m >= 0.0 && b.min_range_m < b.max_range_m) {
        return Err(SymmetryError::InvalidParameter {
            name: "boxes.min_range_m",
            value: b.min_range_m,
            reason: "must be >= 0 and below max_range_m",
        });
    }
    let cells = (2.0 * (b.max_range_m + b.box_size_m) / b.stride_m + 1.0).powi(3);
    if cells > 5e7 {
        return Err(SymmetryError::InvalidParameter {
            name: "boxes.stride_m",
            value: b.stride_m,
            reason: "too fine for the working range (the voxel count table would exceed 5e7 cells)",
        });
    }
    if b.box_size_m / b.stride_m > 64.0 {
        return Err(SymmetryError::InvalidParameter {
            name: "boxes.stride_m",
            value: b.stride_m,
            reason: "more than 64 strides per box",
        });
    }
    Ok(())
}

/// The checks of [`StageParams::validate`] on the symmetry-plane search.
fn validate_symmetry(s: &SymmetryPlaneParams) -> Result<(), SymmetryError> {
    check_at_least("symmetry.azimuth_steps", s.azimuth_steps, 2)?;
    check_at_least("symmetry.elevation_steps", s.elevation_steps, 1)?;
    check_at_least("symmetry.score_points", s.score_points, 4)?;
    check_at_least("symmetry.coarse_points", s.coarse_points, 4)?;
    check_at_least("symmetry.coarse_keep", s.coarse_keep, 1)?;
    check_positive("symmetry.max_distance_m", s.max_distance_m)?;
    if !(s.angle_weight_m.is_finite() && s.angle_weight_m >= 0.0) {
        return Err(SymmetryError::InvalidParameter {
            name: "symmetry.angle_weight_m",
            value: s.angle_weight_m,
            reason: "must be finite and >= 0",
        });
    }
    if !(0.0..=1.0).contains(&s.min_contributing) {
        return Err(SymmetryError::InvalidParameter {
            name: "symmetry.min_contributing",
            value: s.min_contributing,
            reason: "must be in [0, 1]",
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_round_trip() {
        for p in [StageParams::symmetry(), StageParams::viewer_pose()] {
            p.validate().unwrap();
            let json = serde_json::to_value(&p).unwrap();
            let back: StageParams = serde_json::from_value(json).unwrap();
            assert_eq!(back, p);
        }
        assert_eq!(HistogramParams::default().feature_len(), 3 * 4 * 14);
    }

    /// A model written before the refinement existed runs without it; a partial block reads
    /// the other keys' defaults, except `facing_camera`, off as in the files written before it.
    #[test]
    fn refinement_is_off_without_its_block_and_keys_default() {
        let mut json = serde_json::to_value(StageParams::symmetry()).unwrap();
        let object = json.as_object_mut().unwrap();
        object.remove("refinement");
        let old: StageParams = serde_json::from_value(json.clone()).unwrap();
        assert_eq!(old.refinement, CentreRefinementParams::disabled());
        json["refinement"] = serde_json::json!({"enabled": true, "max_shift_m": 0.03});
        let partial: StageParams = serde_json::from_value(json).unwrap();
        assert_eq!(
            partial.refinement,
            CentreRefinementParams {
                max_shift_m: 0.03,
                // The one key whose absence means "as before", not the default.
                facing_camera: false,
                ..CentreRefinementParams::default()
            }
        );
        assert!(StageParams::symmetry().refinement.enabled);
        assert!(StageParams::viewer_pose().refinement.enabled);
        // Both built-in models fit the refining sphere to the side the camera sees.
        for params in built_in_params() {
            assert!(params.refinement.enabled && params.refinement.facing_camera);
        }
    }

    /// The stage parameters of the built-in `symmetry` and `viewer-pose` files.
    fn built_in_params() -> [StageParams; 2] {
        [
            include_str!("../models/symmetry.json"),
            include_str!("../models/viewer-pose.json"),
        ]
        .map(|text| {
            let model: serde_json::Value = serde_json::from_str(text).unwrap();
            serde_json::from_value(model["stage_params"].clone()).unwrap()
        })
    }

    #[test]
    fn the_colour_blind_detectors_hold_detections_to_the_strict_free_space_check() {
        assert_eq!(StageParams::symmetry().free_space, FreeSpaceCheck::strict());
        assert_eq!(
            StageParams::viewer_pose().free_space,
            FreeSpaceCheck::strict()
        );
        // A file without the key gets it too; one whose `free_space` lacks the see-through
        // keys gets the lenient defaults of the first version of that check.
        let mut json = serde_json::to_value(StageParams::symmetry()).unwrap();
        let fresh: StageParams = serde_json::from_value(json.clone()).unwrap();
        assert_eq!(fresh.free_space, FreeSpaceCheck::strict());
        json.as_object_mut().unwrap().remove("free_space");
        let older: StageParams = serde_json::from_value(json.clone()).unwrap();
        assert_eq!(older.free_space, FreeSpaceCheck::strict());
        json["free_space"] = serde_json::json!(
            {"enabled": true, "min_lead_radii": -1.5, "disc_radius_fraction": 0.5}
        );
        let partial: StageParams = serde_json::from_value(json).unwrap();
        assert_eq!(partial.free_space, FreeSpaceCheck::default());
        // The built-in files carry the strict values (added by hand to files whose classifiers
        // and calibrations were fitted before: detection only, see the training example).
        for params in built_in_params() {
            assert_eq!(params.free_space, FreeSpaceCheck::strict());
        }
    }

    #[test]
    fn symmetry_checks_the_double_curvature_viewer_pose_and_older_files_do_not() {
        assert_eq!(
            StageParams::symmetry().double_curvature,
            DoubleCurvatureCheck::default()
        );
        assert!(DoubleCurvatureCheck::default().enabled);
        assert_eq!(
            StageParams::viewer_pose().double_curvature,
            DoubleCurvatureCheck::off()
        );
        let mut json = serde_json::to_value(StageParams::symmetry()).unwrap();
        json.as_object_mut().unwrap().remove("double_curvature");
        let older: StageParams = serde_json::from_value(json.clone()).unwrap();
        assert_eq!(older.double_curvature, DoubleCurvatureCheck::off());
        json["double_curvature"] = serde_json::json!({"enabled": true});
        let on: StageParams = serde_json::from_value(json).unwrap();
        assert_eq!(on.double_curvature, DoubleCurvatureCheck::default());
        // The built-in files: symmetry's carries the check (added by hand, detection only),
        // viewer-pose's does not.
        let [symmetry, viewer_pose] = built_in_params();
        assert_eq!(symmetry.double_curvature, DoubleCurvatureCheck::default());
        assert_eq!(viewer_pose.double_curvature, DoubleCurvatureCheck::off());
    }

    #[test]
    fn the_normal_window_is_scaled_above_the_finest_training_camera_only() {
        let normals = StageParams::symmetry().normals;
        assert_eq!(normals.reference_focal_px, Some(365.0));
        assert!(normals.keep_sample_count);
        assert_eq!(normals.scale_above_focal_px, Some(615.0));
        assert_eq!(StageParams::viewer_pose().normals, normals);
        // Older files keep the fixed window on every camera.
        let mut json = serde_json::to_value(StageParams::symmetry()).unwrap();
        for key in [
            "reference_focal_px",
            "keep_sample_count",
            "scale_above_focal_px",
        ] {
            json["normals"].as_object_mut().unwrap().remove(key);
        }
        let older: StageParams = serde_json::from_value(json).unwrap();
        assert_eq!(older.normals, WindowNormalParams::default());
        // Both built-in files carry the defaults (added by hand: their training cameras are all
        // at or below the floor, so the classifiers are the ones trained before).
        for params in built_in_params() {
            assert_eq!(params.normals, normals);
        }
    }

    #[test]
    fn bad_values_are_named() {
        // `p` refused by `validate`, with `name` in the message.
        let refused_naming = |p: StageParams, name: &str| {
            let err = p.validate().unwrap_err().to_string();
            assert!(err.contains(name), "{err}");
        };
        let mut p = StageParams::symmetry();
        p.boxes.stride_m = 0.0;
        refused_naming(p, "boxes.stride_m");
        let mut p = StageParams::symmetry();
        p.histogram.angle_bins = 0;
        assert!(p.validate().is_err());
        let mut p = StageParams::viewer_pose();
        p.free_space.disc_radius_fraction = -1.0;
        refused_naming(p, "free_space.disc_radius_fraction");
        let mut p = StageParams::symmetry();
        p.double_curvature.patch_radii = f64::NAN;
        refused_naming(p, "double_curvature.patch_radii");
        let mut p = StageParams::symmetry();
        p.cascade.score_weight = -1.0;
        refused_naming(p, "cascade.score_weight");
        let mut p = StageParams::symmetry();
        p.cascade.min_score = f64::NAN;
        refused_naming(p, "cascade.min_score");
    }

    /// Both box pipelines score a box with both SVMs (`symmetry` lets more boxes through the
    /// cascade than before and merges from a lower score); files without `score_weight` score
    /// with the main SVM alone.
    #[test]
    fn both_pipelines_add_the_cascade_value_older_files_do_not() {
        let p = StageParams::symmetry();
        assert_eq!(
            (
                p.cascade.min_score,
                p.cascade.score_weight,
                p.merging.min_score
            ),
            (-0.5, 1.0, -1.5)
        );
        let v = StageParams::viewer_pose();
        assert!(v.cascade.enabled);
        assert_eq!((v.cascade.min_score, v.cascade.score_weight), (-1.0, 1.0));
        assert_eq!(v.merging, MergeParams::default());
        let mut json = serde_json::to_value(&p).unwrap();
        json["cascade"]
            .as_object_mut()
            .unwrap()
            .remove("score_weight");
        let older: StageParams = serde_json::from_value(json).unwrap();
        assert_eq!(older.cascade.score_weight, 0.0);
    }
}
