//! MSAC, M-estimator sample consensus (Torr & Murray 1997), as seed 002 uses it (Eqs. 4–5).
//!
//! Each hypothesis is scored by the *mean* truncated residual over all valid points of the cloud:
//! `E = Σ ρ(eᵢ) / N` with `ρ(e) = e` for `e < T` and `ρ(e) = T` otherwise. Unlike RANSAC's inlier
//! count, inliers contribute how well they fit, so among models with similar support the tighter
//! one wins. After `L` hypotheses the lowest-cost model is *accepted* only when `E ≤ d`
//! (Algorithm 1 starts its running minimum at `d`, so nothing costlier is ever chosen).
//!
//! ## Units and defaults
//! The paper states `T = 25 mm` and `d = 2 mm` with residuals in millimetres; everything here is in
//! metres, so the defaults are `cost_threshold_m = 0.025` and `acceptance_cost_m = 0.002`, with
//! `iterations = 500` (`L`).
//!
//! Because `E` averages over *all* points, the paper's acceptance test also bounds the outlier
//! fraction: points farther than `T` each add `T`, so a cloud with more than `d / T = 8 %` of its
//! points off the shape can never be accepted with the defaults — including a cluster holding two
//! similar fruits, which Algorithm 1 is meant to split. [`Acceptance::MeanCost`] is that literal
//! test (the default); [`Acceptance::InlierResidual`] (our addition) instead bounds the mean
//! residual of the model's own inliers and requires a minimum inlier fraction, which lets
//! repeated extraction find several shapes in one cluster and tolerates clutter.
//!
//! A large `T` is also forgiving of clutter *near* the fruit: with outliers packed around a 40 mm
//! sphere (half the points, uniform in a 20 cm cube), a larger sphere grazing many outliers within
//! 25 mm can cost less than the true one. In our tests `T = 10 mm` recovers the fruit there,
//! while `T = 25 mm` does when the same outliers are spread over a 30 cm cube.
//!
//! ## Additions beyond the paper (each optional)
//! * [`CostFunction::TruncatedQuadratic`] (`ρ(e) = min(e², T²)`, the classic MSAC of Torr &
//!   Zisserman); its reported cost is the root of the mean so it stays in metres and is compared
//!   with `d` directly.
//! * A least-squares refinement of the best model on points within `refine_threshold_m`, kept
//!   only when it does not raise `E`.
//! * Adaptive early stopping (`early_stop_confidence`), off by default.
//! * The paper does not define "inliers" for Algorithm 1's removal step; we use the points whose
//!   residual is below `inlier_threshold_m`, by default `T` (the points whose cost is not
//!   truncated, MSAC's own notion of inlier).

use serde::{Deserialize, Serialize};

use crate::consensus::{check_fraction, check_positive, run_loop, LoopSettings};
use crate::{Consensus, ConsensusError, Estimator, Fit, Sampler};

/// The per-residual cost ρ of MSAC.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum CostFunction {
    /// `ρ(e) = min(e, T)` — seed 002 Eq. 5. Cost in metres.
    #[default]
    TruncatedLinear,
    /// `ρ(e) = min(e², T²)` — Torr & Zisserman's MSAC. Reported cost `√E`, metres.
    TruncatedQuadratic,
}

/// When MSAC's best model counts as found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Acceptance {
    /// Seed 002 Algorithm 1: the cost `E` over all valid points is at most `max_cost_m`
    /// (`d`, paper: 2 mm).
    MeanCost {
        /// `d`, metres.
        max_cost_m: f64,
    },
    /// Our addition: the mean residual of the model's inliers is at most `max_residual_m` and
    /// they make up at least `min_inlier_fraction` of the valid points.
    InlierResidual {
        /// Bound on the inliers' mean residual, metres.
        max_residual_m: f64,
        /// Minimum share of valid points that are inliers, in `(0, 1]`.
        min_inlier_fraction: f64,
    },
    /// Every best model is accepted.
    Always,
}

impl Default for Acceptance {
    fn default() -> Self {
        Self::MeanCost { max_cost_m: 0.002 }
    }
}

impl Acceptance {
    fn check(&self) -> Result<(), ConsensusError> {
        match *self {
            Acceptance::MeanCost { max_cost_m } => {
                check_positive("acceptance.max_cost_m", max_cost_m)
            }
            Acceptance::InlierResidual {
                max_residual_m,
                min_inlier_fraction,
            } => {
                check_positive("acceptance.max_residual_m", max_residual_m)?;
                check_fraction("acceptance.min_inlier_fraction", min_inlier_fraction)
            }
            Acceptance::Always => Ok(()),
        }
    }

    fn accepts(&self, cost: f64, inlier_residual: f64, inliers: usize, valid: usize) -> bool {
        match *self {
            Acceptance::MeanCost { max_cost_m } => cost <= max_cost_m,
            Acceptance::InlierResidual {
                max_residual_m,
                min_inlier_fraction,
            } => {
                inlier_residual <= max_residual_m
                    && inliers as f64 >= min_inlier_fraction * valid as f64
            }
            Acceptance::Always => true,
        }
    }
}

/// MSAC parameters with the paper's defaults; validate with [`MsacParams::check`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MsacParams {
    /// Truncation threshold `T` of the cost, metres (paper: 25 mm).
    pub cost_threshold_m: f64,
    /// When the best model counts as found (paper: mean cost `E ≤ d = 2 mm`).
    pub acceptance: Acceptance,
    /// Number of hypotheses `L` (paper: 500).
    pub iterations: usize,
    /// Our addition: stop before `L` once a hypothesis's inlier fraction `w` (residual below
    /// `inlier_threshold_m`) makes an all-inlier sample this likely to have been drawn already
    /// (`k = ln(1−p) / ln(1−wⁿ)`, Fischler & Bolles). `None` (default) runs all `L`, as the paper.
    pub early_stop_confidence: Option<f64>,
    /// Which truncated cost.
    pub cost: CostFunction,
    /// Residual below which a point is an inlier of the final model, metres (default `T`).
    pub inlier_threshold_m: f64,
    /// Residual below which points support the least-squares refinement, metres; `None` skips
    /// refinement (the paper's behaviour). Default 10 mm.
    pub refine_threshold_m: Option<f64>,
    /// Our addition: score each hypothesis on at most this many of the cluster's valid points,
    /// an even stride through them (deterministic), and only the winner on all of them; the
    /// least-squares refinement likewise refits on at most this many of its supporting points
    /// (each refit is still kept only if it lowers the cost over all points), and the final
    /// inliers are selected among all points. MSAC's cost is a mean, which a stride of a few
    /// hundred points estimates to a fraction of a millimetre, so the choice of model barely
    /// changes while the time per hypothesis and per refit stops growing with the cluster.
    /// `None` (default, and in older model files) uses every point, as the paper.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_scored_points: Option<usize>,
}

impl Default for MsacParams {
    fn default() -> Self {
        Self {
            cost_threshold_m: 0.025,
            acceptance: Acceptance::default(),
            iterations: 500,
            early_stop_confidence: None,
            cost: CostFunction::TruncatedLinear,
            inlier_threshold_m: 0.025,
            refine_threshold_m: Some(0.010),
            max_scored_points: None,
        }
    }
}

impl MsacParams {
    /// Validates the parameters into a runnable [`Msac`].
    ///
    /// # Errors
    /// [`ConsensusError::InvalidParameter`] when a threshold is not finite and positive,
    /// `iterations` is zero or the early-stop confidence is outside `(0, 1)`.
    pub fn check(self) -> Result<Msac, ConsensusError> {
        check_positive("cost_threshold_m", self.cost_threshold_m)?;
        self.acceptance.check()?;
        check_positive("inlier_threshold_m", self.inlier_threshold_m)?;
        if let Some(r) = self.refine_threshold_m {
            check_positive("refine_threshold_m", r)?;
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
        if self.max_scored_points == Some(0) {
            return Err(ConsensusError::InvalidParameter {
                name: "max_scored_points",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        if self.iterations == 0 {
            return Err(ConsensusError::InvalidParameter {
                name: "iterations",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        Ok(Msac { params: self })
    }
}

/// A validated MSAC loop; build it with [`MsacParams::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Msac {
    params: MsacParams,
}

impl Msac {
    /// The validated parameters.
    pub fn params(&self) -> &MsacParams {
        &self.params
    }
}

impl Consensus for Msac {
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
        let t = p.cost_threshold_m;
        let settings = LoopSettings {
            iterations: p.iterations,
            confidence: p.early_stop_confidence,
            inlier_threshold_m: p.inlier_threshold_m,
            refine_threshold_m: p.refine_threshold_m,
            max_scored_points: p.max_scored_points,
        };
        // `e < T` is false for NaN, so non-finite residuals cost the full T.
        let result = match p.cost {
            CostFunction::TruncatedLinear => run_loop(estimator, data, sampler, &settings, |e| {
                if e < t {
                    e
                } else {
                    t
                }
            })?,
            CostFunction::TruncatedQuadratic => {
                run_loop(estimator, data, sampler, &settings, |e| {
                    if e < t {
                        e * e
                    } else {
                        t * t
                    }
                })?
            }
        };
        Ok(result.map(|r| {
            let mean = r.total_score / r.valid_points as f64;
            let cost = match p.cost {
                CostFunction::TruncatedLinear => mean,
                CostFunction::TruncatedQuadratic => mean.sqrt(),
            };
            Fit {
                model: r.model,
                accepted: p.acceptance.accepts(
                    cost,
                    r.inlier_mean_residual_m,
                    r.inliers.len(),
                    r.valid_points,
                ),
                inliers: r.inliers,
                inlier_mean_residual_m: r.inlier_mean_residual_m,
                cost,
                valid_points: r.valid_points,
                models_scored: r.models_scored,
                iterations_run: r.iterations_run,
            }
        }))
    }
}
