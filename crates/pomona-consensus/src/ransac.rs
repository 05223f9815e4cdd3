//! Plain RANSAC (Fischler & Bolles 1981): the hypothesis with the most inliers wins.
//!
//! Kept for comparison with [`crate::Msac`]: it shares the sampler, estimators and loop, and
//! differs only in the per-residual score (0 for an inlier, 1 for an outlier), so every inlier
//! counts the same however well it fits. Its [`crate::Fit::cost`] is the outlier fraction.

use serde::{Deserialize, Serialize};

use crate::consensus::{check_fraction, check_positive, run_loop, LoopSettings};
use crate::{Consensus, ConsensusError, Estimator, Fit, Sampler};

/// RANSAC parameters; validate with [`RansacParams::check`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RansacParams {
    /// Residual below which a point is an inlier, metres (default 10 mm).
    pub inlier_threshold_m: f64,
    /// Number of hypotheses (default 500, as MSAC).
    pub iterations: usize,
    /// Stop early once an all-inlier sample has been drawn with this probability (see
    /// [`crate::MsacParams::early_stop_confidence`]); `None` (default) runs every iteration.
    pub early_stop_confidence: Option<f64>,
    /// Minimum inlier fraction of the valid points to accept the model (`None`: always accept).
    pub min_inlier_fraction: Option<f64>,
    /// Residual below which points support least-squares refinement, metres; `None` skips it.
    pub refine_threshold_m: Option<f64>,
}

impl Default for RansacParams {
    fn default() -> Self {
        Self {
            inlier_threshold_m: 0.010,
            iterations: 500,
            early_stop_confidence: None,
            min_inlier_fraction: None,
            refine_threshold_m: Some(0.010),
        }
    }
}

impl RansacParams {
    /// Validates the parameters into a runnable [`Ransac`].
    ///
    /// # Errors
    /// [`ConsensusError::InvalidParameter`] when a threshold is not finite and positive, the
    /// fraction is outside `(0, 1]`, `iterations` is zero or the early-stop confidence is outside
    /// `(0, 1)`.
    pub fn check(self) -> Result<Ransac, ConsensusError> {
        check_positive("inlier_threshold_m", self.inlier_threshold_m)?;
        if let Some(r) = self.refine_threshold_m {
            check_positive("refine_threshold_m", r)?;
        }
        if let Some(f) = self.min_inlier_fraction {
            check_fraction("min_inlier_fraction", f)?;
        }
        if let Some(c) = self.early_stop_confidence {
            if !(c > 0.0 && c < 1.0) {
                return Err(ConsensusError::InvalidParameter {
                    name: "early_stop_confidence",
                    value: c,
                    reason: "must lie in (0, 1)",
                });
            }
        }
        if self.iterations == 0 {
            return Err(ConsensusError::InvalidParameter {
                name: "iterations",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        Ok(Ransac { params: self })
    }
}

/// A validated RANSAC loop; build it with [`RansacParams::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ransac {
    params: RansacParams,
}

impl Ransac {
    /// The validated parameters.
    pub fn params(&self) -> &RansacParams {
        &self.params
    }
}

impl Consensus for Ransac {
    fn fit<D, E, S>(
        &self,
        estimator: &E,
        data: &[D],
        sampler: &mut S,
    ) -> Result<Option<Fit<E::Model>>, ConsensusError>
    where
        E: Estimator<D>,
        S: Sampler,
    {
        let p = &self.params;
        let thr = p.inlier_threshold_m;
        let settings = LoopSettings {
            iterations: p.iterations,
            confidence: p.early_stop_confidence,
            inlier_threshold_m: thr,
            refine_threshold_m: p.refine_threshold_m,
            max_scored_points: None,
        };
        let result = run_loop(estimator, data, sampler, &settings, |e| {
            if e < thr {
                0.0
            } else {
                1.0
            }
        })?;
        Ok(result.map(|r| {
            let cost = r.total_score / r.valid_points as f64;
            Fit {
                model: r.model,
                inliers: r.inliers,
                inlier_mean_residual_m: r.inlier_mean_residual_m,
                cost,
                accepted: p.min_inlier_fraction.is_none_or(|f| 1.0 - cost >= f),
                valid_points: r.valid_points,
                models_scored: r.models_scored,
                iterations_run: r.iterations_run,
            }
        }))
    }
}
