//! Matching and average precision on hand-built cases whose answers are worked out in comments.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use pomona_core::nalgebra::Point3;
use pomona_core::{Detection, FrameTruth, FruitTruth, PinholeCamera, PixelBox};
use pomona_eval::{
    evaluate, match_frame, DetectionOutcome, EvalConfig, FrameInput, PrCurve, TruthStatus,
};

fn camera() -> PinholeCamera {
    PinholeCamera::new(640, 480, 500.0, 500.0, 320.0, 240.0).unwrap()
}

fn fruit(id: &str, center: Option<[f64; 3]>, visibility: Option<f64>) -> FruitTruth {
    FruitTruth {
        id: id.into(),
        kind: "pepper".into(),
        center_m: center.map(Point3::from),
        diameter_m: Some(0.08),
        axis: None,
        bbox_px: None,
        center_px: None,
        radius_px: None,
        visibility,
        extra: Default::default(),
    }
}

fn truth(complete: bool, fruits: Vec<FruitTruth>) -> FrameTruth {
    FrameTruth {
        complete,
        fruits,
        extra: Default::default(),
    }
}

fn det(center: [f64; 3], score: f64) -> Detection {
    Detection::new(Point3::from(center), score)
}

fn frame(name: &str, t: FrameTruth, d: Vec<Detection>) -> FrameInput {
    FrameInput {
        frame: name.into(),
        truth: t,
        detections: d,
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

/// Four fruit at x = 0, 0.2, 0.4, 0.6 m (z = 1 m); six detections, alternately on a fruit and
/// nowhere, scores 0.9 … 0.4. The fourth fruit is never found.
///
/// | rank | score | hit | TP | FP | precision | recall |
/// |------|-------|-----|----|----|-----------|--------|
/// | 1    | 0.9   | yes | 1  | 0  | 1         | 0.25   |
/// | 2    | 0.8   | no  | 1  | 1  | 1/2       | 0.25   |
/// | 3    | 0.7   | yes | 2  | 1  | 2/3       | 0.50   |
/// | 4    | 0.6   | no  | 2  | 2  | 1/2       | 0.50   |
/// | 5    | 0.5   | yes | 3  | 2  | 3/5       | 0.75   |
/// | 6    | 0.4   | no  | 3  | 3  | 1/2       | 0.75   |
///
/// VOC 11-point: max precision at recall ≥ r for r = 0, 0.1, 0.2 is 1; for r = 0.3, 0.4, 0.5 it
/// is 2/3; for r = 0.6, 0.7 it is 3/5; for r = 0.8, 0.9, 1.0 nothing reaches it, 0.
/// AP = (3·1 + 3·2/3 + 2·3/5 + 3·0) / 11 = (3 + 2 + 1.2) / 11 = 6.2 / 11.
/// All-point: 0.25·1 + 0.25·2/3 + 0.25·3/5 = 0.25 + 1/6 + 0.15 = 0.5666….
fn six_detections() -> FrameInput {
    let fruits = (0..4)
        .map(|i| fruit(&i.to_string(), Some([0.2 * i as f64, 0.0, 1.0]), Some(0.9)))
        .collect();
    let dets = vec![
        det([0.0, 0.0, 1.01], 0.9),
        det([0.0, 0.5, 1.0], 0.8),
        det([0.2, 0.01, 1.0], 0.7),
        det([0.0, 0.5, 2.0], 0.6),
        det([0.4, 0.0, 0.98], 0.5),
        det([-0.5, 0.0, 1.0], 0.4),
    ];
    frame("a", truth(true, fruits), dets)
}

#[test]
fn voc11_and_all_point_ap_match_hand_computation() {
    let r = evaluate(&[six_detections()], &camera(), &EvalConfig::default()).unwrap();
    assert!(close(r.ap_voc11.unwrap(), 6.2 / 11.0), "{:?}", r.ap_voc11);
    assert!(close(r.ap.unwrap(), 0.25 + 0.25 * 2.0 / 3.0 + 0.25 * 0.6));
    // Threshold 0 admits all six: 3 TP, 3 FP.
    assert_eq!((r.true_positives, r.false_positives), (3, 3));
    assert_eq!(r.precision, Some(0.5));
    assert_eq!(r.recall, Some(0.75));
    // Centre errors of the three hits: 0.01, 0.01, 0.02 m.
    let ce = r.center_error_m;
    assert!(close(ce.median.unwrap(), 0.01));
    assert!(close(ce.mean.unwrap(), 0.04 / 3.0));
    // Detections have no diameter, so there is no diameter error.
    assert_eq!(r.diameter_error_m.mean_abs, None);
    assert!(r.null_reasons.contains_key("diameter_error_m"));
}

#[test]
fn threshold_selects_the_operating_point() {
    let config = EvalConfig {
        threshold: 0.65,
        ..EvalConfig::default()
    };
    let r = evaluate(&[six_detections()], &camera(), &config).unwrap();
    // Scores ≥ 0.65: ranks 1–3, 2 TP and 1 FP.
    assert_eq!(r.precision, Some(2.0 / 3.0));
    assert_eq!(r.recall, Some(0.5));
    // AP does not depend on the threshold.
    assert!(close(r.ap_voc11.unwrap(), 6.2 / 11.0));
    let high = EvalConfig {
        threshold: 5.0,
        ..EvalConfig::default()
    };
    let r = evaluate(&[six_detections()], &camera(), &high).unwrap();
    assert_eq!(r.precision, None);
    assert!(r.null_reasons["precision"].contains("threshold"));
    assert_eq!(r.recall, Some(0.0));
}

#[test]
fn tied_scores_do_not_depend_on_file_order() {
    // Two fruit. A false and a true detection tie at 0.9, another true one scores 0.5.
    // Admitting the tie at once: (p, r) = (1/2, 1/2), then (2/3, 1). Every VOC sample point
    // r = 0 … 1 sees max precision 2/3, so AP_VOC11 = 2/3; all-point AP = 0.5·2/3 + 0.5·2/3.
    let fruits = vec![
        fruit("a", Some([0.0, 0.0, 1.0]), None),
        fruit("b", Some([0.3, 0.0, 1.0]), None),
    ];
    let fp = det([1.0, 1.0, 1.0], 0.9);
    let tp = det([0.0, 0.0, 1.0], 0.9);
    let tp2 = det([0.3, 0.0, 1.0], 0.5);
    for dets in [vec![fp.clone(), tp.clone(), tp2.clone()], vec![tp, fp, tp2]] {
        let r = evaluate(
            &[frame("t", truth(true, fruits.clone()), dets)],
            &camera(),
            &EvalConfig::default(),
        )
        .unwrap();
        assert!(close(r.ap_voc11.unwrap(), 2.0 / 3.0), "{:?}", r.ap_voc11);
        assert!(close(r.ap.unwrap(), 2.0 / 3.0));
        let curve = r.pr_curve.unwrap();
        assert_eq!(curve.points.len(), 2);
        assert_eq!(
            (curve.points[0].precision, curve.points[0].recall),
            (0.5, 0.5)
        );
    }
}

#[test]
fn duplicates_are_false_positives_and_higher_score_wins() {
    let t = truth(true, vec![fruit("a", Some([0.0, 0.0, 1.0]), None)]);
    // The closer detection scores lower; greedy-by-score gives the fruit to the other one.
    let dets = vec![det([0.0, 0.0, 1.001], 0.2), det([0.0, 0.0, 1.04], 0.7)];
    let m = match_frame(&t, &dets, &camera(), &EvalConfig::default());
    assert_eq!(m.detections[0], DetectionOutcome::FalsePositive);
    assert!(matches!(
        m.detections[1],
        DetectionOutcome::TruePositive { truth: 0, center_error_m: Some(e), .. } if close(e, 0.04)
    ));
    assert_eq!(m.truth, vec![TruthStatus::Found { by: 1 }]);
}

#[test]
fn a_detection_takes_the_nearest_unmatched_fruit() {
    // Fruit 3 cm apart; both detections lie within 5 cm of both fruit.
    let t = truth(
        true,
        vec![
            fruit("left", Some([0.0, 0.0, 1.0]), None),
            fruit("right", Some([0.03, 0.0, 1.0]), None),
        ],
    );
    let dets = vec![det([0.025, 0.0, 1.0], 0.9), det([0.02, 0.0, 1.0], 0.8)];
    let m = match_frame(&t, &dets, &camera(), &EvalConfig::default());
    // First (0.9) is nearest to "right"; second then takes "left", the nearest still unmatched.
    assert!(matches!(
        m.detections[0],
        DetectionOutcome::TruePositive { truth: 1, .. }
    ));
    assert!(matches!(
        m.detections[1],
        DetectionOutcome::TruePositive { truth: 0, .. }
    ));
    // Exactly at the tolerance still matches; just beyond does not.
    let t = truth(true, vec![fruit("a", Some([0.0, 0.0, 1.0]), None)]);
    let config = EvalConfig {
        tolerance_m: 0.25,
        ..EvalConfig::default()
    };
    let m = match_frame(&t, &[det([0.0, 0.0, 1.25], 1.0)], &camera(), &config);
    assert!(matches!(
        m.detections[0],
        DetectionOutcome::TruePositive { .. }
    ));
    let m = match_frame(&t, &[det([0.0, 0.0, 1.2501], 1.0)], &camera(), &config);
    assert_eq!(m.detections[0], DetectionOutcome::FalsePositive);
}

#[test]
fn ignored_truth_is_neither_hit_nor_miss() {
    // Fruit "hidden" is 30 % visible (< 50 %), found twice; "seen" is 80 % visible, missed;
    // "nowhere" has neither centre nor box, so cannot be located and is ignored too.
    let mut nowhere = fruit("nowhere", None, Some(0.9));
    nowhere.bbox_px = None;
    let t = truth(
        true,
        vec![
            fruit("hidden", Some([0.0, 0.0, 1.0]), Some(0.3)),
            fruit("seen", Some([0.5, 0.0, 1.0]), Some(0.8)),
            nowhere,
        ],
    );
    let dets = vec![
        det([0.0, 0.0, 1.01], 0.9),
        det([0.0, 0.01, 1.0], 0.8),
        det([2.0, 0.0, 1.0], 0.1),
    ];
    let m = match_frame(&t, &dets, &camera(), &EvalConfig::default());
    assert_eq!(m.detections[0], DetectionOutcome::Ignored);
    assert_eq!(m.detections[1], DetectionOutcome::Ignored);
    assert_eq!(m.detections[2], DetectionOutcome::FalsePositive);
    assert_eq!(
        m.truth,
        vec![
            TruthStatus::Ignored,
            TruthStatus::Missed,
            TruthStatus::Ignored
        ]
    );
    let r = evaluate(
        &[frame("i", t.clone(), dets)],
        &camera(),
        &EvalConfig::default(),
    )
    .unwrap();
    assert_eq!((r.fruits, r.ignored), (1, 2));
    assert_eq!((r.true_positives, r.false_positives), (0, 1));
    assert_eq!(r.precision, Some(0.0));
    assert_eq!(r.recall, Some(0.0));
    // With --min-visibility 0.2 the hidden fruit counts: one TP, one duplicate FP.
    let lenient = EvalConfig {
        min_visibility: 0.2,
        ..EvalConfig::default()
    };
    let m = match_frame(
        &t,
        &[det([0.0, 0.0, 1.01], 0.9), det([0.0, 0.01, 1.0], 0.8)],
        &camera(),
        &lenient,
    );
    assert!(matches!(
        m.detections[0],
        DetectionOutcome::TruePositive { truth: 0, .. }
    ));
    assert_eq!(m.detections[1], DetectionOutcome::FalsePositive);
}

#[test]
fn box_only_truth_is_matched_by_projected_centre() {
    // Camera f = 500, c = (320, 240). A detection at (0.1, 0, 1) projects to (370, 240).
    let mut boxed = fruit("boxed", None, None);
    boxed.bbox_px = Some(PixelBox::new(350.0, 220.0, 390.0, 260.0).unwrap());
    let t = truth(true, vec![boxed]);
    let inside = det([0.1, 0.0, 1.0], 0.9);
    // (0.2, 0, 1) projects to (420, 240): outside the box although only 10 cm away in 3D.
    let outside = det([0.2, 0.0, 1.0], 0.95);
    let m = match_frame(&t, &[outside, inside], &camera(), &EvalConfig::default());
    assert_eq!(m.detections[0], DetectionOutcome::FalsePositive);
    assert!(matches!(
        m.detections[1],
        DetectionOutcome::TruePositive {
            truth: 0,
            center_error_m: None,
            ..
        }
    ));
    // A detection behind the camera cannot project and does not match.
    let m = match_frame(
        &t,
        &[det([0.1, 0.0, -1.0], 1.0)],
        &camera(),
        &EvalConfig::default(),
    );
    assert_eq!(m.detections[0], DetectionOutcome::FalsePositive);
}

#[test]
fn empty_frames_count_correctly() {
    let frames = vec![
        // Nothing at all.
        frame("empty", truth(true, vec![]), vec![]),
        // A false alarm on an empty frame.
        frame("fp", truth(true, vec![]), vec![det([0.0, 0.0, 1.0], 1.0)]),
        // A fruit the detector did not report.
        frame(
            "miss",
            truth(true, vec![fruit("a", Some([0.0, 0.0, 1.0]), None)]),
            vec![],
        ),
    ];
    let r = evaluate(&frames, &camera(), &EvalConfig::default()).unwrap();
    assert_eq!(
        (r.frames, r.fruits, r.true_positives, r.false_positives),
        (3, 1, 0, 1)
    );
    assert_eq!(r.ap_voc11, Some(0.0));
    assert_eq!(r.ap, Some(0.0));
    assert_eq!(r.per_frame[0].precision, None);
    assert_eq!(r.per_frame[0].recall, None);
    assert_eq!(r.per_frame[1].precision, Some(0.0));
    assert_eq!(r.per_frame[2].recall, Some(0.0));
    // No truth anywhere: AP and recall are null with reasons.
    let r = evaluate(&frames[..2], &camera(), &EvalConfig::default()).unwrap();
    assert_eq!((r.ap, r.recall), (None, None));
    assert!(r.null_reasons["ap"].contains("no counted truth"));
    // No frames at all.
    let r = evaluate(&[], &camera(), &EvalConfig::default()).unwrap();
    assert_eq!(r.frames, 0);
    assert_eq!(r.ap, None);
}

#[test]
fn incomplete_truth_gives_recall_but_no_precision_or_ap() {
    let mut frames = vec![six_detections()];
    frames.push(frame(
        "partial",
        truth(false, vec![fruit("x", Some([0.0, 0.0, 1.0]), None)]),
        vec![det([0.0, 0.0, 1.0], 2.0), det([1.0, 0.0, 1.0], 1.5)],
    ));
    let r = evaluate(&frames, &camera(), &EvalConfig::default()).unwrap();
    assert_eq!((r.precision, r.ap, r.ap_voc11), (None, None, None));
    assert!(r.pr_curve.is_none());
    assert!(r.null_reasons["precision"].contains("partial"));
    assert!(r.null_reasons["ap"].contains("incomplete"));
    // Recall still counts the partial frame: 3 + 1 of 4 + 1 fruit.
    assert_eq!(r.recall, Some(0.8));
    assert_eq!(r.per_frame[1].precision, None);
    assert_eq!(r.per_frame[1].recall, Some(1.0));
    assert_eq!(r.per_frame[0].precision, Some(0.5));
}

#[test]
fn diameter_error_uses_pairs_with_both_sides() {
    let t = truth(
        true,
        vec![
            fruit("a", Some([0.0, 0.0, 1.0]), None),
            fruit("b", Some([0.5, 0.0, 1.0]), None),
        ],
    );
    let mut d1 = det([0.0, 0.0, 1.0], 1.0);
    d1.diameter_m = Some(0.07);
    let d2 = det([0.5, 0.0, 1.0], 1.0);
    let r = evaluate(
        &[frame("d", t, vec![d1, d2])],
        &camera(),
        &EvalConfig::default(),
    )
    .unwrap();
    assert!(close(r.diameter_error_m.mean_abs.unwrap(), 0.01));
    assert_eq!(r.center_error_m.median, Some(0.0));
}

#[test]
fn pr_curve_edge_cases() {
    let empty = PrCurve::new(&[], 3);
    assert_eq!(empty.ap_voc11(), 0.0);
    assert_eq!(empty.ap_all_points(), 0.0);
    assert!(empty.at_threshold(0.0).is_none());
    // Perfect ranking: AP = 1 under both definitions.
    let perfect = PrCurve::new(&[(3.0, true), (2.0, true), (1.0, false)], 2);
    assert_eq!(perfect.ap_voc11(), 1.0);
    assert_eq!(perfect.ap_all_points(), 1.0);
    assert_eq!(perfect.at_threshold(1.5).unwrap().precision, 1.0);
    assert_eq!(perfect.at_threshold(0.0).unwrap().precision, 2.0 / 3.0);
    assert!(EvalConfig {
        tolerance_m: 0.0,
        ..EvalConfig::default()
    }
    .validate()
    .is_err());
}

#[test]
fn split_summary_averages_figures_and_curves() {
    let a = evaluate(&[six_detections()], &camera(), &EvalConfig::default()).unwrap();
    let mut perfect = six_detections();
    perfect
        .detections
        .retain(|d| d.center_m.y == 0.0 || d.center_m.y == 0.01);
    perfect.detections.retain(|d| d.center_m.x >= 0.0);
    let b = evaluate(&[perfect], &camera(), &EvalConfig::default()).unwrap();
    // b: three hits ranked first, no false positives: AP_VOC11 = 8/11 (recall stops at 0.75).
    assert!(close(b.ap_voc11.unwrap(), 8.0 / 11.0));
    let s = pomona_eval::SplitSummary::new(&[a, b]);
    let m = s.ap_voc11.unwrap();
    assert!(close(m.mean, (6.2 / 11.0 + 8.0 / 11.0) / 2.0));
    assert!(close(m.sd, (1.8 / 11.0) / 2.0f64.sqrt()));
    let curve = s.mean_pr_curve.unwrap();
    assert_eq!(curve.len(), 101);
    // At recall 0.5: split a's interpolated precision is 2/3, b's is 1.
    assert!(close(curve[50].1, (2.0 / 3.0 + 1.0) / 2.0));
}

/// `--2d`: a hit when the detection's circle centre is within half the truth radius; truth
/// circles come from `center_px`/`radius_px` or are projected from the 3D sphere.
#[test]
fn image_2d_matching_uses_half_the_truth_radius() {
    use pomona_core::nalgebra::Point2;
    let cam = camera();
    // Fruit 0: an annotated circle at (100, 100), radius 20 px. Fruit 1: a sphere ⌀ 80 mm at
    // 1 m on the optical axis, imaged at (320, 240) with radius 500·0.04/√0.9984 = 20.016 px.
    let mut annotated = fruit("0", None, None);
    annotated.center_px = Some(Point2::new(100.0, 100.0));
    annotated.radius_px = Some(20.0);
    let sphere = fruit("1", Some([0.0, 0.0, 1.0]), None);
    let t = truth(true, vec![annotated, sphere]);
    let circle = |x: f64, y: f64, score: f64| Detection {
        center_px: Some(Point2::new(x, y)),
        radius_px: Some(18.0),
        ..Detection::new(Point3::new(9.0, 9.0, 9.0), score) // 3D centre ignored in 2D
    };
    let dets = [
        circle(109.0, 100.0, 3.0), // 0.45 r from fruit 0: hit
        circle(330.5, 240.0, 2.0), // 10.5 px = 0.525 r from fruit 1: miss
        circle(329.0, 240.0, 1.0), // 9 px = 0.45 r from fruit 1: hit
    ];
    let m = match_frame(&t, &dets, &cam, &EvalConfig::image_2d());
    match m.detections[0] {
        DetectionOutcome::TruePositive {
            truth: 0,
            center_error_m: None,
            center_error_radii: Some(e),
            ..
        } => assert!(close(e, 0.45)),
        ref other => panic!("{other:?}"),
    }
    assert_eq!(m.detections[1], DetectionOutcome::FalsePositive);
    assert!(matches!(
        m.detections[2],
        DetectionOutcome::TruePositive { truth: 1, .. }
    ));
    // The same detections in 3D match nothing: the 2D rule is what found them.
    let m3 = match_frame(&t, &dets, &cam, &EvalConfig::default());
    assert!(m3
        .detections
        .iter()
        .all(|d| *d == DetectionOutcome::FalsePositive));
    let report = evaluate(
        &[FrameInput {
            frame: "f".into(),
            truth: t,
            detections: dets.to_vec(),
        }],
        &cam,
        &EvalConfig::image_2d(),
    )
    .unwrap();
    assert_eq!((report.true_positives, report.false_positives), (2, 1));
    assert_eq!(report.radius_fraction_2d, Some(0.5));
    let radii = report.center_error_radii.unwrap();
    // Median of 0.45 and 9 / 20.016 = 0.4496.
    assert!((radii.median.unwrap() - 0.44982).abs() < 1e-4, "{radii:?}");
    assert!(report.to_markdown().contains("truth radii"));
}

/// A depth band keeps the fruit inside it and drops, rather than counts, what lies outside:
/// fruit at z = 0.5, 1.0 and 1.5 m, band [0.8, 1.2) m.
///
/// | detection | where | outcome |
/// |---|---|---|
/// | 0.9 on the 1 m fruit | in band | true positive |
/// | 0.8 on the 0.5 m fruit | out of band, its fruit ignored | ignored |
/// | 0.7 at 1.1 m, no fruit | in band | false positive |
/// | 0.6 at 1.4 m, no fruit | out of band | ignored |
///
/// One counted fruit, found; one false positive: precision 1/2, recall 1, AP 1 (the hit ranks
/// first).
#[test]
fn a_depth_band_counts_only_the_fruit_and_stray_detections_inside_it() {
    let t = truth(
        true,
        vec![
            fruit("near", Some([0.0, 0.0, 0.5]), Some(1.0)),
            fruit("mid", Some([0.2, 0.0, 1.0]), Some(1.0)),
            fruit("far", Some([0.4, 0.0, 1.5]), Some(1.0)),
            fruit("unplaced", None, Some(1.0)),
        ],
    );
    let d = vec![
        det([0.2, 0.0, 1.01], 0.9),
        det([0.0, 0.0, 0.51], 0.8),
        det([-0.3, 0.0, 1.1], 0.7),
        det([-0.3, 0.0, 1.4], 0.6),
    ];
    let band = EvalConfig {
        depth_range_m: Some((0.8, 1.2)),
        ..EvalConfig::default()
    };
    let m = match_frame(&t, &d, &camera(), &band);
    assert!(matches!(
        m.detections[0],
        DetectionOutcome::TruePositive { truth: 1, .. }
    ));
    assert_eq!(m.detections[1], DetectionOutcome::Ignored);
    assert_eq!(m.detections[2], DetectionOutcome::FalsePositive);
    assert_eq!(m.detections[3], DetectionOutcome::Ignored);
    assert_eq!(
        m.truth,
        vec![
            TruthStatus::Ignored,
            TruthStatus::Found { by: 0 },
            TruthStatus::Ignored,
            TruthStatus::Ignored,
        ]
    );
    let report = evaluate(&[frame("f", t.clone(), d.clone())], &camera(), &band).unwrap();
    assert_eq!((report.fruits, report.ignored), (1, 3));
    assert_eq!(report.precision, Some(0.5));
    assert_eq!(report.recall, Some(1.0));
    assert_eq!(report.ap_voc11, Some(1.0));
    assert_eq!(report.depth_range_m, Some((0.8, 1.2)));
    // Without the band every placed fruit counts: the 1.5 m fruit is missed.
    let all = evaluate(&[frame("f", t, d)], &camera(), &EvalConfig::default()).unwrap();
    assert_eq!(all.fruits, 3);
    assert_eq!(all.depth_range_m, None);
    for bad in [(1.2, 0.8), (-0.1, 1.0), (0.5, 0.5), (f64::NAN, 1.0)] {
        let config = EvalConfig {
            depth_range_m: Some(bad),
            ..EvalConfig::default()
        };
        assert!(config.validate().is_err(), "{bad:?}");
    }
}

#[test]
fn confidences_rank_when_every_detection_has_one() {
    let t = truth(true, vec![fruit("a", Some([0.0, 0.0, 1.0]), None)]);
    // The closer detection scores lower but is the more confident (a cue calibration can
    // reorder): with confidences on both it takes the fruit; with one missing, scores rank.
    let with = |c: [Option<f64>; 2]| {
        vec![
            Detection {
                confidence: c[0],
                ..det([0.0, 0.0, 1.001], 0.2)
            },
            Detection {
                confidence: c[1],
                ..det([0.0, 0.0, 1.04], 0.7)
            },
        ]
    };
    let m = match_frame(
        &t,
        &with([Some(0.9), Some(0.3)]),
        &camera(),
        &EvalConfig::default(),
    );
    assert!(matches!(
        m.detections[0],
        DetectionOutcome::TruePositive { truth: 0, .. }
    ));
    assert_eq!(m.detections[1], DetectionOutcome::FalsePositive);
    let m = match_frame(
        &t,
        &with([Some(0.9), None]),
        &camera(),
        &EvalConfig::default(),
    );
    assert_eq!(m.detections[0], DetectionOutcome::FalsePositive);
    // The PR curve ranks the same way: the confident hit first gives precision 1 at recall 1.
    let config = EvalConfig {
        min_confidence: Some(0.0),
        ..EvalConfig::default()
    };
    let r = evaluate(
        &[frame("f", t, with([Some(0.9), Some(0.3)]))],
        &camera(),
        &config,
    )
    .unwrap();
    assert!(close(r.ap_voc11.unwrap(), 1.0), "{:?}", r.ap_voc11);
}

/// Three counted fruit and one too hidden to count, at z = 1 m, threshold score 0.5: A is found
/// by a detection at 0.9; B only by one at 0.2 (below the threshold); C by none, the nearest
/// detection (an unmatched one at 0.7) 80 mm from it; D (visibility 0.2) by none. The report
/// lists B and C as missed, B with the detection that would find it, C with the distance, and
/// counts them in the summary.
#[test]
fn missed_fruit_say_whether_a_lower_threshold_would_find_them() {
    let t = truth(
        true,
        vec![
            fruit("A", Some([0.0, 0.0, 1.0]), None),
            fruit("B", Some([0.3, 0.0, 1.0]), None),
            fruit("C", Some([0.6, 0.0, 1.0]), None),
            fruit("D", Some([0.9, 0.0, 1.0]), Some(0.2)),
        ],
    );
    let d = vec![
        det([0.01, 0.0, 1.0], 0.9),
        det([0.3, 0.02, 1.0], 0.2),
        det([0.6, 0.08, 1.0], 0.7),
    ];
    let config = EvalConfig {
        threshold: 0.5,
        ..EvalConfig::default()
    };
    let report = evaluate(&[frame("f", t, d)], &camera(), &config).unwrap();
    let missed = &report.per_frame[0].missed;
    let ids: Vec<&str> = missed.iter().map(|m| m.id.as_str()).collect();
    assert_eq!(ids, ["B", "C"]);
    let b = missed[0].below_threshold.unwrap();
    assert!(close(b.score, 0.2) && b.confidence.is_none(), "{b:?}");
    assert!(close(missed[0].nearest_detection_m.unwrap(), 0.02));
    assert!(missed[1].below_threshold.is_none());
    assert!(close(missed[1].nearest_detection_m.unwrap(), 0.08));
    assert_eq!(missed[1].kind, "pepper");
    assert_eq!(report.recall, Some(1.0 / 3.0));
    assert!(
        report
            .to_markdown()
            .contains("| missed: never detected / only below the threshold | 1 / 1 |"),
        "{}",
        report.to_markdown()
    );
    // Reports written before the list existed still read.
    let mut json = serde_json::to_value(&report).unwrap();
    json["per_frame"][0]
        .as_object_mut()
        .unwrap()
        .remove("missed");
    let old: pomona_eval::EvalReport = serde_json::from_value(json).unwrap();
    assert!(old.per_frame[0].missed.is_empty());
}
