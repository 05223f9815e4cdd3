//! Precision/recall over score thresholds and the two average precisions.
//!
//! The curve has one point per *distinct* score: lowering the threshold past a score admits all
//! detections with that score at once, so the result does not depend on how ties happen to be
//! ordered (PASCAL's reference code ranks tied detections arbitrarily). With `n` counted truth
//! fruit, after admitting everything scoring at least `s`: recall = TP/n, precision = TP/(TP+FP).
//!
//! * **VOC 11-point AP** (PASCAL VOC 2007, seed 000): the mean over r ∈ {0, 0.1, …, 1} of the
//!   largest precision at any recall ≥ r (0 when no point reaches r).
//! * **All-point AP** (PASCAL VOC 2010 onwards): the area under the curve made monotone by taking,
//!   at each recall, the largest precision at that or any higher recall.

use serde::{Deserialize, Serialize};

/// One point of the curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PrPoint {
    /// Lowest score admitted.
    pub threshold: f64,
    /// Fraction of admitted detections that are true positives.
    pub precision: f64,
    /// Fraction of counted truth found.
    pub recall: f64,
}

/// A precision/recall curve, thresholds decreasing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PrCurve {
    /// Points in order of decreasing threshold (increasing recall).
    pub points: Vec<PrPoint>,
    /// Number of counted truth fruit (the recall denominator).
    pub positives: usize,
}

impl PrCurve {
    /// Builds the curve from `(score, is_true_positive)` of every counted detection (ignored
    /// detections excluded) and the number of counted truth fruit.
    ///
    /// ```
    /// use pomona_eval::PrCurve;
    /// let c = PrCurve::new(&[(0.9, true), (0.8, false), (0.7, true)], 4);
    /// assert_eq!(c.points.len(), 3);
    /// assert_eq!((c.points[2].precision, c.points[2].recall), (2.0 / 3.0, 0.5));
    /// ```
    pub fn new(scored: &[(f64, bool)], positives: usize) -> Self {
        let mut sorted: Vec<(f64, bool)> = scored.to_vec();
        sorted.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut points = Vec::new();
        let (mut tp, mut fp) = (0usize, 0usize);
        for (k, &(score, hit)) in sorted.iter().enumerate() {
            if hit {
                tp += 1;
            } else {
                fp += 1;
            }
            let last_of_group = sorted.get(k + 1).is_none_or(|next| next.0 != score);
            if last_of_group {
                points.push(PrPoint {
                    threshold: score,
                    precision: tp as f64 / (tp + fp) as f64,
                    recall: if positives == 0 {
                        0.0
                    } else {
                        tp as f64 / positives as f64
                    },
                });
            }
        }
        Self { points, positives }
    }

    /// PASCAL VOC 2007 11-point interpolated average precision.
    pub fn ap_voc11(&self) -> f64 {
        (0..=10)
            .map(|i| {
                let r = f64::from(i) / 10.0;
                self.points
                    .iter()
                    .filter(|p| p.recall >= r)
                    .map(|p| p.precision)
                    .fold(0.0, f64::max)
            })
            .sum::<f64>()
            / 11.0
    }

    /// All-point interpolated average precision (area under the monotone envelope).
    pub fn ap_all_points(&self) -> f64 {
        let mut envelope = 0.0f64;
        let mut area = 0.0;
        // Walk from the highest recall down, carrying the running maximum precision.
        for k in (0..self.points.len()).rev() {
            envelope = envelope.max(self.points[k].precision);
            let prev_recall = if k == 0 {
                0.0
            } else {
                self.points[k - 1].recall
            };
            area += (self.points[k].recall - prev_recall) * envelope;
        }
        area
    }

    /// Precision and recall with every detection scoring at least `threshold` admitted;
    /// `None` when no detection scores that high.
    pub fn at_threshold(&self, threshold: f64) -> Option<PrPoint> {
        self.points
            .iter()
            .take_while(|p| p.threshold >= threshold)
            .last()
            .copied()
    }
}
