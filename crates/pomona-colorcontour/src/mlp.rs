//! The colour classifier of seed 004 (§3.1): a multilayer perceptron with one hidden layer of
//! sigmoid units and a sigmoid output, trained by back-propagation of errors on fruit and
//! background pixels in the HΣ plane.
//!
//! Choices the paper leaves open, documented: 8 hidden units (2-8-1); inputs scaled by 1/255 so
//! both lie in about [−1, 1]; cross-entropy loss (its gradient at a sigmoid output is the plain
//! error, the textbook back-propagation of a logistic output); online gradient descent with
//! momentum over a seeded shuffle of a class-balanced sample, weights drawn uniformly in
//! ±0.5 from the same seed. Training is deterministic for a seed.
//!
//! Not in the paper, on by default for new trainings ([`MlpParams::intensity`]): a third input,
//! the pixel's intensity band ([`crate::intensity_level`], its middle scaled like the others),
//! so that one network separates fruit from background in daylight, dim and harsh light alike
//! (the plane alone cannot; docs/results.md, "Colour with intensity"). A network without
//! intensity weights is the paper's 2-H-1.

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Scale of both network inputs (HΣ coordinates are at most 255 in magnitude).
const INPUT_SCALE: f64 = 1.0 / 255.0;

/// Training settings of the perceptron.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MlpParams {
    /// Hidden sigmoid units (2-`hidden`-1, or 3-`hidden`-1 with `intensity`).
    pub hidden: usize,
    /// Whether the network also sees the intensity band (not in the paper; default `true`,
    /// parameters from before this setting mean `false`, the paper's HΣ plane alone).
    #[serde(default)]
    pub intensity: bool,
    /// Passes over the training pixels.
    pub epochs: usize,
    /// Step size of gradient descent.
    pub learning_rate: f64,
    /// Momentum of gradient descent.
    pub momentum: f64,
}

impl Default for MlpParams {
    fn default() -> Self {
        Self {
            hidden: 8,
            intensity: true,
            epochs: 30,
            learning_rate: 0.05,
            momentum: 0.5,
        }
    }
}

/// A trained 2-H-1 perceptron on HΣ coordinates, or 3-H-1 with the intensity band;
/// [`Mlp::probability`] is its output in (0, 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Mlp {
    /// Input → hidden weights, `[w_x, w_y]` per hidden unit.
    pub hidden_weights: Vec<[f64; 2]>,
    /// Intensity → hidden weights, one per hidden unit; empty for the paper's 2-H-1 network
    /// (and in files written before the third input).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub intensity_weights: Vec<f64>,
    /// Hidden biases.
    pub hidden_bias: Vec<f64>,
    /// Hidden → output weights.
    pub output_weights: Vec<f64>,
    /// Output bias.
    pub output_bias: f64,
}

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// One labelled training pixel: its network inputs ([`crate::network_inputs`]: HΣ `X`, `Y` and
/// the middle of its intensity band) and whether it is fruit.
pub type HSigmaSample = ([f64; 3], bool);

impl Mlp {
    /// Whether the network has the intensity input.
    pub fn uses_intensity(&self) -> bool {
        !self.intensity_weights.is_empty()
    }

    /// The network's output for HΣ coordinates `(x, y)` and mean intensity `intensity` (0–255;
    /// ignored by a network without the intensity input): fruit probability in (0, 1).
    pub fn probability(&self, x: f64, y: f64, intensity: f64) -> f64 {
        let (x, y, i) = (x * INPUT_SCALE, y * INPUT_SCALE, intensity * INPUT_SCALE);
        let mut sum = self.output_bias;
        for (k, ((w, b), v)) in self
            .hidden_weights
            .iter()
            .zip(&self.hidden_bias)
            .zip(&self.output_weights)
            .enumerate()
        {
            let wi = self.intensity_weights.get(k).copied().unwrap_or(0.0);
            sum += v * sigmoid(w[0] * x + w[1] * y + wi * i + b);
        }
        sigmoid(sum)
    }

    /// Whether the weights describe a usable network (matching lengths, finite values, at least
    /// one hidden unit).
    pub fn is_valid(&self) -> bool {
        let n = self.hidden_weights.len();
        n > 0
            && self.hidden_bias.len() == n
            && (self.intensity_weights.is_empty() || self.intensity_weights.len() == n)
            && self.intensity_weights.iter().all(|v| v.is_finite())
            && self.output_weights.len() == n
            && self.output_bias.is_finite()
            && self.hidden_weights.iter().flatten().all(|v| v.is_finite())
            && self.hidden_bias.iter().all(|v| v.is_finite())
            && self.output_weights.iter().all(|v| v.is_finite())
    }

    /// Trains a network on `samples` by back-propagation; `None` when `samples` lacks one of the
    /// two classes or `params.hidden` is zero.
    pub fn train(samples: &[HSigmaSample], params: &MlpParams, seed: u64) -> Option<Self> {
        let positives = samples.iter().filter(|s| s.1).count();
        if positives == 0 || positives == samples.len() || params.hidden == 0 {
            return None;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let h = params.hidden;
        let mut net = Self {
            hidden_weights: (0..h)
                .map(|_| [rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5)])
                .collect(),
            hidden_bias: (0..h).map(|_| rng.gen_range(-0.5..0.5)).collect(),
            output_weights: (0..h).map(|_| rng.gen_range(-0.5..0.5)).collect(),
            output_bias: 0.0,
            intensity_weights: Vec::new(),
        };
        if params.intensity {
            net.intensity_weights = (0..h).map(|_| rng.gen_range(-0.5..0.5)).collect();
        }
        // Velocities of every weight: per hidden unit w_x, w_y, bias, w_intensity.
        let mut v_hidden = vec![[0.0; 4]; h];
        let mut v_out = vec![0.0; h + 1];
        let mut order: Vec<usize> = (0..samples.len()).collect();
        let mut hidden_out = vec![0.0; h];
        let (lr, mu) = (params.learning_rate, params.momentum);
        for _ in 0..params.epochs {
            order.shuffle(&mut rng);
            for &i in &order {
                let ([x, y, intensity], fruit) = samples[i];
                let (x, y) = (x * INPUT_SCALE, y * INPUT_SCALE);
                // The paper's network has no intensity weights: `t` then reaches nothing.
                let t = intensity * INPUT_SCALE;
                let mut sum = net.output_bias;
                for (k, out) in hidden_out.iter_mut().enumerate() {
                    let w = net.hidden_weights[k];
                    let wi = net.intensity_weights.get(k).copied().unwrap_or(0.0);
                    *out = sigmoid(w[0] * x + w[1] * y + wi * t + net.hidden_bias[k]);
                    sum += net.output_weights[k] * *out;
                }
                // Cross-entropy at a sigmoid output: the error signal is output − target.
                let delta = sigmoid(sum) - if fruit { 1.0 } else { 0.0 };
                for k in 0..h {
                    let dh = delta * net.output_weights[k] * hidden_out[k] * (1.0 - hidden_out[k]);
                    v_out[k] = mu * v_out[k] - lr * delta * hidden_out[k];
                    net.output_weights[k] += v_out[k];
                    let g = [dh * x, dh * y, dh, dh * t];
                    for (j, gj) in g.iter().enumerate() {
                        v_hidden[k][j] = mu * v_hidden[k][j] - lr * gj;
                    }
                    net.hidden_weights[k][0] += v_hidden[k][0];
                    net.hidden_weights[k][1] += v_hidden[k][1];
                    net.hidden_bias[k] += v_hidden[k][2];
                    if let Some(wi) = net.intensity_weights.get_mut(k) {
                        *wi += v_hidden[k][3];
                    }
                }
                v_out[h] = mu * v_out[h] - lr * delta;
                net.output_bias += v_out[h];
            }
        }
        net.is_valid().then_some(net)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fruit inside a disc: a region no single line separates (needs the hidden layer).
    fn disc_samples() -> Vec<HSigmaSample> {
        let mut out = Vec::new();
        for i in -20..=20 {
            for j in -20..=20 {
                let (x, y) = (f64::from(i) * 12.0, f64::from(j) * 12.0);
                let d = ((x - 60.0).powi(2) + (y - 40.0).powi(2)).sqrt();
                out.push(([x, y, 0.0], d < 110.0));
            }
        }
        out
    }

    #[test]
    fn learns_a_region_no_line_separates_and_is_deterministic() {
        let samples = disc_samples();
        let params = MlpParams {
            intensity: false,
            epochs: 200,
            learning_rate: 0.2,
            momentum: 0.8,
            ..MlpParams::default()
        };
        let net = Mlp::train(&samples, &params, 7).unwrap();
        let correct = samples
            .iter()
            .filter(|([x, y, i], t)| (net.probability(*x, *y, *i) >= 0.5) == *t)
            .count();
        let accuracy = correct as f64 / samples.len() as f64;
        assert!(accuracy > 0.97, "accuracy {accuracy}");
        assert_eq!(Mlp::train(&samples, &params, 7), Some(net));
        assert!(Mlp::train(&samples[..1], &params, 7).is_none());
    }
}
