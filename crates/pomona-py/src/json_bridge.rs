//! Values that cross between Rust and Python as JSON: detections, truth, evaluation reports and
//! the camera dictionary all have a JSON form (docs/formats.md), so they cross through it.
//!
//! Why: a Python dict made from the JSON a Rust value serialises to has exactly the keys and
//! values of the file `pomona detect` or `pomona eval` writes, with no second description of
//! each type to keep in step. The cost (microseconds per frame) is nothing beside detection.

use pomona::ParamOverride;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::py_error::to_py;

/// `value` as the Python object of its JSON form (dicts, lists, floats, strings, `None`).
///
/// # Errors
/// `PomonaError` if `value` cannot be serialised (non-string map keys), or Python's `json`
/// module fails.
pub fn to_python<'py>(py: Python<'py>, value: &impl Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(to_py)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// The Rust value of type `T` whose JSON form is the Python object `obj`; `what` names it in
/// errors (for example "camera").
///
/// # Errors
/// `PomonaError` naming `what` when `obj` is not JSON-serialisable or not a valid `T`.
pub fn from_python<T: DeserializeOwned>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<T> {
    let text: String = obj
        .py()
        .import("json")?
        .call_method1("dumps", (obj,))
        .map_err(|e| to_py(format!("{what} is not JSON-serialisable: {e}")))?
        .extract()?;
    serde_json::from_str(&text).map_err(|e| to_py(format!("invalid {what} {text}: {e}")))
}

/// A constructor's `set={"dotted.key": value}` as parameter overrides, in the dict's order.
///
/// # Errors
/// `TypeError` for a key that is not a string, `PomonaError` for a value that is not
/// JSON-serialisable.
pub fn overrides_from(set: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<ParamOverride>> {
    let Some(set) = set else {
        return Ok(Vec::new());
    };
    set.iter()
        .map(|(key, value)| {
            let key: String = key.extract()?;
            let value: serde_json::Value = from_python(&value, &format!("value of `{key}`"))?;
            Ok(ParamOverride::new(key, value))
        })
        .collect()
}
