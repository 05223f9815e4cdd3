//! Errors of the symmetry detectors' stages, converted to [`PipelineError`] at the pipeline
//! boundary so the CLI sees one error type for every method.

use pomona_consensus::ConsensusError;
use pomona_pipeline::PipelineError;

/// Why a stage of the `symmetry` / `viewer-pose` detectors could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SymmetryError {
    /// A stage parameter is out of range.
    #[error("invalid parameter `{name}` ({value}): {reason}")]
    InvalidParameter {
        /// Parameter path as in the model's `stage_params`, e.g. `boxes.stride_m`.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A scene cloud needs an organised cloud of its camera's size.
    #[error(
        "the scene cloud must be organised as the camera's {expected:?} pixels, found {found:?}"
    )]
    NotOrganized {
        /// The camera's `(width, height)`.
        expected: (u32, u32),
        /// The cloud's grid, `None` when unorganised.
        found: Option<(u32, u32)>,
    },
    /// Normal estimation failed (for example the cloud is not organised).
    #[error("normal estimation: {0}")]
    Normals(#[from] ConsensusError),
}

impl From<SymmetryError> for PipelineError {
    fn from(e: SymmetryError) -> Self {
        match e {
            SymmetryError::InvalidParameter {
                name,
                value,
                reason,
            } => PipelineError::InvalidParameter {
                name: name.to_owned(),
                reason: format!("{value}: {reason}"),
            },
            other => PipelineError::StageParams(other.to_string()),
        }
    }
}

/// `Ok` when `value` is finite and strictly positive.
pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<(), SymmetryError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SymmetryError::InvalidParameter {
            name,
            value,
            reason: "must be finite and > 0",
        })
    }
}

/// `Ok` when `value` is at least `min`.
pub(crate) fn check_at_least(
    name: &'static str,
    value: usize,
    min: usize,
) -> Result<(), SymmetryError> {
    if value >= min {
        Ok(())
    } else {
        Err(SymmetryError::InvalidParameter {
            name,
            value: value as f64,
            reason: "is below its minimum",
        })
    }
}
