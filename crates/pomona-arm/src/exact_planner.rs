//! The exact planner, for checking the heuristic on small problems: every split of the targets
//! both arms reach, each arm's best closed tour from home by Held–Karp dynamic programming over
//! subsets of the targets it reaches, and the split with the smallest (makespan, total).
//!
//! Cost O(2^k · k²) per arm for the k targets it reaches, plus one lookup per split; limited to
//! [`MAX_EXACT_TARGETS`] reachable targets.

use crate::{Arm, ArmError, PickPlan, PlanProblem};

/// Most reachable targets [`plan_exact`] accepts (2^14 · 14² ≈ 3 M steps per arm).
pub const MAX_EXACT_TARGETS: usize = 14;

/// Best closed tours from home over every subset of `targets` for one arm: `cost[mask]` and the
/// predecessor table to rebuild the order.
struct HeldKarp {
    targets: Vec<usize>,
    /// `parent[mask * k + last]`: the target before `last` on the shortest path from home
    /// visiting `mask` and ending at `last`.
    parent: Vec<usize>,
    /// Closed-tour time (back home, picks included) per mask, and its last target.
    tour: Vec<(f64, usize)>,
}

impl HeldKarp {
    fn new(p: &PlanProblem, arm: Arm, targets: Vec<usize>) -> Self {
        let k = targets.len();
        let h = p.home();
        let full = 1usize << k;
        // best[mask * k + last]: shortest path from home visiting `mask`, ending at `last`.
        let mut best = vec![f64::INFINITY; full * k];
        let mut parent = vec![usize::MAX; full * k];
        for (i, &t) in targets.iter().enumerate() {
            best[(1 << i) * k + i] = p.leg_s(arm, h, t);
        }
        for mask in 1..full {
            for last in 0..k {
                let here = best[mask * k + last];
                if mask & (1 << last) == 0 || !here.is_finite() {
                    continue;
                }
                for next in 0..k {
                    if mask & (1 << next) != 0 {
                        continue;
                    }
                    let m2 = mask | (1 << next);
                    let c = here + p.leg_s(arm, targets[last], targets[next]);
                    if c < best[m2 * k + next] {
                        best[m2 * k + next] = c;
                        parent[m2 * k + next] = last;
                    }
                }
            }
        }
        let tour = (0..full)
            .map(|mask| {
                if mask == 0 {
                    return (0.0, usize::MAX);
                }
                let picks = mask.count_ones() as f64 * p.pick_s();
                (0..k)
                    .filter(|&l| mask & (1 << l) != 0)
                    .map(|l| (best[mask * k + l] + p.leg_s(arm, targets[l], h) + picks, l))
                    .fold(
                        (f64::INFINITY, usize::MAX),
                        |a, b| if b.0 < a.0 { b } else { a },
                    )
            })
            .collect();
        Self {
            targets,
            parent,
            tour,
        }
    }

    /// The order of the best tour over `mask`.
    fn route(&self, mask: usize) -> Vec<usize> {
        let k = self.targets.len();
        let mut out = Vec::new();
        let (mut mask, mut last) = (mask, self.tour[mask].1);
        while mask != 0 && last != usize::MAX {
            out.push(self.targets[last]);
            let prev = self.parent[mask * k + last];
            mask &= !(1 << last);
            last = prev;
        }
        out.reverse();
        out
    }
}

/// The optimal plan of a small problem (see the module docs).
///
/// # Errors
/// [`ArmError::TooManyForExact`] with more than [`MAX_EXACT_TARGETS`] reachable targets.
pub fn plan_exact(problem: &PlanProblem) -> Result<PickPlan, ArmError> {
    let reachable: Vec<usize> = (0..problem.len())
        .filter(|&t| Arm::BOTH.iter().any(|&a| problem.reaches(t, a)))
        .collect();
    if reachable.len() > MAX_EXACT_TARGETS {
        return Err(ArmError::TooManyForExact {
            got: reachable.len(),
            max: MAX_EXACT_TARGETS,
        });
    }
    let per_arm = |arm: Arm| -> Vec<usize> {
        reachable
            .iter()
            .copied()
            .filter(|&t| problem.reaches(t, arm))
            .collect()
    };
    let hk = Arm::BOTH.map(|arm| HeldKarp::new(problem, arm, per_arm(arm)));
    // Bit of each target in each arm's subset numbering.
    let bit = |arm: usize, t: usize| hk[arm].targets.iter().position(|&x| x == t).map(|i| 1 << i);
    let shared: Vec<usize> = reachable
        .iter()
        .copied()
        .filter(|&t| Arm::BOTH.iter().all(|&a| problem.reaches(t, a)))
        .collect();
    let base = |arm: usize| -> usize {
        reachable
            .iter()
            .filter(|&&t| !shared.contains(&t))
            .filter_map(|&t| bit(arm, t))
            .sum()
    };
    let (base_a, base_b) = (base(0), base(1));
    let mut best: Option<((f64, f64), usize, usize)> = None;
    for split in 0..(1usize << shared.len()) {
        let (mut ma, mut mb) = (base_a, base_b);
        for (s, &t) in shared.iter().enumerate() {
            if split & (1 << s) != 0 {
                ma |= bit(0, t).unwrap_or(0);
            } else {
                mb |= bit(1, t).unwrap_or(0);
            }
        }
        let (ta, tb) = (hk[0].tour[ma].0, hk[1].tour[mb].0);
        let k = (ta.max(tb), ta + tb);
        if best.is_none_or(|(bk, ..)| k.0 < bk.0 || (k.0 == bk.0 && k.1 < bk.1)) {
            best = Some((k, ma, mb));
        }
    }
    let (ma, mb) = best.map_or((0, 0), |(_, a, b)| (a, b));
    Ok(problem.plan([hk[0].route(ma), hk[1].route(mb)]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{plan_heuristic, MotionModel, Target, TwoArmCell};
    use nalgebra::Point3;

    fn random_problem(seed: u64, n: usize) -> PlanProblem {
        let targets = crate::random_targets(n, seed);
        PlanProblem::new(&targets, &TwoArmCell::default(), &MotionModel::default()).unwrap()
    }

    #[test]
    fn exact_plans_are_valid_and_their_times_add_up() {
        for seed in 0..20 {
            let p = random_problem(seed, 7);
            let plan = plan_exact(&p).unwrap();
            assert!(plan.is_valid_for(&p), "seed {seed}: {plan:?}");
            for arm in Arm::BOTH {
                let t = p.route_s(arm, &plan.routes[arm.index()]);
                assert!((t - plan.time_s[arm.index()]).abs() < 1e-9);
            }
        }
    }

    /// The target: the heuristic within 5 % of the optimum on 7-target problems.
    #[test]
    fn heuristic_is_within_five_percent_of_the_optimum_on_seven_targets() {
        let mut worst: f64 = 1.0;
        for seed in 0..200 {
            let p = random_problem(seed, 7);
            let exact = plan_exact(&p).unwrap().makespan_s();
            let heuristic = plan_heuristic(&p).makespan_s();
            assert!(heuristic >= exact - 1e-9, "seed {seed}: beat the optimum?");
            if exact > 0.0 {
                worst = worst.max(heuristic / exact);
            }
        }
        assert!(worst <= 1.05, "worst ratio {worst}");
    }

    #[test]
    fn exact_on_a_line_visits_in_order() {
        // Three targets straight ahead of A, out of B's reach (B sees them beyond −40°): only
        // the link moves, so the best tour goes out and back once.
        let targets: Vec<Target> = [0.4, 0.7, 0.6]
            .iter()
            .enumerate()
            .map(|(i, &z)| Target {
                id: i.to_string(),
                center_m: Point3::new(0.0, 0.0, z),
            })
            .collect();
        let p =
            PlanProblem::new(&targets, &TwoArmCell::default(), &MotionModel::default()).unwrap();
        let plan = plan_exact(&p).unwrap();
        let mut route = plan.routes[0].clone();
        route.sort_unstable();
        assert_eq!(
            (route, plan.routes[1].len()),
            (vec![0, 1, 2], 0),
            "{plan:?}"
        );
        // The link travels 0.8 m in all at 0.5 m/s (e.g. 0.3 → 0.7 → 0.3 m, or 0.3 → 0.6 →
        // 0.7 → 0.4 → 0.3 m: several orders tie), plus three 2 s picks.
        assert!(
            (plan.time_s[0] - (0.8 / 0.5 + 6.0)).abs() < 1e-9,
            "{plan:?}"
        );
    }

    #[test]
    fn too_many_targets_is_an_error() {
        let targets: Vec<Target> = (0..=MAX_EXACT_TARGETS)
            .map(|i| Target {
                id: i.to_string(),
                center_m: Point3::new(-0.2 + 0.02 * i as f64, 0.0, 0.6),
            })
            .collect();
        let p =
            PlanProblem::new(&targets, &TwoArmCell::default(), &MotionModel::default()).unwrap();
        assert!(p.unreachable().is_empty());
        assert!(matches!(
            plan_exact(&p),
            Err(ArmError::TooManyForExact { got, max: MAX_EXACT_TARGETS }) if got == MAX_EXACT_TARGETS + 1
        ));
    }
}
