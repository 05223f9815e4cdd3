//! A sampled scene: everything the renderer needs, in one "scene" frame.
//!
//! The scene frame is the camera frame of the primary view (OpenCV: x right, y down, z forward,
//! metres), so truth of the primary view needs no transformation. Other views (stereo) render the
//! same scene through a rigid `camera_from_scene` transform. A scene can be built by hand (tests
//! do) or drawn at random by [`crate::SceneSpec::sample`].

use crate::{Backdrop, FruitBody, ImageEffects, Leaf, Light, NoiseModel, Stem};

/// Geometry, appearance and sensor model of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Fruit bodies; truth and mask ids follow this order (hidden fruit are skipped).
    pub fruits: Vec<FruitBody>,
    /// Leaf blades.
    pub leaves: Vec<Leaf>,
    /// Main stalks and fruit peduncles.
    pub stems: Vec<Stem>,
    /// The background plane.
    pub backdrop: Backdrop,
    /// The light.
    pub light: Light,
    /// Depth noise model.
    pub noise: NoiseModel,
    /// Seed of the per-view image and depth noise.
    pub noise_seed: u64,
    /// Cast shadows from the light (wide domain); `false` shades without them.
    pub shadows: bool,
    /// Exposure, white balance and vignetting (wide domain); `None` leaves colour untouched.
    pub image_effects: Option<ImageEffects>,
    /// Farthest depth the sensor reports, metres; farther surfaces read as "no depth"
    /// (`f64::INFINITY`: no limit).
    pub max_depth_m: f64,
    /// Frame-level truth `extra` written with every rendered view (the wide domain records its
    /// drawn values under `"synth"`; empty in the narrow domain).
    pub truth_extra: serde_json::Map<String, serde_json::Value>,
}
