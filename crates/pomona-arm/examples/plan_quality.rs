//! How close the heuristic planner comes to the optimum: random problems of N targets (default
//! 7) in the cell's working volume, heuristic makespan over the exact one, and timings.
//!
//! `cargo run --release -p pomona-arm --example plan_quality -- [N] [PROBLEMS] [SEED]`

use std::time::Instant;

use pomona_arm::{
    plan_exact, plan_heuristic, random_targets, ArmError, MotionModel, PlanProblem, TwoArmCell,
};
use rand::{RngCore, SeedableRng};

fn arg(i: usize, default: u64) -> Result<u64, String> {
    std::env::args().nth(i).map_or(Ok(default), |s| {
        s.parse().map_err(|e| format!("argument {i} `{s}`: {e}"))
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n = arg(1, 7)? as usize;
    let problems = arg(2, 500)?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(arg(3, 1)?);
    let (mut ratios, mut exact_ms, mut heuristic_ms) = (Vec::new(), 0.0, 0.0);
    for _ in 0..problems {
        let targets = random_targets(n, rng.next_u64());
        let p = PlanProblem::new(&targets, &TwoArmCell::default(), &MotionModel::default())?;
        let t0 = Instant::now();
        let h = plan_heuristic(&p).makespan_s();
        let t1 = Instant::now();
        let e = match plan_exact(&p) {
            Ok(plan) => plan.makespan_s(),
            Err(ArmError::TooManyForExact { .. }) => continue,
            Err(e) => return Err(e.into()),
        };
        heuristic_ms += (t1 - t0).as_secs_f64() * 1e3;
        exact_ms += t1.elapsed().as_secs_f64() * 1e3;
        if e > 0.0 {
            ratios.push(h / e);
        }
    }
    ratios.sort_by(f64::total_cmp);
    let k = ratios.len().max(1) as f64;
    let at_optimum = ratios.iter().filter(|&&r| r <= 1.0 + 1e-9).count();
    println!(
        "{} problems of {n} targets: heuristic / optimum makespan mean {:.4}, median {:.4}, \
         worst {:.4}; optimal in {at_optimum}; mean time heuristic {:.3} ms, exact {:.3} ms",
        ratios.len(),
        ratios.iter().sum::<f64>() / k,
        ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN),
        ratios.last().copied().unwrap_or(f64::NAN),
        heuristic_ms / k,
        exact_ms / k,
    );
    Ok(())
}
