//! Mean-shift merging of positive boxes (seed 001): every positive box centre climbs to the mode
//! of the score-weighted density of positive centres (flat kernel of radius `bandwidth`), and
//! boxes reaching the same mode (within half a bandwidth) become one detection at that mode
//! carrying the best member's score and symmetry-plane normal.
//!
//! Weights are `score − min_score` (positive for every box passed in), so confident boxes pull
//! harder. Seeds are processed in input order and modes merged greedily in that order:
//! deterministic.

use nalgebra::Point3;

use crate::ScoredBox;

/// Merges `boxes` (all scoring above `min_score`) by mean shift.
pub fn mean_shift(
    boxes: &[ScoredBox],
    min_score: f64,
    bandwidth_m: f64,
    max_iterations: usize,
) -> Vec<ScoredBox> {
    let h2 = bandwidth_m * bandwidth_m;
    let weight = |b: &ScoredBox| (b.score - min_score).max(1e-9);
    let mut modes: Vec<(Point3<f64>, ScoredBox)> = Vec::new();
    for seed in boxes {
        let mut x = seed.center;
        for _ in 0..max_iterations {
            let (mut sum, mut wsum) = (nalgebra::Vector3::zeros(), 0.0);
            for b in boxes {
                if (b.center - x).norm_squared() <= h2 {
                    let w = weight(b);
                    sum += b.center.coords * w;
                    wsum += w;
                }
            }
            if wsum <= 0.0 {
                break;
            }
            let next = Point3::from(sum / wsum);
            let moved = (next - x).norm();
            x = next;
            if moved < 1e-3 * bandwidth_m {
                break;
            }
        }
        match modes
            .iter_mut()
            .find(|(m, _)| (m - x).norm() < 0.5 * bandwidth_m)
        {
            Some((_, best)) => {
                if seed.score > best.score {
                    best.score = seed.score;
                    best.symmetry_plane_normal = seed.symmetry_plane_normal;
                }
            }
            None => modes.push((x, *seed)),
        }
    }
    modes
        .into_iter()
        .map(|(m, b)| ScoredBox {
            center: m,
            score: b.score,
            symmetry_plane_normal: b.symmetry_plane_normal,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(x: f64, y: f64, score: f64) -> ScoredBox {
        ScoredBox {
            center: Point3::new(x, y, 1.0),
            score,
            symmetry_plane_normal: None,
        }
    }

    #[test]
    fn two_clusters_give_two_modes() {
        let boxes = [
            b(0.0, 0.0, 1.0),
            b(0.02, 0.0, 1.0),
            b(0.01, 0.02, 2.0),
            b(0.3, 0.0, 0.5),
            b(0.32, 0.0, 0.7),
        ];
        let modes = mean_shift(&boxes, 0.0, 0.04, 50);
        assert_eq!(modes.len(), 2);
        assert_eq!(modes[0].score, 2.0);
        assert!((modes[0].center.x - 0.01).abs() < 0.01);
        assert!((modes[1].center.x - 0.31).abs() < 0.01);
        assert_eq!(modes[1].score, 0.7);
    }

    #[test]
    fn single_box_stays_put() {
        let modes = mean_shift(&[b(0.1, 0.2, 0.3)], 0.0, 0.04, 10);
        assert_eq!(modes.len(), 1);
        assert_eq!(modes[0].center, Point3::new(0.1, 0.2, 1.0));
    }
}
