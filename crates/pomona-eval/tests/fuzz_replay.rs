//! Replays the `detection_json` fuzz corpus (`fuzz/corpus/detection_json/`) and the inputs that
//! once crashed the parser (`tests/fuzz_regressions/detection_json/`) through the fuzz target's
//! entry point on the stable toolchain: errors are fine, panics fail.
//!
//! `cargo test -p pomona-eval --test fuzz_replay -- --ignored write_seed` (re)writes the seed.

use std::path::{Path, PathBuf};

use pomona_eval::fuzzing::{detection_json, SEED, TARGET};
use pomona_io::fuzzing::replay_dir;

fn here() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn corpus_and_regressions_replay_without_panics() {
    let corpus = replay_dir(
        &here().join("../../fuzz/corpus").join(TARGET),
        detection_json,
    );
    let regressions = replay_dir(
        &here().join("tests/fuzz_regressions").join(TARGET),
        detection_json,
    );
    println!("{TARGET}: {corpus} corpus inputs, {regressions} regression inputs");
    assert!(corpus > 0, "no corpus for fuzz target {TARGET}");
}

#[test]
fn seed_parses() {
    let d: pomona_core::FrameDetections = serde_json::from_str(SEED).unwrap();
    assert_eq!(d.frame, "f");
    assert_eq!(d.detections.len(), 2);
    detection_json(SEED.as_bytes());
}

#[test]
#[ignore = "writes the seed input into fuzz/corpus/"]
fn write_seed() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/corpus")
        .join(TARGET);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("seed.json"), SEED).unwrap();
}
