//! Fruit in 3D from the two colour shots of seed 004's rotating camera (§4.1–4.2), without any
//! depth image: what `pomona stereo` runs on each frame, for a robot program.
//!
//! Per pair of shots ([`StereoLocator::locate`]): a `color-contour` [`Detector`] (built with
//! [`StereoLocator::detector_overrides`]) finds circles in both colour images (kept by the
//! [`KeepRule`]); the circles are matched by the seed's
//! relaxation within the Eq. 10 windows of the rig and the working volume, with the evidence
//! [`PairEvidence`] adds and, after it, the pass over the circles it leaves unpaired
//! ([`LeftoverPairing`]); each pair's stereo-view centre is refined by appearance
//! ([`DisparityRefinement`]) and the pair located by Eq. 18 or triangulation
//! ([`StereoMethod`]); a located fruit whose circle, at the located depth, is not a fruit's
//! size is dropped (seed 004 §3.2's size test, on the stereo depth:
//! [`StereoSettings::fruit_radius_m`]). Every step beyond the seed is a setting of
//! [`StereoSettings`], whose default is what `pomona stereo` runs (docs/results.md measures
//! each).
//!
//! Kept apart from [`Detector`] because it needs a rig and two images, and returns what the
//! matching did as well as the located fruit (a stereo report scores both).

use pomona_arm::{
    ArmError, BetterElsewhere, DisparityMatrix, DisparityRefinement, EvidenceOutcome,
    LeftoverPairing, MatchingWindows, PairEvidence, PairScore, RefinementOutcome, RelaxationParams,
    RotatedStereo,
};
use pomona_core::nalgebra::{Point2, Point3};
use pomona_core::{ColorImage, DepthImage, Detection, ImageCircle, RgbdFrame};
use serde::Serialize;

use crate::{Detector, Error, KeepRule, ParamOverride};

/// How a matched pair becomes a 3D point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StereoMethod {
    /// The seed's rotated-camera depth, Eq. 18.
    Paper,
    /// Calibrated triangulation (midpoint of the two rays).
    Triangulate,
}

impl std::str::FromStr for StereoMethod {
    type Err = String;

    /// `paper` or `triangulate` (the names `pomona stereo --method` and the Python package take).
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "paper" => Ok(Self::Paper),
            "triangulate" => Ok(Self::Triangulate),
            _ => Err(format!("need `paper` or `triangulate`, got `{s}`")),
        }
    }
}

impl StereoMethod {
    /// Locates the fruit seen at `primary` and `stereo` with this method.
    ///
    /// # Errors
    /// When the pixels do not locate a point in front of both views.
    pub fn locate(
        self,
        rig: &RotatedStereo,
        primary: &Point2<f64>,
        stereo: &Point2<f64>,
    ) -> Result<Point3<f64>, ArmError> {
        match self {
            Self::Paper => rig.locate_paper(primary, stereo),
            Self::Triangulate => rig.triangulate(primary, stereo),
        }
    }
}

/// How [`StereoLocator`] matches and locates. The default is what `pomona stereo` runs: Eq. 18,
/// the better-elsewhere check and the leftover pass on, the refinement on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StereoSettings {
    /// How a pair becomes a 3D point.
    pub method: StereoMethod,
    /// The working volume, distances from the hub in metres, `(near, far)`, from which the
    /// Eq. 10 windows and the appearance sweeps' ranges are derived; `None`: pivot + 0.2 m to
    /// pivot + 2.0 m.
    pub reach_m: Option<(f64, f64)>,
    /// Pixels added to every Eq. 10 window (detector centre error, lens effects).
    pub margin_px: f64,
    /// Evidence beyond disparity in the relaxation (its better-elsewhere sweep range is set from
    /// `reach_m`). [`PairEvidence::default`] is the seed's relaxation.
    pub evidence: PairEvidence,
    /// The pass over the circles the relaxation leaves unpaired (its sweep range is set from
    /// `reach_m`); `None`: none, as in the seed.
    pub leftovers: Option<LeftoverPairing>,
    /// Sub-pixel refinement of each pair's stereo-view centre; `None`: the circle centres, as
    /// in the seed.
    pub refinement: Option<DisparityRefinement>,
    /// The size test at the located depth, `(smallest, largest)` fruit radius in metres: a
    /// located pair whose primary circle's radius at its located depth falls outside is not a
    /// fruit where it was located — a wrong pair, or a right one whose disparity is wrong —
    /// and goes to [`StereoFrame::rejected_by_size`]. Seed 004 prunes circles outside 25–55 mm
    /// at the measured depth; the default is the `color-contour` detector's accepted range
    /// (that range widened by its radius tolerance, as with depth). `None`: no test.
    pub fruit_radius_m: Option<(f64, f64)>,
}

impl StereoSettings {
    /// The working volume's hub distances for `rig`: `reach_m`, or pivot + 0.2 m to
    /// pivot + 2.0 m.
    pub fn reach_for(reach_m: Option<(f64, f64)>, rig: &RotatedStereo) -> (f64, f64) {
        let d = rig.pivot_distance_m;
        reach_m.unwrap_or((d + 0.2, d + 2.0))
    }

    /// The distances from the primary lens the appearance sweeps cover for that reach: the hub
    /// lies `d` behind the lens on its axis, so each hub distance less `d` (the nearest at least
    /// 5 cm).
    pub fn sweep_range_m(reach_m: Option<(f64, f64)>, rig: &RotatedStereo) -> (f64, f64) {
        let (near, far) = Self::reach_for(reach_m, rig);
        let d = rig.pivot_distance_m;
        ((near - d).max(0.05), far - d)
    }
}

impl Default for StereoSettings {
    fn default() -> Self {
        // The sweep ranges are placeholders: StereoLocator::new sets them from the reach.
        let range = (0.1, 2.0);
        Self {
            method: StereoMethod::Paper,
            reach_m: None,
            margin_px: 4.0,
            evidence: PairEvidence {
                better_elsewhere: Some(BetterElsewhere {
                    margin: 0.5,
                    min_distance_radii: 1.0,
                    distance_range_m: range,
                }),
                ..PairEvidence::default()
            },
            leftovers: Some(LeftoverPairing::new(range)),
            refinement: Some(DisparityRefinement::default()),
            fruit_radius_m: Some(
                pomona_colorcontour::ColorContourParams::default().accepted_radius_range_m(),
            ),
        }
    }
}

/// A matched pair and where it was located.
#[derive(Debug, Clone, PartialEq)]
pub struct LocatedPair {
    /// Index into [`StereoFrame::primary`].
    pub primary: usize,
    /// Index into [`StereoFrame::stereo`].
    pub stereo: usize,
    /// Primary circle centre, pixels.
    pub primary_px: Point2<f64>,
    /// Stereo circle centre, pixels (the fruit's identity in the stereo view).
    pub stereo_circle_px: Point2<f64>,
    /// The stereo pixel the fruit was located with (refined or the circle centre).
    pub stereo_px: Point2<f64>,
    /// The refinement's outcome (`None` without refinement).
    pub refinement: Option<RefinementOutcome>,
    /// The located centre, primary camera frame, metres.
    pub center_m: Point3<f64>,
    /// The matching evidence's score of the pair (`None` when the evidence is off or the pass
    /// over the leftovers made the pair).
    pub evidence: Option<PairScore>,
    /// Whether the pass over the leftover circles made the pair (not the relaxation).
    pub from_leftovers: bool,
}

/// What [`StereoLocator::locate`] found in one pair of shots.
#[derive(Debug, Clone)]
pub struct StereoFrame {
    /// One located detection per pair, primary camera frame: the primary detection with the
    /// located centre, the diameter of its circle at that depth, the mean score of the two and
    /// the lower confidence.
    pub detections: Vec<Detection>,
    /// The primary view's kept detections that have a circle (the pairs index them).
    pub primary: Vec<Detection>,
    /// The stereo view's, likewise.
    pub stereo: Vec<Detection>,
    /// The located pairs, in the order of `detections`.
    pub pairs: Vec<LocatedPair>,
    /// Pairs matched and located, then dropped by the size test
    /// ([`StereoSettings::fruit_radius_m`]).
    pub rejected_by_size: Vec<LocatedPair>,
    /// What the matching evidence did (all zero when off).
    pub evidence: EvidenceOutcome,
}

/// Locates fruit from the two shots of one rig (see the module docs).
#[derive(Debug)]
pub struct StereoLocator {
    detector: Detector,
    keep: KeepRule,
    rig: RotatedStereo,
    windows: MatchingWindows,
    settings: StereoSettings,
}

impl StereoLocator {
    /// A locator for `rig` that detects with `detector` (a `color-contour` detector: its
    /// detections need image circles), keeping what `keep` keeps.
    ///
    /// # Errors
    /// [`Error::StereoDetector`] for a detector of another pipeline; [`Error::Stereo`] for a
    /// reach or margin the rig cannot use, or settings out of range.
    pub fn new(
        detector: Detector,
        keep: KeepRule,
        rig: RotatedStereo,
        mut settings: StereoSettings,
    ) -> Result<Self, Error> {
        if detector.pipeline() != pomona_colorcontour::PIPELINE_NAME {
            return Err(Error::StereoDetector {
                pipeline: detector.pipeline(),
            });
        }
        let (near, far) = StereoSettings::reach_for(settings.reach_m, &rig);
        let windows = MatchingWindows::for_rig(&rig, near, far, settings.margin_px)?;
        let range = StereoSettings::sweep_range_m(settings.reach_m, &rig);
        if let Some(check) = settings.evidence.better_elsewhere.as_mut() {
            check.distance_range_m = range;
        }
        if let Some(pass) = settings.leftovers.as_mut() {
            pass.distance_range_m = range;
            pass.validate()?;
        }
        settings.evidence.validate()?;
        if let Some((lo, hi)) = settings.fruit_radius_m {
            if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo < hi) {
                return Err(ArmError::InvalidParameter {
                    name: "fruit_radius_m",
                    value: lo,
                    reason: "needs finite 0 < smallest < largest",
                }
                .into());
            }
        }
        if let Some(refinement) = &settings.refinement {
            refinement.validate()?;
        }
        Ok(Self {
            detector,
            keep,
            rig,
            windows,
            settings,
        })
    }

    /// The overrides a stereo locator's detector is built with: the color-contour detector's
    /// extra circle sources (ray and Hough circles) off — they centre pieces of a fruit, and
    /// differently in the two views (docs/results.md, "Hough circles from the outline") — then
    /// `user`'s, which can turn them on again.
    pub fn detector_overrides(user: impl IntoIterator<Item = ParamOverride>) -> Vec<ParamOverride> {
        pomona_colorcontour::EXTRA_CIRCLE_SOURCE_KEYS
            .into_iter()
            .map(|key| ParamOverride::new(key, serde_json::Value::Null))
            .chain(user)
            .collect()
    }

    /// The detector both views go through.
    pub fn detector(&self) -> &Detector {
        &self.detector
    }

    /// The rig.
    pub fn rig(&self) -> &RotatedStereo {
        &self.rig
    }

    /// The Eq. 10 windows derived from the rig and the reach.
    pub fn windows(&self) -> &MatchingWindows {
        &self.windows
    }

    /// The settings, sweep ranges filled in.
    pub fn settings(&self) -> &StereoSettings {
        &self.settings
    }

    /// Detects, matches and locates the fruit of one pair of shots (`primary`, `stereo`; the
    /// rig camera's size). Depth is never read: the detector sees exactly what a colour camera
    /// gives.
    ///
    /// # Errors
    /// [`Error::Frame`] for an image of another size than the rig camera's, [`Error::Detect`]
    /// when detection fails, [`Error::Stereo`] when matching or refinement refuses the images.
    pub fn locate(&self, primary: &ColorImage, stereo: &ColorImage) -> Result<StereoFrame, Error> {
        let detect = |color: &ColorImage| -> Result<Vec<Detection>, Error> {
            let camera = self.rig.camera;
            let frame = RgbdFrame::new(
                camera,
                DepthImage::empty(camera.width, camera.height),
                Some(color.clone()),
            )?;
            Ok(self
                .detector
                .detect(&frame)?
                .into_iter()
                .filter(|d| self.keep.keeps(d) && d.center_px.is_some() && d.radius_px.is_some())
                .collect())
        };
        let (found_primary, found_stereo) = (detect(primary)?, detect(stereo)?);
        let (pc, sc) = (circles(&found_primary), circles(&found_stereo));
        let centres = |c: &[ImageCircle]| c.iter().map(|c| c.center_px).collect::<Vec<_>>();
        let images = (primary, stereo);
        let mut matrix = DisparityMatrix::from_centres(&centres(&pc), &centres(&sc), &self.windows);
        let evidence = self
            .settings
            .evidence
            .apply(&mut matrix, &self.rig, images, (&pc, &sc))?;
        let relaxed = matrix.relax(&RelaxationParams::default()).pairs;
        let leftovers = match &self.settings.leftovers {
            Some(pass) => pass.pair(&self.rig, images, (&pc, &sc), &self.windows, &relaxed)?,
            None => Vec::new(),
        };
        let mut matched = relaxed;
        matched.extend(leftovers.iter().copied());
        matched.sort_by_key(|p| p.primary);
        let mut detections = Vec::new();
        let mut pairs = Vec::new();
        let mut rejected_by_size = Vec::new();
        for pair in &matched {
            let (p, s) = (&pc[pair.primary], &sc[pair.stereo]);
            let refinement = match &self.settings.refinement {
                Some(r) => {
                    Some(r.refine(&self.rig, images, &p.center_px, p.radius_px, &s.center_px)?)
                }
                None => None,
            };
            let stereo_px = refinement.map_or(s.center_px, |r| r.stereo_center_px(&s.center_px));
            let Ok(center_m) = self
                .settings
                .method
                .locate(&self.rig, &p.center_px, &stereo_px)
            else {
                continue;
            };
            let located_pair = LocatedPair {
                primary: pair.primary,
                stereo: pair.stereo,
                primary_px: p.center_px,
                stereo_circle_px: s.center_px,
                stereo_px,
                refinement,
                center_m,
                evidence: evidence.score(pair.primary, pair.stereo),
                from_leftovers: leftovers.contains(pair),
            };
            let radius_m = radius_at(&self.rig, &center_m, p.radius_px);
            if let Some((lo, hi)) = self.settings.fruit_radius_m {
                if !(lo..=hi).contains(&radius_m) {
                    rejected_by_size.push(located_pair);
                    continue;
                }
            }
            detections.push(located(
                center_m,
                &found_primary[pair.primary],
                &found_stereo[pair.stereo],
                radius_m,
            ));
            pairs.push(located_pair);
        }
        Ok(StereoFrame {
            detections,
            primary: found_primary,
            stereo: found_stereo,
            pairs,
            rejected_by_size,
            evidence,
        })
    }
}

/// The image circles of `detections` (every one has a centre and radius: see `locate`).
fn circles(detections: &[Detection]) -> Vec<ImageCircle> {
    detections
        .iter()
        .filter_map(|d| {
            Some(ImageCircle {
                center_px: d.center_px?,
                radius_px: d.radius_px?,
            })
        })
        .collect()
}

/// The radius in metres of a circle of `radius_px` at the depth of `center_m` (primary camera).
fn radius_at(rig: &RotatedStereo, center_m: &Point3<f64>, radius_px: f64) -> f64 {
    center_m.z * radius_px / rig.camera.mean_focal_px()
}

/// The located detection of a matched pair: the primary detection with the centre located, the
/// diameter of its circle at that depth (`radius_m`, [`radius_at`]), the mean score and the
/// lower confidence.
fn located(
    center_m: Point3<f64>,
    primary: &Detection,
    stereo: &Detection,
    radius_m: f64,
) -> Detection {
    Detection {
        center_m,
        diameter_m: Some(2.0 * radius_m),
        score: 0.5 * (primary.score + stereo.score),
        confidence: primary
            .confidence
            .zip(stereo.confidence)
            .map(|(a, b)| a.min(b)),
        ..primary.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::PinholeCamera;

    const LEAF: [u8; 3] = [40, 80, 30];
    const ORANGE: [u8; 3] = [235, 120, 15];
    const RADIUS_M: f64 = 0.04;

    fn rig() -> RotatedStereo {
        let camera = PinholeCamera::new(320, 240, 300.0, 300.0, 159.5, 119.5).unwrap();
        RotatedStereo::new(6f64.to_radians(), 0.3, camera).unwrap()
    }

    /// Three fruit in the primary camera frame.
    fn fruit() -> [Point3<f64>; 3] {
        [
            Point3::new(-0.15, -0.05, 0.9),
            Point3::new(0.05, 0.06, 1.0),
            Point3::new(0.2, -0.08, 1.1),
        ]
    }

    /// The primary and stereo shots of [`fruit`]: each sphere's image an orange disc of radius
    /// f·R/z on leaves; `shaded`, darker towards the rim (lit from the camera), so that the
    /// refinement has an appearance to match (a flat disc gives it none and it falls back).
    fn shots(rig: &RotatedStereo, shaded: bool) -> (ColorImage, ColorImage) {
        let camera = &rig.camera;
        let draw = |centres: &[Point3<f64>]| {
            let mut image = ColorImage::filled(camera.width, camera.height, LEAF);
            for c in centres {
                let px = camera.project(c).unwrap();
                let r = camera.fx * RADIUS_M / c.z;
                for v in 0..camera.height {
                    for u in 0..camera.width {
                        let rho = (f64::from(u) - px.x).hypot(f64::from(v) - px.y) / r;
                        if rho <= 1.0 {
                            let light = if shaded {
                                0.4 + 0.6 * (1.0 - rho * rho).max(0.0).sqrt()
                            } else {
                                1.0
                            };
                            image.set(u, v, ORANGE.map(|c| (f64::from(c) * light) as u8));
                        }
                    }
                }
            }
            image
        };
        let there: Vec<Point3<f64>> = fruit()
            .iter()
            .map(|p| rig.stereo_from_camera() * p)
            .collect();
        (draw(&fruit()), draw(&there))
    }

    /// Distance from `truth` to the nearest located fruit, metres.
    fn miss_m(found: &StereoFrame, truth: &Point3<f64>) -> f64 {
        found
            .detections
            .iter()
            .map(|d| (d.center_m - truth).norm())
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn the_refinement_moves_the_stereo_centres_of_shaded_fruit_and_none_keeps_the_circles() {
        let rig = rig();
        let (a, b) = shots(&rig, true);
        let locate = |refinement: Option<DisparityRefinement>| {
            let settings = StereoSettings {
                method: StereoMethod::Triangulate,
                refinement,
                ..StereoSettings::default()
            };
            let detector = Detector::builtin("color-contour").unwrap();
            let locator = StereoLocator::new(detector, KeepRule::All, rig, settings).unwrap();
            locator.locate(&a, &b).unwrap()
        };
        let refined = locate(Some(DisparityRefinement::default()));
        let circles = locate(None);
        assert_eq!(refined.pairs.len(), 3, "{:?}", refined.pairs);
        assert_eq!(circles.pairs.len(), 3, "{:?}", circles.pairs);
        for pair in &circles.pairs {
            assert!(pair.refinement.is_none());
            assert_eq!(pair.stereo_px, pair.stereo_circle_px);
        }
        let moved = refined
            .pairs
            .iter()
            .filter(|p| matches!(p.refinement, Some(RefinementOutcome::Refined { .. })))
            .filter(|p| p.stereo_px != p.stereo_circle_px)
            .count();
        assert!(moved > 0, "{:?}", refined.pairs);
        for truth in &fruit() {
            let nearest = miss_m(&refined, truth);
            assert!(nearest < 0.03, "{truth} missed by {nearest} m");
        }
    }

    #[test]
    fn two_shots_locate_each_fruit_in_the_primary_frame() {
        let rig = rig();
        let images = shots(&rig, false);
        let detector = || Detector::builtin("color-contour").unwrap();
        for method in [StereoMethod::Paper, StereoMethod::Triangulate] {
            let settings = StereoSettings {
                method,
                ..StereoSettings::default()
            };
            let locator = StereoLocator::new(detector(), KeepRule::All, rig, settings).unwrap();
            // The sweep ranges follow the default reach: pivot + 0.2 m to pivot + 2.0 m.
            let range = locator.settings().leftovers.unwrap().distance_range_m;
            assert!((range.0 - 0.2).abs() < 1e-12 && (range.1 - 2.0).abs() < 1e-12);
            let found = locator.locate(&images.0, &images.1).unwrap();
            assert_eq!(found.detections.len(), 3, "{method:?}: {:?}", found.pairs);
            for truth in &fruit() {
                let nearest = miss_m(&found, truth);
                assert!(nearest < 0.03, "{method:?}: {truth} missed by {nearest} m");
            }
            for (pair, detection) in found.pairs.iter().zip(&found.detections) {
                assert_eq!(pair.center_m, detection.center_m);
                assert_eq!(Some(pair.primary_px), found.primary[pair.primary].center_px);
                assert_eq!(
                    Some(pair.stereo_circle_px),
                    found.stereo[pair.stereo].center_px
                );
            }
        }
        // An image of another size than the rig camera's is an error, not a panic.
        let small = ColorImage::filled(64, 48, LEAF);
        let locator =
            StereoLocator::new(detector(), KeepRule::All, rig, StereoSettings::default()).unwrap();
        assert!(locator.locate(&small, &images.1).is_err());
    }

    #[test]
    fn pairs_located_at_a_depth_where_their_circle_is_no_fruit_are_dropped() {
        let rig = rig();
        let (a, b) = shots(&rig, true);
        let locate = |fruit_radius_m: Option<(f64, f64)>| {
            let settings = StereoSettings {
                fruit_radius_m,
                ..StereoSettings::default()
            };
            let detector = Detector::builtin("color-contour").unwrap();
            StereoLocator::new(detector, KeepRule::All, rig, settings)
                .unwrap()
                .locate(&a, &b)
                .unwrap()
        };
        // The fruit are 40 mm in radius: inside the default range, and inside 35–45 mm.
        for range in [
            StereoSettings::default().fruit_radius_m,
            Some((0.035, 0.045)),
            None,
        ] {
            let found = locate(range);
            assert_eq!(found.pairs.len(), 3, "{range:?}: {:?}", found.pairs);
            assert!(found.rejected_by_size.is_empty(), "{range:?}");
            for d in &found.detections {
                let r = 0.5 * d.diameter_m.unwrap();
                assert!((r - RADIUS_M).abs() < 0.005, "{range:?}: radius {r}");
            }
        }
        // Ranges that leave them out: every pair is matched and located, then dropped.
        for range in [(0.01, 0.03), (0.05, 0.08)] {
            let found = locate(Some(range));
            assert!(
                found.detections.is_empty() && found.pairs.is_empty(),
                "{range:?}"
            );
            assert_eq!(found.rejected_by_size.len(), 3, "{range:?}");
        }
        // A range that is not one is refused.
        for bad in [
            (0.05, 0.03),
            (0.0, 0.03),
            (0.02, f64::INFINITY),
            (f64::NAN, 0.03),
        ] {
            let settings = StereoSettings {
                fruit_radius_m: Some(bad),
                ..StereoSettings::default()
            };
            let detector = Detector::builtin("color-contour").unwrap();
            let refused = StereoLocator::new(detector, KeepRule::All, rig, settings);
            assert!(
                matches!(refused, Err(Error::Stereo(_))),
                "{bad:?}: {refused:?}"
            );
        }
    }

    #[test]
    fn a_reach_the_rig_cannot_use_and_a_detector_without_circles_are_refused() {
        let detector = Detector::builtin("color-contour").unwrap();
        let settings = StereoSettings {
            reach_m: Some((2.0, 1.0)),
            ..StereoSettings::default()
        };
        let refused = StereoLocator::new(detector, KeepRule::All, rig(), settings);
        assert!(matches!(refused, Err(Error::Stereo(_))), "{refused:?}");
        // A detector without image circles cannot be matched.
        let depth_only = Detector::builtin("shape-fit").unwrap();
        let refused =
            StereoLocator::new(depth_only, KeepRule::All, rig(), StereoSettings::default());
        assert!(
            matches!(
                refused,
                Err(Error::StereoDetector {
                    pipeline: "shape-fit"
                })
            ),
            "{refused:?}"
        );
    }

    #[test]
    fn the_detector_overrides_turn_the_extra_circle_sources_off_before_the_users() {
        let user = ParamOverride::new("params.hough_circles", serde_json::json!({}));
        let all = StereoLocator::detector_overrides([user.clone()]);
        let keys: Vec<&str> = all.iter().map(|o| o.key.as_str()).collect();
        assert_eq!(
            keys,
            [
                "params.ray_circles",
                "params.hough_circles",
                "params.hough_circles"
            ]
        );
        assert!(all[..2].iter().all(|o| o.value.is_null()));
        assert_eq!(all[2], user);
    }

    #[test]
    fn located_detections_take_the_depth_scaled_radius() {
        let camera = PinholeCamera::new(640, 480, 500.0, 500.0, 320.0, 240.0).unwrap();
        let rig = RotatedStereo::new(0.07, 0.3, camera).unwrap();
        let mut a = Detection::new(Point3::new(0.0, 0.0, 9.0), 2.0);
        a.center_px = Some(Point2::new(300.0, 200.0));
        a.radius_px = Some(20.0);
        a.confidence = Some(0.9);
        let mut b = Detection::new(Point3::new(0.0, 0.0, 9.0), 4.0);
        b.confidence = Some(0.6);
        let center_m = Point3::new(0.1, 0.0, 1.0);
        let d = located(center_m, &a, &b, radius_at(&rig, &center_m, 20.0));
        assert_eq!(d.center_m, Point3::new(0.1, 0.0, 1.0));
        assert!((d.diameter_m.unwrap() - 0.08).abs() < 1e-12);
        assert_eq!((d.score, d.confidence), (3.0, Some(0.6)));
        assert_eq!(d.center_px, a.center_px);
    }
}
