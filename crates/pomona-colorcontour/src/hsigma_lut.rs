//! The perceptron compiled into a lookup table (seed 004 §3.1: "the network is used to build a
//! look-up table of integer values for each possible point in the color space").
//!
//! The HΣ coordinates depend on a colour only through `(G − B, 2R − G − B)`, so one cell per
//! pair of those integers (511 × 1021 cells, 510 KiB) holds the network's output *exactly* —
//! quantised to an integer 0–255 as in the paper — and a frame costs one table read per pixel.

use crate::hsigma::{GB_COUNT, GB_MIN, SIGMA_COUNT, SIGMA_MIN};
use crate::{hsigma_integers, hsigma_of_integers, Mlp};

/// Fruit probability quantised to 0–255 for every `(G − B, 2R − G − B)` cell.
#[derive(Debug, Clone, PartialEq)]
pub struct HSigmaLut {
    cells: Vec<u8>,
}

/// The table's integer value for a network output `p` in [0, 1].
pub fn quantise_probability(p: f64) -> u8 {
    (p.clamp(0.0, 1.0) * 255.0).round() as u8
}

fn cell_index(g_minus_b: i32, sigma: i32) -> usize {
    (sigma - SIGMA_MIN) as usize * GB_COUNT + (g_minus_b - GB_MIN) as usize
}

impl HSigmaLut {
    /// Evaluates `net` on every cell.
    pub fn compile(net: &Mlp) -> Self {
        let mut cells = Vec::with_capacity(GB_COUNT * SIGMA_COUNT);
        for s in 0..SIGMA_COUNT as i32 {
            for gb in 0..GB_COUNT as i32 {
                let (x, y) = hsigma_of_integers(gb + GB_MIN, s + SIGMA_MIN);
                cells.push(quantise_probability(net.probability(x, y)));
            }
        }
        Self { cells }
    }

    /// The table value (0–255) of the cell `(G − B, 2R − G − B)`; `None` outside the 8-bit range.
    pub fn cell(&self, g_minus_b: i32, sigma: i32) -> Option<u8> {
        let inside = (GB_MIN..GB_MIN + GB_COUNT as i32).contains(&g_minus_b)
            && (SIGMA_MIN..SIGMA_MIN + SIGMA_COUNT as i32).contains(&sigma);
        inside.then(|| self.cells[cell_index(g_minus_b, sigma)])
    }

    /// The table value (0–255) of an 8-bit colour.
    pub fn value(&self, rgb: [u8; 3]) -> u8 {
        let (gb, s) = hsigma_integers(rgb);
        self.cells[cell_index(gb, s)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MlpParams;

    fn net() -> Mlp {
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
                samples.push((crate::hsigma(c), fruit));
            }
        }
        Mlp::train(&samples, &MlpParams::default(), 3).unwrap()
    }

    #[test]
    fn table_equals_the_network_on_every_cell_and_every_colour() {
        let net = net();
        let lut = HSigmaLut::compile(&net);
        for s in SIGMA_MIN..SIGMA_MIN + SIGMA_COUNT as i32 {
            for gb in GB_MIN..GB_MIN + GB_COUNT as i32 {
                let (x, y) = hsigma_of_integers(gb, s);
                let expected = quantise_probability(net.probability(x, y));
                assert_eq!(lut.cell(gb, s), Some(expected), "cell ({gb}, {s})");
            }
        }
        assert_eq!(lut.cell(256, 0), None);
        // Looking up by colour reaches the right cell.
        for rgb in [
            [0u8, 0, 0],
            [255, 0, 255],
            [230, 120, 20],
            [60, 140, 40],
            [7, 250, 3],
        ] {
            let (x, y) = crate::hsigma(rgb);
            assert_eq!(lut.value(rgb), quantise_probability(net.probability(x, y)));
        }
        assert!(lut.value([230, 120, 20]) > 200 && lut.value([60, 140, 40]) < 50);
    }
}
