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
//!
//! Which circle is the stronger is [`PruneRank`]: the detection score (support fraction ×
//! colour purity, this crate's first reading of the paper's score) or the arc length in pixels ×
//! colour purity (closer to the paper: its score is accumulated window by window along the
//! contour, so it grows with the length of the arc, not with the arc's share of the
//! circumference).

use pomona_core::nalgebra::Point2;
use serde::{Deserialize, Serialize};

/// What makes one of two overlapping circles the one kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PruneRank {
    /// The detection score, support fraction × colour purity (what model files from before
    /// this setting mean). A small circle on a fragment of a fruit's outline has a larger
    /// support fraction than the fruit's own circle, and wins.
    #[default]
    Score,
    /// Arc length in pixels × colour purity, i.e. the score × 2πr: the circle resting on more
    /// outline wins, and a fragment's small circle no longer beats the fruit it lies in.
    ArcLength,
}

impl PruneRank {
    /// The value by which circles are ranked, from the detection score (support fraction ×
    /// colour purity) and the radius in pixels.
    pub fn key(self, score: f64, radius_px: f64) -> f64 {
        match self {
            Self::Score => score,
            Self::ArcLength => score * std::f64::consts::TAU * radius_px,
        }
    }
}

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

/// Whether two circles are taken for one fruit, so that only one is kept: they share more than
/// `max_overlap` of the smaller circle's area (§3.2) and, with `center_reach > 0` (not in the
/// paper), their centres are closer than `center_reach` times the larger radius. Two touching
/// fruit, a small one half in front of a large one, share much of the small one's area, but the
/// small one's centre lies near or beyond the large one's outline; two circles on one fruit are
/// centred near each other. `center_reach = 0` is the paper's test alone.
pub fn clash(
    a: (Point2<f64>, f64),
    b: (Point2<f64>, f64),
    max_overlap: f64,
    center_reach: f64,
) -> bool {
    let (small, large) = (a.1.min(b.1), a.1.max(b.1));
    let near = center_reach <= 0.0 || (a.0 - b.0).norm() < center_reach * large;
    near && disc_overlap_area(a, b) > max_overlap * std::f64::consts::PI * small * small
}

/// Indices of the circles kept: by decreasing `scores` (the ranking values, e.g.
/// [`PruneRank::key`]; ties by index), a circle is dropped when it shares more than
/// `max_overlap` of the smaller area with a circle already kept and, when `center_reach` is
/// positive, its centre and that circle's are closer than `center_reach` times the larger
/// radius (see [`clash`]).
pub fn prune_overlapping(
    circles: &[(Point2<f64>, f64)],
    scores: &[f64],
    max_overlap: f64,
    center_reach: f64,
) -> Vec<usize> {
    let mut order: Vec<usize> = (0..circles.len().min(scores.len())).collect();
    order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
    let mut kept: Vec<usize> = Vec::new();
    for i in order {
        if !kept
            .iter()
            .any(|&k| clash(circles[i], circles[k], max_overlap, center_reach))
        {
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
            prune_overlapping(&c, &[0.5, 0.9, 0.4, 0.1], 0.4, 0.0),
            vec![1, 2, 3]
        );
        assert_eq!(
            prune_overlapping(&c, &[0.9, 0.5, 0.4, 0.1], 0.4, 0.0),
            vec![0, 2, 3]
        );
    }

    #[test]
    fn ranked_by_arc_length_the_fruit_beats_a_fragment_inside_it() {
        // A fruit of radius 30 whose circle rests on 60 % of its outline, 95 % fruit-coloured,
        // and a small circle of radius 6 on a bump of its outline (90 % of that small
        // circumference, all fruit-coloured) inside it.
        let fruit = (Point2::new(100.0, 100.0), 30.0);
        let fragment = (Point2::new(118.0, 104.0), 6.0);
        let scores = [0.6 * 0.95, 0.9 * 1.0];
        let circles = [fruit, fragment];
        let keys = |rank: PruneRank| -> Vec<f64> {
            circles
                .iter()
                .zip(scores)
                .map(|(c, s)| rank.key(s, c.1))
                .collect()
        };
        // By score (support fraction) the fragment wins and the fruit is lost.
        assert_eq!(
            prune_overlapping(&circles, &keys(PruneRank::Score), 0.4, 0.8),
            vec![1]
        );
        assert_eq!(
            prune_overlapping(&circles, &keys(PruneRank::ArcLength), 0.4, 0.8),
            vec![0]
        );
        // Two circles of one fruit with equal arcs: the one more inside the colour mask wins
        // either way (an oversized circle reaches into the background and loses purity).
        let right = (Point2::new(50.0, 50.0), 20.0);
        let oversized = (Point2::new(53.0, 50.0), 24.0);
        let arc = 0.5 * std::f64::consts::TAU * 20.0;
        let s_right = arc / (std::f64::consts::TAU * 20.0);
        let s_over = arc / (std::f64::consts::TAU * 24.0) * 0.7;
        for rank in [PruneRank::Score, PruneRank::ArcLength] {
            let k = [rank.key(s_over, 24.0), rank.key(s_right, 20.0)];
            assert_eq!(
                prune_overlapping(&[oversized, right], &k, 0.4, 0.8),
                vec![1],
                "{rank:?}"
            );
        }
        // A small fruit half in front of a large one: 64 % of the small one's area is shared,
        // but its centre lies at 0.85 of the large radius. The paper's test drops the weaker;
        // with a centre reach of 0.8 both stay, while a circle centred well inside still goes.
        let large = (Point2::new(0.0, 0.0), 20.0);
        let front = (Point2::new(17.0, 0.0), 10.0);
        let inner = (Point2::new(12.0, 0.0), 10.0);
        assert_eq!(
            prune_overlapping(&[large, front], &[1.0, 0.5], 0.4, 0.0),
            vec![0]
        );
        assert_eq!(
            prune_overlapping(&[large, front], &[1.0, 0.5], 0.4, 0.8),
            vec![0, 1]
        );
        assert_eq!(
            prune_overlapping(&[large, inner], &[1.0, 0.5], 0.4, 0.8),
            vec![0]
        );
        let old: PruneRank = serde_json::from_value(serde_json::json!("score")).unwrap();
        assert_eq!(old, PruneRank::default());
        assert_eq!(
            serde_json::to_value(PruneRank::ArcLength).unwrap(),
            serde_json::json!("arc-length")
        );
    }
}
