//! The parser entry point of the `detection_json` fuzz target in the repository's `fuzz/`
//! folder, and a seed input for it.
//!
//! The fuzz target and the replay test (`tests/fuzz_replay.rs`) both call [`detection_json`], so
//! the code fuzzed and the code replayed on the stable toolchain cannot drift apart. Not part of
//! the supported API.

use std::path::Path;

/// Name of the fuzz target, as in `fuzz/Cargo.toml`.
pub const TARGET: &str = "detection_json";

/// Parses `data` as the detection file of frame `f`, through the detection folder reader's own
/// parser and checks; an error is an expected outcome, a panic is a bug.
pub fn detection_json(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = crate::detection_dir::parse_detections(text, Path::new("fuzz/f.json"), "f");
    }
}

/// A detection file of frame `f` with every optional field.
pub const SEED: &str = r#"{"frame": "f", "pipeline": "shape-fit", "operating_confidence": 0.5,
 "detections": [{"center_m": [0.1, -0.2, 0.5], "score": 1.5, "diameter_m": 0.07,
  "axis": [0, 0, 1], "bbox_px": [1, 2, 3, 4], "kind": "apple", "support_points": 12,
  "fit_rms_m": 0.001, "confidence": 0.9}, {"center_m": [0, 0, 1], "score": -0.25}]}"#;
