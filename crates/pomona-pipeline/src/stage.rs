//! One step of a detector behind one small trait.
//!
//! `I` is usually a borrow of the previous stage's output, so a detector stores stages as
//! `Box<dyn for<'a> Stage<&'a X, Y>>` and a benchmark can call any of them on its own input.

use std::time::Instant;

use crate::{PipelineError, StageTimings};

/// A named, thread-safe transformation from one intermediate result to the next.
pub trait Stage<I, O>: Send + Sync {
    /// Short name used in timings and logs, for example `"region-growing"`.
    fn name(&self) -> &'static str;

    /// Runs the stage.
    ///
    /// # Errors
    /// Whatever the stage cannot handle in its input, as a [`PipelineError`].
    fn run(&self, input: I) -> Result<O, PipelineError>;
}

/// Runs `stage` on `input` and adds its wall time to `timings`.
///
/// # Errors
/// The stage's error.
///
/// ```
/// use pomona_pipeline::{run_stage, PipelineError, Stage, StageTimings};
/// struct Double;
/// impl Stage<u32, u32> for Double {
///     fn name(&self) -> &'static str { "double" }
///     fn run(&self, x: u32) -> Result<u32, PipelineError> { Ok(2 * x) }
/// }
/// let mut timings = StageTimings::default();
/// assert_eq!(run_stage(&Double, 21, &mut timings).unwrap(), 42);
/// assert_eq!(timings.entries()[0].0, "double");
/// ```
pub fn run_stage<I, O>(
    stage: &(impl Stage<I, O> + ?Sized),
    input: I,
    timings: &mut StageTimings,
) -> Result<O, PipelineError> {
    let start = Instant::now();
    let out = stage.run(input);
    timings.add(stage.name(), start.elapsed());
    out
}
