//! Model files: bit-exact round trip and typed rejection of foreign files.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use pomona_learn::{ModelFile, ModelFileError, SvmParams, TrainingSet, MODEL_VERSION};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn trained() -> pomona_learn::SvmClassifier {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let rows: Vec<Vec<f64>> = (0..80)
        .map(|_| {
            (0..5)
                .map(|_| rng.gen_range(-1e3..1e3) * rng.gen::<f64>())
                .collect()
        })
        .collect();
    let labels = rows.iter().map(|r| r[0] * r[1] > 0.0).collect();
    let data = TrainingSet::from_rows(&rows, labels).unwrap();
    SvmParams::default()
        .c(3.7)
        .gamma(0.123456789)
        .probability(true)
        .check()
        .unwrap()
        .fit(&data)
        .unwrap()
}

#[test]
fn round_trip_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.json");
    let model = trained();
    let file = ModelFile::new(
        "shape-fit",
        serde_json::json!({"window_m": 0.12, "bins": 8}),
        &model,
    );
    file.save(&path).unwrap();
    let back = ModelFile::load(&path, "shape-fit").unwrap();
    assert_eq!(back, file);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(
        bits(&back.svm.support_vectors),
        bits(&file.svm.support_vectors)
    );
    assert_eq!(bits(&back.svm.coef), bits(&file.svm.coef));
    assert_eq!(back.svm.rho.to_bits(), file.svm.rho.to_bits());
    let s = back.scaler.as_ref().unwrap();
    assert_eq!(bits(&s.min), bits(&model.scaler.as_ref().unwrap().min));
    // Same scores from the loaded model, bit for bit.
    let loaded = back.classifier();
    for x in [[1.0, -2.0, 3.0, 0.5, 7.0], [-400.0, 2.0, 0.0, 1e-9, 12.5]] {
        assert_eq!(
            loaded.decision_value(&x).unwrap().to_bits(),
            model.decision_value(&x).unwrap().to_bits()
        );
    }
}

#[test]
fn awkward_floats_round_trip_exactly() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let mut model = trained();
    let mut values: Vec<f64> = (0..5000)
        .map(|_| f64::from_bits(rng.gen::<u64>() >> 2))
        .collect();
    values.extend([
        f64::MIN_POSITIVE,
        5e-324,
        0.1 + 0.2,
        -0.0,
        f64::MAX,
        1.0 / 3.0,
    ]);
    values.retain(|v| v.is_finite());
    model.svm.coef = values.clone();
    model.svm.n_features = 1;
    model.svm.support_vectors = values.clone();
    model.svm.n_support_negative = values.len();
    model.svm.n_support_positive = 0;
    model.scaler = None;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.json");
    ModelFile::new("p", serde_json::Value::Null, &model)
        .save(&path)
        .unwrap();
    let back = ModelFile::load(&path, "p").unwrap();
    for (a, b) in back.svm.coef.iter().zip(&values) {
        assert_eq!(a.to_bits(), b.to_bits(), "{b:e}");
    }
}

#[test]
fn other_version_pipeline_or_format_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.json");
    ModelFile::new("shape-fit", serde_json::json!({}), &trained())
        .save(&path)
        .unwrap();
    let err = ModelFile::load(&path, "symmetry").unwrap_err();
    assert!(matches!(err, ModelFileError::Pipeline { ref found, .. } if found == "shape-fit"));
    assert!(err.to_string().contains("model.json"), "{err}");

    let text = std::fs::read_to_string(&path).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["version"] = serde_json::json!(MODEL_VERSION + 1);
    v["svm"] = serde_json::json!("a future layout");
    std::fs::write(&path, v.to_string()).unwrap();
    let err = ModelFile::load(&path, "shape-fit").unwrap_err();
    assert!(
        matches!(err, ModelFileError::Version { found, .. } if found == u64::from(MODEL_VERSION) + 1)
    );
    assert!(err.to_string().contains("model.json"));

    std::fs::write(&path, r#"{"format": "something-else"}"#).unwrap();
    assert!(matches!(
        ModelFile::load(&path, "shape-fit"),
        Err(ModelFileError::NotAModel { .. })
    ));
    std::fs::write(&path, "{not json").unwrap();
    assert!(matches!(
        ModelFile::load(&path, "shape-fit"),
        Err(ModelFileError::Json { .. })
    ));
    assert!(matches!(
        ModelFile::load(dir.path().join("missing.json"), "shape-fit"),
        Err(ModelFileError::Io { .. })
    ));
}

#[test]
fn inconsistent_model_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.json");
    let mut file = ModelFile::new("p", serde_json::json!({}), &trained());
    file.svm.coef.pop();
    std::fs::write(&path, serde_json::to_string(&file).unwrap()).unwrap();
    assert!(matches!(
        ModelFile::load(&path, "p"),
        Err(ModelFileError::Invalid { .. })
    ));
}

/// A calibration a model file cannot honestly carry — an operating confidence outside [0, 1]
/// (keeping every detection or none) or a sigmoid that falls with the score — is refused with
/// the file's name; a fitted one loads.
#[test]
fn impossible_calibration_is_rejected_by_name() {
    use pomona_learn::{OperatingPoint, ScoreCalibration};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.json");
    let scores = [-2.0, -1.0, -0.5, 0.2, 0.8, 1.5, 2.5, -0.2];
    let is_true = [false, false, true, false, true, true, true, false];
    let fitted = ScoreCalibration::fit(&scores, &is_true, 5, OperatingPoint::MaxF1).unwrap();
    let mut file = ModelFile::new("p", serde_json::json!({}), &trained());
    file.calibration = Some(fitted);
    file.save(&path).unwrap();
    assert_eq!(
        ModelFile::load(&path, "p").unwrap().calibration,
        Some(fitted)
    );
    for (broken, said) in [
        (
            ScoreCalibration {
                operating_confidence: 3.0,
                ..fitted
            },
            "operating_confidence",
        ),
        (
            ScoreCalibration {
                sigmoid: pomona_learn::PlattSigmoid {
                    a: -fitted.sigmoid.a,
                    ..fitted.sigmoid
                },
                ..fitted
            },
            "sigmoid",
        ),
    ] {
        file.calibration = Some(broken);
        std::fs::write(&path, serde_json::to_string(&file).unwrap()).unwrap();
        let err = ModelFile::load(&path, "p").unwrap_err();
        assert!(matches!(err, ModelFileError::Invalid { .. }), "{err}");
        let text = err.to_string();
        assert!(text.contains(said) && text.contains("model.json"), "{text}");
    }
}
