//! Platt scaling: a sigmoid `P(positive | f) = 1 / (1 + exp(A f + B))` fitted to decision values.
//!
//! The algorithm is LIBSVM's (Lin, Lin & Weng 2007, "A note on Platt's probabilistic outputs for
//! support vector machines"): regularised targets, Newton's method with a backtracking line
//! search, and a numerically stable evaluation of the log-likelihood. As in LIBSVM the decision
//! values come from an internal 5-fold cross-validation so the sigmoid is not fitted to
//! over-confident training-set scores; folds here are stratified and seeded.

use rand::RngCore;
use serde::{Deserialize, Serialize};

use crate::svm::{train_rbf, SolverSettings};
use crate::{stratified_folds, Samples};

/// Folds of the internal cross-validation (LIBSVM uses 5).
const PROBABILITY_FOLDS: usize = 5;

/// The fitted sigmoid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlattSigmoid {
    /// Slope (negative when larger decision values mean "positive").
    pub a: f64,
    /// Offset.
    pub b: f64,
}

impl PlattSigmoid {
    /// Probability of the positive class for decision value `f`, computed without overflow.
    pub fn probability(&self, f: f64) -> f64 {
        let fab = f * self.a + self.b;
        if fab >= 0.0 {
            (-fab).exp() / (1.0 + (-fab).exp())
        } else {
            1.0 / (1.0 + fab.exp())
        }
    }

    /// Fits the sigmoid to decision values and labels (LIBSVM's `sigmoid_train`).
    pub fn fit(decision_values: &[f64], labels: &[bool]) -> Self {
        let prior1 = labels.iter().filter(|&&l| l).count() as f64;
        let prior0 = labels.len() as f64 - prior1;
        let max_iter = 100;
        let min_step = 1e-10;
        let sigma = 1e-12;
        let eps = 1e-5;
        let hi = (prior1 + 1.0) / (prior1 + 2.0);
        let lo = 1.0 / (prior0 + 2.0);
        let t: Vec<f64> = labels.iter().map(|&l| if l { hi } else { lo }).collect();
        let objective = |a: f64, b: f64| -> f64 {
            decision_values
                .iter()
                .zip(&t)
                .map(|(&f, &ti)| {
                    let fab = f * a + b;
                    if fab >= 0.0 {
                        ti * fab + (-fab).exp().ln_1p()
                    } else {
                        (ti - 1.0) * fab + fab.exp().ln_1p()
                    }
                })
                .sum()
        };
        let mut a = 0.0;
        let mut b = ((prior0 + 1.0) / (prior1 + 1.0)).ln();
        let mut fval = objective(a, b);
        for _ in 0..max_iter {
            let (mut h11, mut h22, mut h21, mut g1, mut g2) = (sigma, sigma, 0.0, 0.0, 0.0);
            for (&f, &ti) in decision_values.iter().zip(&t) {
                let fab = f * a + b;
                let (p, q) = if fab >= 0.0 {
                    let e = (-fab).exp();
                    (e / (1.0 + e), 1.0 / (1.0 + e))
                } else {
                    let e = fab.exp();
                    (1.0 / (1.0 + e), e / (1.0 + e))
                };
                let d2 = p * q;
                h11 += f * f * d2;
                h22 += d2;
                h21 += f * d2;
                let d1 = ti - p;
                g1 += f * d1;
                g2 += d1;
            }
            if g1.abs() < eps && g2.abs() < eps {
                break;
            }
            let det = h11 * h22 - h21 * h21;
            let da = -(h22 * g1 - h21 * g2) / det;
            let db = -(-h21 * g1 + h11 * g2) / det;
            let gd = g1 * da + g2 * db;
            let mut step = 1.0;
            while step >= min_step {
                let (na, nb) = (a + step * da, b + step * db);
                let nf = objective(na, nb);
                if nf < fval + 1e-4 * step * gd {
                    a = na;
                    b = nb;
                    fval = nf;
                    break;
                }
                step /= 2.0;
            }
            if step < min_step {
                break;
            }
        }
        Self { a, b }
    }

    /// Fits the sigmoid to cross-validated decision values of an RBF SVM on scaled samples `x`.
    pub(crate) fn fit_cross_validated(
        x: &Samples,
        labels: &[bool],
        gamma: f64,
        penalties: (f64, f64),
        solver: SolverSettings,
        rng: &mut dyn RngCore,
    ) -> Self {
        let folds = stratified_folds(labels, PROBABILITY_FOLDS, rng.next_u64());
        let mut dec = vec![0.0; labels.len()];
        for k in 0..PROBABILITY_FOLDS {
            let train: Vec<usize> = (0..labels.len()).filter(|&i| folds[i] != k).collect();
            let test: Vec<usize> = (0..labels.len()).filter(|&i| folds[i] == k).collect();
            if test.is_empty() {
                continue;
            }
            let tl: Vec<bool> = train.iter().map(|&i| labels[i]).collect();
            let has_pos = tl.iter().any(|&l| l);
            let has_neg = tl.iter().any(|&l| !l);
            if !(has_pos && has_neg) {
                // LIBSVM's convention for a one-class fold.
                let v = if has_pos { 1.0 } else { -1.0 };
                for &i in &test {
                    dec[i] = v;
                }
                continue;
            }
            let (svm, _) = train_rbf(&x.select(&train), &tl, gamma, penalties, solver);
            for &i in &test {
                dec[i] = svm.decision_value(x.row(i));
            }
        }
        Self::fit(&dec, labels)
    }
}
