//! The seed's learned mapping from a target's two image positions to the arm's encoder readings
//! (Eq. 19, `[I_l, I_r] → J`): a 4-H-3 perceptron (seed: H = 8) with tanh hidden units and
//! linear outputs, whose inputs and outputs are scaled to about [−1, 1] by scalings stored in
//! the model. Learning the mapping directly folds the lens distortion, the camera's mounting and
//! the encoders' offsets into one step, which is why the seed uses it instead of Eq. 18.
//!
//! Inputs `[xL, yL, xR, yR]` (pixels), outputs `[α, θ, 1/r]` (radians, radians, 1/metres):
//! the extension is learned as its reciprocal, which — like depth from disparity — is nearly an
//! affine function of the image coordinates; learned directly, r's 1/disparity curve takes most
//! of the eight units and the end-position error triples (`docs/results.md`). [`JointNetwork::
//! predict`] returns r itself. Trained by [`crate::train_joint_network`].

use serde::{Deserialize, Serialize};

use crate::{ArmError, ArmJoints, ShotPixels};

/// Number of inputs: `xL, yL, xR, yR`.
pub const NETWORK_INPUTS: usize = 4;
/// Number of outputs: `α, θ, r`.
pub const NETWORK_OUTPUTS: usize = 3;

/// Per-column affine scaling `normalised = (value − centre) / half_range`, fitted to the
/// training data's range (so it maps that range onto [−1, 1]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinearScaling {
    /// Middle of each column's range.
    pub centre: Vec<f64>,
    /// Half of each column's range (1 for a constant column).
    pub half_range: Vec<f64>,
}

impl LinearScaling {
    /// Fits the scaling of `columns` columns to `rows` (each `columns` long).
    pub fn fit<'a>(columns: usize, rows: impl IntoIterator<Item = &'a [f64]>) -> Self {
        let mut lo = vec![f64::INFINITY; columns];
        let mut hi = vec![f64::NEG_INFINITY; columns];
        for row in rows {
            for (c, &v) in row.iter().enumerate().take(columns) {
                lo[c] = lo[c].min(v);
                hi[c] = hi[c].max(v);
            }
        }
        let centre = lo.iter().zip(&hi).map(|(l, h)| 0.5 * (l + h)).collect();
        let half_range = lo
            .iter()
            .zip(&hi)
            .map(|(l, h)| {
                let half = 0.5 * (h - l);
                if half > 0.0 && half.is_finite() {
                    half
                } else {
                    1.0
                }
            })
            .collect();
        Self { centre, half_range }
    }

    /// Scales one value of column `c`.
    pub fn normalise(&self, c: usize, value: f64) -> f64 {
        (value - self.centre[c]) / self.half_range[c]
    }

    /// Undoes [`LinearScaling::normalise`].
    pub fn denormalise(&self, c: usize, normalised: f64) -> f64 {
        normalised * self.half_range[c] + self.centre[c]
    }

    fn is_valid(&self, columns: usize) -> bool {
        self.centre.len() == columns
            && self.half_range.len() == columns
            && self.centre.iter().all(|v| v.is_finite())
            && self.half_range.iter().all(|v| v.is_finite() && *v > 0.0)
    }
}

/// The 4-H-3 network with its scalings.
///
/// `weights` holds, for each hidden unit `j`, its 4 input weights then its bias
/// (`weights[5j .. 5j + 5]`), then for each output `k` its H hidden weights then its bias
/// (`weights[5H + k(H + 1) ..]`): `8H + 3` numbers (67 for H = 8).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointNetwork {
    /// Hidden units, H.
    pub hidden: usize,
    /// All weights and biases, laid out as above.
    pub weights: Vec<f64>,
    /// Scaling of the inputs `[xL, yL, xR, yR]`.
    pub input_scaling: LinearScaling,
    /// Scaling of the outputs `[α, θ, 1/r]`.
    pub output_scaling: LinearScaling,
}

impl JointNetwork {
    /// Number of weights and biases of a network with `hidden` hidden units.
    pub fn weight_count(hidden: usize) -> usize {
        (NETWORK_INPUTS + 1) * hidden + NETWORK_OUTPUTS * (hidden + 1)
    }

    /// Checks the sizes and that every number is finite (for a network read from a file).
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] naming what is wrong.
    pub fn validate(&self) -> Result<(), ArmError> {
        let bad = |name, value: f64, reason| {
            Err(ArmError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        if self.hidden == 0 {
            return bad("hidden", 0.0, "the network needs at least one hidden unit");
        }
        if self.weights.len() != Self::weight_count(self.hidden) {
            return bad(
                "weights",
                self.weights.len() as f64,
                "the number of weights must be 8H + 3",
            );
        }
        if let Some(&w) = self.weights.iter().find(|w| !w.is_finite()) {
            return bad("weights", w, "every weight must be finite");
        }
        if !self.input_scaling.is_valid(NETWORK_INPUTS) {
            return bad(
                "input_scaling",
                self.input_scaling.centre.len() as f64,
                "4 finite centres and 4 finite positive half ranges",
            );
        }
        if !self.output_scaling.is_valid(NETWORK_OUTPUTS) {
            return bad(
                "output_scaling",
                self.output_scaling.centre.len() as f64,
                "3 finite centres and 3 finite positive half ranges",
            );
        }
        Ok(())
    }

    /// The scaled inputs of `pixels`.
    pub fn normalised_input(&self, pixels: &ShotPixels) -> [f64; NETWORK_INPUTS] {
        let raw = pixels.to_array();
        std::array::from_fn(|i| self.input_scaling.normalise(i, raw[i]))
    }

    /// The forward pass on scaled inputs: fills `hidden_out` (H tanh activations) and returns
    /// the scaled outputs.
    pub fn forward(
        &self,
        input: &[f64; NETWORK_INPUTS],
        hidden_out: &mut [f64],
    ) -> [f64; NETWORK_OUTPUTS] {
        forward_with(&self.weights, self.hidden, input, hidden_out)
    }

    /// The encoder readings the network gives for a target seen at `pixels` (r is the
    /// reciprocal of the third output; not finite when that output is not positive).
    pub fn predict(&self, pixels: &ShotPixels) -> ArmJoints {
        let mut hidden = vec![0.0; self.hidden];
        let y = self.forward(&self.normalised_input(pixels), &mut hidden);
        ArmJoints {
            alpha_rad: self.output_scaling.denormalise(0, y[0]),
            theta_rad: self.output_scaling.denormalise(1, y[1]),
            r_m: 1.0 / self.output_scaling.denormalise(2, y[2]),
        }
    }
}

/// The forward pass of weights laid out as in [`JointNetwork`] (shared with training).
pub(crate) fn forward_with(
    weights: &[f64],
    hidden: usize,
    input: &[f64; NETWORK_INPUTS],
    hidden_out: &mut [f64],
) -> [f64; NETWORK_OUTPUTS] {
    for (j, h) in hidden_out.iter_mut().enumerate().take(hidden) {
        let w = &weights[(NETWORK_INPUTS + 1) * j..(NETWORK_INPUTS + 1) * (j + 1)];
        let z = w[NETWORK_INPUTS]
            + w[..NETWORK_INPUTS]
                .iter()
                .zip(input)
                .map(|(a, b)| a * b)
                .sum::<f64>();
        *h = z.tanh();
    }
    let base = (NETWORK_INPUTS + 1) * hidden;
    std::array::from_fn(|k| {
        let w = &weights[base + k * (hidden + 1)..base + (k + 1) * (hidden + 1)];
        w[hidden]
            + w[..hidden]
                .iter()
                .zip(hidden_out.iter())
                .map(|(a, b)| a * b)
                .sum::<f64>()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;

    fn identity_scaling(columns: usize) -> LinearScaling {
        LinearScaling {
            centre: vec![0.0; columns],
            half_range: vec![1.0; columns],
        }
    }

    #[test]
    fn forward_pass_by_hand() {
        // H = 1: h = tanh(x0 + 0.5), outputs 2h, −h + 1, 1/r = 4.
        let mut weights = vec![1.0, 0.0, 0.0, 0.0, 0.5];
        weights.extend([2.0, 0.0, -1.0, 1.0, 0.0, 4.0]);
        let net = JointNetwork {
            hidden: 1,
            weights,
            input_scaling: identity_scaling(4),
            output_scaling: identity_scaling(3),
        };
        net.validate().unwrap();
        let q = net.predict(&ShotPixels {
            left: Point2::new(0.25, 9.0),
            right: Point2::new(9.0, 9.0),
        });
        let h = 0.75f64.tanh();
        assert!((q.alpha_rad - 2.0 * h).abs() < 1e-15);
        assert!((q.theta_rad - (1.0 - h)).abs() < 1e-15);
        assert!((q.r_m - 0.25).abs() < 1e-15);
    }

    #[test]
    fn scaling_maps_the_range_to_unit_and_back_and_bad_networks_are_rejected() {
        let rows = [[1.0, 5.0], [3.0, 5.0]];
        let s = LinearScaling::fit(2, rows.iter().map(|r| r.as_slice()));
        assert_eq!(s.normalise(0, 1.0), -1.0);
        assert_eq!(s.normalise(0, 3.0), 1.0);
        assert_eq!(s.half_range[1], 1.0, "constant column");
        assert_eq!(s.denormalise(0, s.normalise(0, 2.5)), 2.5);
        let mut net = JointNetwork {
            hidden: 8,
            weights: vec![0.0; JointNetwork::weight_count(8)],
            input_scaling: identity_scaling(4),
            output_scaling: identity_scaling(3),
        };
        assert_eq!(JointNetwork::weight_count(8), 67);
        net.validate().unwrap();
        net.weights.pop();
        assert!(net.validate().is_err());
        net.weights.push(f64::NAN);
        assert!(net.validate().is_err());
    }
}
