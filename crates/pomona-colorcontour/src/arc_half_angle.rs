//! Eq. 8 of seed 004: an arc of length `a` whose chord is `c` spans the half-angle θ with
//! (c/a)·θ = sin θ, and its radius is r = a / (2θ).
//!
//! The paper says a non-zero root exists for c/a ∈ [0, 2/π]; in fact f(θ) = sin θ − kθ with
//! k = c/a is positive just above 0 and equals −kπ < 0 at π for every 0 < k < 1, so a root in
//! (0, π) always exists (and is unique: f is concave there). We solve it by Newton-type steps
//! (Halley's, below), falling back to bisection on the bracket whenever a step leaves it, until
//! f is zero to within its rounding.
//!
//! The edge fit solves it about ten thousand times a frame, so two choices keep that cheap: the
//! start is read off a table of θ over u = √(1 − k) (smooth in u, unlike in k near a straight
//! arc), interpolated to within 10⁻⁵; and the step is Halley's — Newton's with the second
//! derivative, −sin θ, which the sine already computed gives for free — so one step from there
//! reaches machine precision. A solve then costs two sines and a cosine (counted on real
//! orchard frames: 2.0 and 1.0 a solve) instead of about eight trigonometric calls from the
//! series start θ ≈ √(6(1 − k)).

/// The half-angle θ ∈ (0, π) of Eq. 8 for the ratio `chord_over_arc` = c/a; `None` unless
/// 0 < c/a < 1 (c/a ≥ 1 is a straight line, c/a ≤ 0 a closed loop).
///
/// ```
/// // A quarter circle: θ = π/4, c/a = sin θ / θ.
/// let theta = std::f64::consts::FRAC_PI_4;
/// let k = theta.sin() / theta;
/// assert!((pomona_colorcontour::arc_half_angle(k).unwrap() - theta).abs() < 1e-12);
/// ```
pub fn arc_half_angle(chord_over_arc: f64) -> Option<f64> {
    let k = chord_over_arc;
    if !(k > 0.0 && k < 1.0) {
        return None;
    }
    Some(solve(k, tabulated_start(k)))
}

/// The root of sin θ − kθ in (0, π) for 0 < k < 1, by Halley's steps from `start`, bisection on
/// the bracket whenever a step would leave it.
fn solve(k: f64, start: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, std::f64::consts::PI);
    let mut t = start.clamp(f64::MIN_POSITIVE, std::f64::consts::PI);
    for _ in 0..100 {
        let sin = t.sin();
        let ft = sin - k * t;
        // Zero to within the rounding of its two terms, each at most θ: near θ = 0 the root is
        // ill-conditioned (f' ≈ −θ²/3), so θ is then as exact as f can tell.
        if ft.abs() <= 4.0 * f64::EPSILON * t {
            break;
        }
        // f > 0 left of the root, < 0 right of it.
        if ft > 0.0 {
            lo = lo.max(t);
        } else {
            hi = hi.min(t);
        }
        // f' = cos θ − k, f'' = −sin θ.
        let df = t.cos() - k;
        let denominator = 2.0 * df * df + ft * sin;
        let halley = t - 2.0 * ft * df / denominator;
        let next = if denominator != 0.0 && halley > lo && halley < hi {
            halley
        } else {
            0.5 * (lo + hi)
        };
        if (next - t).abs() < 1e-15 * t.max(1.0) {
            t = next;
            break;
        }
        t = next;
    }
    t
}

/// Intervals of the start table over u = √(1 − k).
const START_INTERVALS: usize = 1024;

/// A start for [`solve`]: θ interpolated linearly in u = √(1 − k) between nodes solved once
/// (from the series start θ ≈ √(6u²), the small-angle form of sin θ/θ ≈ 1 − θ²/6).
fn tabulated_start(k: f64) -> f64 {
    static TABLE: std::sync::OnceLock<Vec<f64>> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..=START_INTERVALS)
            .map(|i| {
                let u = i as f64 / START_INTERVALS as f64;
                let k = 1.0 - u * u;
                if i == 0 {
                    0.0
                } else if i == START_INTERVALS {
                    std::f64::consts::PI
                } else {
                    solve(k, (6.0 * u * u).sqrt().min(3.0))
                }
            })
            .collect()
    });
    let x = (1.0 - k).max(0.0).sqrt() * START_INTERVALS as f64;
    let i = (x.floor() as usize).min(START_INTERVALS - 1);
    let f = x - i as f64;
    table[i] + f * (table[i + 1] - table[i])
}

/// Radius r = a / (2θ) of an arc of length `arc` with chord `chord` (Eq. 8); `None` when the
/// pair describes no arc (see [`arc_half_angle`]).
pub fn arc_radius(arc: f64, chord: f64) -> Option<f64> {
    if arc <= 0.0 {
        return None;
    }
    arc_half_angle(chord / arc).map(|theta| arc / (2.0 * theta))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_closed_form_arcs_over_the_whole_range() {
        // Arcs of radius r and half-angle θ: a = 2rθ, c = 2r sin θ.
        for i in 1..1000 {
            let theta = std::f64::consts::PI * f64::from(i) / 1000.0;
            for r in [0.5, 7.0, 120.0] {
                let (a, c) = (2.0 * r * theta, 2.0 * r * theta.sin());
                let got = arc_half_angle(c / a).unwrap();
                assert!((got - theta).abs() < 1e-9, "θ {theta}: {got}");
                let radius = arc_radius(a, c).unwrap();
                assert!((radius - r).abs() < 1e-8 * r, "r {r} θ {theta}: {radius}");
            }
        }
        // Beyond the paper's printed range c/a ≤ 2/π (arcs of more than a half circle).
        assert!(arc_half_angle(0.9).is_some() && 2.0 / std::f64::consts::PI < 0.9);
    }

    #[test]
    fn the_tabulated_start_is_close_and_the_root_as_exact_as_f_allows() {
        let mut worst = 0.0f64;
        for i in 1..20_000 {
            let theta = std::f64::consts::PI * f64::from(i) / 20_000.0;
            let k = theta.sin() / theta;
            worst = worst.max((tabulated_start(k) - theta).abs());
            let got = arc_half_angle(k).unwrap();
            // As exact as the conditioning allows: f' ≈ −θ²/3 near 0 magnifies f's rounding.
            let allowed = 1e-14 * (1.0 + 1.0 / theta);
            assert!((got - theta).abs() <= allowed, "θ {theta}: {got}");
        }
        assert!(worst < 1e-5, "worst start error {worst}");
    }

    #[test]
    fn no_arc_outside_the_open_interval() {
        for k in [0.0, -0.5, 1.0, 1.5, f64::NAN] {
            assert_eq!(arc_half_angle(k), None, "{k}");
        }
        assert_eq!(arc_radius(0.0, 0.0), None);
    }
}
