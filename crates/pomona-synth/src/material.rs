//! Surface appearance for Blinn–Phong shading: a diffuse colour plus a white specular lobe.
//!
//! Glossy fruit get a strong, tight lobe so they show the small near-white highlights that the
//! highlight-pruning stage of the shape detector looks for; leaves and stems get a weak, broad one.

use serde::{Deserialize, Serialize};

/// How a surface reflects light.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Diffuse reflectance (albedo) per channel, linear, in `[0, 1]`.
    pub albedo: [f64; 3],
    /// Weight of the white specular lobe, `>= 0`.
    pub specular: f64,
    /// Blinn–Phong exponent: larger means a smaller, sharper highlight.
    pub shininess: f64,
}

impl Material {
    /// Luminance of the albedo (Rec. 709 weights), used for dark-surface depth dropouts.
    pub fn luminance(&self) -> f64 {
        0.2126 * self.albedo[0] + 0.7152 * self.albedo[1] + 0.0722 * self.albedo[2]
    }

    /// The same material with its albedo scaled per channel (clamped to `[0, 1]`).
    pub fn tinted(&self, factor: [f64; 3]) -> Self {
        let mut m = *self;
        for (a, f) in m.albedo.iter_mut().zip(factor) {
            *a = (*a * f).clamp(0.0, 1.0);
        }
        m
    }
}
