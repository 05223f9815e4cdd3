//! Overriding a model's stage parameters before its detector is built.
//!
//! A model file keeps the parameters of a pipeline's non-learnt stages in `stage_params` (a JSON
//! object). Changing one of them in the loaded model (`pruning = false`, `color.threshold = 0.03`)
//! is how a detection-time ablation runs without retraining; the CLI's `--set KEY=VALUE` is this.
//! Keys are dotted paths into the object (`msac.iterations`); the key must already exist, so a
//! typo is an error that lists the keys there are, and the value must have the same JSON type as
//! the one it replaces (`null` may be replaced by anything, and may replace anything: it switches
//! an optional parameter off, and the typed parameters refuse it where it is required).
//!
//! An object given for a group of parameters that is on updates the members it names, each as
//! its own override (`split={"radius_m":0.05}` is `split.radius_m=0.05`); given for a group that
//! is off (`null`), it is the whole group. So one override switches a group on, or retunes it,
//! in two models of which only one has it on (a pipeline's colour and depth-only built-ins).

use std::str::FromStr;

use serde_json::Value;

use crate::Error;

/// Keys listed in an unknown-key message before the rest are only counted.
const MAX_LISTED: usize = 60;

/// One stage-parameter override: a dotted key and its new value. Give them to
/// [`crate::DetectorBuilder::overrides`] (or one at a time with
/// [`crate::DetectorBuilder::set`]).
///
/// ```
/// let o: pomona::ParamOverride = "highlight.enabled=false".parse().unwrap();
/// assert_eq!(o, pomona::ParamOverride::new("highlight.enabled", false));
/// assert!("no-equals-sign".parse::<pomona::ParamOverride>().is_err());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ParamOverride {
    /// Dotted path into `stage_params`, e.g. `msac.iterations`.
    pub key: String,
    /// The new value.
    pub value: Value,
}

impl ParamOverride {
    /// An override of `key` by `value`.
    pub fn new(key: impl Into<String>, value: impl Into<Value>) -> Self {
        Self {
            key: key.into(),
            value: value.into(),
        }
    }
}

impl FromStr for ParamOverride {
    type Err = String;

    /// Parses `key=value`: the value as JSON (`true`, `25`, `0.5`, `"x"`, `[1,2]`), and anything
    /// that is not JSON as a string (`frame=symmetry`).
    ///
    /// # Errors
    /// No `=`, or an empty key or key segment.
    fn from_str(s: &str) -> Result<Self, String> {
        let Some((key, value)) = s.split_once('=') else {
            return Err(format!("expected KEY=VALUE, got `{s}`"));
        };
        let key = key.trim();
        if key.is_empty() || key.split('.').any(str::is_empty) {
            return Err(format!("`{s}` has an empty key"));
        }
        let value = value.trim();
        let value = serde_json::from_str(value).unwrap_or_else(|_| Value::String(value.to_owned()));
        Ok(Self::new(key, value))
    }
}

/// The overrides as one JSON object (dotted keys kept as they are), for reports.
///
/// ```
/// let json = pomona::overrides_to_json(&[pomona::ParamOverride::new("a.b", 1)]);
/// assert_eq!(json.to_string(), r#"{"a.b":1}"#);
/// ```
pub fn overrides_to_json(overrides: &[ParamOverride]) -> Value {
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

/// Every settable key of `params` (dotted paths to non-object values): what a model's
/// `stage_params` offer to [`crate::DetectorBuilder::set`].
///
/// ```
/// let params = serde_json::json!({"msac": {"iterations": 500}, "pruning": true});
/// assert_eq!(pomona::settable_keys(&params), ["msac.iterations", "pruning"]);
/// ```
pub fn settable_keys(params: &Value) -> Vec<String> {
    let mut keys = Vec::new();
    leaf_keys(params, "", &mut keys);
    keys
}

/// The value at the dotted `key` through nested objects of `params`.
fn at<'a>(params: &'a Value, key: &str) -> Option<&'a Value> {
    key.split('.')
        .try_fold(params, |v, k| v.as_object()?.get(k))
}

/// [`at`], mutable.
fn at_mut<'a>(params: &'a mut Value, key: &str) -> Option<&'a mut Value> {
    key.split('.')
        .try_fold(params, |v, k| v.as_object_mut()?.get_mut(k))
}

/// Applies `overrides` in order to `params`; `what` names the parameters' owner in messages
/// ("the model of `shape-fit` (the built-in model)"). A value replaces one parameter; `null`
/// also switches off an optional group of them (`ray_circles=null`).
///
/// ```
/// let mut params = serde_json::json!({"msac": {"iterations": 500}});
/// let set = [pomona::ParamOverride::new("msac.iterations", 100)];
/// pomona::apply_overrides(&mut params, &set, "my model")?;
/// assert_eq!(params["msac"]["iterations"], 100);
/// let typo = [pomona::ParamOverride::new("msac.iteration", 100)];
/// assert!(pomona::apply_overrides(&mut params, &typo, "my model").is_err());
/// # Ok::<(), pomona::Error>(())
/// ```
///
/// # Errors
/// [`Error::UnknownParameter`] for a key that does not exist (the message lists the keys that
/// do), [`Error::ParameterType`] for a value of another JSON type than the one it replaces
/// (other than `null`).
pub fn apply_overrides(
    params: &mut Value,
    overrides: &[ParamOverride],
    what: &str,
) -> Result<(), Error> {
    for o in overrides {
        // An object for a group that is on: each member as its own override.
        if let Value::Object(members) = &o.value {
            if at(params, &o.key).is_some_and(Value::is_object) {
                let each: Vec<ParamOverride> = members
                    .iter()
                    .map(|(k, v)| ParamOverride::new(format!("{}.{k}", o.key), v.clone()))
                    .collect();
                apply_overrides(params, &each, what)?;
                continue;
            }
        }
        // A group of parameters that is on is not replaced by a value that is not an object
        // (objects were merged above), only switched off (`null`), when optional.
        let slot = at_mut(params, &o.key).filter(|s| !s.is_object() || o.value.is_null());
        let Some(slot) = slot else {
            let keys = settable_keys(params);
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
            return Err(Error::UnknownParameter {
                key: o.key.clone(),
                owner: what.to_owned(),
                known,
            });
        };
        // `null` switches an optional parameter off; on a required one the typed parameters
        // refuse it when they are read back.
        let same_type = std::mem::discriminant(slot) == std::mem::discriminant(&o.value);
        if !same_type && !slot.is_null() && !o.value.is_null() {
            return Err(Error::ParameterType {
                key: o.key.clone(),
                owner: what.to_owned(),
                expected: type_name(slot),
                current: slot.to_string(),
                got: o.value.to_string(),
            });
        }
        *slot = o.value.clone();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn parse(s: &str) -> ParamOverride {
        s.parse().unwrap()
    }

    #[test]
    fn parses_json_values_and_bare_strings() {
        let o = parse("pruning=false");
        assert_eq!((o.key.as_str(), &o.value), ("pruning", &json!(false)));
        assert_eq!(parse("a.b=2.5").value, json!(2.5));
        assert_eq!(parse("frame=symmetry").value, json!("symmetry"));
        assert_eq!(parse("x=[1, 2]").value, json!([1, 2]));
        for bad in ["novalue", "=3", "a..b=3"] {
            assert!(bad.parse::<ParamOverride>().is_err(), "{bad}");
        }
    }

    #[test]
    fn applies_dotted_keys_and_rejects_unknown_keys_and_types() {
        let mut p = json!({"pruning": true, "msac": {"iterations": 500, "t_m": 0.025}});
        apply_overrides(&mut p, &[parse("pruning=false")], "m").unwrap();
        apply_overrides(&mut p, &[parse("msac.iterations=100")], "m").unwrap();
        assert_eq!(
            p,
            json!({"pruning": false, "msac": {"iterations": 100, "t_m": 0.025}})
        );
        let err = apply_overrides(&mut p, &[parse("prunning=false")], "model x").unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("prunning") && msg.contains("msac.t_m") && msg.contains("model x"),
            "{msg}"
        );
        assert!(
            apply_overrides(&mut p, &[parse("msac=3")], "m").is_err(),
            "objects are not leaves"
        );
        let err = apply_overrides(&mut p, &[parse("pruning=7")], "m").unwrap_err();
        assert!(err.to_string().contains("a boolean"), "{err}");
        apply_overrides(&mut p, &[parse("msac.t_m=null")], "m").unwrap();
        assert_eq!(p["msac"]["t_m"], Value::Null);
        assert_eq!(settable_keys(&p).len(), 3);
        assert_eq!(overrides_to_json(&[parse("a.b=1")]), json!({"a.b": 1}));
        // A group is switched off whole (an optional stage), never replaced by a value.
        apply_overrides(&mut p, &[parse("msac=null")], "m").unwrap();
        assert_eq!(p["msac"], Value::Null);
    }

    #[test]
    fn an_object_updates_a_group_that_is_on_and_sets_one_that_is_off() {
        let on = json!({"split": {"radius_m": 0.06, "max_discs": 2.0}, "x": 1});
        let off = json!({"split": null, "x": 1});
        let whole = parse(r#"split={"radius_m": 0.05, "max_discs": 3.0}"#);
        for start in [&on, &off] {
            let mut p = start.clone();
            apply_overrides(&mut p, std::slice::from_ref(&whole), "m").unwrap();
            assert_eq!(p["split"], json!({"radius_m": 0.05, "max_discs": 3.0}));
        }
        // On, only the members named change; each must exist and keep its type.
        let mut p = on.clone();
        apply_overrides(&mut p, &[parse(r#"split={"radius_m": 0.04}"#)], "m").unwrap();
        assert_eq!(p["split"], json!({"radius_m": 0.04, "max_discs": 2.0}));
        let typo = apply_overrides(&mut p, &[parse(r#"split={"radius": 0.04}"#)], "m");
        assert!(
            matches!(&typo, Err(Error::UnknownParameter { key, .. }) if key == "split.radius"),
            "{typo:?}"
        );
        let wrong = apply_overrides(&mut p, &[parse(r#"split={"max_discs": "two"}"#)], "m");
        assert!(
            matches!(wrong, Err(Error::ParameterType { .. })),
            "{wrong:?}"
        );
    }
}
