//! Errors of the generator: a bad parameter, a core type refusing a value, or a file that could
//! not be written. Kept in one enum so the CLI can report any of them with one `?`.

use std::path::PathBuf;

use pomona_core::CoreError;

/// Why a scene could not be specified, rendered or written.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// A [`crate::SceneSpec`] or [`crate::DatasetSpec`] field is out of its allowed range.
    #[error("invalid synth parameter `{name}`: {reason}")]
    InvalidParameter {
        /// Field name, as on the command line where there is one.
        name: &'static str,
        /// What is wrong and what is allowed.
        reason: String,
    },
    /// A core type rejected a value built by the renderer (a bug if it ever happens).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// Writing the dataset failed.
    #[error(transparent)]
    Dataset(#[from] pomona_io::DatasetError),
    /// Writing a generator-specific file (`rig.json`, `synth.json`) failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The worker thread pool could not be built.
    #[error("could not start {threads} worker threads: {reason}")]
    ThreadPool {
        /// Requested thread count.
        threads: usize,
        /// The pool builder's explanation.
        reason: String,
    },
}
