//! The [`Consensus`] trait (a robust-fitting loop) and the [`Fit`] it returns, plus the
//! hypothesise-and-verify loop that [`crate::Msac`] and [`crate::Ransac`] share.
//!
//! The loops differ only in how one residual is scored (truncated distance for MSAC, a 0/1 outlier
//! indicator for RANSAC), so the shared loop takes the per-residual score as a closure. Scores are
//! non-negative, which allows an exact early exit: once a hypothesis's partial sum exceeds the best
//! total so far it cannot win, so its remaining residuals are not computed. This changes speed,
//! never the result.

use serde::{Deserialize, Serialize};

use crate::{ConsensusError, Estimator, Sampler, UniformSampler};

/// The outcome of a consensus fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fit<M> {
    /// The lowest-cost model (refined on its inliers when refinement is enabled and helped).
    pub model: M,
    /// Indices into the input data of the model's inliers, ascending.
    pub inliers: Vec<usize>,
    /// The loop's cost of `model` over all valid data. MSAC: mean truncated cost in metres (for
    /// the quadratic cost, the root of the mean, also metres). RANSAC: the outlier fraction.
    pub cost: f64,
    /// Mean residual of the inliers, metres (`NaN` without inliers).
    pub inlier_mean_residual_m: f64,
    /// Whether the model passed the acceptance test of the loop's parameters.
    pub accepted: bool,
    /// Number of valid data the cost was averaged over (invalid data are skipped).
    pub valid_points: usize,
    /// Hypotheses that survived estimation and validity checks and were scored.
    pub models_scored: usize,
    /// Samples drawn (the iteration count, or fewer when adaptive stopping ended the loop).
    pub iterations_run: usize,
}

/// A robust fitting loop: draws minimal samples, builds hypotheses, keeps the best.
pub trait Consensus {
    /// Fits one model of `estimator`'s kind to `data`, drawing samples from `sampler`.
    ///
    /// Invalid data (per [`Estimator::is_datum_valid`]) are skipped. Returns `Ok(None)` when no
    /// sample produced a valid model; check [`Fit::accepted`] for the acceptance test.
    ///
    /// # Errors
    /// [`ConsensusError::TooFewPoints`] when fewer valid data than a minimal sample remain.
    fn fit<D, E, S>(
        &self,
        estimator: &E,
        data: &[D],
        sampler: &mut S,
    ) -> Result<Option<Fit<E::Model>>, ConsensusError>
    where
        E: Estimator<D>,
        S: Sampler;

    /// [`Consensus::fit`] with a [`UniformSampler`] seeded by `seed`.
    ///
    /// # Errors
    /// As [`Consensus::fit`].
    fn fit_seeded<D, E>(
        &self,
        estimator: &E,
        data: &[D],
        seed: u64,
    ) -> Result<Option<Fit<E::Model>>, ConsensusError>
    where
        E: Estimator<D>,
    {
        self.fit(estimator, data, &mut UniformSampler::new(seed))
    }
}

/// Settings of the shared loop, already validated by the caller.
pub(crate) struct LoopSettings {
    pub iterations: usize,
    pub confidence: Option<f64>,
    pub inlier_threshold_m: f64,
    pub refine_threshold_m: Option<f64>,
    /// Score hypotheses, and refit the winner, on at most this many evenly strided points
    /// (`None`: all).
    pub max_scored_points: Option<usize>,
}

/// The best model found, with its total score and inliers.
pub(crate) struct LoopResult<M> {
    pub model: M,
    pub total_score: f64,
    pub inliers: Vec<usize>,
    pub inlier_mean_residual_m: f64,
    pub valid_points: usize,
    pub models_scored: usize,
    pub iterations_run: usize,
}

/// Rounds of refine → re-select inliers; each round is kept only if it lowers the loop's score.
const REFINE_ROUNDS: usize = 3;

/// Total score of `model` over `valid`, stopping early (returning `None`) once it exceeds `bound`.
fn total_score<D, E: Estimator<D>>(
    estimator: &E,
    model: &E::Model,
    data: &[D],
    valid: &[usize],
    score: &impl Fn(f64) -> f64,
    inlier_threshold_m: f64,
    bound: f64,
) -> Option<(f64, usize)> {
    let mut sum = 0.0;
    let mut inliers = 0;
    // Check the bound every few points: cheap, and still exits early on bad hypotheses.
    for chunk in valid.chunks(16) {
        for &i in chunk {
            let e = estimator.residual(model, &data[i]);
            inliers += usize::from(e < inlier_threshold_m);
            sum += score(e);
        }
        if sum > bound {
            return None;
        }
    }
    Some((sum, inliers))
}

/// Hypotheses needed to draw, with probability `confidence`, at least one all-inlier sample of
/// size `n` when a fraction `w` of the data are inliers (Fischler & Bolles).
fn required_iterations(confidence: f64, w: f64, n: usize) -> usize {
    let all_inlier = w.powi(n as i32);
    if all_inlier >= 1.0 {
        return 1;
    }
    if all_inlier <= 0.0 {
        return usize::MAX;
    }
    let k = (1.0 - confidence).ln() / (1.0 - all_inlier).ln();
    if k.is_finite() && k >= 0.0 {
        (k.ceil() as usize).max(1)
    } else {
        usize::MAX
    }
}

fn select_inliers<D, E: Estimator<D>>(
    estimator: &E,
    model: &E::Model,
    data: &[D],
    valid: &[usize],
    threshold_m: f64,
) -> Vec<usize> {
    valid
        .iter()
        .copied()
        .filter(|&i| estimator.residual(model, &data[i]) < threshold_m)
        .collect()
}

/// Least-squares refinement of the best hypothesis on its support (up to [`REFINE_ROUNDS`]
/// rounds), kept only while the consensus score does not get worse.
struct Refinement {
    /// Residual below which a point supports the refit, metres.
    threshold_m: f64,
    /// The consensus loop's inlier threshold, metres.
    inlier_threshold_m: f64,
    /// Refit on at most this many of the supporting points, an even stride (`None`: all).
    max_points: Option<usize>,
}

impl Refinement {
    /// Returns the refined model and its total score (the inputs when no refit helps).
    fn run<D, E: Estimator<D>>(
        &self,
        estimator: &E,
        data: &[D],
        valid: &[usize],
        score: &impl Fn(f64) -> f64,
        mut model: E::Model,
        mut total: f64,
    ) -> (E::Model, f64) {
        for _ in 0..REFINE_ROUNDS {
            let mut support = select_inliers(estimator, &model, data, valid, self.threshold_m);
            if let Some(fewer) = evenly_strided(&support, self.max_points) {
                support = fewer;
            }
            if support.len() < estimator.min_samples() {
                break;
            }
            let Some(refined) = estimator.refine(&model, data, &support) else {
                break;
            };
            if !estimator.is_model_valid(&refined) {
                break;
            }
            let thr = self.inlier_threshold_m;
            match total_score(estimator, &refined, data, valid, score, thr, total) {
                Some((sum, _)) if sum <= total => {
                    let improved = sum < total;
                    model = refined;
                    total = sum;
                    if !improved {
                        break;
                    }
                }
                _ => break,
            }
        }
        (model, total)
    }
}

/// At most `max` of `indices`, an even stride through them (deterministic); `None` when all of
/// them are to be used (`max` unset or not exceeded).
fn evenly_strided(indices: &[usize], max: Option<usize>) -> Option<Vec<usize>> {
    let stride = indices.len().div_ceil(max?.max(1));
    (stride > 1).then(|| indices.iter().copied().step_by(stride).collect())
}

/// Hypothesise-and-verify with per-residual `score` (non-negative, `NaN`-safe).
pub(crate) fn run_loop<D, E, S>(
    estimator: &E,
    data: &[D],
    sampler: &mut S,
    settings: &LoopSettings,
    score: impl Fn(f64) -> f64,
) -> Result<Option<LoopResult<E::Model>>, ConsensusError>
where
    E: Estimator<D>,
    S: Sampler,
{
    let n = estimator.min_samples();
    let valid: Vec<usize> = (0..data.len())
        .filter(|&i| estimator.is_datum_valid(&data[i]))
        .collect();
    if valid.len() < n.max(1) {
        return Err(ConsensusError::TooFewPoints {
            what: "consensus fit",
            needed: n.max(1),
            valid: valid.len(),
        });
    }

    // Hypotheses are scored on `scored` (an even stride through the valid points when there
    // are more than `max_scored_points`); the winner is re-scored on every valid point below.
    let strided = evenly_strided(&valid, settings.max_scored_points);
    let scored = strided.as_deref().unwrap_or(&valid);

    let mut picks = Vec::with_capacity(n);
    let mut sample: Vec<&D> = Vec::with_capacity(n);
    let mut best: Option<(E::Model, f64)> = None;
    let mut models_scored = 0;
    let mut required = settings.iterations;
    let mut iterations_run = 0;
    while iterations_run < required {
        iterations_run += 1;
        sampler.sample(valid.len(), n, &mut picks);
        if picks.len() != n {
            continue;
        }
        sample.clear();
        sample.extend(picks.iter().map(|&k| &data[valid[k]]));
        let Some(model) = estimator.estimate(&sample) else {
            continue;
        };
        if !estimator.is_model_valid(&model) {
            continue;
        }
        models_scored += 1;
        let bound = best.as_ref().map_or(f64::INFINITY, |(_, s)| *s);
        let thr = settings.inlier_threshold_m;
        if let Some((sum, inliers)) =
            total_score(estimator, &model, data, scored, &score, thr, bound)
        {
            if sum < bound {
                best = Some((model, sum));
                if let Some(p) = settings.confidence {
                    let w = inliers as f64 / scored.len() as f64;
                    required = required.min(required_iterations(p, w, n));
                }
            }
        }
    }
    let Some((mut model, mut total)) = best else {
        return Ok(None);
    };
    if strided.is_some() {
        let everything = total_score(estimator, &model, data, &valid, &score, 0.0, f64::INFINITY);
        total = everything.map_or(f64::INFINITY, |(sum, _)| sum);
    }

    if let Some(refine_threshold_m) = settings.refine_threshold_m {
        let refine = Refinement {
            threshold_m: refine_threshold_m,
            inlier_threshold_m: settings.inlier_threshold_m,
            max_points: settings.max_scored_points,
        };
        (model, total) = refine.run(estimator, data, &valid, &score, model, total);
    }

    let inliers = select_inliers(estimator, &model, data, &valid, settings.inlier_threshold_m);
    let inlier_mean_residual_m = inliers
        .iter()
        .map(|&i| estimator.residual(&model, &data[i]))
        .sum::<f64>()
        / inliers.len() as f64;
    let model = estimator.finish(model, data, &inliers);
    Ok(Some(LoopResult {
        model,
        total_score: total,
        inliers,
        inlier_mean_residual_m,
        valid_points: valid.len(),
        models_scored,
        iterations_run,
    }))
}

/// `value` must lie in `(0, 1]` (a fraction or ratio that may be whole but not zero).
pub(crate) fn check_fraction(name: &'static str, value: f64) -> Result<(), ConsensusError> {
    if value > 0.0 && value <= 1.0 {
        Ok(())
    } else {
        Err(ConsensusError::InvalidParameter {
            name,
            value,
            reason: "must lie in (0, 1]",
        })
    }
}

/// `value` must be finite and strictly positive.
pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<(), ConsensusError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ConsensusError::InvalidParameter {
            name,
            value,
            reason: "must be finite and positive",
        })
    }
}
