//! The exit statuses of `pomona`, documented in the README and `pomona detect --help`:
//!
//! * `0`: success;
//! * `1`: the command failed (bad arguments, unreadable model or dataset, ...);
//! * `2`: the command line could not be parsed (clap's status);
//! * `3` ([`SOME_FRAMES_FAILED`]): a batch finished but some frames failed; every other frame's
//!   output was written and the failures are listed in the output folder's `failures.json`.

use std::path::PathBuf;
use std::process::ExitCode;

/// Status of a batch in which some frames failed and the rest were written.
pub const SOME_FRAMES_FAILED: u8 = 3;

/// The error a batch command returns when some of its frames failed.
#[derive(Debug, thiserror::Error)]
#[error("{failed} of {total} frame(s) failed (listed in {})", report.display())]
pub struct FramesFailed {
    /// Frames that failed.
    pub failed: usize,
    /// Frames the run tried.
    pub total: usize,
    /// The `failures.json` listing them.
    pub report: PathBuf,
}

/// The exit status for a command's result.
pub fn exit_code(result: &anyhow::Result<()>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) if err.downcast_ref::<FramesFailed>().is_some() => {
            ExitCode::from(SOME_FRAMES_FAILED)
        }
        Err(_) => ExitCode::FAILURE,
    }
}
