//! The second pass of seed 004 §3.2: "the area of overlap of each pair of identified circular
//! regions [is calculated], and if the overlap is greater than a threshold (40 % of the area)
//! then the circle that accumulated the lowest score ... is rejected. In addition, detected
//! oranges with unreasonable sizes are discarded."
//!
//! The overlap is taken relative to the *smaller* circle's area (the paper does not say whose
//! area; a small duplicate inside a large circle must go). Circles are visited by decreasing
//! score and each is kept unless it overlaps a kept one by more than the threshold, which for
//! pairs is exactly the paper's rule. The size test lives with the detector, which knows the
//! depth ([`crate::ColorContourParams`]).

use pomona_core::nalgebra::Point2;

/// Area shared by two discs (the lens formula).
pub fn disc_overlap_area(a: (Point2<f64>, f64), b: (Point2<f64>, f64)) -> f64 {
    let ((ca, ra), (cb, rb)) = (a, b);
    let d = (ca - cb).norm();
    if d >= ra + rb {
        return 0.0;
    }
    let small = ra.min(rb);
    if d <= (ra - rb).abs() {
        return std::f64::consts::PI * small * small;
    }
    let alpha = ((d * d + ra * ra - rb * rb) / (2.0 * d * ra))
        .clamp(-1.0, 1.0)
        .acos();
    let beta = ((d * d + rb * rb - ra * ra) / (2.0 * d * rb))
        .clamp(-1.0, 1.0)
        .acos();
    let triangle = 0.5
        * ((-d + ra + rb) * (d + ra - rb) * (d - ra + rb) * (d + ra + rb))
            .max(0.0)
            .sqrt();
    ra * ra * alpha + rb * rb * beta - triangle
}

/// Indices of the circles kept: by decreasing score (ties by index), a circle is dropped when it
/// shares more than `max_overlap` of the smaller area with a circle already kept.
pub fn prune_overlapping(
    circles: &[(Point2<f64>, f64)],
    scores: &[f64],
    max_overlap: f64,
) -> Vec<usize> {
    let mut order: Vec<usize> = (0..circles.len().min(scores.len())).collect();
    order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
    let mut kept: Vec<usize> = Vec::new();
    for i in order {
        let clash = kept.iter().any(|&k| {
            let small = circles[i].1.min(circles[k].1);
            let area = std::f64::consts::PI * small * small;
            disc_overlap_area(circles[i], circles[k]) > max_overlap * area
        });
        if !clash {
            kept.push(i);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lens_area_matches_the_limits_and_a_numeric_count() {
        let o = Point2::origin();
        assert_eq!(
            disc_overlap_area((o, 1.0), (Point2::new(3.0, 0.0), 1.0)),
            0.0
        );
        let inside = disc_overlap_area((o, 2.0), (Point2::new(0.5, 0.0), 1.0));
        assert!((inside - std::f64::consts::PI).abs() < 1e-12);
        // Two unit discs one radius apart, counted on a fine grid.
        let (a, b) = ((o, 1.0), (Point2::new(1.0, 0.0), 1.0));
        let step = 0.002;
        let mut count = 0usize;
        for i in 0..1500 {
            for j in 0..1000 {
                let p = Point2::new(-0.5 + i as f64 * step, -1.0 + j as f64 * step * 2.0);
                if (p - a.0).norm() <= 1.0 && (p - b.0).norm() <= 1.0 {
                    count += 1;
                }
            }
        }
        let numeric = count as f64 * step * step * 2.0;
        let exact = disc_overlap_area(a, b);
        assert!((exact - numeric).abs() < 0.01, "{exact} vs {numeric}");
        assert!((exact - (2.0 * std::f64::consts::PI / 3.0 - 0.75f64.sqrt())).abs() < 1e-12);
    }

    #[test]
    fn the_weaker_of_two_overlapping_circles_goes() {
        let c = [
            (Point2::new(0.0, 0.0), 10.0),
            (Point2::new(3.0, 0.0), 9.0),   // overlaps 0 heavily
            (Point2::new(17.0, 0.0), 10.0), // touches 0 a little (< 40 %)
            (Point2::new(50.0, 0.0), 5.0),
        ];
        assert_eq!(
            prune_overlapping(&c, &[0.5, 0.9, 0.4, 0.1], 0.4),
            vec![1, 2, 3]
        );
        assert_eq!(
            prune_overlapping(&c, &[0.9, 0.5, 0.4, 0.1], 0.4),
            vec![0, 2, 3]
        );
    }
}
