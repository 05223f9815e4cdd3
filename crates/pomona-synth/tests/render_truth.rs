//! Rendered frames agree with the scene they were rendered from: depth lies on the fruit
//! surfaces (within each noise model), masks, boxes and visibility are consistent, and an
//! unoccluded fruit has visibility exactly 1.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use nalgebra::{Point3, Rotation3, Unit, Vector3};
use pomona_core::PinholeCamera;
use pomona_synth::{
    render, render_view, Backdrop, BackdropKind, CameraPreset, FruitBody, FruitChoice, FruitKind,
    FruitShape, Leaf, LeafFamily, LightPreset, Material, NoiseModel, RenderedFrame, Scene,
    SceneSpec, StereoRig, TOF_EDGE_JUMP, TOF_SIGMA_MAX,
};

fn spec(kind: FruitChoice, noise: NoiseModel) -> SceneSpec {
    SceneSpec {
        fruit: kind,
        noise,
        ..SceneSpec::default()
    }
}

/// The scene fruit behind mask id `k` (1-based) of a rendered frame.
fn fruit_of<'a>(scene: &'a Scene, out: &RenderedFrame, k: u16) -> &'a FruitBody {
    let id: usize = out.truth.fruits[k as usize - 1].id.parse().unwrap();
    &scene.fruits[id]
}

/// Whether the surface of `f` lies within 0.05 mm (along the pixel ray) of depth `z`: the
/// implicit function is outside just before and inside just after, or is itself tiny.
fn on_surface(f: &FruitBody, cam: &PinholeCamera, u: u32, v: u32, z: f64) -> bool {
    let at = |z: f64| f.implicit_at(&cam.back_project(u as f64, v as f64, z));
    let delta = 5e-5;
    (at(z - delta) >= 0.0 && at(z + delta) <= 0.0) || at(z).abs() < 1e-5
}

/// Pixels `(u, v, mask id)` of fruit, excluding those next to a clean-depth edge.
fn interior_fruit_pixels(clean: &RenderedFrame) -> Vec<(u32, u32, u16)> {
    let cam = clean.frame.camera();
    let depth = clean.frame.depth();
    let mut px = Vec::new();
    for v in 1..cam.height - 1 {
        for u in 1..cam.width - 1 {
            let id = clean.mask.get(u, v).unwrap();
            if id == 0 {
                continue;
            }
            let z = depth.get(u, v).unwrap();
            let edge = [(u - 1, v), (u + 1, v), (u, v - 1), (u, v + 1)]
                .iter()
                .any(|&(a, b)| (depth.get(a, b).unwrap() - z).abs() as f64 > TOF_EDGE_JUMP);
            if !edge {
                px.push((u, v, id));
            }
        }
    }
    px
}

#[test]
fn noise_free_depth_back_projects_onto_the_fruit_surface() {
    for kind in FruitKind::ALL {
        let spec = spec(FruitChoice::Only(kind), NoiseModel::None);
        for seed in 0..3 {
            let scene = spec.sample(seed).unwrap();
            let out = render(&scene, &spec.camera).unwrap();
            let cam = out.frame.camera();
            let mut checked = 0;
            for v in 0..cam.height {
                for u in 0..cam.width {
                    let k = out.mask.get(u, v).unwrap();
                    if k == 0 {
                        continue;
                    }
                    let z = out.frame.depth().get(u, v).unwrap() as f64;
                    let f = fruit_of(&scene, &out, k);
                    assert!(
                        on_surface(f, cam, u, v, z),
                        "{kind:?} seed {seed} ({u},{v}): z = {z} is not on the surface"
                    );
                    checked += 1;
                }
            }
            assert!(
                checked > 100,
                "{kind:?} seed {seed}: only {checked} fruit pixels"
            );
        }
    }
}

#[test]
fn tof_and_low_depth_stay_within_their_noise_model() {
    let clean_spec = spec(FruitChoice::Mixed, NoiseModel::None);
    for seed in 0..4 {
        let mut scene = clean_spec.sample(seed).unwrap();
        let clean = render(&scene, &clean_spec.camera).unwrap();
        let interior = interior_fruit_pixels(&clean);
        assert!(interior.len() > 500);

        scene.noise = NoiseModel::Tof;
        let tof = render(&scene, &clean_spec.camera).unwrap();
        let mut diffs = Vec::new();
        for &(u, v, k) in &interior {
            let Some(z) = tof.frame.depth().get(u, v) else {
                continue; // dropout
            };
            let z0 = clean.frame.depth().get(u, v).unwrap();
            let d = (z - z0).abs() as f64;
            // 4σ plus the 1 mm quantisation.
            assert!(
                d < 4.0 * TOF_SIGMA_MAX + 0.0005,
                "tof off by {d} at ({u},{v})"
            );
            // The pixel still shows the same fruit.
            assert_eq!(tof.mask.get(u, v), Some(k));
            diffs.push(d);
        }
        assert!(
            diffs.len() as f64 > 0.5 * interior.len() as f64,
            "too many dropouts"
        );
        let mean = diffs.iter().sum::<f64>() / diffs.len() as f64;
        // Mean absolute deviation of N(0, σ) is 0.8σ with σ in [4, 8] mm.
        assert!(mean > 0.0025 && mean < 0.0075, "mean |tof error| {mean}");

        scene.noise = NoiseModel::Low;
        let low = render(&scene, &clean_spec.camera).unwrap();
        for &(u, v, _) in &interior {
            let z0 = clean.frame.depth().get(u, v).unwrap() as f64;
            let z = low.frame.depth().get(u, v).unwrap() as f64;
            let sigma = NoiseModel::Low.sigma_m(z0, 0.0);
            assert!((z - z0).abs() < 5.5 * sigma + 1e-6, "low off by {}", z - z0);
        }
        // Image noise is the same for every depth model: colour does not change.
        assert_eq!(clean.frame.color(), tof.frame.color());
    }
}

#[test]
fn truth_boxes_masks_and_visibility_are_consistent() {
    let mut bins = [0usize; 3];
    for seed in 0..12 {
        let spec = spec(FruitChoice::Mixed, NoiseModel::None);
        let scene = spec.sample(seed).unwrap();
        let out = render(&scene, &spec.camera).unwrap();
        let cam = &spec.camera;
        assert!(out.truth.complete);
        let mut ids = std::collections::HashSet::new();
        for (i, f) in out.truth.fruits.iter().enumerate() {
            assert!(ids.insert(f.id.clone()), "duplicate id");
            let k = (i + 1) as u16;
            let vis = f.visibility.unwrap();
            assert!(vis > 0.0 && vis <= 1.0, "visibility {vis}");
            bins[if vis < 0.4 {
                0
            } else if vis < 0.8 {
                1
            } else {
                2
            }] += 1;
            let b = f.bbox_px.unwrap();
            assert!(b.xmin >= 0.0 && b.ymin >= 0.0);
            assert!(b.xmax <= cam.width as f64 - 1.0 && b.ymax <= cam.height as f64 - 1.0);
            // The box is exactly the box of the mask pixels.
            let (mut lo_u, mut lo_v, mut hi_u, mut hi_v) = (u32::MAX, u32::MAX, 0, 0);
            for v in 0..cam.height {
                for u in 0..cam.width {
                    if out.mask.get(u, v) == Some(k) {
                        lo_u = lo_u.min(u);
                        lo_v = lo_v.min(v);
                        hi_u = hi_u.max(u);
                        hi_v = hi_v.max(v);
                    }
                }
            }
            assert_eq!(
                [lo_u as f64, lo_v as f64, hi_u as f64, hi_v as f64],
                [b.xmin, b.ymin, b.xmax, b.ymax]
            );
            // The centre projects inside the box, or near it for heavily occluded fruit.
            let c = cam.project(&f.center_m.unwrap()).unwrap();
            let d_px = f.diameter_m.unwrap() * cam.fx / f.center_m.unwrap().z;
            let slack = if vis > 0.9 { 0.0 } else { d_px };
            assert!(
                c.x >= b.xmin - slack
                    && c.x <= b.xmax + slack
                    && c.y >= b.ymin - slack
                    && c.y <= b.ymax + slack,
                "centre {c:?} far from box {b:?} (visibility {vis})"
            );
            let axis = f.axis.unwrap();
            assert!((axis.norm() - 1.0).abs() < 1e-12);
            let kind = FruitKind::ALL
                .into_iter()
                .find(|x| x.name() == f.kind)
                .unwrap();
            let (lo, hi) = kind.width_range_m();
            let d = f.diameter_m.unwrap();
            assert!(d >= lo - 1e-9 && d <= hi + 1e-9);
        }
        // No mask id beyond the truth list.
        assert!(out
            .mask
            .as_slice()
            .iter()
            .all(|&id| (id as usize) <= out.truth.fruits.len()));
    }
    // Visibility spans the range (some hidden, some half, some whole).
    assert!(bins.iter().all(|&b| b > 3), "visibility bins {bins:?}");
}

fn lone_scene(fruit: FruitBody, leaves: Vec<Leaf>) -> Scene {
    let mut rng = pomona_synth::frame_rng(0, 0);
    Scene {
        fruits: vec![fruit],
        leaves,
        stems: Vec::new(),
        backdrop: Backdrop {
            point: Point3::new(0.0, 0.0, 1.5),
            normal: Unit::new_normalize(Vector3::new(0.0, 0.0, -1.0)),
            texture_seed: 1,
            kind: BackdropKind::Foliage,
        },
        light: LightPreset::Day.sample(&mut rng),
        noise: NoiseModel::None,
        noise_seed: 7,
        shadows: false,
        image_effects: None,
        max_depth_m: f64::INFINITY,
        truth_extra: serde_json::Map::new(),
    }
}

fn leaf_at(center: Point3<f64>) -> Leaf {
    Leaf {
        center,
        orientation: Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
        half_length_m: 0.05,
        half_width_m: 0.025,
        bend_along: 2.0,
        bend_across: 0.0,
        material: Material {
            albedo: [0.05, 0.2, 0.03],
            specular: 0.03,
            shininess: 10.0,
        },
        family: LeafFamily::Elliptic,
    }
}

#[test]
fn unoccluded_fruit_has_full_visibility_and_the_right_size() {
    let cam = CameraPreset::KinectV2.camera();
    let mut rng = pomona_synth::frame_rng(5, 0);
    let orange = FruitBody::new(
        FruitKind::Orange,
        Point3::new(0.0, 0.0, 0.6),
        Rotation3::identity(),
        FruitShape::sphere(0.04),
        FruitKind::Orange.sample_material(&mut rng, false),
    );
    // A leaf behind the fruit does not hide it.
    let out = render(
        &lone_scene(orange.clone(), vec![leaf_at(Point3::new(0.0, 0.0, 0.8))]),
        &cam,
    )
    .unwrap();
    assert_eq!(out.truth.fruits.len(), 1);
    let f = &out.truth.fruits[0];
    assert_eq!(f.visibility, Some(1.0));
    assert_eq!(f.kind, "orange");
    assert!((f.diameter_m.unwrap() - 0.08).abs() < 1e-9);
    // Disk area of the projected sphere: π (f r / sqrt(z² - r²))².
    let r_px = cam.fx * 0.04 / (0.6f64 * 0.6 - 0.04 * 0.04).sqrt();
    let area = std::f64::consts::PI * r_px * r_px;
    let count = out.mask.count(1) as f64;
    assert!((count / area - 1.0).abs() < 0.03, "{count} vs {area}");
    let b = f.bbox_px.unwrap();
    assert!((b.center().x - cam.cx).abs() < 1.0 && (b.center().y - cam.cy).abs() < 1.0);

    // A leaf in front, off to one side, hides part of it.
    let hidden = render(
        &lone_scene(orange.clone(), vec![leaf_at(Point3::new(0.04, 0.0, 0.5))]),
        &cam,
    )
    .unwrap();
    let v = hidden.truth.fruits[0].visibility.unwrap();
    assert!(v > 0.05 && v < 0.95, "visibility {v}");
    assert_eq!(hidden.mask.count(1) as f64 / count, v);

    // A fruit wholly behind a large leaf is not listed and has no mask pixels.
    let mut wall = leaf_at(Point3::new(0.0, 0.0, 0.45));
    wall.half_length_m = 0.3;
    wall.half_width_m = 0.3;
    let gone = render(&lone_scene(orange, vec![wall]), &cam).unwrap();
    assert!(gone.truth.fruits.is_empty());
    assert_eq!(gone.mask.count(0), cam.pixel_count());
}

#[test]
fn tilted_pepper_axis_and_centre_are_reported_in_the_camera_frame() {
    let cam = PinholeCamera::new(320, 240, 300.0, 300.0, 159.5, 119.5).unwrap();
    let mut rng = pomona_synth::frame_rng(6, 0);
    let tilt = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.4)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2);
    let pepper = FruitBody::new(
        FruitKind::Pepper,
        Point3::new(0.02, -0.01, 0.5),
        tilt,
        FruitKind::Pepper.sample_shape(&mut rng),
        FruitKind::Pepper.sample_material(&mut rng, false),
    );
    let out = render(&lone_scene(pepper.clone(), Vec::new()), &cam).unwrap();
    let f = &out.truth.fruits[0];
    assert_eq!(f.visibility, Some(1.0));
    assert_eq!(f.center_m, Some(pepper.center));
    let axis = f.axis.unwrap();
    assert!((axis.into_inner() - tilt * Vector3::z()).norm() < 1e-12);
    // Glossy fruit show a highlight: some fruit pixel is much brighter and less saturated than
    // the fruit's median.
    let color = out.frame.color().unwrap();
    let mut lum: Vec<(u32, u32)> = Vec::new();
    for v in 0..cam.height {
        for u in 0..cam.width {
            if out.mask.get(u, v) == Some(1) {
                let c = color.get(u, v).unwrap();
                let max = *c.iter().max().unwrap() as u32;
                let min = *c.iter().min().unwrap() as u32;
                lum.push((max, max - min));
            }
        }
    }
    let whitest = lum
        .iter()
        .map(|&(v, s)| v as f64 / (s as f64 + 1.0))
        .fold(0.0, f64::max);
    assert!(
        whitest > 1.5,
        "no low-saturation highlight (max V/S {whitest})"
    );
}

#[test]
fn stereo_view_reports_the_same_fruit_in_its_own_frame() {
    let spec = spec(FruitChoice::Only(FruitKind::Apple), NoiseModel::None);
    let scene = spec.sample(11).unwrap();
    let rig = StereoRig::default();
    let pose = rig.stereo_from_camera();
    let left = render(&scene, &spec.camera).unwrap();
    let right = render_view(&scene, &spec.camera, &pose, 1).unwrap();
    assert_ne!(left.frame.color(), right.frame.color());
    let mut shared = 0;
    for f in &right.truth.fruits {
        let id: usize = f.id.parse().unwrap();
        let expected = pose * scene.fruits[id].center;
        assert!((f.center_m.unwrap() - expected).norm() < 1e-12);
        if left.truth.fruits.iter().any(|g| g.id == f.id) {
            shared += 1;
        }
    }
    assert!(shared > 0);
    // Noise-free depth of the second view also lies on the fruit surface.
    let cam = &spec.camera;
    let inv = pose.inverse();
    for v in (0..cam.height).step_by(3) {
        for u in (0..cam.width).step_by(3) {
            let k = right.mask.get(u, v).unwrap();
            if k > 0 {
                let z = right.frame.depth().get(u, v).unwrap() as f64;
                let f = fruit_of(&scene, &right, k);
                let at = |z: f64| f.implicit_at(&(inv * cam.back_project(u as f64, v as f64, z)));
                assert!(at(z - 5e-5) >= 0.0 && at(z + 5e-5) <= 0.0 || at(z).abs() < 1e-5);
            }
        }
    }
}

#[test]
fn every_camera_preset_renders_at_its_size() {
    for preset in CameraPreset::ALL {
        let cam = preset.camera();
        let spec = SceneSpec {
            camera: cam,
            fruit_count: (3, 3),
            ..SceneSpec::default()
        };
        let out = render(&spec.sample(1).unwrap(), &cam).unwrap();
        assert_eq!(out.frame.camera(), &cam);
        assert_eq!(out.mask.width(), cam.width);
        assert!(out.frame.depth().valid_fraction() > 0.99, "{preset:?}");
        assert!(!out.truth.fruits.is_empty(), "{preset:?}");
    }
}
