//! What a detector knows about the model it runs: where it came from, a stable identity, and its
//! operating confidence.
//!
//! The identity ([`ModelInfo::id`]) is written into every detection file so a resumed or merged
//! batch can tell detections of one model from another's: it is a 64-bit FNV-1a hash of the
//! model's compact JSON after parameter overrides (two models that detect identically hash
//! identically; it is an identity check, not a security hash).

use std::fmt;
use std::path::PathBuf;

use pomona_learn::ModelFile;

/// Where a model came from, for messages and reports (see [`ModelInfo`] for an example).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ModelSource {
    /// A model file on disk.
    File(PathBuf),
    /// The pipeline's model compiled into the library.
    BuiltIn,
    /// The pipeline's depth-only model compiled into the library (frames without colour).
    BuiltInDepthOnly,
    /// A model handed over in memory (for example just trained), with a label for messages.
    InMemory(String),
}

impl fmt::Display for ModelSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::File(p) => write!(f, "{}", p.display()),
            Self::BuiltIn => f.write_str("the built-in model"),
            Self::BuiltInDepthOnly => f.write_str("the built-in depth-only model"),
            Self::InMemory(label) => f.write_str(label),
        }
    }
}

/// A loaded model's provenance and operating point.
///
/// ```
/// let detector = pomona::Detector::builtin("shape-fit")?;
/// let model = detector.model();
/// assert_eq!(model.source, pomona::ModelSource::BuiltIn);
/// assert_eq!(model.id.len(), 16);
/// assert!(model.operating_confidence.is_some(), "built-in models are calibrated");
/// # Ok::<(), pomona::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ModelInfo {
    /// Where it came from.
    pub source: ModelSource,
    /// Stable identity: 16 hex digits of the FNV-1a hash of the model's JSON (after overrides).
    pub id: String,
    /// The calibrated confidence at or above which detections are reported by default (`None`
    /// for a model without calibration).
    pub operating_confidence: Option<f64>,
}

impl ModelInfo {
    /// The info of `model` (already overridden) from `source`.
    pub(crate) fn of(model: &ModelFile, source: ModelSource) -> Self {
        // Serialising a plain struct of numbers, strings and JSON values cannot fail; an empty
        // text would still give a stable (if shared) identity.
        let json = serde_json::to_vec(model).unwrap_or_default();
        Self {
            source,
            id: format!("{:016x}", fnv1a64(&json)),
            operating_confidence: model.calibration.map(|c| c.operating_confidence),
        }
    }
}

/// 64-bit FNV-1a of `bytes`.
fn fnv1a64(bytes: &[u8]) -> u64 {
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    bytes
        .iter()
        .fold(OFFSET, |h, &b| (h ^ u64::from(b)).wrapping_mul(PRIME))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_matches_the_reference_vectors() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }
}
