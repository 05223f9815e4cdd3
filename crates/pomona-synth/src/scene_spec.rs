//! What kind of scenes to draw, and the random sampler that draws them.
//!
//! A [`SceneSpec`] holds the user-facing knobs (`--domain`, `--fruit`, `--camera`, `--noise`,
//! `--light`, `--green-fraction`, and the wide domain's hold-out knobs `--leaf-families`,
//! `--distance-m`, `--backgrounds`) plus the scene layout ranges. In the wide domain
//! [`SceneSpec::sample`] hands over to the wide sampler (`wide_scene.rs`); in the narrow domain
//! (described here, unchanged since before the wide domain) it turns the spec and a seed
//! into a [`Scene`]: a crop row 0.4–0.9 m in front of the camera with 3–10 fruit hanging among
//! leaves that mostly face the camera, one to three stalks, and a textured background. Part of
//! the leaves are placed right in front of fruit so visibility spans about 0.1 to 1. Fruit do
//! not overlap one another, and leaves and stalks are re-drawn (a few times, then dropped) when
//! they would cut through a fruit.

use nalgebra::{Point3, Rotation3, Unit, Vector3};
use pomona_core::PinholeCamera;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::orchard_scene::sample_orchard;
use crate::rng::{frame_rng, uniform, SynthRng};
use crate::wide_scene::{sample_wide, WIDE_DISTANCE_LIMITS_M, WIDE_DISTANCE_M};
use crate::{
    Backdrop, BackdropKind, Background, CameraPreset, Domain, FruitBody, FruitChoice, FruitKind,
    Leaf, LeafFamily, LightPreset, Material, NoiseModel, Scene, Stem, SynthError,
};

/// Leaves per square metre of the canopy's cross-section in view.
const LEAF_DENSITY_PER_M2: f64 = 520.0;
/// Bounds on the number of background leaves per frame (keeps tiny and huge views sane).
const LEAF_COUNT_RANGE: (usize, usize) = (40, 1000);
/// Tries to place a leaf or stalk clear of the fruit before giving up on it.
const PLACEMENT_ATTEMPTS: usize = 6;
/// Depth of the fruit layer behind the canopy front, metres.
const FRUIT_LAYER_DEPTH_M: f64 = 0.15;

/// Parameters of the scenes to draw. Build with [`SceneSpec::default`] and set fields, then
/// [`SceneSpec::validate`] (sampling validates too).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneSpec {
    /// Which fruit kinds appear.
    pub fruit: FruitChoice,
    /// The camera scenes are composed for (fruit are placed inside its view).
    pub camera: PinholeCamera,
    /// Depth noise model.
    pub noise: NoiseModel,
    /// Illumination preset (narrow and orchard domains; the wide domain draws its own sun).
    pub light: LightPreset,
    /// Fraction of peppers coloured like the leaves, in `[0, 1]`.
    pub green_fraction: f64,
    /// Inclusive range of fruit per frame (narrow and wide; the orchard domain places
    /// [`crate::ORCHARD_FRUIT_COUNT`]).
    pub fruit_count: (u32, u32),
    /// Range of the distance from the camera to the front of the fruit layer, metres (narrow
    /// domain; the wide domain uses `wide_distance_m`).
    pub distance_m: (f64, f64),
    /// Which family of worlds to draw (`Narrow` by default; the CLI defaults to `Wide`).
    #[serde(default)]
    pub domain: Domain,
    /// Wide only: the leaf families frames draw from (`--leaf-families`; default all).
    #[serde(default = "all_leaf_families")]
    pub leaf_families: Vec<LeafFamily>,
    /// Wide only: the backgrounds frames draw from (`--backgrounds`; default all).
    #[serde(default = "all_backgrounds")]
    pub backgrounds: Vec<Background>,
    /// Wide only: band of camera-to-fruit-centre distances, metres (`--distance-m`; default
    /// [`WIDE_DISTANCE_M`]).
    #[serde(default = "wide_distance")]
    pub wide_distance_m: (f64, f64),
}

fn all_leaf_families() -> Vec<LeafFamily> {
    LeafFamily::ALL.to_vec()
}

fn all_backgrounds() -> Vec<Background> {
    Background::ALL.to_vec()
}

fn wide_distance() -> (f64, f64) {
    WIDE_DISTANCE_M
}

impl Default for SceneSpec {
    fn default() -> Self {
        Self {
            fruit: FruitChoice::Only(FruitKind::Pepper),
            camera: CameraPreset::KinectV2.camera(),
            noise: NoiseModel::None,
            light: LightPreset::Day,
            green_fraction: 0.0,
            fruit_count: (3, 10),
            distance_m: (0.4, 0.9),
            domain: Domain::Narrow,
            leaf_families: all_leaf_families(),
            backgrounds: all_backgrounds(),
            wide_distance_m: WIDE_DISTANCE_M,
        }
    }
}

impl SceneSpec {
    /// Checks every field.
    ///
    /// # Errors
    /// [`SynthError::InvalidParameter`] for a green fraction outside `[0, 1]`, an empty or
    /// too-large fruit-count range, a distance range not within 0.2–5 m, or an invalid camera.
    pub fn validate(&self) -> Result<(), SynthError> {
        let bad = |name, reason: String| Err(SynthError::InvalidParameter { name, reason });
        if !(0.0..=1.0).contains(&self.green_fraction) {
            return bad(
                "green-fraction",
                format!("must be in [0, 1], got {}", self.green_fraction),
            );
        }
        let (lo, hi) = self.fruit_count;
        if lo > hi || hi > 1000 {
            return bad(
                "fruit_count",
                format!("need min <= max <= 1000, got {lo}..={hi}"),
            );
        }
        let (dlo, dhi) = self.distance_m;
        if !(dlo.is_finite() && dhi.is_finite() && dlo >= 0.2 && dlo <= dhi && dhi <= 5.0) {
            return bad(
                "distance_m",
                format!("need 0.2 <= min <= max <= 5 m, got {dlo}..{dhi}"),
            );
        }
        if let Err(e) = self.camera.validate() {
            return bad("camera", e.to_string());
        }
        self.validate_wide_knobs()
    }

    /// Checks the wide-only hold-out knobs: non-empty, no repeats, a distance band within
    /// [`WIDE_DISTANCE_LIMITS_M`], and left at their defaults in the narrow domain.
    fn validate_wide_knobs(&self) -> Result<(), SynthError> {
        let bad = |name, reason: String| Err(SynthError::InvalidParameter { name, reason });
        if self.domain == Domain::Narrow {
            if self.leaf_families != all_leaf_families() {
                return bad(
                    "leaf-families",
                    "only applies to the wide domain".to_string(),
                );
            }
            if self.backgrounds != all_backgrounds() {
                return bad("backgrounds", "only applies to the wide domain".to_string());
            }
            if self.wide_distance_m != WIDE_DISTANCE_M {
                return bad("distance-m", "only applies to the wide domain".to_string());
            }
            return Ok(());
        }
        let names = |v: Vec<&str>| v.join(",");
        if self.leaf_families.is_empty() {
            return bad(
                "leaf-families",
                format!(
                    "need at least one of {}",
                    names(LeafFamily::ALL.iter().map(|f| f.name()).collect())
                ),
            );
        }
        if (1..self.leaf_families.len())
            .any(|i| self.leaf_families[..i].contains(&self.leaf_families[i]))
        {
            return bad("leaf-families", "a family is listed twice".to_string());
        }
        if self.backgrounds.is_empty() {
            return bad(
                "backgrounds",
                format!(
                    "need at least one of {}",
                    names(Background::ALL.iter().map(|b| b.name()).collect())
                ),
            );
        }
        if (1..self.backgrounds.len()).any(|i| self.backgrounds[..i].contains(&self.backgrounds[i]))
        {
            return bad("backgrounds", "a background is listed twice".to_string());
        }
        let (lo, hi) = self.wide_distance_m;
        let (min, max) = WIDE_DISTANCE_LIMITS_M;
        if !(lo.is_finite() && hi.is_finite() && lo >= min && lo <= hi && hi <= max) {
            return bad(
                "distance-m",
                format!("need {min} <= MIN <= MAX <= {max} m, got {lo},{hi}"),
            );
        }
        Ok(())
    }

    /// Draws one scene from `seed` (equivalent to frame 0 of a dataset with that seed).
    ///
    /// # Errors
    /// As [`SceneSpec::validate`].
    pub fn sample(&self, seed: u64) -> Result<Scene, SynthError> {
        self.sample_frame(seed, 0)
    }

    /// Draws the scene of frame `index` of a dataset with seed `dataset_seed`; independent of
    /// every other frame.
    ///
    /// # Errors
    /// As [`SceneSpec::validate`].
    pub fn sample_frame(&self, dataset_seed: u64, index: u64) -> Result<Scene, SynthError> {
        self.validate()?;
        Ok(self.sample_with(&mut frame_rng(dataset_seed, index)))
    }

    /// Draws a scene from an explicit generator (the spec must be valid).
    pub fn sample_with(&self, rng: &mut SynthRng) -> Scene {
        match self.domain {
            Domain::Narrow => self.sample_narrow(rng),
            Domain::Wide => sample_wide(self, rng),
            Domain::Orchard => sample_orchard(self, rng),
        }
    }

    /// The narrow crop row (see the module docs); unchanged since before the wide domain.
    fn sample_narrow(&self, rng: &mut SynthRng) -> Scene {
        let kind = self.fruit.pick(rng);
        let front = uniform(rng, self.distance_m.0, self.distance_m.1);
        let light = self.light.sample(rng);
        let mut stems = Vec::new();
        let fruits = self.sample_fruits(rng, kind, front, &mut stems);
        let mut leaves = self.sample_canopy_leaves(rng, front, &fruits);
        for f in &fruits {
            sample_occluding_leaves(rng, f, &fruits, &mut leaves);
        }
        for _ in 0..rng.gen_range(1..=3) {
            if let Some(stalk) = self.sample_stalk(rng, front, &fruits) {
                stems.push(stalk);
            }
        }
        let tilt = Vector3::new(uniform(rng, -0.25, 0.25), uniform(rng, -0.25, 0.25), -1.0);
        let backdrop = Backdrop {
            point: Point3::new(0.0, 0.0, front + uniform(rng, 0.45, 0.9)),
            normal: Unit::new_normalize(tilt),
            texture_seed: rng.gen(),
            kind: BackdropKind::Foliage,
        };
        Scene {
            fruits,
            leaves,
            stems,
            backdrop,
            light,
            noise: self.noise,
            noise_seed: rng.gen(),
            shadows: false,
            image_effects: None,
            max_depth_m: f64::INFINITY,
            truth_extra: serde_json::Map::new(),
        }
    }

    /// A point of the view: pixel `(u, v)` (may lie outside the image) back-projected to `z`.
    fn point_at(&self, u: f64, v: f64, z: f64) -> Point3<f64> {
        self.camera.back_project(u, v, z)
    }

    /// A uniformly random pixel position, with the image grown by `margin` (fraction) per side.
    fn random_pixel(&self, rng: &mut SynthRng, margin: f64) -> (f64, f64) {
        let (w, h) = (self.camera.width as f64, self.camera.height as f64);
        (
            uniform(rng, -margin * w, (1.0 + margin) * w),
            uniform(rng, -margin * h, (1.0 + margin) * h),
        )
    }

    fn sample_fruits(
        &self,
        rng: &mut SynthRng,
        kind: FruitKind,
        front: f64,
        stems: &mut Vec<Stem>,
    ) -> Vec<FruitBody> {
        let count = rng.gen_range(self.fruit_count.0..=self.fruit_count.1);
        let mut fruits: Vec<FruitBody> = Vec::new();
        for _ in 0..count {
            for _attempt in 0..40 {
                let shape = kind.sample_shape(rng);
                let (u, v) = self.random_pixel(rng, -0.08);
                let depth = front + uniform(rng, 0.0, FRUIT_LAYER_DEPTH_M) + shape.radius_m;
                let center = self.point_at(u, v, depth);
                let orientation = hanging_orientation(rng, kind.max_tilt_rad());
                let green = kind == FruitKind::Pepper && rng.gen_bool(self.green_fraction);
                let material = kind.sample_material(rng, green);
                let body = FruitBody::new(kind, center, orientation, shape, material);
                let clear = fruits.iter().all(|o| {
                    (o.center - body.center).norm()
                        > 0.85 * (o.bounding_radius_m() + body.bounding_radius_m())
                });
                if !clear {
                    continue;
                }
                if let Some(p) = kind.peduncle() {
                    let axis = body.axis().into_inner();
                    let h = shape.half_length_m;
                    stems.push(Stem {
                        start: body.center + axis * (0.8 * h),
                        end: body.center + axis * (h + uniform(rng, p.length_m.0, p.length_m.1)),
                        radius_m: uniform(rng, p.radius_m.0, p.radius_m.1),
                        material: p.material,
                    });
                }
                fruits.push(body);
                break;
            }
        }
        fruits
    }

    fn sample_canopy_leaves(
        &self,
        rng: &mut SynthRng,
        front: f64,
        fruits: &[FruitBody],
    ) -> Vec<Leaf> {
        let mid = front + 0.1;
        let area = (self.camera.width as f64 * mid / self.camera.fx)
            * (self.camera.height as f64 * mid / self.camera.fy);
        let count = ((LEAF_DENSITY_PER_M2 * area).round() as usize)
            .clamp(LEAF_COUNT_RANGE.0, LEAF_COUNT_RANGE.1);
        (0..count)
            .filter_map(|_| {
                (0..PLACEMENT_ATTEMPTS).find_map(|_| {
                    // A tenth of the canopy hangs in front of the fruit layer, the rest behind.
                    let z = if rng.gen_bool(0.1) {
                        front - uniform(rng, 0.0, 0.08)
                    } else {
                        front + uniform(rng, 0.0, 0.35)
                    };
                    let (u, v) = self.random_pixel(rng, 0.1);
                    let mut leaf = sample_leaf(rng, self.point_at(u, v, z), (0.04, 0.12));
                    // Deeper leaves get less light inside the canopy: darken them (no shadows).
                    let shade = 1.0 - 0.55 * ((z - front) / 0.35).clamp(0.0, 1.0);
                    leaf.material = leaf.material.tinted([shade; 3]);
                    (!cuts_fruit(&leaf, fruits)).then_some(leaf)
                })
            })
            .collect()
    }

    fn sample_stalk(&self, rng: &mut SynthRng, front: f64, fruits: &[FruitBody]) -> Option<Stem> {
        (0..PLACEMENT_ATTEMPTS).find_map(|_| {
            let stalk = self.random_stalk(rng, front);
            let clear = fruits.iter().all(|f| {
                segment_distance(&f.center, &stalk.start, &stalk.end)
                    > f.bounding_radius_m() + stalk.radius_m + 0.005
            });
            clear.then_some(stalk)
        })
    }

    fn random_stalk(&self, rng: &mut SynthRng, front: f64) -> Stem {
        let z = front + uniform(rng, 0.03, 0.25);
        let u = uniform(rng, 0.0, self.camera.width as f64);
        let h = self.camera.height as f64;
        let lean = uniform(rng, -0.1, 0.1);
        let top = self.point_at(u, -0.3 * h, z);
        let bottom = self.point_at(u, 1.3 * h, z);
        Stem {
            start: Point3::new(top.x + lean, top.y, top.z),
            end: bottom,
            radius_m: uniform(rng, 0.005, 0.011),
            material: Material {
                albedo: [
                    uniform(rng, 0.06, 0.10),
                    uniform(rng, 0.13, 0.20),
                    uniform(rng, 0.02, 0.04),
                ],
                specular: 0.08,
                shininess: 12.0,
            },
        }
    }
}

/// Orientation of a hanging fruit: the symmetry axis (body z, towards the stem) points up
/// (scene −y) tilted by up to `max_tilt` in a random direction, with a random spin about it.
fn hanging_orientation(rng: &mut SynthRng, max_tilt: f64) -> Rotation3<f64> {
    let tilt = uniform(rng, 0.0, max_tilt);
    let azimuth = uniform(rng, 0.0, std::f64::consts::TAU);
    let axis = Vector3::new(
        tilt.sin() * azimuth.cos(),
        -tilt.cos(),
        tilt.sin() * azimuth.sin(),
    );
    let spin =
        Rotation3::from_axis_angle(&Vector3::z_axis(), uniform(rng, 0.0, std::f64::consts::TAU));
    let align = Rotation3::rotation_between(&Vector3::z(), &axis)
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
    align * spin
}

/// A leaf at `center` with a length drawn from `length_m`, mostly facing the camera.
fn sample_leaf(rng: &mut SynthRng, center: Point3<f64>, length_m: (f64, f64)) -> Leaf {
    let half_length = 0.5 * uniform(rng, length_m.0, length_m.1);
    // Leaf normal (+z) towards the camera, spun in its plane, then tilted by up to 55°.
    let face = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
    let spin =
        Rotation3::from_axis_angle(&Vector3::z_axis(), uniform(rng, 0.0, std::f64::consts::TAU));
    let tilt_dir = uniform(rng, 0.0, std::f64::consts::TAU);
    let tilt_axis = Unit::new_normalize(Vector3::new(tilt_dir.cos(), tilt_dir.sin(), 0.0));
    let tilt = Rotation3::from_axis_angle(&tilt_axis, uniform(rng, 0.0, 55f64.to_radians()));
    let yellowed = rng.gen_bool(0.08);
    let albedo = if yellowed {
        [
            uniform(rng, 0.14, 0.22),
            uniform(rng, 0.20, 0.28),
            uniform(rng, 0.02, 0.05),
        ]
    } else {
        [
            uniform(rng, 0.03, 0.09),
            uniform(rng, 0.10, 0.24),
            uniform(rng, 0.012, 0.04),
        ]
    };
    Leaf {
        center,
        orientation: tilt * face * spin,
        half_length_m: half_length,
        half_width_m: half_length * uniform(rng, 0.35, 0.55),
        bend_along: uniform(rng, -5.0, 5.0),
        bend_across: uniform(rng, -10.0, 10.0),
        material: Material {
            albedo,
            specular: uniform(rng, 0.02, 0.06),
            shininess: uniform(rng, 8.0, 20.0),
        },
        family: LeafFamily::Elliptic,
    }
}

/// With probability 0.6, one or two large leaves just in front of `fruit`, offset sideways so
/// they hide part of it.
fn sample_occluding_leaves(
    rng: &mut SynthRng,
    fruit: &FruitBody,
    fruits: &[FruitBody],
    leaves: &mut Vec<Leaf>,
) {
    if !rng.gen_bool(0.6) {
        return;
    }
    let r = fruit.bounding_radius_m();
    for _ in 0..rng.gen_range(1..=2) {
        let placed = (0..PLACEMENT_ATTEMPTS).find_map(|_| {
            let angle = uniform(rng, 0.0, std::f64::consts::TAU);
            let offset = uniform(rng, 0.2, 1.3) * r;
            let center = Point3::new(
                fruit.center.x + offset * angle.cos(),
                fruit.center.y + offset * angle.sin(),
                fruit.center.z - r - uniform(rng, 0.01, 0.06),
            );
            let leaf = sample_leaf(rng, center, (0.06, 0.12));
            (!cuts_fruit(&leaf, fruits)).then_some(leaf)
        });
        leaves.extend(placed);
    }
}

/// Whether any probe point of the blade lies inside (or within 3 mm of) a fruit body: leaves
/// and fruit must not interpenetrate.
pub(crate) fn cuts_fruit(leaf: &Leaf, fruits: &[FruitBody]) -> bool {
    let reach = leaf.bounding_radius_m();
    let probes = leaf.probe_points();
    fruits.iter().any(|f| {
        (f.center - leaf.center).norm() < f.bounding_radius_m() + reach
            && probes.iter().any(|p| {
                (f.center - p).norm() < f.bounding_radius_m() + 0.003 && f.implicit_at(p) < 0.003
            })
    })
}

/// Distance from `p` to the segment `a`–`b`.
pub(crate) fn segment_distance(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_specs_are_rejected() {
        let mut s = SceneSpec::default();
        s.validate().unwrap();
        s.green_fraction = 1.5;
        assert!(s.validate().is_err());
        let s = SceneSpec {
            fruit_count: (5, 2),
            ..SceneSpec::default()
        };
        assert!(s.validate().is_err());
        let s = SceneSpec {
            distance_m: (0.1, 0.5),
            ..SceneSpec::default()
        };
        assert!(s.sample(0).is_err());
    }

    #[test]
    fn sampled_scene_respects_the_layout() {
        let spec = SceneSpec::default();
        for seed in 0..20 {
            let scene = spec.sample(seed).unwrap();
            assert!(
                (3..=10).contains(&scene.fruits.len()),
                "{}",
                scene.fruits.len()
            );
            assert!(scene.leaves.len() >= LEAF_COUNT_RANGE.0);
            for f in &scene.fruits {
                assert!(f.center.z > 0.4 && f.center.z < 1.2);
                for leaf in &scene.leaves {
                    assert!(!cuts_fruit(leaf, std::slice::from_ref(f)));
                }
                // Tilt from straight up (−y) is at most 30° for peppers.
                assert!(-f.axis().y >= 30f64.to_radians().cos() - 1e-9);
            }
        }
        assert_eq!(spec.sample(3).unwrap(), spec.sample(3).unwrap());
        assert_ne!(spec.sample(3).unwrap(), spec.sample(4).unwrap());
    }

    #[test]
    fn green_fraction_one_makes_every_pepper_leaf_green() {
        let spec = SceneSpec {
            green_fraction: 1.0,
            ..SceneSpec::default()
        };
        let scene = spec.sample(1).unwrap();
        for f in &scene.fruits {
            assert!(f.material.albedo[1] > f.material.albedo[0]);
        }
    }
}
