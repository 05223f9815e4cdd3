//! The three keys of a model file checked before the rest is parsed (`format`, `version`,
//! `pipeline`), read without building the whole document in memory: every other key is
//! skipped as it is parsed, and a key of an unexpected type is reduced to a short description.
//!
//! Why: a generic JSON value takes up to about 25 times its text in memory, so reading the
//! whole file as one (as an earlier version did) let a small hostile file claim far more memory
//! than its size.

use serde::de::{Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;

/// The keys checked first; `None` when absent.
#[derive(Debug, Deserialize)]
pub(crate) struct ModelHead {
    #[serde(default)]
    pub(crate) format: Option<Peek>,
    #[serde(default)]
    pub(crate) version: Option<Peek>,
    #[serde(default)]
    pub(crate) pipeline: Option<Peek>,
}

/// A JSON value reduced to what the checks need.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Peek {
    /// A string.
    Str(String),
    /// A non-negative integer.
    Unsigned(u64),
    /// Anything else, as JSON text (scalars) or a description (`an array`, `an object`).
    Other(String),
}

impl Peek {
    /// The value as shown in an error message: JSON text for scalars.
    pub(crate) fn describe(&self) -> String {
        match self {
            Peek::Str(s) => serde_json::Value::from(s.as_str()).to_string(),
            Peek::Unsigned(v) => v.to_string(),
            Peek::Other(s) => s.clone(),
        }
    }

    pub(crate) fn as_str(&self) -> Option<&str> {
        match self {
            Peek::Str(s) => Some(s),
            _ => None,
        }
    }

    pub(crate) fn as_u64(&self) -> Option<u64> {
        match self {
            Peek::Unsigned(v) => Some(*v),
            _ => None,
        }
    }
}

impl<'de> Deserialize<'de> for Peek {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(PeekVisitor)
    }
}

struct PeekVisitor;

impl<'de> Visitor<'de> for PeekVisitor {
    type Value = Peek;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("any JSON value")
    }

    fn visit_str<E>(self, v: &str) -> Result<Peek, E> {
        Ok(Peek::Str(v.to_owned()))
    }

    fn visit_u64<E>(self, v: u64) -> Result<Peek, E> {
        Ok(Peek::Unsigned(v))
    }

    fn visit_i64<E>(self, v: i64) -> Result<Peek, E> {
        Ok(Peek::Other(v.to_string()))
    }

    fn visit_f64<E>(self, v: f64) -> Result<Peek, E> {
        Ok(Peek::Other(serde_json::Value::from(v).to_string()))
    }

    fn visit_bool<E>(self, v: bool) -> Result<Peek, E> {
        Ok(Peek::Other(v.to_string()))
    }

    fn visit_unit<E>(self) -> Result<Peek, E> {
        Ok(Peek::Other("null".into()))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Peek, A::Error> {
        while seq.next_element::<IgnoredAny>()?.is_some() {}
        Ok(Peek::Other("an array".into()))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Peek, A::Error> {
        while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
        Ok(Peek::Other("an object".into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_peeked_and_the_rest_skipped() {
        let head: ModelHead = serde_json::from_str(
            r#"{"svm": [1, 2, {"a": []}], "format": "pomona-model", "version": 1, "pipeline": [3]}"#,
        )
        .unwrap();
        assert_eq!(head.format.unwrap().as_str(), Some("pomona-model"));
        assert_eq!(head.version.unwrap().as_u64(), Some(1));
        assert_eq!(head.pipeline.unwrap().describe(), "an array");
        let head: ModelHead = serde_json::from_str(r#"{"version": -1.5}"#).unwrap();
        assert!(head.format.is_none());
        assert_eq!(head.version.unwrap().describe(), "-1.5");
    }
}
