//! Replays the `model_file` fuzz corpus (`fuzz/corpus/model_file/`) and the inputs that once
//! crashed the parser (`tests/fuzz_regressions/model_file/`) through the fuzz target's entry
//! point on the stable toolchain: errors are fine, panics fail.
//!
//! `cargo test -p pomona-learn --test fuzz_replay -- --ignored write_seed` (re)writes the seed.

use std::path::{Path, PathBuf};

use pomona_io::fuzzing::replay_target;
use pomona_learn::fuzzing::{model_json, seed, PIPELINE, TARGET};
use pomona_learn::ModelFile;

fn here() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn corpus_and_regressions_replay_without_panics() {
    replay_target(&here(), TARGET, model_json);
}

#[test]
fn seed_loads() {
    let text = seed();
    let model = ModelFile::from_json(&text, Path::new("seed.json"), PIPELINE).unwrap();
    assert_eq!(model.svm.n_features, 2);
    assert!(model.calibration.is_some());
    model_json(text.as_bytes());
}

#[test]
fn overflowing_support_vector_counts_are_invalid_not_a_panic() {
    let text = seed();
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    value["svm"]["n_features"] = serde_json::json!(u64::MAX);
    value["svm"]["support_vectors"] = serde_json::json!([]);
    let err = ModelFile::from_json(&value.to_string(), Path::new("m.json"), PIPELINE).unwrap_err();
    assert!(err.to_string().contains("m.json"), "{err}");
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    value["svm"]["n_support_negative"] = serde_json::json!(u64::MAX);
    let err = ModelFile::from_json(&value.to_string(), Path::new("m.json"), PIPELINE).unwrap_err();
    assert!(err.to_string().contains("m.json"), "{err}");
}

#[test]
#[ignore = "writes the seed input into fuzz/corpus/"]
fn write_seed() {
    let dir = here().join("../../fuzz/corpus").join(TARGET);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("seed.json"), seed()).unwrap();
}
