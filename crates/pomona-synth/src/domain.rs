//! Which family of worlds a [`crate::SceneSpec`] draws from.
//!
//! * `narrow` — the original crop row: fruit 0.4–0.9 m away, one ovate leaf shape, a textured
//!   backdrop plane, no shadows, level camera. Kept byte-identical per seed, so results measured
//!   on it stay reproducible.
//! * `wide` — domain-randomised worlds (ranges in the `wide_scene` module, e.g. [`crate::WIDE_DISTANCE_M`]):
//!   every factor a detector could overfit to (distance, camera tilt, canopy density, leaf shape,
//!   background, shadows, exposure, fruit shape and colour, depth-sensor artefacts) is drawn per
//!   frame from a wide range, so a model trained on it holds on other renderers and real frames.

use serde::{Deserialize, Serialize};

/// Scene family (`--domain`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Domain {
    /// The original, narrow crop-row statistics (library default).
    #[default]
    Narrow,
    /// Domain-randomised worlds (the CLI default).
    Wide,
}

impl Domain {
    /// Both domains, in CLI order.
    pub const ALL: [Domain; 2] = [Domain::Narrow, Domain::Wide];

    /// The name used on the command line and in the truth `synth` record.
    pub fn name(self) -> &'static str {
        match self {
            Domain::Narrow => "narrow",
            Domain::Wide => "wide",
        }
    }
}
