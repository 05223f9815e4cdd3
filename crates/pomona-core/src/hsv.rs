//! RGB → HSV, the one conversion every crate uses: seed 002 segments and describes fruit in HSV
//! (hue is less sensitive to illumination than RGB), seed 000's highlight test reads value and
//! saturation (Eq. 1). All three components are in `[0, 1]`; hue is circular (0 and 1 are red),
//! so averaging hues needs [`circular_mean_hue`], not an arithmetic mean.

use std::f64::consts::TAU;

/// Converts an 8-bit RGB triple to `(h, s, v)` in `[0, 1]`.
///
/// ```
/// let [h, s, v] = pomona_core::rgb_to_hsv([255, 0, 0]);
/// assert_eq!((h, s, v), (0.0, 1.0, 1.0));
/// ```
pub fn rgb_to_hsv(rgb: [u8; 3]) -> [f64; 3] {
    let [r, g, b] = rgb.map(|c| c as f64 / 255.0);
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let delta = max - min;
    let s = if max > 0.0 { delta / max } else { 0.0 };
    let h = if delta == 0.0 {
        0.0
    } else if max == r {
        ((g - b) / delta).rem_euclid(6.0) / 6.0
    } else if max == g {
        ((b - r) / delta + 2.0) / 6.0
    } else {
        ((r - g) / delta + 4.0) / 6.0
    };
    [h.rem_euclid(1.0), s, max]
}

/// The circular mean of hues in `[0, 1)` (the direction of the mean of the unit vectors at
/// angle `2π h`), or `None` when there are none or they cancel out (e.g. two opposite hues).
/// Red hues either side of 0 average to red, where the arithmetic mean gives cyan.
///
/// ```
/// let h = pomona_core::circular_mean_hue(&[0.98, 0.02]).unwrap();
/// assert!(h < 1e-9 || h > 1.0 - 1e-9);
/// ```
pub fn circular_mean_hue(hues: &[f64]) -> Option<f64> {
    let (s, c) = hues.iter().fold((0.0, 0.0), |(s, c), h| {
        let a = TAU * h;
        (s + a.sin(), c + a.cos())
    });
    let n = hues.len() as f64;
    if hues.is_empty() || (s * s + c * c).sqrt() <= 1e-9 * n {
        return None;
    }
    Some((s.atan2(c) / TAU).rem_euclid(1.0))
}

/// The signed difference `a − b` of two hues on the circle, in `[-0.5, 0.5)`.
///
/// ```
/// assert!((pomona_core::hue_difference(0.02, 0.98) - 0.04).abs() < 1e-12);
/// ```
pub fn hue_difference(a: f64, b: f64) -> f64 {
    (a - b + 0.5).rem_euclid(1.0) - 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circular_mean_wraps_around_red() {
        let m = circular_mean_hue(&[0.95, 0.05, 0.0]).unwrap();
        assert!(hue_difference(m, 0.0).abs() < 1e-12, "{m}");
        let m = circular_mean_hue(&[0.2, 0.3]).unwrap();
        assert!((m - 0.25).abs() < 1e-12);
        assert_eq!(circular_mean_hue(&[]), None);
        assert_eq!(circular_mean_hue(&[0.0, 0.5]), None);
        assert!((hue_difference(0.9, 0.1) + 0.2).abs() < 1e-12);
    }

    #[test]
    fn primaries_and_greys() {
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9);
        assert!(close(rgb_to_hsv([0, 255, 0]), [1.0 / 3.0, 1.0, 1.0]));
        assert!(close(rgb_to_hsv([0, 0, 255]), [2.0 / 3.0, 1.0, 1.0]));
        assert!(close(rgb_to_hsv([255, 0, 255]), [5.0 / 6.0, 1.0, 1.0]));
        assert!(close(
            rgb_to_hsv([128, 128, 128]),
            [0.0, 0.0, 128.0 / 255.0]
        ));
        assert!(close(rgb_to_hsv([0, 0, 0]), [0.0, 0.0, 0.0]));
    }
}
