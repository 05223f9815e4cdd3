//! What a detection file records for one frame (`<out>/<frame>.json`, docs/formats.md), and the
//! confidence threshold it is written at: the one rule `pomona detect`, the Python package and
//! its Dask runner share, so each writes byte-identical files for the same frame and model.
//!
//! The threshold is the one asked for, else the model's operating confidence, else none (every
//! detection is kept, as for models trained before calibration); asking for one of a model
//! without calibration is an error, since its detections carry no confidence to compare.

use pomona_core::{Detection, FrameDetections};

use crate::{Detector, Error};

impl Detector {
    /// The confidence threshold detection files are written at: `requested` when given
    /// (`Some(0.0)` keeps everything), else the model's operating confidence, else `None`
    /// (keep every detection).
    ///
    /// ```
    /// # fn main() -> Result<(), pomona::Error> {
    /// let detector = pomona::Detector::builtin("shape-fit")?;
    /// assert_eq!(detector.min_confidence_for(None)?, detector.operating_confidence());
    /// assert_eq!(detector.min_confidence_for(Some(0.0))?, Some(0.0));
    /// assert!(detector.min_confidence_for(Some(1.5)).is_err());
    /// # Ok(())
    /// # }
    /// ```
    ///
    /// # Errors
    /// [`Error::MinConfidence`] for a value outside `[0, 1]` or a model without calibration.
    pub fn min_confidence_for(&self, requested: Option<f64>) -> Result<Option<f64>, Error> {
        match (requested, self.operating_confidence()) {
            (Some(c), _) if !(0.0..=1.0).contains(&c) => Err(Error::MinConfidence {
                value: c,
                reason: "it must be in [0, 1]".into(),
            }),
            (Some(c), None) => Err(Error::MinConfidence {
                value: c,
                reason: format!(
                    "the model of `{}` has no confidence calibration (retrain it with \
                     `pomona train`, which calibrates by default)",
                    self.pipeline()
                ),
            }),
            (Some(c), Some(_)) => Ok(Some(c)),
            (None, operating) => Ok(operating),
        }
    }

    /// The detection file of frame `stem`: `detections` (found in a frame with or without
    /// colour, `has_color`) kept at `min_confidence` (from [`Detector::min_confidence_for`]),
    /// with the pipeline, the model's identity and its operating confidence.
    pub fn frame_record(
        &self,
        stem: &str,
        has_color: bool,
        detections: &[Detection],
        min_confidence: Option<f64>,
    ) -> FrameDetections {
        let model = self.model_for_color(has_color);
        FrameDetections {
            frame: stem.to_owned(),
            pipeline: self.pipeline().to_owned(),
            detections: detections
                .iter()
                .filter(|d| min_confidence.is_none_or(|c| d.confidence_at_least(c)))
                .cloned()
                .collect(),
            operating_confidence: model.operating_confidence,
            min_confidence,
            model_id: Some(model.id.clone()),
            stamp_ns: None,
            frame_id: None,
        }
    }
}
