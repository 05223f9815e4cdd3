//! Seed 002's probabilistic colour segmentation (Eqs. 1–2): naive Bayes over H, S and V with
//! class-conditional densities from normalised histograms smoothed by a Gaussian Parzen window,
//! and priors from the training pixel counts.
//!
//! Split in two: [`ColorBayes`] is the learned model (small, serialised into the model file), and
//! [`ColorLut`] is the same posterior evaluated once for every quantised RGB colour, so a frame
//! costs one table lookup per pixel instead of an HSV conversion and six density lookups.

use serde::{Deserialize, Serialize};

use crate::rgb_to_hsv;

/// Parameters of the colour model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ColorBayesParams {
    /// Histogram bins per HSV channel (the paper uses image histograms; 64 bins keeps the
    /// densities smooth with a few thousand training pixels).
    pub bins: usize,
    /// Standard deviation of the Gaussian Parzen window, in bins (hue wraps around).
    pub parzen_sigma_bins: f64,
    /// Posterior threshold of the mask (paper: 0.1, low on purpose to avoid over-segmentation).
    pub threshold: f64,
    /// Bits per RGB channel of the compiled lookup table (6 → 2^18 entries, 1 MiB).
    pub lut_bits: u32,
}

impl Default for ColorBayesParams {
    fn default() -> Self {
        Self {
            bins: 64,
            parzen_sigma_bins: 1.5,
            threshold: 0.1,
            lut_bits: 6,
        }
    }
}

/// Pixel counts per HSV bin for fruit (foreground) and everything else (background).
#[derive(Debug, Clone, PartialEq)]
pub struct ColorHistograms {
    bins: usize,
    foreground: [Vec<u64>; 3],
    background: [Vec<u64>; 3],
}

impl ColorHistograms {
    /// Empty histograms with `bins` bins per channel (at least 1).
    pub fn new(bins: usize) -> Self {
        let bins = bins.max(1);
        Self {
            bins,
            foreground: std::array::from_fn(|_| vec![0; bins]),
            background: std::array::from_fn(|_| vec![0; bins]),
        }
    }

    fn bin(&self, x: f64) -> usize {
        ((x * self.bins as f64) as usize).min(self.bins - 1)
    }

    /// Counts one training pixel.
    pub fn add(&mut self, rgb: [u8; 3], is_fruit: bool) {
        let hsv = rgb_to_hsv(rgb);
        let bins = hsv.map(|x| self.bin(x));
        let target = if is_fruit {
            &mut self.foreground
        } else {
            &mut self.background
        };
        for (c, &b) in bins.iter().enumerate() {
            target[c][b] += 1;
        }
    }

    /// Adds another set of counts (for example from another frame).
    pub fn merge(&mut self, other: &Self) {
        if other.bins != self.bins {
            return;
        }
        for c in 0..3 {
            for b in 0..self.bins {
                self.foreground[c][b] += other.foreground[c][b];
                self.background[c][b] += other.background[c][b];
            }
        }
    }

    /// `(foreground, background)` pixel counts.
    pub fn counts(&self) -> (u64, u64) {
        (
            self.foreground[0].iter().sum(),
            self.background[0].iter().sum(),
        )
    }
}

/// The learned naive-Bayes colour model: smoothed, normalised densities and the fruit prior.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColorBayes {
    /// Densities `p(h|f), p(s|f), p(v|f)`, each summing to 1.
    pub foreground: [Vec<f64>; 3],
    /// Densities `p(h|b), p(s|b), p(v|b)`.
    pub background: [Vec<f64>; 3],
    /// `p(f)`: share of fruit pixels among the training pixels.
    pub prior_fruit: f64,
}

/// Gaussian Parzen smoothing of a histogram, then normalisation to sum 1. `circular` wraps the
/// kernel around (hue).
fn smooth(counts: &[u64], sigma_bins: f64, circular: bool) -> Vec<f64> {
    let n = counts.len() as isize;
    let radius = (3.0 * sigma_bins).ceil() as isize;
    let kernel: Vec<f64> = (-radius..=radius)
        .map(|k| {
            if sigma_bins > 0.0 {
                (-0.5 * (k as f64 / sigma_bins).powi(2)).exp()
            } else {
                (k == 0) as u8 as f64
            }
        })
        .collect();
    let mut out = vec![0.0; counts.len()];
    for (i, o) in out.iter_mut().enumerate() {
        for (k, w) in (-radius..=radius).zip(&kernel) {
            let j = i as isize + k;
            let j = if circular {
                j.rem_euclid(n)
            } else if (0..n).contains(&j) {
                j
            } else {
                continue;
            };
            *o += w * counts[j as usize] as f64;
        }
    }
    // A tiny floor keeps colours never seen in training from giving 0/0.
    let total: f64 = out.iter().sum::<f64>();
    let floor = 1e-9;
    out.iter()
        .map(|x| (x / total.max(f64::MIN_POSITIVE)).max(floor))
        .collect()
}

impl ColorBayes {
    /// Learns the model from counted pixels. Returns `None` when either class has no pixels.
    pub fn fit(histograms: &ColorHistograms, params: &ColorBayesParams) -> Option<Self> {
        let (fg, bg) = histograms.counts();
        if fg == 0 || bg == 0 {
            return None;
        }
        let s = params.parzen_sigma_bins;
        let dens = |h: &[Vec<u64>; 3]| {
            [
                smooth(&h[0], s, true),
                smooth(&h[1], s, false),
                smooth(&h[2], s, false),
            ]
        };
        Some(Self {
            foreground: dens(&histograms.foreground),
            background: dens(&histograms.background),
            prior_fruit: fg as f64 / (fg + bg) as f64,
        })
    }

    /// Posterior probability that a pixel of this colour is fruit (Eq. 2).
    pub fn posterior(&self, rgb: [u8; 3]) -> f64 {
        let hsv = rgb_to_hsv(rgb);
        let bins = self.foreground[0].len();
        let mut pf = self.prior_fruit;
        let mut pb = 1.0 - self.prior_fruit;
        for ((x, fg), bg) in hsv.iter().zip(&self.foreground).zip(&self.background) {
            let b = ((x * bins as f64) as usize).min(bins - 1);
            pf *= fg[b];
            pb *= bg[b];
        }
        if pf + pb > 0.0 {
            pf / (pf + pb)
        } else {
            0.0
        }
    }

    /// Evaluates the posterior at the centre of every quantised RGB cell.
    pub fn compile(&self, lut_bits: u32) -> ColorLut {
        let bits = lut_bits.clamp(1, 8);
        let levels = 1usize << bits;
        let step = 256 / levels;
        let centre = |q: usize| (q * step + step / 2).min(255) as u8;
        let mut posterior = Vec::with_capacity(levels * levels * levels);
        for r in 0..levels {
            for g in 0..levels {
                for b in 0..levels {
                    posterior.push(self.posterior([centre(r), centre(g), centre(b)]) as f32);
                }
            }
        }
        ColorLut { bits, posterior }
    }
}

/// The posterior tabulated over quantised RGB.
#[derive(Debug, Clone, PartialEq)]
pub struct ColorLut {
    bits: u32,
    posterior: Vec<f32>,
}

impl ColorLut {
    /// Posterior of a colour, by table lookup.
    #[inline]
    pub fn posterior(&self, rgb: [u8; 3]) -> f32 {
        let shift = 8 - self.bits;
        let [r, g, b] = rgb.map(|c| (c >> shift) as usize);
        self.posterior[(r << (2 * self.bits)) | (g << self.bits) | b]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trained() -> ColorBayes {
        let mut h = ColorHistograms::new(64);
        for i in 0..200u8 {
            h.add([200 + i % 50, 20 + i % 30, 10], true); // reds
            h.add([30, 120 + i % 100, 40 + i % 20], false); // greens
            h.add([90 + i % 20, 70, 50], false); // soil
        }
        ColorBayes::fit(&h, &ColorBayesParams::default()).unwrap()
    }

    #[test]
    fn separates_red_fruit_from_green_leaves() {
        let m = trained();
        assert!(m.posterior([220, 30, 12]) > 0.9);
        assert!(m.posterior([30, 160, 45]) < 0.1);
        assert!((m.prior_fruit - 1.0 / 3.0).abs() < 1e-12);
        for c in 0..3 {
            assert!((m.foreground[c].iter().sum::<f64>() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn lookup_table_agrees_with_direct_posterior() {
        let m = trained();
        let lut = m.compile(6);
        for rgb in [
            [220, 30, 12],
            [30, 160, 45],
            [100, 70, 50],
            [0, 0, 0],
            [255, 255, 255],
        ] {
            // The LUT evaluates cell centres: compare against the centre of rgb's cell.
            let centre = rgb.map(|c: u8| (c & !3) + 2);
            assert!((lut.posterior(rgb) as f64 - m.posterior(centre)).abs() < 1e-6);
        }
    }

    #[test]
    fn hue_smoothing_wraps_around() {
        let s = smooth(&[10, 0, 0, 0, 0, 0, 0, 0], 1.0, true);
        assert!((s[1] - s[7]).abs() < 1e-12 && s[7] > 1e-3);
        let s = smooth(&[10, 0, 0, 0, 0, 0, 0, 0], 1.0, false);
        assert!(s[7] < 1e-6);
    }

    #[test]
    fn one_class_only_cannot_be_fitted() {
        let mut h = ColorHistograms::new(8);
        h.add([1, 2, 3], true);
        assert!(ColorBayes::fit(&h, &ColorBayesParams::default()).is_none());
    }
}
