//! The perceptron compiled into a lookup table (seed 004 §3.1: "the network is used to build a
//! look-up table of integer values for each possible point in the color space").
//!
//! The HΣ coordinates depend on a colour only through `(G − B, 2R − G − B)`, so one cell per
//! pair of those integers (511 × 1021 cells, 510 KiB) holds the network's output *exactly* —
//! quantised to an integer 0–255 as in the paper — and a frame costs one table read per pixel.
//! A network with the intensity input (not in the paper) gets one such plane per intensity band
//! ([`crate::INTENSITY_LEVELS`] planes, 4 MiB), each evaluated at its band's middle intensity —
//! the value the network was trained on — so the table is still exact for the network; only the
//! cells a colour can reach (`2R − G − B` and `G − B` have the same parity) are evaluated, the
//! planes in parallel.

use rayon::prelude::*;

use crate::hsigma::{GB_COUNT, GB_MIN, SIGMA_COUNT, SIGMA_MIN};
use crate::{
    hsigma_integers, hsigma_of_integers, intensity_level, intensity_of_level, Mlp, INTENSITY_LEVELS,
};

/// Fruit probability quantised to 0–255 for every `(G − B, 2R − G − B)` cell, per intensity band
/// when the network has the intensity input.
#[derive(Debug, Clone, PartialEq)]
pub struct HSigmaLut {
    cells: Vec<u8>,
    /// Planes of `GB_COUNT × SIGMA_COUNT` cells: 1, or [`INTENSITY_LEVELS`].
    levels: usize,
}

const PLANE: usize = GB_COUNT * SIGMA_COUNT;

/// The table's integer value for a network output `p` in [0, 1].
pub fn quantise_probability(p: f64) -> u8 {
    (p.clamp(0.0, 1.0) * 255.0).round() as u8
}

fn cell_index(g_minus_b: i32, sigma: i32) -> usize {
    (sigma - SIGMA_MIN) as usize * GB_COUNT + (g_minus_b - GB_MIN) as usize
}

/// The largest `|G − B|` and `|2R − G − B|` of a colour in intensity band `level` of a table of
/// `levels` bands: with `S = R + G + B`, `|G − B| ≤ min(S, 765 − S)` and `|2R − G − B|` at most
/// twice that (a colour and its complement `255 − c` mirror each other), capped by the 8-bit
/// range. One band covers every colour.
fn reach(level: usize, levels: usize) -> (i32, i32) {
    let full = (-GB_MIN, -SIGMA_MIN);
    if levels == 1 {
        return full;
    }
    let band = 768 / levels as i32;
    let (lo, hi) = (
        band * level as i32,
        (band * (level as i32 + 1) - 1).min(765),
    );
    let m = hi.min(765 - lo);
    (m.min(full.0), (2 * m).min(full.1))
}

impl HSigmaLut {
    /// Evaluates `net` on every cell (every cell a colour can reach, per intensity band when the
    /// network has the intensity input; unreachable cells hold 0).
    pub fn compile(net: &Mlp) -> Self {
        let levels = if net.uses_intensity() {
            INTENSITY_LEVELS
        } else {
            1
        };
        let mut cells = vec![0u8; levels * PLANE];
        cells
            .par_chunks_mut(PLANE)
            .enumerate()
            .for_each(|(level, plane)| {
                let intensity = intensity_of_level(level);
                let (gb_reach, sigma_reach) = reach(level, levels);
                for sigma in -sigma_reach..=sigma_reach {
                    // G − B ≡ 2R − G − B (mod 2).
                    let first = -gb_reach + (sigma + gb_reach).rem_euclid(2);
                    for gb in (first..=gb_reach).step_by(2) {
                        let (x, y) = hsigma_of_integers(gb, sigma);
                        plane[cell_index(gb, sigma)] =
                            quantise_probability(net.probability(x, y, intensity));
                    }
                }
            });
        Self { cells, levels }
    }

    /// Intensity bands of the table: 1 for the paper's network, [`INTENSITY_LEVELS`] with the
    /// intensity input.
    pub fn levels(&self) -> usize {
        self.levels
    }

    /// The table value (0–255) of the cell `(G − B, 2R − G − B)` in intensity band `level`;
    /// `None` outside the 8-bit range or the table's bands. Cells no colour reaches hold 0.
    pub fn cell(&self, g_minus_b: i32, sigma: i32, level: usize) -> Option<u8> {
        let inside = (GB_MIN..GB_MIN + GB_COUNT as i32).contains(&g_minus_b)
            && (SIGMA_MIN..SIGMA_MIN + SIGMA_COUNT as i32).contains(&sigma)
            && level < self.levels;
        inside.then(|| self.cells[level * PLANE + cell_index(g_minus_b, sigma)])
    }

    /// The table value (0–255) of an 8-bit colour.
    pub fn value(&self, rgb: [u8; 3]) -> u8 {
        let (gb, s) = hsigma_integers(rgb);
        let plane = if self.levels > 1 {
            intensity_level(rgb) * PLANE
        } else {
            0
        };
        self.cells[plane + cell_index(gb, s)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MlpParams;

    fn net(intensity: bool) -> Mlp {
        // Orange-ish (large Y, small X) against green and grey.
        let mut samples = Vec::new();
        for (rgb, fruit) in [
            ([230u8, 120u8, 20u8], true),
            ([200, 90, 10], true),
            ([250, 160, 40], true),
            ([60, 140, 40], false),
            ([90, 100, 80], false),
            ([30, 30, 30], false),
            ([120, 160, 200], false),
        ] {
            for k in 0..20u8 {
                let c = rgb.map(|v| v.saturating_add(k).saturating_sub(10));
                samples.push((crate::network_inputs(c), fruit));
            }
        }
        Mlp::train(
            &samples,
            &MlpParams {
                intensity,
                ..MlpParams::default()
            },
            3,
        )
        .unwrap()
    }

    #[test]
    fn table_equals_the_network_on_every_reachable_cell_and_every_colour() {
        for intensity in [false, true] {
            let net = net(intensity);
            let lut = HSigmaLut::compile(&net);
            assert_eq!(lut.levels(), if intensity { INTENSITY_LEVELS } else { 1 });
            // Every colour (every fifth value per channel, and the extremes) finds its cell
            // holding the network's output there: the cells skipped as unreachable never are.
            let values: Vec<u8> = (0..=255).step_by(5).chain([1, 254]).collect();
            for &r in &values {
                for &g in &values {
                    for &b in &values {
                        let rgb = [r, g, b];
                        let [x, y, i] = crate::network_inputs(rgb);
                        let expected = quantise_probability(net.probability(x, y, i));
                        assert_eq!(lut.value(rgb), expected, "colour {rgb:?}");
                        let (gb, s) = hsigma_integers(rgb);
                        let level = if intensity { intensity_level(rgb) } else { 0 };
                        assert_eq!(lut.cell(gb, s, level), Some(expected));
                    }
                }
            }
            // The paper's single plane: every cell a colour can reach (G − B and 2R − G − B of
            // one parity) holds the network's output there.
            if !intensity {
                for s in SIGMA_MIN..SIGMA_MIN + SIGMA_COUNT as i32 {
                    for gb in (GB_MIN..GB_MIN + GB_COUNT as i32).filter(|gb| (s - gb) % 2 == 0) {
                        let (x, y) = hsigma_of_integers(gb, s);
                        let expected = quantise_probability(net.probability(x, y, 0.0));
                        assert_eq!(lut.cell(gb, s, 0), Some(expected), "cell ({gb}, {s})");
                    }
                }
            }
            assert_eq!(lut.cell(256, 0, 0), None);
            assert_eq!(lut.cell(0, 0, lut.levels()), None);
            assert!(lut.value([230, 120, 20]) > 200 && lut.value([60, 140, 40]) < 50);
        }
    }

    #[test]
    fn the_intensity_input_tells_apart_colours_of_one_place_in_the_plane() {
        // Two colours with the same (G − B, 2R − G − B), one dim fruit, one bright background.
        let (dim_fruit, bright_leaf) = ([70u8, 40, 20], [200, 170, 150]);
        assert_eq!(hsigma_integers(dim_fruit), hsigma_integers(bright_leaf));
        let mut samples = Vec::new();
        for _ in 0..200 {
            for (c, fruit) in [(dim_fruit, true), (bright_leaf, false)] {
                samples.push((crate::network_inputs(c), fruit));
            }
        }
        let params = MlpParams {
            epochs: 200,
            ..MlpParams::default()
        };
        let lut = HSigmaLut::compile(&Mlp::train(&samples, &params, 1).unwrap());
        assert!(lut.value(dim_fruit) > 200 && lut.value(bright_leaf) < 55);
        let plane_only = MlpParams {
            intensity: false,
            ..params
        };
        let lut = HSigmaLut::compile(&Mlp::train(&samples, &plane_only, 1).unwrap());
        assert_eq!(lut.value(dim_fruit), lut.value(bright_leaf));
    }
}
