//! `pomona._pomona.write_failures`: the failures list of a detection run (`failures.json`)
//! written by the facade's code ([`pomona::write_failures`]), so the Dask runner's list is the
//! file `pomona detect` writes, with no second copy of its format in Python.

use std::path::PathBuf;

use pomona::FailedFrame;
use pyo3::prelude::*;

use crate::json_bridge::from_python;
use crate::py_error::to_py;

/// Writes ``<out>/failures.json`` as ``pomona detect`` does (atomically), listing ``failures``
/// of a run of ``pipeline`` that tried ``frames_tried`` frames, or removes an old one when
/// ``failures`` is empty. Each failure is a dict with ``frame``, ``file`` (``None`` or the file
/// at fault) and ``error`` (other keys are ignored, so the rows ``Detector.write_detections``
/// returns can be passed as they are).
///
/// Returns the path written, or ``None``. Raises ``PomonaError`` naming the file when it cannot
/// be written or removed, or for a failure without those keys.
#[pyfunction]
#[pyo3(signature = (out, pipeline, frames_tried, failures))]
pub fn write_failures(
    out: PathBuf,
    pipeline: &str,
    frames_tried: usize,
    failures: &Bound<'_, PyAny>,
) -> PyResult<Option<PathBuf>> {
    let failures: Vec<FailedFrame> = from_python(failures, "failures")?;
    pomona::write_failures(&out, None, pipeline, frames_tried, &failures).map_err(to_py)
}
