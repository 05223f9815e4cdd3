//! How well the colour classifier separates fruit from background, pixel by pixel, against the
//! labels of [`crate::fruit_labels`] (instance mask, or inscribed truth discs): the measure of the
//! issue's colour targets (pixel F1).

use pomona_pipeline::{FrameSource, LabelledFrame, PipelineError};

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

/// Per table value 0–255: how many fruit and background pixels of `lf` have it, by the labels
/// training teaches ([`crate::taught_labels`]: pixels left out are not counted); empty without
/// colour.
pub fn value_histograms(
    lf: &LabelledFrame,
    labels: &[Option<bool>],
    lut: &HSigmaLut,
) -> [[u64; 256]; 2] {
    let mut h = [[0u64; 256]; 2];
    if let Some(color) = lf.frame.color() {
        for (rgb, label) in color.pixels().zip(labels) {
            if let Some(fruit) = *label {
                h[usize::from(fruit)][usize::from(lut.value(rgb))] += 1;
            }
        }
    }
    h
}

/// The table value from which calling a pixel fruit maximises pixel F1, given per-value counts
/// `[background, fruit]` (ties: the lowest such value); `None` without fruit pixels.
pub fn best_f1_threshold(histograms: &[[u64; 256]; 2]) -> Option<u8> {
    let [background, fruit] = histograms;
    let total_fruit: u64 = fruit.iter().sum();
    if total_fruit == 0 {
        return None;
    }
    let (mut tp, mut fp) = (0u64, 0u64);
    let mut best = (0.0, 255u8);
    for t in (0..256).rev() {
        tp += fruit[t];
        fp += background[t];
        let counts = PixelCounts {
            true_positives: tp,
            false_positives: fp,
            false_negatives: total_fruit - tp,
        };
        let f1 = counts.precision_recall_f1().2;
        if f1 >= best.0 {
            best = (f1, t as u8);
        }
    }
    Some(best.1)
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
    for_each_labelled_pixel(frames, |rgb, truth| {
        let predicted = lut.value(rgb) >= threshold;
        match (predicted, truth) {
            (true, true) => c.true_positives += 1,
            (true, false) => c.false_positives += 1,
            (false, true) => c.false_negatives += 1,
            (false, false) => {}
        }
    })?;
    Ok(c)
}

/// Calls `visit(colour, is_fruit)` for every pixel of every frame of `frames` that has colour
/// and labels ([`crate::fruit_labels`]); frames without are skipped.
///
/// # Errors
/// The first frame that fails to load.
pub fn for_each_labelled_pixel(
    frames: &dyn FrameSource,
    mut visit: impl FnMut([u8; 3], bool),
) -> Result<(), PipelineError> {
    for i in 0..frames.len() {
        let lf = frames.load(i)?;
        let (Some(color), Some(labels)) = (lf.frame.color(), fruit_labels(&lf)) else {
            continue;
        };
        for (rgb, &fruit) in color.pixels().zip(&labels) {
            visit(rgb, fruit);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_best_threshold_maximises_f1() {
        let mut h = [[0u64; 256]; 2];
        h[1][200] = 90; // most fruit high
        h[1][100] = 10;
        h[0][100] = 500; // background in the middle
        h[0][10] = 10_000;
        // Every value in 101..=200 separates alike; ties go to the lowest.
        assert_eq!(best_f1_threshold(&h), Some(101));
        // Little background at 100: taking all fruit wins (values 11..=100 tie).
        h[0][100] = 1;
        assert_eq!(best_f1_threshold(&h), Some(11));
        assert_eq!(best_f1_threshold(&[[0; 256], [0; 256]]), None);
    }
}
