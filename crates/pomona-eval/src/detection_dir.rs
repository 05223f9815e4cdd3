//! Reading a folder of detection files (`<dir>/<frame>.json`) against a dataset.
//!
//! A frame without a file is taken to have no detections (the detector may skip empty frames)
//! and reported in [`DetectionSet::missing`] so the caller can warn; a file for a frame the
//! dataset does not have is an error naming the file, because it almost always means the wrong
//! folder or dataset was given.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use pomona_core::FrameDetections;
use pomona_io::read_budget::{read_json_text, MAX_JSON_FILE_BYTES};
use pomona_io::Dataset;

use crate::EvalError;

/// Detections of a dataset's frames.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectionSet {
    /// Detections per frame that has a file.
    pub by_frame: BTreeMap<String, FrameDetections>,
    /// Dataset frames without a detection file, in frame order.
    pub missing: Vec<String>,
}

impl DetectionSet {
    /// Takes the detections of `frame` out of the set (none when it has no file).
    pub fn take(&mut self, frame: &str) -> Vec<pomona_core::Detection> {
        self.by_frame
            .remove(frame)
            .map(|d| d.detections)
            .unwrap_or_default()
    }

    /// The operating confidence every detection file records, when they all record the same
    /// one (the default operating point of an evaluation).
    pub fn recorded_operating_confidence(&self) -> Option<f64> {
        let mut values = self.by_frame.values().map(|d| d.operating_confidence);
        let first = values.next()??;
        values.all(|v| v == Some(first)).then_some(first)
    }
}

fn read_one(path: &Path, stem: &str) -> Result<FrameDetections, EvalError> {
    let text = read_json_text(path, MAX_JSON_FILE_BYTES).map_err(|source| EvalError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_detections(&text, path, stem)
}

/// Parses the text of the detection file `path` of frame `stem` and checks it (`path` only
/// names the file in errors).
pub(crate) fn parse_detections(
    text: &str,
    path: &Path,
    stem: &str,
) -> Result<FrameDetections, EvalError> {
    let d: FrameDetections =
        serde_json::from_str(text).map_err(|source| EvalError::DetectionJson {
            path: path.to_owned(),
            source,
        })?;
    if d.frame != stem {
        return Err(EvalError::FrameMismatch {
            path: path.to_owned(),
            stem: stem.to_owned(),
            frame: d.frame,
        });
    }
    if let Some(index) = d
        .detections
        .iter()
        .position(|x| !(x.score.is_finite() && x.center_m.iter().all(|c| c.is_finite())))
    {
        return Err(EvalError::NonFiniteDetection {
            path: path.to_owned(),
            index,
        });
    }
    Ok(d)
}

/// The file `pomona detect` writes into a detection folder listing the frames it could not
/// process (not a detection file; skipped here unless the dataset has a frame of that name).
pub const FAILURES_FILE: &str = "failures.json";

/// The failures file of a run: [`FAILURES_FILE`] for a whole run, `failures.shard-I-of-N.json`
/// for shard `I` (0-based) of `N` (`pomona detect --shard I/N`), so the shards of one run
/// writing into one folder never overwrite each other's list.
///
/// ```
/// assert_eq!(pomona_eval::failures_file(None), "failures.json");
/// assert_eq!(pomona_eval::failures_file(Some((2, 8))), "failures.shard-2-of-8.json");
/// ```
pub fn failures_file(shard: Option<(usize, usize)>) -> String {
    match shard {
        None => FAILURES_FILE.to_owned(),
        Some((index, count)) => format!("failures.shard-{index}-of-{count}.json"),
    }
}

/// Whether `stem` is the stem of a failures file ([`failures_file`] of a run or of a shard).
fn is_failures_stem(stem: &str) -> bool {
    let Some(rest) = stem.strip_prefix("failures") else {
        return false;
    };
    let numbered = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    rest.is_empty()
        || rest
            .strip_prefix(".shard-")
            .and_then(|r| r.split_once("-of-"))
            .is_some_and(|(i, n)| numbered(i) && numbered(n))
}

/// The frame whose detections the file at `path` holds, when it is a detection file name:
/// `<frame>.json` (extension in any case), not hidden, and not a failures file
/// ([`failures_file`]) unless `is_frame` says the dataset has a frame of that name. `pomona eval` and `pomona detect` use
/// this one rule for which files of a detection folder are frames'.
pub fn detection_file_frame(path: &Path, is_frame: impl Fn(&str) -> bool) -> Option<&str> {
    let is_json = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let stem = path.file_stem().and_then(|s| s.to_str())?;
    (is_json && !stem.starts_with('.') && (!is_failures_stem(stem) || is_frame(stem)))
        .then_some(stem)
}

/// Reads every `*.json` in `dir` (hidden files, other extensions and failures files are
/// skipped).
///
/// # Errors
/// [`EvalError::Io`] for an unreadable folder or file (or one over
/// [`pomona_io::read_budget::MAX_JSON_FILE_BYTES`]), [`EvalError::DetectionJson`],
/// [`EvalError::FrameMismatch`], [`EvalError::NonFiniteDetection`], and
/// [`EvalError::UnknownFrame`] for a file whose frame is not in `dataset`.
pub fn load_detections(dir: &Path, dataset: &Dataset) -> Result<DetectionSet, EvalError> {
    let io = |source| EvalError::Io {
        path: dir.to_owned(),
        source,
    };
    let mut files: Vec<(String, PathBuf)> = Vec::new();
    let known: std::collections::BTreeSet<&str> =
        dataset.frames().iter().map(String::as_str).collect();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        if let Some(stem) = detection_file_frame(&path, |f| known.contains(f)) {
            if path.is_file() {
                files.push((stem.to_owned(), path.clone()));
            }
        }
    }
    files.sort();
    let mut by_frame = BTreeMap::new();
    for (stem, path) in files {
        if !known.contains(stem.as_str()) {
            return Err(EvalError::UnknownFrame { path, frame: stem });
        }
        let d = read_one(&path, &stem)?;
        by_frame.insert(stem, d);
    }
    let missing = dataset
        .frames()
        .iter()
        .filter(|f| !by_frame.contains_key(*f))
        .cloned()
        .collect();
    Ok(DetectionSet { by_frame, missing })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failures_files_of_runs_and_shards_are_not_frames_unless_the_dataset_says_so() {
        let none = |_: &str| false;
        for name in [
            "failures.json",
            "failures.shard-0-of-2.json",
            "failures.shard-11-of-12.json",
        ] {
            assert_eq!(detection_file_frame(Path::new(name), none), None, "{name}");
            let stem = name.trim_end_matches(".json");
            assert_eq!(detection_file_frame(Path::new(name), |_| true), Some(stem));
        }
        for (name, stem) in [
            ("000001.json", "000001"),
            ("failures.shard-x-of-2.json", "failures.shard-x-of-2"),
            ("failures.shard-1.json", "failures.shard-1"),
            ("failures2.json", "failures2"),
        ] {
            assert_eq!(detection_file_frame(Path::new(name), none), Some(stem));
        }
        assert_eq!(detection_file_frame(Path::new(".x.json"), none), None);
        assert_eq!(detection_file_frame(Path::new("x.png"), none), None);
    }
}
