//! The global point cloud descriptor (GPCD) of seed 002: 27-bin angular histogram (Eqs. 7–8),
//! 9 colour values (HSV mean and the 6 distinct covariance terms) and a 30-bin D2 shape
//! histogram — 66 numbers per fruit candidate.
//!
//! Two readings of the paper are made explicit here:
//! * Eq. 7 as printed uses the source normal `n_i` in `f1` and `f3`, which makes `f1` constant
//!   (`v ⟂ n_i`). We follow PFH (Rusu et al.), which the paper extends: the *target* normal
//!   `n_j`, with `v` normalised. `f3` can leave `[0, 1]` for normals facing away from each other;
//!   its bin index is clamped to the three bins.
//! * The D2 histogram spans a fixed metric range `[0, d2_max_m]` (distances beyond go to the last
//!   bin), so it encodes size as well as shape; RGB-D depth is metric, and fruit size is among the
//!   best cues against leaves.
//!
//! * Hue is circular, and red fruit straddle hue 0: an arithmetic mean of hues 0.98 and 0.02 is
//!   0.5 (cyan). Seed 002 does not say how it averages hue. [`HueStatistics::Circular`] takes
//!   the circular mean and wrapped hue deviations for the covariance terms; the default stays
//!   [`HueStatistics::Linear`] because the built-in models were trained with it (changing it
//!   changes the descriptor, so a model must be retrained with the same setting; the setting
//!   is stored in the model).
//!
//! Pairs: with more than `max_points` points, an evenly strided subset is used (deterministic,
//! no RNG); all ordered pairs of that subset vote. The module tests check that subsampling barely
//! moves the descriptor.

use pomona_core::nalgebra::{Point3, Unit, Vector3};
use serde::{Deserialize, Serialize};
use wide::{f64x4, CmpGe, CmpGt, CmpLt};

use pomona_core::{circular_mean_hue, hue_difference, rgb_to_hsv};

/// Length of the descriptor.
pub const GPCD_LEN: usize = 27 + 9 + 30;

/// Parameters of the descriptor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GpcdParams {
    /// Largest number of points paired (all pairs of this many points vote).
    pub max_points: usize,
    /// Upper end of the D2 histogram, metres.
    pub d2_max_m: f64,
    /// How the hue mean and the hue terms of the covariance are taken (absent in older model
    /// files: `linear`, what they were trained with).
    #[serde(default)]
    pub hue_statistics: HueStatistics,
}

/// Hue statistics of the colour moments (see the module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HueStatistics {
    /// Arithmetic mean and differences of hue, as if hue were not circular (the built-in
    /// models' setting; red hues either side of 0 average to cyan).
    #[default]
    Linear,
    /// Circular mean of hue and hue deviations wrapped to `[-0.5, 0.5)`; hues that cancel out
    /// (no mean direction) fall back to the arithmetic mean.
    Circular,
}

impl GpcdParams {
    /// The step through `n` points that leaves at most `max_points` of them (at least 2) to pair:
    /// the subset the descriptor uses is every `stride`-th point from the first.
    pub fn stride_for(&self, n: usize) -> usize {
        n.div_ceil(self.max_points.max(2)).max(1)
    }

    /// The subset of `items` the descriptor pairs: every [`GpcdParams::stride_for`]-th from the
    /// first. [`gpcd`] of the subset (with the whole set's colours) is [`gpcd`] of the whole set.
    pub fn sample<T: Copy>(&self, items: &[T]) -> Vec<T> {
        items
            .iter()
            .copied()
            .step_by(self.stride_for(items.len()))
            .collect()
    }
}

impl Default for GpcdParams {
    fn default() -> Self {
        Self {
            max_points: 200,
            d2_max_m: 0.25,
            hue_statistics: HueStatistics::Linear,
        }
    }
}

/// Computes the 66-D descriptor of a candidate. `colors` may be empty (depth-only data): the
/// nine colour values are then zero. Points without a normal take part in D2 only.
pub fn gpcd(
    points: &[Point3<f64>],
    normals: &[Option<Unit<Vector3<f64>>>],
    colors: &[[u8; 3]],
    params: &GpcdParams,
) -> [f64; GPCD_LEN] {
    let mut out = [0.0; GPCD_LEN];
    let n = points.len();
    if n < 2 {
        return out;
    }
    let stride = params.stride_for(n);
    let subset = Columns::of(points, normals, stride);
    let mut votes = Votes::default();
    let d2_bin_width = params.d2_max_m / 30.0;
    for k in 0..subset.len {
        votes.add_source(&subset, k, d2_bin_width);
    }
    let (angular, rest) = out.split_at_mut(27);
    let (color, d2) = rest.split_at_mut(9);
    normalise(angular, &votes.angular_totals());
    normalise(d2, &votes.d2_totals());
    if !colors.is_empty() {
        color.copy_from_slice(&color_moments(colors, params.hue_statistics));
    }
    out
}

/// `out[b]` = the share of all votes in bin `b` (all zero without votes).
fn normalise<const N: usize>(out: &mut [f64], counts: &[u64; N]) {
    let total = counts.iter().sum::<u64>().max(1) as f64;
    for (x, &c) in out.iter_mut().zip(counts) {
        *x = c as f64 / total;
    }
}

/// Lanes of the pair loop: four targets per step.
const LANES: usize = 4;

/// The strided subset of a candidate as columns (structure of arrays) for the pair loop; a
/// point without a normal has a `NaN` normal.
struct Columns {
    len: usize,
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    nx: Vec<f64>,
    ny: Vec<f64>,
    nz: Vec<f64>,
}

impl Columns {
    fn of(points: &[Point3<f64>], normals: &[Option<Unit<Vector3<f64>>>], stride: usize) -> Self {
        let len = points.len().div_ceil(stride);
        let mut c = Self {
            len,
            x: Vec::with_capacity(len),
            y: Vec::with_capacity(len),
            z: Vec::with_capacity(len),
            nx: Vec::with_capacity(len),
            ny: Vec::with_capacity(len),
            nz: Vec::with_capacity(len),
        };
        let nan = Vector3::repeat(f64::NAN);
        for (i, p) in points.iter().enumerate().step_by(stride) {
            let n = normals
                .get(i)
                .copied()
                .flatten()
                .map_or(nan, Unit::into_inner);
            c.push(p.coords, n);
        }
        c
    }

    fn push(&mut self, p: Vector3<f64>, n: Vector3<f64>) {
        self.x.push(p.x);
        self.y.push(p.y);
        self.z.push(p.z);
        self.nx.push(n.x);
        self.ny.push(n.y);
        self.nz.push(n.z);
    }

    /// Lanes `j..j + LANES` of one column.
    fn lanes(column: &[f64], j: usize) -> f64x4 {
        let mut lanes = [f64::NAN; LANES];
        lanes.copy_from_slice(&column[j..j + LANES]);
        f64x4::new(lanes)
    }

    fn point(&self, i: usize) -> Vector3<f64> {
        Vector3::new(self.x[i], self.y[i], self.z[i])
    }

    fn normal(&self, i: usize) -> Option<Vector3<f64>> {
        let n = Vector3::new(self.nx[i], self.ny[i], self.nz[i]);
        (!n.x.is_nan()).then_some(n)
    }
}

/// Vote counts of the D2 and angular histograms, one copy per lane (and per pair order for the
/// angular one) summed at the end: neighbouring points vote into the same few bins, and a single
/// table would make every increment wait for the previous one to the same bin. The counts are
/// integers, so the totals are exactly those of one table.
struct Votes {
    d2: [[u64; 30]; LANES],
    angular: [[u64; 27]; 2 * LANES],
}

impl Default for Votes {
    fn default() -> Self {
        Self {
            d2: [[0; 30]; LANES],
            angular: [[0; 27]; 2 * LANES],
        }
    }
}

impl Votes {
    fn d2_totals(&self) -> [u64; 30] {
        sum_tables(&self.d2)
    }

    fn angular_totals(&self) -> [u64; 27] {
        sum_tables(&self.angular)
    }

    /// The votes of every pair of subset point `k` with the points after it: four targets at a
    /// time, then the last few one by one ([`Votes::add_pair`]). Each lane computes what
    /// `add_pair` computes for one pair — the same IEEE operations in the same order
    /// (nalgebra's `-`, `dot`, `norm` and `cross` written out), so the histograms are exactly
    /// those of the pair-by-pair loop (unit test `lanes_vote_as_the_pair_by_pair_loop`), at
    /// about half its time on SSE2.
    fn add_source(&mut self, s: &Columns, k: usize, d2_bin_width: f64) {
        let splat = f64x4::splat;
        let (px, py, pz) = (splat(s.x[k]), splat(s.y[k]), splat(s.z[k]));
        let (ux, uy, uz) = (splat(s.nx[k]), splat(s.ny[k]), splat(s.nz[k]));
        let source_oriented = !s.nx[k].is_nan();
        let zero = splat(0.0);
        let whole = k + 1 + (s.len - (k + 1)) / LANES * LANES;
        for j in whole..s.len {
            self.add_pair(s, k, j, d2_bin_width);
        }
        for j in (k + 1..whole).step_by(LANES) {
            let lanes = |column: &[f64]| Columns::lanes(column, j);
            let (dx, dy, dz) = (lanes(&s.x) - px, lanes(&s.y) - py, lanes(&s.z) - pz);
            let dist = (dx * dx + dy * dy + dz * dz).sqrt();
            // `dist > 0`: not coincident, and no NaN (a missing coordinate).
            let voting = dist.cmp_gt(zero).move_mask();
            let bins = (dist / splat(d2_bin_width)).to_array();
            for (lane, q) in bins.iter().enumerate() {
                if voting & (1 << lane) != 0 {
                    self.d2[lane][(*q as usize).min(29)] += 1; // both orders: two votes each
                }
            }
            let (tx, ty, tz) = (lanes(&s.nx), lanes(&s.ny), lanes(&s.nz));
            let oriented = voting & !tx.is_nan().move_mask();
            if !source_oriented || oriented == 0 {
                continue;
            }
            // u × nt, then the four products of `PairProducts`.
            let (cx, cy, cz) = (uy * tz - uz * ty, uz * tx - ux * tz, ux * ty - uy * tx);
            let a = ux * dx + uy * dy + uz * dz;
            let b = ux * tx + uy * ty + uz * tz;
            let c = dx * tx + dy * ty + dz * tz;
            let e = dx * cx + dy * cy + dz * cz;
            let orders = [lane_bins(a, b, c, e, dist), lane_bins(-c, b, -a, e, dist)];
            for ((bins, degenerate), tables) in
                orders.iter().zip(self.angular.chunks_exact_mut(LANES))
            {
                let voting = oriented & !degenerate;
                for ((lane, bin), table) in bins.iter().enumerate().zip(tables) {
                    if voting & (1 << lane) != 0 {
                        table[*bin as usize] += 1;
                    }
                }
            }
        }
    }

    /// The votes of the pair of subset points `k` and `j`.
    fn add_pair(&mut self, s: &Columns, k: usize, j: usize, d2_bin_width: f64) {
        let d = s.point(j) - s.point(k);
        let dist = d.norm();
        if dist.is_nan() || dist <= 0.0 {
            return;
        }
        self.d2[0][((dist / d2_bin_width) as usize).min(29)] += 1; // both orders: two votes each
        let (Some(u), Some(nt)) = (s.normal(k), s.normal(j)) else {
            return;
        };
        let products = PairProducts {
            a: u.dot(&d),
            b: u.dot(&nt),
            c: d.dot(&nt),
            e: d.dot(&u.cross(&nt)),
            dist,
        };
        for b in [products.forward_bin(), products.reverse_bin()]
            .into_iter()
            .flatten()
        {
            self.angular[0][b] += 1;
        }
    }
}

/// The bin-by-bin sum of per-lane vote tables.
fn sum_tables<const N: usize>(tables: &[[u64; N]]) -> [u64; N] {
    let mut total = [0u64; N];
    for table in tables {
        for (t, &c) in total.iter_mut().zip(table) {
            *t += c;
        }
    }
    total
}

/// [`bin`] on four lanes: each lane's bin as a float (exact small integers), and a bit mask
/// of the lanes whose frame is degenerate (no vote).
fn lane_bins(a: f64x4, b: f64x4, c: f64x4, e: f64x4, dist: f64x4) -> ([f64; LANES], i32) {
    let splat = f64x4::splat;
    let one = splat(1.0);
    let dist2 = dist * dist;
    let v_norm2 = dist2 - a * a;
    let degenerate = v_norm2.cmp_lt(splat(1e-24) * dist2).move_mask();
    // Third of x/s in [−1, 1], see `bin`; a true mask AND 1.0 is 1.0, a false one 0.0.
    let third = |x: f64x4, s2: f64x4| {
        let x2 = splat(9.0) * x * x;
        let negative = x.cmp_lt(splat(0.0));
        (!(negative & x2.cmp_gt(s2)) & one) + (!(negative | x2.cmp_lt(s2)) & one)
    };
    let y = c - a * b;
    let middle = b.cmp_gt(splat(0.0)) & (splat(3.0) * y * y).cmp_lt(b * b * v_norm2);
    let q3 = (middle & one) + (!middle & y.cmp_ge(splat(0.0)) & splat(2.0));
    let bins = third(e, v_norm2) + splat(3.0) * third(a, dist2) + splat(9.0) * q3;
    (bins.to_array(), degenerate)
}

/// The nine colour values of the descriptor: HSV mean, then the covariance terms hh, hs, hv,
/// ss, sv, vv. `colors` must not be empty.
fn color_moments(colors: &[[u8; 3]], hue: HueStatistics) -> [f64; 9] {
    let hsv: Vec<[f64; 3]> = colors.iter().map(|&c| rgb_to_hsv(c)).collect();
    let m = hsv.len() as f64;
    let mut mean: [f64; 3] = std::array::from_fn(|c| hsv.iter().map(|x| x[c]).sum::<f64>() / m);
    let circular = hue == HueStatistics::Circular;
    if circular {
        let hues: Vec<f64> = hsv.iter().map(|x| x[0]).collect();
        mean[0] = circular_mean_hue(&hues).unwrap_or(mean[0]);
    }
    let deviation = |x: &[f64; 3], c: usize| match c {
        0 if circular => hue_difference(x[0], mean[0]),
        _ => x[c] - mean[c],
    };
    let mut out = [0.0; 9];
    out[..3].copy_from_slice(&mean);
    let pairs = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
    for (k, (a, b)) in pairs.into_iter().enumerate() {
        out[3 + k] = hsv
            .iter()
            .map(|x| deviation(x, a) * deviation(x, b))
            .sum::<f64>()
            / m;
    }
    out
}

/// The products one unordered pair of oriented points needs for both ordered pairs' bins in
/// the 27-bin angular histogram: with source `p_i`, normal `u`, target `p_j`, normal `nt` and
/// `d = p_j − p_i`: `a = u·d`, `b = u·nt`, `c = d·nt`, `e = d·(u × nt)`, `dist = |d|`.
///
/// With `v = d × u / |d × u|`, `w = u × v` and the direction `d / dist`, the features are
/// `f1 = (1 + v·nt)/2`, `f2 = (1 + u·d/dist)/2`, `f3 = (π/2 + atan2(w·nt, u·nt))/π`, each cut
/// into thirds. In the products: `|d × u|² = dist² − a²`, `(d × u)·nt = e` and
/// `(u × (d × u))·nt = c − a·b` (since `u × (d × u) = d − a·u` for a unit `u`). The reverse
/// order swaps the normals and negates `d`, which maps `(a, b, c, e)` to `(−c, b, −a, e)`: one
/// cross product serves both orders. Every cut is a sign test, so the bins are found without
/// normalising `v` or calling `atan2` (the same bins up to rounding at a cut; see
/// `angular_bins_match_the_formulas`): `f < 1/3 ⇔ x < −1/3` for `f = (1 + x)/2`, and `f3`'s
/// thirds are `atan2 < −π/6`, `−π/6 ≤ atan2 < π/6`, `atan2 ≥ π/6`.
#[derive(Debug, Clone, Copy)]
struct PairProducts {
    a: f64,
    b: f64,
    c: f64,
    e: f64,
    dist: f64,
}

impl PairProducts {
    /// Bin of the order source → target; `None` when `d` is parallel to `u`.
    fn forward_bin(&self) -> Option<usize> {
        bin(self.a, self.b, self.c, self.e, self.dist)
    }

    /// Bin of the order target → source; `None` when `d` is parallel to `nt`.
    fn reverse_bin(&self) -> Option<usize> {
        bin(-self.c, self.b, -self.a, self.e, self.dist)
    }
}

/// The bin of one ordered pair from its products (see [`PairProducts`]). Every cut compares
/// squares, so no square root is taken: `3x < −s ⇔ x < 0 ∧ 9x² > s²` and `3x < s ⇔ x < 0 ∨
/// 9x² < s²` for `s > 0`.
fn bin(a: f64, b: f64, c: f64, e: f64, dist: f64) -> Option<usize> {
    let dist2 = dist * dist;
    let v_norm2 = dist2 - a * a; // |d × u|²
    if v_norm2 < 1e-24 * dist2 {
        return None;
    }
    // Third of x/s in [−1, 1] (s > 0) from x and s², without branches (the cuts are
    // unpredictable, and this runs for every pair of points).
    let third = |x: f64, s2: f64| {
        let x2 = 9.0 * x * x;
        let negative = x < 0.0;
        usize::from(!(negative && x2 > s2)) + usize::from(!(negative || x2 < s2))
    };
    let q1 = third(e, v_norm2);
    let q2 = third(a, dist2);
    // u × (d × u) is the frame's w scaled by |v|; with x = (u·nt)|v| and y = c − a·b, atan2's
    // thirds are x > 0 ∧ |y| < x tan 30° (middle), else the sign of y; squared: y² < x²/3.
    let y = c - a * b;
    let middle = b > 0.0 && 3.0 * y * y < b * b * v_norm2;
    let q3 = usize::from(middle) + 2 * usize::from(!middle && y >= 0.0);
    Some(q1 + 3 * q2 + 9 * q3)
}

#[cfg(test)]
mod tests {
    use super::*;

    type Normals = Vec<Option<Unit<Vector3<f64>>>>;

    /// Red pixels either side of hue 0: the linear mean is cyan-ish (0.5), the circular one red
    /// with a small hue variance; saturation and value terms agree.
    #[test]
    fn circular_hue_moments_keep_red_red() {
        let colors = [[255, 0, 20], [255, 20, 0], [255, 0, 10], [255, 10, 0]];
        let linear = color_moments(&colors, HueStatistics::Linear);
        let circular = color_moments(&colors, HueStatistics::Circular);
        assert!((linear[0] - 0.5).abs() < 0.05, "{linear:?}");
        assert!(
            hue_difference(circular[0], 0.0).abs() < 1e-9,
            "{circular:?}"
        );
        assert!(
            linear[3] > 0.2 && circular[3] < 1e-3,
            "hh {} {}",
            linear[3],
            circular[3]
        );
        assert_eq!(linear[1..3], circular[1..3]);
        assert_eq!(
            (linear[6], linear[7], linear[8]),
            (circular[6], circular[7], circular[8])
        );
        // Hues away from 0 give nearly the same moments either way (the circular mean of a
        // narrow spread is within its cube of the arithmetic mean).
        let green = [[0, 200, 30], [10, 220, 0], [0, 180, 60]];
        let (a, b) = (
            color_moments(&green, HueStatistics::Linear),
            color_moments(&green, HueStatistics::Circular),
        );
        assert!(
            a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-4),
            "{a:?} {b:?}"
        );
    }

    fn sphere_cap(n: usize, radius: f64) -> (Vec<Point3<f64>>, Normals) {
        let centre = Point3::new(0.0, 0.0, 0.8);
        (0..n)
            .map(|i| {
                let z = -(i as f64 + 0.5) / n as f64;
                let phi = i as f64 * 2.399_963;
                let s = (1.0 - z * z).sqrt();
                let nrm = Vector3::new(s * phi.cos(), s * phi.sin(), z);
                (centre + nrm * radius, Some(Unit::new_normalize(nrm)))
            })
            .unzip()
    }

    #[test]
    fn lanes_vote_as_the_pair_by_pair_loop() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for n in [2, 3, 5, 8, 9, 64, 203] {
            // A cap with noise, duplicated points (zero distance), missing normals and a
            // non-finite point: every branch of a pair's vote.
            let (mut points, mut normals) = sphere_cap(n, 0.04);
            for (p, nrm) in points.iter_mut().zip(normals.iter_mut()) {
                *p += Vector3::new(rng.gen(), rng.gen(), rng.gen()) * 0.004;
                if rng.gen_bool(0.15) {
                    *nrm = None;
                }
            }
            if n > 4 {
                points[3] = points[1];
                normals[2] = normals[4];
                points[n - 1].x = f64::NAN;
            }
            let subset = Columns::of(&points, &normals, 1);
            let (mut lanes, mut pairs) = (Votes::default(), Votes::default());
            for k in 0..subset.len {
                lanes.add_source(&subset, k, 0.25 / 30.0);
                for j in k + 1..subset.len {
                    pairs.add_pair(&subset, k, j, 0.25 / 30.0);
                }
            }
            assert_eq!(lanes.d2_totals(), pairs.d2_totals(), "{n}");
            assert_eq!(lanes.angular_totals(), pairs.angular_totals(), "{n}");
            assert!(n < 8 || lanes.angular_totals().iter().filter(|&&c| c > 0).count() > 5);
        }
    }

    #[test]
    fn histograms_are_normalised_and_colour_moments_exact() {
        let (p, n) = sphere_cap(300, 0.04);
        let colors: Vec<[u8; 3]> = (0..300)
            .map(|i| {
                if i % 2 == 0 {
                    [255, 0, 0]
                } else {
                    [255, 255, 255]
                }
            })
            .collect();
        let f = gpcd(&p, &n, &colors, &GpcdParams::default());
        assert!((f[..27].iter().sum::<f64>() - 1.0).abs() < 1e-9);
        assert!((f[36..].iter().sum::<f64>() - 1.0).abs() < 1e-9);
        // S is 1 or 0 half the time each: mean 0.5, variance 0.25; V is 1 always.
        assert!((f[28] - 0.5).abs() < 1e-12 && (f[29] - 1.0).abs() < 1e-12);
        assert!((f[27 + 3 + 3] - 0.25).abs() < 1e-12);
        // All distances on an 80 mm sphere are below 80 mm: no votes past bin 9 of 30 (0.25 m).
        assert!(f[36 + 10..].iter().all(|&x| x == 0.0));
    }

    #[test]
    fn subsampling_barely_changes_the_descriptor() {
        let (p, n) = sphere_cap(2000, 0.04);
        let full = gpcd(
            &p,
            &n,
            &[],
            &GpcdParams {
                max_points: 2000,
                ..Default::default()
            },
        );
        let sub = gpcd(&p, &n, &[], &GpcdParams::default());
        let l1: f64 = full.iter().zip(&sub).map(|(a, b)| (a - b).abs()).sum();
        assert!(l1 < 0.1, "L1 distance {l1}");
    }

    #[test]
    fn the_sample_alone_gives_the_whole_descriptor() {
        let colors: Vec<[u8; 3]> = (0..2003).map(|i| [i as u8, 40, (i / 9) as u8]).collect();
        for n in [2003, 401, 200, 7] {
            let (p, normals) = sphere_cap(n, 0.04);
            let params = GpcdParams::default();
            let whole = gpcd(&p, &normals, &colors[..n], &params);
            let (ps, ns) = (params.sample(&p), params.sample(&normals));
            assert!(ps.len() <= params.max_points && ps.len() >= 2);
            assert_eq!(gpcd(&ps, &ns, &colors[..n], &params), whole, "{n} points");
        }
    }

    #[test]
    fn plane_and_sphere_differ() {
        let (p, n) = sphere_cap(300, 0.04);
        let plane: Vec<Point3<f64>> = (0..300)
            .map(|i| Point3::new((i % 20) as f64 * 0.004, (i / 20) as f64 * 0.004, 0.8))
            .collect();
        let up = vec![Some(Unit::new_normalize(Vector3::new(0.0, 0.0, -1.0))); 300];
        let a = gpcd(&p, &n, &[], &GpcdParams::default());
        let b = gpcd(&plane, &up, &[], &GpcdParams::default());
        let l1: f64 = a[..27]
            .iter()
            .zip(&b[..27])
            .map(|(x, y)| (x - y).abs())
            .sum();
        assert!(l1 > 0.5, "angular histograms should differ, L1 {l1}");
    }

    /// The bin of one ordered pair computed the direct way (normalised frame, `atan2`).
    fn bin_by_formula(u: &Vector3<f64>, nt: &Vector3<f64>, along: &Vector3<f64>) -> usize {
        let dir = along.normalize();
        let v = dir.cross(u).normalize();
        let w = u.cross(&v);
        let f1 = (1.0 + v.dot(nt)) / 2.0;
        let f2 = (1.0 + u.dot(&dir)) / 2.0;
        let f3 = (std::f64::consts::FRAC_PI_2 + w.dot(nt).atan2(u.dot(nt))) / std::f64::consts::PI;
        let q = |f: f64| ((3.0 * f).floor() as isize).clamp(0, 2) as usize;
        q(f1) + 3 * q(f2) + 9 * q(f3)
    }

    #[test]
    fn angular_bins_match_the_formulas() {
        // Pseudo-random unit vectors and offsets (a fixed LCG: no RNG dependency needed).
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut seen = [false; 27];
        for _ in 0..20_000 {
            let u = Unit::new_normalize(Vector3::new(next(), next(), next()));
            let nt = Unit::new_normalize(Vector3::new(next(), next(), next()));
            let along = Vector3::new(next(), next(), next()) * 0.05;
            let products = PairProducts {
                a: u.dot(&along),
                b: u.dot(&nt),
                c: along.dot(&nt),
                e: along.dot(&u.cross(&nt)),
                dist: along.norm(),
            };
            let forward = products.forward_bin().unwrap();
            assert_eq!(forward, bin_by_formula(&u, &nt, &along));
            let reverse = products.reverse_bin().unwrap();
            assert_eq!(reverse, bin_by_formula(&nt, &u, &-along));
            seen[forward] = true;
            seen[reverse] = true;
        }
        assert!(seen.iter().all(|&s| s), "every bin is exercised");
        let u = Vector3::z_axis();
        let along = Vector3::new(0.0, 0.0, 0.1);
        let parallel = PairProducts {
            a: u.dot(&along),
            b: 1.0,
            c: along.dot(&u),
            e: 0.0,
            dist: 0.1,
        };
        assert_eq!(
            (parallel.forward_bin(), parallel.reverse_bin()),
            (None, None)
        );
    }

    #[test]
    fn degenerate_input_gives_zeros() {
        assert_eq!(gpcd(&[], &[], &[], &GpcdParams::default()), [0.0; GPCD_LEN]);
        let one = [Point3::origin()];
        assert_eq!(
            gpcd(&one, &[None], &[], &GpcdParams::default()),
            [0.0; GPCD_LEN]
        );
    }
}
