//! `pomona.PomonaError`: the one Python exception for everything the Rust side reports (an
//! unknown pipeline, an unreadable model or dataset file, a frame whose sizes disagree...), with
//! the Rust message, which names the file, model or frame at fault.

use pyo3::exceptions::PyException;
use pyo3::PyErr;

pyo3::create_exception!(
    pomona,
    PomonaError,
    PyException,
    "A Pomona error; the message names the file, model, parameter or frame at fault."
);

/// The Python exception of any Rust error.
pub fn to_py(e: impl std::fmt::Display) -> PyErr {
    PomonaError::new_err(e.to_string())
}
