//! Fruit the truth does not list, seen through a first model (not in the seeds).
//!
//! Real frames are often annotated only in part (`"complete": false`): the shared orchard
//! frames box the apples tagged for measurement, and many more hang beside them. Training that
//! takes every pixel outside the boxes as background teaches those apples' colours as
//! background. Color-contour therefore trains twice on such frames: a first model, trained as
//! usual, detects on its own training frames, and the pixels of what it finds centred outside
//! every annotated box are left out of the second training (neither fruit nor background). This
//! module finds those circles; the detector decides what to leave out with them. Measured and
//! not adopted (docs/results.md, "Untagged fruit in training"): the same for shape-fit's colour
//! model (no gain on the real apples, twice the training time), and a cut by colour alone.

use pomona_core::{Detection, ImageCircle, PixelBox};

use crate::LabelledFrame;

/// Whether fruit of `lf` may be missing from its labels: truth marked incomplete and no
/// instance mask (a mask labels every fruit pixel whatever the truth lists).
pub fn may_have_untagged_fruit(lf: &LabelledFrame) -> bool {
    !lf.truth.complete && lf.mask.is_none()
}

/// The image circles of `detections` on `lf`, radii `scale` times, whose centre lies in no
/// annotated object's box: fruit the truth may not list.
/// A detection's circle is its own 2D circle, else the outline of its sphere (centre and
/// diameter), else its box ([`ImageCircle::from_parts`]); detections with none are skipped.
pub fn untagged_fruit_circles(
    lf: &LabelledFrame,
    detections: &[Detection],
    scale: f64,
) -> Vec<ImageCircle> {
    let camera = lf.frame.camera();
    let tagged: Vec<PixelBox> = lf.truth.fruits.iter().filter_map(|f| f.bbox_px).collect();
    detections
        .iter()
        .filter_map(|d| {
            let sphere = d.diameter_m.map(|diameter| (d.center_m, diameter));
            ImageCircle::from_parts(camera, d.center_px, d.radius_px, sphere, d.bbox_px.as_ref())
        })
        .filter(|c| !tagged.iter().any(|b| b.contains(&c.center_px)))
        .map(|c| ImageCircle {
            radius_px: c.radius_px * scale,
            ..c
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::nalgebra::{Point2, Point3};
    use pomona_core::{DepthImage, FrameTruth, PinholeCamera, RgbdFrame};

    fn frame(complete: bool) -> LabelledFrame {
        let cam = PinholeCamera::new(100, 80, 100.0, 100.0, 50.0, 40.0).unwrap();
        let depth = DepthImage::from_u16(100, 80, &[1000; 8000], 0.001).unwrap();
        let truth: FrameTruth = serde_json::from_value(serde_json::json!({
            "complete": complete,
            "fruits": [{"id": "a", "kind": "apple", "bbox_px": [10.0, 10.0, 30.0, 30.0]}],
        }))
        .unwrap();
        LabelledFrame {
            name: "test/0".into(),
            frame: RgbdFrame::new(cam, depth, None).unwrap(),
            truth,
            mask: None,
        }
    }

    #[test]
    fn only_circles_centred_outside_the_boxes_are_untagged_fruit() {
        let lf = frame(false);
        let mut in_box = Detection::new(Point3::origin(), 1.0);
        in_box.center_px = Some(Point2::new(29.0, 12.0)); // a box corner, off its inscribed disc
        in_box.radius_px = Some(8.0);
        let mut circle = in_box.clone();
        circle.center_px = Some(Point2::new(70.0, 40.0));
        // A sphere without a 2D circle: its outline, 40 mm across at 1 m on the axis.
        let mut sphere = Detection::new(Point3::new(0.0, 0.0, 1.0), 1.0);
        sphere.diameter_m = Some(0.04);
        let bare = Detection::new(Point3::new(0.1, 0.0, 1.0), 1.0); // no size: no circle
        let found = untagged_fruit_circles(&lf, &[in_box, circle, sphere, bare], 1.5);
        assert_eq!(found.len(), 2);
        assert_eq!(found[0].center_px, Point2::new(70.0, 40.0));
        assert_eq!(found[0].radius_px, 12.0);
        assert!((found[1].center_px - Point2::new(50.0, 40.0)).norm() < 1e-9);
        assert!(
            (found[1].radius_px - 1.5 * 2.0).abs() < 0.01,
            "{:?}",
            found[1]
        );
        assert!(may_have_untagged_fruit(&lf));
        assert!(!may_have_untagged_fruit(&frame(true)));
    }
}
