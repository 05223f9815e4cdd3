//! Greedy 3D non-maximum suppression (seed 000): the best-scoring box wins, every box whose
//! centre is within the radius of a kept one is dropped. Ties are broken by input order, so the
//! result is deterministic.

use nalgebra::{Point3, Unit, Vector3};

/// A positive box before merging.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScoredBox {
    /// Box centre, camera frame, metres.
    pub center: Point3<f64>,
    /// SVM decision value.
    pub score: f64,
    /// Symmetry-plane normal of the box's reference frame (symmetry frame only), carried to the
    /// detection.
    pub symmetry_plane_normal: Option<Unit<Vector3<f64>>>,
}

/// Keeps local maxima: sorted by score (descending, stable), a box survives when no kept box is
/// closer than `radius_m`.
pub fn non_maximum_suppression(boxes: &[ScoredBox], radius_m: f64) -> Vec<ScoredBox> {
    let mut order: Vec<usize> = (0..boxes.len()).collect();
    order.sort_by(|&a, &b| boxes[b].score.total_cmp(&boxes[a].score).then(a.cmp(&b)));
    let r2 = radius_m * radius_m;
    let mut kept: Vec<ScoredBox> = Vec::new();
    for i in order {
        let b = boxes[i];
        if kept
            .iter()
            .all(|k| (k.center - b.center).norm_squared() >= r2)
        {
            kept.push(b);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(x: f64, score: f64) -> ScoredBox {
        ScoredBox {
            center: Point3::new(x, 0.0, 1.0),
            score,
            symmetry_plane_normal: None,
        }
    }

    #[test]
    fn keeps_local_maxima() {
        let boxes = [
            b(0.0, 1.0),
            b(0.02, 2.0),
            b(0.04, 0.5),
            b(0.2, 0.1),
            b(0.21, 0.3),
        ];
        let kept = non_maximum_suppression(&boxes, 0.05);
        let xs: Vec<f64> = kept.iter().map(|k| k.center.x).collect();
        assert_eq!(xs, vec![0.02, 0.21]);
        assert!(non_maximum_suppression(&[], 0.05).is_empty());
    }

    #[test]
    fn ties_are_broken_by_order() {
        let kept = non_maximum_suppression(&[b(0.0, 1.0), b(0.01, 1.0)], 0.05);
        assert_eq!(kept.len(), 1);
        assert_eq!(kept[0].center.x, 0.0);
    }
}
