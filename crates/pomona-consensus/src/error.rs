//! Errors raised when the input to a consensus fit, a shape extraction or a normal estimation
//! cannot be used.
//!
//! Invalid *points* (non-finite coordinates, missing normals where one is needed) are not errors:
//! they are skipped. An error means the request as a whole cannot be answered, for example because
//! a parameter is out of range or too few valid points remain.

/// Why a consensus, extraction or normal-estimation request was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConsensusError {
    /// A parameter is not finite, not positive, or outside its allowed range.
    #[error("parameter `{name}` is invalid ({value}): {reason}")]
    InvalidParameter {
        /// Field name in the params struct.
        name: &'static str,
        /// The offending value (as `f64`, counts converted).
        value: f64,
        /// What the value must satisfy.
        reason: &'static str,
    },
    /// Fewer valid data than the estimator's minimal sample.
    #[error("{what}: need at least {needed} valid points, got {valid}")]
    TooFewPoints {
        /// Which input.
        what: &'static str,
        /// Points required.
        needed: usize,
        /// Valid points supplied.
        valid: usize,
    },
    /// A grid-based operation was given an unorganised cloud.
    #[error("{what}: the cloud is not organised (it has no image grid)")]
    NotOrganized {
        /// Which operation.
        what: &'static str,
    },
}
