//! The wide (domain-randomised) scene sampler.
//!
//! Detectors trained on the narrow crop row (one leaf shape, 0.4–0.9 m, a textured plane behind,
//! no shadows, level camera) fail on frames from other renderers and real cameras: they learn
//! the generator instead of the fruit. The wide domain draws every nuisance factor per frame
//! from a range much wider than any one field condition, so that what stays constant across
//! frames is only the fruit itself. All ranges are the `WIDE_*` constants below.
//!
//! Composition (all in the camera frame, so truth needs no transform):
//! * camera pitch and roll are drawn and applied to *gravity*: fruit hang, stalks run and the
//!   sun and ground sit relative to the tilted "up" `R·(0, −1, 0)`, which is what a tilted
//!   camera sees; fruit are still placed inside the view;
//! * a row distance `D` is drawn from the distance band (default [`WIDE_DISTANCE_M`]); each
//!   fruit centre lies `D ± WIDE_FRUIT_LAYER_HALF_DEPTH_M` from the camera (Euclidean, clamped
//!   to the band), some in touching clusters of 2–4;
//! * the canopy is drawn with a density (blade area per unit cross-section) and a split into
//!   leaves in front of and behind the fruit layer, all of one [`LeafFamily`] per frame, with
//!   bent/curled blades, petioles, stalks and branches of varied thickness;
//! * one [`Background`] is drawn; the sun comes from any direction (cast shadows, see
//!   `shadow.rs`) with a sky light; exposure, white balance, vignetting and sensor noise vary;
//! * depth noise is the spec's (the CLI picks it from the camera, see
//!   [`crate::NoiseModel::for_camera`]), and surfaces beyond [`WIDE_MAX_DEPTH_M`] read as none.
//!
//! The drawn values are recorded as a [`WideDraw`] in the frame's truth `extra` under
//! `"synth"`.

use nalgebra::{Point3, Rotation3, Unit, Vector3};
use rand::Rng;

use crate::orchard_scene::orchard_light;
use crate::rng::{uniform, SynthRng};
use crate::scene_spec::{cuts_fruit, segment_distance};
use crate::{
    Backdrop, BackdropKind, Background, Blush, FruitBody, FruitKind, FruitShape, ImageEffects,
    Leaf, LeafFamily, Light, LightPreset, Material, Scene, SceneSpec, Stem, SunDraw, WideDraw,
};

/// Default band of camera-to-fruit-centre distances, metres (`--distance-m`).
pub const WIDE_DISTANCE_M: (f64, f64) = (0.3, 1.6);
/// Allowed limits of a `--distance-m` band, metres.
pub const WIDE_DISTANCE_LIMITS_M: (f64, f64) = (0.25, 3.0);
/// Fruit centres lie within this distance of the frame's row distance, metres.
pub const WIDE_FRUIT_LAYER_HALF_DEPTH_M: f64 = 0.12;
/// Largest camera pitch (about the camera x axis) either way, degrees.
pub const WIDE_PITCH_MAX_DEG: f64 = 20.0;
/// Largest camera roll (about the optical axis) either way, degrees.
pub const WIDE_ROLL_MAX_DEG: f64 = 20.0;
/// Canopy density: total blade area per square metre of the view's cross-section at the row
/// (m²/m²; 0.15 = sparse, 1.5 = dense and layered).
pub const WIDE_CANOPY_DENSITY: (f64, f64) = (0.15, 1.5);
/// Fraction of the canopy's leaves in front of the fruit layer (the rest is behind it).
pub const WIDE_FRONT_LEAF_FRACTION: (f64, f64) = (0.03, 0.35);
/// Depth of the canopy in front of the fruit layer, metres.
pub const WIDE_FRONT_DEPTH_M: (f64, f64) = (0.05, 0.3);
/// Depth of the canopy behind the fruit layer, metres.
pub const WIDE_BEHIND_DEPTH_M: (f64, f64) = (0.1, 0.6);
/// Nearest a leaf may come to the camera, metres.
pub const WIDE_MIN_LEAF_Z_M: f64 = 0.12;
/// Bounds on the number of canopy leaves per frame.
pub const WIDE_LEAF_COUNT: (usize, usize) = (10, 1500);
/// Leaf (blade) length, metres: the frame draws a typical length in this range, each leaf
/// varies ±30 % about it (clamped to the range).
pub const WIDE_LEAF_LENGTH_M: (f64, f64) = (0.03, 0.15);
/// Blade bend along its length: tip sag relative to the half length, either way.
pub const WIDE_LEAF_BEND_ALONG: f64 = 0.6;
/// Blade cupping/curl across: margin sag relative to the half width, either way.
pub const WIDE_LEAF_CURL_ACROSS: f64 = 0.9;
/// Largest tilt of a blade's normal away from the camera direction, degrees.
pub const WIDE_LEAF_TILT_MAX_DEG: f64 = 70.0;
/// Probability that a leaf shows a petiole.
pub const WIDE_PETIOLE_PROBABILITY: f64 = 0.6;
/// Petiole length relative to the blade length.
pub const WIDE_PETIOLE_LENGTH: (f64, f64) = (0.2, 0.6);
/// Main stalks per frame.
pub const WIDE_STALKS: (u32, u32) = (1, 4);
/// Main stalk radius, metres.
pub const WIDE_STALK_RADIUS_M: (f64, f64) = (0.003, 0.02);
/// Side branches per frame.
pub const WIDE_BRANCHES: (u32, u32) = (0, 6);
/// Side branch radius, metres.
pub const WIDE_BRANCH_RADIUS_M: (f64, f64) = (0.002, 0.008);
/// Side branch length, metres.
pub const WIDE_BRANCH_LENGTH_M: (f64, f64) = (0.1, 0.5);
/// Second-row leaves' distance from the camera, metres.
pub const WIDE_SECOND_ROW_M: (f64, f64) = (1.5, 3.0);
/// Farthest depth the sensor reports in the wide domain, metres (Kinect v2's range).
pub const WIDE_MAX_DEPTH_M: f64 = 4.5;
/// Sun elevation above the (tilted) horizon, degrees; the azimuth is uniform over the circle.
pub const WIDE_SUN_ELEVATION_DEG: (f64, f64) = (10.0, 85.0);
/// Sun (directional light) strength.
pub const WIDE_SUN_INTENSITY: (f64, f64) = (0.4, 1.6);
/// Sky (ambient) light strength.
pub const WIDE_SKY_LIGHT: (f64, f64) = (0.06, 0.45);
/// Exposure gain on linear radiance, drawn log-uniformly.
pub const WIDE_EXPOSURE: (f64, f64) = (0.6, 1.6);
/// White-balance gain per channel.
pub const WIDE_WHITE_BALANCE: (f64, f64) = (0.85, 1.15);
/// Vignetting: brightness lost in the corners.
pub const WIDE_VIGNETTING: (f64, f64) = (0.0, 0.45);
/// Additive image noise, 8-bit grey levels (σ).
pub const WIDE_IMAGE_NOISE_SIGMA: (f64, f64) = (0.8, 6.0);
/// Largest tilt of a fruit's axis away from the (tilted) up direction, degrees.
pub const WIDE_FRUIT_TILT_MAX_DEG: f64 = 45.0;
/// Fruit length (along the axis) scale, drawn per fruit.
pub const WIDE_FRUIT_ASPECT: (f64, f64) = (0.8, 1.25);
/// Probability that a placed fruit starts a cluster.
pub const WIDE_CLUSTER_PROBABILITY: f64 = 0.3;
/// Fruit per cluster.
pub const WIDE_CLUSTER_SIZE: (u32, u32) = (2, 4);
/// Fruit colour classes: probabilities of ripe (the kind's colours), unripe green, blushed and
/// yellow, in that order.
pub const WIDE_COLOUR_MIX: [f64; 4] = [0.45, 0.2, 0.2, 0.15];
/// Gloss: the kind's specular weight is scaled by this factor, drawn log-uniformly.
pub const WIDE_GLOSS_SCALE: (f64, f64) = (0.3, 2.5);

/// What distinguishes one family of worlds drawn by this sampler from another (the wide
/// domain, the orchard domain): everything else (canopy, backgrounds, stalks, shadows) is
/// shared.
pub(crate) struct WorldProfile {
    /// The domain's name, recorded in [`WideDraw::domain`].
    pub(crate) domain: &'static str,
    /// Inclusive range of fruit per frame.
    pub(crate) fruit_count: (u32, u32),
    /// Largest camera pitch and roll either way, degrees.
    pub(crate) pitch_roll_max_deg: (f64, f64),
    /// Probability that a placed fruit starts a cluster.
    pub(crate) cluster_probability: f64,
    /// Fruit per cluster.
    pub(crate) cluster_size: (u32, u32),
    /// Draws a fruit's surface (and blush) for a kind.
    pub(crate) colour: fn(&mut SynthRng, FruitKind) -> (Material, Option<Blush>),
    /// `None`: the wide domain's random sun, sky, exposure, white balance and vignetting;
    /// otherwise a preset's (`orchard_scene.rs`).
    pub(crate) lighting: Option<LightPreset>,
}

/// The drawn illumination and camera response of one frame.
pub(crate) struct FrameLight {
    pub(crate) light: Light,
    pub(crate) sun: SunDraw,
    pub(crate) exposure: f64,
    pub(crate) white_balance: [f64; 3],
    pub(crate) vignetting: f64,
}

/// Draws one wide-domain scene (`spec` must be valid).
pub(crate) fn sample_wide(spec: &SceneSpec, rng: &mut SynthRng) -> Scene {
    let profile = WorldProfile {
        domain: "wide",
        fruit_count: spec.fruit_count,
        pitch_roll_max_deg: (WIDE_PITCH_MAX_DEG, WIDE_ROLL_MAX_DEG),
        cluster_probability: WIDE_CLUSTER_PROBABILITY,
        cluster_size: WIDE_CLUSTER_SIZE,
        colour: wide_colour,
        lighting: None,
    };
    sample_world(spec, &profile, rng)
}

/// Draws one scene of `profile`'s family (`spec` must be valid).
pub(crate) fn sample_world(spec: &SceneSpec, profile: &WorldProfile, rng: &mut SynthRng) -> Scene {
    let kind = spec.fruit.pick(rng);
    let family = spec.leaf_families[rng.gen_range(0..spec.leaf_families.len())];
    let background = spec.backgrounds[rng.gen_range(0..spec.backgrounds.len())];
    let (pitch_max, roll_max) = profile.pitch_roll_max_deg;
    let pitch_deg = uniform(rng, -pitch_max, pitch_max);
    let roll_deg = uniform(rng, -roll_max, roll_max);
    // Looking down by `pitch` makes the world's up lean towards the camera's −z.
    let camera_from_level = Rotation3::from_axis_angle(&Vector3::z_axis(), roll_deg.to_radians())
        * Rotation3::from_axis_angle(&Vector3::x_axis(), -pitch_deg.to_radians());
    let band = spec.wide_distance_m;
    let row = uniform(rng, band.0, band.1);
    let leaf_length = uniform(rng, WIDE_LEAF_LENGTH_M.0, WIDE_LEAF_LENGTH_M.1);
    let w = WideSampler {
        spec,
        profile,
        up: Unit::new_normalize(camera_from_level * -Vector3::y()),
        row,
        band,
        family,
        leaf_length,
    };

    let mut stems = Vec::new();
    let (fruits, clusters) = w.sample_fruits(rng, kind, &mut stems);
    let canopy_density = uniform(rng, WIDE_CANOPY_DENSITY.0, WIDE_CANOPY_DENSITY.1);
    let front_fraction = uniform(rng, WIDE_FRONT_LEAF_FRACTION.0, WIDE_FRONT_LEAF_FRACTION.1);
    let (mut leaves, canopy_back) =
        w.sample_vegetation(rng, &fruits, canopy_density, front_fraction, &mut stems);
    let backdrop = w.sample_background(
        rng,
        background,
        canopy_back,
        &fruits,
        &mut leaves,
        &mut stems,
    );
    w.add_petioles(rng, &leaves, &fruits, &mut stems);

    let FrameLight {
        light,
        sun,
        exposure,
        white_balance,
        vignetting,
    } = w.sample_frame_light(rng, &camera_from_level);
    let draw = WideDraw {
        domain: profile.domain.to_string(),
        leaf_family: family,
        leaf_length_m: leaf_length,
        background,
        distance_m: row,
        distance_band_m: band,
        pitch_deg,
        roll_deg,
        canopy_density,
        front_leaf_fraction: front_fraction,
        leaves: leaves.len(),
        fruits: fruits.len(),
        fruit_clusters: clusters,
        sun,
        sky_light: light.ambient,
        exposure,
        white_balance,
        vignetting,
        image_noise_sigma: light.image_noise_sigma,
        noise: spec.noise,
        leaf_families: spec.leaf_families.clone(),
        backgrounds: spec.backgrounds.clone(),
        light: profile.lighting,
    };
    let mut truth_extra = serde_json::Map::new();
    if let Ok(value) = serde_json::to_value(&draw) {
        truth_extra.insert("synth".to_string(), value);
    }
    Scene {
        fruits,
        leaves,
        stems,
        backdrop,
        light,
        noise: spec.noise,
        noise_seed: rng.gen(),
        shadows: true,
        image_effects: Some(ImageEffects {
            exposure,
            white_balance,
            vignetting,
        }),
        max_depth_m: WIDE_MAX_DEPTH_M,
        truth_extra,
    }
}

/// Per-frame state of the wide sampler.
struct WideSampler<'a> {
    spec: &'a SceneSpec,
    profile: &'a WorldProfile,
    /// The world's up direction in the camera frame (tilted by pitch and roll).
    up: Unit<Vector3<f64>>,
    /// Row distance, metres.
    row: f64,
    /// Band of fruit-centre distances, metres.
    band: (f64, f64),
    family: LeafFamily,
    /// Typical blade length, metres.
    leaf_length: f64,
}

impl WideSampler<'_> {
    /// The frame's light: the profile's preset, or (wide worlds) a random sun and sky, exposure,
    /// white balance and vignetting.
    fn sample_frame_light(
        &self,
        rng: &mut SynthRng,
        camera_from_level: &Rotation3<f64>,
    ) -> FrameLight {
        if let Some(preset) = self.profile.lighting {
            return orchard_light(preset, rng, camera_from_level);
        }
        let (light, sun) = self.sample_light(rng, camera_from_level);
        let exposure = uniform(rng, WIDE_EXPOSURE.0.ln(), WIDE_EXPOSURE.1.ln()).exp();
        let white_balance: [f64; 3] =
            std::array::from_fn(|_| uniform(rng, WIDE_WHITE_BALANCE.0, WIDE_WHITE_BALANCE.1));
        let vignetting = uniform(rng, WIDE_VIGNETTING.0, WIDE_VIGNETTING.1);
        FrameLight {
            light,
            sun,
            exposure,
            white_balance,
            vignetting,
        }
    }

    fn point_at(&self, u: f64, v: f64, z: f64) -> Point3<f64> {
        self.spec.camera.back_project(u, v, z)
    }

    fn random_pixel(&self, rng: &mut SynthRng, margin: f64) -> (f64, f64) {
        let (w, h) = (
            self.spec.camera.width as f64,
            self.spec.camera.height as f64,
        );
        (
            uniform(rng, -margin * w, (1.0 + margin) * w),
            uniform(rng, -margin * h, (1.0 + margin) * h),
        )
    }

    /// Two unit vectors perpendicular to `up` and to each other.
    fn horizontal_basis(&self) -> (Vector3<f64>, Vector3<f64>) {
        let up = self.up.into_inner();
        let e1 = up.cross(&Vector3::z()).normalize();
        let e2 = up.cross(&e1);
        (e1, e2)
    }

    /// Fruit (with peduncles pushed to `stems`) and the number of clusters.
    fn sample_fruits(
        &self,
        rng: &mut SynthRng,
        kind: FruitKind,
        stems: &mut Vec<Stem>,
    ) -> (Vec<FruitBody>, usize) {
        let (lo, hi) = self.profile.fruit_count;
        let count = rng.gen_range(lo..=hi) as usize;
        let mut fruits: Vec<FruitBody> = Vec::new();
        let mut cluster_of: Vec<usize> = Vec::new();
        let mut clusters = 0;
        let mut attempts = 0;
        while fruits.len() < count && attempts < 40 * count.max(1) {
            attempts += 1;
            let (u, v) = self.random_pixel(rng, -0.05);
            let ray = self.point_at(u, v, 1.0).coords.normalize();
            let d = (self.row
                + uniform(
                    rng,
                    -WIDE_FRUIT_LAYER_HALF_DEPTH_M,
                    WIDE_FRUIT_LAYER_HALF_DEPTH_M,
                ))
            .clamp(self.band.0, self.band.1);
            let body = self.sample_body(rng, kind, Point3::from(ray * d), WIDE_FRUIT_TILT_MAX_DEG);
            if !fits(&body, &fruits, &cluster_of, usize::MAX) {
                continue;
            }
            fruits.push(body);
            cluster_of.push(fruits.len() - 1);
            if fruits.len() < count && rng.gen_bool(self.profile.cluster_probability) {
                let id = fruits.len() - 1;
                let (lo, hi) = self.profile.cluster_size;
                let size = rng.gen_range(lo..=hi) as usize;
                let mut members = 1;
                for _ in 0..4 * size {
                    if members >= size || fruits.len() >= count {
                        break;
                    }
                    if self.grow_cluster(rng, kind, id, &mut fruits, &mut cluster_of) {
                        members += 1;
                    }
                }
                if members > 1 {
                    clusters += 1;
                }
            }
        }
        for f in &fruits {
            if let Some(p) = kind.peduncle() {
                let axis = f.axis().into_inner();
                let h = f.shape.half_length_m;
                stems.push(Stem {
                    start: f.center + axis * (0.8 * h),
                    end: f.center + axis * (h + uniform(rng, p.length_m.0, p.length_m.1)),
                    radius_m: uniform(rng, p.radius_m.0, p.radius_m.1),
                    material: p.material,
                });
            }
        }
        (fruits, clusters)
    }

    /// Adds one fruit touching a random member of cluster `id`; whether it fitted.
    fn grow_cluster(
        &self,
        rng: &mut SynthRng,
        kind: FruitKind,
        id: usize,
        fruits: &mut Vec<FruitBody>,
        cluster_of: &mut Vec<usize>,
    ) -> bool {
        let members: Vec<usize> = (0..fruits.len()).filter(|&k| cluster_of[k] == id).collect();
        let anchor = &fruits[members[rng.gen_range(0..members.len())]];
        let (e1, e2) = self.horizontal_basis();
        let angle = uniform(rng, 0.0, std::f64::consts::TAU);
        let drop = uniform(rng, -0.5, 0.5);
        let dir = (e1 * angle.cos() + e2 * angle.sin() - self.up.into_inner() * drop).normalize();
        let shape = wide_shape(rng, kind);
        let gap = anchor.shape.extents().0 + shape.extents().0;
        let center = anchor.center + dir * gap;
        let dist = center.coords.norm();
        if dist < self.band.0 || dist > self.band.1 {
            return false;
        }
        let body = self.body_with(rng, kind, shape, center, 15.0);
        if !fits(&body, fruits, cluster_of, id) {
            return false;
        }
        fruits.push(body);
        cluster_of.push(id);
        true
    }

    /// A fruit of `kind` at `center` with the wide shape, pose and colour variation.
    fn sample_body(
        &self,
        rng: &mut SynthRng,
        kind: FruitKind,
        center: Point3<f64>,
        max_tilt_deg: f64,
    ) -> FruitBody {
        let shape = wide_shape(rng, kind);
        self.body_with(rng, kind, shape, center, max_tilt_deg)
    }

    /// A fruit of `kind` and `shape` at `center` with the wide pose and colour variation.
    fn body_with(
        &self,
        rng: &mut SynthRng,
        kind: FruitKind,
        shape: FruitShape,
        center: Point3<f64>,
        max_tilt_deg: f64,
    ) -> FruitBody {
        let orientation = self.hanging(rng, max_tilt_deg.to_radians());
        let (material, blush) = (self.profile.colour)(rng, kind);
        FruitBody::new(kind, center, orientation, shape, material).with_blush(blush)
    }

    /// A hanging orientation: body z (towards the stem) tilted from `up` by up to `max_tilt`.
    fn hanging(&self, rng: &mut SynthRng, max_tilt: f64) -> Rotation3<f64> {
        let (e1, e2) = self.horizontal_basis();
        let tilt = uniform(rng, 0.0, max_tilt);
        let azimuth = uniform(rng, 0.0, std::f64::consts::TAU);
        let axis = self.up.into_inner() * tilt.cos()
            + (e1 * azimuth.cos() + e2 * azimuth.sin()) * tilt.sin();
        let spin = Rotation3::from_axis_angle(
            &Vector3::z_axis(),
            uniform(rng, 0.0, std::f64::consts::TAU),
        );
        let align = Rotation3::rotation_between(&Vector3::z(), &axis).unwrap_or_else(|| {
            Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
        });
        align * spin
    }

    /// A leaf of the frame's family at `center`, length near `length`.
    fn leaf(&self, rng: &mut SynthRng, center: Point3<f64>, length: f64) -> Leaf {
        let length =
            (length * uniform(rng, 0.7, 1.3)).clamp(WIDE_LEAF_LENGTH_M.0, WIDE_LEAF_LENGTH_M.1);
        let a = 0.5 * length;
        let (rlo, rhi) = self.family.width_ratio_range();
        let b = a * uniform(rng, rlo, rhi);
        let face = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
        let spin = Rotation3::from_axis_angle(
            &Vector3::z_axis(),
            uniform(rng, 0.0, std::f64::consts::TAU),
        );
        let tilt_dir = uniform(rng, 0.0, std::f64::consts::TAU);
        let tilt_axis = Unit::new_normalize(Vector3::new(tilt_dir.cos(), tilt_dir.sin(), 0.0));
        let tilt = Rotation3::from_axis_angle(
            &tilt_axis,
            uniform(rng, 0.0, WIDE_LEAF_TILT_MAX_DEG.to_radians()),
        );
        let tone = rng.gen::<f64>();
        let albedo = if tone < 0.08 {
            // Yellowing.
            [
                uniform(rng, 0.14, 0.30),
                uniform(rng, 0.18, 0.32),
                uniform(rng, 0.02, 0.06),
            ]
        } else if tone < 0.2 {
            // Pale or young.
            [
                uniform(rng, 0.08, 0.16),
                uniform(rng, 0.22, 0.38),
                uniform(rng, 0.03, 0.08),
            ]
        } else if tone < 0.3 {
            // Dark, bluish or purple-tinged.
            [
                uniform(rng, 0.02, 0.06),
                uniform(rng, 0.05, 0.12),
                uniform(rng, 0.03, 0.07),
            ]
        } else {
            [
                uniform(rng, 0.03, 0.10),
                uniform(rng, 0.09, 0.26),
                uniform(rng, 0.012, 0.05),
            ]
        };
        Leaf {
            center,
            orientation: tilt * face * spin,
            half_length_m: a,
            half_width_m: b,
            bend_along: uniform(rng, -WIDE_LEAF_BEND_ALONG, WIDE_LEAF_BEND_ALONG) / a,
            bend_across: uniform(rng, -WIDE_LEAF_CURL_ACROSS, WIDE_LEAF_CURL_ACROSS) / b,
            material: Material {
                albedo,
                specular: uniform(rng, 0.02, 0.2),
                shininess: uniform(rng, 6.0, 40.0),
            },
            family: self.family,
        }
    }

    /// Canopy leaves: `depths` = (front of the canopy, front of the fruit layer, back of the
    /// canopy), camera z in metres.
    fn sample_canopy(
        &self,
        rng: &mut SynthRng,
        fruits: &[FruitBody],
        density: f64,
        front_fraction: f64,
        depths: (f64, f64, f64),
    ) -> Vec<Leaf> {
        let (front, layer_front, back) = depths;
        let cam = &self.spec.camera;
        let mid = 0.5 * (layer_front + back);
        let area =
            (1.2 * cam.width as f64 * mid / cam.fx) * (1.2 * cam.height as f64 * mid / cam.fy);
        let a = 0.5 * self.leaf_length;
        let (rlo, rhi) = self.family.width_ratio_range();
        let blade_area = 0.6 * (2.0 * a) * (2.0 * a * 0.5 * (rlo + rhi));
        let count = ((density * area / blade_area).round() as usize)
            .clamp(WIDE_LEAF_COUNT.0, WIDE_LEAF_COUNT.1);
        let front = front.max(WIDE_MIN_LEAF_Z_M);
        (0..count)
            .filter_map(|_| {
                (0..6).find_map(|_| {
                    let z = if rng.gen_bool(front_fraction) && layer_front > front {
                        uniform(rng, front, layer_front)
                    } else {
                        uniform(rng, layer_front.max(front), back)
                    };
                    let (u, v) = self.random_pixel(rng, 0.1);
                    let mut leaf = self.leaf(rng, self.point_at(u, v, z), self.leaf_length);
                    // Less sky light reaches deep into the canopy.
                    let shade = 1.0
                        - 0.45
                            * ((z - layer_front) / (back - layer_front).max(0.05)).clamp(0.0, 1.0);
                    leaf.material = leaf.material.tinted([shade; 3]);
                    (!cuts_fruit(&leaf, fruits)).then_some(leaf)
                })
            })
            .collect()
    }

    /// With probability 0.6, one or two leaves just in front of `fruit`, partly hiding it.
    fn sample_occluding_leaves(
        &self,
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
            let placed = (0..6).find_map(|_| {
                let angle = uniform(rng, 0.0, std::f64::consts::TAU);
                let offset = uniform(rng, 0.2, 1.3) * r;
                let z = fruit.center.z - r - uniform(rng, 0.01, 0.06);
                if z < WIDE_MIN_LEAF_Z_M {
                    return None;
                }
                let center = Point3::new(
                    fruit.center.x + offset * angle.cos(),
                    fruit.center.y + offset * angle.sin(),
                    z,
                );
                let length = self.leaf_length.max(1.5 * r);
                let leaf = self.leaf(rng, center, length);
                (!cuts_fruit(&leaf, fruits)).then_some(leaf)
            });
            leaves.extend(placed);
        }
    }

    /// A main stalk along the tilted up direction, clear of the fruit.
    fn sample_stalk(&self, rng: &mut SynthRng, fruits: &[FruitBody], back: f64) -> Option<Stem> {
        (0..6).find_map(|_| {
            let z = uniform(rng, self.row, back.max(self.row + 0.05));
            let u = uniform(rng, 0.0, self.spec.camera.width as f64);
            let centre = self.point_at(u, 0.5 * self.spec.camera.height as f64, z);
            let (e1, _) = self.horizontal_basis();
            let dir = (self.up.into_inner() + e1 * uniform(rng, -0.15, 0.15)).normalize();
            let half = 2.0 * z;
            let stalk = Stem {
                start: centre - dir * half,
                end: centre + dir * half,
                radius_m: uniform(rng, WIDE_STALK_RADIUS_M.0, WIDE_STALK_RADIUS_M.1),
                material: stem_material(rng),
            };
            clear_of(&stalk, fruits).then_some(stalk)
        })
    }

    /// A side branch leaving a random stalk upwards and sideways.
    fn sample_branch(
        &self,
        rng: &mut SynthRng,
        fruits: &[FruitBody],
        stalks: &[Stem],
    ) -> Option<Stem> {
        if stalks.is_empty() {
            return None;
        }
        (0..6).find_map(|_| {
            let stalk = &stalks[rng.gen_range(0..stalks.len())];
            let start = stalk.start + (stalk.end - stalk.start) * uniform(rng, 0.25, 0.75);
            let (e1, e2) = self.horizontal_basis();
            let az = uniform(rng, 0.0, std::f64::consts::TAU);
            let side = e1 * az.cos() + e2 * az.sin();
            let angle = uniform(rng, 30f64, 75.0).to_radians();
            let dir = self.up.into_inner() * angle.cos() + side * angle.sin();
            let branch = Stem {
                start,
                end: start + dir * uniform(rng, WIDE_BRANCH_LENGTH_M.0, WIDE_BRANCH_LENGTH_M.1),
                radius_m: uniform(rng, WIDE_BRANCH_RADIUS_M.0, WIDE_BRANCH_RADIUS_M.1)
                    .min(stalk.radius_m),
                material: stem_material(rng),
            };
            (branch.start.z > WIDE_MIN_LEAF_Z_M
                && branch.end.z > WIDE_MIN_LEAF_Z_M
                && clear_of(&branch, fruits))
            .then_some(branch)
        })
    }

    /// Petioles from the base of some leaves, backwards along the blade axis.
    fn add_petioles(
        &self,
        rng: &mut SynthRng,
        leaves: &[Leaf],
        fruits: &[FruitBody],
        stems: &mut Vec<Stem>,
    ) {
        for leaf in leaves {
            if !rng.gen_bool(WIDE_PETIOLE_PROBABILITY) {
                continue;
            }
            let a = leaf.half_length_m;
            let length = 2.0 * a * uniform(rng, WIDE_PETIOLE_LENGTH.0, WIDE_PETIOLE_LENGTH.1);
            let inset = match leaf.family {
                LeafFamily::Lobed => 0.35 * a,
                _ => 0.98 * a,
            };
            let base_leaf = Vector3::new(-inset, 0.0, leaf.bend_along * inset * inset);
            let start = leaf.center + leaf.orientation * base_leaf;
            let dir = (leaf.orientation * -Vector3::x() - self.up.into_inner() * 0.3).normalize();
            let petiole = Stem {
                start,
                end: start + dir * length,
                radius_m: (0.012 * 2.0 * a).clamp(0.0008, 0.003),
                material: Material {
                    albedo: leaf.material.albedo.map(|c| (c * 1.2).min(1.0)),
                    specular: 0.05,
                    shininess: 10.0,
                },
            };
            if petiole.end.z > WIDE_MIN_LEAF_Z_M && clear_of(&petiole, fruits) {
                stems.push(petiole);
            }
        }
    }

    /// The canopy around the fruit layer (leaves in front of, among and behind the fruit, leaves
    /// hiding each fruit), stalks and branches; returns the leaves and the depth of the canopy's
    /// back, and adds stalks and branches to `stems`.
    fn sample_vegetation(
        &self,
        rng: &mut SynthRng,
        fruits: &[FruitBody],
        canopy_density: f64,
        front_fraction: f64,
        stems: &mut Vec<Stem>,
    ) -> (Vec<Leaf>, f64) {
        let row = self.row;
        let front_depth = uniform(rng, WIDE_FRONT_DEPTH_M.0, WIDE_FRONT_DEPTH_M.1);
        let behind_depth = uniform(rng, WIDE_BEHIND_DEPTH_M.0, WIDE_BEHIND_DEPTH_M.1);
        let layer_front = fruits
            .iter()
            .map(|f| f.center.z - f.bounding_radius_m())
            .fold(row - WIDE_FRUIT_LAYER_HALF_DEPTH_M, f64::min);
        let layer_back = fruits
            .iter()
            .map(|f| f.center.z + f.bounding_radius_m())
            .fold(row + WIDE_FRUIT_LAYER_HALF_DEPTH_M, f64::max);
        let canopy_back = layer_back + behind_depth;
        let mut leaves = self.sample_canopy(
            rng,
            fruits,
            canopy_density,
            front_fraction,
            (layer_front - front_depth, layer_front, canopy_back),
        );
        for f in fruits {
            self.sample_occluding_leaves(rng, f, fruits, &mut leaves);
        }
        let mut stalks = Vec::new();
        for _ in 0..rng.gen_range(WIDE_STALKS.0..=WIDE_STALKS.1) {
            stalks.extend(self.sample_stalk(rng, fruits, canopy_back));
        }
        stems.extend(stalks.iter().cloned());
        for _ in 0..rng.gen_range(WIDE_BRANCHES.0..=WIDE_BRANCHES.1) {
            if let Some(branch) = self.sample_branch(rng, fruits, &stalks) {
                stems.push(branch);
            }
        }
        (leaves, canopy_back)
    }

    /// The backdrop of `background`, adding second-row leaves or greenhouse structure.
    fn sample_background(
        &self,
        rng: &mut SynthRng,
        background: Background,
        canopy_back: f64,
        fruits: &[FruitBody],
        leaves: &mut Vec<Leaf>,
        stems: &mut Vec<Stem>,
    ) -> Backdrop {
        match background {
            Background::Soil => {
                let z = (self.row + uniform(rng, 0.3, 1.2)).max(canopy_back + 0.05);
                let n = self.backdrop_normal(rng, 0.6);
                backdrop_plane(z, n, BackdropKind::Soil, rng.gen())
            }
            Background::Cloth => {
                let z = (self.row + uniform(rng, 0.15, 0.6)).max(canopy_back + 0.03);
                let n = self.backdrop_normal(rng, 0.2);
                backdrop_plane(z, n, BackdropKind::Cloth, rng.gen())
            }
            Background::Sky => {
                let b = uniform(rng, 0.7, 1.4);
                let horizon = [0.72 * b, 0.80 * b, 0.90 * b];
                let zenith = [
                    uniform(rng, 0.25, 0.45) * b,
                    uniform(rng, 0.45, 0.6) * b,
                    uniform(rng, 0.8, 1.0) * b,
                ];
                backdrop_plane(
                    100.0,
                    Unit::new_normalize(-Vector3::z()),
                    BackdropKind::Sky {
                        horizon,
                        zenith,
                        up: self.up,
                    },
                    rng.gen(),
                )
            }
            Background::SecondRow => self.second_row(rng, canopy_back, fruits, leaves),
            Background::Greenhouse => self.greenhouse(rng, canopy_back, fruits, stems),
        }
    }

    /// A backdrop normal facing the camera, tilted up by up to `ground` (towards the ground
    /// plane) and a little sideways.
    fn backdrop_normal(&self, rng: &mut SynthRng, ground: f64) -> Unit<Vector3<f64>> {
        let (e1, _) = self.horizontal_basis();
        let n = -Vector3::z()
            + self.up.into_inner() * uniform(rng, 0.0, ground)
            + e1 * uniform(rng, -0.15, 0.15);
        Unit::new_normalize(n)
    }

    /// A far second row of hazy leaves in front of soil.
    fn second_row(
        &self,
        rng: &mut SynthRng,
        canopy_back: f64,
        fruits: &[FruitBody],
        leaves: &mut Vec<Leaf>,
    ) -> Backdrop {
        let near = WIDE_SECOND_ROW_M
            .0
            .max(canopy_back + 0.1)
            .min(WIDE_SECOND_ROW_M.1 - 0.2);
        let cam = &self.spec.camera;
        let mid = 0.5 * (near + WIDE_SECOND_ROW_M.1);
        let area = (cam.width as f64 * mid / cam.fx) * (cam.height as f64 * mid / cam.fy);
        let length = uniform(rng, 0.08, 0.15);
        let count =
            ((uniform(rng, 0.8, 2.0) * area / (0.3 * length * length)) as usize).clamp(50, 800);
        let haze = uniform(rng, 0.7, 1.0);
        for _ in 0..count {
            let z = uniform(rng, near, WIDE_SECOND_ROW_M.1);
            let (u, v) = self.random_pixel(rng, 0.05);
            let mut leaf = self.leaf(rng, self.point_at(u, v, z), length);
            leaf.material = leaf.material.tinted([haze, haze, haze * 1.1]);
            if !cuts_fruit(&leaf, fruits) {
                leaves.push(leaf);
            }
        }
        let z = uniform(rng, WIDE_SECOND_ROW_M.1 + 0.2, WIDE_MAX_DEPTH_M - 0.3);
        let n = self.backdrop_normal(rng, 0.5);
        backdrop_plane(z, n, BackdropKind::Soil, rng.gen())
    }

    /// Greenhouse plastic behind metal posts and pipes.
    fn greenhouse(
        &self,
        rng: &mut SynthRng,
        canopy_back: f64,
        fruits: &[FruitBody],
        stems: &mut Vec<Stem>,
    ) -> Backdrop {
        let z = (self.row + uniform(rng, 1.0, 2.5))
            .max(canopy_back + 0.3)
            .min(WIDE_MAX_DEPTH_M - 0.3);
        let n = self.backdrop_normal(rng, 0.1);
        let metal = |rng: &mut SynthRng| {
            let g = uniform(rng, 0.35, 0.75);
            Material {
                albedo: [g, g, 0.98 * g],
                specular: uniform(rng, 0.2, 0.6),
                shininess: uniform(rng, 20.0, 60.0),
            }
        };
        let (e1, _) = self.horizontal_basis();
        let up = self.up.into_inner();
        let (width, height) = (
            self.spec.camera.width as f64,
            self.spec.camera.height as f64,
        );
        for _ in 0..rng.gen_range(1..=3) {
            let zp = uniform(rng, canopy_back.min(z - 0.1), z - 0.05);
            let u = uniform(rng, 0.0, width);
            let c = self.point_at(u, 0.5 * height, zp);
            let post = Stem {
                start: c - up * 3.0,
                end: c + up * 3.0,
                radius_m: uniform(rng, 0.02, 0.05),
                material: metal(rng),
            };
            if clear_of(&post, fruits) {
                stems.push(post);
            }
        }
        for _ in 0..rng.gen_range(1..=2) {
            let zp = uniform(rng, canopy_back.min(z - 0.1), z - 0.05);
            let v = uniform(rng, 0.4, 1.1) * height;
            let c = self.point_at(0.5 * width, v, zp);
            let pipe = Stem {
                start: c - e1 * 4.0,
                end: c + e1 * 4.0,
                radius_m: uniform(rng, 0.02, 0.03),
                material: metal(rng),
            };
            if clear_of(&pipe, fruits) {
                stems.push(pipe);
            }
        }
        backdrop_plane(z, n, BackdropKind::Plastic, rng.gen())
    }

    /// The sun and sky light, and their record.
    fn sample_light(
        &self,
        rng: &mut SynthRng,
        camera_from_level: &Rotation3<f64>,
    ) -> (Light, SunDraw) {
        let elevation = uniform(rng, WIDE_SUN_ELEVATION_DEG.0, WIDE_SUN_ELEVATION_DEG.1);
        let azimuth = uniform(rng, -180.0, 180.0);
        let (el, az) = (elevation.to_radians(), azimuth.to_radians());
        let level = Vector3::new(el.cos() * az.sin(), -el.sin(), -el.cos() * az.cos());
        let intensity = uniform(rng, WIDE_SUN_INTENSITY.0, WIDE_SUN_INTENSITY.1);
        let warmth = uniform(rng, -1.0, 1.0);
        let light = Light {
            towards_light: Unit::new_normalize(camera_from_level * level),
            intensity,
            ambient: uniform(rng, WIDE_SKY_LIGHT.0, WIDE_SKY_LIGHT.1),
            color: [1.0 + 0.08 * warmth, 1.0, 1.0 - 0.1 * warmth],
            image_noise_sigma: uniform(rng, WIDE_IMAGE_NOISE_SIGMA.0, WIDE_IMAGE_NOISE_SIGMA.1),
        };
        let sun = SunDraw {
            azimuth_deg: azimuth,
            elevation_deg: elevation,
            intensity,
        };
        (light, sun)
    }
}

/// Whether `body` may join `fruits`: clear of every fruit outside cluster `cluster` by the
/// narrow domain's rule, and not interpenetrating members of that cluster (they may touch).
fn fits(body: &FruitBody, fruits: &[FruitBody], cluster_of: &[usize], cluster: usize) -> bool {
    fruits.iter().zip(cluster_of).all(|(o, &c)| {
        let dist = (o.center - body.center).norm();
        if c != cluster {
            return dist > 0.85 * (o.bounding_radius_m() + body.bounding_radius_m());
        }
        // Probe the segment between the centres: no point inside both bodies.
        (0..=16).all(|i| {
            let p = o.center + (body.center - o.center) * (i as f64 / 16.0);
            o.implicit_at(&p) > 0.0 || body.implicit_at(&p) > 0.0
        })
    })
}

/// Whether a stem keeps clear of every fruit.
fn clear_of(stem: &Stem, fruits: &[FruitBody]) -> bool {
    fruits.iter().all(|f| {
        segment_distance(&f.center, &stem.start, &stem.end)
            > f.bounding_radius_m() + stem.radius_m + 0.005
    })
}

/// Green to woody-brown stem surface.
fn stem_material(rng: &mut SynthRng) -> Material {
    let wood = rng.gen::<f64>();
    let green = [0.07, 0.17, 0.03];
    let brown = [0.16, 0.11, 0.06];
    let g = uniform(rng, 0.7, 1.3);
    Material {
        albedo: std::array::from_fn(|c| g * (green[c] * (1.0 - wood) + brown[c] * wood)),
        specular: uniform(rng, 0.03, 0.15),
        shininess: uniform(rng, 8.0, 25.0),
    }
}

/// The kind's shape with the wide variation: length scale (aspect), extra or deeper lobes,
/// rescaled to a width inside the kind's range.
fn wide_shape(rng: &mut SynthRng, kind: FruitKind) -> FruitShape {
    let mut shape = kind.sample_shape(rng);
    let (_, width) = shape.extents();
    shape.half_length_m *= uniform(rng, WIDE_FRUIT_ASPECT.0, WIDE_FRUIT_ASPECT.1);
    if shape.lobes == 0 {
        if rng.gen_bool(0.3) {
            shape.lobes = rng.gen_range(4..=6);
            shape.lobe_depth = uniform(rng, 0.01, 0.04);
        }
    } else {
        shape.lobe_depth *= uniform(rng, 0.5, 1.6);
    }
    shape.with_width(width)
}

/// A colour class per [`WIDE_COLOUR_MIX`] and a gloss per [`WIDE_GLOSS_SCALE`].
fn wide_colour(rng: &mut SynthRng, kind: FruitKind) -> (Material, Option<Blush>) {
    let ripe = kind.sample_material(rng, false);
    let pick = rng.gen::<f64>();
    let [p_ripe, p_green, p_blush, _] = WIDE_COLOUR_MIX;
    let unripe = [
        uniform(rng, 0.06, 0.2),
        uniform(rng, 0.18, 0.4),
        uniform(rng, 0.03, 0.08),
    ];
    let yellow = [
        uniform(rng, 0.55, 0.8),
        uniform(rng, 0.42, 0.62),
        uniform(rng, 0.02, 0.08),
    ];
    let mut blush = None;
    let albedo = if pick < p_ripe {
        ripe.albedo
    } else if pick < p_ripe + p_green {
        unripe
    } else if pick < p_ripe + p_green + p_blush {
        let towards = Unit::new_normalize(Vector3::new(
            uniform(rng, -1.0, 1.0),
            uniform(rng, -1.0, 0.3),
            uniform(rng, -1.0, 0.2),
        ));
        let red = [
            uniform(rng, 0.35, 0.6),
            uniform(rng, 0.02, 0.08),
            uniform(rng, 0.02, 0.05),
        ];
        blush = Some(Blush {
            towards,
            albedo: red,
            fade_cos: uniform(rng, -0.6, 0.4),
        });
        if rng.gen_bool(0.5) {
            unripe
        } else {
            yellow
        }
    } else {
        yellow
    };
    let gloss = uniform(rng, WIDE_GLOSS_SCALE.0.ln(), WIDE_GLOSS_SCALE.1.ln()).exp();
    let material = Material {
        albedo,
        specular: (ripe.specular * gloss).min(1.5),
        shininess: ripe.shininess * uniform(rng, 0.5, 2.0),
    };
    (material, blush)
}

/// A backdrop plane at depth `z` (on the optical axis) with `normal`.
fn backdrop_plane(
    z: f64,
    normal: Unit<Vector3<f64>>,
    kind: BackdropKind,
    texture_seed: u64,
) -> Backdrop {
    Backdrop {
        point: Point3::new(0.0, 0.0, z),
        normal,
        texture_seed,
        kind,
    }
}
