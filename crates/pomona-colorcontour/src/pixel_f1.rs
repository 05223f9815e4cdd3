//! How well the colour classifier separates fruit from background, pixel by pixel, against the
//! labels of [`crate::fruit_labels`] (instance mask, or inscribed truth discs): the measure of the
//! issue's colour targets (pixel F1).

use pomona_pipeline::{FrameSource, PipelineError};

use crate::{fruit_labels, HSigmaLut};

/// Pixel counts of a classifier against labels.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PixelCounts {
    /// Fruit classified fruit.
    pub true_positives: u64,
    /// Background classified fruit.
    pub false_positives: u64,
    /// Fruit classified background.
    pub false_negatives: u64,
}

impl PixelCounts {
    /// Precision, recall and F1 (0 where undefined).
    pub fn precision_recall_f1(&self) -> (f64, f64, f64) {
        let (tp, fp, fn_) = (
            self.true_positives as f64,
            self.false_positives as f64,
            self.false_negatives as f64,
        );
        let p = if tp + fp > 0.0 { tp / (tp + fp) } else { 0.0 };
        let r = if tp + fn_ > 0.0 { tp / (tp + fn_) } else { 0.0 };
        let f1 = if p + r > 0.0 {
            2.0 * p * r / (p + r)
        } else {
            0.0
        };
        (p, r, f1)
    }
}

/// Counts over every frame of `frames` with colour, classifying with `lut` at `threshold`
/// (table value 0–255).
///
/// # Errors
/// The first frame that fails to load.
pub fn pixel_counts(
    frames: &dyn FrameSource,
    lut: &HSigmaLut,
    threshold: u8,
) -> Result<PixelCounts, PipelineError> {
    let mut c = PixelCounts::default();
    for i in 0..frames.len() {
        let lf = frames.load(i)?;
        let (Some(color), Some(labels)) = (lf.frame.color(), fruit_labels(&lf)) else {
            continue;
        };
        for (rgb, &truth) in color.pixels().zip(&labels) {
            let predicted = lut.value(rgb) >= threshold;
            match (predicted, truth) {
                (true, true) => c.true_positives += 1,
                (true, false) => c.false_positives += 1,
                (false, true) => c.false_negatives += 1,
                (false, false) => {}
            }
        }
    }
    Ok(c)
}
