//! Local maxima of a row-major grid, one per plateau: the centres of the inscribed discs of the
//! ray circles ([`crate::ray_circles`], on the distance transform) and the centre hypotheses of
//! the Hough circles ([`crate::hough_circles`], on the vote sums) are both found this way.

/// Indices, in raster order, of the cells of `values` (row-major, `width` wide) that pass
/// `candidate` and hold the largest value within `half` cells in x and y. A cell must be
/// strictly above the cells before it in raster order and at least the ones after it, so a
/// plateau gives its first cell only.
pub(crate) fn local_maxima<T: PartialOrd + Copy>(
    values: &[T],
    width: usize,
    half: usize,
    candidate: impl Fn(T) -> bool,
) -> Vec<usize> {
    let width = width.max(1);
    let height = values.len() / width;
    let mut found = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let v = values[y * width + x];
            if !candidate(v) {
                continue;
            }
            let is_peak = (y.saturating_sub(half)..(y + half + 1).min(height)).all(|yy| {
                (x.saturating_sub(half)..(x + half + 1).min(width)).all(|xx| {
                    let u = values[yy * width + xx];
                    if (yy, xx) < (y, x) {
                        v > u
                    } else {
                        v >= u
                    }
                })
            });
            if is_peak {
                found.push(y * width + x);
            }
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

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
