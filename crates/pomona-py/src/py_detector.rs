//! `pomona.Detector`: a detector loaded once (built-in model or a model file, with parameter
//! overrides) and called on many frames, from numpy arrays or straight from a dataset folder.
//!
//! Both calls return or write exactly what `pomona detect` writes: the same facade detector,
//! the same threshold rule ([`pomona::Detector::keep_rule_for`]) and the same
//! detection file record ([`pomona::Detector::frame_record`]). Detection runs with the GIL
//! released. `prepare_folder` applies `pomona detect`'s output-folder rules
//! ([`pomona::prepare_detection_folder`]) for runners such as the Dask one.

use std::path::{Path, PathBuf};
use std::time::Instant;

use pomona::RgbdFrame;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::frame_arrays::frame_from_arrays;
use crate::json_bridge::{overrides_from, to_python};
use crate::py_error::to_py;

/// A fruit detector of one pipeline, loaded once and called many times (thread-safe; the GIL is
/// released while it detects).
///
/// ``Detector("shape-fit")`` loads the pipeline's built-in model; ``model="m.json"`` a model
/// file from ``pomona train``; ``set={"key": value}`` overrides stage parameters (dotted keys,
/// as ``pomona detect --set``).
#[pyclass(frozen, module = "pomona")]
pub struct Detector {
    inner: pomona::Detector,
}

impl Detector {
    /// The dataset folder `data`, checked to suit this detector's pipeline, and `frames` of it
    /// (default: all), checked to exist.
    fn open_dataset(
        &self,
        data: &Path,
        frames: Option<Vec<String>>,
    ) -> PyResult<(pomona::Dataset, Vec<String>)> {
        let dataset = pomona::Dataset::open(data).map_err(to_py)?;
        let pipeline = pomona::pipeline(self.inner.pipeline()).map_err(to_py)?;
        if pipeline.needs_color() && !dataset.has_color() {
            return Err(to_py(format!(
                "{} has no colour images (no color/ folder), and pipeline `{}` needs colour",
                data.display(),
                self.inner.pipeline()
            )));
        }
        let frames = frames.unwrap_or_else(|| dataset.frames().to_vec());
        if let Some(unknown) = frames.iter().find(|f| !dataset.frames().contains(f)) {
            return Err(to_py(format!(
                "{} has no frame `{unknown}`",
                data.display()
            )));
        }
        Ok((dataset, frames))
    }

    /// Detections of `frame` kept by the rule `min_confidence` gives, as the detection file's
    /// list.
    fn detect_frame(
        &self,
        py: Python<'_>,
        frame: &RgbdFrame,
        min_confidence: Option<f64>,
    ) -> PyResult<pomona::FrameDetections> {
        let keep = self.inner.keep_rule_for(min_confidence).map_err(to_py)?;
        let found = py.detach(|| self.inner.detect(frame)).map_err(to_py)?;
        Ok(self
            .inner
            .frame_record("", frame.color().is_some(), &found, keep))
    }
}

/// The detector of `pipeline`: the built-in model or the file `model`, with `overrides`.
/// Shared by `Detector` and `StereoLocator`.
pub(crate) fn load_detector(
    pipeline: &str,
    model: Option<PathBuf>,
    overrides: Vec<pomona::ParamOverride>,
) -> PyResult<pomona::Detector> {
    let mut builder = pomona::Detector::builder(pipeline).map_err(to_py)?;
    if let Some(path) = model {
        builder = builder.model_file(path);
    }
    builder.overrides(overrides).build().map_err(to_py)
}

#[pymethods]
impl Detector {
    #[new]
    #[pyo3(signature = (pipeline = "shape-fit", model = None, set = None))]
    fn new(
        pipeline: &str,
        model: Option<PathBuf>,
        set: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        Ok(Self {
            inner: load_detector(pipeline, model, overrides_from(set)?)?,
        })
    }

    /// The pipeline's name (as written into detection files).
    #[getter]
    fn pipeline(&self) -> &'static str {
        self.inner.pipeline()
    }

    /// The model's identity: 16 hex digits, as detection files record it.
    #[getter]
    fn model_id(&self) -> String {
        self.inner.model().id.clone()
    }

    /// The model's operating confidence (``None`` for a model without calibration): the
    /// default ``min_confidence``.
    #[getter]
    fn operating_confidence(&self) -> Option<f64> {
        self.inner.operating_confidence()
    }

    /// Finds fruit in one frame.
    ///
    /// ``depth``: (H, W) uint16 in ``camera["depth_unit_m"]`` units (0 = no reading) or float32
    /// metres; ``color``: (H, W, 3) uint8 RGB or ``None``; ``camera``: a dict with the keys of
    /// ``camera.json``. Returns a list of dicts with the detection JSON's keys (``center_m`` in
    /// the camera frame, metres; ``score``; ``confidence``; ``diameter_m``...). ``min_confidence``
    /// ``None`` keeps those at the model's operating confidence (as ``pomona detect``; score ≥ 0
    /// for a model without calibration), ``0.0`` keeps every detection.
    ///
    /// Raises ``TypeError`` for arrays of another dtype or shape, ``PomonaError`` for sizes that
    /// disagree, an invalid camera or a threshold the model cannot apply.
    #[pyo3(signature = (depth, color = None, *, camera, min_confidence = None))]
    fn detect<'py>(
        &self,
        py: Python<'py>,
        depth: &Bound<'py, PyAny>,
        color: Option<&Bound<'py, PyAny>>,
        camera: &Bound<'py, PyAny>,
        min_confidence: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let color = color.filter(|c| !c.is_none());
        let frame = frame_from_arrays(depth, color, camera)?;
        let record = self.detect_frame(py, &frame, min_confidence)?;
        to_python(py, &record.detections)
    }

    /// Detects in frames of the dataset folder ``data`` and writes ``<out>/<frame>.json`` for
    /// each, byte-identical to ``pomona detect``'s files; one frame after another on this
    /// thread, with the GIL released. ``frames``: stems to do (default: all).
    ///
    /// Returns one dict per frame: ``frame``, ``detections`` (number written), ``seconds``
    /// (detection time, reading and writing excluded), ``error`` (``None``, or why the frame failed: a failure does not stop
    /// the others) and ``file`` (the dataset file at fault, when known).
    ///
    /// Raises ``PomonaError`` for an unreadable dataset, an unknown frame, a colour pipeline on a
    /// colour-less dataset, or a threshold the model cannot apply.
    #[pyo3(signature = (data, out, frames = None, *, min_confidence = None))]
    fn write_detections<'py>(
        &self,
        py: Python<'py>,
        data: PathBuf,
        out: PathBuf,
        frames: Option<Vec<String>>,
        min_confidence: Option<f64>,
    ) -> PyResult<Bound<'py, PyList>> {
        let keep = self.inner.keep_rule_for(min_confidence).map_err(to_py)?;
        let (dataset, frames) = self.open_dataset(&data, frames)?;
        std::fs::create_dir_all(&out)
            .map_err(|e| to_py(format!("cannot create {}: {e}", out.display())))?;
        let results = py.detach(|| {
            frames
                .iter()
                .map(|stem| {
                    let mut seconds = 0.0;
                    let written = (|| -> Result<usize, pomona::Error> {
                        let frame = dataset.load_frame(stem)?;
                        let started = Instant::now();
                        let found = self.inner.detect(&frame)?;
                        seconds = started.elapsed().as_secs_f64();
                        let record =
                            self.inner
                                .frame_record(stem, frame.color().is_some(), &found, keep);
                        pomona_io::write_json(&out.join(format!("{stem}.json")), &record)?;
                        Ok(record.detections.len())
                    })();
                    (stem, written, seconds)
                })
                .collect::<Vec<_>>()
        });
        let list = PyList::empty(py);
        for (stem, written, seconds) in results {
            let row = PyDict::new(py);
            row.set_item("frame", stem)?;
            row.set_item("seconds", seconds)?;
            match written {
                Ok(n) => {
                    row.set_item("detections", n)?;
                    row.set_item("error", py.None())?;
                    row.set_item("file", py.None())?;
                }
                Err(e) => {
                    row.set_item("detections", 0)?;
                    row.set_item("error", e.to_string())?;
                    let file = match &e {
                        pomona::Error::Dataset(d) => Some(d.path().display().to_string()),
                        _ => None,
                    };
                    row.set_item("file", file)?;
                }
            }
            list.append(row)?;
        }
        Ok(list)
    }

    /// Prepares the output folder ``out`` for writing detection files of ``frames`` of the
    /// dataset folder ``data`` (default: all) at ``min_confidence``, with the rules of
    /// ``pomona detect``: creates the folder, removes the ``.pomona-*.partial`` temporaries a
    /// killed run left, and checks the existing ``<frame>.json`` files of those frames.
    ///
    /// Returns the frames whose detection file this detector would write unchanged (same
    /// pipeline, model, overrides and threshold), sorted: skip them to resume a run, or write
    /// them again.
    ///
    /// Raises ``PomonaError`` naming the file for a ``<frame>.json`` that is not a detection
    /// file or was made by another pipeline, model or threshold (two runs never mix in one
    /// folder), and for the errors of ``write_detections`` (dataset, frames, threshold).
    #[pyo3(signature = (data, out, frames = None, *, min_confidence = None))]
    fn prepare_folder(
        &self,
        data: PathBuf,
        out: PathBuf,
        frames: Option<Vec<String>>,
        min_confidence: Option<f64>,
    ) -> PyResult<Vec<String>> {
        let keep = self.inner.keep_rule_for(min_confidence).map_err(to_py)?;
        let (dataset, frames) = self.open_dataset(&data, frames)?;
        let identity = self.inner.run_identity(dataset.has_color(), keep);
        let done = pomona::prepare_detection_folder(&out, &frames, &identity).map_err(to_py)?;
        Ok(done.into_iter().collect())
    }

    fn __repr__(&self) -> String {
        format!(
            "Detector(pipeline={:?}, model_id={:?})",
            self.inner.pipeline(),
            self.inner.model().id
        )
    }
}
