//! Fruit and background pixels for the colour perceptron, from a labelled frame.
//!
//! Fruit pixels come from the instance mask (id > 0) when the frame has one; otherwise from the
//! truth boxes, taking the disc inscribed in each box (a round fruit fills its box's inscribed
//! circle, while the box corners are background). Every other pixel is background — unless the
//! truth says it does not list every fruit (`"complete": false`, no mask): then what a first
//! model detects there is left out ([`taught_labels`], below). Up to
//! `per_class` of each class are drawn by a seeded shuffle, so classes are balanced and the draw
//! is reproducible.
//!
//! ## Untagged fruit
//! Real frames are often annotated only in part (the shared orchard frames box the tagged
//! apples; many more hang beside them). Taught as background, those apples pull the network and
//! its learnt threshold away from the fruit's own colours, most of all from their shaded and
//! highlighted parts (seed 004 trained on hand-cut samples and does not meet this). Training
//! therefore runs twice on such frames ([`pomona_pipeline::may_have_untagged_fruit`]): the
//! circles the first model finds away from every tagged fruit
//! ([`pomona_pipeline::untagged_fruit_circles`]) are left out of the second training and of the
//! learnt threshold ([`taught_labels`]).

use pomona_core::nalgebra::Point2;
use pomona_core::ImageCircle;
use pomona_pipeline::LabelledFrame;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::{network_inputs, HSigmaSample};

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

/// What training teaches about each pixel of `lf`: `Some(true)` fruit, `Some(false)`
/// background, `None` left out; `None` without colour. The labels of [`fruit_labels`], with
/// the background pixels inside any of `left_out` (the untagged fruit of
/// [`pomona_pipeline::untagged_fruit_circles`]) left out.
pub fn taught_labels(lf: &LabelledFrame, left_out: &[ImageCircle]) -> Option<Vec<Option<bool>>> {
    let labels = fruit_labels(lf)?;
    let w = lf.frame.color()?.width() as usize;
    let mut taught: Vec<Option<bool>> = labels.into_iter().map(Some).collect();
    let h = taught.len() / w.max(1);
    for c in left_out {
        let (centre, r) = (c.center_px, c.radius_px);
        if !(centre.x.is_finite() && centre.y.is_finite() && r.is_finite() && r > 0.0) {
            continue;
        }
        // The circle's bounding rows and columns, clipped to the image.
        let span = |mid: f64, len: usize| {
            let lo = (mid - r).floor().max(0.0) as usize;
            let hi = ((mid + r).ceil().max(0.0) as usize).min(len.saturating_sub(1));
            lo..=hi
        };
        for y in span(centre.y, h) {
            for x in span(centre.x, w) {
                let label = &mut taught[y * w + x];
                if *label == Some(false) && c.contains(&Point2::new(x as f64, y as f64)) {
                    *label = None;
                }
            }
        }
    }
    Some(taught)
}

/// Up to `per_class` fruit and `per_class` background samples of `lf` in the HΣ plane (with the
/// middle of their intensity band), drawn with
/// `seed` among the pixels `labels` ([`taught_labels`]) teaches; empty without colour.
pub fn training_pixels(
    lf: &LabelledFrame,
    labels: &[Option<bool>],
    per_class: usize,
    seed: u64,
) -> Vec<HSigmaSample> {
    let Some(color) = lf.frame.color() else {
        return Vec::new();
    };
    let rgb: Vec<[u8; 3]> = color.pixels().collect();
    let (mut fruit, mut background) = (Vec::new(), Vec::new());
    for (i, label) in labels.iter().enumerate().take(rgb.len()) {
        match label {
            Some(true) => fruit.push(i),
            Some(false) => background.push(i),
            None => {}
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(2 * per_class);
    for (indices, is_fruit) in [(&mut fruit, true), (&mut background, false)] {
        let (chosen, _) = indices.partial_shuffle(&mut rng, per_class);
        out.extend(chosen.iter().map(|&i| (network_inputs(rgb[i]), is_fruit)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::{ColorImage, DepthImage, FrameTruth, PinholeCamera, RgbdFrame};

    /// A 20×10 frame whose incomplete truth boxes one fruit at x 2–8 (disc of radius 3 around
    /// (5, 5)).
    fn frame() -> LabelledFrame {
        let cam = PinholeCamera::new(20, 10, 100.0, 100.0, 9.5, 4.5).unwrap();
        let depth = DepthImage::from_u16(20, 10, &[1000; 200], 0.001).unwrap();
        let color = ColorImage::from_rgb(20, 10, vec![40; 600]).unwrap();
        let truth: FrameTruth = serde_json::from_value(serde_json::json!({
            "complete": false,
            "fruits": [{"id": "a", "kind": "orange", "bbox_px": [2.0, 2.0, 8.0, 8.0]}],
        }))
        .unwrap();
        LabelledFrame {
            name: "test/0".into(),
            frame: RgbdFrame::new(cam, depth, Some(color)).unwrap(),
            truth,
            mask: None,
        }
    }

    fn circle(x: f64, y: f64, r: f64) -> ImageCircle {
        ImageCircle {
            center_px: Point2::new(x, y),
            radius_px: r,
        }
    }

    #[test]
    fn only_background_inside_a_left_out_disc_is_left_out() {
        let lf = frame();
        let plain = fruit_labels(&lf).unwrap();
        let taught = taught_labels(&lf, &[circle(14.0, 5.0, 2.0), circle(5.0, 5.0, 4.0)]).unwrap();
        for (i, (&fruit, &label)) in plain.iter().zip(&taught).enumerate() {
            let (x, y) = ((i % 20) as f64, (i / 20) as f64);
            let near = |cx: f64, r: f64| (x - cx).powi(2) + (y - 5.0).powi(2) <= r * r;
            let expected = if fruit {
                Some(true) // a tagged fruit's pixels stay fruit, inside a disc or not
            } else if near(14.0, 2.0) || near(5.0, 4.0) {
                None
            } else {
                Some(false)
            };
            assert_eq!(label, expected, "pixel ({x}, {y})");
        }
        assert_eq!(
            taught.iter().filter(|l| l.is_none()).count(),
            13 + (49 - 29)
        );
        // Without discs the labels are fruit_labels' own; discs off the image are harmless.
        let none = taught_labels(&lf, &[circle(-50.0, 80.0, 3.0)]).unwrap();
        assert_eq!(none, plain.into_iter().map(Some).collect::<Vec<_>>());
    }

    #[test]
    fn left_out_pixels_are_never_drawn() {
        let lf = frame();
        let taught = taught_labels(&lf, &[circle(14.0, 5.0, 100.0)]).unwrap();
        // Every background pixel is left out: the draw has fruit samples only.
        let samples = training_pixels(&lf, &taught, 1000, 3);
        assert_eq!(samples.len(), 29);
        assert!(samples.iter().all(|s| s.1));
    }
}
