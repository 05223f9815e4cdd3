//! The RBF C-SVC: parameters ([`SvmParams`] → [`ValidSvmParams`]), training, and the fitted
//! classifier ([`SvmClassifier`] = optional [`MinMaxScaler`] + [`RbfSvm`]).
//!
//! Decision values `f(x) = Σ cᵢ K(svᵢ, x) − rho` are positive for the positive class (fruit) and
//! are what detectors report as scores. The training problem is laid out as scikit-learn hands it
//! to LIBSVM for labels `{false, true}` — negatives first, the negative class as LIBSVM's first
//! label — so decision values, support vectors and `rho` can be compared with `sklearn.svm.SVC`
//! directly (see `tests/golden/make_svm_golden.py`).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::kernel_cache::{rbf, QMatrix};
use crate::platt::PlattSigmoid;
use crate::{smo, LearnError, MinMaxScaler, Samples, TrainingSet};

fn default_true() -> bool {
    true
}

/// Rows per parallel task in batched prediction.
const PREDICT_CHUNK: usize = 64;

/// Per-class multipliers of `C` (LIBSVM's `-wi`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ClassWeights {
    /// `C₊ = positive · C`, `C₋ = negative · C`.
    Fixed {
        /// Weight of the positive class.
        positive: f64,
        /// Weight of the negative class.
        negative: f64,
    },
    /// Weights inversely proportional to class frequency, `n / (2 n_class)` (scikit-learn's
    /// `class_weight="balanced"`): with 5 negatives per positive, a missed fruit costs 5 times a
    /// false alarm.
    Balanced,
}

/// Unchecked training parameters of an RBF C-SVC. Defaults are LIBSVM's (`C = 1`,
/// `γ = 1/n_features`, `eps = 1e-3`, 100 MB cache) plus `[-1, 1]` feature scaling.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SvmParams {
    /// Penalty `C` of a margin violation.
    pub c: f64,
    /// RBF width `γ` in `exp(-γ‖x − z‖²)`; `None` means `1 / n_features`.
    pub gamma: Option<f64>,
    /// Class weights.
    pub class_weights: ClassWeights,
    /// Stopping tolerance on the KKT violation.
    pub eps: f64,
    /// Whether the solver shrinks the active set (LIBSVM's `-h`, on by default; same optimum
    /// within `eps`, faster on large problems).
    #[serde(default = "default_true")]
    pub shrinking: bool,
    /// Kernel cache size in megabytes.
    pub cache_mb: f64,
    /// Whether to scale features to `[-1, 1]` before training (stored with the model).
    pub scale: bool,
    /// Whether to fit Platt probabilities (costs an extra internal 5-fold cross-validation).
    pub probability: bool,
    /// Seed of the random fold assignment for probabilities.
    pub seed: u64,
}

impl Default for SvmParams {
    fn default() -> Self {
        Self {
            c: 1.0,
            gamma: None,
            class_weights: ClassWeights::Fixed {
                positive: 1.0,
                negative: 1.0,
            },
            eps: 1e-3,
            shrinking: true,
            cache_mb: 100.0,
            scale: true,
            probability: false,
            seed: 0,
        }
    }
}

impl SvmParams {
    /// Sets `C`.
    pub fn c(mut self, c: f64) -> Self {
        self.c = c;
        self
    }

    /// Sets `γ`.
    pub fn gamma(mut self, gamma: f64) -> Self {
        self.gamma = Some(gamma);
        self
    }

    /// Sets the class weights.
    pub fn class_weights(mut self, weights: ClassWeights) -> Self {
        self.class_weights = weights;
        self
    }

    /// Sets the stopping tolerance.
    pub fn eps(mut self, eps: f64) -> Self {
        self.eps = eps;
        self
    }

    /// Turns shrinking on or off.
    pub fn shrinking(mut self, shrinking: bool) -> Self {
        self.shrinking = shrinking;
        self
    }

    /// Turns feature scaling on or off.
    pub fn scale(mut self, scale: bool) -> Self {
        self.scale = scale;
        self
    }

    /// Turns Platt probabilities on or off.
    pub fn probability(mut self, probability: bool) -> Self {
        self.probability = probability;
        self
    }

    /// Sets the seed.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Validates the parameters.
    ///
    /// # Errors
    /// [`LearnError::InvalidParameter`] when `C`, `γ`, a weight, `eps` or the cache size is not
    /// finite and positive.
    pub fn check(&self) -> Result<ValidSvmParams, LearnError> {
        let positive = |name, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(LearnError::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and > 0",
                })
            }
        };
        positive("c", self.c)?;
        if let Some(g) = self.gamma {
            positive("gamma", g)?;
        }
        if let ClassWeights::Fixed {
            positive: p,
            negative: n,
        } = self.class_weights
        {
            positive("class_weights.positive", p)?;
            positive("class_weights.negative", n)?;
        }
        positive("eps", self.eps)?;
        positive("cache_mb", self.cache_mb)?;
        Ok(ValidSvmParams(self.clone()))
    }
}

/// Validated training parameters; [`ValidSvmParams::fit`] trains.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidSvmParams(SvmParams);

impl ValidSvmParams {
    /// The parameters.
    pub fn params(&self) -> &SvmParams {
        &self.0
    }

    /// Trains on `data`.
    ///
    /// # Errors
    /// [`LearnError::OneClass`] unless both classes are present (and, with probabilities, at least
    /// two samples of each class for the internal cross-validation).
    pub fn fit(&self, data: &TrainingSet) -> Result<SvmClassifier, LearnError> {
        let p = &self.0;
        let (positives, negatives) = data.class_counts();
        let min_per_class = if p.probability { 2 } else { 1 };
        if positives < min_per_class || negatives < min_per_class {
            return Err(LearnError::OneClass {
                positives,
                negatives,
            });
        }
        let scaler = p.scale.then(|| MinMaxScaler::fit(data.samples()));
        let x = match &scaler {
            Some(s) => s.transform(data.samples())?,
            None => data.samples().clone(),
        };
        let gamma = p.gamma.unwrap_or(1.0 / data.samples().n_features() as f64);
        let (c_pos, c_neg) = self.class_penalties(positives, negatives);
        let solver = SolverSettings {
            eps: p.eps,
            cache_mb: p.cache_mb,
            shrinking: p.shrinking,
        };
        let (mut svm, info) = train_rbf(&x, data.labels(), gamma, (c_pos, c_neg), solver);
        if p.probability {
            let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
            svm.probability = Some(PlattSigmoid::fit_cross_validated(
                &x,
                data.labels(),
                gamma,
                (c_pos, c_neg),
                solver,
                &mut rng,
            ));
        }
        Ok(SvmClassifier {
            scaler,
            svm,
            info: Some(info),
        })
    }

    /// `(C₊, C₋)` for the given class counts.
    pub fn class_penalties(&self, positives: usize, negatives: usize) -> (f64, f64) {
        let p = &self.0;
        match p.class_weights {
            ClassWeights::Fixed { positive, negative } => (p.c * positive, p.c * negative),
            ClassWeights::Balanced => {
                let n = (positives + negatives) as f64;
                (
                    p.c * n / (2.0 * positives.max(1) as f64),
                    p.c * n / (2.0 * negatives.max(1) as f64),
                )
            }
        }
    }
}

/// How a training run went.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainingInfo {
    /// SMO iterations.
    pub iterations: usize,
    /// Whether the tolerance was reached (`false`: the iteration limit stopped it).
    pub converged: bool,
    /// Final dual objective.
    pub objective: f64,
    /// `(C₊, C₋)` used.
    pub penalties: (f64, f64),
}

/// Solver options shared by every training run of one fit.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SolverSettings {
    pub eps: f64,
    pub cache_mb: f64,
    pub shrinking: bool,
}

/// Trains on already-scaled samples; the shared core of `fit`, cross-validation and Platt.
pub(crate) fn train_rbf(
    x: &Samples,
    labels: &[bool],
    gamma: f64,
    (c_pos, c_neg): (f64, f64),
    solver: SolverSettings,
) -> (RbfSvm, TrainingInfo) {
    // scikit-learn's layout: negatives (LIBSVM's first class, solver label +1) then positives.
    let order: Vec<usize> = (0..labels.len())
        .filter(|&i| !labels[i])
        .chain((0..labels.len()).filter(|&i| labels[i]))
        .collect();
    let xs = x.select(&order);
    let y: Vec<f64> = order
        .iter()
        .map(|&i| if labels[i] { -1.0 } else { 1.0 })
        .collect();
    let c: Vec<f64> = order
        .iter()
        .map(|&i| if labels[i] { c_pos } else { c_neg })
        .collect();
    let cache_bytes = (solver.cache_mb * 1024.0 * 1024.0) as usize;
    let mut q = QMatrix::new(&xs, &y, gamma, cache_bytes);
    let out = smo::solve(&mut q, &y, &c, solver.eps, solver.shrinking);
    // Solver decision (negative class positive) is Σ yₛαK − ρₛ; ours is its negation.
    let n = x.n_features();
    let mut support_vectors = Vec::new();
    let mut coef = Vec::new();
    let mut n_support = [0usize; 2];
    for (k, &a) in out.alpha.iter().enumerate() {
        if a > 0.0 {
            support_vectors.extend_from_slice(xs.row(k));
            coef.push(-y[k] * a);
            n_support[usize::from(y[k] < 0.0)] += 1;
        }
    }
    let svm = RbfSvm {
        n_features: n,
        gamma,
        rho: -out.rho,
        support_vectors,
        coef,
        n_support_negative: n_support[0],
        n_support_positive: n_support[1],
        probability: None,
    };
    let info = TrainingInfo {
        iterations: out.iterations,
        converged: out.converged,
        objective: out.objective,
        penalties: (c_pos, c_neg),
    };
    (svm, info)
}

/// A trained RBF SVM on (already scaled) features.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RbfSvm {
    /// Features per sample.
    pub n_features: usize,
    /// RBF width.
    pub gamma: f64,
    /// Bias: `f(x) = Σ coef_i K(sv_i, x) − rho`.
    pub rho: f64,
    /// Support vectors, flat row-major, negatives first.
    pub support_vectors: Vec<f64>,
    /// `yᵢ αᵢ` per support vector (positive for positive-class vectors).
    pub coef: Vec<f64>,
    /// Number of negative-class support vectors.
    pub n_support_negative: usize,
    /// Number of positive-class support vectors.
    pub n_support_positive: usize,
    /// Platt sigmoid, when trained with probabilities.
    pub probability: Option<PlattSigmoid>,
}

impl RbfSvm {
    /// Decision value of one (scaled) sample.
    pub fn decision_value(&self, x: &[f64]) -> f64 {
        let sum: f64 = self
            .support_vectors
            .chunks_exact(self.n_features)
            .zip(&self.coef)
            .map(|(sv, c)| c * rbf(self.gamma, sv, x))
            .sum();
        sum - self.rho
    }

    /// Total number of support vectors.
    pub fn n_support(&self) -> usize {
        self.coef.len()
    }

    pub(crate) fn validate(&self) -> Result<(), LearnError> {
        let bad = |m: &str| Err(LearnError::InconsistentModel(m.into()));
        if self.n_features == 0 {
            return bad("zero features");
        }
        if self.coef.len().checked_mul(self.n_features) != Some(self.support_vectors.len()) {
            return bad("support vector array does not match coefficient count");
        }
        let counted = self.n_support_negative.checked_add(self.n_support_positive);
        if counted != Some(self.coef.len()) {
            return bad("support vector counts do not add up");
        }
        let finite = self.gamma.is_finite()
            && self.gamma > 0.0
            && self.rho.is_finite()
            && self.support_vectors.iter().all(|v| v.is_finite())
            && self.coef.iter().all(|v| v.is_finite());
        if !finite {
            return bad("non-finite gamma, rho, coefficient or support vector");
        }
        Ok(())
    }
}

/// A trained classifier: the feature scaler (when training scaled) and the SVM.
#[derive(Debug, Clone, PartialEq)]
pub struct SvmClassifier {
    /// Feature scaling learnt on the training data.
    pub scaler: Option<MinMaxScaler>,
    /// The SVM on scaled features.
    pub svm: RbfSvm,
    /// Training diagnostics (`None` for a model read from a file).
    pub info: Option<TrainingInfo>,
}

impl SvmClassifier {
    /// A classifier without support vectors whose decision value is `score` for every sample
    /// (ρ = −score): what a method that stores no trained SVM puts in its model file, and a
    /// stand-in classifier in tests.
    pub fn constant(n_features: usize, score: f64) -> Self {
        Self {
            scaler: None,
            svm: RbfSvm {
                n_features,
                gamma: 1.0,
                rho: 0.0 - score, // not `-score`: a score of 0 gives ρ = +0, not −0
                support_vectors: Vec::new(),
                coef: Vec::new(),
                n_support_negative: 0,
                n_support_positive: 0,
                probability: None,
            },
            info: None,
        }
    }

    /// Features per sample.
    pub fn n_features(&self) -> usize {
        self.svm.n_features
    }

    fn check_features(&self, found: usize) -> Result<(), LearnError> {
        if found == self.n_features() {
            Ok(())
        } else {
            Err(LearnError::FeatureCount {
                expected: self.n_features(),
                found,
            })
        }
    }

    /// Decision value (score) of one raw sample; positive means the positive class.
    ///
    /// # Errors
    /// [`LearnError::FeatureCount`] for a sample of the wrong length.
    pub fn decision_value(&self, x: &[f64]) -> Result<f64, LearnError> {
        self.check_features(x.len())?;
        match &self.scaler {
            Some(s) => {
                let mut scaled = vec![0.0; x.len()];
                s.transform_row(x, &mut scaled)?;
                Ok(self.svm.decision_value(&scaled))
            }
            None => Ok(self.svm.decision_value(x)),
        }
    }

    /// Decision values of many raw samples, computed in parallel batches; the result does not
    /// depend on the number of threads.
    ///
    /// # Errors
    /// [`LearnError::FeatureCount`] when the samples have the wrong number of features.
    pub fn decision_function(&self, samples: &Samples) -> Result<Vec<f64>, LearnError> {
        self.check_features(samples.n_features())?;
        let n = samples.n_features();
        let chunks: Vec<Vec<f64>> = samples
            .as_slice()
            .par_chunks(PREDICT_CHUNK * n)
            .map(|block| {
                let mut scaled = vec![0.0; n];
                block
                    .chunks_exact(n)
                    .map(|row| match &self.scaler {
                        Some(s) => {
                            // Lengths were checked above, so scaling cannot fail.
                            let _ = s.transform_row(row, &mut scaled);
                            self.svm.decision_value(&scaled)
                        }
                        None => self.svm.decision_value(row),
                    })
                    .collect()
            })
            .collect();
        Ok(chunks.concat())
    }

    /// Predicted classes (`decision ≥ 0` → positive, LIBSVM's tie rule).
    ///
    /// # Errors
    /// As [`SvmClassifier::decision_function`].
    pub fn predict(&self, samples: &Samples) -> Result<Vec<bool>, LearnError> {
        Ok(self
            .decision_function(samples)?
            .into_iter()
            .map(|d| d >= 0.0)
            .collect())
    }

    /// Predicted class of one sample.
    ///
    /// # Errors
    /// As [`SvmClassifier::decision_value`].
    pub fn predict_one(&self, x: &[f64]) -> Result<bool, LearnError> {
        Ok(self.decision_value(x)? >= 0.0)
    }

    /// Platt probabilities of the positive class.
    ///
    /// # Errors
    /// [`LearnError::NoProbability`] for a model trained without probabilities, and as
    /// [`SvmClassifier::decision_function`].
    pub fn probability(&self, samples: &Samples) -> Result<Vec<f64>, LearnError> {
        let Some(sigmoid) = self.svm.probability else {
            return Err(LearnError::NoProbability);
        };
        Ok(self
            .decision_function(samples)?
            .into_iter()
            .map(|d| sigmoid.probability(d))
            .collect())
    }
}
