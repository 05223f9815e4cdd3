//! Rendering speed: one Kinect v2 frame (512×424) of a fixed pepper scene, single-threaded, for
//! each depth noise model; plus scene sampling alone.
//!
//! `cargo bench -p pomona-synth --bench render`

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_synth::{render, NoiseModel, SceneSpec};

fn bench_render(c: &mut Criterion) {
    let spec = SceneSpec::default();
    let mut group = c.benchmark_group("kinect_v2_frame");
    group.sample_size(20);
    for noise in NoiseModel::ALL {
        let spec = SceneSpec {
            noise,
            ..spec.clone()
        };
        let Ok(scene) = spec.sample(2024) else {
            return;
        };
        group.bench_function(format!("render/{}", noise.name()), |b| {
            b.iter(|| render(&scene, &spec.camera))
        });
    }
    group.bench_function("sample_scene", |b| b.iter(|| spec.sample(2024)));
    group.finish();
}

criterion_group!(benches, bench_render);
criterion_main!(benches);
