//! In-memory synthetic training and test frames (a [`FrameSource`] over `pomona-synth`), for the
//! detectors' tests, benchmarks and the examples that train their built-in models.

use crate::{FrameSource, LabelledFrame, PipelineError};
use pomona_synth::{render, CameraPreset, Domain, FruitChoice, NoiseModel, SceneSpec};

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

impl SyntheticFrames {
    /// `count` frames of mixed fruit (a fraction `green_fraction` green) seen by `camera` in
    /// `domain`, with that domain's depth noise for the camera (`tof` in the narrow domain):
    /// the training sets the built-in models are made from.
    pub fn mixed_fruit(
        domain: Domain,
        camera: CameraPreset,
        green_fraction: f64,
        seed: u64,
        count: usize,
    ) -> Self {
        Self {
            spec: SceneSpec {
                fruit: FruitChoice::Mixed,
                camera: camera.camera(),
                noise: match domain {
                    Domain::Narrow => NoiseModel::Tof,
                    Domain::Wide | Domain::Orchard => NoiseModel::for_camera(camera),
                },
                green_fraction,
                domain,
                ..SceneSpec::default()
            },
            seed,
            first: 0,
            count,
        }
    }
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
