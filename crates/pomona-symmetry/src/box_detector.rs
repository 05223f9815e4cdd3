//! The trained `symmetry` / `viewer-pose` detector ([`BoxDetector`]) and its detection path.
//!
//! Detection per frame (each step a [`Stage`] timed with [`run_stage`]):
//! `highlight` (pruning mask, colour frames only) → `cloud` (points) → `sliding-box` (box
//! candidates: early rejection and their pixels) → `normals` (only at those pixels) →
//! `box-cut` (patches) → `cascade`
//! (`cascade.enabled`, symmetry and viewer frames: a fixed-frame SVM drops clearly negative
//! boxes and its value is added to the main SVM's)
//! → `reference-frame` → `features` → `classifier` (SVM decision value per box) → `merge`
//! (3D NMS or mean shift) → `refine` (ours: sphere-fitted centre off the stride grid and a
//! diameter, see [`crate::CentreRefinement`]) → `free-space` and `double-curvature` (ours:
//! detections the camera sees through, or on a surface that does not bend both ways, are
//! dropped; see [`pomona_pipeline::FreeSpaceCheck`] and
//! [`pomona_pipeline::DoubleCurvatureCheck`]).
//!
//! A detection's `symmetry_plane_normal` is the normal of its box's symmetry plane (symmetry
//! frame only; fixed and viewer frames estimate no plane). No box detector estimates the fruit
//! axis, so `fruit_axis` stays `None`.

use std::sync::atomic::{AtomicBool, Ordering};

use nalgebra::{Unit, Vector3};
use pomona_core::{Detection, RgbdFrame};
use pomona_learn::{BatchedClassifier, ModelFile};
use pomona_pipeline::{run_stage, Detector, PipelineError, StageTimings};

use crate::cascade::{box_score, Cascade};
use crate::classify::Classify;
use crate::merge::Merge;
use crate::scene_cloud::CloudStage;
use crate::sliding_box::BoxCut;
use crate::{
    BoxPatch, FrameKind, FrameResult, Highlights, LocalFrame, PruningState, SceneCloud, ScoredBox,
    StageParams, Stages,
};

/// A trained `symmetry` or `viewer-pose` detector.
pub struct BoxDetector {
    name: &'static str,
    stages: Stages,
    classifier: BatchedClassifier,
    /// The cascade's fixed-frame classifier, when the cascade is on.
    cascade: Option<BatchedClassifier>,
    warned_no_color: AtomicBool,
}

impl BoxDetector {
    /// Builds the detector stored in `model` for pipeline `name`.
    ///
    /// # Errors
    /// [`PipelineError::StageParams`] when the parameters do not parse,
    /// [`PipelineError::InvalidParameter`] when they are invalid or do not match the classifier.
    pub fn from_model(name: &'static str, model: &ModelFile) -> Result<Self, PipelineError> {
        let params: StageParams = serde_json::from_value(model.stage_params.clone())
            .map_err(|e| PipelineError::StageParams(e.to_string()))?;
        let stages = Stages::new(&params)?;
        let classifier = model.classifier();
        if classifier.n_features() != stages.features.feature_len() {
            return Err(PipelineError::InvalidParameter {
                name: "histogram".into(),
                reason: format!(
                    "the classifier takes {} features, the histogram parameters give {}",
                    classifier.n_features(),
                    stages.features.feature_len()
                ),
            });
        }
        let cascade = match (&stages.cascade_features, &params.cascade.classifier) {
            (None, _) => None,
            (Some(fs), Some(c)) => {
                let c = c.classifier();
                if c.n_features() != fs.feature_len() {
                    return Err(PipelineError::InvalidParameter {
                        name: "cascade.classifier".into(),
                        reason: format!(
                            "takes {} features, the histogram parameters give {}",
                            c.n_features(),
                            fs.feature_len()
                        ),
                    });
                }
                Some(BatchedClassifier::new(c)?)
            }
            (Some(_), None) => {
                return Err(PipelineError::InvalidParameter {
                    name: "cascade.classifier".into(),
                    reason: "the cascade is enabled but the model holds no cascade classifier \
                             (retrain, or set cascade.enabled to false)"
                        .into(),
                })
            }
        };
        Ok(Self {
            name,
            stages,
            classifier: BatchedClassifier::new(classifier)?,
            cascade,
            warned_no_color: AtomicBool::new(false),
        })
    }

    /// The stages (for benches and experiments).
    pub fn stages(&self) -> &Stages {
        &self.stages
    }

    /// Detects fruit in `frame` and reports how (pruning state, box counts).
    ///
    /// # Errors
    /// Classifier errors (feature length mismatch, which `from_model` rules out).
    pub fn detect_frame(
        &self,
        frame: &RgbdFrame,
        timings: &mut StageTimings,
    ) -> Result<FrameResult, PipelineError> {
        let s = &self.stages;
        let highlights: Option<Highlights> = run_stage(&s.highlight, frame, timings)?;
        let pruning = self.pruning_state(highlights.as_ref());
        // Normals only where some box reads them (exact; see `scene_cloud.rs`).
        let mut cloud = run_stage(&CloudStage(&s.normals), frame, timings)?;
        let mask = highlights.as_ref().map(|h| &h.mask);
        let candidates = run_stage(&s.boxes, (&cloud, mask), timings)?;
        let normals = run_stage(&s.normals, (&cloud, candidates.as_slice()), timings)?;
        cloud.set_normals(normals);
        let patches = run_stage(&BoxCut(&s.boxes), (&cloud, candidates.as_slice()), timings)?;
        let boxes = patches.len();
        let (patches, cascade_scores) = match (&self.cascade, &s.cascade_features) {
            (Some(classifier), Some(features)) => {
                let cascade = Cascade {
                    classifier,
                    features,
                    min_score: s.params.cascade.min_score,
                };
                let (patches, scores) = run_stage(&cascade, patches, timings)?;
                (patches, scores.into_iter().map(Some).collect())
            }
            _ => {
                let n = patches.len();
                (patches, vec![None; n])
            }
        };
        let positives = self.positive_boxes(&patches, &cascade_scores, timings)?;
        let detections = self.merged_detections(&cloud, &positives, timings)?;
        let detections = run_stage(&s.free_space, (frame, detections), timings)?;
        let detections = run_stage(&s.double_curvature, (frame, detections), timings)?;
        Ok(FrameResult {
            detections,
            pruning,
            boxes,
            searched: patches.len(),
            positives: positives.len(),
        })
    }

    /// The pruning outcome of a frame (and, once per detector, a note that a frame without
    /// colour runs without pruning).
    fn pruning_state(&self, highlights: Option<&Highlights>) -> PruningState {
        let pruning = match (highlights, self.stages.params.highlight.enabled) {
            (Some(h), _) => PruningState::Applied {
                kept_fraction: h.mask.kept_fraction(),
                markers: h.markers.len(),
            },
            (None, true) => PruningState::NoColor,
            (None, false) => PruningState::Disabled,
        };
        if pruning == PruningState::NoColor && !self.warned_no_color.swap(true, Ordering::Relaxed) {
            eprintln!(
                "{}: frame has no colour image; highlight pruning is off (depth-only operation)",
                self.name
            );
        }
        pruning
    }

    /// Reference frame, features and score of every patch (the main SVM's decision value plus
    /// `cascade.score_weight` × the cascade's, `cascade_scores`, one per patch); the boxes
    /// scoring at least `merging.min_score`.
    fn positive_boxes(
        &self,
        patches: &[BoxPatch],
        cascade_scores: &[Option<f64>],
        timings: &mut StageTimings,
    ) -> Result<Vec<ScoredBox>, PipelineError> {
        let s = &self.stages;
        let frames = run_stage(&s.frames, patches, timings)?;
        let features = run_stage(&s.features, (patches, frames.as_slice()), timings)?;
        let classify = Classify {
            classifier: &self.classifier,
        };
        let scores = run_stage(&classify, features.as_slice(), timings)?;
        let min_score = s.params.merging.min_score;
        let weight = s.params.cascade.score_weight;
        Ok(patches
            .iter()
            .zip(&frames)
            .zip(scores.iter().zip(cascade_scores))
            .filter_map(|((p, f), (main, cascade))| {
                let score = box_score((*main)?, *cascade, weight);
                (score >= min_score).then(|| ScoredBox {
                    center: p.center,
                    score,
                    symmetry_plane_normal: plane_normal_of(f.as_ref(), s.params.frame),
                })
            })
            .collect())
    }

    /// Merged, refined detections, best first.
    fn merged_detections(
        &self,
        cloud: &SceneCloud,
        positives: &[ScoredBox],
        timings: &mut StageTimings,
    ) -> Result<Vec<Detection>, PipelineError> {
        let s = &self.stages;
        let merge = Merge {
            kind: s.params.merge,
            params: s.params.merging,
        };
        let merged = run_stage(&merge, positives, timings)?;
        let refined = run_stage(&s.refinement, (cloud, merged.as_slice()), timings)?;
        Ok(refined
            .into_iter()
            .map(|b| Detection {
                diameter_m: b.diameter_m(),
                support_points: b.support_px(),
                symmetry_plane_normal: b.merged.symmetry_plane_normal,
                ..Detection::new(b.center(), b.merged.score)
            })
            .collect())
    }
}

/// The symmetry-plane normal of a symmetry frame. Fixed and viewer frames estimate no plane.
fn plane_normal_of(frame: Option<&LocalFrame>, kind: FrameKind) -> Option<Unit<Vector3<f64>>> {
    match kind {
        FrameKind::Symmetry => frame.map(|f| f.normal),
        FrameKind::Fixed | FrameKind::Viewer => None,
    }
}

impl Detector for BoxDetector {
    fn pipeline(&self) -> &'static str {
        self.name
    }

    fn detect(
        &self,
        frame: &RgbdFrame,
        timings: &mut StageTimings,
    ) -> Result<Vec<Detection>, PipelineError> {
        Ok(self.detect_frame(frame, timings)?.detections)
    }
}
