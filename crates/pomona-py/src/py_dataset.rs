//! `pomona.Dataset`: a dataset folder (docs/formats.md) read frame by frame into numpy arrays:
//! depth in metres, colour, truth and back-projected point clouds.
//!
//! Frames are read when asked for, so a dataset of any size opens at once; the camera
//! dictionary it gives is the one `Detector.detect` takes, so its arrays can be passed straight
//! back.

use std::path::PathBuf;

use numpy::{PyArray2, PyArray3};
use pyo3::prelude::*;

use crate::frame_arrays::{cloud_to_array, color_to_array, depth_to_array};
use crate::json_bridge::to_python;
use crate::py_error::to_py;

/// A dataset folder (``camera.json``, ``depth/``, optional ``color/`` and ``truth/``).
///
/// ``frames`` lists the frame names (sorted); ``depth(frame)``, ``color(frame)``,
/// ``truth(frame)`` and ``cloud(frame)`` read one frame.
#[pyclass(frozen, module = "pomona")]
pub struct Dataset {
    inner: pomona::Dataset,
}

impl Dataset {
    /// Wraps an opened dataset.
    pub fn from_inner(inner: pomona::Dataset) -> Self {
        Self { inner }
    }
}

#[pymethods]
impl Dataset {
    /// Opens the dataset folder ``path``; raises ``PomonaError`` naming the file at fault.
    #[new]
    fn new(path: PathBuf) -> PyResult<Self> {
        pomona::Dataset::open(&path)
            .map(Self::from_inner)
            .map_err(to_py)
    }

    /// The dataset folder.
    #[getter]
    fn path(&self) -> PathBuf {
        self.inner.root().to_path_buf()
    }

    /// Frame names (file stems), sorted.
    #[getter]
    fn frames(&self) -> Vec<String> {
        self.inner.frames().to_vec()
    }

    /// Whether the dataset has colour images.
    #[getter]
    fn has_color(&self) -> bool {
        self.inner.has_color()
    }

    /// The camera as a dict with the keys of ``camera.json`` (``width``, ``height``, ``fx``,
    /// ``fy``, ``cx``, ``cy``, ``depth_unit_m``).
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let file = pomona_io::CameraFile {
            camera: *self.inner.camera(),
            depth_unit_m: self.inner.depth_unit_m(),
        };
        to_python(py, &file)
    }

    /// Depth of ``frame`` as a (H, W) float32 array of metres (NaN = no reading).
    fn depth<'py>(&self, py: Python<'py>, frame: &str) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let depth = self.inner.load_depth(frame).map_err(to_py)?;
        Ok(depth_to_array(py, &depth))
    }

    /// Colour of ``frame`` as a (H, W, 3) uint8 RGB array, or ``None`` without colour.
    fn color<'py>(
        &self,
        py: Python<'py>,
        frame: &str,
    ) -> PyResult<Option<Bound<'py, PyArray3<u8>>>> {
        let color = self.inner.load_color(frame).map_err(to_py)?;
        Ok(color.map(|c| color_to_array(py, c)))
    }

    /// Truth of ``frame`` as the dict of ``truth/<frame>.json``, or ``None`` without truth.
    fn truth<'py>(&self, py: Python<'py>, frame: &str) -> PyResult<Bound<'py, PyAny>> {
        let truth = self.inner.load_truth(frame).map_err(to_py)?;
        to_python(py, &truth)
    }

    /// The points of ``frame`` with depth, back-projected: an (N, 3) float32 array of x, y, z
    /// in metres in the camera frame (x right, y down, z forward).
    fn cloud<'py>(&self, py: Python<'py>, frame: &str) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let frame = self.inner.load_frame(frame).map_err(to_py)?;
        Ok(cloud_to_array(py, &frame.to_cloud()))
    }

    fn __len__(&self) -> usize {
        self.inner.frames().len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Dataset({:?}, frames={})",
            self.inner.root().display().to_string(),
            self.inner.frames().len()
        )
    }
}
