//! Local maxima of a row-major grid, one per plateau: the centres of the inscribed discs of the
//! ray circles ([`crate::ray_circles`], on the distance transform) and the centre hypotheses of
//! the Hough circles ([`crate::hough_circles`], on the vote sums) are both found this way.

use std::cmp::Ordering;

use crate::window_reduce::window_reduce;

/// Indices, in raster order, of the cells of `values` (row-major, `width` wide) that pass
/// `candidate` and hold the largest value within `half` cells in x and y. A cell must be
/// strictly above the cells before it in raster order and at least the ones after it, so a
/// plateau gives its first cell only.
///
/// The window's largest value is taken first for every cell, separably
/// ([`window_reduce`]); only the cells
/// that reach it — few on a vote grid where nearly every cell passes `candidate` — are then
/// compared with their window one by one for the raster-order rule.
pub(crate) fn local_maxima<T: PartialOrd + Copy>(
    values: &[T],
    width: usize,
    half: usize,
    candidate: impl Fn(T) -> bool,
) -> Vec<usize> {
    let width = width.max(1);
    let height = values.len() / width;
    let values = &values[..width * height];
    let window_max = window_max(values, width, half);
    let mut found = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let v = values[y * width + x];
            // `v` is at least every value of its window only if it is at least their largest.
            let reaches = v
                .partial_cmp(&window_max[y * width + x])
                .is_some_and(Ordering::is_ge);
            if !candidate(v) || !reaches {
                continue;
            }
            // The window's rows above and its row left of the cell come before it in raster
            // order (strictly below `v`), the rest after it (at most `v`).
            let (x0, x1) = (x.saturating_sub(half), (x + half + 1).min(width));
            let row = |yy: usize| &values[yy * width + x0..yy * width + x1];
            let below = |u: &T| v > *u;
            let at_most = |u: &T| v >= *u;
            let is_peak = (y.saturating_sub(half)..y).all(|yy| row(yy).iter().all(below))
                && row(y)[..x - x0].iter().all(below)
                && row(y)[x - x0..].iter().all(at_most)
                && (y + 1..(y + half + 1).min(height)).all(|yy| row(yy).iter().all(at_most));
            if is_peak {
                found.push(y * width + x);
            }
        }
    }
    found
}

/// The larger of two values (the first when they do not compare).
fn larger<T: PartialOrd + Copy>(a: T, b: T) -> T {
    if b > a {
        b
    } else {
        a
    }
}

/// For every cell of `values` (row-major, `width` wide, whole rows), a value of its window of
/// `half` cells in x and y that no other value of the window exceeds.
fn window_max<T: PartialOrd + Copy>(values: &[T], width: usize, half: usize) -> Vec<T> {
    window_reduce(values, width, half, larger)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn peaks_follow_the_raster_order_rule_on_random_grids() {
        // Few distinct values, so plateaus and ties are everywhere.
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..300 {
            let (w, h, half) = (
                rng.gen_range(1..15),
                rng.gen_range(1..15),
                rng.gen_range(0..4),
            );
            let grid: Vec<u32> = (0..w * h).map(|_| rng.gen_range(0..4)).collect();
            let expected: Vec<usize> = (0..w * h)
                .filter(|&i| {
                    let (x, y) = (i % w, i / w);
                    grid[i] > 0
                        && (0..w * h).all(|j| {
                            let (xx, yy) = (j % w, j / w);
                            let inside = xx.abs_diff(x) <= half && yy.abs_diff(y) <= half;
                            !inside
                                || if j < i {
                                    grid[i] > grid[j]
                                } else {
                                    grid[i] >= grid[j]
                                }
                        })
                })
                .collect();
            assert_eq!(
                local_maxima(&grid, w, half, |v| v > 0),
                expected,
                "{w}×{h}, half {half}"
            );
        }
    }

    #[test]
    fn the_window_maximum_is_the_largest_value_of_each_window() {
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        for _ in 0..300 {
            let (w, h, half): (usize, usize, usize) = (
                rng.gen_range(1..15),
                rng.gen_range(1..15),
                rng.gen_range(0..5),
            );
            let grid: Vec<u32> = (0..w * h).map(|_| rng.gen_range(0..50)).collect();
            let expected: Vec<u32> = (0..w * h)
                .map(|i| {
                    let (x, y) = (i % w, i / w);
                    (0..w * h)
                        .filter(|&j| (j % w).abs_diff(x) <= half && (j / w).abs_diff(y) <= half)
                        .map(|j| grid[j])
                        .max()
                        .unwrap_or(0)
                })
                .collect();
            assert_eq!(window_max(&grid, w, half), expected, "{w}×{h}, half {half}");
        }
    }

    #[test]
    fn a_plateau_gives_its_first_cell_and_the_candidate_test_applies() {
        #[rustfmt::skip]
        let grid = [
            0, 0, 0, 0, 0, 0,
            0, 5, 5, 0, 0, 0,
            0, 0, 0, 0, 3, 0,
            0, 0, 0, 0, 0, 0,
        ];
        assert_eq!(local_maxima(&grid, 6, 1, |v| v > 0), vec![7, 16]);
        assert_eq!(local_maxima(&grid, 6, 1, |v| v > 4), vec![7]);
        // A window wide enough to see the 5s hides the 3.
        assert_eq!(local_maxima(&grid, 6, 3, |v| v > 0), vec![7]);
        assert!(local_maxima::<u32>(&[], 0, 1, |_| true).is_empty());
    }
}
