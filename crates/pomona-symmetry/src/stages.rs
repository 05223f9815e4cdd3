//! The stages a box detector is built from, shared by training and detection so that both cut,
//! orient and describe boxes identically: highlight pruning, normals, the sliding box, the
//! reference frame, the feature histograms, the centre refinement, and (symmetry or viewer frame
//! with the cascade on) the fixed-frame features of the cascade.

use nalgebra::Point3;
use pomona_pipeline::{DoubleCurvatureFilter, FreeSpaceFilter};
use rayon::prelude::*;

use crate::{
    BoxPatch, CentreRefinement, FeatureStage, FixedFrame, FrameKind, FrameStage, HighlightDetector,
    NormalStage, ReferenceFrame, SceneCloud, SlidingBox, StageParams, SymmetryError, SymmetryFrame,
    SymmetryPlaneSearch, ViewerFrame,
};

/// The stages shared by training and detection.
pub struct Stages {
    pub(crate) params: StageParams,
    pub(crate) highlight: HighlightDetector,
    pub(crate) normals: NormalStage,
    pub(crate) boxes: SlidingBox,
    pub(crate) frames: FrameStage,
    pub(crate) features: FeatureStage,
    /// Fixed-frame features, for the cascade (symmetry or viewer frame with `cascade.enabled`).
    pub(crate) cascade_features: Option<FeatureStage>,
    pub(crate) refinement: CentreRefinement,
    /// Drops merged detections the camera sees through; a detection the refinement gave no
    /// diameter counts as a fruit a quarter of the box across.
    pub(crate) free_space: FreeSpaceFilter,
    /// Drops merged detections on a surface that does not bend both ways; a detection the
    /// refinement gave no diameter passes unjudged (no fruit radius to measure the patch and
    /// the bend by; measuring it as a fruit a quarter or three eighths of the box across was no
    /// better on the tuning sets).
    pub(crate) double_curvature: DoubleCurvatureFilter,
}

impl Stages {
    /// Builds every stage from validated parameters.
    ///
    /// # Errors
    /// [`SymmetryError::InvalidParameter`] for invalid parameters.
    pub fn new(params: &StageParams) -> Result<Self, SymmetryError> {
        params.validate()?;
        let frame: Box<dyn ReferenceFrame> = match params.frame {
            FrameKind::Symmetry => Box::new(SymmetryFrame::new(SymmetryPlaneSearch::new(
                params.symmetry,
            ))),
            FrameKind::Fixed => Box::new(FixedFrame),
            FrameKind::Viewer => Box::new(ViewerFrame),
        };
        let boxes = SlidingBox::new(params.boxes);
        let cascade_features = (params.cascade.enabled && params.frame != FrameKind::Fixed)
            .then(|| FeatureStage::new(FrameKind::Fixed, boxes.half_m(), params.cascade.histogram));
        Ok(Self {
            cascade_features,
            params: params.clone(),
            highlight: HighlightDetector::new(params.highlight.clone()),
            normals: NormalStage::new(params.normals, params.boxes.pixel_lattice)?,
            frames: FrameStage::new(frame),
            features: FeatureStage::new(params.frame, boxes.half_m(), params.histogram),
            refinement: CentreRefinement::new(params.refinement)?,
            free_space: FreeSpaceFilter {
                check: params.free_space,
                fallback_radius_m: Some(params.boxes.box_size_m / 4.0),
            },
            double_curvature: DoubleCurvatureFilter {
                check: params.double_curvature,
                fallback_radius_m: None,
            },
            boxes,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &StageParams {
        &self.params
    }

    /// The normal stage (frame → cloud).
    pub fn normal_stage(&self) -> &NormalStage {
        &self.normals
    }

    /// The sliding box.
    pub fn sliding_box(&self) -> &SlidingBox {
        &self.boxes
    }

    /// The reference-frame stage.
    pub fn frame_stage(&self) -> &FrameStage {
        &self.frames
    }

    /// The feature stage.
    pub fn feature_stage(&self) -> &FeatureStage {
        &self.features
    }

    /// The centre refinement of merged detections.
    pub fn centre_refinement(&self) -> &CentreRefinement {
        &self.refinement
    }

    /// Features of explicit boxes (training): patch, frame, features; boxes that fail any step
    /// are left out.
    pub fn describe_centres(&self, cloud: &SceneCloud, centres: &[Point3<f64>]) -> Vec<Vec<f64>> {
        self.describe_centres_with_cascade(cloud, centres).0
    }

    /// [`Stages::describe_centres`], plus the fixed-frame features of every box with a patch
    /// when the cascade is on (its training samples; empty otherwise).
    pub fn describe_centres_with_cascade(
        &self,
        cloud: &SceneCloud,
        centres: &[Point3<f64>],
    ) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let patches: Vec<BoxPatch> = centres
            .par_iter()
            .filter_map(|&c| self.boxes.patch(cloud, c))
            .collect();
        let frames = self.frames.frames(&patches);
        let main = self
            .features
            .features(&patches, &frames)
            .into_iter()
            .flatten()
            .collect();
        let cascade = match &self.cascade_features {
            Some(fs) => patches
                .iter()
                .filter_map(|p| {
                    FixedFrame
                        .frame(p, &Point3::origin())
                        .map(|f| fs.describe(p, &f))
                })
                .collect(),
            None => Vec::new(),
        };
        (main, cascade)
    }
}
