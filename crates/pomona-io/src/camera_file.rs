//! `camera.json`: the intrinsics shared by a dataset's colour and depth images, and the unit of
//! its 16-bit depth values.

use std::path::Path;

use pomona_core::{CoreError, PinholeCamera};
use serde::{Deserialize, Serialize};

use crate::DatasetError;

/// Contents of `camera.json`.
///
/// ```
/// let json = r#"{"width":512,"height":424,"fx":365.0,"fy":365.0,"cx":256.0,"cy":212.0,"depth_unit_m":0.001}"#;
/// let cam: pomona_io::CameraFile = serde_json::from_str(json).unwrap();
/// assert_eq!(cam.camera.width, 512);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CameraFile {
    /// Pinhole intrinsics (flattened into the same JSON object).
    #[serde(flatten)]
    pub camera: PinholeCamera,
    /// Metres per unit of the 16-bit depth PNGs (0.001 for millimetres).
    pub depth_unit_m: f64,
}

impl CameraFile {
    /// Reads and validates a camera file.
    ///
    /// # Errors
    /// [`DatasetError::Io`] when it cannot be read or is over
    /// [`crate::read_budget::MAX_JSON_FILE_BYTES`], [`DatasetError::Json`] when it is not the
    /// expected JSON, [`DatasetError::InvalidCamera`] when a value is not finite and positive.
    pub fn read(path: &Path) -> Result<Self, DatasetError> {
        let text =
            crate::read_budget::read_json_text(path, crate::read_budget::MAX_JSON_FILE_BYTES)
                .map_err(|e| DatasetError::io(path, e))?;
        let file: Self = serde_json::from_str(&text).map_err(|source| DatasetError::Json {
            path: path.to_owned(),
            source,
        })?;
        file.validate()
            .map_err(|source| DatasetError::InvalidCamera {
                path: path.to_owned(),
                source,
            })?;
        Ok(file)
    }

    /// Checks the camera and the depth unit.
    ///
    /// # Errors
    /// The [`CoreError`] of the first invalid value.
    pub fn validate(&self) -> Result<(), CoreError> {
        self.camera.validate()?;
        if !(self.depth_unit_m.is_finite() && self.depth_unit_m > 0.0) {
            return Err(CoreError::InvalidDepthUnit(self.depth_unit_m));
        }
        Ok(())
    }
}
