//! One versioned JSON file per trained detector:
//!
//! ```json
//! {"format": "pomona-model", "version": 1, "pipeline": "shape-fit",
//!  "stage_params": {...}, "scaler": {...} | null, "svm": {...},
//!  "calibration": {...}}            // optional: score → confidence, operating threshold
//! ```
//!
//! `stage_params` holds whatever the pipeline's non-learnt stages need (thresholds, window sizes)
//! so a model file alone reproduces a detector. `format` and `version` are checked before anything
//! else is parsed, so a file from a newer release fails with a version error rather than a
//! confusing missing-field message; a model loaded by the wrong pipeline is rejected as well.
//! Numbers are written in shortest round-trip form and parsed with correct rounding, so every
//! `f64` survives a save and load bit for bit.

use std::path::Path;

use pomona_io::read_budget::read_json_text;

use serde::{Deserialize, Serialize};

use serde_json::value::RawValue;

use crate::model_head::{ModelHead, Peek};
use crate::{MinMaxScaler, ModelFileError, RbfSvm, ScoreCalibration, SvmClassifier};

/// Value of the `format` key.
pub const MODEL_FORMAT: &str = "pomona-model";
/// Format version this build writes and reads.
pub const MODEL_VERSION: u32 = 1;

/// Largest model file read (the built-in models are under 3 MB); together with
/// [`MAX_STAGE_PARAMS_BYTES`] it keeps the memory a hostile model file can claim within a small
/// multiple of its size (see `pomona_io::read_budget`).
pub const MAX_MODEL_FILE_BYTES: u64 = 16 << 20;

/// Largest `stage_params` object read: it is parsed into a generic JSON value, which takes up
/// to about 17 times its text (measured by `tests/model_alloc_cap.rs`). The built-in symmetry
/// model's stage parameters (which hold its cascade classifier) are 1.45 MB, so 4 MiB leaves
/// room for models trained on more data while a hostile file stays within 4 × its size + 64 MB.
pub const MAX_STAGE_PARAMS_BYTES: usize = 4 << 20;

/// Contents of a model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    /// Always [`MODEL_FORMAT`].
    pub format: String,
    /// Always [`MODEL_VERSION`] for files this build writes.
    pub version: u32,
    /// Name of the pipeline the model belongs to.
    pub pipeline: String,
    /// Parameters of the pipeline's other stages, pipeline-defined.
    pub stage_params: serde_json::Value,
    /// Feature scaling, when the model was trained on scaled features.
    pub scaler: Option<MinMaxScaler>,
    /// The SVM.
    pub svm: RbfSvm,
    /// Score → confidence map and operating threshold fitted on held-out frames; `None` for a
    /// model trained without calibration (older files, or `--calibration-folds 0`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<ScoreCalibration>,
}

impl ModelFile {
    /// Packages a trained classifier for `pipeline`.
    pub fn new(
        pipeline: impl Into<String>,
        stage_params: serde_json::Value,
        classifier: &SvmClassifier,
    ) -> Self {
        Self {
            format: MODEL_FORMAT.into(),
            version: MODEL_VERSION,
            pipeline: pipeline.into(),
            stage_params,
            scaler: classifier.scaler.clone(),
            svm: classifier.svm.clone(),
            calibration: None,
        }
    }

    /// The classifier stored in the file.
    pub fn classifier(&self) -> SvmClassifier {
        SvmClassifier {
            scaler: self.scaler.clone(),
            svm: self.svm.clone(),
            info: None,
        }
    }

    /// Writes the file atomically (temporary file, then rename) as compact JSON: thousands of
    /// support-vector numbers are read by programs, and indentation would double the file.
    ///
    /// # Errors
    /// [`ModelFileError::Write`] naming the file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), ModelFileError> {
        pomona_io::write_json_compact(path.as_ref(), self)?;
        Ok(())
    }

    /// Reads a model file and checks it was made for `pipeline` by this format version.
    ///
    /// # Errors
    /// [`ModelFileError::Io`] (also for a file over [`MAX_MODEL_FILE_BYTES`]),
    /// [`ModelFileError::Json`], [`ModelFileError::NotAModel`], [`ModelFileError::Version`],
    /// [`ModelFileError::Pipeline`], [`ModelFileError::Invalid`] (also for `stage_params` over
    /// [`MAX_STAGE_PARAMS_BYTES`]); each names the file.
    pub fn load(path: impl AsRef<Path>, pipeline: &str) -> Result<Self, ModelFileError> {
        let path = path.as_ref();
        let text =
            read_json_text(path, MAX_MODEL_FILE_BYTES).map_err(|source| ModelFileError::Io {
                path: path.to_owned(),
                source,
            })?;
        Self::from_json(&text, path, pipeline)
    }

    /// Reads a model file of any pipeline (the one it names), checking everything
    /// [`ModelFile::load`] checks except which pipeline it is for.
    ///
    /// # Errors
    /// As [`ModelFile::load`], without [`ModelFileError::Pipeline`].
    pub fn load_any(path: impl AsRef<Path>) -> Result<Self, ModelFileError> {
        #[derive(serde::Deserialize)]
        struct Named {
            #[serde(default)]
            pipeline: serde_json::Value,
        }
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| ModelFileError::Io {
            path: path.to_owned(),
            source,
        })?;
        let named: Named = serde_json::from_str(&text).map_err(|source| ModelFileError::Json {
            path: path.to_owned(),
            source,
        })?;
        let pipeline = named.pipeline.as_str().unwrap_or_default().to_owned();
        Self::from_json(&text, path, &pipeline)
    }

    /// Parses model JSON; `path` is only used in error messages.
    ///
    /// # Errors
    /// As [`ModelFile::load`] except for I/O.
    pub fn from_json(text: &str, path: &Path, pipeline: &str) -> Result<Self, ModelFileError> {
        let json_err = |source| ModelFileError::Json {
            path: path.to_owned(),
            source,
        };
        let head: ModelHead = serde_json::from_str(text).map_err(json_err)?;
        if head.format.as_ref().and_then(Peek::as_str) != Some(MODEL_FORMAT) {
            return Err(ModelFileError::NotAModel {
                path: path.to_owned(),
                found: head.format.as_ref().map(Peek::describe),
            });
        }
        let version = head.version.as_ref().and_then(Peek::as_u64);
        if version != Some(u64::from(MODEL_VERSION)) {
            return Err(ModelFileError::Version {
                path: path.to_owned(),
                found: version.unwrap_or(0),
                supported: MODEL_VERSION,
            });
        }
        let found = head.pipeline.as_ref().and_then(Peek::as_str).unwrap_or("");
        if found != pipeline {
            return Err(ModelFileError::Pipeline {
                path: path.to_owned(),
                found: found.to_owned(),
                expected: pipeline.to_owned(),
            });
        }
        // Parse from the text, not a generic value, so numbers keep their exact decimal form.
        let wire: ModelWire = serde_json::from_str(text).map_err(json_err)?;
        let model = wire.into_model(path)?;
        let invalid = |source| ModelFileError::Invalid {
            path: path.to_owned(),
            source,
        };
        model.svm.validate().map_err(invalid)?;
        if let Some(c) = &model.calibration {
            c.validate().map_err(invalid)?;
        }
        if let Some(s) = &model.scaler {
            s.validate().map_err(invalid)?;
            if s.n_features() != model.svm.n_features {
                return Err(invalid(crate::LearnError::InconsistentModel(format!(
                    "scaler has {} features, svm {}",
                    s.n_features(),
                    model.svm.n_features
                ))));
            }
        }
        Ok(model)
    }
}

/// A model file as parsed: `stage_params` kept as text until its size is checked.
#[derive(Deserialize)]
struct ModelWire<'a> {
    format: String,
    version: u32,
    pipeline: String,
    #[serde(borrow)]
    stage_params: &'a RawValue,
    scaler: Option<MinMaxScaler>,
    svm: RbfSvm,
    #[serde(default)]
    calibration: Option<ScoreCalibration>,
}

impl ModelWire<'_> {
    /// The model, once `stage_params` is known to be small enough to parse.
    fn into_model(self, path: &Path) -> Result<ModelFile, ModelFileError> {
        let raw = self.stage_params.get();
        let invalid = |reason: String| ModelFileError::Invalid {
            path: path.to_owned(),
            source: crate::LearnError::InconsistentModel(reason),
        };
        if raw.len() > MAX_STAGE_PARAMS_BYTES {
            return Err(invalid(format!(
                "stage_params of {} bytes is over the {MAX_STAGE_PARAMS_BYTES}-byte limit",
                raw.len()
            )));
        }
        let stage_params = serde_json::from_str(raw).map_err(|source| ModelFileError::Json {
            path: path.to_owned(),
            source,
        })?;
        Ok(ModelFile {
            format: self.format,
            version: self.version,
            pipeline: self.pipeline,
            stage_params,
            scaler: self.scaler,
            svm: self.svm,
            calibration: self.calibration,
        })
    }
}
