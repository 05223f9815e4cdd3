//! `--set key=value`: overriding a pipeline's stage parameters from the command line.
//!
//! A model file keeps the parameters of a pipeline's non-learnt stages in `stage_params` (a JSON
//! object). `pomona detect --set pruning=false` changes one of them in the loaded model before the
//! detector is built, which is how a detection-time ablation (seed 000's pruning on/off) runs
//! without retraining. Keys are dotted paths into the object (`msac.iterations`); the key must
//! already exist, so a typo is an error that lists the keys there are, and the value must have the
//! same JSON type as the one it replaces. Values are parsed as JSON (`true`, `25`, `0.5`,
//! `"x"`, `[1,2]`), and anything that is not JSON is taken as a string (`frame=symmetry`).

use anyhow::{bail, Result};
use serde_json::Value;

/// Keys listed in an unknown-key message before the rest are only counted.
const MAX_LISTED: usize = 60;

/// One `--set key=value`.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamOverride {
    /// Dotted path into `stage_params`.
    pub key: String,
    /// The new value.
    pub value: Value,
}

/// Parses `key=value` (clap value parser of `--set`).
///
/// # Errors
/// No `=`, or an empty key or key segment.
pub fn parse_override(s: &str) -> Result<ParamOverride, String> {
    let Some((key, value)) = s.split_once('=') else {
        return Err(format!("expected KEY=VALUE, got `{s}`"));
    };
    let key = key.trim();
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(format!("`{s}` has an empty key"));
    }
    let value = value.trim();
    let value = serde_json::from_str(value).unwrap_or_else(|_| Value::String(value.to_owned()));
    Ok(ParamOverride {
        key: key.to_owned(),
        value,
    })
}

/// The overrides as one JSON object (dotted keys kept as they are), for reports.
pub fn to_json(overrides: &[ParamOverride]) -> Value {
    Value::Object(
        overrides
            .iter()
            .map(|o| (o.key.clone(), o.value.clone()))
            .collect(),
    )
}

fn type_name(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

fn leaf_keys(v: &Value, prefix: &str, out: &mut Vec<String>) {
    if let Value::Object(map) = v {
        for (k, child) in map {
            let path = if prefix.is_empty() {
                k.clone()
            } else {
                format!("{prefix}.{k}")
            };
            if child.is_object() {
                leaf_keys(child, &path, out);
            } else {
                out.push(path);
            }
        }
    }
}

/// Every settable key of `stage_params` (dotted paths to non-object values).
pub fn settable_keys(stage_params: &Value) -> Vec<String> {
    let mut keys = Vec::new();
    leaf_keys(stage_params, "", &mut keys);
    keys
}

/// Applies `overrides` in order to `stage_params`; `what` names the model in messages.
///
/// # Errors
/// A key that does not exist (the message lists the keys that do) or a value of another JSON
/// type than the one it replaces (`null` may be replaced by anything).
pub fn apply(stage_params: &mut Value, overrides: &[ParamOverride], what: &str) -> Result<()> {
    for o in overrides {
        let keys = settable_keys(stage_params);
        let mut slot = Some(&mut *stage_params);
        for segment in o.key.split('.') {
            slot = slot
                .and_then(|v| v.as_object_mut())
                .and_then(|m| m.get_mut(segment));
        }
        let Some(slot) = slot.filter(|s| !s.is_object()) else {
            let known = if keys.is_empty() {
                "it has no stage parameters".to_owned()
            } else if keys.len() > MAX_LISTED {
                format!(
                    "its parameters are: {}, and {} more",
                    keys[..MAX_LISTED].join(", "),
                    keys.len() - MAX_LISTED
                )
            } else {
                format!("its parameters are: {}", keys.join(", "))
            };
            bail!(
                "--set {}: {what} has no parameter `{}`; {known}",
                o.key,
                o.key
            );
        };
        let same_type = std::mem::discriminant(slot) == std::mem::discriminant(&o.value);
        if !same_type && !slot.is_null() {
            bail!(
                "--set {}: {what} expects {} (currently {}), got {}",
                o.key,
                type_name(slot),
                slot,
                o.value
            );
        }
        *slot = o.value.clone();
    }
    Ok(())
}

/// `pipeline` with `overrides` applied to its training parameters (unchanged without
/// overrides).
///
/// # Errors
/// An unknown key or a value of the wrong type (listing the keys there are), or parameters the
/// pipeline rejects.
pub fn configured(
    pipeline: &dyn pomona_pipeline::Pipeline,
    overrides: &[ParamOverride],
) -> Result<Option<Box<dyn pomona_pipeline::Pipeline>>> {
    if overrides.is_empty() {
        return Ok(None);
    }
    let mut train_params = pipeline.train_params();
    apply(&mut train_params, overrides, "training parameters")?;
    Ok(Some(pipeline.with_train_params(train_params)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn parses_json_values_and_bare_strings() {
        let o = parse_override("pruning=false").unwrap();
        assert_eq!((o.key.as_str(), &o.value), ("pruning", &json!(false)));
        assert_eq!(parse_override("a.b=2.5").unwrap().value, json!(2.5));
        assert_eq!(
            parse_override("frame=symmetry").unwrap().value,
            json!("symmetry")
        );
        assert_eq!(parse_override("x=[1, 2]").unwrap().value, json!([1, 2]));
        assert!(parse_override("novalue").is_err());
        assert!(parse_override("=3").is_err());
        assert!(parse_override("a..b=3").is_err());
    }

    #[test]
    fn applies_dotted_keys_and_rejects_unknown_keys_and_types() {
        let mut p = json!({"pruning": true, "msac": {"iterations": 500, "t_m": 0.025}});
        let set = |s: &str| vec![parse_override(s).unwrap()];
        apply(&mut p, &set("pruning=false"), "m").unwrap();
        apply(&mut p, &set("msac.iterations=100"), "m").unwrap();
        assert_eq!(
            p,
            json!({"pruning": false, "msac": {"iterations": 100, "t_m": 0.025}})
        );
        let err = apply(&mut p, &set("prunning=false"), "model x").unwrap_err();
        let msg = format!("{err:#}");
        assert!(
            msg.contains("prunning") && msg.contains("msac.t_m"),
            "{msg}"
        );
        assert!(
            apply(&mut p, &set("msac=3"), "m").is_err(),
            "objects are not leaves"
        );
        let err = apply(&mut p, &set("pruning=7"), "m").unwrap_err();
        assert!(format!("{err:#}").contains("a boolean"), "{err:#}");
        assert_eq!(settable_keys(&p).len(), 3);
        assert_eq!(to_json(&set("a.b=1")), json!({"a.b": 1}));
    }
}
