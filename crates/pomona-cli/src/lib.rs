//! The library behind the `pomona` binary: one module per subcommand and shared helpers, over the
//! `pomona` library (which holds the pipeline registry and the detector facade).
//!
//! It is a library (and `main.rs` a thin dispatcher) so tests can drive the pipeline-generic
//! commands (`train`, `detect`, `experiment`, `demo`) with a pipeline list of their own through
//! the `run_with` functions, without shipping a test pipeline in the binary.

pub mod commands;
pub mod detect_input;
pub mod detection_run;
pub mod error_line;
pub mod exit_status;
pub mod matching_args;
pub mod number_pair;
pub mod overlay;
pub mod params;
pub mod progress;
pub mod recording;
pub mod robot_recording;
pub mod shard;
