//! Training the 4-H-3 joint network ([`JointNetwork`]) on targets whose encoder readings are
//! known (the seed's training set: the end effector moved onto each target of a regular grid).
//!
//! The seed trains by back-propagation. This uses back-propagation to get the gradient of every
//! output with respect to every weight (the Jacobian) and then takes Levenberg–Marquardt steps,
//! `(JᵀJ + μ·diag(JᵀJ)) δ = −Jᵀe`, on the mean squared error of the scaled outputs — "or
//! better, with the reason": for a network of tens of weights a Gauss–Newton step costs next to
//! nothing and reaches errors orders of magnitude lower than gradient descent or Adam in a few
//! hundred passes (the mapping must be learned to about 10⁻⁴ of its range for millimetre
//! accuracy). Several seeded starting points are trained and the best kept; same samples and
//! configuration, same network.

use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::joint_network::{forward_with, NETWORK_INPUTS, NETWORK_OUTPUTS};
use crate::{ArmError, ArmSample, JointNetwork, LinearScaling};

/// How to train.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NetworkTraining {
    /// Hidden units; default 8 (the seed's choice).
    pub hidden: usize,
    /// Starting points tried; default 4.
    pub restarts: usize,
    /// Levenberg–Marquardt iterations per start at most; default 400.
    pub max_iterations: usize,
    /// Seed of the starting weights.
    pub seed: u64,
}

impl Default for NetworkTraining {
    fn default() -> Self {
        Self {
            hidden: 8,
            restarts: 4,
            max_iterations: 400,
            seed: 0,
        }
    }
}

/// What training reached.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrainingReport {
    /// Root mean square error of the scaled outputs on the training set, before training (best
    /// start's initial weights).
    pub initial_rms: f64,
    /// The same after training.
    pub final_rms: f64,
    /// Iterations taken by the kept start.
    pub iterations: usize,
    /// Training samples.
    pub samples: usize,
}

/// Scaled inputs and targets of the training set.
struct Scaled {
    inputs: Vec<[f64; NETWORK_INPUTS]>,
    targets: Vec<[f64; NETWORK_OUTPUTS]>,
}

/// Trains a network on `samples` (their pixels as inputs, their encoder readings — r as 1/r —
/// as targets).
///
/// # Errors
/// [`ArmError::InvalidParameter`] for no samples, no hidden units, no starts or no iterations.
pub fn train_joint_network(
    samples: &[ArmSample],
    training: &NetworkTraining,
) -> Result<(JointNetwork, TrainingReport), ArmError> {
    let checks = [
        ("samples", samples.len()),
        ("hidden", training.hidden),
        ("restarts", training.restarts),
        ("max_iterations", training.max_iterations),
    ];
    if let Some((name, value)) = checks.into_iter().find(|&(_, v)| v == 0) {
        return Err(ArmError::InvalidParameter {
            name,
            value: value as f64,
            reason: "must be at least 1",
        });
    }
    let raw_in: Vec<[f64; 4]> = samples.iter().map(|s| s.pixels.to_array()).collect();
    let raw_out: Vec<[f64; 3]> = samples
        .iter()
        .map(|s| {
            [
                s.readings.alpha_rad,
                s.readings.theta_rad,
                1.0 / s.readings.r_m,
            ]
        })
        .collect();
    let input_scaling = LinearScaling::fit(NETWORK_INPUTS, raw_in.iter().map(|r| r.as_slice()));
    let output_scaling = LinearScaling::fit(NETWORK_OUTPUTS, raw_out.iter().map(|r| r.as_slice()));
    let scaled = Scaled {
        inputs: raw_in
            .iter()
            .map(|r| std::array::from_fn(|i| input_scaling.normalise(i, r[i])))
            .collect(),
        targets: raw_out
            .iter()
            .map(|r| std::array::from_fn(|k| output_scaling.normalise(k, r[k])))
            .collect(),
    };
    let mut rng = ChaCha8Rng::seed_from_u64(training.seed);
    let mut best: Option<(Vec<f64>, TrainingReport)> = None;
    for _ in 0..training.restarts {
        let start = initial_weights(training.hidden, &mut rng);
        let initial_rms = rms(&scaled, &start, training.hidden);
        let (weights, iterations) = levenberg_marquardt(&scaled, start, training);
        let final_rms = rms(&scaled, &weights, training.hidden);
        let report = TrainingReport {
            initial_rms,
            final_rms,
            iterations,
            samples: samples.len(),
        };
        if best
            .as_ref()
            .is_none_or(|(_, b)| report.final_rms < b.final_rms)
        {
            best = Some((weights, report));
        }
    }
    let (weights, report) = best.ok_or(ArmError::InvalidParameter {
        name: "restarts",
        value: 0.0,
        reason: "must be at least 1",
    })?;
    let network = JointNetwork {
        hidden: training.hidden,
        weights,
        input_scaling,
        output_scaling,
    };
    Ok((network, report))
}

/// Random starting weights: hidden weights uniform in ±1 (the inputs are in [−1, 1], so every
/// unit starts in tanh's sloped part), output weights uniform in ±1/√H.
fn initial_weights(hidden: usize, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let out_size = 1.0 / (hidden as f64).sqrt();
    let mut w = Vec::with_capacity(JointNetwork::weight_count(hidden));
    for _ in 0..(NETWORK_INPUTS + 1) * hidden {
        w.push(rng.gen_range(-1.0..=1.0));
    }
    for _ in 0..NETWORK_OUTPUTS * (hidden + 1) {
        w.push(rng.gen_range(-out_size..=out_size));
    }
    w
}

/// Residuals (output − target), scaled, one per sample and output.
fn residuals(scaled: &Scaled, weights: &[f64], hidden: usize) -> DVector<f64> {
    let mut h = vec![0.0; hidden];
    let mut e = DVector::zeros(scaled.inputs.len() * NETWORK_OUTPUTS);
    for (n, (x, t)) in scaled.inputs.iter().zip(&scaled.targets).enumerate() {
        let y = forward_with(weights, hidden, x, &mut h);
        for k in 0..NETWORK_OUTPUTS {
            e[n * NETWORK_OUTPUTS + k] = y[k] - t[k];
        }
    }
    e
}

fn rms(scaled: &Scaled, weights: &[f64], hidden: usize) -> f64 {
    let e = residuals(scaled, weights, hidden);
    (e.norm_squared() / e.len() as f64).sqrt()
}

/// The Jacobian of every residual with respect to every weight, by back-propagation.
fn jacobian(scaled: &Scaled, weights: &[f64], hidden: usize) -> DMatrix<f64> {
    let p = weights.len();
    let base = (NETWORK_INPUTS + 1) * hidden;
    let mut jac = DMatrix::zeros(scaled.inputs.len() * NETWORK_OUTPUTS, p);
    let mut h = vec![0.0; hidden];
    for (n, x) in scaled.inputs.iter().enumerate() {
        forward_with(weights, hidden, x, &mut h);
        for k in 0..NETWORK_OUTPUTS {
            let row = n * NETWORK_OUTPUTS + k;
            let out = base + k * (hidden + 1);
            for j in 0..hidden {
                jac[(row, out + j)] = h[j];
                // Back-propagated through output k's weight and tanh's slope.
                let delta = weights[out + j] * (1.0 - h[j] * h[j]);
                let unit = (NETWORK_INPUTS + 1) * j;
                for i in 0..NETWORK_INPUTS {
                    jac[(row, unit + i)] = delta * x[i];
                }
                jac[(row, unit + NETWORK_INPUTS)] = delta;
            }
            jac[(row, out + hidden)] = 1.0;
        }
    }
    jac
}

/// Levenberg–Marquardt from `weights`; returns the trained weights and the iterations taken.
fn levenberg_marquardt(
    scaled: &Scaled,
    mut weights: Vec<f64>,
    training: &NetworkTraining,
) -> (Vec<f64>, usize) {
    let hidden = training.hidden;
    let mut e = residuals(scaled, &weights, hidden);
    let mut loss = e.norm_squared();
    let mut mu = 1e-3;
    for iteration in 0..training.max_iterations {
        let jac = jacobian(scaled, &weights, hidden);
        let jtj = jac.tr_mul(&jac);
        let gradient = jac.tr_mul(&e);
        let mut improved = false;
        while mu < 1e12 {
            let mut a = jtj.clone();
            for d in 0..a.nrows() {
                a[(d, d)] += mu * (jtj[(d, d)] + 1e-9);
            }
            let Some(step) = a.cholesky().map(|c| c.solve(&gradient)) else {
                mu *= 10.0;
                continue;
            };
            let trial: Vec<f64> = weights
                .iter()
                .zip(step.iter())
                .map(|(w, s)| w - s)
                .collect();
            let trial_e = residuals(scaled, &trial, hidden);
            let trial_loss = trial_e.norm_squared();
            if trial_loss < loss {
                let relative_gain = (loss - trial_loss) / loss.max(f64::MIN_POSITIVE);
                weights = trial;
                e = trial_e;
                loss = trial_loss;
                mu = (mu / 10.0).max(1e-15);
                improved = relative_gain > 1e-12;
                break;
            }
            mu *= 10.0;
        }
        if !improved {
            return (weights, iteration + 1);
        }
    }
    (weights, training.max_iterations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{
        ArmRig, ArmSimulation, CalibrationErrors, CalibrationMagnitudes, EndPositionError,
    };

    #[test]
    fn jacobian_matches_finite_differences() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let hidden = 3;
        let scaled = Scaled {
            inputs: vec![[0.1, -0.4, 0.7, 0.2], [-0.9, 0.3, 0.0, 0.5]],
            targets: vec![[0.0; 3], [0.5, -0.5, 0.1]],
        };
        let w = initial_weights(hidden, &mut rng);
        let jac = jacobian(&scaled, &w, hidden);
        let e0 = residuals(&scaled, &w, hidden);
        for p in 0..w.len() {
            let mut w2 = w.clone();
            w2[p] += 1e-7;
            let diff = (residuals(&scaled, &w2, hidden) - &e0) / 1e-7;
            for r in 0..e0.len() {
                assert!((diff[r] - jac[(r, p)]).abs() < 1e-5, "weight {p} row {r}");
            }
        }
    }

    #[test]
    fn training_reduces_the_error_on_a_small_grid() {
        let errors = CalibrationErrors::draw(&CalibrationMagnitudes::default(), 11);
        let sim = ArmSimulation::new(ArmRig::default(), errors);
        let samples = sim.grid_samples([7, 5, 9]).unwrap();
        assert!(samples.len() >= 30, "{} samples", samples.len());
        let training = NetworkTraining {
            restarts: 1,
            max_iterations: 150,
            ..NetworkTraining::default()
        };
        let (net, report) = train_joint_network(&samples, &training).unwrap();
        assert!(
            report.final_rms < 0.05 * report.initial_rms && report.final_rms < 0.01,
            "{report:?}"
        );
        // The network puts the true end near the training targets.
        let errors = EndPositionError::measure(&sim, &samples, |p| Some(net.predict(p))).unwrap();
        assert!(errors.median < 5.0 && errors.p95 < 15.0, "{errors:?}");
        // Same samples and configuration, same network.
        assert_eq!(train_joint_network(&samples, &training).unwrap().0, net);
        assert!(train_joint_network(&[], &training).is_err());
    }
}
