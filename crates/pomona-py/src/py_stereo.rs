//! `pomona.StereoLocator`: seed 004's stereo from the two colour shots of a rotating camera,
//! from Python, through the facade's [`pomona::StereoLocator`] — what `pomona stereo` runs on
//! each frame, with its defaults.

use std::path::PathBuf;

use pomona::{RotatedStereo, StereoMethod, StereoSettings};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::frame_arrays::{camera_from_dict, color_from_array};
use crate::json_bridge::{overrides_from, to_python};
use crate::py_detector::load_detector;
use crate::py_error::to_py;

/// Locates fruit from the two shots of one rig: the camera turned by ``±beta_deg`` about a hub
/// ``pivot_m`` behind its lens (the ``rig.json`` of ``pomona synth --stereo``: ``beta_rad`` and
/// minus ``pivot_m[2]``). ``camera``: a dict with the keys of ``camera.json``; ``model``,
/// ``set``: the ``color-contour`` model and overrides, as ``Detector`` (its ray and Hough
/// circles start off, as in ``pomona stereo``; ``set`` can turn them on); ``method``:
/// ``"paper"`` (Eq. 18) or ``"triangulate"``; ``min_confidence``: as ``Detector.detect``
/// (``None``: the model's operating confidence); ``reach_m``: ``(near, far)`` hub distances of
/// the working volume (``None``: pivot + 0.2 to pivot + 2.0 m); ``refine``: the sub-pixel
/// refinement of each pair's stereo-view centre (``False``: the circle centres, as in the seed
/// and ``pomona stereo --no-refine``); ``leftovers``: the pass that pairs the circles the
/// relaxation leaves by appearance (``False``: none, as in the seed); ``fruit_radius_m``:
/// ``(smallest, largest)`` radius in metres a located fruit's circle must have at its located
/// depth (seed 004's size test on the stereo depth; ``None``: the detector's accepted radii,
/// as ``pomona stereo``); ``size_test``: ``False`` for no size test (``--fruit-radius-m off``).
#[pyclass(frozen, module = "pomona")]
pub struct StereoLocator {
    inner: pomona::StereoLocator,
}

#[pymethods]
impl StereoLocator {
    #[new]
    #[pyo3(signature = (*, camera, beta_deg, pivot_m, model = None, set = None, method = "paper", min_confidence = None, reach_m = None, refine = true, leftovers = true, fruit_radius_m = None, size_test = true))]
    #[allow(clippy::too_many_arguments)] // Python keyword arguments
    fn new(
        camera: &Bound<'_, PyAny>,
        beta_deg: f64,
        pivot_m: f64,
        model: Option<PathBuf>,
        set: Option<&Bound<'_, PyDict>>,
        method: &str,
        min_confidence: Option<f64>,
        reach_m: Option<(f64, f64)>,
        refine: bool,
        leftovers: bool,
        fruit_radius_m: Option<(f64, f64)>,
        size_test: bool,
    ) -> PyResult<Self> {
        let camera = camera_from_dict(camera)?.camera;
        let rig = RotatedStereo::new(beta_deg.to_radians(), pivot_m, camera)
            .map_err(|e| to_py(format!("rig: {e}")))?;
        let method: StereoMethod = method.parse().map_err(|e| to_py(format!("method: {e}")))?;
        let overrides = pomona::StereoLocator::detector_overrides(overrides_from(set)?);
        let detector = load_detector("color-contour", model, overrides)?;
        let keep = detector.keep_rule_for(min_confidence).map_err(to_py)?;
        let defaults = StereoSettings::default();
        let settings = StereoSettings {
            method,
            reach_m,
            refinement: defaults.refinement.filter(|_| refine),
            leftovers: defaults.leftovers.filter(|_| leftovers),
            fruit_radius_m: fruit_radius_m
                .or(defaults.fruit_radius_m)
                .filter(|_| size_test),
            ..defaults
        };
        Ok(Self {
            inner: pomona::StereoLocator::new(detector, keep, rig, settings).map_err(to_py)?,
        })
    }

    /// The fruit of one pair of shots, ``primary`` and ``stereo``: (H, W, 3) uint8 RGB arrays of
    /// the camera's size. Returns a list of dicts with the detection JSON's keys, one per located
    /// fruit (``center_m`` in the primary camera frame, metres; ``diameter_m``; ``center_px`` and
    /// ``radius_px`` of its primary circle; ``score``; ``confidence``). The GIL is released while
    /// it works.
    ///
    /// Raises ``TypeError`` for arrays of another dtype or shape, ``PomonaError`` for images of
    /// another size than the camera's.
    fn locate<'py>(
        &self,
        py: Python<'py>,
        primary: &Bound<'py, PyAny>,
        stereo: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (a, b) = (color_from_array(primary)?, color_from_array(stereo)?);
        let found = py.detach(|| self.inner.locate(&a, &b)).map_err(to_py)?;
        to_python(py, &found.detections)
    }

    fn __repr__(&self) -> String {
        let rig = self.inner.rig();
        format!(
            "StereoLocator(beta_deg={:.3}, pivot_m={:.3}, model_id={:?})",
            rig.beta_rad.to_degrees(),
            rig.pivot_distance_m,
            self.inner.detector().model().id
        )
    }
}
