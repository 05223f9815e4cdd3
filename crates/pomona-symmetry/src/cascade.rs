//! Stage `cascade` (ours, symmetry frame only, `cascade.enabled`): the symmetry-plane search is
//! the costliest step, so each box is first described in the cheap fixed frame and scored by a
//! second SVM trained alongside the main one; boxes below `cascade.min_score` are dropped before
//! the search (see [`crate::CascadeParams`]).

use nalgebra::Point3;
use pomona_learn::BatchedClassifier;
use pomona_pipeline::{PipelineError, Stage};
use rayon::prelude::*;

use crate::classify::Classify;
use crate::{BoxPatch, FeatureStage, FixedFrame, ReferenceFrame};

/// Stage `cascade`: fixed-frame features and decision value per box; keeps the boxes scoring at
/// least `min_score` (see [`crate::CascadeParams`]).
pub(crate) struct Cascade<'a> {
    pub(crate) classifier: &'a BatchedClassifier,
    pub(crate) features: &'a FeatureStage,
    pub(crate) min_score: f64,
}

impl Stage<Vec<BoxPatch>, Vec<BoxPatch>> for Cascade<'_> {
    fn name(&self) -> &'static str {
        "cascade"
    }

    fn run(&self, patches: Vec<BoxPatch>) -> Result<Vec<BoxPatch>, PipelineError> {
        Ok(self.gate(patches)?.into_iter().map(|(p, _)| p).collect())
    }
}

impl Cascade<'_> {
    /// The patches that pass, in order, each with its fixed-frame features.
    pub(crate) fn gate(
        &self,
        patches: Vec<BoxPatch>,
    ) -> Result<Vec<(BoxPatch, Vec<f64>)>, PipelineError> {
        let features: Vec<Option<Vec<f64>>> = patches
            .par_iter()
            .map(|p| {
                FixedFrame
                    .frame(p, &Point3::origin())
                    .map(|f| self.features.describe(p, &f))
            })
            .collect();
        let scores = Classify {
            classifier: self.classifier,
        }
        .run(&features)?;
        Ok(patches
            .into_iter()
            .zip(features)
            .zip(scores)
            .filter_map(|((p, f), s)| {
                let f = f?;
                s.is_some_and(|s| s >= self.min_score).then_some((p, f))
            })
            .collect())
    }
}
