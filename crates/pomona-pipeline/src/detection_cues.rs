//! The cues of one detection that a cue calibration ([`pomona_learn::CueLogistic`]) rates beside
//! its score, measured in the frame it was found in. Split from the calibration because the
//! measuring needs the frame (its camera and depth) and the fitting does not.

use pomona_core::{Detection, RgbdFrame};
use pomona_learn::DetectionCues;

use crate::DoubleCurvatureCheck;

/// Log coverage is clamped to this range: a sliver of a few points and a cluster spilling far
/// past its disc (a sphere fitted too small) say no more beyond it.
const LOG_COVERAGE_RANGE: (f64, f64) = (-5.0, 1.5);

/// Relative curvature is clamped to this range: a ball seen whole reads about 1.6, and steeper or
/// more saddle-like readings come from a handful of points at the rim.
const RELATIVE_CURVATURE_RANGE: (f64, f64) = (-1.0, 2.0);

/// The cues of `detection` in `frame`, its curvature measured over `curvature_patch_radii` fruit
/// radii round its centre (see `pomona_learn::cue_logistic` for what each one is). A cue that
/// cannot be measured is `None`: no support count or diameter (coverage), a centre not in front
/// of the camera (depth, coverage, curvature), too few depth readings round it (curvature). An
/// elongated detection (with a fruit axis) has no curvature cue: a cylinder is straight along
/// its axis, so its flattest curvature is near 0 whether it is a fruit or not.
pub fn detection_cues(
    detection: &Detection,
    frame: &RgbdFrame,
    curvature_patch_radii: f64,
) -> DetectionCues {
    let z = detection.center_m.z;
    let in_front = z > 0.0 && z.is_finite();
    let radius_m = detection
        .diameter_m
        .filter(|d| d.is_finite() && *d > 0.0)
        .map(|d| d / 2.0);
    let log_coverage = match (detection.support_points, radius_m) {
        (Some(n), Some(r)) if in_front => {
            let r_px = frame.camera().fx * r / z;
            let disc_px = std::f64::consts::PI * r_px * r_px;
            (disc_px > 0.0).then(|| {
                (n.max(1) as f64 / disc_px)
                    .ln()
                    .clamp(LOG_COVERAGE_RANGE.0, LOG_COVERAGE_RANGE.1)
            })
        }
        _ => None,
    };
    let relative_curvature = radius_m
        .filter(|_| in_front && detection.fruit_axis.is_none())
        .and_then(|r| {
            let check = DoubleCurvatureCheck {
                patch_radii: curvature_patch_radii,
                ..DoubleCurvatureCheck::default()
            };
            check
                .seen_curvature(frame, &detection.center_m, r)
                .map(|c| {
                    (c.flattest_per_m * r)
                        .clamp(RELATIVE_CURVATURE_RANGE.0, RELATIVE_CURVATURE_RANGE.1)
                })
        });
    DetectionCues {
        score: detection.score,
        log_coverage,
        log_depth: in_front.then(|| z.ln()),
        relative_curvature,
        elongated: detection.fruit_axis.is_some(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::nalgebra::{Point3, Unit, Vector3};
    use pomona_core::{DepthImage, PinholeCamera};

    /// A 128×128 camera (focal 200 px) looking at a wall at 1.2 m with a 40 mm ball whose
    /// centre is 0.8 m away on the optical axis (its near cap at 0.76 m).
    fn ball_scene() -> RgbdFrame {
        let cam = PinholeCamera::new(128, 128, 200.0, 200.0, 63.5, 63.5).unwrap();
        let mut depth = vec![1.2_f32; 128 * 128];
        for v in 0..128 {
            for u in 0..128 {
                let p = cam.back_project(u as f64, v as f64, 0.8);
                let r2 = 0.04 * 0.04 - p.x * p.x - p.y * p.y;
                if r2 >= 0.0 {
                    depth[v * 128 + u] = (0.8 - r2.sqrt()) as f32;
                }
            }
        }
        RgbdFrame::new(cam, DepthImage::from_meters(128, 128, depth).unwrap(), None).unwrap()
    }

    fn ball_detection(support_points: usize) -> Detection {
        Detection {
            diameter_m: Some(0.08),
            support_points: Some(support_points),
            ..Detection::new(Point3::new(0.0, 0.0, 0.8), 0.7)
        }
    }

    #[test]
    fn a_ball_fills_its_disc_and_bends_both_ways() {
        let frame = ball_scene();
        // The disc of a 40 mm radius at 0.8 m through a 200 px focal: 10 px, 314 pixels.
        let c = detection_cues(&ball_detection(314), &frame, 1.2);
        assert!(c.log_coverage.unwrap().abs() < 0.01, "{c:?}");
        assert!((c.log_depth.unwrap() - 0.8_f64.ln()).abs() < 1e-12);
        let k = c.relative_curvature.unwrap();
        assert!((0.8..=2.0).contains(&k), "{c:?}");
        assert!(!c.elongated && c.score == 0.7);
        // A sliver of the disc reads low coverage; a few points are clamped.
        let sliver = detection_cues(&ball_detection(31), &frame, 1.2);
        let drop = c.log_coverage.unwrap() - sliver.log_coverage.unwrap();
        assert!((drop - (314.0_f64 / 31.0).ln()).abs() < 1e-9, "{sliver:?}");
        let few = detection_cues(&ball_detection(0), &frame, 1.2);
        assert_eq!(few.log_coverage, Some(LOG_COVERAGE_RANGE.0));
    }

    #[test]
    fn cues_that_cannot_be_measured_are_missing() {
        let frame = ball_scene();
        let bare = Detection::new(Point3::new(0.0, 0.0, 0.8), 0.1);
        let c = detection_cues(&bare, &frame, 1.2);
        assert_eq!((c.log_coverage, c.relative_curvature), (None, None));
        assert!(c.log_depth.is_some());
        let behind = Detection {
            center_m: Point3::new(0.0, 0.0, -0.5),
            ..ball_detection(314)
        };
        let c = detection_cues(&behind, &frame, 1.2);
        assert_eq!(
            (c.log_coverage, c.log_depth, c.relative_curvature),
            (None, None, None)
        );
        // A cylinder is not judged by its curvature.
        let cylinder = Detection {
            fruit_axis: Some(Unit::new_normalize(Vector3::y())),
            ..ball_detection(314)
        };
        let c = detection_cues(&cylinder, &frame, 1.2);
        assert!(c.elongated && c.relative_curvature.is_none() && c.log_coverage.is_some());
    }
}
