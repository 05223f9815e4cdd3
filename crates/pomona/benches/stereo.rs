//! Seed 004's two-shot stereo end to end ([`pomona::StereoLocator::locate`]: color-contour on
//! both shots, matching, refinement, location) with the built-in model, one thread, on three
//! `orchard` D435 stereo frames of oranges (seed 613, noise-free rig, β = 2°, lever 0.8 m: the
//! rig whose 3D error docs/results.md tracks), rendered into a temporary folder once; one
//! iteration locates all three. Three settings: `pomona stereo`'s defaults, without the pass
//! over the relaxation's leftovers, and the seed's matching and circle centres alone (no
//! evidence, no leftover pass, no refinement).
//!
//! `cargo bench -p pomona --bench stereo`

#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona::{ColorImage, Dataset, Detector, RotatedStereo, StereoLocator, StereoSettings};
use pomona_synth::{
    generate_dataset, CameraPreset, DatasetSpec, Domain, FruitChoice, FruitKind, LightPreset,
    NoiseModel, SceneSpec, StereoRig,
};

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let rig = StereoRig {
        beta_rad: 2f64.to_radians(),
        pivot_distance_m: 0.8,
    };
    let scene = SceneSpec {
        fruit: FruitChoice::Only(FruitKind::Orange),
        camera: CameraPreset::D435.camera(),
        noise: NoiseModel::None,
        domain: Domain::Orchard,
        light: LightPreset::Day,
        ..SceneSpec::default()
    };
    let spec = DatasetSpec {
        stereo: Some(rig),
        ..DatasetSpec::new(scene, 3, 613)
    };
    generate_dataset(&spec, dir.path(), &|_| {}).unwrap_or_else(|e| panic!("{e}"));
    let views = [dir.path().to_owned(), dir.path().join("stereo")].map(|p| {
        let data = Dataset::open(&p).unwrap_or_else(|e| panic!("{e}"));
        data.frames()
            .iter()
            .map(|s| {
                data.load_color(s)
                    .ok()
                    .flatten()
                    .unwrap_or_else(|| panic!("{s}"))
            })
            .collect::<Vec<ColorImage>>()
    });
    let camera = spec.scene.camera;
    let rig = RotatedStereo::new(rig.beta_rad, rig.pivot_distance_m, camera)
        .unwrap_or_else(|e| panic!("{e}"));
    let defaults = StereoSettings::default();
    let settings = [
        ("defaults", defaults),
        (
            "no leftover pass",
            StereoSettings {
                leftovers: None,
                ..defaults
            },
        ),
        (
            "the seed's",
            StereoSettings {
                evidence: pomona::PairEvidence::default(),
                leftovers: None,
                refinement: None,
                ..defaults
            },
        ),
    ];
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap_or_else(|e| panic!("{e}"));
    for (name, settings) in settings {
        let detector = Detector::builder("color-contour")
            .and_then(|b| b.overrides(StereoLocator::detector_overrides([])).build())
            .unwrap_or_else(|e| panic!("{e}"));
        let keep = detector
            .keep_rule_for(None)
            .unwrap_or_else(|e| panic!("{e}"));
        let locator =
            StereoLocator::new(detector, keep, rig, settings).unwrap_or_else(|e| panic!("{e}"));
        c.bench_function(
            &format!("stereo locate 3 orchard d435 frames, {name}"),
            |b| {
                b.iter(|| {
                    pool.install(|| {
                        views[0]
                            .iter()
                            .zip(&views[1])
                            .map(|(a, s)| locator.locate(a, s).map(|f| f.detections.len()))
                            .sum::<Result<usize, _>>()
                            .unwrap_or_else(|e| panic!("{e}"))
                    })
                });
            },
        );
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
