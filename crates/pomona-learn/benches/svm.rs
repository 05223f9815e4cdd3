//! Training and batched prediction of the RBF C-SVC on fixed-seed data: 2000 samples × 100
//! features (about the size of one detector's candidate set), five negatives per positive.

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_learn::{ClassWeights, Samples, SvmParams, TrainingSet};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn data(n: usize, d: usize, seed: u64) -> TrainingSet {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut values = Vec::with_capacity(n * d);
    let mut labels = Vec::with_capacity(n);
    for i in 0..n {
        let positive = i % 6 == 0;
        let shift = if positive { 0.3 } else { 0.0 };
        for k in 0..d {
            let signal = if k < 10 { shift } else { 0.0 };
            values.push(rng.gen_range(-1.0..1.0) + signal);
        }
        labels.push(positive);
    }
    TrainingSet::new(Samples::new(d, values).unwrap(), labels).unwrap()
}

fn bench(c: &mut Criterion) {
    let train = data(2000, 100, 1);
    let params = SvmParams::default()
        .c(4.0)
        .gamma(0.01)
        .class_weights(ClassWeights::Balanced)
        .check()
        .unwrap();
    let mut group = c.benchmark_group("svm");
    group.sample_size(10);
    group.bench_function("train_2000x100", |b| b.iter(|| params.fit(&train).unwrap()));
    let model = params.fit(&train).unwrap();
    let candidates = data(10_000, 100, 2);
    group.bench_function("predict_10000x100", |b| {
        b.iter(|| model.decision_function(candidates.samples()).unwrap())
    });
    // The detectors' scoring path: a frame's candidates against a symmetry-sized model (168
    // features, about 2000 support vectors), one thread.
    let wide = data(4000, 168, 3);
    let model = params.fit(&wide).unwrap();
    let boxes = data(500, 168, 4);
    let rows: Vec<&[f64]> = (0..boxes.len()).map(|i| boxes.samples().row(i)).collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    group.bench_function(
        format!(
            "decision_values_500x168_{}sv_1_thread",
            model.svm.n_support()
        ),
        |b| b.iter(|| pool.install(|| model.decision_values(&rows).unwrap())),
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
