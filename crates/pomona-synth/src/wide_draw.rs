//! The record of what a wide- or orchard-domain frame drew ([`WideDraw`]), written to the frame's truth
//! `extra` under `"synth"` (documented in `docs/formats.md`), so results can be sliced by
//! factor and hold-out experiments can check what their data contained.

use serde::{Deserialize, Serialize};

use crate::{Background, LeafFamily, LightPreset, NoiseModel};

/// The values drawn for one wide frame, written to truth `extra.synth`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WideDraw {
    /// `"wide"` or `"orchard"`.
    pub domain: String,
    /// Leaf outline family of every leaf in the frame.
    pub leaf_family: LeafFamily,
    /// Typical blade length, metres.
    pub leaf_length_m: f64,
    /// Background.
    pub background: Background,
    /// Row distance: fruit centres lie within ±0.12 m of it (clamped to the band), metres.
    pub distance_m: f64,
    /// The band fruit-centre distances were restricted to, metres.
    pub distance_band_m: (f64, f64),
    /// Camera pitch, degrees (positive: looking down).
    pub pitch_deg: f64,
    /// Camera roll, degrees.
    pub roll_deg: f64,
    /// Canopy density, blade area per cross-section area.
    pub canopy_density: f64,
    /// Fraction of canopy leaves in front of the fruit layer.
    pub front_leaf_fraction: f64,
    /// Leaves in the scene (canopy, occluders and second row).
    pub leaves: usize,
    /// Fruit placed (visible or not).
    pub fruits: usize,
    /// Clusters of touching fruit.
    pub fruit_clusters: usize,
    /// The sun.
    pub sun: SunDraw,
    /// Sky (ambient) light strength.
    pub sky_light: f64,
    /// Exposure gain.
    pub exposure: f64,
    /// White-balance gains (linear RGB).
    pub white_balance: [f64; 3],
    /// Vignetting strength.
    pub vignetting: f64,
    /// Image noise σ, grey levels.
    pub image_noise_sigma: f64,
    /// Depth noise model.
    pub noise: NoiseModel,
    /// The leaf families this dataset draws from.
    pub leaf_families: Vec<LeafFamily>,
    /// The backgrounds this dataset draws from.
    pub backgrounds: Vec<Background>,
    /// Orchard only: the light preset (absent in the wide domain, which draws its own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light: Option<LightPreset>,
}

/// The sun of a wide frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SunDraw {
    /// Azimuth about the up direction, degrees; 0 = behind the camera, ±180 = facing it.
    pub azimuth_deg: f64,
    /// Elevation above the horizon, degrees.
    pub elevation_deg: f64,
    /// Directional strength.
    pub intensity: f64,
}
