//! Which family of worlds a [`crate::SceneSpec`] draws from.
//!
//! * `narrow` — the original crop row: fruit 0.4–0.9 m away, one ovate leaf shape, a textured
//!   backdrop plane, no shadows, level camera. Kept byte-identical per seed, so results measured
//!   on it stay reproducible.
//! * `wide` — domain-randomised worlds (ranges in the `wide_scene` module, e.g. [`crate::WIDE_DISTANCE_M`]):
//!   every factor a detector could overfit to (distance, camera tilt, canopy density, leaf shape,
//!   background, shadows, exposure, fruit shape and colour, depth-sensor artefacts) is drawn per
//!   frame from a wide range, so a model trained on it holds on other renderers and real frames.
//! * `orchard` — citrus-orchard scenes for the colour-contour method of seed 004 (ranges in the
//!   `orchard_scene` module, e.g. [`crate::ORCHARD_FRUIT_COUNT`]): the wide domain's canopy,
//!   backgrounds and shadows, but 5–20 fruit per frame with many touching clusters, fruit
//!   colours from orange to yellow-green, a milder camera tilt, and the sun, sky light and
//!   exposure of one [`crate::LightPreset`] (`day`, `dim`, `harsh`, `low-sun`, `backlight`).

use serde::{Deserialize, Serialize};

use crate::Background;

/// Scene family (`--domain`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Domain {
    /// The original, narrow crop-row statistics (library default).
    #[default]
    Narrow,
    /// Domain-randomised worlds (the CLI default).
    Wide,
    /// Citrus orchard under a chosen light preset.
    Orchard,
}

impl Domain {
    /// Every domain, in CLI order.
    pub const ALL: [Domain; 3] = [Domain::Narrow, Domain::Wide, Domain::Orchard];

    /// The name used on the command line and in the truth `synth` record.
    pub fn name(self) -> &'static str {
        match self {
            Domain::Narrow => "narrow",
            Domain::Wide => "wide",
            Domain::Orchard => "orchard",
        }
    }

    /// The backgrounds a frame of this domain draws from unless told otherwise: all of
    /// [`Background::ALL`], except in the orchard (soil, a second row, sky: no greenhouse or
    /// ground cloth between citrus rows).
    pub fn default_backgrounds(self) -> Vec<Background> {
        match self {
            Domain::Narrow | Domain::Wide => Background::ALL.to_vec(),
            Domain::Orchard => vec![Background::Soil, Background::SecondRow, Background::Sky],
        }
    }
}
