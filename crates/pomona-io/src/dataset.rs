//! Reading a dataset folder (the layout contract in `docs/formats.md`):
//!
//! ```text
//! <root>/camera.json          intrinsics + depth unit
//! <root>/depth/<frame>.png    16-bit depth, registered to colour, 0 = no reading   (*)
//! <root>/color/<frame>.png    8-bit RGB (or .jpg/.jpeg)                             (*)
//! <root>/truth/<frame>.json   ground truth                                          (optional)
//! <root>/mask/<frame>.png     16-bit instance ids, 0 = background                   (optional)
//! ```
//!
//! (*) At least one of `depth/` and `color/`; when both exist every frame must be in both. A
//! dataset without `depth/` is *colour-only* (a 2D camera, seed 004's setting): its frames load
//! with a depth image that has no reading anywhere, so only methods that work from colour alone
//! find anything in them (the CLI refuses the others, see `Pipeline::needs_depth`).
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
    depth_files: Option<BTreeMap<String, PathBuf>>,
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
    /// Opens a dataset folder: reads `camera.json`, lists `depth/` and `color/` (either may be
    /// missing, not both), and checks that every frame has both when both exist.
    ///
    /// # Errors
    /// [`DatasetError::Missing`] without `camera.json` or without both image folders, the camera
    /// file's errors, [`DatasetError::UnpairedFrame`] or [`DatasetError::DuplicateFrame`] for bad
    /// pairing.
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
        let listed = |dir: &str, extensions| {
            let dir = root.join(dir);
            dir.is_dir()
                .then(|| list_stems(&dir, extensions))
                .transpose()
        };
        let depth_files = listed("depth", DEPTH_EXTENSIONS)?;
        let color_files = listed("color", COLOR_EXTENSIONS)?;
        let frames = match (&depth_files, &color_files) {
            (None, None) => {
                return Err(DatasetError::Missing {
                    path: root.join("depth"),
                    what: "folder of 16-bit depth PNGs (or, for a colour-only dataset, color/)",
                })
            }
            (Some(depth), Some(color)) => {
                check_paired(color, depth, "depth")?;
                check_paired(depth, color, "colour")?;
                depth.keys().cloned().collect()
            }
            (Some(only), None) | (None, Some(only)) => only.keys().cloned().collect(),
        };
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

    /// Whether frames have depth images (`false` for a colour-only dataset).
    pub fn has_depth(&self) -> bool {
        self.depth_files.is_some()
    }

    /// The frame's depth file, else its colour file (every frame has one of them).
    fn frame_path(&self, frame: &str) -> Result<&Path, DatasetError> {
        [&self.depth_files, &self.color_files]
            .into_iter()
            .flatten()
            .find_map(|files| files.get(frame))
            .map(PathBuf::as_path)
            .ok_or_else(|| DatasetError::UnknownFrame {
                root: self.root.clone(),
                frame: frame.to_owned(),
            })
    }

    fn size(&self) -> (u32, u32) {
        (self.camera().width, self.camera().height)
    }

    /// Decodes one frame's depth; in a colour-only dataset, a depth image without any reading
    /// (every pixel NaN).
    ///
    /// # Errors
    /// [`DatasetError::UnknownFrame`] and the image errors of [`read_depth_png`].
    pub fn load_depth(&self, frame: &str) -> Result<DepthImage, DatasetError> {
        let path = self.frame_path(frame)?;
        if self.depth_files.is_none() {
            let (w, h) = self.size();
            let no_reading = vec![f32::NAN; w as usize * h as usize];
            return DepthImage::from_meters(w, h, no_reading).map_err(|source| {
                DatasetError::Core {
                    path: path.to_owned(),
                    source,
                }
            });
        }
        read_depth_png(path, self.size(), self.depth_unit_m())
    }

    /// Decodes one frame's colour, `None` for a depth-only dataset.
    ///
    /// # Errors
    /// [`DatasetError::UnknownFrame`] and the image errors of [`read_color_image`].
    pub fn load_color(&self, frame: &str) -> Result<Option<ColorImage>, DatasetError> {
        self.frame_path(frame)?;
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
            path: self.frame_path(frame).unwrap_or(&self.root).to_owned(),
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
        self.frame_path(frame)?;
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
        self.frame_path(frame)?;
        let path = self.root.join("mask").join(format!("{frame}.png"));
        if !path.is_file() {
            return Ok(None);
        }
        read_mask_png(&path, self.size()).map(Some)
    }
}

/// Fails on the first frame of `files` that `partners` lacks (`missing` names the partner kind).
fn check_paired(
    files: &BTreeMap<String, PathBuf>,
    partners: &BTreeMap<String, PathBuf>,
    missing: &'static str,
) -> Result<(), DatasetError> {
    match files.iter().find(|(s, _)| !partners.contains_key(*s)) {
        Some((frame, path)) => Err(DatasetError::UnpairedFrame {
            path: path.clone(),
            frame: frame.clone(),
            missing,
        }),
        None => Ok(()),
    }
}

/// Parses the text of a truth file; `path` names it in errors.
pub(crate) fn parse_truth(text: &str, path: &Path) -> Result<FrameTruth, DatasetError> {
    serde_json::from_str(text).map_err(|source| DatasetError::Json {
        path: path.to_owned(),
        source,
    })
}
