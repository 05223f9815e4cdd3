//! Following one fruit from frame to frame: seed 004's approach tracker (§3.3) behind the facade,
//! for the arm's camera while it closes in on the fruit it chose.
//!
//! Two types, as [`crate::Detector`] and its detections: a [`Tracker`] is loaded once — the
//! `color-contour` model (built-in or a file from `pomona train`) supplies the compiled colour
//! table and, for the local contour re-detection, the detector's stage parameters; the tracker's
//! own settings are [`TrackParams`], overridable by dotted key as `pomona track --set` does —
//! and [`Tracker::start`] gives a [`Track`] per fruit, which [`Track::update`] moves through the
//! frames. Loading compiles the table (70 ms on one core for the built-in model, whose network
//! has the intensity input; docs/results.md, "Colour with intensity"); starting a track copies
//! it, so many tracks of one model compile it once.
//!
//! ```
//! # fn main() -> Result<(), pomona::Error> {
//! use pomona::{nalgebra::Point2, ColorImage, ImageCircle, TrackStatus};
//!
//! let tracker = pomona::Tracker::builder().set("max_radius_change", 1.2).build()?;
//! let start = ImageCircle { center_px: Point2::new(32.0, 24.0), radius_px: 10.0 };
//! let mut track = tracker.start(start)?;
//! // A grey frame holds no fruit colour: the track is lost and keeps its last circle.
//! let estimate = track.update(&ColorImage::filled(64, 48, [90, 90, 90]));
//! assert_eq!(estimate.status, TrackStatus::Lost);
//! assert_eq!(track.circle(), start);
//! # Ok(())
//! # }
//! ```

use std::path::PathBuf;

use pomona_colorcontour::{
    ApproachTracker, ColorContourParams, ColorContourStageParams, HSigmaLut, TrackEstimate,
    TrackParams, PIPELINE_NAME,
};
use pomona_core::{ColorImage, ImageCircle};
use pomona_learn::ModelFile;
use pomona_pipeline::PipelineError;

use crate::model_choice::ModelChoice;
use crate::{apply_overrides, registry, Error, ModelInfo, ModelSource, ParamOverride};

/// A loaded approach tracker: a `color-contour` model's colour table and stages, and the
/// tracker's parameters. [`Tracker::start`] follows a fruit.
#[derive(Clone)]
pub struct Tracker {
    table: (HSigmaLut, u8),
    stage: ColorContourParams,
    params: TrackParams,
    model: ModelInfo,
}

impl std::fmt::Debug for Tracker {
    // Not the colour table: megabytes of cells.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tracker")
            .field("model", &self.model)
            .field("params", &self.params)
            .finish_non_exhaustive()
    }
}

impl Tracker {
    /// A builder: the built-in `color-contour` model and the default parameters until told
    /// otherwise.
    pub fn builder() -> TrackerBuilder {
        TrackerBuilder::default()
    }

    /// The tracker's parameters (defaults with the overrides applied).
    pub fn params(&self) -> &TrackParams {
        &self.params
    }

    /// The model whose colour table and stages the tracker uses.
    pub fn model(&self) -> &ModelInfo {
        &self.model
    }

    /// A track of the fruit whose circle in the first frame is `start` (a detection of it, or a
    /// circle a person or a planner gave). Pass that first frame to [`Track::update`] too.
    ///
    /// # Errors
    /// [`Error::Track`] when the circle is not finite with a positive radius.
    pub fn start(&self, start: ImageCircle) -> Result<Track, Error> {
        let (lut, threshold) = self.table.clone();
        let inner = ApproachTracker::from_table(
            lut,
            threshold,
            &self.stage,
            self.params,
            start.center_px,
            start.radius_px,
        )
        .map_err(|e| self.error(e))?;
        Ok(Track { inner })
    }

    fn error(&self, source: PipelineError) -> Error {
        Error::Track {
            model: self.model.source.to_string(),
            source: Box::new(source),
        }
    }
}

/// One fruit being followed (see the module docs).
#[derive(Clone)]
pub struct Track {
    inner: ApproachTracker,
}

impl std::fmt::Debug for Track {
    // Not the tracker's colour table: megabytes of cells.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Track")
            .field("circle", &self.circle())
            .finish_non_exhaustive()
    }
}

impl Track {
    /// Follows the fruit into `color`, the next frame (the first frame included), and returns
    /// the estimate: centre, radius, how it was found, and the 5×5 checks it took. A frame where
    /// the fruit is not found is [`pomona_colorcontour::TrackStatus::Lost`] and repeats the last
    /// circle; the next frames search again.
    pub fn update(&mut self, color: &ColorImage) -> TrackEstimate {
        self.inner.update(color)
    }

    /// The current circle (the start circle before the first update).
    pub fn circle(&self) -> ImageCircle {
        let (center_px, radius_px) = self.inner.circle();
        ImageCircle {
            center_px,
            radius_px,
        }
    }
}

/// Chooses a [`Tracker`]'s model and parameters; [`TrackerBuilder::build`] loads it.
#[derive(Debug, Default)]
pub struct TrackerBuilder {
    model: ModelChoice,
    params: Option<TrackParams>,
    overrides: Vec<ParamOverride>,
}

impl TrackerBuilder {
    /// Use the `color-contour` model file at `path` instead of the built-in model.
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

    /// Start from `params` instead of [`TrackParams::default`] (overrides still apply after).
    #[must_use]
    pub fn params(mut self, params: TrackParams) -> Self {
        self.params = Some(params);
        self
    }

    /// Override the tracker parameter at dotted `key` (as `pomona track --set`, e.g.
    /// `"edge_scan.gap_px"`; it must exist, with the same JSON type).
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

    /// Loads the model, compiles its colour table and checks the parameters.
    ///
    /// # Errors
    /// [`Error::ModelFile`] (unreadable, or not a `color-contour` model),
    /// [`Error::UnknownParameter`] / [`Error::ParameterType`] for a bad override, [`Error::Load`]
    /// for a model whose parameters or colour network are unusable, [`Error::Track`] for
    /// tracker parameters the tracker refuses.
    pub fn build(self) -> Result<Tracker, Error> {
        let (model, source) = self
            .model
            .load(registry::pipeline(PIPELINE_NAME)?.as_ref())?;
        let load_error = |e: PipelineError| Error::Load {
            pipeline: PIPELINE_NAME.to_owned(),
            model: source.to_string(),
            source: Box::new(e),
        };
        let stage = ColorContourStageParams::from_model(&model).map_err(load_error)?;
        let table = stage.color_table().map_err(load_error)?;
        let model = ModelInfo::of(&model, source);
        let track_error = |reason: String| Error::Track {
            model: model.source.to_string(),
            source: Box::new(PipelineError::InvalidParameter {
                name: "tracker".into(),
                reason,
            }),
        };
        let mut json = serde_json::to_value(self.params.unwrap_or_default())
            .map_err(|e| track_error(e.to_string()))?;
        apply_overrides(&mut json, &self.overrides, "the tracker")?;
        let params: TrackParams =
            serde_json::from_value(json).map_err(|e| track_error(e.to_string()))?;
        if let Some(reason) = params.invalid_reason() {
            return Err(track_error(reason.to_owned()));
        }
        Ok(Tracker {
            table,
            stage: stage.params,
            params,
            model,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::nalgebra::Point2;

    fn circle(x: f64, y: f64, r: f64) -> ImageCircle {
        ImageCircle {
            center_px: Point2::new(x, y),
            radius_px: r,
        }
    }

    /// An orange disc on green: the track follows it as it moves and grows.
    #[test]
    fn a_moving_orange_disc_is_followed() -> Result<(), Error> {
        let tracker = Tracker::builder().build()?;
        assert_eq!(tracker.model().source, ModelSource::BuiltIn);
        let frame = |cx: f64, cy: f64, r: f64| {
            let (w, h) = (160u32, 120u32);
            let mut rgb = Vec::with_capacity((3 * w * h) as usize);
            for y in 0..h {
                for x in 0..w {
                    let inside = (f64::from(x) - cx).hypot(f64::from(y) - cy) <= r;
                    rgb.extend_from_slice(if inside {
                        &[235, 120, 20]
                    } else {
                        &[40, 110, 35]
                    });
                }
            }
            ColorImage::from_rgb(w, h, rgb)
        };
        let mut track = tracker.start(circle(60.0, 60.0, 15.0))?;
        for k in 0..8 {
            let (cx, r) = (60.0 + 4.0 * f64::from(k), 15.0 + 0.5 * f64::from(k));
            let estimate = track.update(&frame(cx, 60.0, r)?);
            let error = (estimate.center_px - Point2::new(cx, 60.0)).norm();
            assert!(error < 1.5, "frame {k}: {error} px off ({estimate:?})");
            assert!(
                (estimate.radius_px - r).abs() < 1.5,
                "frame {k}: {estimate:?}"
            );
        }
        Ok(())
    }

    #[test]
    fn bad_parameters_and_start_circles_are_named() -> Result<(), Error> {
        let unknown = Tracker::builder().set("max_radius_chnage", 1.2).build();
        assert!(
            matches!(&unknown, Err(Error::UnknownParameter { key, .. }) if key.ends_with("chnage")),
            "{unknown:?}"
        );
        let invalid = Tracker::builder()
            .set("scan_threshold_fraction", 0.0)
            .build();
        assert!(matches!(&invalid, Err(Error::Track { .. })), "{invalid:?}");
        let enum_value = Tracker::builder().set("redetect", "sometimes").build();
        assert!(
            enum_value
                .as_ref()
                .is_err_and(|e| e.to_string().contains("sometimes")),
            "{enum_value:?}"
        );
        let missing = Tracker::builder().model_file("no/such/model.json").build();
        assert!(
            missing
                .as_ref()
                .is_err_and(|e| e.to_string().contains("no/such/model.json")),
            "{missing:?}"
        );
        let tracker = Tracker::builder().build()?;
        let shown = format!("{tracker:?}");
        assert!(
            shown.contains("BuiltIn") && shown.len() < 4000,
            "{} bytes",
            shown.len()
        );
        let bad = tracker.start(circle(f64::NAN, 10.0, 5.0));
        assert!(matches!(bad, Err(Error::Track { .. })), "{bad:?}");
        assert!(tracker.start(circle(10.0, 10.0, 0.0)).is_err());
        Ok(())
    }
}
