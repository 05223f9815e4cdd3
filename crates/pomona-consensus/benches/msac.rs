//! MSAC sphere fitting on a 2000-point partial cap (seed 002's defaults: T = 25 mm, L = 500), a
//! cylinder fit for comparison, and PCA normals on an organised sphere cloud by image window
//! versus k nearest neighbours (kd-tree). Fixed seeds throughout. Run single-threaded for stable
//! figures: `RAYON_NUM_THREADS=1 cargo bench -p pomona-consensus --bench msac`.

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

#[path = "../tests/common/mod.rs"]
mod common;

use common::*;
use criterion::{criterion_group, criterion_main, Criterion};
use pomona_consensus::nalgebra::{Point3, Unit, Vector3};
use pomona_consensus::{
    Acceptance, Consensus, CylinderEstimatorParams, KnnNormalParams, MsacParams,
    SphereEstimatorParams, UniformSampler, WindowNormalParams,
};

fn bench(c: &mut Criterion) {
    let mut r = rng(1);
    let centre = Point3::new(0.02, -0.03, 0.8);
    let cap = sphere_cap(centre, 0.04, 0.4, 2000, 0.002, &mut r);
    let sphere = SphereEstimatorParams::default().check().unwrap();
    let mut g = c.benchmark_group("msac");
    for (name, refine) in [
        ("sphere_cap_2000", Some(0.01)),
        ("sphere_cap_2000_no_refine", None),
    ] {
        let msac = MsacParams {
            acceptance: Acceptance::Always,
            refine_threshold_m: refine,
            ..Default::default()
        }
        .check()
        .unwrap();
        g.bench_function(name, |b| {
            b.iter(|| {
                msac.fit(&sphere, &cap, &mut UniformSampler::new(7))
                    .unwrap()
                    .unwrap()
            })
        });
    }
    let axis = Unit::new_normalize(Vector3::new(0.2, 1.0, 0.3));
    let half = cylinder_half(centre, axis, 0.03, 0.18, 2000, 0.002, &mut r);
    let cylinder = CylinderEstimatorParams::default().check().unwrap();
    let msac = MsacParams::default().check().unwrap();
    g.bench_function("cylinder_half_2000", |b| {
        b.iter(|| {
            msac.fit(&cylinder, &half, &mut UniformSampler::new(7))
                .unwrap()
                .unwrap()
        })
    });
    let early = MsacParams {
        early_stop_confidence: Some(0.99),
        ..Default::default()
    }
    .check()
    .unwrap();
    g.bench_function("cylinder_half_2000_early_stop_0.99", |b| {
        b.iter(|| {
            early
                .fit(&cylinder, &half, &mut UniformSampler::new(7))
                .unwrap()
                .unwrap()
        })
    });
    g.bench_function("sphere_cap_2000_early_stop_0.99", |b| {
        b.iter(|| {
            early
                .fit(&sphere, &cap, &mut UniformSampler::new(7))
                .unwrap()
                .unwrap()
        })
    });
    g.finish();

    // A 60 mm-radius fruit filling most of a 200×200 window at 0.6 m (kinect-v2-like focal).
    let cloud = organised_sphere(200, 200, 365.0, Point3::new(0.0, 0.0, 0.6), 0.06);
    let positions: Vec<Point3<f64>> = cloud.points().iter().map(|p| p.cast::<f64>()).collect();
    let valid = positions.iter().filter(|p| p.x.is_finite()).count();
    let window = WindowNormalParams::default().check().unwrap();
    let knn = KnnNormalParams::default().check().unwrap();
    let mut g = c.benchmark_group(format!("normals_{valid}_points"));
    g.sample_size(20);
    g.bench_function("window_5x5", |b| {
        b.iter(|| window.estimate(&cloud).unwrap())
    });
    // The window the shape-fit model scales to on a 1080p Azure Kinect (917 px focal length).
    let window_11 = WindowNormalParams {
        half_window: 5,
        ..WindowNormalParams::default()
    }
    .check()
    .unwrap();
    g.bench_function("window_11x11", |b| {
        b.iter(|| window_11.estimate(&cloud).unwrap())
    });
    g.bench_function("knn_16_kdtree", |b| b.iter(|| knn.estimate(&positions)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
