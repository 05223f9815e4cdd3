//! Stage `cascade` (ours; symmetry and viewer frames, `cascade.enabled`): each box is first
//! described in the cheap fixed frame and scored by a second SVM trained alongside the main one;
//! boxes below `cascade.min_score` are dropped before their own frame, features and the main SVM
//! (for the symmetry frame the plane search is the costliest step). The decision values of the
//! boxes that pass go on with them: a box's score adds `cascade.score_weight` times its cascade
//! value to the main SVM's ([`box_score`]), in detection and in hard-negative mining alike — two
//! SVMs on two descriptions of the box rank fruit better than either (see
//! [`crate::CascadeParams`]).

use nalgebra::Point3;
use pomona_learn::BatchedClassifier;
use pomona_pipeline::{PipelineError, Stage};
use rayon::prelude::*;

use crate::classify::Classify;
use crate::{BoxPatch, FeatureStage, FixedFrame, ReferenceFrame};

/// Stage `cascade`: fixed-frame features and decision value per box; keeps the boxes scoring at
/// least `min_score`, each with its decision value (see [`crate::CascadeParams`]).
pub(crate) struct Cascade<'a> {
    pub(crate) classifier: &'a BatchedClassifier,
    pub(crate) features: &'a FeatureStage,
    pub(crate) min_score: f64,
}

impl Stage<Vec<BoxPatch>, (Vec<BoxPatch>, Vec<f64>)> for Cascade<'_> {
    fn name(&self) -> &'static str {
        "cascade"
    }

    fn run(&self, patches: Vec<BoxPatch>) -> Result<(Vec<BoxPatch>, Vec<f64>), PipelineError> {
        Ok(self
            .gate(patches)?
            .into_iter()
            .map(|(p, _, score)| (p, score))
            .unzip())
    }
}

/// The score of a box: the main SVM's decision value plus `weight` times the cascade's (`None`
/// without the cascade, which adds nothing).
pub(crate) fn box_score(main: f64, cascade: Option<f64>, weight: f64) -> f64 {
    main + cascade.map_or(0.0, |c| weight * c)
}

impl Cascade<'_> {
    /// The patches that pass, in order, each with its fixed-frame features and decision value.
    pub(crate) fn gate(
        &self,
        patches: Vec<BoxPatch>,
    ) -> Result<Vec<(BoxPatch, Vec<f64>, f64)>, PipelineError> {
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
                let (f, s) = (f?, s?);
                (s >= self.min_score).then_some((p, f, s))
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::box_score;

    #[test]
    fn a_box_adds_the_weighted_cascade_value_when_there_is_one() {
        assert_eq!(box_score(0.25, None, 1.0), 0.25);
        assert_eq!(box_score(0.25, Some(-0.5), 0.0), 0.25);
        assert_eq!(box_score(0.25, Some(-0.5), 1.0), -0.25);
        assert_eq!(box_score(0.25, Some(1.0), 2.0), 2.25);
    }
}
