//! In-memory synthetic training and test frames (a [`FrameSource`] over `pomona-synth`), for the
//! detectors' tests, benchmarks and the examples that train their built-in models.

use crate::{FrameSource, LabelledFrame, PipelineError};
use pomona_synth::{render, SceneSpec};

/// Frames `first..first + count` of the synthetic dataset `(spec, seed)`, rendered on demand.
#[derive(Debug, Clone)]
pub struct SyntheticFrames {
    /// Scene parameters.
    pub spec: SceneSpec,
    /// Dataset seed (frame `i` uses a seed derived from it and `i`).
    pub seed: u64,
    /// Index of the first frame.
    pub first: u64,
    /// Number of frames.
    pub count: usize,
}

impl FrameSource for SyntheticFrames {
    fn len(&self) -> usize {
        self.count
    }

    fn load(&self, i: usize) -> Result<LabelledFrame, PipelineError> {
        let index = self.first + i as u64;
        let invalid = |e: pomona_synth::SynthError| PipelineError::InvalidParameter {
            name: "synthetic scene".into(),
            reason: e.to_string(),
        };
        let scene = self.spec.sample_frame(self.seed, index).map_err(invalid)?;
        let r = render(&scene, &self.spec.camera).map_err(invalid)?;
        Ok(LabelledFrame {
            name: format!("synthetic/{}/{index:06}", self.seed),
            frame: r.frame,
            truth: r.truth,
            mask: Some(r.mask),
        })
    }
}
