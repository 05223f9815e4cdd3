//! The exit statuses of `pomona`, documented in the README and `pomona detect --help`:
//!
//! * `0`: success;
//! * `1`: the command failed (bad arguments, unreadable model or dataset, ...);
//! * `2`: the command line could not be parsed (clap's status);
//! * `3` ([`SOME_FRAMES_FAILED`]): a batch finished but some frames failed; every other frame's
//!   output was written and the failures are listed in the output folder's `failures.json`;
//! * `141` ([`STDOUT_CLOSED`]): standard output was closed while printing (`pomona ... | head`);
//!   files already written are kept. The status a shell reports for a process ended by SIGPIPE,
//!   which Rust programs ignore (printing then panics instead; [`exit_quietly_when_stdout_closes`]).

use std::path::PathBuf;
use std::process::ExitCode;

/// Status of a batch in which some frames failed and the rest were written.
pub const SOME_FRAMES_FAILED: u8 = 3;

/// Status when standard output was closed by its reader (128 + SIGPIPE, as a shell reports).
pub const STDOUT_CLOSED: i32 = 141;

/// Makes a print to a closed standard output end the process with [`STDOUT_CLOSED`] and no
/// message, as command-line tools do, instead of a panic and a backtrace. Other panics keep the
/// default report.
pub fn exit_quietly_when_stdout_closes() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or_default();
        if is_closed_stdout(message) {
            std::process::exit(STDOUT_CLOSED);
        }
        default(info);
    }));
}

/// Whether a panic message is the standard library's for printing to a closed stdout.
fn is_closed_stdout(message: &str) -> bool {
    message.starts_with("failed printing to stdout") && message.contains("Broken pipe")
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_closed_stdout_panic_is_quiet() {
        assert!(is_closed_stdout(
            "failed printing to stdout: Broken pipe (os error 32)"
        ));
        assert!(!is_closed_stdout(
            "failed printing to stdout: No space left on device (os error 28)"
        ));
        assert!(!is_closed_stdout("index out of bounds: Broken pipe"));
    }
}
