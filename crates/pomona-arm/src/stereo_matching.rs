//! Stereo matching of fruit centres between the two shots (seed 004 §4.1, Eqs. 9–16).
//!
//! Every pair (primary centre l, stereo centre r) that passes the epipolar windows of Eq. 10
//! ([`MatchingWindows`]) enters the L×R disparity matrix ΔX (Eq. 9). A relaxation then
//! reduces it to single matches, on the seed's ground that one scene holds fruit at similar
//! depths: at step n, with the mean disparity of the remaining entries ΔX̄ₙ and the squared
//! deviations σᵢⱼ = (ΔXᵢⱼ − ΔX̄ₙ)² (Eq. 11), mark each row's minima (c, Eq. 13) and each column's
//! minima (r); keep the entries marked in either (Eq. 12, the logical OR) and iterate until the
//! two marks agree (Eq. 14 — then the marked entries are single matches, Eq. 16) or the mean moves
//! by less than ε (Eq. 15).
//!
//! Multiple matches that remain (Eq. 15 stopped first, or exact ties of σ survive Eq. 14) are
//! resolved by the seed's heuristic, which keeps in each row and column the element closest to
//! the mean: entries are taken in increasing σ (ties by primary then stereo index, so results
//! are deterministic) and accepted while their row and column are still free.
//!
//! Beyond the seed, a candidate can be removed before the relaxation
//! ([`DisparityMatrix::remove`]) or carry an extra non-negative cost added to its σ wherever σ is
//! compared (Eq. 13 marks and the heuristic; [`DisparityMatrix::add_cost`]), in pixels²: other
//! evidence than disparity, such as the appearance of the pair ([`crate::PairEvidence`]). The
//! mean disparity of Eq. 11 is unchanged. Without removals or costs the relaxation is the seed's,
//! bit for bit (every extra cost is +0.0, which leaves σ unchanged).

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

use crate::MatchingWindows;

/// Parameters of the relaxation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RelaxationParams {
    /// ε of Eq. 15 in pixels: stop when the mean disparity moves by less. The seed only says
    /// "a small positive number"; the default is 0.01 px.
    pub epsilon_px: f64,
    /// Safety cap on the iterations (each one removes entries or stops, so at most L·R are ever
    /// needed).
    pub max_iterations: usize,
}

impl Default for RelaxationParams {
    fn default() -> Self {
        Self {
            epsilon_px: 0.01,
            max_iterations: 100,
        }
    }
}

/// Why the relaxation stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RelaxationStop {
    /// No candidate pair passed the windows.
    Empty,
    /// Row and column minima agree (Eq. 14).
    MinimaAgree,
    /// The mean disparity settled (Eq. 15).
    MeanSettled,
    /// [`RelaxationParams::max_iterations`] were run.
    IterationCap,
}

/// One matched pair.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StereoPair {
    /// Index into the primary view's centres (the seed's left image, row l).
    pub primary: usize,
    /// Index into the stereo view's centres (right image, column r).
    pub stereo: usize,
    /// Its disparity `u_primary − u_stereo`, pixels.
    pub disparity_px: f64,
}

/// The outcome of matching: single pairs sorted by primary index, and how it went.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StereoMatching {
    /// The matches, at most one per row and per column.
    pub pairs: Vec<StereoPair>,
    /// Relaxation steps run.
    pub iterations: usize,
    /// What ended the relaxation.
    pub stop: RelaxationStop,
    /// The last mean disparity ΔX̄, pixels (0 when empty).
    pub mean_disparity_px: f64,
    /// Pairs chosen by the tie-breaking heuristic rather than by Eq. 14 alone.
    pub resolved_by_heuristic: usize,
}

/// The L×R disparity matrix ΔX of Eq. 9 restricted by Eq. 10: `None` where a pair fails the
/// windows (the seed's zero).
#[derive(Debug, Clone, PartialEq)]
pub struct DisparityMatrix {
    rows: usize,
    cols: usize,
    cells: Vec<Option<f64>>,
    /// Extra cost of each cell added to its σ, pixels² (0 = the seed's relaxation).
    extra: Vec<f64>,
}

impl DisparityMatrix {
    /// A matrix from rows of candidate disparities (`None` = no candidate); rows shorter than
    /// the longest are padded with `None`. For hand-made matrices and tests.
    pub fn from_rows(rows: &[Vec<Option<f64>>]) -> Self {
        let cols = rows.iter().map(Vec::len).max().unwrap_or(0);
        let mut cells = vec![None; rows.len() * cols];
        for (i, row) in rows.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                cells[i * cols + j] = v.filter(|v| v.is_finite());
            }
        }
        Self {
            rows: rows.len(),
            cols,
            extra: vec![0.0; cells.len()],
            cells,
        }
    }

    /// Eqs. 9–10: the disparities of every pair of centres that passes `windows`.
    pub fn from_centres(
        primary: &[Point2<f64>],
        stereo: &[Point2<f64>],
        windows: &MatchingWindows,
    ) -> Self {
        let cells = primary
            .iter()
            .flat_map(|p| stereo.iter().map(|s| windows.disparity_if_admissible(p, s)))
            .collect();
        Self {
            rows: primary.len(),
            cols: stereo.len(),
            extra: vec![0.0; primary.len() * stereo.len()],
            cells,
        }
    }

    /// Removes candidate `(l, r)` (no-op outside the matrix).
    pub fn remove(&mut self, l: usize, r: usize) {
        if l < self.rows && r < self.cols {
            self.cells[l * self.cols + r] = None;
        }
    }

    /// Adds `cost_px2` (pixels², finite and non-negative; anything else is ignored) to the σ of
    /// candidate `(l, r)` wherever the relaxation compares σ.
    pub fn add_cost(&mut self, l: usize, r: usize, cost_px2: f64) {
        if l < self.rows && r < self.cols && cost_px2.is_finite() && cost_px2 >= 0.0 {
            self.extra[l * self.cols + r] += cost_px2;
        }
    }

    /// The extra cost of candidate `(l, r)`, pixels² (0 outside the matrix).
    pub fn cost(&self, l: usize, r: usize) -> f64 {
        if l < self.rows && r < self.cols {
            self.extra[l * self.cols + r]
        } else {
            0.0
        }
    }

    /// Candidates of the matrix: `(l, r, disparity)`.
    pub fn candidates(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        self.entries()
    }

    /// `(L, R)`.
    pub fn shape(&self) -> (usize, usize) {
        (self.rows, self.cols)
    }

    /// Candidate disparity of pair `(l, r)`.
    pub fn get(&self, l: usize, r: usize) -> Option<f64> {
        (l < self.rows && r < self.cols)
            .then(|| self.cells[l * self.cols + r])
            .flatten()
    }

    fn entries(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        self.cells
            .iter()
            .enumerate()
            .filter_map(|(k, v)| v.map(|v| (k / self.cols, k % self.cols, v)))
    }

    fn mean(&self) -> Option<f64> {
        let (sum, n) = self
            .entries()
            .fold((0.0, 0usize), |(s, n), (_, _, v)| (s + v, n + 1));
        (n > 0).then(|| sum / n as f64)
    }

    /// Eq. 13: the row-minimum marks c and column-minimum marks r of σ about `mean`.
    fn minima_marks(&self, mean: f64) -> (Vec<bool>, Vec<bool>) {
        let sigma = |i: usize, j: usize, v: f64| self.sigma(i, j, v, mean);
        let mut row_min = vec![f64::INFINITY; self.rows];
        let mut col_min = vec![f64::INFINITY; self.cols];
        for (i, j, v) in self.entries() {
            row_min[i] = row_min[i].min(sigma(i, j, v));
            col_min[j] = col_min[j].min(sigma(i, j, v));
        }
        let mut c = vec![false; self.cells.len()];
        let mut r = vec![false; self.cells.len()];
        for (i, j, v) in self.entries() {
            let k = i * self.cols + j;
            c[k] = sigma(i, j, v) == row_min[i];
            r[k] = sigma(i, j, v) == col_min[j];
        }
        (c, r)
    }

    /// σ of Eq. 11 for candidate `(i, j)` with disparity `v` about `mean`, plus its extra cost.
    fn sigma(&self, i: usize, j: usize, v: f64, mean: f64) -> f64 {
        (v - mean) * (v - mean) + self.extra[i * self.cols + j]
    }

    /// Runs the relaxation (Eqs. 11–16) and the tie-breaking heuristic.
    pub fn relax(&self, params: &RelaxationParams) -> StereoMatching {
        let mut current = self.clone();
        let Some(mut mean) = current.mean() else {
            return StereoMatching {
                pairs: Vec::new(),
                iterations: 0,
                stop: RelaxationStop::Empty,
                mean_disparity_px: 0.0,
                resolved_by_heuristic: 0,
            };
        };
        let mut stop = RelaxationStop::IterationCap;
        let mut iterations = 0;
        while iterations < params.max_iterations {
            iterations += 1;
            let (c, r) = current.minima_marks(mean);
            if c == r {
                // Eq. 14: keep the marked entries (single matches unless σ ties).
                for (k, cell) in current.cells.iter_mut().enumerate() {
                    if !c[k] {
                        *cell = None;
                    }
                }
                stop = RelaxationStop::MinimaAgree;
                break;
            }
            // Eq. 12: ΔXₙ₊₁ = (c OR r) ∘ ΔXₙ.
            for (k, cell) in current.cells.iter_mut().enumerate() {
                if !(c[k] || r[k]) {
                    *cell = None;
                }
            }
            let Some(next) = current.mean() else {
                break;
            };
            let settled = (next - mean).abs() < params.epsilon_px;
            mean = next;
            if settled {
                stop = RelaxationStop::MeanSettled;
                break;
            }
        }
        let (pairs, resolved_by_heuristic) = current.single_matches(mean);
        StereoMatching {
            pairs,
            iterations,
            stop,
            mean_disparity_px: mean,
            resolved_by_heuristic,
        }
    }

    /// The heuristic for leftover multiple matches: repeatedly accept the entry closest to
    /// `mean` among those that are the only candidate left in their row or column (so no
    /// centre loses its only partner to a neighbour's better one), or among all entries when
    /// none is, and drop the rest of its row and column. Ties of σ go to the lower primary,
    /// then stereo, index. Returns the pairs and how many of them had a rival.
    fn single_matches(&self, mean: f64) -> (Vec<StereoPair>, usize) {
        let sigma = |e: &(usize, usize, f64)| self.sigma(e.0, e.1, e.2, mean);
        let mut left: Vec<(usize, usize, f64)> = self.entries().collect();
        let mut pairs = Vec::new();
        let mut by_heuristic = 0;
        while !left.is_empty() {
            let mut per_row = vec![0usize; self.rows];
            let mut per_col = vec![0usize; self.cols];
            for &(i, j, _) in &left {
                per_row[i] += 1;
                per_col[j] += 1;
            }
            let order = |a: &&(usize, usize, f64), b: &&(usize, usize, f64)| {
                sigma(a)
                    .total_cmp(&sigma(b))
                    .then(a.0.cmp(&b.0))
                    .then(a.1.cmp(&b.1))
            };
            let forced = left
                .iter()
                .filter(|(i, j, _)| per_row[*i] == 1 || per_col[*j] == 1)
                .min_by(order);
            let Some(&(i, j, v)) = forced.or_else(|| left.iter().min_by(order)) else {
                break;
            };
            if per_row[i] > 1 || per_col[j] > 1 {
                by_heuristic += 1;
            }
            pairs.push(StereoPair {
                primary: i,
                stereo: j,
                disparity_px: v,
            });
            left.retain(|&(a, b, _)| a != i && b != j);
        }
        pairs.sort_by_key(|p| (p.primary, p.stereo));
        (pairs, by_heuristic)
    }
}

/// Matches centres of the primary view to centres of the stereo view: Eqs. 9–10 with
/// `windows`, then [`DisparityMatrix::relax`].
pub fn match_centres(
    primary: &[Point2<f64>],
    stereo: &[Point2<f64>],
    windows: &MatchingWindows,
    params: &RelaxationParams,
) -> StereoMatching {
    DisparityMatrix::from_centres(primary, stereo, windows).relax(params)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs(m: &StereoMatching) -> Vec<(usize, usize)> {
        m.pairs.iter().map(|p| (p.primary, p.stereo)).collect()
    }

    #[test]
    fn a_diagonal_matrix_is_already_single_matches() {
        let m = DisparityMatrix::from_rows(&[
            vec![Some(30.0), None, None],
            vec![None, Some(32.0), None],
            vec![None, None, Some(29.0)],
        ])
        .relax(&RelaxationParams::default());
        assert_eq!(pairs(&m), [(0, 0), (1, 1), (2, 2)]);
        assert_eq!(m.stop, RelaxationStop::MinimaAgree);
        assert_eq!(m.iterations, 1);
        assert_eq!(m.resolved_by_heuristic, 0);
    }

    #[test]
    fn the_mean_disparity_picks_the_consistent_depth() {
        // Rows 0 and 2 each have a far-off candidate (a fruit at another depth or a false
        // pair); the scene's mean disparity is about 30, so those go.
        let m = DisparityMatrix::from_rows(&[
            vec![Some(30.0), Some(80.0), None, None],
            vec![None, Some(31.0), None, Some(12.0)],
            vec![Some(75.0), None, Some(29.0), None],
            vec![None, None, None, Some(28.0)],
        ])
        .relax(&RelaxationParams::default());
        assert_eq!(pairs(&m), [(0, 0), (1, 1), (2, 2), (3, 3)]);
        assert_eq!(m.stop, RelaxationStop::MinimaAgree);
        // The mean of the step that agreed: all seven candidates.
        assert!((m.mean_disparity_px - 285.0 / 7.0).abs() < 1e-12, "{m:?}");
    }

    #[test]
    fn relaxation_iterates_until_row_and_column_minima_agree() {
        // Step 1 (mean 42): rows keep 50, 31, 29 and columns 30, 50, 29, so c ≠ r; the OR
        // drops 70 and the mean moves to 35. Step 2: rows and columns both keep the diagonal.
        let m = DisparityMatrix::from_rows(&[
            vec![Some(30.0), Some(50.0), None],
            vec![None, Some(31.0), Some(70.0)],
            vec![None, None, Some(29.0)],
        ])
        .relax(&RelaxationParams::default());
        assert_eq!(m.stop, RelaxationStop::MinimaAgree);
        assert_eq!(m.iterations, 2);
        assert!((m.mean_disparity_px - 35.0).abs() < 1e-12);
        assert_eq!(pairs(&m), [(0, 0), (1, 1), (2, 2)]);
        assert_eq!(m.resolved_by_heuristic, 0);
    }

    #[test]
    fn when_the_mean_settles_first_the_heuristic_keeps_every_row_matched() {
        // Step 1 (mean 44.75) keeps 38, 40, 41; step 2 (mean 39.67) keeps them again, so the
        // mean settles with 40 contested by row 1 and column 0. Taking 40 (closest to the mean)
        // would leave row 0 without a partner; the heuristic takes the forced 38 first.
        let matrix = DisparityMatrix::from_rows(&[
            vec![Some(38.0), Some(60.0)],
            vec![Some(40.0), Some(41.0)],
        ]);
        let m = matrix.relax(&RelaxationParams::default());
        assert_eq!(m.stop, RelaxationStop::MeanSettled);
        assert_eq!(m.iterations, 2);
        assert_eq!(pairs(&m), [(0, 0), (1, 1)]);
        assert!(m.resolved_by_heuristic > 0);
        // A cap of one step stops there.
        let capped = matrix.relax(&RelaxationParams {
            max_iterations: 1,
            ..RelaxationParams::default()
        });
        assert_eq!(capped.stop, RelaxationStop::IterationCap);
        assert_eq!(pairs(&capped), [(0, 0), (1, 1)]);
    }

    #[test]
    fn exact_ties_are_broken_deterministically_by_index() {
        // One primary centre, two stereo centres at the same disparity: σ ties, both are row
        // minima and column minima (c = r), so the heuristic keeps the lower stereo index.
        let m = DisparityMatrix::from_rows(&[vec![Some(20.0), Some(20.0)]])
            .relax(&RelaxationParams::default());
        assert_eq!(pairs(&m), [(0, 0)]);
        assert_eq!(m.resolved_by_heuristic, 1);
        // A symmetric 2×2 tie: all four equal; one per row and column, lowest indices first.
        let m = DisparityMatrix::from_rows(&[
            vec![Some(20.0), Some(20.0)],
            vec![Some(20.0), Some(20.0)],
        ])
        .relax(&RelaxationParams::default());
        assert_eq!(pairs(&m), [(0, 0), (1, 1)]);
        // Ties of σ on both sides of the mean (18 and 22 about 20) also fall to the index.
        let m = DisparityMatrix::from_rows(&[vec![Some(22.0), Some(18.0)], vec![None, Some(20.0)]])
            .relax(&RelaxationParams::default());
        assert_eq!(pairs(&m), [(0, 0), (1, 1)]);
    }

    #[test]
    fn extra_costs_and_removals_change_the_choice_and_zero_costs_change_nothing() {
        // Column 0 is contested by rows 0 (41) and 1 (30); row 2 pulls the mean to 37.7, so by
        // disparity alone row 0 takes it and row 1 is left with nothing.
        let rows = [vec![Some(41.0)], vec![Some(30.0)], vec![None, Some(42.0)]];
        let seed = DisparityMatrix::from_rows(&rows).relax(&RelaxationParams::default());
        assert_eq!(pairs(&seed), [(0, 0), (2, 1)]);
        let mut zero = DisparityMatrix::from_rows(&rows);
        for (l, r) in [(0, 0), (1, 0), (2, 1)] {
            zero.add_cost(l, r, 0.0);
        }
        assert_eq!(zero.relax(&RelaxationParams::default()), seed);
        // A cost on (0, 0) hands column 0 to row 1.
        let mut costly = DisparityMatrix::from_rows(&rows);
        costly.add_cost(0, 0, 500.0);
        // Invalid costs and cells outside the matrix are ignored.
        costly.add_cost(1, 0, -1.0);
        costly.add_cost(1, 0, f64::NAN);
        costly.add_cost(5, 5, 1.0);
        assert_eq!((costly.cost(0, 0), costly.cost(1, 0)), (500.0, 0.0));
        let m = costly.relax(&RelaxationParams::default());
        assert_eq!(pairs(&m), [(1, 0), (2, 1)]);
        // The mean disparity is still Eq. 11's (nothing was dropped).
        assert!((m.mean_disparity_px - 113.0 / 3.0).abs() < 1e-12);
        // Removing the candidate does the same.
        let mut removed = DisparityMatrix::from_rows(&rows);
        removed.remove(0, 0);
        removed.remove(7, 7);
        assert_eq!(removed.get(0, 0), None);
        assert_eq!(
            pairs(&removed.relax(&RelaxationParams::default())),
            [(1, 0), (2, 1)]
        );
    }

    #[test]
    fn a_duplicated_circle_pairs_its_fruit_once() {
        // Fruit A has two primary circles (rows 0 and 1, disparities 40 and 41.5 to its one
        // stereo circle, column 0); fruit B (row 2, column 1) is also in the window of the
        // duplicate (30). The duplicate with the larger deviation loses column 0 and its
        // candidate for B is dropped by Eq. 12, so A pairs once and B keeps its partner.
        let m = DisparityMatrix::from_rows(&[
            vec![Some(40.0)],
            vec![Some(41.5), Some(30.0)],
            vec![None, Some(38.0)],
        ])
        .relax(&RelaxationParams::default());
        assert_eq!(pairs(&m), [(0, 0), (2, 1)]);
        // Without B's primary circle the duplicate's only remaining candidate is B's stereo
        // circle, which nobody contests: disparity alone cannot refuse it (the appearance floor
        // of `PairEvidence` can).
        let m = DisparityMatrix::from_rows(&[vec![Some(40.0)], vec![Some(41.5), Some(30.0)]])
            .relax(&RelaxationParams::default());
        assert_eq!(pairs(&m), [(0, 0), (1, 1)]);
    }

    #[test]
    fn empty_and_one_sided_inputs() {
        let m = DisparityMatrix::from_rows(&[]).relax(&RelaxationParams::default());
        assert_eq!(m.stop, RelaxationStop::Empty);
        assert!(m.pairs.is_empty());
        let m = DisparityMatrix::from_rows(&[vec![None, None], vec![None, None]])
            .relax(&RelaxationParams::default());
        assert_eq!(m.stop, RelaxationStop::Empty);
        // More primary than stereo centres: at most min(L, R) matches.
        let m = DisparityMatrix::from_rows(&[vec![Some(10.0)], vec![Some(11.0)], vec![Some(9.0)]])
            .relax(&RelaxationParams::default());
        assert_eq!(m.pairs.len(), 1);
        assert_eq!(m.pairs[0].stereo, 0);
        assert!((m.pairs[0].disparity_px - 10.0).abs() < 1e-12);
    }

    #[test]
    fn centres_are_matched_through_the_windows() {
        let windows = MatchingWindows {
            min_disparity_px: 5.0,
            max_disparity_px: 60.0,
            max_vertical_offset_px: 4.0,
        };
        // Three fruit at disparities 30, 32, 28 (stereo listed in another order), plus a
        // stereo-only blob and a primary-only blob.
        let primary = [
            Point2::new(100.0, 50.0),
            Point2::new(200.0, 80.0),
            Point2::new(300.0, 82.0),
            Point2::new(500.0, 400.0),
        ];
        let stereo = [
            Point2::new(272.0, 81.0),
            Point2::new(10.0, 300.0),
            Point2::new(70.0, 51.0),
            Point2::new(168.0, 79.0),
        ];
        let m = match_centres(&primary, &stereo, &windows, &RelaxationParams::default());
        assert_eq!(pairs(&m), [(0, 2), (1, 3), (2, 0)]);
        let matrix = DisparityMatrix::from_centres(&primary, &stereo, &windows);
        assert_eq!(matrix.shape(), (4, 4));
        assert_eq!(matrix.get(0, 2), Some(30.0));
        // 300 − 168 = 132 exceeds ΔX_M.
        assert_eq!(matrix.get(2, 3), None);
        assert_eq!(matrix.get(9, 9), None);
    }
}
