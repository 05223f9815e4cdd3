//! The native part of the `pomona` Python package (`pomona._pomona`): thin PyO3 wrappers over the
//! Rust facade (`pomona::Detector`, `pomona::Dataset`, `pomona::Tracker`) and the synthesis and
//! evaluation crates.
//!
//! Why a separate crate: the Python package is a front end beside the CLI (top layer), and it
//! must add nothing of its own to what is detected: every wrapper converts Python values in,
//! calls the same Rust function `pomona detect` calls, and converts the result out, so the
//! detections equal the CLI's files. Depth arrives as a numpy array and is converted once (to
//! metres, `f32`); detection runs with the GIL released, so Python threads (and Dask) can detect
//! in parallel. The Python side (`python/pomona/`) adds the module-level `detect`, type stubs and
//! the Dask runner, which prepares its output folder and writes its failures list through the
//! facade's code as the CLI does.

mod frame_arrays;
mod json_bridge;
mod py_dataset;
mod py_detector;
mod py_error;
mod py_evaluate;
mod py_failures_list;
mod py_stereo;
mod py_synth;
mod py_tracker;

use pyo3::prelude::*;

/// Fruit detection in 3D for harvesting robots (native module; import `pomona`).
#[pymodule]
fn _pomona(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("PomonaError", m.py().get_type::<py_error::PomonaError>())?;
    m.add_class::<py_detector::Detector>()?;
    m.add_class::<py_dataset::Dataset>()?;
    m.add_class::<py_tracker::Tracker>()?;
    m.add_class::<py_tracker::Track>()?;
    m.add_class::<py_stereo::StereoLocator>()?;
    m.add_function(wrap_pyfunction!(pipelines, m)?)?;
    m.add_function(wrap_pyfunction!(py_synth::synth, m)?)?;
    m.add_function(wrap_pyfunction!(py_evaluate::evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(py_failures_list::write_failures, m)?)?;
    Ok(())
}

/// The names of the detection pipelines this build ships, e.g. ``["shape-fit", "symmetry", ...]``.
#[pyfunction]
fn pipelines() -> Vec<&'static str> {
    pomona::pipelines().iter().map(|p| p.name()).collect()
}
