//! Matching and AP over 10 000 detections (100 frames × 100 detections, 20 fruit per frame),
//! fixed seed.

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_core::nalgebra::Point3;
use pomona_core::{Detection, FrameTruth, FruitTruth, PinholeCamera};
use pomona_eval::{evaluate, EvalConfig, FrameInput, PrCurve};

/// A small deterministic generator (SplitMix64) so the bench needs no RNG crate.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) as f64 / u64::MAX as f64
    }
}

fn frames() -> Vec<FrameInput> {
    let mut rng = SplitMix(42);
    (0..100)
        .map(|f| {
            let fruits: Vec<FruitTruth> = (0..20)
                .map(|i| FruitTruth {
                    id: i.to_string(),
                    kind: "pepper".into(),
                    center_m: Some(Point3::new(
                        rng.next() - 0.5,
                        rng.next() - 0.5,
                        0.5 + rng.next(),
                    )),
                    diameter_m: Some(0.08),
                    axis: None,
                    bbox_px: None,
                    center_px: None,
                    radius_px: None,
                    visibility: Some(rng.next()),
                    extra: Default::default(),
                })
                .collect();
            let detections = (0..100)
                .map(|k| {
                    let near = fruits[k % 20].center_m.unwrap();
                    let jitter = if k % 3 == 0 { 0.02 } else { 0.3 };
                    let center_m = near
                        + pomona_core::nalgebra::Vector3::new(
                            jitter * (rng.next() - 0.5),
                            jitter * (rng.next() - 0.5),
                            jitter * (rng.next() - 0.5),
                        );
                    let score = rng.next() * 4.0 - 2.0;
                    Detection {
                        diameter_m: Some(0.07 + 0.02 * rng.next()),
                        ..Detection::new(center_m, score)
                    }
                })
                .collect();
            FrameInput {
                frame: format!("{f:04}"),
                truth: FrameTruth {
                    complete: true,
                    fruits,
                    extra: Default::default(),
                },
                detections,
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let frames = frames();
    let cam = PinholeCamera::new(640, 480, 525.0, 525.0, 319.5, 239.5).unwrap();
    let config = EvalConfig::default();
    c.bench_function("evaluate_10k_detections", |b| {
        b.iter(|| evaluate(&frames, &cam, &config).unwrap())
    });
    let mut rng = SplitMix(7);
    let scored: Vec<(f64, bool)> = (0..10_000)
        .map(|_| (rng.next(), rng.next() < 0.3))
        .collect();
    c.bench_function("pr_curve_ap_10k", |b| {
        b.iter(|| {
            let curve = PrCurve::new(&scored, 3000);
            (curve.ap_voc11(), curve.ap_all_points())
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
