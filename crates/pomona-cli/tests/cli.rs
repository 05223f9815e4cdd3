//! End-to-end tests of the `pomona` binary: output on real and hand-made datasets, and the
//! one-line error and non-zero exit for broken input.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

#[path = "support/run.rs"]
mod run;
use run::{pomona, stderr, stdout, synth_dataset};

use std::path::{Path, PathBuf};
use std::process::Output;

use pomona_core::{ColorImage, DepthImage, PinholeCamera};
use pomona_io::DatasetWriter;

fn shared_data(rel: &str) -> Option<PathBuf> {
    pomona_test_support::shared_data(rel, "pomona-cli/tests/cli.rs")
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
    let eval = |extra: &[&str]| {
        let mut args = vec![
            "eval",
            "--data",
            dir.path().to_str().unwrap(),
            "--detections",
            det_dir.to_str().unwrap(),
            "--json",
            report.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        pomona(&args)
    };
    // A run that must succeed: its output and the report it wrote.
    let evaluated = |extra: &[&str]| -> (std::process::Output, serde_json::Value) {
        let out = eval(extra);
        assert!(out.status.success(), "{}", stderr(&out));
        let r = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        (out, r)
    };
    let (out, r) = evaluated(&[]);
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

    // --depth-range-m: a band holding both fruit changes nothing but the report's record of it;
    // one beyond them leaves no fruit counted, and a reversed band is refused by name.
    let (out, r) = evaluated(&["--depth-range-m", "0.4,0.6"]);
    assert_eq!(
        (r["fruits"].as_u64(), r["precision"].as_f64()),
        (Some(2), Some(0.5))
    );
    assert_eq!(r["depth_range_m"], serde_json::json!([0.4, 0.6]));
    assert!(stdout(&out).contains("0.4–0.6 m deep"), "{}", stdout(&out));
    let (_, r) = evaluated(&["--depth-range-m", "0.6,1.5"]);
    assert_eq!(
        (r["fruits"].as_u64(), r["ignored"].as_u64()),
        (Some(0), Some(2))
    );
    assert_eq!(r["false_positives"], 0);
    let out = eval(&["--depth-range-m", "1.0,0.5"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("NEAR < FAR"), "{}", stderr(&out));

    // --kind: fruit 2 becomes a reference ball; evaluating apples leaves it out (recall 1/1),
    // and a kind nobody has is a clear error.
    std::fs::write(
        dir.path().join("truth/f0.json"),
        truth.replacen(
            r#""id": "2", "kind": "apple""#,
            r#""id": "2", "kind": "reference_ball""#,
            1,
        ),
    )
    .unwrap();
    let (out, r) = evaluated(&["--kind", "apple"]);
    assert!(
        stderr(&out).contains("1 of other kinds left out"),
        "{}",
        stderr(&out)
    );
    assert_eq!(
        (r["fruits"].as_u64(), r["recall"].as_f64()),
        (Some(1), Some(1.0))
    );
    let out = eval(&["--kind", "pear"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("no truth object has kind pear"),
        "{}",
        stderr(&out)
    );
}

// ---------------------------------------------------------------------------------------------
// Pipeline-generic commands (`train`, `detect`, `experiment`, `demo`), driven through the library
// with a real test-only detector (`tests/support/blob.rs`) injected as the pipeline list.

#[path = "support/blob.rs"]
mod blob;

use blob::BlobPipeline;
use pomona_cli::commands::{calibrate, demo, detect, experiment, train};
use pomona_core::{Detection, FrameDetections};
use pomona_pipeline::{ModelFile, Pipeline};

fn only(p: BlobPipeline) -> Vec<Box<dyn Pipeline>> {
    vec![Box::new(p)]
}

fn train_args(pipeline: &str, data: &[&Path], out: &Path) -> train::TrainArgs {
    train::TrainArgs {
        pipeline: pipeline.into(),
        data: data.iter().map(|d| d.to_path_buf()).collect(),
        out: out.to_path_buf(),
        seed: 1,
        folds: 3,
        full_grid: false,
        threads: None,
        set: Vec::new(),
        calibration_folds: 3,
        cues: false,
        operating_precision: None,
    }
}

fn detect_args(
    pipeline: &str,
    model: Option<&Path>,
    data: &Path,
    out: &Path,
) -> detect::DetectArgs {
    detect::DetectArgs {
        pipeline: pipeline.into(),
        model: model.map(Path::to_path_buf),
        data: Some(data.to_path_buf()),
        recording: None,
        topics: Default::default(),
        out: out.to_path_buf(),
        timings: true,
        threads: None,
        set: Vec::new(),
        overlay: None,
        min_confidence: None,
        resume: false,
        rrd: None,
        shard: None,
    }
}

fn experiment_args(data: &Path, seed: u64, json: &Path) -> experiment::ExperimentArgs {
    experiment::ExperimentArgs {
        pipeline: blob::NAME.into(),
        data: Some(data.to_path_buf()),
        train: Vec::new(),
        test: Vec::new(),
        leave_one_out: false,
        calibration_folds: 3,
        cues: false,
        kind: Vec::new(),
        splits: 2,
        train_fraction: 0.5,
        seed,
        matching: Default::default(),
        threshold: 0.0,
        folds: 3,
        full_grid: false,
        json: Some(json.to_path_buf()),
        threads: None,
        set: Vec::new(),
        train_set: Vec::new(),
    }
}

fn read_detections(dir: &Path) -> Vec<FrameDetections> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files
        .iter()
        .map(|f| serde_json::from_str(&std::fs::read_to_string(f).unwrap()).unwrap())
        .collect()
}

#[test]
fn train_detect_eval_through_an_injected_pipeline() {
    let dir = tempfile::tempdir().unwrap();
    let (train_ds, test_ds) = (dir.path().join("train"), dir.path().join("test"));
    synth_dataset(&train_ds, 6, 11);
    synth_dataset(&test_ds, 4, 12);
    let pipelines = only(BlobPipeline::colour());
    let model = dir.path().join("blob.model.json");
    let t = train::run_with(&pipelines, &train_args("blob", &[&train_ds], &model)).unwrap();
    assert_eq!(t.frames, 6);
    assert!(t.support_vectors > 0);
    let m = ModelFile::load(&model, "blob").unwrap();
    assert_eq!(m.pipeline, "blob");

    // Two datasets at once.
    let model2 = dir.path().join("both.json");
    let t2 = train::run_with(
        &pipelines,
        &train_args("blob", &[&train_ds, &test_ds], &model2),
    )
    .unwrap();
    assert_eq!(t2.frames, 10);

    let det = dir.path().join("det");
    let d = detect::run_with(
        &pipelines,
        &detect_args("blob", Some(&model), &test_ds, &det),
    )
    .unwrap();
    assert_eq!(d.frames, 4);
    assert!(d.ms_per_frame.is_some());
    let stages: Vec<&str> = d.timings.entries().iter().map(|e| e.0).collect();
    assert_eq!(stages, ["blob-candidates", "svm", "nms"]);
    let files = read_detections(&det);
    assert_eq!(files.len(), 4);
    for (i, f) in files.iter().enumerate() {
        assert_eq!(f.frame, format!("{i:06}"));
        assert_eq!(f.pipeline, "blob");
    }
    assert_eq!(
        files.iter().map(|f| f.detections.len()).sum::<usize>(),
        d.detections
    );

    // Same files with one thread; --overlay draws one PNG of the frame's size per frame.
    let det1 = dir.path().join("det1");
    let mut one = detect_args("blob", Some(&model), &test_ds, &det1);
    one.threads = Some(1);
    let overlays = dir.path().join("overlays");
    one.overlay = Some(overlays.clone());
    detect::run_with(&pipelines, &one).unwrap();
    assert_eq!(read_detections(&det1), files);
    let ds = pomona_io::Dataset::open(&test_ds).unwrap();
    let color = ds.load_color("000000").unwrap().unwrap();
    let png = pomona_io::read_color_image(
        &overlays.join("000000.png"),
        (color.width(), color.height()),
    )
    .unwrap();
    assert_ne!(png, color, "something is drawn");
    assert_eq!(std::fs::read_dir(&overlays).unwrap().count(), 4);

    // The binary evaluates what the library wrote.
    let report = dir.path().join("report.json");
    let out = pomona(&[
        "eval",
        "--data",
        test_ds.to_str().unwrap(),
        "--detections",
        det.to_str().unwrap(),
        "--json",
        report.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert!(r["fruits"].as_u64().unwrap() > 0, "{r}");
    let ap = r["ap"].as_f64().unwrap();
    eprintln!("blob on 4 test frames: AP {ap:.3}, recall {}", r["recall"]);
    assert!(ap > 0.2, "a real detector finds some oranges: AP {ap}");

    // --set changes a stored stage parameter; a wrong key lists the real ones.
    let det2 = dir.path().join("det2");
    let mut set = detect_args("blob", Some(&model), &test_ds, &det2);
    set.set = vec!["nms_m=0.5".parse().unwrap()];
    let wide = detect::run_with(&pipelines, &set).unwrap();
    assert!(
        wide.detections < d.detections,
        "a wider NMS keeps fewer detections"
    );
    set.set = vec!["nms=0.5".parse().unwrap()];
    let err = format!("{:#}", detect::run_with(&pipelines, &set).unwrap_err());
    assert!(err.contains("nms_m") && err.contains("window_m"), "{err}");
}

#[test]
fn unknown_pipeline_errors_list_the_known_ones() {
    let dir = tempfile::tempdir().unwrap();
    let pipelines = only(BlobPipeline::colour());
    let args = train_args("nope", &[dir.path()], &dir.path().join("m.json"));
    let err = format!("{:#}", train::run_with(&pipelines, &args).unwrap_err());
    assert!(err.contains("unknown pipeline `nope`"), "{err}");
    assert!(err.contains("blob"), "{err}");
    let err = format!(
        "{:#}",
        detect::run_with(
            &pipelines,
            &detect_args("nope", None, dir.path(), dir.path())
        )
        .unwrap_err()
    );
    assert!(err.contains("blob"), "{err}");

    // The binary: one line, non-zero exit.
    for cmd in [
        &["detect", "--pipeline", "nope", "--data", "d", "--out", "o"][..],
        &[
            "train",
            "--pipeline",
            "nope",
            "--data",
            "d",
            "--out",
            "m.json",
        ],
        &["experiment", "--pipeline", "nope", "--data", "d"],
    ] {
        let out = pomona(cmd);
        assert!(!out.status.success());
        let err = stderr(&out);
        assert!(
            err.contains("unknown pipeline `nope`; known pipelines"),
            "{err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
}

#[test]
fn detect_without_any_model_and_with_a_foreign_model_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dir.path().join("ds");
    synth_dataset(&ds, 2, 5);
    let pipelines = only(BlobPipeline::colour());
    let out = dir.path().join("det");
    let err = format!(
        "{:#}",
        detect::run_with(&pipelines, &detect_args("blob", None, &ds, &out)).unwrap_err()
    );
    assert!(err.contains("no built-in model"), "{err}");
    assert!(err.contains("--model"), "{err}");

    let model = dir.path().join("m.json");
    train::run_with(&pipelines, &train_args("blob", &[&ds], &model)).unwrap();
    let text = std::fs::read_to_string(&model).unwrap();
    let foreign = dir.path().join("foreign.json");
    std::fs::write(&foreign, text.replace("\"blob\"", "\"shape-fit\"")).unwrap();
    let err = format!(
        "{:#}",
        detect::run_with(&pipelines, &detect_args("blob", Some(&foreign), &ds, &out)).unwrap_err()
    );
    assert!(
        err.contains("foreign.json") && err.contains("shape-fit"),
        "{err}"
    );
}

#[test]
fn colour_pipelines_refuse_depth_only_datasets() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dir.path().join("ds");
    synth_dataset(&ds, 2, 6);
    std::fs::remove_dir_all(ds.join("color")).unwrap();
    let depth_only = only(BlobPipeline::default());
    let model = dir.path().join("m.json");
    let mut targs = train_args("blob", &[&ds], &model);
    targs.calibration_folds = 0; // two frames: too few to calibrate the blob detector
    train::run_with(&depth_only, &targs).unwrap();
    let det = dir.path().join("det");
    detect::run_with(&depth_only, &detect_args("blob", Some(&model), &ds, &det))
        .expect("depth-only pipelines run without colour");

    let colour = only(BlobPipeline {
        needs_color: true,
        default_model: None,
    });
    for err in [
        detect::run_with(&colour, &detect_args("blob", Some(&model), &ds, &det)).unwrap_err(),
        train::run_with(&colour, &train_args("blob", &[&ds], &model)).unwrap_err(),
    ] {
        let err = format!("{err:#}");
        assert!(
            err.contains("no colour images") && err.contains("needs colour"),
            "{err}"
        );
        assert!(err.contains(ds.to_str().unwrap()), "{err}");
    }
}

#[test]
fn experiment_splits_are_seeded_and_reported() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dir.path().join("ds");
    synth_dataset(&ds, 8, 21);
    let pipelines = only(BlobPipeline::colour());
    let json = dir.path().join("exp.json");
    let a = experiment::run_with(&pipelines, &experiment_args(&ds, 3, &json)).unwrap();
    assert_eq!(a.per_split.len(), 2);
    assert_eq!(a.summary.splits, 2);
    for s in &a.per_split {
        assert_eq!((s.train_frames.len(), s.test_frames.len()), (4, 4));
        assert!(s.train_frames.iter().all(|f| !s.test_frames.contains(f)));
        assert_eq!(s.report.frames, 4);
        assert!(s.detect_ms_per_frame.is_some());
    }
    assert_ne!(a.per_split[0].test_frames, a.per_split[1].test_frames);
    assert!(a.summary.ap.is_some() && a.detect_ms_per_frame.is_some());
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(saved["per_split"].as_array().unwrap().len(), 2);
    assert!(saved["summary"]["ap"]["mean"].is_number(), "{saved}");
    assert!(saved["per_split"][0]["report"]["ap_voc11"].is_number());
    assert_eq!(
        saved["train_set"],
        serde_json::json!({}),
        "training overrides recorded"
    );

    let again = experiment::run_with(&pipelines, &experiment_args(&ds, 3, &json)).unwrap();
    let b = experiment::run_with(&pipelines, &experiment_args(&ds, 4, &json)).unwrap();
    let frames = |r: &experiment::ExperimentReport| -> Vec<Vec<String>> {
        r.per_split.iter().map(|s| s.test_frames.clone()).collect()
    };
    assert_eq!(frames(&a), frames(&again), "same seed, same splits");
    assert_eq!(
        a.summary.ap.map(|m| m.mean),
        again.summary.ap.map(|m| m.mean),
        "same seed, same result"
    );
    assert_ne!(frames(&a), frames(&b), "another seed, other splits");
}

#[test]
fn train_with_cues_stores_a_cue_calibration_that_detect_applies() {
    let dir = tempfile::tempdir().unwrap();
    let (train_ds, test_ds) = (dir.path().join("train"), dir.path().join("test"));
    synth_dataset(&train_ds, 8, 31);
    synth_dataset(&test_ds, 3, 32);
    let pipelines = only(BlobPipeline::colour());
    let (plain, with_cues) = (dir.path().join("plain.json"), dir.path().join("cues.json"));
    train::run_with(&pipelines, &train_args(blob::NAME, &[&train_ds], &plain)).unwrap();
    let mut args = train_args(blob::NAME, &[&train_ds], &with_cues);
    args.cues = true;
    train::run_with(&pipelines, &args).unwrap();
    let plain = ModelFile::load(&plain, blob::NAME).unwrap();
    let cued = ModelFile::load(&with_cues, blob::NAME).unwrap();
    assert!(plain.calibration.expect("calibrated").cues.is_none());
    let calibration = cued.calibration.expect("calibrated");
    let cues = calibration
        .cues
        .as_ref()
        .expect("--cues stores a cue regression");
    assert!(cues.weight.score > 0.0, "confidence rises with the score");
    // Same classifier: --cues changes only how the score becomes a confidence.
    assert_eq!(plain.svm, cued.svm);

    let det = dir.path().join("det");
    let mut dargs = detect_args(blob::NAME, Some(&with_cues), &test_ds, &det);
    dargs.min_confidence = Some(0.0);
    detect::run_with(&pipelines, &dargs).unwrap();
    let detections: Vec<Detection> = read_detections(&det)
        .into_iter()
        .flat_map(|f| f.detections)
        .collect();
    assert!(!detections.is_empty());
    for d in &detections {
        let c = d
            .confidence
            .expect("a calibrated model gives every detection a confidence");
        assert!((0.0..=1.0).contains(&c), "confidence {c}");
    }
}

/// The test pipeline with a model trained on 8 synthetic frames (seed 31, `dir/train`), written
/// to `dir/m.json`, and a second dataset `dir/<name>` of `frames` frames (`seed`) to test or
/// calibrate on: (pipelines, training data, model, other data).
fn trained_blob_model(
    dir: &Path,
    name: &str,
    frames: u32,
    seed: u64,
) -> (Vec<Box<dyn Pipeline>>, PathBuf, PathBuf, PathBuf) {
    let (train_ds, other_ds) = (dir.join("train"), dir.join(name));
    synth_dataset(&train_ds, 8, 31);
    synth_dataset(&other_ds, frames, seed);
    let pipelines = only(BlobPipeline::colour());
    let model = dir.join("m.json");
    train::run_with(&pipelines, &train_args(blob::NAME, &[&train_ds], &model)).unwrap();
    (pipelines, train_ds, model, other_ds)
}

fn calibrate_args(model: Option<&Path>, data: &Path, out: &Path) -> calibrate::CalibrateArgs {
    calibrate::CalibrateArgs {
        pipeline: blob::NAME.into(),
        model: model.map(Path::to_path_buf),
        data: vec![data.to_path_buf()],
        out: out.to_path_buf(),
        cues: false,
        operating_precision: None,
        threads: Some(1),
    }
}

#[test]
fn calibrate_refits_only_the_calibration_and_names_the_missing_model() {
    let dir = tempfile::tempdir().unwrap();
    let (pipelines, _, model, other_ds) = trained_blob_model(dir.path(), "other", 6, 33);

    // The test pipeline ships no model: without --model the message says how to get one.
    let refitted = dir.path().join("refit.json");
    let err = calibrate::run_with(&pipelines, &calibrate_args(None, &other_ds, &refitted))
        .expect_err("no built-in model");
    let message = format!("{err:#}");
    assert!(
        message.contains("has no built-in model") && message.contains("--model MODEL"),
        "{message}"
    );
    assert!(!refitted.exists(), "nothing written on error");

    let mut args = calibrate_args(Some(&model), &other_ds, &refitted);
    args.cues = true;
    calibrate::run_with(&pipelines, &args).unwrap();
    let before = ModelFile::load(&model, blob::NAME).unwrap();
    let after = ModelFile::load(&refitted, blob::NAME).unwrap();
    // Only how scores become confidences changes: same classifier, same stages.
    assert_eq!(before.svm, after.svm);
    assert_eq!(before.stage_params, after.stage_params);
    let calibration = after.calibration.expect("calibrated");
    assert!(calibration.cues.is_some(), "--cues stores a cue regression");
    assert!((0.0..=1.0).contains(&calibration.operating_confidence));
    assert_ne!(
        before.calibration,
        Some(calibration),
        "refitted on other frames"
    );
}

#[test]
fn calibrated_model_round_trips_and_sets_the_default_operating_point() {
    let dir = tempfile::tempdir().unwrap();
    let (pipelines, train_ds, model, test_ds) = trained_blob_model(dir.path(), "test", 3, 32);
    let saved = ModelFile::load(&model, blob::NAME).unwrap();
    let calibration = saved
        .calibration
        .expect("trained with calibration by default");
    assert!((0.0..=1.0).contains(&calibration.operating_confidence));
    // The operating threshold and the sigmoid survive the file bit for bit.
    let text = std::fs::read_to_string(&model).unwrap();
    let again = ModelFile::from_json(&text, &model, blob::NAME).unwrap();
    assert_eq!(again.calibration, Some(calibration));

    // Default: only detections at or above the operating confidence are written.
    let det = dir.path().join("det");
    detect::run_with(
        &pipelines,
        &detect_args(blob::NAME, Some(&model), &test_ds, &det),
    )
    .unwrap();
    let kept: Vec<Detection> = read_detections(&det)
        .into_iter()
        .flat_map(|f| {
            assert_eq!(
                f.operating_confidence,
                Some(calibration.operating_confidence)
            );
            f.detections
        })
        .collect();
    assert!(kept
        .iter()
        .all(|d| d.confidence.unwrap() >= calibration.operating_confidence));
    // --min-confidence 0 keeps everything; confidences rise with scores.
    let all_dir = dir.path().join("all");
    let mut args = detect_args(blob::NAME, Some(&model), &test_ds, &all_dir);
    args.min_confidence = Some(0.0);
    detect::run_with(&pipelines, &args).unwrap();
    let mut all: Vec<Detection> = read_detections(&all_dir)
        .into_iter()
        .flat_map(|f| f.detections)
        .collect();
    assert!(all.len() >= kept.len());
    all.sort_by(|a, b| a.score.total_cmp(&b.score));
    for w in all.windows(2) {
        assert!(w[0].confidence.unwrap() <= w[1].confidence.unwrap());
    }
    // An uncalibrated model refuses --min-confidence.
    let raw = dir.path().join("raw.json");
    let mut targs = train_args(blob::NAME, &[&train_ds], &raw);
    targs.calibration_folds = 0;
    train::run_with(&pipelines, &targs).unwrap();
    assert!(ModelFile::load(&raw, blob::NAME)
        .unwrap()
        .calibration
        .is_none());
    let mut args = detect_args(blob::NAME, Some(&raw), &test_ds, &dir.path().join("d2"));
    args.min_confidence = Some(0.5);
    let err = format!("{:#}", detect::run_with(&pipelines, &args).unwrap_err());
    assert!(err.contains("calibration"), "{err}");
    // By default it keeps what its classifier accepts (score ≥ 0, recorded as `min_score`);
    // --min-confidence 0 keeps every detection.
    let accepted_dir = dir.path().join("accepted");
    detect::run_with(
        &pipelines,
        &detect_args(blob::NAME, Some(&raw), &test_ds, &accepted_dir),
    )
    .unwrap();
    let accepted = read_detections(&accepted_dir);
    assert!(accepted
        .iter()
        .all(|f| f.min_score == Some(0.0) && f.min_confidence.is_none()));
    let accepted: Vec<Detection> = accepted.into_iter().flat_map(|f| f.detections).collect();
    assert!(accepted.iter().all(|d| d.score >= 0.0));
    let every_dir = dir.path().join("every");
    let mut args = detect_args(blob::NAME, Some(&raw), &test_ds, &every_dir);
    args.min_confidence = Some(0.0);
    detect::run_with(&pipelines, &args).unwrap();
    let every = read_detections(&every_dir);
    assert!(every
        .iter()
        .all(|f| f.min_score.is_none() && f.min_confidence.is_none()));
    let every: Vec<Detection> = every.into_iter().flat_map(|f| f.detections).collect();
    assert!(
        every.iter().any(|d| d.score < 0.0),
        "the blob detector scores some detections below 0"
    );
    assert_eq!(
        every.iter().filter(|d| d.score >= 0.0).count(),
        accepted.len()
    );
}

#[test]
fn incomplete_truth_leaves_the_model_uncalibrated_instead_of_failing() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dir.path().join("ds");
    synth_dataset(&ds, 6, 51);
    // Annotate only the first fruit of each frame and say the truth is incomplete.
    for entry in std::fs::read_dir(ds.join("truth")).unwrap() {
        let path = entry.unwrap().path();
        let mut truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        truth["complete"] = serde_json::Value::Bool(false);
        truth["fruits"].as_array_mut().unwrap().truncate(1);
        std::fs::write(&path, truth.to_string()).unwrap();
    }
    let pipelines = only(BlobPipeline::colour());
    let model = dir.path().join("m.json");
    train::run_with(&pipelines, &train_args(blob::NAME, &[&ds], &model)).unwrap();
    assert!(ModelFile::load(&model, blob::NAME)
        .unwrap()
        .calibration
        .is_none());
}

#[test]
fn cross_domain_experiment_refuses_shared_sets_and_leave_one_out_tests_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    synth_dataset(&a, 6, 41);
    synth_dataset(&b, 3, 42);
    let pipelines = only(BlobPipeline::colour());
    let json = dir.path().join("x.json");
    let mut args = experiment_args(&a, 1, &json);
    args.data = None;
    args.train = vec![a.clone()];
    // The same folder by another spelling is still the same set.
    args.test = vec![b.clone(), a.join("..").join("a")];
    let err = format!("{:#}", experiment::run_with(&pipelines, &args).unwrap_err());
    assert!(err.contains("both a training set"), "{err}");

    args.test = vec![b.clone()];
    let r = experiment::run_with(&pipelines, &args).unwrap();
    assert_eq!(r.protocol, experiment::Protocol::CrossDomain);
    assert_eq!(r.per_split.len(), 1);
    assert_eq!(r.per_split[0].test_frames.len(), 3);
    assert!(r.per_split[0].operating_confidence.is_some());
    assert_eq!(r.pooled.as_ref().map(|p| p.frames), Some(3));

    let mut loo = experiment_args(&b, 1, &json);
    loo.leave_one_out = true;
    loo.calibration_folds = 0;
    let r = experiment::run_with(&pipelines, &loo).unwrap();
    assert_eq!(r.protocol, experiment::Protocol::LeaveOneOut);
    let mut tested: Vec<String> = r
        .per_split
        .iter()
        .flat_map(|s| {
            assert_eq!((s.train_frames.len(), s.test_frames.len()), (2, 1));
            assert!(!s.train_frames.contains(&s.test_frames[0]));
            s.test_frames.clone()
        })
        .collect();
    tested.sort();
    tested.dedup();
    assert_eq!(tested.len(), 3, "every frame tested once");
    assert_eq!(r.pooled.as_ref().map(|p| p.frames), Some(3));
}

#[test]
fn demo_renders_data_detects_and_draws_overlays() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("demo");
    let args = [
        "demo",
        "--out",
        out_dir.to_str().unwrap(),
        "--frames",
        "2",
        "--seed",
        "3",
    ];
    let out = pomona(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    // Every registered pipeline with a built-in model runs and is evaluated.
    for p in pomona::pipelines()
        .iter()
        .filter(|p| p.default_model().is_some())
    {
        assert!(stdout(&out).contains(p.name()), "{}", stdout(&out));
        assert!(out_dir.join(p.name()).join("pr.png").exists());
        assert!(out_dir.join(p.name()).join("overlay/000001.png").exists());
        assert!(out_dir
            .join(p.name())
            .join("detections/000000.json")
            .exists());
    }
    for f in ["000000", "000001"] {
        let png = out_dir.join(format!("overlay/{f}.png"));
        let img = pomona_io::read_color_image(&png, (512, 424)).unwrap();
        assert_eq!(img.width(), 512);
        assert!(out_dir.join(format!("data/depth/{f}.png")).exists());
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("report.json")).unwrap())
            .unwrap();
    assert_eq!(report["frames"], 2);
    // Re-running over an earlier demo replaces it; a foreign non-empty folder is refused.
    let out = pomona(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let foreign = dir.path().join("mine");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "keep").unwrap();
    let out = pomona(&["demo", "--out", foreign.to_str().unwrap(), "--frames", "1"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("not empty"), "{}", stderr(&out));
    assert!(foreign.join("notes.txt").exists());
}

#[test]
fn demo_runs_pipelines_with_a_builtin_model() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dir.path().join("train");
    synth_dataset(&ds, 4, 31);
    let model = dir.path().join("m.json");
    train::run_with(
        &only(BlobPipeline::colour()),
        &train_args("blob", &[&ds], &model),
    )
    .unwrap();
    let text: &'static str = Box::leak(std::fs::read_to_string(&model).unwrap().into_boxed_str());
    let pipelines: Vec<Box<dyn Pipeline>> = vec![Box::new(BlobPipeline {
        needs_color: false,
        default_model: Some(text),
    })];
    let out = dir.path().join("demo");
    let report = demo::run_with(
        &pipelines,
        &demo::DemoArgs {
            out: out.clone(),
            frames: 2,
            seed: 2,
            threads: None,
        },
    )
    .unwrap();
    assert_eq!(report.pipelines.len(), 1);
    assert!(report.without_builtin_model.is_empty());
    assert_eq!(report.pipelines[0].report.frames, 2);
    // The fruit found per kind add up to the evaluation's true positives and scored fruit.
    let by_kind = &report.pipelines[0].found_by_kind;
    assert!(!by_kind.is_empty());
    let (found, fruits) = by_kind
        .values()
        .fold((0, 0), |(a, b), k| (a + k.found, b + k.fruits));
    assert_eq!(fruits, report.pipelines[0].report.fruits);
    assert_eq!(found, report.pipelines[0].report.true_positives);
    for f in ["000000", "000001"] {
        assert!(out.join(format!("blob/overlay/{f}.png")).exists());
        assert!(out.join(format!("overlay/{f}.png")).exists());
    }
    assert_eq!(read_detections(&out.join("blob/detections")).len(), 2);
    assert!(out.join("report.json").exists());
    if report.pipelines[0].report.pr_curve.is_some() {
        assert!(out.join("blob/pr.png").exists());
    }
}

/// `pomona detect --pipeline shape-fit` (the built-in model) on `data` into `out`, plus `extra`.
fn shape_fit_detect(data: &Path, out: &Path, extra: &[&str]) -> Output {
    run::detect("shape-fit", data, out, extra)
}

/// A depth unit ten times too large (the depth PNGs read as ten times farther) gets a warning
/// naming the unit; the right unit gets none.
#[test]
fn an_implausible_depth_unit_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth_dataset(&data, 1, 19);
    let out = shape_fit_detect(&data, &dir.path().join("right"), &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!stderr(&out).contains("depth_unit_m"), "{}", stderr(&out));
    let path = data.join("camera.json");
    let mut camera: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let unit = camera["depth_unit_m"].as_f64().unwrap();
    camera["depth_unit_m"] = (unit * 100.0).into();
    std::fs::write(&path, camera.to_string()).unwrap();
    let out = shape_fit_detect(&data, &dir.path().join("wrong"), &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("warning: the median depth of frame 000000")
            && stderr(&out).contains("depth_unit_m"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn built_in_shape_fit_detects_with_and_without_colour() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth_dataset(&data, 2, 17);
    for (label, drop_colour) in [("colour", false), ("depth-only", true)] {
        if drop_colour {
            std::fs::remove_dir_all(data.join("color")).unwrap();
        }
        let out_dir = dir.path().join(label);
        let out = shape_fit_detect(&data, &out_dir, &[]);
        assert!(out.status.success(), "{label}: {}", stderr(&out));
        let dets = read_detections(&out_dir);
        assert_eq!(dets.len(), 2, "{label}");
        assert!(dets.iter().all(|d| d.pipeline == "shape-fit"));
        assert!(
            dets.iter().any(|d| !d.detections.is_empty()),
            "{label}: nothing found"
        );
    }
}

/// A colour-only dataset (no `depth/`): `color-contour` still finds circles and places each on
/// the ray through its centre without a diameter; `pomona eval --2d` scores both runs, and on
/// colour-only data `eval` matches in the image even without `--2d`; depth pipelines refuse the
/// dataset, naming it.
#[test]
fn color_contour_runs_on_colour_only_data_and_eval_2d_scores_it() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth_dataset(&data, 2, 17);
    let eval = |det: &Path, report: &Path, extra: &[&str]| {
        let mut args = vec![
            "eval",
            "--threshold",
            "0",
            "--data",
            data.to_str().unwrap(),
            "--detections",
            det.to_str().unwrap(),
            "--json",
            report.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = pomona(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(report).unwrap()).unwrap();
        (json, out)
    };
    let detect = |label: &str| {
        let out_dir = dir.path().join(label);
        let out = run::detect("color-contour", &data, &out_dir, &["--min-confidence", "0"]);
        assert!(out.status.success(), "{label}: {}", stderr(&out));
        let dets = read_detections(&out_dir);
        let all: Vec<Detection> = dets.into_iter().flat_map(|f| f.detections).collect();
        assert!(!all.is_empty(), "{label}: nothing found");
        assert!(all
            .iter()
            .all(|d| d.center_px.is_some() && d.radius_px.is_some()));
        let (report, _) = eval(
            &out_dir,
            &dir.path().join(format!("{label}.json")),
            &["--2d"],
        );
        assert!(
            report["true_positives"].as_u64().unwrap() > 0,
            "{label}: {report}"
        );
        assert!(report["center_error_radii"]["median"].as_f64().unwrap() < 0.5);
        (out_dir, all)
    };
    let (_, with_depth) = detect("rgbd");
    assert!(with_depth.iter().all(|d| d.diameter_m.is_some()));

    std::fs::remove_dir_all(data.join("depth")).unwrap();
    let (colour_dir, colour_only) = detect("colour-only");
    let cam = pomona_io::Dataset::open(&data).unwrap().camera().to_owned();
    for d in &colour_only {
        assert_eq!(d.diameter_m, None);
        let on_ray = cam.project(&d.center_m).unwrap();
        assert!((on_ray - d.center_px.unwrap()).norm() < 1e-6);
    }
    let (explicit, _) = eval(&colour_dir, &dir.path().join("a.json"), &["--2d"]);
    let (implicit, out) = eval(&colour_dir, &dir.path().join("b.json"), &[]);
    assert!(
        stderr(&out).contains("matched in the image"),
        "{}",
        stderr(&out)
    );
    assert_eq!(explicit, implicit);

    let refused = shape_fit_detect(&data, &dir.path().join("sf"), &[]);
    assert!(!refused.status.success());
    let err = stderr(&refused);
    assert!(
        err.contains("no depth images") && err.contains("color-contour"),
        "{err}"
    );
    assert!(err.contains(data.to_str().unwrap()), "{err}");
}

// `pomona detect --rrd`: the recording is a real rerun file on disk, and decoding it back gives,
// per frame of the `frame` timeline, the detections the run wrote and the dataset's truth; a
// binary built without the `rerun` feature refuses `--rrd` saying so.

#[cfg(feature = "rerun")]
mod rrd_recording {
    use std::collections::{BTreeMap, BTreeSet};
    use std::path::Path;

    use pomona_core::FrameTruth;
    use rerun::components::{HalfSize3D, Text};
    use rerun::external::re_log_encoding::{DecoderApp, RRD_FOURCC};
    use rerun::log::{Chunk, LogMsg};
    use rerun::{Ellipsoids3D, TextDocument, TimelineName};

    use super::{read_detections, shape_fit_detect, stderr, stdout, synth_dataset};

    /// What a recording holds: its entities (static and per frame), the number of spheres per
    /// (entity, frame index), and the `frame` text per frame index.
    #[derive(Default)]
    struct Recorded {
        static_entities: BTreeSet<String>,
        frame_entities: BTreeSet<String>,
        spheres: BTreeMap<(String, i64), usize>,
        frame_texts: BTreeMap<i64, String>,
    }

    fn decode(path: &Path) -> Recorded {
        let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        let frame = TimelineName::from_static_str("frame");
        let half_sizes = Ellipsoids3D::descriptor_half_sizes().component;
        let text = TextDocument::descriptor_text().component;
        let mut recorded = Recorded::default();
        for msg in DecoderApp::decode_eager(file).unwrap() {
            let LogMsg::ArrowMsg(_, arrow) = msg.unwrap() else {
                continue;
            };
            let chunk = Chunk::from_arrow_msg(&arrow).unwrap();
            let entity = chunk.entity_path().to_string();
            let entity = entity.trim_start_matches('/').to_owned();
            if chunk.is_static() {
                recorded.static_entities.insert(entity);
                continue;
            }
            recorded.frame_entities.insert(entity.clone());
            let rows = chunk.iter_component::<HalfSize3D>(half_sizes);
            for ((t, _), row) in chunk.iter_component_indices(frame, half_sizes).zip(rows) {
                let key = (entity.clone(), t.as_i64());
                *recorded.spheres.entry(key).or_default() += row.len();
            }
            let rows = chunk.iter_component::<Text>(text);
            for ((t, _), row) in chunk.iter_component_indices(frame, text).zip(rows) {
                let line: String = row.iter().map(|s| s.as_str()).collect();
                recorded.frame_texts.insert(t.as_i64(), line);
            }
        }
        recorded
    }

    #[test]
    fn recording_holds_each_frames_images_cloud_truth_and_detections() {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("data");
        synth_dataset(&data, 2, 17);
        let (out, rrd) = (dir.path().join("det"), dir.path().join("run.rrd"));
        let run = shape_fit_detect(
            &data,
            &out,
            &["--threads", "2", "--rrd", rrd.to_str().unwrap()],
        );
        assert!(run.status.success(), "{}", stderr(&run));
        assert!(stdout(&run).contains("run.rrd"), "{}", stdout(&run));

        let bytes = std::fs::read(&rrd).unwrap();
        assert!(bytes.len() > 50_000, "only {} bytes", bytes.len());
        assert_eq!(bytes[..4], RRD_FOURCC);

        let recorded = decode(&rrd);
        for e in ["world", "world/camera", "run"] {
            assert!(recorded.static_entities.contains(e), "static {e} missing");
        }
        for e in [
            "world/camera/rgb",
            "world/camera/depth",
            "world/points",
            "world/truth",
            "world/detections",
            "frame",
        ] {
            assert!(recorded.frame_entities.contains(e), "{e} missing");
        }
        let written = read_detections(&out);
        assert_eq!(written.len(), 2);
        for (index, frame) in written.iter().enumerate() {
            let (index, stem) = (index as i64, &frame.frame);
            let count = |e: &str| recorded.spheres.get(&(e.to_owned(), index)).copied();
            assert_eq!(
                count("world/detections").unwrap_or(0),
                frame.detections.len(),
                "frame {stem}"
            );
            let truth_file = data.join("truth").join(format!("{stem}.json"));
            let truth: FrameTruth =
                serde_json::from_str(&std::fs::read_to_string(truth_file).unwrap()).unwrap();
            let placed = truth.fruits.iter().filter(|f| f.center_m.is_some()).count();
            assert!(placed > 0);
            assert_eq!(count("world/truth"), Some(placed), "frame {stem}");
            let text = &recorded.frame_texts[&index];
            assert!(text.contains(stem.as_str()), "{text}");
        }
        assert!(
            written.iter().any(|f| !f.detections.is_empty()),
            "shape-fit found nothing: the recording shows too little"
        );
    }

    #[test]
    fn an_unwritable_recording_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("data");
        synth_dataset(&data, 1, 17);
        let rrd = dir.path().join("no-such-folder").join("run.rrd");
        let run = shape_fit_detect(
            &data,
            &dir.path().join("det"),
            &["--rrd", rrd.to_str().unwrap()],
        );
        assert!(!run.status.success());
        let err = stderr(&run);
        assert!(err.contains("cannot create the recording"), "{err}");
        assert!(err.contains(rrd.to_str().unwrap()), "{err}");
    }
}

#[cfg(not(feature = "rerun"))]
#[test]
fn without_the_rerun_feature_rrd_is_refused_saying_why() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth_dataset(&data, 1, 17);
    let rrd = dir.path().join("run.rrd");
    let run = shape_fit_detect(
        &data,
        &dir.path().join("det"),
        &["--rrd", rrd.to_str().unwrap()],
    );
    assert!(!run.status.success());
    let err = stderr(&run);
    assert!(err.contains("without the `rerun` feature"), "{err}");
    assert!(!rrd.exists());
}

/// `pomona plan`: every reachable target in exactly one arm's list, unreachable ones listed,
/// times that add up to the makespan; `--exact` is never worse; a bad file is named.
#[test]
fn plan_assigns_every_reachable_target_once() {
    let dir = tempfile::tempdir().unwrap();
    let targets = dir.path().join("t.json");
    std::fs::write(
        &targets,
        r#"{"targets": [
            {"id": "left", "center_m": [-0.4, 0.0, 0.6]},
            {"id": "right", "center_m": [1.0, 0.0, 0.6]},
            {"id": "mid1", "center_m": [0.3, 0.1, 0.7]},
            {"id": "mid2", "center_m": [0.3, -0.1, 0.8]},
            {"id": "far", "center_m": [0.0, 0.0, 3.0]}]}"#,
    )
    .unwrap();
    let mut makespans = Vec::new();
    for extra in [&[][..], &["--exact"][..]] {
        let out = dir.path().join("plan.json");
        let mut args = vec![
            "plan",
            "--targets",
            targets.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let run = pomona(&args);
        assert!(run.status.success(), "{}", stderr(&run));
        let plan: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
        let ids = |v: &serde_json::Value| -> Vec<String> {
            v.as_array()
                .unwrap()
                .iter()
                .map(|s| s.as_str().unwrap().to_owned())
                .collect()
        };
        let (a, b) = (ids(&plan["arms"]["a"]), ids(&plan["arms"]["b"]));
        assert!(
            a.contains(&"left".to_owned()) && b.contains(&"right".to_owned()),
            "{plan}"
        );
        assert_eq!(ids(&plan["unreachable"]), vec!["far"]);
        let mut all: Vec<String> = a.into_iter().chain(b).collect();
        all.sort();
        assert_eq!(all, vec!["left", "mid1", "mid2", "right"]);
        let t = |k: &str| plan["time_s"][k].as_f64().unwrap();
        let makespan = plan["makespan_s"].as_f64().unwrap();
        assert!((makespan - t("a").max(t("b"))).abs() < 1e-9);
        makespans.push(makespan);
    }
    assert!(makespans[1] <= makespans[0] + 1e-9, "{makespans:?}");

    std::fs::write(
        &targets,
        r#"{"targets": [{"id": "x", "center_m": [0, 0]}]}"#,
    )
    .unwrap();
    let bad = pomona(&[
        "plan",
        "--targets",
        targets.to_str().unwrap(),
        "--out",
        dir.path().join("p2.json").to_str().unwrap(),
    ]);
    assert!(!bad.status.success());
    assert!(
        stderr(&bad).contains(targets.to_str().unwrap()),
        "{}",
        stderr(&bad)
    );
}
