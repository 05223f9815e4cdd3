//! The orchard domain: citrus trees for the colour-and-contour method of seed 004 (Plebe &
//! Grasso 2001), whose difficulties are many fruit per view, fruit touching in clusters and hiding
//! one another, unripe fruit shading from orange to yellow-green, and the light: the paper's
//! harvest rate drops from 85 % under clouds to 52 % with a low sun.
//!
//! It reuses the wide sampler (`wide_scene.rs`: canopy, leaf families, backgrounds, stalks,
//! cast shadows, depth range and noise) with its own profile:
//! * [`ORCHARD_FRUIT_COUNT`] fruit per frame, a cluster started with probability
//!   [`ORCHARD_CLUSTER_PROBABILITY`] of [`ORCHARD_CLUSTER_SIZE`] touching fruit;
//! * camera pitch and roll within ±[`ORCHARD_PITCH_ROLL_MAX_DEG`];
//! * colour: oranges get a ripeness `t = u²` (`u` uniform; half the fruit have `t < 0.25`) that
//!   blends the albedo from orange ([`ORCHARD_ORANGE`], `t = 0`) through yellow
//!   ([`ORCHARD_YELLOW`], `t = 0.5`) to yellow-green ([`ORCHARD_YELLOW_GREEN`], `t = 1`), times a
//!   brightness gain 0.85–1.1 and a per-channel tint of ±7 %; other kinds keep their own ripe
//!   colours;
//! * the light of the spec's [`LightPreset`] ([`orchard_light`]):
//!
//! | preset    | sun elevation | sun azimuth (0 = behind camera) | sun  | sky light | exposure | noise σ |
//! |-----------|---------------|---------------------------------|------|-----------|----------|---------|
//! | day       | 35–75°        | −90–90°                         | 0.8–1.1 | 0.25–0.40 | 0.9–1.1 | 1–2.5 |
//! | dim       | 20–60°        | any                             | 0.15–0.35 | 0.08–0.15 | 0.9–1.2 | 3–5 |
//! | harsh     | 50–85°        | −60–60°                         | 1.4–1.8 | 0.05–0.10 | 1.0–1.2 | 1–2 |
//! | low-sun   | 3–15°         | ±(60–120)° (from a side)        | 0.9–1.3 | 0.10–0.20 | 0.9–1.2 | 1.5–3 |
//! | backlight | 15–45°        | 150–210° (facing the camera)    | 1.0–1.5 | 0.12–0.25 | 0.7–0.95 | 1.5–3 |
//!
//! Light colour: day and harsh neutral to slightly warm, dim bluish `[0.88, 0.93, 1.0]`, low
//! sun warm `[1.0, 0.82, 0.6]`, backlight `[1.0, 0.97, 0.9]`; white balance within ±3 % per
//! channel, vignetting 0–0.2. Everything drawn is recorded in truth `extra.synth` (domain
//! `"orchard"`, the preset under `light`).

use nalgebra::{Rotation3, Unit, Vector3};
use rand::Rng;

use crate::rng::{uniform, SynthRng};
use crate::wide_scene::{sample_world, FrameLight, WorldProfile};
use crate::{Blush, FruitKind, Light, LightPreset, Material, Scene, SceneSpec, SunDraw};

/// Fruit per orchard frame (inclusive).
pub const ORCHARD_FRUIT_COUNT: (u32, u32) = (5, 20);
/// Probability that a placed fruit starts a cluster of touching fruit.
pub const ORCHARD_CLUSTER_PROBABILITY: f64 = 0.5;
/// Fruit per cluster.
pub const ORCHARD_CLUSTER_SIZE: (u32, u32) = (2, 5);
/// Largest camera pitch and roll either way, degrees.
pub const ORCHARD_PITCH_ROLL_MAX_DEG: f64 = 10.0;
/// Albedo of a ripe orange (ripeness 0).
pub const ORCHARD_ORANGE: [f64; 3] = [0.80, 0.22, 0.01];
/// Albedo of a yellow, half-ripe orange (ripeness 0.5).
pub const ORCHARD_YELLOW: [f64; 3] = [0.72, 0.50, 0.03];
/// Albedo of a yellow-green, unripe orange (ripeness 1).
pub const ORCHARD_YELLOW_GREEN: [f64; 3] = [0.42, 0.50, 0.05];

/// Draws one orchard scene (`spec` must be valid).
pub(crate) fn sample_orchard(spec: &SceneSpec, rng: &mut SynthRng) -> Scene {
    let profile = WorldProfile {
        domain: "orchard",
        fruit_count: ORCHARD_FRUIT_COUNT,
        pitch_roll_max_deg: (ORCHARD_PITCH_ROLL_MAX_DEG, ORCHARD_PITCH_ROLL_MAX_DEG),
        cluster_probability: ORCHARD_CLUSTER_PROBABILITY,
        cluster_size: ORCHARD_CLUSTER_SIZE,
        colour: orchard_colour,
        lighting: Some(spec.light),
    };
    sample_world(spec, &profile, rng)
}

/// An orange's albedo at ripeness `t` in [0, 1] (see the module docs).
pub fn orchard_albedo(t: f64) -> [f64; 3] {
    let t = t.clamp(0.0, 1.0);
    let (a, b, f) = if t < 0.5 {
        (ORCHARD_ORANGE, ORCHARD_YELLOW, 2.0 * t)
    } else {
        (ORCHARD_YELLOW, ORCHARD_YELLOW_GREEN, 2.0 * t - 1.0)
    };
    std::array::from_fn(|c| a[c] + (b[c] - a[c]) * f)
}

/// The orchard's fruit surface: oranges from orange to yellow-green, other kinds ripe.
fn orchard_colour(rng: &mut SynthRng, kind: FruitKind) -> (Material, Option<Blush>) {
    let ripe = kind.sample_material(rng, false);
    if kind != FruitKind::Orange {
        return (ripe, None);
    }
    let u: f64 = rng.gen();
    let base = orchard_albedo(u * u);
    let g = uniform(rng, 0.85, 1.1);
    let tint: [f64; 3] = std::array::from_fn(|_| g * uniform(rng, 0.93, 1.07));
    let material = Material {
        albedo: std::array::from_fn(|c| (base[c] * tint[c]).min(1.0)),
        ..ripe
    };
    (material, None)
}

/// The sun, sky light and camera response of `preset` (table in the module docs), in the
/// camera frame tilted by `camera_from_level`.
pub(crate) fn orchard_light(
    preset: LightPreset,
    rng: &mut SynthRng,
    camera_from_level: &Rotation3<f64>,
) -> FrameLight {
    struct Ranges {
        elevation: (f64, f64),
        azimuth: (f64, f64),
        sun: (f64, f64),
        sky: (f64, f64),
        exposure: (f64, f64),
        noise: (f64, f64),
        color: [f64; 3],
    }
    let r = match preset {
        LightPreset::Day => Ranges {
            elevation: (35.0, 75.0),
            azimuth: (-90.0, 90.0),
            sun: (0.8, 1.1),
            sky: (0.25, 0.4),
            exposure: (0.9, 1.1),
            noise: (1.0, 2.5),
            color: [1.0, 1.0, 0.97],
        },
        LightPreset::Dim => Ranges {
            elevation: (20.0, 60.0),
            azimuth: (-180.0, 180.0),
            sun: (0.15, 0.35),
            sky: (0.08, 0.15),
            exposure: (0.9, 1.2),
            noise: (3.0, 5.0),
            color: [0.88, 0.93, 1.0],
        },
        LightPreset::Harsh => Ranges {
            elevation: (50.0, 85.0),
            azimuth: (-60.0, 60.0),
            sun: (1.4, 1.8),
            sky: (0.05, 0.1),
            exposure: (1.0, 1.2),
            noise: (1.0, 2.0),
            color: [1.0, 0.98, 0.92],
        },
        LightPreset::LowSun => Ranges {
            elevation: (3.0, 15.0),
            azimuth: (60.0, 120.0),
            sun: (0.9, 1.3),
            sky: (0.1, 0.2),
            exposure: (0.9, 1.2),
            noise: (1.5, 3.0),
            color: [1.0, 0.82, 0.6],
        },
        LightPreset::Backlight => Ranges {
            elevation: (15.0, 45.0),
            azimuth: (150.0, 210.0),
            sun: (1.0, 1.5),
            sky: (0.12, 0.25),
            exposure: (0.7, 0.95),
            noise: (1.5, 3.0),
            color: [1.0, 0.97, 0.9],
        },
    };
    let elevation = uniform(rng, r.elevation.0, r.elevation.1);
    let mut azimuth = uniform(rng, r.azimuth.0, r.azimuth.1);
    if preset == LightPreset::LowSun && rng.gen_bool(0.5) {
        azimuth = -azimuth;
    }
    if azimuth > 180.0 {
        azimuth -= 360.0;
    }
    let (el, az) = (elevation.to_radians(), azimuth.to_radians());
    let level = Vector3::new(el.cos() * az.sin(), -el.sin(), -el.cos() * az.cos());
    let intensity = uniform(rng, r.sun.0, r.sun.1);
    let light = Light {
        towards_light: Unit::new_normalize(camera_from_level * level),
        intensity,
        ambient: uniform(rng, r.sky.0, r.sky.1),
        color: r.color,
        image_noise_sigma: uniform(rng, r.noise.0, r.noise.1),
    };
    FrameLight {
        light,
        sun: SunDraw {
            azimuth_deg: azimuth,
            elevation_deg: elevation,
            intensity,
        },
        exposure: uniform(rng, r.exposure.0, r.exposure.1),
        white_balance: std::array::from_fn(|_| uniform(rng, 0.97, 1.03)),
        vignetting: uniform(rng, 0.0, 0.2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{render, Domain, FruitChoice};

    fn spec(light: LightPreset) -> SceneSpec {
        SceneSpec {
            fruit: FruitChoice::Only(FruitKind::Orange),
            domain: Domain::Orchard,
            light,
            camera: crate::CameraPreset::Sr4000.camera(),
            ..SceneSpec::default()
        }
    }

    #[test]
    fn orchard_scenes_have_many_clustered_fruit_from_orange_to_yellow_green() {
        let mut clusters = 0;
        let mut greenest: f64 = 0.0;
        for seed in 0..12 {
            let scene = spec(LightPreset::Day).sample(seed).unwrap();
            let n = scene.fruits.len() as u32;
            assert!(n >= 3 && n <= ORCHARD_FRUIT_COUNT.1, "{n} fruit");
            let synth = &scene.truth_extra["synth"];
            assert_eq!(synth["domain"], "orchard");
            assert_eq!(synth["light"], "day");
            clusters += synth["fruit_clusters"].as_u64().unwrap();
            for f in &scene.fruits {
                let [r, g, b] = f.material.albedo;
                assert!(r > b && g > b, "{:?}", f.material.albedo);
                greenest = greenest.max(g / r);
            }
        }
        assert!(clusters >= 6, "{clusters} clusters in 12 frames");
        assert!(
            greenest > 0.9,
            "no yellow-green fruit: largest g/r {greenest}"
        );
        assert_eq!(orchard_albedo(0.0), ORCHARD_ORANGE);
        assert_eq!(orchard_albedo(1.0), ORCHARD_YELLOW_GREEN);
    }

    #[test]
    fn presets_place_the_sun_where_documented() {
        let up = Rotation3::identity();
        for seed in 0..20 {
            let mut rng = crate::frame_rng(seed, 0);
            let low = orchard_light(LightPreset::LowSun, &mut rng, &up);
            assert!(low.sun.elevation_deg <= 15.0 && low.sun.azimuth_deg.abs() >= 60.0);
            let back = orchard_light(LightPreset::Backlight, &mut rng, &up);
            assert!(
                back.sun.azimuth_deg.abs() >= 150.0,
                "{}",
                back.sun.azimuth_deg
            );
            // Facing the camera: the light comes from beyond the fruit (+z).
            assert!(back.light.towards_light.z > 0.0);
            let dim = orchard_light(LightPreset::Dim, &mut rng, &up);
            let harsh = orchard_light(LightPreset::Harsh, &mut rng, &up);
            assert!(dim.light.intensity < harsh.light.intensity);
            assert!(dim.light.image_noise_sigma > harsh.light.image_noise_sigma);
        }
    }

    #[test]
    fn backlit_fruit_are_darker_than_daylit_ones() {
        let mean_fruit_red = |light| {
            let s = spec(light);
            let (mut sum, mut n) = (0.0, 0usize);
            for seed in 0..4 {
                let out = render(&s.sample(seed).unwrap(), &s.camera).unwrap();
                let color = out.frame.color().unwrap();
                for (rgb, id) in color.pixels().zip(out.mask.as_slice()) {
                    if *id > 0 {
                        sum += f64::from(rgb[0]);
                        n += 1;
                    }
                }
            }
            sum / n.max(1) as f64
        };
        let (day, back) = (
            mean_fruit_red(LightPreset::Day),
            mean_fruit_red(LightPreset::Backlight),
        );
        assert!(back < day, "backlight {back:.1} vs day {day:.1}");
    }
}
