//! Replays the `detection_json` fuzz corpus (`fuzz/corpus/detection_json/`) and the inputs that
//! once crashed the parser (`tests/fuzz_regressions/detection_json/`) through the fuzz target's
//! entry point on the stable toolchain: errors are fine, panics fail.
//!
//! `cargo test -p pomona-eval --test fuzz_replay -- --ignored write_seed` (re)writes the seed.

use std::path::PathBuf;

use pomona_eval::fuzzing::{detection_json, SEED, TARGET};
use pomona_io::fuzzing::replay_target;

fn here() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn corpus_and_regressions_replay_without_panics() {
    replay_target(&here(), TARGET, detection_json);
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
    let dir = here().join("../../fuzz/corpus").join(TARGET);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("seed.json"), SEED).unwrap();
}
