//! The planner `pomona plan` runs: cheapest insertion, then local search (2-opt inside each
//! route, and moving one target to any position of either arm that reaches it) until nothing
//! improves.
//!
//! Plans are compared by makespan first and total time second (so moves that shorten the
//! faster arm without changing the makespan are still taken, which frees room for later moves).
//! Every move is evaluated in O(1) from the move-time tables; a 40-target problem takes
//! well under a millisecond per improvement pass. Deterministic: ties keep the first candidate
//! in index order.

use crate::{Arm, PickPlan, PlanProblem};

/// Improvements smaller than this (seconds) are not taken, so rounding cannot cycle.
const EPS_S: f64 = 1e-9;

/// (makespan, total) of two arm times.
fn key(t: [f64; 2]) -> (f64, f64) {
    (t[0].max(t[1]), t[0] + t[1])
}

fn better(a: (f64, f64), b: (f64, f64)) -> bool {
    a.0 < b.0 - EPS_S || (a.0 <= b.0 + EPS_S && a.1 < b.1 - EPS_S)
}

/// Routes being improved, with their times kept current.
struct Routes<'a> {
    p: &'a PlanProblem,
    routes: [Vec<usize>; 2],
    time_s: [f64; 2],
}

impl Routes<'_> {
    /// The node before position `i` (home at the start) and at position `i` (home past the end).
    fn before(&self, arm: Arm, i: usize) -> usize {
        if i == 0 {
            self.p.home()
        } else {
            self.routes[arm.index()][i - 1]
        }
    }

    fn at(&self, arm: Arm, i: usize) -> usize {
        self.routes[arm.index()]
            .get(i)
            .copied()
            .unwrap_or(self.p.home())
    }

    /// Added time of inserting `t` at position `i` of `arm`'s route.
    fn insertion_s(&self, arm: Arm, t: usize, i: usize) -> f64 {
        let (a, b) = (self.before(arm, i), self.at(arm, i));
        self.p.leg_s(arm, a, t) + self.p.leg_s(arm, t, b) - self.p.leg_s(arm, a, b)
            + self.p.pick_s()
    }

    /// Time saved by removing the target at position `i` of `arm`'s route.
    fn removal_s(&self, arm: Arm, i: usize) -> f64 {
        let (a, t, b) = (self.before(arm, i), self.at(arm, i), self.at(arm, i + 1));
        self.p.leg_s(arm, a, t) + self.p.leg_s(arm, t, b) - self.p.leg_s(arm, a, b)
            + self.p.pick_s()
    }

    fn with(&self, arm: Arm, delta_s: f64) -> [f64; 2] {
        let mut t = self.time_s;
        t[arm.index()] += delta_s;
        t
    }

    /// Inserts `t` where the plan gets best; `false` when no arm reaches it.
    fn insert_best(&mut self, t: usize) -> bool {
        let mut best: Option<((f64, f64), Arm, usize, f64)> = None;
        for arm in Arm::BOTH {
            if !self.p.reaches(t, arm) {
                continue;
            }
            for i in 0..=self.routes[arm.index()].len() {
                let d = self.insertion_s(arm, t, i);
                let k = key(self.with(arm, d));
                if best.is_none_or(|(bk, ..)| better(k, bk)) {
                    best = Some((k, arm, i, d));
                }
            }
        }
        let Some((_, arm, i, d)) = best else {
            return false;
        };
        self.routes[arm.index()].insert(i, t);
        self.time_s[arm.index()] += d;
        true
    }

    /// One improving move of a single target to another position or arm; `true` if one was made.
    fn relocate_once(&mut self) -> bool {
        let current = key(self.time_s);
        for from in Arm::BOTH {
            for i in 0..self.routes[from.index()].len() {
                let t = self.routes[from.index()][i];
                let saved = self.removal_s(from, i);
                let removed = self.routes[from.index()].remove(i);
                let mut times = self.with(from, -saved);
                let mut best: Option<((f64, f64), Arm, usize, f64)> = None;
                for to in Arm::BOTH {
                    if !self.p.reaches(t, to) {
                        continue;
                    }
                    for j in 0..=self.routes[to.index()].len() {
                        let d = self.insertion_s(to, t, j);
                        let mut after = times;
                        after[to.index()] += d;
                        if better(key(after), best.map_or(current, |b| b.0)) {
                            best = Some((key(after), to, j, d));
                        }
                    }
                }
                match best {
                    Some((_, to, j, d)) => {
                        self.routes[to.index()].insert(j, t);
                        times[to.index()] += d;
                        self.time_s = times;
                        return true;
                    }
                    None => self.routes[from.index()].insert(i, removed),
                }
            }
        }
        false
    }

    /// One improving exchange of a target of A with a target of B (each taking the other's
    /// place); `true` if one was made.
    fn swap_once(&mut self) -> bool {
        let current = key(self.time_s);
        let (a, b) = (Arm::A, Arm::B);
        for i in 0..self.routes[0].len() {
            let t = self.routes[0][i];
            if !self.p.reaches(t, b) {
                continue;
            }
            for j in 0..self.routes[1].len() {
                let u = self.routes[1][j];
                if !self.p.reaches(u, a) {
                    continue;
                }
                let replace = |arm: Arm, pos: usize, old: usize, new: usize| {
                    let (x, y) = (self.before(arm, pos), self.at(arm, pos + 1));
                    let leg = |p, q| self.p.leg_s(arm, p, q);
                    leg(x, new) + leg(new, y) - leg(x, old) - leg(old, y)
                };
                let after = [
                    self.time_s[0] + replace(a, i, t, u),
                    self.time_s[1] + replace(b, j, u, t),
                ];
                if better(key(after), current) {
                    self.routes[0][i] = u;
                    self.routes[1][j] = t;
                    self.time_s = after;
                    return true;
                }
            }
        }
        false
    }

    /// One improving 2-opt move (reversing a stretch of one route); `true` if one was made.
    fn two_opt_once(&mut self) -> bool {
        for arm in Arm::BOTH {
            let n = self.routes[arm.index()].len();
            for i in 0..n {
                for j in i + 1..n {
                    // Edges (before i → i) and (j → after j) become (before i → j), (i → after j).
                    let (a, b) = (self.before(arm, i), self.at(arm, i));
                    let (c, d) = (self.at(arm, j), self.at(arm, j + 1));
                    let leg = |x, y| self.p.leg_s(arm, x, y);
                    let delta = leg(a, c) + leg(b, d) - leg(a, b) - leg(c, d);
                    if delta < -EPS_S {
                        self.routes[arm.index()][i..=j].reverse();
                        self.time_s[arm.index()] += delta;
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// Plans the picks of `problem` (see the module docs). Every reachable target is picked once
/// by an arm that reaches it; unreachable ones are listed in the plan.
///
/// ```
/// use pomona_arm::{plan_heuristic, MotionModel, PlanProblem, Target, TwoArmCell};
/// use pomona_core::nalgebra::Point3;
/// let targets: Vec<Target> = [(-0.2, 0.7), (0.1, 0.6), (0.7, 0.8), (0.3, 0.9)]
///     .iter()
///     .enumerate()
///     .map(|(i, &(x, z))| Target { id: i.to_string(), center_m: Point3::new(x, 0.0, z) })
///     .collect();
/// let problem = PlanProblem::new(&targets, &TwoArmCell::default(), &MotionModel::default())?;
/// let plan = plan_heuristic(&problem);
/// assert!(plan.is_valid_for(&problem));
/// assert!(plan.routes[0].len() + plan.routes[1].len() == 4);
/// # Ok::<(), pomona_arm::ArmError>(())
/// ```
pub fn plan_heuristic(problem: &PlanProblem) -> PickPlan {
    let h = problem.home();
    let reach_count = |t: usize| Arm::BOTH.iter().filter(|&&a| problem.reaches(t, a)).count();
    let from_home = |t: usize| {
        Arm::BOTH
            .iter()
            .filter(|&&a| problem.reaches(t, a))
            .map(|&a| problem.leg_s(a, h, t))
            .fold(f64::INFINITY, f64::min)
    };
    let azimuth = |t: usize| {
        Arm::BOTH
            .iter()
            .find_map(|&a| problem.joints(t, a))
            .map_or(0.0, |q| q.alpha_rad)
    };
    // Three insertion orders, each improved by local search; the best plan wins. Hardest first:
    // targets only one arm reaches, then far from home first, so the far-flung ones shape the
    // routes and near ones slot in. Sweep: left to right, so each arm's share is contiguous.
    // And the first order reversed, which escapes the local optima the first one falls into.
    let mut hardest: Vec<usize> = (0..problem.len()).collect();
    hardest.sort_by(|&a, &b| {
        reach_count(a)
            .cmp(&reach_count(b))
            .then(from_home(b).total_cmp(&from_home(a)))
            .then(a.cmp(&b))
    });
    let mut sweep: Vec<usize> = (0..problem.len()).collect();
    sweep.sort_by(|&a, &b| azimuth(a).total_cmp(&azimuth(b)).then(a.cmp(&b)));
    let nearest: Vec<usize> = hardest.iter().rev().copied().collect();
    [hardest, sweep, nearest]
        .into_iter()
        .map(|order| improved(problem, &order))
        .reduce(|x, y| {
            if better(key(y.time_s), key(x.time_s)) {
                y
            } else {
                x
            }
        })
        .map_or_else(
            || problem.plan([Vec::new(), Vec::new()]),
            |r| problem.plan(r.routes),
        )
}

/// Cheapest insertion in `order`, then local search until no move improves.
fn improved<'a>(problem: &'a PlanProblem, order: &[usize]) -> Routes<'a> {
    let mut r = Routes {
        p: problem,
        routes: [Vec::new(), Vec::new()],
        time_s: [0.0, 0.0],
    };
    for &t in order {
        r.insert_best(t);
    }
    while r.two_opt_once() || r.relocate_once() || r.swap_once() {}
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{MotionModel, Target, TwoArmCell};
    use nalgebra::Point3;

    fn problem(points: &[(f64, f64, f64)]) -> PlanProblem {
        let targets: Vec<Target> = points
            .iter()
            .enumerate()
            .map(|(i, &(x, y, z))| Target {
                id: format!("t{i}"),
                center_m: Point3::new(x, y, z),
            })
            .collect();
        PlanProblem::new(&targets, &TwoArmCell::default(), &MotionModel::default()).unwrap()
    }

    #[test]
    fn single_arm_targets_go_to_their_arm_and_far_ones_are_unreachable() {
        // x = −0.4 at z 0.6: only A (B sees it at α ≈ −59°); x = 1.0: only B; z = 3: nobody.
        let p = problem(&[(-0.4, 0.0, 0.6), (1.0, 0.0, 0.6), (0.0, 0.0, 3.0)]);
        let plan = plan_heuristic(&p);
        assert_eq!(plan.routes, [vec![0], vec![1]]);
        assert_eq!(plan.unreachable, vec![2]);
        assert!(plan.is_valid_for(&p));
    }

    #[test]
    fn shared_targets_are_split_to_balance_the_arms() {
        // Four targets in the middle, reachable by both: two each beats four on one arm.
        let p = problem(&[
            (0.3, 0.0, 0.7),
            (0.3, 0.05, 0.75),
            (0.3, -0.05, 0.8),
            (0.3, 0.0, 0.85),
        ]);
        let plan = plan_heuristic(&p);
        assert!(plan.is_valid_for(&p));
        assert_eq!(plan.routes[0].len(), 2, "{plan:?}");
        assert_eq!(plan.routes[1].len(), 2, "{plan:?}");
    }

    #[test]
    fn an_empty_problem_is_an_empty_plan() {
        let plan = plan_heuristic(&problem(&[]));
        assert_eq!(plan.makespan_s(), 0.0);
        assert!(plan.routes.iter().all(Vec::is_empty));
    }
}
