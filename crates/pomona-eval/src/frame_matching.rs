//! Matching one frame's detections to its truth.
//!
//! Rules (the issue's, made precise):
//! 1. Detections are visited in decreasing score order; equal scores keep file order.
//! 2. Each takes the *nearest not-yet-matched* truth fruit it is within reach of. Reach means a 3D
//!    centre distance ≤ tolerance for truth with `center_m`; for truth with only `bbox_px`, the
//!    detection's centre projected with the camera falls inside the box. 3D candidates are
//!    preferred over 2D ones (a 3D distance and a pixel distance do not compare); among 2D
//!    candidates the nearest box centre wins.
//!
//!    With [`EvalConfig::radius_fraction_2d`] set (`pomona eval --2d`), matching is in the image
//!    instead: reach means the detection's circle centre lies within that fraction of the truth
//!    circle's radius from the truth circle's centre (circles from
//!    [`pomona_core::ImageCircle::from_parts`]), and the nearest in pixels wins.
//! 3. Truth with `visibility < min_visibility`, or with neither centre nor box (it cannot be
//!    located; in 2D, no circle), is *ignored*: a detection taking it is [`DetectionOutcome::Ignored`], it is not a
//!    miss, and further detections within reach of it once it is taken are ignored as well (as
//!    PASCAL VOC treats "difficult" objects) rather than counted as duplicates.
//! 4. With a depth band ([`EvalConfig::depth_range_m`]), truth whose centre lies outside it (or
//!    that has no 3D centre) is ignored as in rule 3, and a detection with no counted fruit in
//!    reach whose centre lies outside the band is ignored as well.
//! 5. Otherwise a detection with nothing in reach is a false positive — including a second
//!    detection of an already-found fruit (duplicates are false positives, as in VOC).

use pomona_core::{Detection, FrameTruth, FruitTruth, ImageCircle, PinholeCamera};
use serde::{Deserialize, Serialize};

use crate::EvalConfig;

/// What became of a detection.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum DetectionOutcome {
    /// Matched a counted truth fruit.
    TruePositive {
        /// Index of the fruit in the frame's truth.
        truth: usize,
        /// Centre distance in metres (`None` for a 2D match).
        center_error_m: Option<f64>,
        /// For a 2D match, the distance between the circle centres in truth radii.
        center_error_radii: Option<f64>,
        /// `|detected − true|` diameter, metres, where both are known.
        diameter_error_m: Option<f64>,
    },
    /// Matched nothing counted.
    FalsePositive,
    /// Matched (or re-matched) an ignored fruit; excluded from all figures.
    Ignored,
}

/// Status of a truth fruit after matching.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TruthStatus {
    /// Counted and found (by detection `by`).
    Found {
        /// Index of the detection that found it.
        by: usize,
    },
    /// Counted and not found.
    Missed,
    /// Not counted (too occluded or not locatable).
    Ignored,
}

/// Matching result of one frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameMatch {
    /// Outcome per detection, in the detections' original order.
    pub detections: Vec<DetectionOutcome>,
    /// Status per truth fruit, in the truth's order.
    pub truth: Vec<TruthStatus>,
}

impl FrameMatch {
    /// Number of counted truth fruit.
    pub fn counted_truth(&self) -> usize {
        self.truth
            .iter()
            .filter(|t| !matches!(t, TruthStatus::Ignored))
            .count()
    }
}

fn is_ignored(f: &FruitTruth, circle: Option<&ImageCircle>, config: &EvalConfig) -> bool {
    let too_hidden = f.visibility.is_some_and(|v| v < config.min_visibility);
    let unlocatable = match config.radius_fraction_2d {
        Some(_) => circle.is_none(),
        None => f.center_m.is_none() && f.bbox_px.is_none(),
    };
    let out_of_band =
        config.depth_range_m.is_some() && !f.center_m.is_some_and(|c| config.in_depth_range(c.z));
    too_hidden || unlocatable || out_of_band
}

/// Distance key of a truth fruit within reach of a detection: `(0, metres)` for a 3D match,
/// `(1, pixels)` for a match on the truth's box, `(0, pixels)` in 2D mode; `None` when out of
/// reach.
fn reach(
    det: &Detection,
    det_circle: Option<&ImageCircle>,
    f: &FruitTruth,
    truth_circle: Option<&ImageCircle>,
    camera: &PinholeCamera,
    config: &EvalConfig,
) -> Option<(u8, f64)> {
    if let Some(fraction) = config.radius_fraction_2d {
        let (d, t) = (det_circle?, truth_circle?);
        let dist = d.center_distance_px(t);
        return (dist <= fraction * t.radius_px).then_some((0, dist));
    }
    let d = &det.center_m;
    if let Some(c) = f.center_m {
        let dist = (c - d).norm();
        return (dist <= config.tolerance_m).then_some((0, dist));
    }
    let bbox = f.bbox_px?;
    let px = camera.project(d)?;
    bbox.contains(&px).then(|| (1, (px - bbox.center()).norm()))
}

/// Matches one frame (see the module documentation for the rules).
///
/// ```
/// use pomona_core::{nalgebra::Point3, Detection, FrameTruth, FruitTruth, PinholeCamera};
/// use pomona_eval::{match_frame, DetectionOutcome, EvalConfig};
/// let truth: FrameTruth = serde_json::from_str(
///     r#"{"complete": true, "fruits": [{"id": "1", "kind": "pepper", "center_m": [0, 0, 1]}]}"#,
/// ).unwrap();
/// let det = |z: f64, score: f64| Detection::new(Point3::new(0.0, 0.0, z), score);
/// let cam = PinholeCamera::new(640, 480, 500.0, 500.0, 319.5, 239.5).unwrap();
/// let m = match_frame(&truth, &[det(1.03, 0.5), det(1.01, 2.0)], &cam, &EvalConfig::default());
/// // The higher score is matched first and takes the fruit; the other is a duplicate.
/// assert!(matches!(m.detections[1], DetectionOutcome::TruePositive { truth: 0, .. }));
/// assert_eq!(m.detections[0], DetectionOutcome::FalsePositive);
/// ```
pub fn match_frame(
    truth: &FrameTruth,
    detections: &[Detection],
    camera: &PinholeCamera,
    config: &EvalConfig,
) -> FrameMatch {
    let image_2d = config.radius_fraction_2d.is_some();
    // Circles are only needed (and only derived) when matching in the image.
    let truth_circles: Vec<Option<ImageCircle>> = truth
        .fruits
        .iter()
        .map(|f| image_2d.then(|| f.image_circle(camera)).flatten())
        .collect();
    let det_circles: Vec<Option<ImageCircle>> = detections
        .iter()
        .map(|d| image_2d.then(|| d.image_circle(camera)).flatten())
        .collect();
    let ignored: Vec<bool> = truth
        .fruits
        .iter()
        .enumerate()
        .map(|(t, f)| is_ignored(f, truth_circles[t].as_ref(), config))
        .collect();
    let mut taken = vec![false; truth.fruits.len()];
    let mut status: Vec<TruthStatus> = ignored
        .iter()
        .map(|&i| {
            if i {
                TruthStatus::Ignored
            } else {
                TruthStatus::Missed
            }
        })
        .collect();
    let mut outcomes = vec![DetectionOutcome::FalsePositive; detections.len()];
    let mut order: Vec<usize> = (0..detections.len()).collect();
    let rank = ranking_values(detections);
    order.sort_by(|&a, &b| rank[b].total_cmp(&rank[a]));

    for d in order {
        let det = &detections[d];
        let mut best: Option<(usize, (u8, f64))> = None;
        let mut near_taken_ignored = false;
        for (t, fruit) in truth.fruits.iter().enumerate() {
            let Some(key) = reach(
                det,
                det_circles[d].as_ref(),
                fruit,
                truth_circles[t].as_ref(),
                camera,
                config,
            ) else {
                continue;
            };
            if taken[t] {
                near_taken_ignored |= ignored[t];
                continue;
            }
            let closer = match best {
                None => true,
                Some((_, bk)) => key.0 < bk.0 || (key.0 == bk.0 && key.1 < bk.1),
            };
            if closer {
                best = Some((t, key));
            }
        }
        outcomes[d] = match best {
            Some((t, key)) => {
                taken[t] = true;
                if ignored[t] {
                    DetectionOutcome::Ignored
                } else {
                    status[t] = TruthStatus::Found { by: d };
                    let fruit = &truth.fruits[t];
                    DetectionOutcome::TruePositive {
                        truth: t,
                        center_error_m: (key.0 == 0 && !image_2d).then_some(key.1),
                        center_error_radii: truth_circles[t].map(|c| key.1 / c.radius_px),
                        diameter_error_m: match (det.diameter_m, fruit.diameter_m) {
                            (Some(a), Some(b)) => Some((a - b).abs()),
                            _ => None,
                        },
                    }
                }
            }
            None if near_taken_ignored || !config.in_depth_range(det.center_m.z) => {
                DetectionOutcome::Ignored
            }
            None => DetectionOutcome::FalsePositive,
        };
    }
    FrameMatch {
        detections: outcomes,
        truth: status,
    }
}

/// What detections are ranked by, best first: their calibrated confidences when every one has
/// one, else their raw scores. A confidence fitted to cues beside the score (a cue
/// calibration) can order detections differently from their scores, and it is the ranking a
/// user thresholds on; with the score alone (Platt's sigmoid) both orders are the same.
pub fn ranking_values(detections: &[Detection]) -> Vec<f64> {
    ranking_of(detections.iter().map(|d| (d.score, d.confidence)))
}

/// [`ranking_values`] of `(score, confidence)` pairs.
pub(crate) fn ranking_of(scored: impl Iterator<Item = (f64, Option<f64>)> + Clone) -> Vec<f64> {
    match scored.clone().map(|(_, c)| c).collect::<Option<Vec<f64>>>() {
        Some(confidences) => confidences,
        None => scored.map(|(score, _)| score).collect(),
    }
}
