//! Reading a dataset folder (the layout contract in `docs/formats.md`):
//!
//! ```text
//! <root>/camera.json          intrinsics + depth unit
//! <root>/depth/<frame>.png    16-bit depth, registered to colour, 0 = no reading   (required)
//! <root>/color/<frame>.png    8-bit RGB (or .jpg/.jpeg)                             (optional)
//! <root>/truth/<frame>.json   ground truth                                          (optional)
//! <root>/mask/<frame>.png     16-bit instance ids, 0 = background                   (optional)
//! ```
//!
//! Opening lists and pairs the frames and reads the camera; pixels are decoded only when a frame
//! is loaded, so opening a dataset of thousands of frames is instant.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use pomona_core::{ColorImage, DepthImage, FrameTruth, InstanceMask, PinholeCamera, RgbdFrame};

use crate::image_file::{read_color_image, read_depth_png, read_mask_png};
use crate::read_budget::{read_json_text, MAX_JSON_FILE_BYTES};
use crate::{CameraFile, DatasetError};

const DEPTH_EXTENSIONS: &[&str] = &["png"];
const COLOR_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg"];

/// An opened dataset: camera, and the sorted list of frames with their files.
#[derive(Debug, Clone)]
pub struct Dataset {
    root: PathBuf,
    camera_file: CameraFile,
    frames: Vec<String>,
    depth_files: BTreeMap<String, PathBuf>,
    color_files: Option<BTreeMap<String, PathBuf>>,
}

/// Lists `dir`'s files with one of `extensions` (case-insensitive) by stem; hidden files and
/// other extensions are ignored (so a README or `.DS_Store` in a folder is harmless).
fn list_stems(dir: &Path, extensions: &[&str]) -> Result<BTreeMap<String, PathBuf>, DatasetError> {
    let mut stems = BTreeMap::new();
    let entries = std::fs::read_dir(dir).map_err(|e| DatasetError::io(dir, e))?;
    for entry in entries {
        let path = entry.map_err(|e| DatasetError::io(dir, e))?.path();
        let (Some(stem), Some(ext)) = (
            path.file_stem().and_then(|s| s.to_str()).map(str::to_owned),
            path.extension().and_then(|s| s.to_str()),
        ) else {
            continue;
        };
        if stem.starts_with('.') || !extensions.contains(&ext.to_ascii_lowercase().as_str()) {
            continue;
        }
        if !path.is_file() {
            continue;
        }
        if stems.insert(stem.clone(), path.clone()).is_some() {
            return Err(DatasetError::DuplicateFrame { path, frame: stem });
        }
    }
    Ok(stems)
}

impl Dataset {
    /// Opens a dataset folder: reads `camera.json`, lists `depth/` and (when present) `color/`,
    /// and checks that every frame has both.
    ///
    /// # Errors
    /// [`DatasetError::Missing`] without `camera.json` or `depth/`, the camera file's errors,
    /// [`DatasetError::UnpairedFrame`] or [`DatasetError::DuplicateFrame`] for bad pairing.
    pub fn open(root: impl AsRef<Path>) -> Result<Self, DatasetError> {
        let root = root.as_ref().to_owned();
        if !root.is_dir() {
            return Err(DatasetError::Missing {
                path: root,
                what: "dataset folder",
            });
        }
        let camera_path = root.join("camera.json");
        if !camera_path.is_file() {
            return Err(DatasetError::Missing {
                path: camera_path,
                what: "camera intrinsics file",
            });
        }
        let camera_file = CameraFile::read(&camera_path)?;
        let depth_dir = root.join("depth");
        if !depth_dir.is_dir() {
            return Err(DatasetError::Missing {
                path: depth_dir,
                what: "folder of 16-bit depth PNGs",
            });
        }
        let depth_files = list_stems(&depth_dir, DEPTH_EXTENSIONS)?;
        let color_dir = root.join("color");
        let color_files = if color_dir.is_dir() {
            let color = list_stems(&color_dir, COLOR_EXTENSIONS)?;
            if let Some((frame, path)) = color.iter().find(|(s, _)| !depth_files.contains_key(*s)) {
                return Err(DatasetError::UnpairedFrame {
                    path: path.clone(),
                    frame: frame.clone(),
                    missing: "depth",
                });
            }
            if let Some((frame, path)) = depth_files.iter().find(|(s, _)| !color.contains_key(*s)) {
                return Err(DatasetError::UnpairedFrame {
                    path: path.clone(),
                    frame: frame.clone(),
                    missing: "colour",
                });
            }
            Some(color)
        } else {
            None
        };
        let frames = depth_files.keys().cloned().collect();
        Ok(Self {
            root,
            camera_file,
            frames,
            depth_files,
            color_files,
        })
    }

    /// The dataset folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The camera shared by all frames.
    pub fn camera(&self) -> &PinholeCamera {
        &self.camera_file.camera
    }

    /// Metres per unit of the depth PNGs.
    pub fn depth_unit_m(&self) -> f64 {
        self.camera_file.depth_unit_m
    }

    /// Frame stems, sorted.
    pub fn frames(&self) -> &[String] {
        &self.frames
    }

    /// Whether frames have colour images.
    pub fn has_color(&self) -> bool {
        self.color_files.is_some()
    }

    fn depth_path(&self, frame: &str) -> Result<&Path, DatasetError> {
        self.depth_files
            .get(frame)
            .map(PathBuf::as_path)
            .ok_or_else(|| DatasetError::UnknownFrame {
                root: self.root.clone(),
                frame: frame.to_owned(),
            })
    }

    fn size(&self) -> (u32, u32) {
        (self.camera().width, self.camera().height)
    }

    /// Decodes one frame's depth.
    ///
    /// # Errors
    /// [`DatasetError::UnknownFrame`] and the image errors of [`read_depth_png`].
    pub fn load_depth(&self, frame: &str) -> Result<DepthImage, DatasetError> {
        read_depth_png(self.depth_path(frame)?, self.size(), self.depth_unit_m())
    }

    /// Decodes one frame's colour, `None` for a depth-only dataset.
    ///
    /// # Errors
    /// [`DatasetError::UnknownFrame`] and the image errors of [`read_color_image`].
    pub fn load_color(&self, frame: &str) -> Result<Option<ColorImage>, DatasetError> {
        self.depth_path(frame)?;
        match self.color_files.as_ref().and_then(|c| c.get(frame)) {
            Some(path) => read_color_image(path, self.size()).map(Some),
            None => Ok(None),
        }
    }

    /// Decodes one frame: depth, colour when present, and the camera.
    ///
    /// # Errors
    /// As [`Dataset::load_depth`] and [`Dataset::load_color`].
    pub fn load_frame(&self, frame: &str) -> Result<RgbdFrame, DatasetError> {
        let depth = self.load_depth(frame)?;
        let color = self.load_color(frame)?;
        RgbdFrame::new(*self.camera(), depth, color).map_err(|source| DatasetError::Core {
            path: self.depth_files[frame].clone(),
            source,
        })
    }

    /// Path of a frame's truth file (whether or not it exists).
    pub fn truth_path(&self, frame: &str) -> PathBuf {
        self.root.join("truth").join(format!("{frame}.json"))
    }

    /// Reads a frame's ground truth; `None` when the frame has no truth file.
    ///
    /// # Errors
    /// [`DatasetError::UnknownFrame`], [`DatasetError::Io`] (also for a file over
    /// [`crate::read_budget::MAX_JSON_FILE_BYTES`]), [`DatasetError::Json`] (which also
    /// covers impossible values such as a zero axis or an inverted box).
    pub fn load_truth(&self, frame: &str) -> Result<Option<FrameTruth>, DatasetError> {
        self.depth_path(frame)?;
        let path = self.truth_path(frame);
        if !path.is_file() {
            return Ok(None);
        }
        let text =
            read_json_text(&path, MAX_JSON_FILE_BYTES).map_err(|e| DatasetError::io(&path, e))?;
        parse_truth(&text, &path).map(Some)
    }

    /// Reads a frame's instance mask; `None` when the frame has none.
    ///
    /// # Errors
    /// [`DatasetError::UnknownFrame`] and the image errors of [`read_mask_png`].
    pub fn load_mask(&self, frame: &str) -> Result<Option<InstanceMask>, DatasetError> {
        self.depth_path(frame)?;
        let path = self.root.join("mask").join(format!("{frame}.png"));
        if !path.is_file() {
            return Ok(None);
        }
        read_mask_png(&path, self.size()).map(Some)
    }
}

/// Parses the text of a truth file; `path` names it in errors.
pub(crate) fn parse_truth(text: &str, path: &Path) -> Result<FrameTruth, DatasetError> {
    serde_json::from_str(text).map_err(|source| DatasetError::Json {
        path: path.to_owned(),
        source,
    })
}
