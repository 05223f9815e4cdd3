//! The JSON round trip behind [`Pipeline::train_params`](crate::Pipeline::train_params) and
//! [`Pipeline::with_train_params`](crate::Pipeline::with_train_params): a pipeline's training
//! parameters go out as JSON, `--set`/`--train-set` edit keys, and they come back typed. Every
//! pipeline does the same two conversions, so they live here once.

use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::PipelineError;

/// Training parameters as JSON (`Null` for a type that cannot be written as JSON, which the
/// caller then reports as having no settable parameters).
pub fn params_to_json<T: Serialize>(params: &T) -> serde_json::Value {
    serde_json::to_value(params).unwrap_or(serde_json::Value::Null)
}

/// Edited training parameters back as their type.
///
/// # Errors
/// [`PipelineError::InvalidParameter`] (named `--set`) when a value has the wrong type or a
/// required key is missing.
pub fn params_from_json<T: DeserializeOwned>(value: serde_json::Value) -> Result<T, PipelineError> {
    serde_json::from_value(value).map_err(|e| PipelineError::InvalidParameter {
        name: "--set".into(),
        reason: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    struct P {
        radius_m: f64,
    }

    #[test]
    fn round_trip_and_type_errors() {
        let json = params_to_json(&P { radius_m: 0.03 });
        assert_eq!(json["radius_m"], 0.03);
        assert_eq!(params_from_json::<P>(json).unwrap(), P { radius_m: 0.03 });
        let err = params_from_json::<P>(serde_json::json!({"radius_m": "big"})).unwrap_err();
        assert!(err.to_string().contains("--set"), "{err}");
    }
}
