//! The detection pipelines this build ships, by name.
//!
//! Everything that picks a method by name (the facade's [`crate::Detector::builtin`], the CLI's
//! `--pipeline`) looks it up here and knows nothing else about it. To add a detector, depend on
//! its crate and add one line to [`pipelines`].

use pomona_pipeline::Pipeline;

use crate::Error;

/// Every registered pipeline, in the order `pomona demo` runs them.
///
/// ```
/// let names: Vec<&str> = pomona::pipelines().iter().map(|p| p.name()).collect();
/// assert_eq!(names, ["shape-fit", "symmetry", "viewer-pose", "color-contour"]);
/// ```
pub fn pipelines() -> Vec<Box<dyn Pipeline>> {
    vec![
        Box::new(pomona_shapefit::ShapeFitPipeline::default()),
        Box::new(pomona_symmetry::SymmetryPipeline::default()),
        Box::new(pomona_symmetry::ViewerPosePipeline::default()),
        Box::new(pomona_colorcontour::ColorContourPipeline::default()),
    ]
}

/// The names of `pipelines`, comma-separated (for messages).
///
/// ```
/// assert_eq!(
///     pomona::pipeline_names(&pomona::pipelines()),
///     "shape-fit, symmetry, viewer-pose, color-contour"
/// );
/// ```
pub fn pipeline_names(pipelines: &[Box<dyn Pipeline>]) -> String {
    if pipelines.is_empty() {
        return "none are registered yet".to_owned();
    }
    pipelines
        .iter()
        .map(|p| p.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Finds the pipeline called `name` in `pipelines` (a list of your own, or [`pipelines`]).
///
/// ```
/// let all = pomona::pipelines();
/// assert!(pomona::find_pipeline(&all, "symmetry")?.needs_color() == false);
/// assert!(pomona::find_pipeline(&all, "symetry").is_err());
/// # Ok::<(), pomona::Error>(())
/// ```
///
/// # Errors
/// [`Error::UnknownPipeline`], listing the known names.
pub fn find_pipeline<'a>(
    pipelines: &'a [Box<dyn Pipeline>],
    name: &str,
) -> Result<&'a dyn Pipeline, Error> {
    match pipelines.iter().find(|p| p.name() == name) {
        Some(p) => Ok(p.as_ref()),
        None => Err(Error::UnknownPipeline {
            name: name.to_owned(),
            known: pipeline_names(pipelines),
        }),
    }
}

/// The registered pipeline called `name` (to train with, for example; to detect, use
/// [`crate::Detector::builtin`]).
///
/// ```
/// let shape_fit = pomona::pipeline("shape-fit")?;
/// assert!(shape_fit.default_model().is_some());
/// # Ok::<(), pomona::Error>(())
/// ```
///
/// # Errors
/// [`Error::UnknownPipeline`], listing the registered names.
pub fn pipeline(name: &str) -> Result<Box<dyn Pipeline>, Error> {
    let mut all = pipelines();
    match all.iter().position(|p| p.name() == name) {
        Some(i) => Ok(all.swap_remove(i)),
        None => Err(Error::UnknownPipeline {
            name: name.to_owned(),
            known: pipeline_names(&all),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_names_list_the_known_ones() {
        let err = pipeline("no-such-detector").err().map(|e| e.to_string());
        let err = err.unwrap_or_default();
        assert!(err.contains("no-such-detector"), "{err}");
        assert!(err.contains("known pipelines"), "{err}");
        for p in pipelines() {
            assert!(err.contains(p.name()), "{err}");
            assert_eq!(pipeline(p.name()).map(|q| q.name()).ok(), Some(p.name()));
        }
    }

    /// Retraining a built-in model writes a calibration by the score alone; the shipped
    /// 3D detectors' models (colour and depth-only) rate detections by their cues as well, fitted
    /// by `scripts/calibrate_builtin.sh` — which a retrain must be followed by. `color-contour`
    /// keeps its sigmoid (docs/results.md, "The depth-only model's confidence").
    #[test]
    fn built_in_3d_models_carry_a_cue_calibration() -> Result<(), Error> {
        use crate::model_choice::built_in;
        use crate::ModelSource;
        for p in pipelines() {
            let models = [
                p.default_model().map(|m| (m, ModelSource::BuiltIn)),
                p.default_depth_only_model()
                    .map(|m| (m, ModelSource::BuiltInDepthOnly)),
            ];
            for (text, source) in models.into_iter().flatten() {
                let (model, source) = built_in(p.name(), text, source)?;
                let calibration = model.calibration.as_ref();
                assert!(
                    calibration.is_some(),
                    "{source} of {} is uncalibrated",
                    p.name()
                );
                assert_eq!(
                    calibration.is_some_and(|c| c.cues.is_some()),
                    p.name() != "color-contour",
                    "{source} of {}: run scripts/calibrate_builtin.sh after retraining",
                    p.name()
                );
            }
        }
        Ok(())
    }
}
