//! The [`pomona_pipeline::Pipeline`] implementation shared by the two box pipelines
//! (`symmetry`, `viewer-pose`): they differ only in their name, default parameters and built-in
//! model, and both train with `training.rs` and detect with [`crate::BoxDetector`]. A macro,
//! because each pipeline is its own public type (`SymmetryPipeline`, `ViewerPosePipeline`) and a
//! blanket implementation of a foreign trait is not allowed.

/// Implements `Pipeline` for `$pipeline` (a struct with a `params: StageParams` field) under the
/// name `$name`, with the built-in model `$model` (a path relative to `src/`) documented by
/// `$model_doc`.
macro_rules! box_pipeline {
    ($pipeline:ident, $name:expr, $model:literal, $model_doc:literal) => {
        impl pomona_pipeline::Pipeline for $pipeline {
            fn name(&self) -> &'static str {
                $name
            }

            fn train_params(&self) -> serde_json::Value {
                pomona_pipeline::params_to_json(&self.params)
            }

            fn with_train_params(
                &self,
                params: serde_json::Value,
            ) -> Result<Box<dyn pomona_pipeline::Pipeline>, pomona_pipeline::PipelineError> {
                Ok(Box::new(Self {
                    params: pomona_pipeline::params_from_json(params)?,
                }))
            }

            fn needs_color(&self) -> bool {
                false
            }

            #[doc = $model_doc]
            fn default_model(&self) -> Option<&'static str> {
                Some(include_str!($model)).filter(|s| !s.trim().is_empty())
            }

            fn train(
                &self,
                frames: &dyn pomona_pipeline::FrameSource,
                options: &pomona_pipeline::TrainOptions,
                progress: &(dyn Fn(usize, usize) + Sync),
            ) -> Result<pomona_learn::ModelFile, pomona_pipeline::PipelineError> {
                $crate::training::train($name, &self.params, frames, options, progress)
            }

            fn complete_stage_params(
                &self,
                stage_params: &serde_json::Value,
            ) -> Result<serde_json::Value, pomona_pipeline::PipelineError> {
                pomona_pipeline::complete_with_defaults::<$crate::StageParams>(stage_params)
            }

            fn load(
                &self,
                model: &pomona_learn::ModelFile,
            ) -> Result<Box<dyn pomona_pipeline::Detector>, pomona_pipeline::PipelineError> {
                Ok(Box::new($crate::BoxDetector::from_model($name, model)?))
            }
        }
    };
}

pub(crate) use box_pipeline;
