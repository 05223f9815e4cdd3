//! Planning time of `plan_heuristic` on 40 targets (the issue's ≤ 10 ms target), fixed seed:
//! `cargo bench -p pomona-arm --bench plan`.

#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_arm::{plan_heuristic, random_targets, MotionModel, PlanProblem, TwoArmCell};

fn bench(c: &mut Criterion) {
    let t = random_targets(40, 7);
    c.bench_function("plan_heuristic_40_targets", |b| {
        b.iter(|| {
            let p = PlanProblem::new(&t, &TwoArmCell::default(), &MotionModel::default());
            p.map(|p| plan_heuristic(&p).makespan_s())
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
