//! Stage `merge`: positive boxes → one box per fruit, by 3D non-maximum suppression (seed 000)
//! or mean shift (seed 001), best first.

use pomona_pipeline::{PipelineError, Stage};

use crate::{mean_shift, non_maximum_suppression, MergeKind, MergeParams, ScoredBox};

/// Stage `merge`: NMS or mean shift.
pub(crate) struct Merge {
    pub(crate) kind: MergeKind,
    pub(crate) params: MergeParams,
}

impl Stage<&[ScoredBox], Vec<ScoredBox>> for Merge {
    fn name(&self) -> &'static str {
        "merge"
    }

    fn run(&self, boxes: &[ScoredBox]) -> Result<Vec<ScoredBox>, PipelineError> {
        let mut out = match self.kind {
            MergeKind::Nms => non_maximum_suppression(boxes, self.params.nms_radius_m),
            MergeKind::MeanShift => mean_shift(
                boxes,
                self.params.min_score,
                self.params.bandwidth_m,
                self.params.max_iterations,
            ),
        };
        out.sort_by(|a, b| b.score.total_cmp(&a.score));
        Ok(out)
    }
}
