//! Writing a dataset in the layout [`crate::Dataset`] reads. Used by the synthetic generator
//! and by converters; every file is written atomically.

use std::path::{Path, PathBuf};

use pomona_core::{ColorImage, DepthImage, FrameTruth, InstanceMask, PinholeCamera, RgbdFrame};

use crate::atomic_write::write_atomically;
use crate::image_file::{write_color_png, write_depth_png, write_mask_png};
use crate::{CameraFile, DatasetError};

/// Writes frames into a dataset folder.
#[derive(Debug, Clone)]
pub struct DatasetWriter {
    root: PathBuf,
    camera_file: CameraFile,
}

/// Writes any serialisable value as pretty JSON, atomically.
///
/// # Errors
/// [`DatasetError::Io`] or [`DatasetError::Json`]; the destination is untouched on failure.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<(), DatasetError> {
    write_json_with(path, value, true)
}

/// Writes any serialisable value as compact JSON (no indentation), atomically: for large
/// machine-read files such as model files, where indentation would double the size.
///
/// # Errors
/// As [`write_json`].
pub fn write_json_compact(path: &Path, value: &impl serde::Serialize) -> Result<(), DatasetError> {
    write_json_with(path, value, false)
}

fn write_json_with(
    path: &Path,
    value: &impl serde::Serialize,
    pretty: bool,
) -> Result<(), DatasetError> {
    write_atomically(
        path,
        |w| {
            let written = if pretty {
                serde_json::to_writer_pretty(&mut *w, value)
            } else {
                serde_json::to_writer(&mut *w, value)
            };
            written.map_err(|source| DatasetError::Json {
                path: path.to_owned(),
                source,
            })?;
            std::io::Write::write_all(w, b"\n").map_err(|e| DatasetError::io(path, e))
        },
        |p: &Path, e| DatasetError::io(p, e),
    )
}

impl DatasetWriter {
    /// Creates `root` (and parents) and writes `camera.json`.
    ///
    /// # Errors
    /// [`DatasetError::InvalidCamera`] for invalid intrinsics or unit; I/O errors naming the path.
    pub fn create(
        root: impl AsRef<Path>,
        camera: &PinholeCamera,
        depth_unit_m: f64,
    ) -> Result<Self, DatasetError> {
        let root = root.as_ref().to_owned();
        let camera_file = CameraFile {
            camera: *camera,
            depth_unit_m,
        };
        let camera_path = root.join("camera.json");
        camera_file
            .validate()
            .map_err(|source| DatasetError::InvalidCamera {
                path: camera_path.clone(),
                source,
            })?;
        std::fs::create_dir_all(&root).map_err(|e| DatasetError::io(&root, e))?;
        write_json(&camera_path, &camera_file)?;
        Ok(Self { root, camera_file })
    }

    /// The dataset folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    fn file(&self, folder: &str, frame: &str, ext: &str) -> Result<PathBuf, DatasetError> {
        let dir = self.root.join(folder);
        std::fs::create_dir_all(&dir).map_err(|e| DatasetError::io(&dir, e))?;
        Ok(dir.join(format!("{frame}.{ext}")))
    }

    fn check_size(&self, path: &Path, width: u32, height: u32) -> Result<(), DatasetError> {
        let cam = &self.camera_file.camera;
        if (width, height) == (cam.width, cam.height) {
            return Ok(());
        }
        Err(DatasetError::SizeMismatch {
            path: path.to_owned(),
            width,
            height,
            expected_width: cam.width,
            expected_height: cam.height,
        })
    }

    /// Writes `color/<frame>.png`.
    ///
    /// # Errors
    /// [`DatasetError::SizeMismatch`] when the image is not the camera's size; I/O and codec
    /// errors naming the file.
    pub fn write_color(&self, frame: &str, image: &ColorImage) -> Result<(), DatasetError> {
        let path = self.file("color", frame, "png")?;
        self.check_size(&path, image.width(), image.height())?;
        write_color_png(&path, image)
    }

    /// Writes `depth/<frame>.png` in the dataset's depth unit.
    ///
    /// # Errors
    /// As [`DatasetWriter::write_color`].
    pub fn write_depth(&self, frame: &str, depth: &DepthImage) -> Result<(), DatasetError> {
        let path = self.file("depth", frame, "png")?;
        self.check_size(&path, depth.width(), depth.height())?;
        write_depth_png(&path, depth, self.camera_file.depth_unit_m)
    }

    /// Writes `mask/<frame>.png`.
    ///
    /// # Errors
    /// As [`DatasetWriter::write_color`].
    pub fn write_mask(&self, frame: &str, mask: &InstanceMask) -> Result<(), DatasetError> {
        let path = self.file("mask", frame, "png")?;
        self.check_size(&path, mask.width(), mask.height())?;
        write_mask_png(&path, mask)
    }

    /// Writes `truth/<frame>.json`.
    ///
    /// # Errors
    /// I/O and JSON errors naming the file.
    pub fn write_truth(&self, frame: &str, truth: &FrameTruth) -> Result<(), DatasetError> {
        write_json(&self.file("truth", frame, "json")?, truth)
    }

    /// Writes a frame's depth, its colour when present, and its truth when given.
    ///
    /// # Errors
    /// As the individual writers (a frame of another size is a [`DatasetError::SizeMismatch`]).
    pub fn write_frame(
        &self,
        frame: &str,
        rgbd: &RgbdFrame,
        truth: Option<&FrameTruth>,
    ) -> Result<(), DatasetError> {
        self.write_depth(frame, rgbd.depth())?;
        if let Some(color) = rgbd.color() {
            self.write_color(frame, color)?;
        }
        if let Some(truth) = truth {
            self.write_truth(frame, truth)?;
        }
        Ok(())
    }
}
