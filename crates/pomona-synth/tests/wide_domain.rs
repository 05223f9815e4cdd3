//! The wide domain: deterministic per seed and thread count, restricted by its hold-out knobs,
//! recording what it drew, with no depth on sky and cloth, and truth consistent under camera
//! pitch and roll.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Point3, Vector3};
use pomona_synth::{
    generate_dataset, render, Background, CameraPreset, DatasetSpec, Domain, FruitChoice,
    LeafFamily, NoiseModel, RenderedFrame, Scene, SceneSpec, WideDraw, WIDE_PITCH_MAX_DEG,
    WIDE_ROLL_MAX_DEG,
};

fn wide(camera: CameraPreset) -> SceneSpec {
    SceneSpec {
        domain: Domain::Wide,
        fruit: FruitChoice::Mixed,
        camera: camera.camera(),
        noise: NoiseModel::for_camera(camera),
        ..SceneSpec::default()
    }
}

fn draw_of(out: &RenderedFrame) -> WideDraw {
    serde_json::from_value(out.truth.extra["synth"].clone()).unwrap()
}

/// Colour bytes, depth bits (NaN compares equal to NaN here), mask ids and truth JSON.
fn bytes(out: &RenderedFrame) -> Vec<u8> {
    let mut v = out.frame.color().unwrap().as_rgb().to_vec();
    for z in out.frame.depth().as_slice() {
        v.extend(z.to_bits().to_le_bytes());
    }
    for id in out.mask.as_slice() {
        v.extend(id.to_le_bytes());
    }
    v.extend(serde_json::to_vec(&out.truth).unwrap());
    v
}

fn tree(root: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let rel = path
                    .strip_prefix(root)
                    .unwrap()
                    .to_string_lossy()
                    .into_owned();
                out.insert(rel, std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

#[test]
fn wide_frames_are_deterministic_per_seed_and_thread_count() {
    let spec = wide(CameraPreset::KinectV2);
    let a = bytes(&render(&spec.sample(11).unwrap(), &spec.camera).unwrap());
    let b = bytes(&render(&spec.sample(11).unwrap(), &spec.camera).unwrap());
    assert!(a == b, "same seed, different frames");
    let c = bytes(&render(&spec.sample(12).unwrap(), &spec.camera).unwrap());
    assert!(a != c);

    let dir = tempfile::tempdir().unwrap();
    let mut ds = DatasetSpec::new(wide(CameraPreset::Sr4000), 4, 5);
    ds.threads = Some(1);
    generate_dataset(&ds, &dir.path().join("one"), &|_| {}).unwrap();
    ds.threads = Some(2);
    generate_dataset(&ds, &dir.path().join("two"), &|_| {}).unwrap();
    let (one, two) = (tree(&dir.path().join("one")), tree(&dir.path().join("two")));
    assert!(one.len() > 10);
    assert_eq!(one, two);
}

/// Whether the primary-view ray through pixel `(u, v)` meets any leaf, stem or fruit.
fn hits_an_object(scene: &Scene, spec: &SceneSpec, u: u32, v: u32) -> bool {
    let o = Point3::origin();
    let d: Vector3<f64> = spec.camera.back_project(u as f64, v as f64, 1.0).coords;
    scene.leaves.iter().any(|l| l.intersect(&o, &d).is_some())
        || scene.stems.iter().any(|s| s.intersect(&o, &d).is_some())
        || scene.fruits.iter().any(|f| f.intersect(&o, &d).is_some())
}

#[test]
fn sky_and_cloth_pixels_have_no_depth() {
    for (background, camera) in [
        (Background::Sky, CameraPreset::D435),
        (Background::Cloth, CameraPreset::Sr4000),
        (Background::Sky, CameraPreset::Sr4000),
        (Background::Cloth, CameraPreset::KinectV2),
    ] {
        let spec = SceneSpec {
            backgrounds: vec![background],
            ..wide(camera)
        };
        for seed in 0..2 {
            let scene = spec.sample(seed).unwrap();
            let out = render(&scene, &spec.camera).unwrap();
            assert_eq!(draw_of(&out).background, background);
            let depth = out.frame.depth();
            let (mut background_px, mut bright) = (0, 0);
            for v in (0..spec.camera.height).step_by(6) {
                for u in (0..spec.camera.width).step_by(6) {
                    if hits_an_object(&scene, &spec, u, v) {
                        continue;
                    }
                    background_px += 1;
                    let z = depth.as_slice()[(v * spec.camera.width + u) as usize];
                    assert!(z.is_nan(), "{background:?} pixel ({u}, {v}) has depth {z}");
                    let rgb = out.frame.color().unwrap().get(u, v).unwrap();
                    if rgb.iter().map(|&c| c as u32).sum::<u32>() > 300 {
                        bright += 1;
                    }
                }
            }
            assert!(
                background_px > 5,
                "{background:?} seed {seed}: no background visible"
            );
            if background == Background::Sky {
                assert!(
                    bright * 2 > background_px,
                    "sky is not bright: {bright}/{background_px}"
                );
            }
        }
    }
}

#[test]
fn hold_out_knobs_restrict_what_is_drawn_and_are_recorded() {
    for (families, backgrounds, band) in [
        (
            vec![LeafFamily::Lobed],
            vec![Background::Soil, Background::Greenhouse],
            (0.3, 0.8),
        ),
        (
            vec![LeafFamily::Compound, LeafFamily::Lanceolate],
            vec![Background::SecondRow],
            (0.8, 1.6),
        ),
        (
            vec![LeafFamily::Elliptic],
            vec![Background::Sky, Background::Cloth],
            (1.0, 1.2),
        ),
    ] {
        let spec = SceneSpec {
            leaf_families: families.clone(),
            backgrounds: backgrounds.clone(),
            wide_distance_m: band,
            ..wide(CameraPreset::Sr4000)
        };
        let mut seen_families = Vec::new();
        for seed in 0..8 {
            let scene = spec.sample(seed).unwrap();
            let out = render(&scene, &spec.camera).unwrap();
            let draw = draw_of(&out);
            assert_eq!(draw.domain, "wide");
            assert!(families.contains(&draw.leaf_family), "{draw:?}");
            assert!(backgrounds.contains(&draw.background), "{draw:?}");
            assert_eq!(draw.distance_band_m, band);
            assert!(draw.distance_m >= band.0 && draw.distance_m <= band.1);
            assert_eq!(
                (draw.leaf_families.clone(), draw.backgrounds.clone()),
                (families.clone(), backgrounds.clone())
            );
            assert_eq!(draw.leaves, scene.leaves.len());
            assert!(
                draw.pitch_deg.abs() <= WIDE_PITCH_MAX_DEG
                    && draw.roll_deg.abs() <= WIDE_ROLL_MAX_DEG
            );
            assert!(!scene.fruits.is_empty());
            for f in &scene.fruits {
                let d = f.center.coords.norm();
                assert!(
                    d >= band.0 - 1e-9 && d <= band.1 + 1e-9,
                    "fruit at {d} m outside {band:?}"
                );
            }
            assert!(scene.leaves.iter().all(|l| l.family == draw.leaf_family));
            seen_families.push(draw.leaf_family);
        }
        if families.len() > 1 {
            assert!(
                families.iter().all(|f| seen_families.contains(f)),
                "{seen_families:?}"
            );
        }
    }
    // The narrow domain records nothing and refuses the knobs.
    let narrow = SceneSpec::default();
    let out = render(&narrow.sample(1).unwrap(), &narrow.camera).unwrap();
    assert!(out.truth.extra.is_empty());
    let bad = SceneSpec {
        backgrounds: vec![Background::Sky],
        ..SceneSpec::default()
    };
    assert!(bad
        .validate()
        .unwrap_err()
        .to_string()
        .contains("backgrounds"));
    for bad in [
        SceneSpec {
            leaf_families: vec![],
            ..wide(CameraPreset::KinectV2)
        },
        SceneSpec {
            backgrounds: vec![],
            ..wide(CameraPreset::KinectV2)
        },
        SceneSpec {
            wide_distance_m: (0.9, 0.5),
            ..wide(CameraPreset::KinectV2)
        },
        SceneSpec {
            wide_distance_m: (0.1, 0.5),
            ..wide(CameraPreset::KinectV2)
        },
    ] {
        assert!(bad.sample(0).is_err(), "{bad:?}");
    }
}

#[test]
fn truth_stays_in_the_camera_frame_under_pitch_and_roll() {
    let spec = wide(CameraPreset::KinectV2);
    let cam = spec.camera;
    let (mut checked, mut tilted) = (0, 0);
    for seed in 0..10 {
        let out = render(&spec.sample(seed).unwrap(), &cam).unwrap();
        let draw = draw_of(&out);
        if draw.pitch_deg.abs().max(draw.roll_deg.abs()) > 8.0 {
            tilted += 1;
        }
        for f in &out.truth.fruits {
            if f.visibility.unwrap() < 0.6 {
                continue;
            }
            let c = f.center_m.unwrap();
            let (u, v) = (cam.fx * c.x / c.z + cam.cx, cam.fy * c.y / c.z + cam.cy);
            let b = f.bbox_px.unwrap();
            assert!(
                u >= b.xmin - 1.0 && u <= b.xmax + 1.0 && v >= b.ymin - 1.0 && v <= b.ymax + 1.0,
                "seed {seed}: centre projects to ({u:.1}, {v:.1}) outside {b:?}"
            );
            checked += 1;
        }
    }
    assert!(
        checked > 10 && tilted > 3,
        "checked {checked}, tilted {tilted}"
    );
}
