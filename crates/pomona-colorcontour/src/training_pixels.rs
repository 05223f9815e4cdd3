//! Fruit and background pixels for the colour perceptron, from a labelled frame.
//!
//! Fruit pixels come from the instance mask (id > 0) when the frame has one; otherwise from the
//! truth boxes, taking the disc inscribed in each box (a round fruit fills its box's inscribed
//! circle, while the box corners are background). Every other pixel is background. Up to
//! `per_class` of each class are drawn by a seeded shuffle, so classes are balanced and the
//! draw is reproducible.

use pomona_pipeline::LabelledFrame;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::{hsigma, HSigmaSample};

/// Per pixel of `lf`: `Some(true)` fruit, `Some(false)` background; `None` without colour.
pub fn fruit_labels(lf: &LabelledFrame) -> Option<Vec<bool>> {
    let color = lf.frame.color()?;
    let (w, h) = (color.width(), color.height());
    if let Some(mask) = &lf.mask {
        return Some(mask.as_slice().iter().map(|&id| id > 0).collect());
    }
    let discs: Vec<(f64, f64, f64)> = lf
        .truth
        .fruits
        .iter()
        .filter_map(|f| f.bbox_px)
        .map(|b| {
            let c = b.center();
            (c.x, c.y, 0.5 * b.width().min(b.height()))
        })
        .collect();
    Some(
        (0..w * h)
            .map(|i| {
                let (x, y) = (f64::from(i % w), f64::from(i / w));
                discs
                    .iter()
                    .any(|&(cx, cy, r)| (x - cx).powi(2) + (y - cy).powi(2) <= r * r)
            })
            .collect(),
    )
}

/// Up to `per_class` fruit and `per_class` background samples of `lf` in the HΣ plane, drawn with
/// `seed`; empty without colour.
pub fn training_pixels(lf: &LabelledFrame, per_class: usize, seed: u64) -> Vec<HSigmaSample> {
    let (Some(color), Some(labels)) = (lf.frame.color(), fruit_labels(lf)) else {
        return Vec::new();
    };
    let rgb: Vec<[u8; 3]> = color.pixels().collect();
    let (mut fruit, mut background): (Vec<usize>, Vec<usize>) =
        (0..labels.len()).partition(|&i| labels[i]);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(2 * per_class);
    for (indices, is_fruit) in [(&mut fruit, true), (&mut background, false)] {
        let (chosen, _) = indices.partial_shuffle(&mut rng, per_class);
        out.extend(chosen.iter().map(|&i| (hsigma(rgb[i]), is_fruit)));
    }
    out
}
