//! The library behind the `pomona` binary: one module per subcommand, the pipeline registry and
//! shared helpers.
//!
//! It is a library (and `main.rs` a thin dispatcher) so tests can drive the pipeline-generic
//! commands (`train`, `detect`, `experiment`, `demo`) with a pipeline list of their own through
//! the `run_with` functions, without shipping a test pipeline in the binary.

pub mod commands;
pub mod detection_run;
pub mod error_line;
pub mod overlay;
pub mod params;
pub mod pipelines;
pub mod progress;
