//! Detection folders read against a dataset on disk, the JSON report's stable keys, and the PNG.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use pomona_core::{DepthImage, FrameTruth, PinholeCamera};
use pomona_eval::{evaluate, load_detections, write_pr_plot, EvalConfig, EvalError, FrameInput};
use pomona_io::{Dataset, DatasetWriter};

fn make_dataset(root: &Path) -> Dataset {
    let cam = PinholeCamera::new(8, 6, 10.0, 10.0, 3.5, 2.5).unwrap();
    let w = DatasetWriter::create(root, &cam, 0.001).unwrap();
    for frame in ["f1", "f2", "f3"] {
        w.write_depth(frame, &DepthImage::empty(8, 6)).unwrap();
    }
    let t: FrameTruth = serde_json::from_str(
        r#"{"complete": true, "fruits": [
            {"id": "1", "kind": "apple", "center_m": [0, 0, 1], "diameter_m": 0.07},
            {"id": "2", "kind": "apple", "center_m": [0.3, 0, 1], "visibility": 0.2}]}"#,
    )
    .unwrap();
    w.write_truth("f1", &t).unwrap();
    w.write_truth("f2", &t).unwrap();
    Dataset::open(root).unwrap()
}

fn write(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap();
}

#[test]
fn reads_detections_and_reports_missing_frames() {
    let dir = tempfile::tempdir().unwrap();
    let ds = make_dataset(&dir.path().join("data"));
    let det = dir.path().join("det");
    std::fs::create_dir(&det).unwrap();
    write(
        &det.join("f1.json"),
        r#"{"frame": "f1", "pipeline": "p", "detections": [
            {"center_m": [0.01, 0, 1], "score": 1.5, "diameter_m": 0.075},
            {"center_m": [0.5, 0, 1], "score": -0.5}]}"#,
    );
    write(&det.join("notes.txt"), "ignored");
    write(&det.join(".hidden.json"), "ignored");
    let set = load_detections(&det, &ds).unwrap();
    assert_eq!(set.by_frame.len(), 1);
    assert_eq!(set.missing, vec!["f2".to_owned(), "f3".to_owned()]);

    let frames: Vec<FrameInput> = ds
        .frames()
        .iter()
        .filter_map(|f| {
            ds.load_truth(f).unwrap().map(|truth| FrameInput {
                frame: f.clone(),
                truth,
                detections: set
                    .by_frame
                    .get(f)
                    .map(|d| d.detections.clone())
                    .unwrap_or_default(),
            })
        })
        .collect();
    let report = evaluate(&frames, ds.camera(), &EvalConfig::default()).unwrap();
    assert_eq!((report.frames, report.fruits, report.ignored), (2, 2, 2));
    assert_eq!(report.recall, Some(0.5));
    assert_eq!(report.precision, Some(1.0));
    assert!((report.diameter_error_m.mean_abs.unwrap() - 0.005).abs() < 1e-12);

    // Stable key order of the JSON report.
    let json = serde_json::to_string(&report).unwrap();
    let keys = [
        "\"frames\"",
        "\"fruits\"",
        "\"ignored\"",
        "\"tolerance_m\"",
        "\"ap_voc11\"",
        "\"ap\"",
        "\"precision\"",
        "\"recall\"",
        "\"threshold\"",
        "\"center_error_m\":{\"median\"",
        "\"diameter_error_m\":{\"mean_abs\"",
        "\"per_frame\"",
    ];
    let mut at = 0;
    for k in keys {
        let pos = json[at..]
            .find(k)
            .unwrap_or_else(|| panic!("{k} missing or out of order"));
        at += pos + k.len();
    }

    // The PR plot is a PNG of the advertised size.
    let png = dir.path().join("pr.png");
    write_pr_plot(&png, report.pr_curve.as_ref().unwrap(), "test", 0.0).unwrap();
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 800);
}

#[test]
fn detection_file_for_unknown_frame_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let ds = make_dataset(&dir.path().join("data"));
    let det = dir.path().join("det");
    std::fs::create_dir(&det).unwrap();
    write(
        &det.join("f9.json"),
        r#"{"frame": "f9", "pipeline": "p", "detections": []}"#,
    );
    let err = load_detections(&det, &ds).unwrap_err();
    assert!(matches!(err, EvalError::UnknownFrame { ref frame, .. } if frame == "f9"));
    assert!(err.to_string().contains("f9.json"), "{err}");
}

#[test]
fn malformed_or_mislabelled_files_are_errors_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let ds = make_dataset(&dir.path().join("data"));
    let det = dir.path().join("det");
    std::fs::create_dir(&det).unwrap();
    write(
        &det.join("f1.json"),
        r#"{"frame": "f2", "pipeline": "p", "detections": []}"#,
    );
    let err = load_detections(&det, &ds).unwrap_err();
    assert!(matches!(err, EvalError::FrameMismatch { .. }), "{err}");
    write(&det.join("f1.json"), r#"{"frame": "f1", "detections": "#);
    let err = load_detections(&det, &ds).unwrap_err();
    assert!(matches!(err, EvalError::DetectionJson { .. }));
    assert!(err.to_string().contains("f1.json"));
    assert!(load_detections(&dir.path().join("nope"), &ds).is_err());
}
