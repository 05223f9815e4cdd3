//! numpy arrays in and out: the depth (`(H, W)` uint16 in the camera's depth units, or float32
//! metres), colour (`(H, W, 3)` uint8 RGB) and camera dictionary a caller holds become an
//! [`RgbdFrame`], and a dataset's images and clouds become arrays.
//!
//! The depth is converted exactly once, into the `f32` metres every detector reads (uint16 is
//! scaled by `depth_unit_m`, 0 = no reading; float32 is copied, non-positive and non-finite =
//! no reading): the array is read in place, never first copied to another numpy array.
//! Arrays handed back to Python take ownership of the Rust buffers (no copy).

use numpy::ndarray::{Array2, Array3};
use numpy::{PyArray2, PyArray3, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pomona_core::{ColorImage, DepthImage, PointCloud, RgbdFrame};
use pomona_io::CameraFile;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

use crate::json_bridge::from_python;
use crate::py_error::to_py;

/// What `obj` is, for error messages: its numpy dtype and shape, or its Python type.
fn describe(obj: &Bound<'_, PyAny>) -> String {
    match (obj.getattr("dtype"), obj.getattr("shape")) {
        (Ok(dtype), Ok(shape)) => format!("a {dtype} array of shape {shape}"),
        _ => format!(
            "a {}",
            obj.get_type()
                .name()
                .map_or("value".to_owned(), |n| n.to_string())
        ),
    }
}

/// `(width, height)` of an array of `shape` (rows = height), checked to fit the image types.
fn size_of(shape: &[usize], what: &str) -> PyResult<(u32, u32)> {
    let dim = |n: usize| {
        u32::try_from(n).map_err(|_| PyValueError::new_err(format!("{what} is too large: {n}")))
    };
    Ok((dim(shape[1])?, dim(shape[0])?))
}

/// The camera of a `camera.json`-shaped dictionary (`width`, `height`, `fx`, `fy`, `cx`, `cy`,
/// `depth_unit_m`).
///
/// # Errors
/// `PomonaError` for a missing key, a wrong type or an invalid value.
pub fn camera_from_dict(camera: &Bound<'_, PyAny>) -> PyResult<CameraFile> {
    let file: CameraFile = from_python(camera, "camera")?;
    file.validate().map_err(|e| to_py(format!("camera: {e}")))?;
    Ok(file)
}

/// The depth image of `depth`: a `(H, W)` uint16 array in `depth_unit_m` units (0 = no reading)
/// or a float32 array in metres.
///
/// # Errors
/// `TypeError` for another dtype or number of dimensions.
pub fn depth_from_array(depth: &Bound<'_, PyAny>, depth_unit_m: f64) -> PyResult<DepthImage> {
    if let Ok(raw) = depth.extract::<PyReadonlyArray2<'_, u16>>() {
        let (w, h) = size_of(raw.shape(), "depth")?;
        let image = match raw.as_slice() {
            Ok(values) => DepthImage::from_u16(w, h, values, depth_unit_m),
            Err(_) => {
                let values: Vec<u16> = raw.as_array().iter().copied().collect();
                DepthImage::from_u16(w, h, &values, depth_unit_m)
            }
        };
        return image.map_err(to_py);
    }
    if let Ok(metres) = depth.extract::<PyReadonlyArray2<'_, f32>>() {
        let (w, h) = size_of(metres.shape(), "depth")?;
        let values = match metres.as_slice() {
            Ok(values) => values.to_vec(),
            Err(_) => metres.as_array().iter().copied().collect(),
        };
        return DepthImage::from_meters(w, h, values).map_err(to_py);
    }
    Err(PyTypeError::new_err(format!(
        "depth must be a (H, W) uint16 array (camera depth units) or float32 array (metres), \
         got {}",
        describe(depth)
    )))
}

/// The colour image of `color`: a `(H, W, 3)` uint8 RGB array.
///
/// # Errors
/// `TypeError` for another dtype or shape.
pub fn color_from_array(color: &Bound<'_, PyAny>) -> PyResult<ColorImage> {
    let wrong = || {
        PyTypeError::new_err(format!(
            "color must be a (H, W, 3) uint8 RGB array, got {}",
            describe(color)
        ))
    };
    let rgb = color
        .extract::<PyReadonlyArray3<'_, u8>>()
        .map_err(|_| wrong())?;
    if rgb.shape()[2] != 3 {
        return Err(wrong());
    }
    let (w, h) = size_of(rgb.shape(), "color")?;
    let values = match rgb.as_slice() {
        Ok(values) => values.to_vec(),
        Err(_) => rgb.as_array().iter().copied().collect(),
    };
    ColorImage::from_rgb(w, h, values).map_err(to_py)
}

/// The frame of a caller's arrays and camera dictionary.
///
/// # Errors
/// As [`camera_from_dict`], [`depth_from_array`] and [`color_from_array`]; `PomonaError` when
/// the images and camera disagree in size.
pub fn frame_from_arrays(
    depth: &Bound<'_, PyAny>,
    color: Option<&Bound<'_, PyAny>>,
    camera: &Bound<'_, PyAny>,
) -> PyResult<RgbdFrame> {
    let camera = camera_from_dict(camera)?;
    let depth = depth_from_array(depth, camera.depth_unit_m)?;
    let color = color.map(color_from_array).transpose()?;
    RgbdFrame::new(camera.camera, depth, color).map_err(to_py)
}

/// `depth` as a `(H, W)` float32 array of metres (NaN = no reading).
pub fn depth_to_array<'py>(py: Python<'py>, depth: &DepthImage) -> Bound<'py, PyArray2<f32>> {
    let shape = (depth.height() as usize, depth.width() as usize);
    let values = Array2::from_shape_vec(shape, depth.as_slice().to_vec())
        .unwrap_or_else(|_| Array2::zeros((0, 0)));
    PyArray2::from_owned_array(py, values)
}

/// `color` as a `(H, W, 3)` uint8 RGB array.
pub fn color_to_array<'py>(py: Python<'py>, color: ColorImage) -> Bound<'py, PyArray3<u8>> {
    let shape = (color.height() as usize, color.width() as usize, 3);
    let values = Array3::from_shape_vec(shape, color.into_rgb())
        .unwrap_or_else(|_| Array3::zeros((0, 0, 3)));
    PyArray3::from_owned_array(py, values)
}

/// The valid points of `cloud` as an `(N, 3)` float32 array (x, y, z in metres, camera frame).
pub fn cloud_to_array<'py>(py: Python<'py>, cloud: &PointCloud) -> Bound<'py, PyArray2<f32>> {
    let xyz: Vec<f32> = cloud
        .points()
        .iter()
        .filter(|p| p.iter().all(|c| c.is_finite()))
        .flat_map(|p| [p.x, p.y, p.z])
        .collect();
    let values =
        Array2::from_shape_vec((xyz.len() / 3, 3), xyz).unwrap_or_else(|_| Array2::zeros((0, 3)));
    PyArray2::from_owned_array(py, values)
}
