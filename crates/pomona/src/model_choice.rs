//! Which model a builder loads ([`crate::DetectorBuilder`], [`crate::TrackerBuilder`]): the
//! pipeline's built-in one, a file from `pomona train`, or one handed over in memory. One type so
//! that both builders — and [`load_model`], for callers that want the model rather than a
//! detector — find, parse and label models the same way.

use std::path::{Path, PathBuf};

use pomona_learn::ModelFile;
use pomona_pipeline::Pipeline;

use crate::model_info::ModelSource;
use crate::Error;

/// A builder's choice of model.
#[derive(Debug, Default)]
pub(crate) enum ModelChoice {
    /// The pipeline's built-in model.
    #[default]
    BuiltIn,
    /// A model file.
    File(PathBuf),
    /// A model in memory, with its label (boxed: a model is much larger than a path).
    Given(Box<(ModelFile, ModelSource)>),
}

impl ModelChoice {
    /// Whether the built-in model is chosen.
    pub(crate) fn is_built_in(&self) -> bool {
        matches!(self, Self::BuiltIn)
    }

    /// The chosen model of `pipeline` and where it came from.
    ///
    /// # Errors
    /// [`Error::ModelFile`] for a file that is unreadable or made for another pipeline or
    /// version, [`Error::NoBuiltInModel`] when the pipeline ships none.
    pub(crate) fn load(self, pipeline: &dyn Pipeline) -> Result<(ModelFile, ModelSource), Error> {
        let name = pipeline.name();
        match self {
            Self::Given(given) => Ok(*given),
            Self::File(path) => Ok((ModelFile::load(&path, name)?, ModelSource::File(path))),
            Self::BuiltIn => {
                let text = pipeline.default_model().ok_or(Error::NoBuiltInModel {
                    pipeline: name.to_owned(),
                })?;
                built_in(name, text, ModelSource::BuiltIn)
            }
        }
    }
}

/// The model a command or program would run for `pipeline`: the file at `path` when given,
/// else the pipeline's built-in model — found, parsed and labelled as the builders do, for
/// callers that need the model itself (to recalibrate or inspect it) rather than a detector.
///
/// ```
/// let pipeline = pomona::pipeline("shape-fit")?;
/// let (model, source) = pomona::load_model(pipeline.as_ref(), None)?;
/// assert_eq!(source, pomona::ModelSource::BuiltIn);
/// assert_eq!(model.pipeline, "shape-fit");
/// # Ok::<(), pomona::Error>(())
/// ```
///
/// # Errors
/// [`Error::ModelFile`] for a file that is unreadable or made for another pipeline or version,
/// [`Error::NoBuiltInModel`] without `path` when the pipeline ships no model.
pub fn load_model(
    pipeline: &dyn Pipeline,
    path: Option<&Path>,
) -> Result<(ModelFile, ModelSource), Error> {
    path.map_or(ModelChoice::BuiltIn, |p| ModelChoice::File(p.to_path_buf()))
        .load(pipeline)
}

/// Parses a built-in model's JSON text.
pub(crate) fn built_in(
    pipeline: &str,
    text: &str,
    source: ModelSource,
) -> Result<(ModelFile, ModelSource), Error> {
    let label = format!("<{source} of {pipeline}>");
    let model = ModelFile::from_json(text, Path::new(&label), pipeline)?;
    Ok((model, source))
}
