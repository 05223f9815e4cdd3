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
    // The strided subset as plain vectors, normals unwrapped once (not once per pair).
    let subset: Vec<(Vector3<f64>, Option<Vector3<f64>>)> = (0..n)
        .step_by(stride)
        .map(|i| {
            let normal = normals.get(i).copied().flatten().map(Unit::into_inner);
            (points[i].coords, normal)
        })
        .collect();

    // Votes are counted in integers, alternating between two copies of each histogram by
    // the target's parity: consecutive pairs mostly fall into the same bin, and a single
    // floating-point counter would make every pair wait for the previous pair's update.
    // Integer counts are exact, so the normalised histograms are what summing 1.0s gives.
    let mut d2_counts = [[0u32; 30]; 2];
    let mut angular_counts = [[0u32; 27]; 2];
    let d2_bin_width = params.d2_max_m / 30.0;
    for (k, (pi, ni)) in subset.iter().enumerate() {
        for (l, (pj, nj)) in subset[k + 1..].iter().enumerate() {
            let copy = l & 1;
            let d = pj - pi;
            let dist = d.norm();
            if dist.is_nan() || dist <= 0.0 {
                continue;
            }
            let bin = ((dist / d2_bin_width) as usize).min(29);
            d2_counts[copy][bin] += 1; // both orders: two votes each, see below
            let (Some(u), Some(nt)) = (ni, nj) else {
                continue;
            };
            // Both orders of the pair from four products (see `PairProducts`).
            let products = PairProducts {
                a: u.dot(&d),
                b: u.dot(nt),
                c: d.dot(nt),
                e: d.dot(&u.cross(nt)),
                dist,
            };
            for b in [products.forward_bin(), products.reverse_bin()]
                .into_iter()
                .flatten()
            {
                angular_counts[copy][b] += 1;
            }
        }
    }
    let (angular, rest) = out.split_at_mut(27);
    let (color, d2) = rest.split_at_mut(9);
    normalise(angular, &angular_counts);
    normalise(d2, &d2_counts);
    if !colors.is_empty() {
        color.copy_from_slice(&color_moments(colors, params.hue_statistics));
    }
    out
}

/// `out[b]` = the share of all votes in bin `b`, summed over the copies of a histogram (all
/// zero without votes).
fn normalise<const N: usize>(out: &mut [f64], copies: &[[u32; N]; 2]) {
    let counts: [u64; N] = std::array::from_fn(|b| copies.iter().map(|c| u64::from(c[b])).sum());
    let total = counts.iter().sum::<u64>().max(1) as f64;
    for (x, &c) in out.iter_mut().zip(&counts) {
        *x = c as f64 / total;
    }
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
