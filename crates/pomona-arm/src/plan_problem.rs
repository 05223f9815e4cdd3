//! A pick-planning problem (targets, which arm reaches each and with which joints, travel
//! times) and its solution, a [`PickPlan`]; with the JSON forms `pomona plan` reads and writes.

use std::collections::{BTreeMap, HashSet};

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::{ArmError, ArmJoints, MotionModel, TwoArmCell};

/// One fruit to pick, in arm A's hub frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Target {
    /// Identifier, unique in the list.
    pub id: String,
    /// Fruit centre in arm A's hub frame, metres.
    pub center_m: Point3<f64>,
}

/// The input of `pomona plan`: `{"targets": [{"id": "...", "center_m": [x, y, z]}, ...]}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TargetList {
    /// The targets.
    pub targets: Vec<Target>,
}

/// One of the cell's two arms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Arm {
    /// The arm whose hub frame the targets are given in.
    A,
    /// The second arm.
    B,
}

impl Arm {
    /// Both arms, A first.
    pub const BOTH: [Arm; 2] = [Arm::A, Arm::B];

    /// 0 for A, 1 for B.
    pub fn index(self) -> usize {
        match self {
            Arm::A => 0,
            Arm::B => 1,
        }
    }
}

/// Targets with their reach and the travel times between them, per arm. Position `n` (the number
/// of targets) in the time tables is the arm's home pose.
#[derive(Debug, Clone)]
pub struct PlanProblem {
    ids: Vec<String>,
    reach: Vec<[Option<ArmJoints>; 2]>,
    /// Per arm, `(n + 1)²` move times (row-major; `f64::INFINITY` where an end is unreachable).
    move_s: [Vec<f64>; 2],
    pick_s: f64,
}

impl PlanProblem {
    /// Builds the problem: reach of every target by each arm of `cell`, and every move time
    /// under `motion`, both arms starting and ending at [`ArmJoints::home`].
    ///
    /// # Errors
    /// [`ArmError::NonFiniteTarget`], [`ArmError::DuplicateId`], and invalid limits or motion.
    pub fn new(
        targets: &[Target],
        cell: &TwoArmCell,
        motion: &MotionModel,
    ) -> Result<Self, ArmError> {
        cell.limits.validate()?;
        motion.validate()?;
        let mut seen = HashSet::new();
        for t in targets {
            if !t.center_m.coords.iter().all(|v| v.is_finite()) {
                return Err(ArmError::NonFiniteTarget { id: t.id.clone() });
            }
            if !seen.insert(t.id.as_str()) {
                return Err(ArmError::DuplicateId { id: t.id.clone() });
            }
        }
        let reach: Vec<[Option<ArmJoints>; 2]> =
            targets.iter().map(|t| cell.reach(&t.center_m)).collect();
        let n = targets.len();
        let pose = |arm: usize, i: usize| {
            if i == n {
                Some(ArmJoints::home())
            } else {
                reach[i][arm]
            }
        };
        let table = |arm: usize| {
            let mut m = vec![f64::INFINITY; (n + 1) * (n + 1)];
            for i in 0..=n {
                for j in 0..=n {
                    if let (Some(a), Some(b)) = (pose(arm, i), pose(arm, j)) {
                        m[i * (n + 1) + j] = motion.move_s(&a, &b);
                    }
                }
            }
            m
        };
        Ok(Self {
            ids: targets.iter().map(|t| t.id.clone()).collect(),
            move_s: [table(0), table(1)],
            reach,
            pick_s: motion.pick_s,
        })
    }

    /// Number of targets.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Whether there are no targets.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Target ids, in input order.
    pub fn ids(&self) -> &[String] {
        &self.ids
    }

    /// The joints with which `arm` reaches target `t`, `None` when it cannot.
    pub fn joints(&self, t: usize, arm: Arm) -> Option<ArmJoints> {
        self.reach.get(t).and_then(|r| r[arm.index()])
    }

    /// Whether `arm` reaches target `t`.
    pub fn reaches(&self, t: usize, arm: Arm) -> bool {
        self.joints(t, arm).is_some()
    }

    /// Targets no arm reaches, in input order.
    pub fn unreachable(&self) -> Vec<usize> {
        (0..self.len())
            .filter(|&t| Arm::BOTH.iter().all(|&a| !self.reaches(t, a)))
            .collect()
    }

    /// The home pose's index in [`PlanProblem::leg_s`].
    pub fn home(&self) -> usize {
        self.len()
    }

    /// Seconds for `arm` to move from `i` to `j` (target indices, or [`PlanProblem::home`]).
    pub fn leg_s(&self, arm: Arm, i: usize, j: usize) -> f64 {
        let n = self.len() + 1;
        self.move_s[arm.index()][i * n + j]
    }

    /// Seconds per pick.
    pub fn pick_s(&self) -> f64 {
        self.pick_s
    }

    /// Seconds for `arm` to leave home, pick `route` in order and return home.
    pub fn route_s(&self, arm: Arm, route: &[usize]) -> f64 {
        let h = self.home();
        let mut t = 0.0;
        let mut at = h;
        for &next in route {
            t += self.leg_s(arm, at, next) + self.pick_s;
            at = next;
        }
        t + self.leg_s(arm, at, h)
    }

    /// The plan with these routes, its times computed.
    pub fn plan(&self, routes: [Vec<usize>; 2]) -> PickPlan {
        let time_s = [
            self.route_s(Arm::A, &routes[0]),
            self.route_s(Arm::B, &routes[1]),
        ];
        PickPlan {
            routes,
            unreachable: self.unreachable(),
            time_s,
        }
    }
}

/// Which arm picks what, in which order, and how long each arm takes.
#[derive(Debug, Clone, PartialEq)]
pub struct PickPlan {
    /// Per arm (A, B), target indices in picking order.
    pub routes: [Vec<usize>; 2],
    /// Targets no arm reaches.
    pub unreachable: Vec<usize>,
    /// Per arm, seconds from leaving home to returning.
    pub time_s: [f64; 2],
}

impl PickPlan {
    /// The time the later arm finishes, seconds.
    pub fn makespan_s(&self) -> f64 {
        self.time_s[0].max(self.time_s[1])
    }

    /// Whether every reachable target is picked exactly once by an arm that reaches it.
    pub fn is_valid_for(&self, problem: &PlanProblem) -> bool {
        let mut count = vec![0usize; problem.len()];
        for (arm, route) in Arm::BOTH.iter().zip(&self.routes) {
            for &t in route {
                if t >= problem.len() || !problem.reaches(t, *arm) {
                    return false;
                }
                count[t] += 1;
            }
        }
        (0..problem.len()).all(|t| {
            let reachable = Arm::BOTH.iter().any(|&a| problem.reaches(t, a));
            count[t] == usize::from(reachable)
        })
    }

    /// The JSON form `pomona plan` writes, with target ids.
    pub fn to_file(&self, problem: &PlanProblem) -> PlanFile {
        let ids =
            |v: &[usize]| -> Vec<String> { v.iter().map(|&t| problem.ids()[t].clone()).collect() };
        PlanFile {
            arms: BTreeMap::from([
                ("a".to_owned(), ids(&self.routes[0])),
                ("b".to_owned(), ids(&self.routes[1])),
            ]),
            unreachable: ids(&self.unreachable),
            makespan_s: self.makespan_s(),
            time_s: BTreeMap::from([
                ("a".to_owned(), self.time_s[0]),
                ("b".to_owned(), self.time_s[1]),
            ]),
        }
    }
}

/// `{"arms": {"a": [ids], "b": [ids]}, "unreachable": [ids], "makespan_s": s, "time_s": {"a": s,
/// "b": s}}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanFile {
    /// Target ids per arm, in picking order.
    pub arms: BTreeMap<String, Vec<String>>,
    /// Targets no arm reaches.
    pub unreachable: Vec<String>,
    /// The later arm's finishing time, seconds.
    pub makespan_s: f64,
    /// Each arm's time, seconds.
    pub time_s: BTreeMap<String, f64>,
}
