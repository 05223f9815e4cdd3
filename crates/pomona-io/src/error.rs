//! Errors of the dataset layout: every variant names the file (or folder) at fault, so a user
//! with a thousand frames knows which one to fix.

use std::path::PathBuf;

use pomona_core::CoreError;

/// Why a dataset could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// The operating system refused a read, write, listing or rename.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A JSON file (camera or truth) is malformed or has a wrong field.
    #[error("{path}: invalid JSON: {source}")]
    Json {
        /// The JSON file.
        path: PathBuf,
        /// The parser's explanation, with line and column.
        source: serde_json::Error,
    },
    /// `camera.json` parsed but holds impossible values.
    #[error("{path}: {source}")]
    InvalidCamera {
        /// The camera file.
        path: PathBuf,
        /// Which parameter is wrong.
        source: CoreError,
    },
    /// An image file could not be decoded (truncated, corrupt, unsupported) or encoded.
    #[error("{path}: {source}")]
    Image {
        /// The image file.
        path: PathBuf,
        /// The codec's explanation.
        source: image::ImageError,
    },
    /// A depth image is not 16-bit single-channel.
    #[error("{path}: depth must be a 16-bit single-channel image, found {found}")]
    DepthNotSixteenBit {
        /// The depth file.
        path: PathBuf,
        /// The colour type found, for example `L8` or `Rgb8`.
        found: String,
    },
    /// An image's size differs from `camera.json`.
    #[error(
        "{path}: image is {width}x{height} but camera.json says {expected_width}x{expected_height}"
    )]
    SizeMismatch {
        /// The image file.
        path: PathBuf,
        /// Width found.
        width: u32,
        /// Height found.
        height: u32,
        /// Width from the camera.
        expected_width: u32,
        /// Height from the camera.
        expected_height: u32,
    },
    /// A required file or folder does not exist.
    #[error("{path}: not found ({what})")]
    Missing {
        /// The path looked for.
        path: PathBuf,
        /// What it should have been.
        what: &'static str,
    },
    /// A colour image has no depth partner or the other way round.
    #[error("{path}: frame `{frame}` has no matching {missing} image")]
    UnpairedFrame {
        /// The file that has no partner.
        path: PathBuf,
        /// Its stem.
        frame: String,
        /// `"depth"` or `"colour"`.
        missing: &'static str,
    },
    /// Two files in one folder share a stem (for example `1.png` and `1.jpg`).
    #[error("{path}: frame `{frame}` appears more than once")]
    DuplicateFrame {
        /// One of the files.
        path: PathBuf,
        /// The shared stem.
        frame: String,
    },
    /// A frame was asked for that the dataset does not have.
    #[error("{root}: no frame `{frame}`")]
    UnknownFrame {
        /// The dataset root.
        root: PathBuf,
        /// The requested stem.
        frame: String,
    },
    /// A value could not be turned into a core type (for example a bad depth unit).
    #[error("{path}: {source}")]
    Core {
        /// The file the value came from or goes to.
        path: PathBuf,
        /// What is wrong.
        source: CoreError,
    },
}

impl DatasetError {
    /// The file or folder at fault (the dataset root for an unknown frame).
    pub fn path(&self) -> &std::path::Path {
        match self {
            Self::Io { path, .. }
            | Self::Json { path, .. }
            | Self::InvalidCamera { path, .. }
            | Self::Image { path, .. }
            | Self::DepthNotSixteenBit { path, .. }
            | Self::SizeMismatch { path, .. }
            | Self::Missing { path, .. }
            | Self::UnpairedFrame { path, .. }
            | Self::DuplicateFrame { path, .. }
            | Self::Core { path, .. } => path,
            Self::UnknownFrame { root, .. } => root,
        }
    }

    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}
