//! The HΣ colour plane of seed 004 (§3.1, Eqs. 6–7): the parallel projection of RGB onto the
//! plane normal to the grey axis,
//!
//! X = (√3/2)(G − B),  Y = R − (G + B)/2.
//!
//! Unlike hue and saturation (point projection, Eqs. 4–5), this keeps dark and unsaturated pixels
//! near the origin, where their noise does no harm, and spreads the saturated orange of fruit far
//! from the blue-to-green band of the background. Both coordinates are functions of the two
//! integers `G − B` and `2R − G − B`, which is what lets [`crate::HSigmaLut`] tabulate a classifier
//! over the plane exactly.
//!
//! Not in the paper: the projection drops the third coordinate, the position along the grey axis
//! (intensity, here the mean `(R + G + B) / 3`). A dim orange and a dark leaf, or a lit orange
//! and a sunlit yellow-green leaf, can share a place in the plane and differ only there; one
//! table over the plane must then trade daylight against dim or harsh light (docs/results.md,
//! "Colour with intensity"; `examples/colour_table_bound.rs` measures how far any table over a
//! colour space can go). [`intensity_level`] quantises the mean into
//! [`INTENSITY_LEVELS`] bands, the optional third input of [`crate::Mlp`] and of its table.

/// Smallest value of `G − B` for 8-bit colour.
pub const GB_MIN: i32 = -255;
/// Number of distinct values of `G − B` (−255..=255).
pub const GB_COUNT: usize = 511;
/// Smallest value of `2R − G − B`.
pub const SIGMA_MIN: i32 = -510;
/// Number of distinct values of `2R − G − B` (−510..=510).
pub const SIGMA_COUNT: usize = 1021;

/// Bands of the mean intensity `(R + G + B) / 3` (each 32 wide) of the optional third input.
pub const INTENSITY_LEVELS: usize = 8;

/// The band (0..[`INTENSITY_LEVELS`]) of a colour's mean intensity.
pub fn intensity_level([r, g, b]: [u8; 3]) -> usize {
    let sum = usize::from(r) + usize::from(g) + usize::from(b);
    (sum * INTENSITY_LEVELS / 768).min(INTENSITY_LEVELS - 1)
}

/// The mean intensity (0–255) a band stands for: its middle.
pub fn intensity_of_level(level: usize) -> f64 {
    (level as f64 + 0.5) * 256.0 / INTENSITY_LEVELS as f64
}

/// What the colour network sees of a colour: HΣ `X`, `Y` (Eqs. 6–7) and the middle of its
/// intensity band — the value the lookup table's plane for that band is evaluated at, so a
/// network trained on these inputs is tabulated exactly. A network without the intensity input
/// ignores the third.
pub fn network_inputs(rgb: [u8; 3]) -> [f64; 3] {
    let (x, y) = hsigma(rgb);
    [x, y, intensity_of_level(intensity_level(rgb))]
}

/// The two integers that determine a colour's place in the HΣ plane: `(G − B, 2R − G − B)`.
pub fn hsigma_integers([r, g, b]: [u8; 3]) -> (i32, i32) {
    let (r, g, b) = (i32::from(r), i32::from(g), i32::from(b));
    (g - b, 2 * r - g - b)
}

/// HΣ coordinates `(X, Y)` (Eqs. 6–7) of the colour with integers `(G − B, 2R − G − B)`.
pub fn hsigma_of_integers(g_minus_b: i32, two_r_minus_g_minus_b: i32) -> (f64, f64) {
    (
        0.75f64.sqrt() * f64::from(g_minus_b),
        0.5 * f64::from(two_r_minus_g_minus_b),
    )
}

/// HΣ coordinates `(X, Y)` of an 8-bit RGB colour (Eqs. 6–7).
///
/// ```
/// let (x, y) = pomona_colorcontour::hsigma([255, 128, 0]);
/// assert!((x - 0.75f64.sqrt() * 128.0).abs() < 1e-12 && (y - 191.0).abs() < 1e-12);
/// ```
pub fn hsigma(rgb: [u8; 3]) -> (f64, f64) {
    let (gb, s) = hsigma_integers(rgb);
    hsigma_of_integers(gb, s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grey_is_the_origin_and_the_hexagon_has_radius_255() {
        for v in [0u8, 77, 255] {
            assert_eq!(hsigma([v, v, v]), (0.0, 0.0));
        }
        // Σ = distance from the centre; the pure primaries sit on the hexagon's corners.
        for rgb in [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 0]] {
            let (x, y) = hsigma(rgb);
            assert!(((x * x + y * y).sqrt() - 255.0).abs() < 1e-9, "{rgb:?}");
        }
        // Orange lies towards +Y (red), leaf green towards +X.
        let (x, y) = hsigma([230, 120, 20]);
        assert!(y > 100.0 && x > 0.0);
        let (x, y) = hsigma([60, 140, 40]);
        assert!(x > 80.0 && y < 0.0);
    }
}
