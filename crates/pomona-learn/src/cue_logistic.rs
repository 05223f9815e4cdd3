//! A confidence from the score *and* what the detection's geometry says: a logistic regression
//! over a few cues that any detector with depth can measure, beside the classifier's score.
//!
//! Platt's sigmoid ([`crate::PlattSigmoid`]) only rescales the score, so it cannot reorder
//! detections: a near fruit the classifier scores low stays below every leaf it scores higher.
//! On our generator's held-out `wide` sets most fruit shape-fit misses at its operating point
//! *are* found, within a few millimetres, but scored below it — and they differ from the false
//! detections around them in ways the classifier's descriptor does not see
//! (docs/results.md, "Confidence from the score and the seen surface"):
//!
//! * **coverage** — the detection's supporting points over the pixels its sphere covers in the
//!   image, `ln(n / (π r_px²))` with `r_px = f · r / z`: a fruit's cluster fills much of its
//!   disc, a sphere fitted to a leaf's edge or a stalk a sliver of it (the same split holds on
//!   the real Azure Kinect frames);
//! * **depth** `ln z`: how far away the detection is (far clusters have fewer, noisier points);
//! * **seen curvature** — the flattest principal curvature of the depth surface round the
//!   centre times the radius (`pomona_pipeline::DoubleCurvatureCheck`): about 1.6 for a ball,
//!   near 0 for a leaf's fold, negative for a saddle;
//! * **elongated** — whether the detection has a fruit axis (a cylinder), whose score scale
//!   differs from a sphere's.
//!
//! Each cue is standardised by the mean and spread of the fitting detections; a cue a detection
//! does not have (no support count, no diameter, too few readings round it) takes the mean, so
//! it neither raises nor lowers the confidence. The weights are fitted by Newton's method with a
//! small ridge penalty, which keeps them finite on separable data. The score's weight must come
//! out positive: the confidence then still rises with the score at fixed cues, as a
//! calibrated confidence should.

use serde::{Deserialize, Serialize};

use crate::LearnError;

/// What one detection shows: its score and the cues beside it (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectionCues {
    /// The classifier's raw score.
    pub score: f64,
    /// `ln(support points / (π r_px²))`, when the detection has a support count and a diameter.
    pub log_coverage: Option<f64>,
    /// `ln z` of the centre in the camera frame (z in metres), when in front of the camera.
    pub log_depth: Option<f64>,
    /// Flattest seen curvature times the fruit's radius, when measured.
    pub relative_curvature: Option<f64>,
    /// Whether the detection has a fruit axis (an elongated fruit).
    pub elongated: bool,
}

impl DetectionCues {
    /// The cues of a detection of which only the score is known (every other cue missing).
    pub fn score_only(score: f64) -> Self {
        Self {
            score,
            log_coverage: None,
            log_depth: None,
            relative_curvature: None,
            elongated: false,
        }
    }
}

/// One number per cue, in the order of [`DetectionCues`]: a mean, a spread or a weight.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CueVector {
    /// For the score.
    pub score: f64,
    /// For the log coverage.
    pub log_coverage: f64,
    /// For the log depth.
    pub log_depth: f64,
    /// For the relative curvature.
    pub relative_curvature: f64,
    /// For the elongated flag (0 or 1).
    pub elongated: f64,
}

impl CueVector {
    const LEN: usize = 5;

    fn to_array(self) -> [f64; Self::LEN] {
        [
            self.score,
            self.log_coverage,
            self.log_depth,
            self.relative_curvature,
            self.elongated,
        ]
    }

    fn from_array(a: [f64; Self::LEN]) -> Self {
        Self {
            score: a[0],
            log_coverage: a[1],
            log_depth: a[2],
            relative_curvature: a[3],
            elongated: a[4],
        }
    }
}

/// A fitted logistic regression from [`DetectionCues`] to the probability of a fruit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CueLogistic {
    /// Fruit radii round the centre over which the curvature cue was measured (the detector
    /// must measure it the same way).
    pub curvature_patch_radii: f64,
    /// Mean of each cue over the fitting detections (a missing cue takes it).
    pub mean: CueVector,
    /// Standard deviation of each cue (1 where a cue did not vary).
    pub spread: CueVector,
    /// Weight of each standardised cue.
    pub weight: CueVector,
    /// Intercept.
    pub bias: f64,
}

/// Ridge penalty on the standardised weights (not on the intercept).
const RIDGE: f64 = 1e-2;

impl CueLogistic {
    /// The cues of `c` as numbers, a missing cue at its mean.
    fn values(&self, c: &DetectionCues) -> [f64; CueVector::LEN] {
        let mean = self.mean.to_array();
        let raw = raw(c);
        std::array::from_fn(|k| raw[k].unwrap_or(mean[k]))
    }

    /// The probability that the detection with cues `c` is a fruit, in `[0, 1]`; for fixed
    /// other cues non-decreasing in the score.
    pub fn probability(&self, c: &DetectionCues) -> f64 {
        let (m, s, w) = (
            self.mean.to_array(),
            self.spread.to_array(),
            self.weight.to_array(),
        );
        let z = self
            .values(c)
            .iter()
            .enumerate()
            .map(|(i, x)| w[i] * (x - m[i]) / s[i])
            .sum::<f64>()
            + self.bias;
        1.0 / (1.0 + (-z).exp())
    }

    /// Checks what a model file could carry wrong: a number that is not finite, a spread or
    /// patch that is not positive, or a score weight that is not positive.
    ///
    /// # Errors
    /// [`LearnError::InconsistentModel`] saying which.
    pub fn validate(&self) -> Result<(), LearnError> {
        let bad = |what: String| Err(LearnError::InconsistentModel(what));
        let mut all = [self.mean, self.spread, self.weight]
            .into_iter()
            .flat_map(CueVector::to_array)
            .chain([self.bias, self.curvature_patch_radii]);
        if let Some(x) = all.find(|x| !x.is_finite()) {
            return bad(format!("calibration cues: a value is not finite ({x})"));
        }
        if self.spread.to_array().iter().any(|&s| s <= 0.0) || self.curvature_patch_radii <= 0.0 {
            return bad("calibration cues: spreads and curvature_patch_radii must be > 0".into());
        }
        if self.weight.score <= 0.0 {
            return bad(format!(
                "calibration cues: the score's weight is {} and must be > 0 (the confidence \
                 rises with the score)",
                self.weight.score
            ));
        }
        Ok(())
    }

    /// Fits the regression to detections `cues[i]` labelled `is_true[i]`.
    ///
    /// # Errors
    /// [`LearnError::InvalidSamples`] when the inputs disagree in length, a cue is not finite,
    /// there is no true or no false detection, or the fitted score weight is not positive (the
    /// scores then carry no signal beside the other cues); [`LearnError::InvalidParameter`] for
    /// a patch that is not finite and positive.
    ///
    /// ```
    /// use pomona_learn::{CueLogistic, DetectionCues};
    /// // Fruit score higher and cover more of their disc.
    /// let cues: Vec<DetectionCues> = (0..40)
    ///     .map(|i| DetectionCues {
    ///         score: (i % 7) as f64 - 3.0 + if i % 2 == 0 { 1.0 } else { 0.0 },
    ///         log_coverage: Some(if i % 2 == 0 { -0.3 } else { -1.5 } + 0.1 * (i % 3) as f64),
    ///         log_depth: Some(0.0),
    ///         relative_curvature: None,
    ///         elongated: false,
    ///     })
    ///     .collect();
    /// let is_true: Vec<bool> = (0..40).map(|i| i % 2 == 0).collect();
    /// let m = CueLogistic::fit(&cues, &is_true, 1.2).unwrap();
    /// let mut c = cues[1];
    /// let low = m.probability(&c);
    /// c.log_coverage = Some(-0.3);
    /// assert!(m.probability(&c) > low);
    /// ```
    pub fn fit(
        cues: &[DetectionCues],
        is_true: &[bool],
        curvature_patch_radii: f64,
    ) -> Result<Self, LearnError> {
        let bad = |reason: String| Err(LearnError::InvalidSamples(reason));
        one_label_each(cues.len(), is_true.len(), "cue sets")?;
        if !(curvature_patch_radii.is_finite() && curvature_patch_radii > 0.0) {
            return Err(LearnError::InvalidParameter {
                name: "curvature_patch_radii",
                value: curvature_patch_radii,
                reason: "must be finite and > 0",
            });
        }
        true_and_false(is_true, "cue calibration needs true and false detections")?;
        // Means and spreads over the detections that have each cue.
        let mut mean = [0.0; CueVector::LEN];
        let mut spread = [1.0; CueVector::LEN];
        for k in 0..CueVector::LEN {
            let xs: Vec<f64> = cues.iter().filter_map(|c| raw(c)[k]).collect();
            if let Some(x) = xs.iter().find(|x| !x.is_finite()) {
                return bad(format!("a detection cue is not finite ({x})"));
            }
            if xs.is_empty() {
                continue;
            }
            let n = xs.len() as f64;
            mean[k] = xs.iter().sum::<f64>() / n;
            let var = xs.iter().map(|x| (x - mean[k]).powi(2)).sum::<f64>() / n;
            if var > 1e-18 {
                spread[k] = var.sqrt();
            }
        }
        let mut model = Self {
            curvature_patch_radii,
            mean: CueVector::from_array(mean),
            spread: CueVector::from_array(spread),
            weight: CueVector::from_array([0.0; CueVector::LEN]),
            bias: 0.0,
        };
        let rows: Vec<[f64; CueVector::LEN]> = cues
            .iter()
            .map(|c| {
                let v = model.values(c);
                std::array::from_fn(|k| (v[k] - mean[k]) / spread[k])
            })
            .collect();
        let theta = newton_logistic(&rows, is_true);
        model.weight = CueVector::from_array(std::array::from_fn(|k| theta[k]));
        model.bias = theta[CueVector::LEN];
        if model.weight.score <= 0.0 || !model.weight.score.is_finite() {
            return bad(format!(
                "beside the other cues, the scores do not rank true detections above false ones \
                 (score weight {:.3} ≤ 0 over {} detections)",
                model.weight.score,
                cues.len()
            ));
        }
        Ok(model)
    }
}

/// Held-out samples and their labels pair up: `samples` of `what` need as many labels.
pub(crate) fn one_label_each(samples: usize, labels: usize, what: &str) -> Result<(), LearnError> {
    if samples == labels {
        return Ok(());
    }
    Err(LearnError::InvalidSamples(format!(
        "{samples} {what} but {labels} labels"
    )))
}

/// The number of true labels in `is_true`, or an error (`needs`, then the count) unless both
/// kinds are there: a calibration cannot be fitted to one kind of detection.
pub(crate) fn true_and_false(is_true: &[bool], needs: &str) -> Result<usize, LearnError> {
    let positives = is_true.iter().filter(|&&t| t).count();
    if positives == 0 || positives == is_true.len() {
        return Err(LearnError::InvalidSamples(format!(
            "{needs}, got {positives} true of {}",
            is_true.len()
        )));
    }
    Ok(positives)
}

/// The cues of `c` in [`CueVector`] order, `None` where missing.
fn raw(c: &DetectionCues) -> [Option<f64>; CueVector::LEN] {
    [
        Some(c.score),
        c.log_coverage,
        c.log_depth,
        c.relative_curvature,
        Some(f64::from(u8::from(c.elongated))),
    ]
}

/// Ridge-penalised logistic regression by Newton's method: weights of the columns of `rows`,
/// then the intercept.
fn newton_logistic(rows: &[[f64; CueVector::LEN]], is_true: &[bool]) -> [f64; CueVector::LEN + 1] {
    const N: usize = CueVector::LEN + 1;
    let mut theta = [0.0; N];
    for _ in 0..100 {
        let mut grad = [0.0; N];
        let mut hess = [[0.0; N]; N];
        for (row, &t) in rows.iter().zip(is_true) {
            let x: [f64; N] = std::array::from_fn(|k| if k < N - 1 { row[k] } else { 1.0 });
            let z: f64 = x.iter().zip(&theta).map(|(a, b)| a * b).sum();
            let p = 1.0 / (1.0 + (-z).exp());
            let y = f64::from(u8::from(t));
            let w = (p * (1.0 - p)).max(1e-12);
            for i in 0..N {
                grad[i] += (p - y) * x[i];
                for j in 0..N {
                    hess[i][j] += w * x[i] * x[j];
                }
            }
        }
        for i in 0..N - 1 {
            grad[i] += RIDGE * theta[i];
            hess[i][i] += RIDGE;
        }
        hess[N - 1][N - 1] += 1e-9;
        let Some(step) = solve(hess, grad) else { break };
        let mut largest: f64 = 0.0;
        for i in 0..N {
            theta[i] -= step[i];
            largest = largest.max(step[i].abs());
        }
        if largest < 1e-10 {
            break;
        }
    }
    theta
}

/// Solves `a · x = b` by Gaussian elimination with partial pivoting; `None` when singular.
fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    for col in 0..N {
        let pivot = (col..N).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..N {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col];
            for (x, p) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; N];
    for row in (0..N).rev() {
        let s: f64 = (row + 1..N).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fruit (even i) score a little higher and cover much more of their disc.
    fn sample() -> (Vec<DetectionCues>, Vec<bool>) {
        let cues = (0..200)
            .map(|i| {
                let fruit = i % 2 == 0;
                DetectionCues {
                    score: ((i * 37) % 11) as f64 / 5.0 - 1.0 + if fruit { 0.5 } else { 0.0 },
                    log_coverage: Some(
                        if fruit { -0.4 } else { -1.6 } + ((i * 13) % 7) as f64 / 7.0,
                    ),
                    log_depth: Some(((i * 3) % 5) as f64 / 5.0 - 0.2),
                    relative_curvature: (i % 5 != 0).then_some(if fruit { 1.2 } else { 0.4 }),
                    elongated: i % 9 == 0,
                }
            })
            .collect();
        (cues, (0..200).map(|i| i % 2 == 0).collect())
    }

    #[test]
    fn confidence_rises_with_the_score_and_the_cues_reorder() {
        let (c, t) = sample();
        let m = CueLogistic::fit(&c, &t, 1.2).unwrap();
        m.validate().unwrap();
        let mut d = c[1];
        let mut last = -1.0;
        for i in -50..50 {
            d.score = 0.1 * f64::from(i);
            let p = m.probability(&d);
            assert!((0.0..=1.0).contains(&p) && p >= last, "{p} < {last}");
            last = p;
        }
        // A lower score with a fruit's coverage outranks a higher one without.
        let fruitlike = DetectionCues {
            score: 0.0,
            log_coverage: Some(-0.3),
            ..c[0]
        };
        let leaflike = DetectionCues {
            score: 0.4,
            log_coverage: Some(-1.8),
            ..c[0]
        };
        assert!(m.probability(&fruitlike) > m.probability(&leaflike));
    }

    #[test]
    fn a_missing_cue_is_neutral() {
        let (c, t) = sample();
        let m = CueLogistic::fit(&c, &t, 1.2).unwrap();
        let with_mean = DetectionCues {
            log_coverage: Some(m.mean.log_coverage),
            relative_curvature: Some(m.mean.relative_curvature),
            ..c[3]
        };
        let without = DetectionCues {
            log_coverage: None,
            relative_curvature: None,
            ..c[3]
        };
        assert!((m.probability(&with_mean) - m.probability(&without)).abs() < 1e-12);
    }

    #[test]
    fn unusable_inputs_and_files_are_refused() {
        let (c, t) = sample();
        assert!(CueLogistic::fit(&c[..3], &t, 1.2).is_err());
        assert!(CueLogistic::fit(&c, &vec![true; c.len()], 1.2).is_err());
        assert!(CueLogistic::fit(&c, &t, 0.0).is_err());
        let mut nan = c.clone();
        nan[4].log_depth = Some(f64::NAN);
        assert!(CueLogistic::fit(&nan, &t, 1.2).is_err());
        // Scores that fall with the truth beside cues that carry it.
        let flipped: Vec<DetectionCues> = c
            .iter()
            .zip(&t)
            .map(|(d, &y)| DetectionCues {
                score: if y { -1.0 } else { 1.0 } + 0.01 * d.score,
                ..*d
            })
            .collect();
        let err = CueLogistic::fit(&flipped, &t, 1.2).unwrap_err().to_string();
        assert!(err.contains("do not rank"), "{err}");
        let mut m = CueLogistic::fit(&c, &t, 1.2).unwrap();
        m.weight.score = -0.5;
        assert!(m.validate().is_err());
        m.weight.score = 0.5;
        m.spread.log_depth = 0.0;
        assert!(m.validate().is_err());
    }

    #[test]
    fn round_trips_through_json() {
        let (c, t) = sample();
        let m = CueLogistic::fit(&c, &t, 1.2).unwrap();
        let json = serde_json::to_string(&m).unwrap();
        assert_eq!(serde_json::from_str::<CueLogistic>(&json).unwrap(), m);
    }
}
