//! The fruit catalogue: which kinds exist and, per kind, realistic ranges of size, shape, pose,
//! colour and gloss. All numbers of "what a pepper looks like" live here and nowhere else.
//!
//! | kind      | size                                  | shape                                   |
//! |-----------|---------------------------------------|-----------------------------------------|
//! | pepper    | 70–105 mm wide, 80–120 mm long        | 3–4 lobes, blocky, tapering, tilt ≤ 30° |
//! | eggplant  | 50–90 mm wide, 140–240 mm long        | elongated, narrow at the stem, hanging  |
//! | guava     | 50–90 mm                              | near-sphere, slightly oblate            |
//! | apple     | 65–95 mm                              | near-sphere, oblate, faint 5 lobes      |
//! | orange    | 50–110 mm                             | sphere                                  |

use serde::{Deserialize, Serialize};

use crate::rng::{uniform, SynthRng};
use crate::{FruitShape, Material};
use rand::Rng;

/// A kind of fruit the generator can draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FruitKind {
    /// Sweet (bell) pepper.
    Pepper,
    /// Eggplant (aubergine).
    Eggplant,
    /// Guava.
    Guava,
    /// Apple.
    Apple,
    /// Orange.
    Orange,
}

/// Which kinds a scene may contain (`--fruit`); written as its name (`"pepper"`, `"mixed"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(into = "String", try_from = "String")]
pub enum FruitChoice {
    /// Every fruit is of this kind.
    Only(FruitKind),
    /// Each frame draws one kind uniformly (a crop row grows one crop).
    Mixed,
}

/// A short stem (peduncle) attached at the stem end of a fruit: length and radius ranges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeduncleRange {
    /// Length range, metres.
    pub length_m: (f64, f64),
    /// Radius range, metres.
    pub radius_m: (f64, f64),
    /// Surface of the stem.
    pub material: Material,
}

impl FruitKind {
    /// All kinds, in CLI order.
    pub const ALL: [FruitKind; 5] = [
        FruitKind::Pepper,
        FruitKind::Eggplant,
        FruitKind::Guava,
        FruitKind::Apple,
        FruitKind::Orange,
    ];

    /// The name written to `truth/*.json` (`kind`) and used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            FruitKind::Pepper => "pepper",
            FruitKind::Eggplant => "eggplant",
            FruitKind::Guava => "guava",
            FruitKind::Apple => "apple",
            FruitKind::Orange => "orange",
        }
    }

    /// Largest tilt of the symmetry axis away from straight up, radians.
    pub fn max_tilt_rad(self) -> f64 {
        match self {
            FruitKind::Pepper => 30f64.to_radians(),
            FruitKind::Eggplant => 15f64.to_radians(),
            FruitKind::Guava | FruitKind::Apple | FruitKind::Orange => 35f64.to_radians(),
        }
    }

    /// Draws a body shape with realistic dimensions for this kind: the largest width is drawn
    /// from the table's range exactly (the shape is rescaled to it).
    pub fn sample_shape(self, rng: &mut SynthRng) -> FruitShape {
        let (lo, hi) = self.width_range_m();
        let width = uniform(rng, lo, hi);
        let shape = self.sample_proportions(rng, width);
        shape.with_width(width)
    }

    /// Range of the largest width (truth `diameter_m`), metres.
    pub fn width_range_m(self) -> (f64, f64) {
        match self {
            FruitKind::Pepper => (0.070, 0.105),
            FruitKind::Eggplant => (0.050, 0.090),
            FruitKind::Guava => (0.050, 0.090),
            FruitKind::Apple => (0.065, 0.095),
            FruitKind::Orange => (0.050, 0.110),
        }
    }

    /// Shape proportions for a fruit about `width` wide (before exact rescaling).
    fn sample_proportions(self, rng: &mut SynthRng, width: f64) -> FruitShape {
        match self {
            FruitKind::Pepper => {
                let lobe_depth = uniform(rng, 0.06, 0.12);
                FruitShape {
                    radius_m: 0.5 * width / (1.0 + lobe_depth),
                    half_length_m: 0.5 * uniform(rng, 0.080, 0.120),
                    profile_exponent: if rng.gen_bool(0.5) { 3.0 } else { 4.0 },
                    taper: uniform(rng, 0.05, 0.2),
                    lobes: if rng.gen_bool(0.5) { 3 } else { 4 },
                    lobe_depth,
                }
            }
            FruitKind::Eggplant => FruitShape {
                radius_m: 0.5 * width,
                half_length_m: 0.5 * uniform(rng, 0.140, 0.240),
                profile_exponent: 2.0,
                taper: uniform(rng, -0.45, -0.25),
                lobes: 0,
                lobe_depth: 0.0,
            },
            FruitKind::Guava => {
                let r = 0.5 * width;
                FruitShape {
                    radius_m: r,
                    half_length_m: r * uniform(rng, 0.88, 0.98),
                    profile_exponent: 2.0,
                    taper: uniform(rng, -0.12, 0.0),
                    lobes: 0,
                    lobe_depth: 0.0,
                }
            }
            FruitKind::Apple => {
                let r = 0.5 * width;
                FruitShape {
                    radius_m: r,
                    half_length_m: r * uniform(rng, 0.85, 0.95),
                    profile_exponent: 2.0,
                    taper: uniform(rng, 0.0, 0.1),
                    lobes: 5,
                    lobe_depth: uniform(rng, 0.0, 0.025),
                }
            }
            FruitKind::Orange => {
                let r = 0.5 * width;
                FruitShape {
                    half_length_m: r * uniform(rng, 0.96, 1.0),
                    ..FruitShape::sphere(r)
                }
            }
        }
    }

    /// Draws a surface. `green` asks for a leaf-coloured fruit (green peppers; only peppers have
    /// a green variety here, other kinds ignore it).
    pub fn sample_material(self, rng: &mut SynthRng, green: bool) -> Material {
        let (albedo, specular, shininess) = match self {
            FruitKind::Pepper if green => ([0.06, 0.20, 0.03], 0.75, 90.0),
            FruitKind::Pepper => {
                let colours = [[0.50, 0.02, 0.015], [0.72, 0.42, 0.01], [0.75, 0.17, 0.01]];
                (colours[rng.gen_range(0..colours.len())], 0.75, 90.0)
            }
            FruitKind::Eggplant => ([0.05, 0.012, 0.04], 0.8, 110.0),
            FruitKind::Guava => ([0.30, 0.45, 0.06], 0.25, 25.0),
            FruitKind::Apple => {
                if rng.gen_bool(0.7) {
                    ([0.42, 0.025, 0.02], 0.4, 45.0)
                } else {
                    ([0.35, 0.40, 0.04], 0.4, 45.0)
                }
            }
            FruitKind::Orange => ([0.80, 0.22, 0.01], 0.3, 30.0),
        };
        let base = Material {
            albedo,
            specular: specular * uniform(rng, 0.8, 1.2),
            shininess: shininess * uniform(rng, 0.8, 1.25),
        };
        let g = uniform(rng, 0.85, 1.1);
        base.tinted([
            g * uniform(rng, 0.93, 1.07),
            g * uniform(rng, 0.93, 1.07),
            g * uniform(rng, 0.93, 1.07),
        ])
    }

    /// The peduncle this kind carries, if any.
    pub fn peduncle(self) -> Option<PeduncleRange> {
        let green_stem = Material {
            albedo: [0.07, 0.18, 0.03],
            specular: 0.15,
            shininess: 20.0,
        };
        match self {
            FruitKind::Pepper => Some(PeduncleRange {
                length_m: (0.015, 0.035),
                radius_m: (0.0035, 0.006),
                material: green_stem,
            }),
            FruitKind::Eggplant => Some(PeduncleRange {
                length_m: (0.02, 0.05),
                radius_m: (0.005, 0.008),
                material: Material {
                    albedo: [0.09, 0.14, 0.03],
                    ..green_stem
                },
            }),
            FruitKind::Apple => Some(PeduncleRange {
                length_m: (0.012, 0.025),
                radius_m: (0.0012, 0.002),
                material: Material {
                    albedo: [0.12, 0.07, 0.025],
                    specular: 0.05,
                    shininess: 10.0,
                },
            }),
            FruitKind::Guava | FruitKind::Orange => None,
        }
    }
}

impl From<FruitChoice> for String {
    fn from(choice: FruitChoice) -> Self {
        choice.name().to_string()
    }
}

impl TryFrom<String> for FruitChoice {
    type Error = String;

    fn try_from(name: String) -> Result<Self, String> {
        FruitChoice::from_name(&name).ok_or_else(|| format!("unknown fruit `{name}`"))
    }
}

impl FruitChoice {
    /// The name used on the command line: a kind's name or `mixed`.
    pub fn name(self) -> &'static str {
        match self {
            FruitChoice::Only(kind) => kind.name(),
            FruitChoice::Mixed => "mixed",
        }
    }

    /// The choice named `name` (see [`FruitChoice::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        if name == "mixed" {
            return Some(FruitChoice::Mixed);
        }
        FruitKind::ALL
            .into_iter()
            .find(|k| k.name() == name)
            .map(FruitChoice::Only)
    }

    /// The kind used for one frame.
    pub fn pick(self, rng: &mut SynthRng) -> FruitKind {
        match self {
            FruitChoice::Only(kind) => kind,
            FruitChoice::Mixed => FruitKind::ALL[rng.gen_range(0..FruitKind::ALL.len())],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::frame_rng;

    #[test]
    fn choices_round_trip_through_their_names() {
        for c in FruitKind::ALL
            .into_iter()
            .map(FruitChoice::Only)
            .chain([FruitChoice::Mixed])
        {
            let json = serde_json::to_string(&c).unwrap();
            assert_eq!(json, format!("\"{}\"", c.name()));
            assert_eq!(serde_json::from_str::<FruitChoice>(&json).unwrap(), c);
        }
        assert!(serde_json::from_str::<FruitChoice>("\"banana\"").is_err());
    }

    #[test]
    fn sampled_sizes_stay_in_the_documented_ranges() {
        let mut rng = frame_rng(11, 0);
        for _ in 0..200 {
            for kind in FruitKind::ALL {
                let shape = kind.sample_shape(&mut rng);
                let (_, d) = shape.extents();
                let (lo, hi) = kind.width_range_m();
                assert!(d >= lo - 1e-9 && d <= hi + 1e-9, "{kind:?} diameter {d}");
                if kind == FruitKind::Eggplant {
                    assert!(shape.half_length_m > 0.069 && shape.half_length_m < 0.121);
                }
            }
        }
    }
}
