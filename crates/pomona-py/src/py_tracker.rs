//! `pomona.Tracker` and `pomona.Track`: seed 004's approach tracker from Python, through the
//! facade's [`pomona::Tracker`] — the same tracker `pomona track` runs, so a track from Python
//! equals the CLI's on the same frames and start circle.
//!
//! A `Tracker` is loaded once (model and parameters); `Tracker.start` gives a `Track` per fruit,
//! whose `update` takes one colour frame as a numpy array and runs with the GIL released.

use std::path::PathBuf;
use std::sync::Mutex;

use pomona::nalgebra::Point2;
use pomona::ImageCircle;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::frame_arrays::color_from_array;
use crate::json_bridge::{overrides_from, to_python};
use crate::py_error::to_py;

/// An approach tracker loaded once: the ``color-contour`` model's colour table and stages (the
/// built-in model, or ``model="m.json"`` from ``pomona train``) and the tracker's parameters,
/// ``set={"key": value}`` overriding them by dotted key as ``pomona track --set`` does.
#[pyclass(frozen, module = "pomona")]
pub struct Tracker {
    inner: pomona::Tracker,
}

#[pymethods]
impl Tracker {
    #[new]
    #[pyo3(signature = (model = None, set = None))]
    fn new(model: Option<PathBuf>, set: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut builder = pomona::Tracker::builder();
        if let Some(path) = model {
            builder = builder.model_file(path);
        }
        builder = builder.overrides(overrides_from(set)?);
        Ok(Self {
            inner: builder.build().map_err(to_py)?,
        })
    }

    /// The tracker's parameters, as a dict (the keys ``set`` takes).
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, self.inner.params())
    }

    /// The model's identity: 16 hex digits, as detection files record it.
    #[getter]
    fn model_id(&self) -> String {
        self.inner.model().id.clone()
    }

    /// A track of the fruit whose circle in the first frame is centred at ``(x, y)`` with radius
    /// ``radius`` (pixels; a detection's ``center_px`` and ``radius_px``). Pass that first frame
    /// to ``Track.update`` too.
    ///
    /// Raises ``PomonaError`` for a circle that is not finite with a positive radius.
    fn start(&self, x: f64, y: f64, radius: f64) -> PyResult<Track> {
        let track = self
            .inner
            .start(ImageCircle {
                center_px: Point2::new(x, y),
                radius_px: radius,
            })
            .map_err(to_py)?;
        Ok(Track {
            inner: Mutex::new(track),
        })
    }

    fn __repr__(&self) -> String {
        format!("Tracker(model_id={:?})", self.inner.model().id)
    }
}

/// One fruit being followed; ``update`` it with every frame.
#[pyclass(frozen, module = "pomona")]
pub struct Track {
    inner: Mutex<pomona::Track>,
}

impl Track {
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, pomona::Track>> {
        self.inner
            .lock()
            .map_err(|_| to_py("the track was poisoned by an earlier failure"))
    }
}

#[pymethods]
impl Track {
    /// Follows the fruit into ``color``, the next frame: an (H, W, 3) uint8 RGB array. Returns a
    /// dict: ``center_px`` ([x, y]), ``radius_px``, ``status`` (``"confirmed"``,
    /// ``"searched"``, ``"redetected"``, ``"predicted"`` — the last circle moved with the image
    /// patch around it, the circle found being too far from there — or ``"lost"``, which
    /// repeats the last circle) and ``probes`` (5×5 checks made). The GIL is released while it
    /// tracks.
    ///
    /// Raises ``TypeError`` for an array of another dtype or shape.
    fn update<'py>(
        &self,
        py: Python<'py>,
        color: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let image = color_from_array(color)?;
        let mut guard = self.lock()?;
        let track: &mut pomona::Track = &mut guard;
        let estimate = py.detach(|| track.update(&image));
        to_python(py, &estimate)
    }

    /// The current circle, ``(x, y, radius)`` in pixels (the start circle before the first
    /// update).
    #[getter]
    fn circle(&self) -> PyResult<(f64, f64, f64)> {
        let c = self.lock()?.circle();
        Ok((c.center_px.x, c.center_px.y, c.radius_px))
    }

    fn __repr__(&self) -> PyResult<String> {
        let (x, y, r) = self.circle()?;
        Ok(format!("Track(circle=({x:.1}, {y:.1}, {r:.1}))"))
    }
}
