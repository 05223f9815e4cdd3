//! Illumination: one directional light (sun or lamp) plus ambient light, and the Blinn–Phong
//! shading model that turns a surface point into a colour.
//!
//! Five presets cover the illumination changes the detectors must survive: `day` (moderate sun),
//! `dim` (overcast dusk: weak, slightly blue light and more sensor noise), `harsh` (strong
//! low-ambient sun: deep shading, clipped highlights), `low-sun` (warm light grazing from one
//! side a few degrees above the horizon: long shading, one half of each fruit dark) and
//! `backlight` (the sun behind the canopy, facing the camera: the visible faces of the fruit get
//! only sky light). The narrow domain draws a direction per frame as below and casts no
//! shadows; the orchard domain turns each preset into a sun with cast shadows and an exposure
//! (ranges in `orchard_scene.rs`).

use nalgebra::{Unit, Vector3};
use serde::{Deserialize, Serialize};

use rand::Rng;

use crate::rng::{uniform, SynthRng};
use crate::Material;

/// Illumination preset (`--light`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LightPreset {
    /// Moderate daylight.
    Day,
    /// Weak, bluish light with stronger image noise.
    Dim,
    /// Strong directional light with little ambient fill.
    Harsh,
    /// Warm sun low on one side.
    LowSun,
    /// Sun behind the canopy, facing the camera.
    Backlight,
}

impl LightPreset {
    /// All presets, in CLI order.
    pub const ALL: [LightPreset; 5] = [
        LightPreset::Day,
        LightPreset::Dim,
        LightPreset::Harsh,
        LightPreset::LowSun,
        LightPreset::Backlight,
    ];

    /// The name used on the command line and in `synth.json`.
    pub fn name(self) -> &'static str {
        match self {
            LightPreset::Day => "day",
            LightPreset::Dim => "dim",
            LightPreset::Harsh => "harsh",
            LightPreset::LowSun => "low-sun",
            LightPreset::Backlight => "backlight",
        }
    }

    /// Draws a light for one frame (narrow domain): the direction varies per frame. `day`,
    /// `dim` and `harsh` light from the camera's side of the canopy and mostly from above
    /// (unchanged since before the other presets); `low-sun` from the left or right, at most
    /// about 17° above the horizon, from the camera's side; `backlight` from behind the canopy.
    pub fn sample(self, rng: &mut SynthRng) -> Light {
        // Towards the light, in the camera frame (y down, z forward).
        let towards = match self {
            // From behind the camera, left or right, usually above.
            LightPreset::Day | LightPreset::Dim | LightPreset::Harsh => Vector3::new(
                uniform(rng, -0.9, 0.9),
                uniform(rng, -1.0, 0.25),
                -uniform(rng, 0.7, 1.3),
            ),
            LightPreset::LowSun => {
                let side = if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
                Vector3::new(
                    side * uniform(rng, 0.7, 1.0),
                    -uniform(rng, 0.05, 0.3),
                    -uniform(rng, 0.1, 0.6),
                )
            }
            LightPreset::Backlight => Vector3::new(
                uniform(rng, -0.5, 0.5),
                -uniform(rng, 0.2, 0.8),
                uniform(rng, 0.5, 1.0),
            ),
        };
        let (intensity, ambient, color, image_noise_sigma) = match self {
            LightPreset::Day => (0.85, 0.32, [1.0, 1.0, 0.97], 1.5),
            LightPreset::Dim => (0.35, 0.12, [0.85, 0.9, 1.0], 3.5),
            LightPreset::Harsh => (1.45, 0.07, [1.0, 0.98, 0.92], 1.5),
            LightPreset::LowSun => (1.1, 0.15, [1.0, 0.82, 0.6], 2.0),
            LightPreset::Backlight => (1.3, 0.22, [1.0, 0.97, 0.9], 2.0),
        };
        Light {
            towards_light: Unit::new_normalize(towards),
            intensity,
            ambient,
            color,
            image_noise_sigma,
        }
    }
}

/// The light of one frame, in the scene (world) frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Unit vector from a surface point towards the light.
    pub towards_light: Unit<Vector3<f64>>,
    /// Strength of the directional light.
    pub intensity: f64,
    /// Strength of the uniform ambient light.
    pub ambient: f64,
    /// Colour of both lights (linear RGB multipliers).
    pub color: [f64; 3],
    /// Standard deviation of the additive Gaussian image noise, in 8-bit grey levels.
    pub image_noise_sigma: f64,
}

impl Light {
    /// Blinn–Phong shading of a surface point: `normal` and `towards_viewer` are unit vectors in
    /// the scene frame, `normal` facing the viewer. Returns linear RGB (may exceed 1 where the
    /// highlight clips).
    pub fn shade(
        &self,
        material: &Material,
        normal: &Vector3<f64>,
        towards_viewer: &Vector3<f64>,
    ) -> [f64; 3] {
        let l = self.towards_light.as_ref();
        let diffuse = normal.dot(l).max(0.0);
        let mut specular = 0.0;
        if diffuse > 0.0 && material.specular > 0.0 {
            let half = (l + towards_viewer).normalize();
            specular = material.specular * normal.dot(&half).max(0.0).powf(material.shininess);
        }
        let lit = self.ambient + self.intensity * diffuse;
        std::array::from_fn(|c| {
            self.color[c] * (material.albedo[c] * lit + self.intensity * specular)
        })
    }
}

impl Light {
    /// [`Light::shade`] with the directional light scaled by `sun` in `[0, 1]` (0 = the point
    /// is in a cast shadow and gets only the ambient sky light).
    pub fn shade_lit(
        &self,
        material: &Material,
        normal: &Vector3<f64>,
        towards_viewer: &Vector3<f64>,
        sun: f64,
    ) -> [f64; 3] {
        let l = self.towards_light.as_ref();
        let diffuse = normal.dot(l).max(0.0) * sun;
        let mut specular = 0.0;
        if diffuse > 0.0 && material.specular > 0.0 {
            let half = (l + towards_viewer).normalize();
            specular = material.specular * normal.dot(&half).max(0.0).powf(material.shininess);
        }
        let lit = self.ambient + self.intensity * diffuse;
        std::array::from_fn(|c| {
            self.color[c] * (material.albedo[c] * lit + self.intensity * specular)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::frame_rng;

    #[test]
    fn highlight_appears_where_normal_bisects_light_and_view() {
        let mut rng = frame_rng(3, 0);
        let light = LightPreset::Day.sample(&mut rng);
        let glossy = Material {
            albedo: [0.6, 0.05, 0.05],
            specular: 0.8,
            shininess: 80.0,
        };
        let view = Vector3::new(0.0, 0.0, -1.0);
        let half = (light.towards_light.as_ref() + view).normalize();
        let at_highlight = light.shade(&glossy, &half, &view);
        // Near-white: the green channel is lifted far above the albedo's share.
        assert!(at_highlight[1] > 0.5, "{at_highlight:?}");
        let away = light.shade(&glossy, &view, &view);
        assert!(away[1] < at_highlight[1]);
        assert!(light.towards_light.z < 0.0);
    }
}
