//! Sequential minimal optimisation for the C-SVC dual, as LIBSVM's `Solver`:
//!
//! ```text
//! min ½ αᵀQα − eᵀα   subject to   yᵀα = 0,   0 ≤ αᵢ ≤ Cᵢ
//! ```
//!
//! Each iteration picks the pair `(i, j)` by second-order working-set selection (WSS3 of Fan,
//! Chen & Lin 2005: `i` maximises the violation, `j` the guaranteed decrease of the objective),
//! solves the two-variable sub-problem analytically with LIBSVM's clipping, and updates the
//! gradient. It stops when the maximal violation `m(α) − M(α)` falls below `eps` (LIBSVM's
//! `-e`, default 1e-3).
//!
//! With shrinking (LIBSVM's `-h 1`), variables stuck at a bound are periodically moved out of
//! the active set and the gradient is rebuilt from `Ḡ` (the bound variables' contribution) before
//! the final optimality check. Variables are permuted exactly as LIBSVM swaps them, so every
//! branch and tie-break — and hence the iterates — match LIBSVM. Kernel columns stay in the
//! original sample order; a position→sample map reads them.

use crate::kernel_cache::QMatrix;

/// LIBSVM's `TAU`: replaces a non-positive curvature.
const TAU: f64 = 1e-12;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Bound {
    Lower,
    Upper,
    Free,
}

/// Result of a solve.
pub(crate) struct SolverOutput {
    /// Dual variables, in the caller's sample order.
    pub alpha: Vec<f64>,
    /// Bias: decision is `Σ yᵢ αᵢ K(xᵢ, x) − rho`.
    pub rho: f64,
    /// Dual objective value.
    pub objective: f64,
    /// Iterations performed.
    pub iterations: usize,
    /// Whether the stopping criterion was met (rather than the iteration limit).
    pub converged: bool,
}

fn bound_of(alpha: f64, c: f64) -> Bound {
    if alpha >= c {
        Bound::Upper
    } else if alpha <= 0.0 {
        Bound::Lower
    } else {
        Bound::Free
    }
}

/// Solver state, indexed by *position*; `sample[k]` is the sample at position `k`.
struct Solver<'q, 'a> {
    q: &'q mut QMatrix<'a>,
    y: Vec<f64>,
    c: Vec<f64>,
    qd: Vec<f64>,
    alpha: Vec<f64>,
    status: Vec<Bound>,
    g: Vec<f64>,
    g_bar: Vec<f64>,
    sample: Vec<usize>,
    active: usize,
    eps: f64,
    shrinking: bool,
    unshrink: bool,
}

/// Solves the dual with labels `y` (±1), per-sample bounds `c`, tolerance `eps`.
pub(crate) fn solve(
    q: &mut QMatrix<'_>,
    y: &[f64],
    c: &[f64],
    eps: f64,
    shrinking: bool,
) -> SolverOutput {
    let l = y.len();
    let qd = q.diagonal().to_vec();
    let mut s = Solver {
        q,
        y: y.to_vec(),
        c: c.to_vec(),
        qd,
        alpha: vec![0.0; l],
        status: (0..l).map(|i| bound_of(0.0, c[i])).collect(),
        // Gradient Qα + p with p = −e; α = 0 initially, so Ḡ = 0 too.
        g: vec![-1.0; l],
        g_bar: vec![0.0; l],
        sample: (0..l).collect(),
        active: l,
        eps,
        shrinking,
        unshrink: false,
    };
    let (iterations, converged) = s.run();
    let rho = s.calculate_rho();
    let objective = s
        .alpha
        .iter()
        .zip(&s.g)
        .map(|(a, gk)| a * (gk - 1.0))
        .sum::<f64>()
        / 2.0;
    let mut alpha = vec![0.0; l];
    for (k, &a) in s.alpha.iter().enumerate() {
        alpha[s.sample[k]] = a;
    }
    SolverOutput {
        alpha,
        rho,
        objective,
        iterations,
        converged,
    }
}

impl Solver<'_, '_> {
    fn l(&self) -> usize {
        self.y.len()
    }

    fn run(&mut self) -> (usize, bool) {
        let l = self.l();
        let max_iter = 10_000_000usize.max(l.saturating_mul(100));
        let mut counter = l.min(1000) + 1;
        let mut iter = 0;
        while iter < max_iter {
            counter -= 1;
            if counter == 0 {
                counter = l.min(1000);
                if self.shrinking {
                    self.do_shrinking();
                }
            }
            let (i, j) = match self.select_working_set() {
                Some(pair) => pair,
                None => {
                    // Optimal on the active set: rebuild the full gradient and check all.
                    self.reconstruct_gradient();
                    self.active = l;
                    match self.select_working_set() {
                        Some(pair) => {
                            counter = 1; // shrink again at the next iteration
                            pair
                        }
                        None => return (iter, true),
                    }
                }
            };
            iter += 1;
            self.update_pair(i, j);
        }
        if self.active < l {
            self.reconstruct_gradient();
            self.active = l;
        }
        (iter, false)
    }

    fn update_pair(&mut self, i: usize, j: usize) {
        let col_i = self.q.column(self.sample[i]);
        let col_j = self.q.column(self.sample[j]);
        let q_ij = f64::from(col_i[self.sample[j]]);
        let (c_i, c_j) = (self.c[i], self.c[j]);
        let (old_i, old_j) = (self.alpha[i], self.alpha[j]);
        let (qd, g, alpha) = (&self.qd, &self.g, &mut self.alpha);

        if self.y[i] != self.y[j] {
            let mut quad = qd[i] + qd[j] + 2.0 * q_ij;
            if quad <= 0.0 {
                quad = TAU;
            }
            let delta = (-g[i] - g[j]) / quad;
            let diff = alpha[i] - alpha[j];
            alpha[i] += delta;
            alpha[j] += delta;
            if diff > 0.0 {
                if alpha[j] < 0.0 {
                    alpha[j] = 0.0;
                    alpha[i] = diff;
                }
            } else if alpha[i] < 0.0 {
                alpha[i] = 0.0;
                alpha[j] = -diff;
            }
            if diff > c_i - c_j {
                if alpha[i] > c_i {
                    alpha[i] = c_i;
                    alpha[j] = c_i - diff;
                }
            } else if alpha[j] > c_j {
                alpha[j] = c_j;
                alpha[i] = c_j + diff;
            }
        } else {
            let mut quad = qd[i] + qd[j] - 2.0 * q_ij;
            if quad <= 0.0 {
                quad = TAU;
            }
            let delta = (g[i] - g[j]) / quad;
            let sum = alpha[i] + alpha[j];
            alpha[i] -= delta;
            alpha[j] += delta;
            if sum > c_i {
                if alpha[i] > c_i {
                    alpha[i] = c_i;
                    alpha[j] = sum - c_i;
                }
            } else if alpha[j] < 0.0 {
                alpha[j] = 0.0;
                alpha[i] = sum;
            }
            if sum > c_j {
                if alpha[j] > c_j {
                    alpha[j] = c_j;
                    alpha[i] = sum - c_j;
                }
            } else if alpha[i] < 0.0 {
                alpha[i] = 0.0;
                alpha[j] = sum;
            }
        }

        let d_i = self.alpha[i] - old_i;
        let d_j = self.alpha[j] - old_j;
        for k in 0..self.active {
            let sk = self.sample[k];
            self.g[k] += f64::from(col_i[sk]) * d_i + f64::from(col_j[sk]) * d_j;
        }

        let was_upper_i = self.status[i] == Bound::Upper;
        let was_upper_j = self.status[j] == Bound::Upper;
        self.status[i] = bound_of(self.alpha[i], c_i);
        self.status[j] = bound_of(self.alpha[j], c_j);
        if self.shrinking {
            // Ḡ = Σ over upper-bound variables of Cⱼ Q[:, j]; only needed to un-shrink.
            for (pos, was_upper, col, c) in
                [(i, was_upper_i, &col_i, c_i), (j, was_upper_j, &col_j, c_j)]
            {
                let now_upper = self.status[pos] == Bound::Upper;
                if was_upper != now_upper {
                    let sign = if was_upper { -c } else { c };
                    for k in 0..self.l() {
                        self.g_bar[k] += sign * f64::from(col[self.sample[k]]);
                    }
                }
            }
        }
    }

    /// WSS3 over the active set; `None` when the maximal violation is below `eps`.
    fn select_working_set(&mut self) -> Option<(usize, usize)> {
        let (y, g, status, qd) = (&self.y, &self.g, &self.status, &self.qd);
        let mut gmax = f64::NEG_INFINITY;
        let mut gmax2 = f64::NEG_INFINITY;
        let mut gmax_idx = None;
        for t in 0..self.active {
            if y[t] > 0.0 {
                if status[t] != Bound::Upper && -g[t] >= gmax {
                    gmax = -g[t];
                    gmax_idx = Some(t);
                }
            } else if status[t] != Bound::Lower && g[t] >= gmax {
                gmax = g[t];
                gmax_idx = Some(t);
            }
        }
        let col_i = gmax_idx.map(|i| self.q.column(self.sample[i]));
        let mut gmin_idx = None;
        let mut obj_diff_min = f64::INFINITY;
        for j in 0..self.active {
            let q_ij = col_i.as_ref().map_or(0.0, |c| f64::from(c[self.sample[j]]));
            let yi = gmax_idx.map_or(0.0, |i| y[i]);
            let qdi = gmax_idx.map_or(0.0, |i| qd[i]);
            let (grad_diff, quad) = if y[j] > 0.0 {
                if status[j] == Bound::Lower {
                    continue;
                }
                if g[j] >= gmax2 {
                    gmax2 = g[j];
                }
                (gmax + g[j], qdi + qd[j] - 2.0 * yi * q_ij)
            } else {
                if status[j] == Bound::Upper {
                    continue;
                }
                if -g[j] >= gmax2 {
                    gmax2 = -g[j];
                }
                (gmax - g[j], qdi + qd[j] + 2.0 * yi * q_ij)
            };
            if grad_diff > 0.0 {
                let obj_diff = if quad > 0.0 {
                    -(grad_diff * grad_diff) / quad
                } else {
                    -(grad_diff * grad_diff) / TAU
                };
                if obj_diff <= obj_diff_min {
                    gmin_idx = Some(j);
                    obj_diff_min = obj_diff;
                }
            }
        }
        if gmax + gmax2 < self.eps {
            return None;
        }
        match (gmax_idx, gmin_idx) {
            (Some(i), Some(j)) => Some((i, j)),
            _ => None,
        }
    }

    fn be_shrunk(&self, i: usize, gmax1: f64, gmax2: f64) -> bool {
        let (y, g) = (self.y[i], self.g[i]);
        match self.status[i] {
            Bound::Upper => {
                if y > 0.0 {
                    -g > gmax1
                } else {
                    -g > gmax2
                }
            }
            Bound::Lower => {
                if y > 0.0 {
                    g > gmax2
                } else {
                    g > gmax1
                }
            }
            Bound::Free => false,
        }
    }

    fn swap_index(&mut self, i: usize, j: usize) {
        self.y.swap(i, j);
        self.c.swap(i, j);
        self.qd.swap(i, j);
        self.alpha.swap(i, j);
        self.status.swap(i, j);
        self.g.swap(i, j);
        self.g_bar.swap(i, j);
        self.sample.swap(i, j);
    }

    fn do_shrinking(&mut self) {
        let mut gmax1 = f64::NEG_INFINITY; // max { −yᵢ∇ᵢ | i ∈ I_up }
        let mut gmax2 = f64::NEG_INFINITY; // max { yᵢ∇ᵢ | i ∈ I_low }
        for i in 0..self.active {
            let (g, st) = (self.g[i], self.status[i]);
            if self.y[i] > 0.0 {
                if st != Bound::Upper && -g >= gmax1 {
                    gmax1 = -g;
                }
                if st != Bound::Lower && g >= gmax2 {
                    gmax2 = g;
                }
            } else {
                if st != Bound::Upper && -g >= gmax2 {
                    gmax2 = -g;
                }
                if st != Bound::Lower && g >= gmax1 {
                    gmax1 = g;
                }
            }
        }
        if !self.unshrink && gmax1 + gmax2 <= self.eps * 10.0 {
            self.unshrink = true;
            self.reconstruct_gradient();
            self.active = self.l();
        }
        let mut i = 0;
        while i < self.active {
            if self.be_shrunk(i, gmax1, gmax2) {
                self.active -= 1;
                while self.active > i {
                    if !self.be_shrunk(self.active, gmax1, gmax2) {
                        self.swap_index(i, self.active);
                        break;
                    }
                    self.active -= 1;
                }
            }
            i += 1;
        }
    }

    /// Rebuilds the gradient of inactive variables from `Ḡ` and the free variables.
    fn reconstruct_gradient(&mut self) {
        let l = self.l();
        let active = self.active;
        if active == l {
            return;
        }
        for j in active..l {
            self.g[j] = self.g_bar[j] - 1.0;
        }
        let n_free = (0..active)
            .filter(|&j| self.status[j] == Bound::Free)
            .count();
        if n_free * l > 2 * active * (l - active) {
            for i in active..l {
                let col = self.q.column(self.sample[i]);
                for j in 0..active {
                    if self.status[j] == Bound::Free {
                        self.g[i] += self.alpha[j] * f64::from(col[self.sample[j]]);
                    }
                }
            }
        } else {
            for i in 0..active {
                if self.status[i] == Bound::Free {
                    let col = self.q.column(self.sample[i]);
                    let a = self.alpha[i];
                    for j in active..l {
                        self.g[j] += a * f64::from(col[self.sample[j]]);
                    }
                }
            }
        }
    }

    /// LIBSVM's bias: the mean of `yᵢ∇ᵢ` over free variables, else the midpoint of the feasible
    /// interval.
    fn calculate_rho(&self) -> f64 {
        let mut ub = f64::INFINITY;
        let mut lb = f64::NEG_INFINITY;
        let mut n_free = 0usize;
        let mut sum_free = 0.0;
        for t in 0..self.active {
            let yg = self.y[t] * self.g[t];
            match self.status[t] {
                Bound::Upper => {
                    if self.y[t] < 0.0 {
                        ub = ub.min(yg);
                    } else {
                        lb = lb.max(yg);
                    }
                }
                Bound::Lower => {
                    if self.y[t] > 0.0 {
                        ub = ub.min(yg);
                    } else {
                        lb = lb.max(yg);
                    }
                }
                Bound::Free => {
                    n_free += 1;
                    sum_free += yg;
                }
            }
        }
        if n_free > 0 {
            sum_free / n_free as f64
        } else {
            (ub + lb) / 2.0
        }
    }
}
