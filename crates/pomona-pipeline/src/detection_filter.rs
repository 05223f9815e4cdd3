//! A geometric check of a detected fruit against the depth image, run as a stage over a
//! detector's output: [`DetectionFilter`] keeps the detections its [`FruitCheck`] admits.
//!
//! The checks ([`crate::FreeSpaceCheck`], [`crate::DoubleCurvatureCheck`]) judge a fruit of a
//! given centre and radius; what every detector needs around them — the radius from the
//! detection's diameter, a fallback for detections without one, the check switched off — is
//! the same for each, so it lives here once.

use pomona_core::nalgebra::Point3;
use pomona_core::{Detection, RgbdFrame};

use crate::{PipelineError, Stage};

/// A test a fruit of `radius_m` centred at `center_m` (camera frame) passes or fails on the
/// depth image of `frame`.
pub trait FruitCheck: Send + Sync {
    /// The stage name of the check's [`DetectionFilter`].
    const STAGE: &'static str;

    /// Whether the fruit passes (a check that is switched off admits everything).
    fn admits(&self, frame: &RgbdFrame, center_m: &Point3<f64>, radius_m: f64) -> bool;
}

/// The check `C` as a stage over a detector's output: the detections it refuses are dropped. A
/// detection without a diameter is measured as a fruit of `fallback_radius_m`, or passes
/// unjudged when that is `None`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectionFilter<C> {
    /// The check and its limits.
    pub check: C,
    /// Radius of a detection that carries no diameter, metres (`None`: such detections pass).
    pub fallback_radius_m: Option<f64>,
}

impl<'a, C: FruitCheck> Stage<(&'a RgbdFrame, Vec<Detection>), Vec<Detection>>
    for DetectionFilter<C>
{
    fn name(&self) -> &'static str {
        C::STAGE
    }

    fn run(
        &self,
        (frame, mut detections): (&'a RgbdFrame, Vec<Detection>),
    ) -> Result<Vec<Detection>, PipelineError> {
        detections.retain(|d| {
            d.diameter_m
                .map(|m| 0.5 * m)
                .or(self.fallback_radius_m)
                .is_none_or(|radius_m| self.check.admits(frame, &d.center_m, radius_m))
        });
        Ok(detections)
    }
}
