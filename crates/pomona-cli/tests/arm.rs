//! `pomona arm train` / `pomona arm eval`: a small network trained and evaluated end to end on
//! the simulated robot, and clear errors for a bad model file.

#[path = "support/run.rs"]
mod run;
use run::{pomona, stderr, stdout};

#[test]
fn arm_train_then_eval_reports_errors_beside_equation_18() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("arm.json");
    let train = pomona(&[
        "arm",
        "train",
        "--out",
        model.to_str().unwrap(),
        "--seed",
        "3",
        "--grid",
        "7,5,9",
        "--restarts",
        "1",
        "--iterations",
        "150",
    ]);
    assert!(train.status.success(), "{}", stderr(&train));
    assert!(stdout(&train).contains("4-8-3"), "{}", stdout(&train));
    let saved: serde_json::Value = serde_json::from_slice(&std::fs::read(&model).unwrap()).unwrap();
    assert_eq!(saved["format"], "pomona-arm-model");
    assert_eq!(saved["calibration_seed"], 3);
    assert_eq!(saved["network"]["weights"].as_array().unwrap().len(), 67);

    let report_path = dir.path().join("r.json");
    let eval = pomona(&[
        "arm",
        "eval",
        "--model",
        model.to_str().unwrap(),
        "--targets",
        "300",
        "--json",
        report_path.to_str().unwrap(),
    ]);
    assert!(eval.status.success(), "{}", stderr(&eval));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&report_path).unwrap()).unwrap();
    let median = |v: &serde_json::Value| v["error_mm"]["median"].as_f64().unwrap();
    let network = median(&report["network"]);
    let eq18 = median(&report["eq18_nominal"]);
    let eq18_ideal = median(&report["calibration_errors_off"]["eq18_nominal"]);
    assert_eq!(report["network"]["count"], 300);
    // Even a small network learns around the calibration errors Eq. 18 does not know.
    assert!(network < eq18, "network {network} mm, Eq. 18 {eq18} mm");
    assert!(
        eq18_ideal < 1e-3,
        "Eq. 18 is exact without errors: {eq18_ideal} mm"
    );
    assert!(report["network"]["error_mm"]["p95"].as_f64().unwrap() >= network);

    // A file that is not a model is named in a one-line error.
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, r#"{"format": "pomona-model", "version": 1}"#).unwrap();
    let run = pomona(&["arm", "eval", "--model", bad.to_str().unwrap()]);
    assert!(!run.status.success());
    let err = stderr(&run);
    assert!(
        err.contains("bad.json") && err.contains("pomona-arm-model"),
        "{err}"
    );
}
