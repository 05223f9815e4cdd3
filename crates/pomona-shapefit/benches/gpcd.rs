//! The GPCD of one candidate (seed 002's descriptor), alone: a 60 mm fruit's visible half as
//! 200 points with normals and colours (every ordered pair of the 200 votes), and as 64 points
//! (the depth proposals' screen budget). Deterministic points, one thread.
//!
//! `cargo bench -p pomona-shapefit --bench gpcd`

#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_core::nalgebra::{Point3, Unit, Vector3};
use pomona_shapefit::{gpcd, GpcdParams};

/// `n` points spread evenly (golden angle) over the half of a sphere facing the camera, with
/// outward normals and two colours.
type Normals = Vec<Option<Unit<Vector3<f64>>>>;

fn half_fruit(n: usize) -> (Vec<Point3<f64>>, Normals, Vec<[u8; 3]>) {
    let centre = Point3::new(0.02, -0.01, 0.7);
    let mut points = Vec::with_capacity(n);
    let mut normals = Vec::with_capacity(n);
    for i in 0..n {
        let z = -(i as f64 + 0.5) / n as f64;
        let phi = i as f64 * 2.399_963;
        let s = (1.0 - z * z).sqrt();
        let outward = Vector3::new(s * phi.cos(), s * phi.sin(), z);
        points.push(centre + outward * 0.06);
        // Every seventh point has no normal (a window too small), as on real clusters.
        normals.push((i % 7 != 3).then(|| Unit::new_normalize(outward)));
    }
    let colors = (0..n)
        .map(|i| {
            if i % 3 == 0 {
                [200, 40, 30]
            } else {
                [150, 90, 40]
            }
        })
        .collect();
    (points, normals, colors)
}

fn bench(c: &mut Criterion) {
    let params = GpcdParams::default();
    let mut g = c.benchmark_group("gpcd");
    for n in [200, 64] {
        let (points, normals, colors) = half_fruit(n);
        g.bench_function(format!("{n}_points"), |b| {
            b.iter(|| gpcd(&points, &normals, &colors, &params))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
