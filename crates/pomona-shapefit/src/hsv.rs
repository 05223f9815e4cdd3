//! RGB → HSV, the colour space seed 002 segments in (hue is less sensitive to illumination
//! than RGB). All three components are in `[0, 1]`; hue is circular (0 and 1 are red).

/// Converts an 8-bit RGB triple to `(h, s, v)` in `[0, 1]`.
///
/// ```
/// let [h, s, v] = pomona_shapefit::rgb_to_hsv([255, 0, 0]);
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

#[cfg(test)]
mod tests {
    use super::*;

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
