//! What lies behind the crop row in a wide-domain frame (`--backgrounds`).
//!
//! | background   | geometry                                                                   | depth |
//! |--------------|----------------------------------------------------------------------------|-------|
//! | `soil`       | brown soil with pebbles, a plane 0.3–1.2 m behind the fruit, tilted like ground seen from above | yes |
//! | `cloth`      | black woven ground cloth 0.15–0.6 m behind the fruit                        | none (dark in the infrared) |
//! | `second-row` | the next crop row: leaves 1.5–3 m from the camera, soil behind it           | yes, up to the sensor's range |
//! | `sky`        | open sky: bright, bluish, no surface                                        | none |
//! | `greenhouse` | white plastic film 1–2.5 m behind the fruit, posts and heating pipes        | yes |

use serde::{Deserialize, Serialize};

/// A background kind of the wide domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Background {
    /// Bare soil.
    Soil,
    /// Black ground cloth (no depth).
    Cloth,
    /// The next crop row, 1.5–3 m away.
    SecondRow,
    /// Open sky (no depth).
    Sky,
    /// Greenhouse structure: white plastic, posts, pipes.
    Greenhouse,
}

impl Background {
    /// All backgrounds, in CLI order.
    pub const ALL: [Background; 5] = [
        Background::Soil,
        Background::Cloth,
        Background::SecondRow,
        Background::Sky,
        Background::Greenhouse,
    ];

    /// The name used on the command line and in the truth `synth` record.
    pub fn name(self) -> &'static str {
        match self {
            Background::Soil => "soil",
            Background::Cloth => "cloth",
            Background::SecondRow => "second-row",
            Background::Sky => "sky",
            Background::Greenhouse => "greenhouse",
        }
    }

    /// The background named `name` (see [`Background::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|b| b.name() == name)
    }
}
