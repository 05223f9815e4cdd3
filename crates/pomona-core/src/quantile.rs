//! Quantiles of measured values (errors, timings), the one definition every report uses: linear
//! interpolation between the two nearest order statistics (Hyndman–Fan type 7, what NumPy's
//! `quantile` does by default), so the median of an even count is the mean of the middle two.
//! Kept apart from the detectors' own robust statistics (a depth "median" that must be one of
//! the measured depths takes the middle sample instead).

/// The `q`-quantile (`q` in `[0, 1]`, clamped) of `sorted`, which must be sorted ascending;
/// `None` when it is empty.
///
/// ```
/// use pomona_core::quantile;
/// assert_eq!(quantile(&[1.0, 2.0, 4.0, 8.0], 0.5), Some(3.0));
/// assert_eq!(quantile(&[1.0, 2.0, 4.0, 8.0], 1.0), Some(8.0));
/// assert_eq!(quantile(&[], 0.5), None);
/// ```
pub fn quantile(sorted: &[f64], q: f64) -> Option<f64> {
    let last = sorted.len().checked_sub(1)?;
    let pos = q.clamp(0.0, 1.0) * last as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    Some(sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64))
}

/// The median of `values` (sorted in place); `None` when there are none.
///
/// ```
/// use pomona_core::median;
/// assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
/// assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), Some(2.5));
/// ```
pub fn median(values: &mut [f64]) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    quantile(values, 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_interpolate_between_order_statistics() {
        let v = [0.0, 10.0, 20.0, 30.0, 40.0];
        assert_eq!(quantile(&v, 0.0), Some(0.0));
        assert_eq!(quantile(&v, 0.9), Some(36.0));
        assert_eq!(quantile(&v, 0.5), Some(20.0));
        assert_eq!(quantile(&[7.0], 0.3), Some(7.0));
        // Out of range: clamped, never out of bounds.
        assert_eq!(quantile(&v, 2.0), Some(40.0));
        assert_eq!(quantile(&v, -1.0), Some(0.0));
        assert_eq!(median(&mut []), None);
        // The stereo report's own quantile, which this one replaced, asserted these.
        assert_eq!(quantile(&[], 0.5), None);
        assert_eq!(quantile(&[1.0, 2.0, 4.0], 0.5), Some(2.0));
        assert_eq!(quantile(&[1.0, 3.0], 0.5), Some(2.0));
    }
}
