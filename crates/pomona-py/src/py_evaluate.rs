//! `pomona.evaluate(...)`: score a folder of detection files against a dataset's truth, as
//! `pomona eval` does, and return the report (the JSON of `pomona eval --json`) as a dict.

use std::path::PathBuf;

use pomona_eval::{load_detections, EvalConfig, FrameInput};
use pyo3::prelude::*;

use crate::json_bridge::to_python;
use crate::py_error::to_py;

/// Scores the detection files in ``detections`` against the truth of dataset ``data``: VOC
/// 11-point and all-point AP, precision and recall at the operating point, centre and diameter
/// errors. Returns the report dict (the JSON ``pomona eval --json`` writes).
///
/// A detection matches a fruit within ``tolerance_mm`` of its centre, or with ``image_2d`` (and
/// always on data without depth) when its image circle's centre is within half the fruit's image
/// radius, as ``pomona eval --2d``; truth less visible than ``min_visibility`` is ignored, and
/// with ``depth_range_m = (near, far)`` so is truth outside that band of depths (metres), with
/// unmatched detections outside it (``pomona eval --depth-range-m``). The operating point is
/// ``min_confidence`` when given, else score ``threshold`` when given, else the operating
/// confidence the files record (score 0 for uncalibrated models). Frames without a detection
/// file count as having none; frames without truth are left out.
///
/// Raises ``PomonaError`` for unreadable files (naming them), a detection file of a frame the
/// dataset lacks, a dataset without truth, or invalid parameters.
#[pyfunction]
#[allow(clippy::too_many_arguments)] // one per keyword argument of the Python function
#[pyo3(signature = (data, detections, *, tolerance_mm = 50.0, min_visibility = 0.5, min_confidence = None, threshold = None, image_2d = false, depth_range_m = None))]
pub fn evaluate<'py>(
    py: Python<'py>,
    data: PathBuf,
    detections: PathBuf,
    tolerance_mm: f64,
    min_visibility: f64,
    min_confidence: Option<f64>,
    threshold: Option<f64>,
    image_2d: bool,
    depth_range_m: Option<(f64, f64)>,
) -> PyResult<Bound<'py, PyAny>> {
    let dataset = pomona::Dataset::open(&data).map_err(to_py)?;
    let mut found = load_detections(&detections, &dataset).map_err(to_py)?;
    let recorded = found.recorded_operating_confidence();
    let config = EvalConfig {
        tolerance_m: tolerance_mm / 1000.0,
        min_visibility,
        threshold: threshold.unwrap_or(0.0),
        min_confidence: match (min_confidence, threshold) {
            (Some(c), _) => Some(c),
            (None, Some(_)) => None,
            (None, None) => recorded,
        },
        radius_fraction_2d: image_2d
            .then(|| EvalConfig::image_2d().radius_fraction_2d)
            .flatten(),
        depth_range_m,
    }
    .for_data(dataset.has_depth());
    let mut frames = Vec::new();
    for stem in dataset.frames() {
        if let Some(truth) = dataset.load_truth(stem).map_err(to_py)? {
            frames.push(FrameInput {
                frame: stem.clone(),
                truth,
                detections: found.take(stem),
            });
        }
    }
    if frames.is_empty() {
        return Err(to_py(format!(
            "{}: no frame has a truth file (truth/<frame>.json), nothing to evaluate",
            data.display()
        )));
    }
    let report = py
        .detach(|| pomona_eval::evaluate(&frames, dataset.camera(), &config))
        .map_err(to_py)?;
    to_python(py, &report)
}
