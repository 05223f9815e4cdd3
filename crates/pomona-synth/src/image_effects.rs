//! Camera-side colour effects of the wide domain, applied to linear radiance before the gamma
//! curve: exposure (a global gain), white balance (per-channel gains: a camera that balances for
//! the wrong illuminant), and vignetting (corners darker than the centre). Sensor noise is the
//! light's `image_noise_sigma`, drawn per frame in the wide domain.

/// Per-frame camera colour effects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageEffects {
    /// Global gain on linear radiance (1 = the light's nominal exposure).
    pub exposure: f64,
    /// Per-channel gains (linear RGB).
    pub white_balance: [f64; 3],
    /// Fraction of brightness lost in the image corners (0 = none); falls off as r².
    pub vignetting: f64,
}

impl ImageEffects {
    /// Applies the effects in place to a row-major `width`-wide buffer of linear RGB.
    pub fn apply(&self, rgb_linear: &mut [[f64; 3]], width: usize, height: usize) {
        let (cx, cy) = (0.5 * (width as f64 - 1.0), 0.5 * (height as f64 - 1.0));
        let r2_max = (cx * cx + cy * cy).max(1.0);
        for (i, px) in rgb_linear.iter_mut().enumerate() {
            let (u, v) = ((i % width) as f64 - cx, (i / width) as f64 - cy);
            let gain = self.exposure * (1.0 - self.vignetting * (u * u + v * v) / r2_max);
            for (c, value) in px.iter_mut().enumerate() {
                *value *= gain * self.white_balance[c];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_are_darker_than_the_centre() {
        let fx = ImageEffects {
            exposure: 2.0,
            white_balance: [1.0, 0.5, 1.0],
            vignetting: 0.4,
        };
        let mut img = vec![[0.25; 3]; 9];
        fx.apply(&mut img, 3, 3);
        assert_eq!(img[4], [0.5, 0.25, 0.5]);
        assert!((img[0][0] - 0.3).abs() < 1e-12);
    }
}
