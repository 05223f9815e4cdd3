//! [`Detector`]: a trained fruit detector, ready to run on frames — the one type a robot program
//! needs — and [`DetectorBuilder`], which chooses its model and parameters.
//!
//! The facade hides what the lower crates keep apart: the pipeline registry, model files, the
//! built-in models (and the depth-only one used for frames without colour), confidence
//! calibration, parameter overrides and per-stage timings.

use std::path::{Path, PathBuf};

use pomona_core::{Detection, RgbdFrame};
use pomona_learn::ModelFile;
use pomona_pipeline::{Pipeline, StageTimings};

use crate::model_choice::{built_in, ModelChoice};
use crate::model_info::{ModelInfo, ModelSource};
use crate::param_override::{apply_overrides, ParamOverride};
use crate::{registry, Error};

/// One loaded model and the detector built from it.
struct Loaded {
    detector: Box<dyn pomona_pipeline::Detector>,
    info: ModelInfo,
}

/// A trained detector of one pipeline.
///
/// [`Detector::detect`] returns every detection with its raw `score` and, for calibrated models
/// (all built-in ones), a `confidence` in `[0, 1]`; no threshold is applied. Keep those with
/// [`Detector::keeps`] to get what `pomona detect` writes by default. A detector is `Send + Sync`:
/// share one across threads and call `detect` concurrently.
///
/// ```
/// # fn main() -> Result<(), pomona::Error> {
/// use pomona::{ColorImage, DepthImage, PinholeCamera, RgbdFrame};
///
/// let detector = pomona::Detector::builtin("shape-fit")?;
/// # let camera = PinholeCamera::new(64, 48, 60.0, 60.0, 31.5, 23.5)?;
/// # let depth = DepthImage::from_meters(64, 48, vec![0.8; 64 * 48])?;
/// # let color = ColorImage::from_rgb(64, 48, vec![90; 3 * 64 * 48])?;
/// # let frame = RgbdFrame::new(camera, depth, Some(color))?;
/// for fruit in detector.detect(&frame)? {
///     if detector.keeps(&fruit) {
///         println!("fruit at {} m, {:?} m across", fruit.center_m, fruit.diameter_m);
///     }
/// }
/// # Ok(())
/// # }
/// ```
pub struct Detector {
    pipeline: &'static str,
    main: Loaded,
    depth_only: Option<Loaded>,
}

impl std::fmt::Debug for Detector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Detector")
            .field("pipeline", &self.pipeline)
            .field("model", &self.main.info)
            .field(
                "depth_only_model",
                &self.depth_only.as_ref().map(|l| &l.info),
            )
            .finish()
    }
}

impl Detector {
    /// The built-in detector of the pipeline called `name` (`"shape-fit"`, `"symmetry"`,
    /// `"viewer-pose"`). Frames without colour use the pipeline's depth-only built-in model
    /// when it ships one.
    ///
    /// # Errors
    /// [`Error::UnknownPipeline`] or [`Error::NoBuiltInModel`].
    pub fn builtin(name: &str) -> Result<Self, Error> {
        Self::builder(name)?.build()
    }

    /// The detector of a model file written by `pomona train` (its pipeline is read from the
    /// file).
    ///
    /// # Errors
    /// [`Error::ModelFile`] for an unreadable or invalid file, [`Error::UnknownPipeline`] when
    /// the file names a pipeline this build lacks, [`Error::Load`] when its parameters are
    /// rejected.
    pub fn from_model_file(path: impl AsRef<Path>) -> Result<Self, Error> {
        let path = path.as_ref();
        let model = ModelFile::load_any(path)?;
        let pipeline = model.pipeline.clone();
        Self::builder(&pipeline)?
            .model(model, ModelSource::File(path.to_owned()))
            .build()
    }

    /// A builder for the registered pipeline called `name`.
    ///
    /// # Errors
    /// [`Error::UnknownPipeline`].
    pub fn builder(name: &str) -> Result<DetectorBuilder<'static>, Error> {
        Ok(DetectorBuilder::new(PipelineHandle::Owned(
            registry::pipeline(name)?,
        )))
    }

    /// A builder for a pipeline the caller holds (for example one not in the registry).
    pub fn builder_for(pipeline: &dyn Pipeline) -> DetectorBuilder<'_> {
        DetectorBuilder::new(PipelineHandle::Borrowed(pipeline))
    }

    /// The pipeline's name (written into detection files).
    pub fn pipeline(&self) -> &'static str {
        self.pipeline
    }

    /// The model used for frames with colour (and for every frame when there is no depth-only
    /// model).
    pub fn model(&self) -> &ModelInfo {
        &self.main.info
    }

    /// The model used for `frame`: the depth-only one when the frame has no colour and the
    /// detector has one.
    pub fn model_for(&self, frame: &RgbdFrame) -> &ModelInfo {
        self.model_for_color(frame.color().is_some())
    }

    /// The model used for frames with (`true`) or without (`false`) colour.
    pub fn model_for_color(&self, has_color: bool) -> &ModelInfo {
        &self.loaded(has_color).info
    }

    /// The main model's operating confidence (see [`ModelInfo::operating_confidence`]).
    pub fn operating_confidence(&self) -> Option<f64> {
        self.main.info.operating_confidence
    }

    /// Whether `pomona detect` would keep `detection` by default: its confidence reaches the
    /// model's operating confidence, or for a model without calibration its score reaches 0
    /// (the classifier accepts it).
    pub fn keeps(&self, detection: &Detection) -> bool {
        self.default_keep_rule().keeps(detection)
    }

    /// Finds fruit in `frame`: every detection, unthresholded, in the camera frame (metres).
    ///
    /// # Errors
    /// [`Error::Detect`], for example a colour pipeline given a frame without colour.
    pub fn detect(&self, frame: &RgbdFrame) -> Result<Vec<Detection>, Error> {
        self.detect_with_timings(frame).map(|(d, _)| d)
    }

    /// As [`Detector::detect`], also returning the time each stage took.
    ///
    /// # Errors
    /// As [`Detector::detect`].
    pub fn detect_with_timings(
        &self,
        frame: &RgbdFrame,
    ) -> Result<(Vec<Detection>, StageTimings), Error> {
        let mut timings = StageTimings::default();
        let detections = self
            .loaded(frame.color().is_some())
            .detector
            .detect(frame, &mut timings)
            .map_err(|source| Error::Detect {
                pipeline: self.pipeline,
                source: Box::new(source),
            })?;
        Ok((detections, timings))
    }

    fn loaded(&self, has_color: bool) -> &Loaded {
        match (&self.depth_only, has_color) {
            (Some(depth_only), false) => depth_only,
            _ => &self.main,
        }
    }
}

/// The pipeline a builder builds for: one from the registry, or one the caller lends.
enum PipelineHandle<'p> {
    Owned(Box<dyn Pipeline>),
    Borrowed(&'p dyn Pipeline),
}

impl PipelineHandle<'_> {
    fn get(&self) -> &dyn Pipeline {
        match self {
            Self::Owned(p) => p.as_ref(),
            Self::Borrowed(p) => *p,
        }
    }
}

/// Chooses a detector's model and stage-parameter overrides; [`DetectorBuilder::build`] loads it.
///
/// ```
/// # fn main() -> Result<(), pomona::Error> {
/// let detector = pomona::Detector::builder("symmetry")?
///     .set("highlight.enabled", false) // seed 000's ablation: no highlight pruning
///     .build()?;
/// assert_eq!(detector.pipeline(), "symmetry");
/// # Ok(())
/// # }
/// ```
pub struct DetectorBuilder<'p> {
    pipeline: PipelineHandle<'p>,
    model: ModelChoice,
    overrides: Vec<ParamOverride>,
}

impl<'p> DetectorBuilder<'p> {
    fn new(pipeline: PipelineHandle<'p>) -> Self {
        Self {
            pipeline,
            model: ModelChoice::BuiltIn,
            overrides: Vec::new(),
        }
    }

    /// Use the model file at `path` instead of the built-in model.
    #[must_use]
    pub fn model_file(mut self, path: impl Into<PathBuf>) -> Self {
        self.model = ModelChoice::File(path.into());
        self
    }

    /// Use `model` (for example one just trained), labelled `source` in messages.
    #[must_use]
    pub fn model(mut self, model: ModelFile, source: ModelSource) -> Self {
        self.model = ModelChoice::Given(Box::new((model, source)));
        self
    }

    /// Override the stage parameter at dotted `key` (it must exist, with the same JSON type).
    #[must_use]
    pub fn set(mut self, key: impl Into<String>, value: impl Into<serde_json::Value>) -> Self {
        self.overrides.push(ParamOverride::new(key, value));
        self
    }

    /// Apply `overrides` in order (after any given before).
    #[must_use]
    pub fn overrides(mut self, overrides: impl IntoIterator<Item = ParamOverride>) -> Self {
        self.overrides.extend(overrides);
        self
    }

    /// Loads the model(s) and builds the detector.
    ///
    /// # Errors
    /// [`Error::ModelFile`] (unreadable, or made for another pipeline or version),
    /// [`Error::NoBuiltInModel`], [`Error::UnknownParameter`] / [`Error::ParameterType`] for a
    /// bad override, [`Error::Load`] for parameters the pipeline rejects.
    pub fn build(self) -> Result<Detector, Error> {
        let pipeline = self.pipeline.get();
        let name = pipeline.name();
        // A built-in model comes with the pipeline's depth-only one, if it has one.
        let depth_only = if self.model.is_built_in() {
            pipeline
                .default_depth_only_model()
                .map(|text| built_in(name, text, ModelSource::BuiltInDepthOnly))
                .transpose()?
        } else {
            None
        };
        let main = self.model.load(pipeline)?;
        let load = |(mut model, source): (ModelFile, ModelSource)| -> Result<Loaded, Error> {
            let owner = format!("the model of `{name}` ({source})");
            if !self.overrides.is_empty() {
                // A model saved before a parameter existed lacks its key; fill the defaults in
                // so every current parameter can be overridden.
                model.stage_params = pipeline
                    .complete_stage_params(&model.stage_params)
                    .map_err(|e| Error::Load {
                        pipeline: name.to_owned(),
                        model: source.to_string(),
                        source: Box::new(e),
                    })?;
            }
            apply_overrides(&mut model.stage_params, &self.overrides, &owner)?;
            let detector =
                pomona_pipeline::load_detector(pipeline, &model).map_err(|e| Error::Load {
                    pipeline: name.to_owned(),
                    model: source.to_string(),
                    source: Box::new(e),
                })?;
            Ok(Loaded {
                detector,
                info: ModelInfo::of(&model, source),
            })
        };
        Ok(Detector {
            pipeline: name,
            main: load(main)?,
            depth_only: depth_only.map(load).transpose()?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model saved before `coaxial_merge` existed (the built-in shape-fit model with the key
    /// removed, as older files are): its parameters can still be overridden (the defaults are
    /// filled in first), and a typo is still an error.
    #[test]
    fn parameters_newer_than_the_model_can_be_overridden() -> Result<(), Box<dyn std::error::Error>>
    {
        let text = registry::pipeline("shape-fit")?
            .default_model()
            .unwrap_or_default();
        let mut json: serde_json::Value = serde_json::from_str(text)?;
        let params = json["stage_params"]["params"]
            .as_object_mut()
            .ok_or("the built-in model has no stage parameters")?;
        assert!(params.remove("coaxial_merge").is_some());
        let older = ModelFile::from_json(&json.to_string(), Path::new("older.json"), "shape-fit")?;
        let source = || ModelSource::InMemory("older model".into());
        Detector::builder("shape-fit")?
            .model(older.clone(), source())
            .set("params.coaxial_merge.max_gap_radii", 0.5)
            .build()?;
        let typo = Detector::builder("shape-fit")?
            .model(older, source())
            .set("params.coaxial_merge.max_gap_radius", 0.5)
            .build();
        assert!(matches!(typo, Err(Error::UnknownParameter { .. })));
        Ok(())
    }
}
