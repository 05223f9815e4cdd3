//! kd-tree build and kNN-30 PCA normals on a Kinect v2-sized frame (512×424, fx = 365): a wavy
//! background surface 1–1.3 m away with five fruit-sized spheres in front, a quarter of the
//! pixels without depth — about 160 k points, as unorganised `f64` points (the input
//! `KnnNormals` takes). Fixed pattern, no randomness. One thread:
//! `cargo bench -p pomona-consensus --bench knn_normals`.

#![allow(clippy::unwrap_used, missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_consensus::nalgebra::{Point3, Vector3};
use pomona_consensus::{KdTree, KnnNormalParams};

fn frame_points() -> Vec<Point3<f64>> {
    let (w, h, f) = (512usize, 424usize, 365.0);
    let spheres = [
        (Point3::new(-0.2, 0.05, 0.7), 0.04),
        (Point3::new(0.1, -0.1, 0.6), 0.05),
        (Point3::new(0.25, 0.2, 0.8), 0.035),
        (Point3::new(-0.05, 0.25, 0.75), 0.045),
        (Point3::new(0.0, 0.0, 0.9), 0.06),
    ];
    let mut pts = Vec::new();
    for v in 0..h {
        for u in 0..w {
            if (u * 7 + v * 13) % 4 == 0 {
                continue; // no depth
            }
            let ray = Vector3::new((u as f64 - 255.5) / f, (v as f64 - 211.5) / f, 1.0);
            let mut z = 1.15 + 0.1 * (u as f64 / 20.0).sin() * (v as f64 / 25.0).cos();
            for (c, r) in &spheres {
                let d = ray.normalize();
                let b = d.dot(&c.coords);
                let disc = b * b - (c.coords.norm_squared() - r * r);
                if disc > 0.0 {
                    z = z.min((b - disc.sqrt()) * d.z);
                }
            }
            // Quantise like a 0.1 mm depth PNG, then back-project in f32 like a cloud.
            let z = (z * 1e4).round() / 1e4;
            let p = (ray * z).cast::<f32>();
            pts.push(Point3::from(p.cast::<f64>()));
        }
    }
    pts
}

fn bench(c: &mut Criterion) {
    let pts = frame_points();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let knn = KnnNormalParams {
        k: 30,
        ..Default::default()
    }
    .check()
    .unwrap();
    let mut g = c.benchmark_group(format!("knn_{}_points", pts.len()));
    g.sample_size(10);
    g.bench_function("kd_tree_build", |b| b.iter(|| KdTree::build(&pts)));
    g.bench_function("knn_30_normals", |b| {
        b.iter(|| one.install(|| knn.estimate(&pts)))
    });
    let tree = KdTree::build(&pts);
    let mut out = Vec::new();
    g.bench_function("nearest_1_every_10th_point_offset", |b| {
        b.iter(|| {
            let mut sum = 0.0;
            for p in pts.iter().step_by(10) {
                tree.nearest_k(&(p + Vector3::new(0.002, -0.001, 0.004)), 1, &mut out);
                sum += out[0].1;
            }
            sum
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
