//! End-to-end tests of the `pomona` binary: output on real and hand-made datasets, and the
//! one-line error and non-zero exit for broken input.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use pomona_core::{ColorImage, DepthImage, PinholeCamera};
use pomona_io::DatasetWriter;

fn pomona(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pomona"))
        .args(args)
        .output()
        .unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn shared_data(rel: &str) -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel);
    if p.exists() {
        Some(p)
    } else {
        eprintln!(
            "skipped: {} is absent (real data lives in ../shared/data)",
            p.display()
        );
        None
    }
}

/// A 4×3 dataset, one frame: depth 0.5..0.61 m with one hole, red colour.
fn small_dataset(root: &Path) {
    let cam = PinholeCamera::new(4, 3, 10.0, 10.0, 1.5, 1.0).unwrap();
    let w = DatasetWriter::create(root, &cam, 0.001).unwrap();
    let raw: Vec<u16> = (0..12)
        .map(|k| if k == 5 { 0 } else { 500 + 10 * k })
        .collect();
    w.write_depth("f0", &DepthImage::from_u16(4, 3, &raw, 0.001).unwrap())
        .unwrap();
    w.write_color("f0", &ColorImage::filled(4, 3, [200, 30, 20]))
        .unwrap();
}

#[test]
fn info_on_real_apples_reports_three_frames() {
    let Some(root) = shared_data("ak-apples") else {
        return;
    };
    let out = pomona(&["info", root.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(report["width"], 1920);
    assert_eq!(report["height"], 1080);
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3);
    for f in frames {
        let valid = f["valid_depth_fraction"].as_f64().unwrap();
        assert!((valid - 0.27).abs() < 0.03, "valid depth {valid}");
        assert_eq!(f["fruits"], 28);
        assert_eq!(f["complete"], false);
    }
    let table = pomona(&["info", root.to_str().unwrap()]);
    assert!(stdout(&table).contains("1920x1080"));
}

#[test]
fn info_table_on_small_dataset() {
    let dir = tempfile::tempdir().unwrap();
    small_dataset(dir.path());
    let out = pomona(&["info", dir.path().to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.contains("4x3"), "{text}");
    assert!(text.contains("91.7%"), "{text}"); // 11 of 12 pixels
    assert!(text.contains("0.500-0.610"), "{text}");
}

#[test]
fn broken_dataset_exits_non_zero_with_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    small_dataset(dir.path());
    std::fs::write(
        dir.path().join("depth/f0.png"),
        b"\x89PNG\r\n\x1a\ntruncated",
    )
    .unwrap();
    let out = pomona(&["info", dir.path().to_str().unwrap()]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("f0.png"), "{err}");
}

#[test]
fn cloud_export_and_convert_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    small_dataset(dir.path());
    let ds = dir.path().to_str().unwrap();
    let pcd = dir.path().join("f0.pcd");
    let ply = dir.path().join("f0.ply");
    let out = pomona(&["cloud", ds, "--frame", "f0", "--out", pcd.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let organised = pomona_io::read_cloud(&pcd).unwrap();
    assert_eq!(organised.grid(), Some((4, 3)));
    assert_eq!(organised.valid_count(), 11);
    assert_eq!(organised.colors().unwrap()[0], [200, 30, 20]);
    // pixel (0, 0) at z = 0.5: x = (0 - 1.5) * 0.5 / 10 = -0.075, y = (0 - 1) * 0.5 / 10 = -0.05
    let p = organised.points()[0];
    assert!((p.x + 0.075).abs() < 1e-6 && (p.y + 0.05).abs() < 1e-6 && (p.z - 0.5).abs() < 1e-6);

    let out = pomona(&["convert", pcd.to_str().unwrap(), ply.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let dense = pomona_io::read_cloud(&ply).unwrap();
    assert_eq!(dense.len(), 12, "convert keeps every point, NaN included");
    assert_eq!(dense.valid_count(), 11);

    let ply2 = dir.path().join("direct.ply");
    let out = pomona(&[
        "cloud",
        ds,
        "--out",
        ply2.to_str().unwrap(),
        "--max-depth-m",
        "0.55",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let clipped = pomona_io::read_cloud(&ply2).unwrap();
    assert_eq!(
        clipped.len(),
        5,
        "PLY export drops invalid and clipped points"
    );
}

#[test]
fn cloud_rejects_unknown_frame_and_extension() {
    let dir = tempfile::tempdir().unwrap();
    small_dataset(dir.path());
    let ds = dir.path().to_str().unwrap();
    let out = pomona(&["cloud", ds, "--frame", "nope", "--out", "/tmp/x.ply"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("nope"));
    let bad = dir.path().join("x.xyz");
    let out = pomona(&["cloud", ds, "--out", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(!bad.exists());
}

#[test]
fn convert_reports_missing_input() {
    let out = pomona(&["convert", "/nonexistent/in.pcd", "/tmp/out.ply"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("/nonexistent/in.pcd"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn eval_scores_hand_made_detections() {
    let dir = tempfile::tempdir().unwrap();
    small_dataset(dir.path());
    let truth = r#"{"complete": true, "fruits": [
        {"id": "1", "kind": "apple", "center_m": [0.0, 0.0, 0.5], "diameter_m": 0.07, "visibility": 1.0},
        {"id": "2", "kind": "apple", "center_m": [0.2, 0.0, 0.5], "diameter_m": 0.08, "visibility": 1.0}]}"#;
    std::fs::create_dir_all(dir.path().join("truth")).unwrap();
    std::fs::write(dir.path().join("truth/f0.json"), truth).unwrap();
    let det_dir = dir.path().join("det");
    std::fs::create_dir_all(&det_dir).unwrap();
    // One hit 10 mm off with score 2, one false positive with score 1; fruit 2 is missed.
    let dets = r#"{"frame": "f0", "pipeline": "hand", "detections": [
        {"center_m": [0.01, 0.0, 0.5], "score": 2.0, "diameter_m": 0.072},
        {"center_m": [-0.3, 0.0, 0.5], "score": 1.0}]}"#;
    std::fs::write(det_dir.join("f0.json"), dets).unwrap();
    let report = dir.path().join("report.json");
    let out = pomona(&[
        "eval",
        "--data",
        dir.path().to_str().unwrap(),
        "--detections",
        det_dir.to_str().unwrap(),
        "--json",
        report.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(r["fruits"], 2);
    assert_eq!(r["precision"], 0.5);
    assert_eq!(r["recall"], 0.5);
    // PR points: (r 0.5, p 1.0) then (0.5, 0.5): VOC 11-point = 6/11 (recall 0..0.5 at p = 1).
    assert!(
        (r["ap_voc11"].as_f64().unwrap() - 6.0 / 11.0).abs() < 1e-9,
        "{r}"
    );
    assert!((r["center_error_m"]["median"].as_f64().unwrap() - 0.01).abs() < 1e-9);
    assert!((r["diameter_error_m"]["mean_abs"].as_f64().unwrap() - 0.002).abs() < 1e-9);
    assert!(stdout(&out).contains("AP (VOC 11-point)"));
}
