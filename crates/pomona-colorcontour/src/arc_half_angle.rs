//! Eq. 8 of seed 004: an arc of length `a` whose chord is `c` spans the half-angle θ with
//! (c/a)·θ = sin θ, and its radius is r = a / (2θ).
//!
//! The paper says a non-zero root exists for c/a ∈ [0, 2/π]; in fact f(θ) = sin θ − kθ with
//! k = c/a is positive just above 0 and equals −kπ < 0 at π for every 0 < k < 1, so a root in
//! (0, π) always exists (and is unique: f is concave there). We solve it by Newton's method from
//! a series start, falling back to bisection on the bracket whenever a Newton step leaves it.

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
    let f = |t: f64| t.sin() - k * t;
    let (mut lo, mut hi) = (0.0f64, std::f64::consts::PI);
    // sin θ/θ ≈ 1 − θ²/6 near 0 gives the start θ ≈ √(6(1 − k)), inside the bracket.
    let mut t = (6.0 * (1.0 - k)).sqrt().min(3.0);
    for _ in 0..100 {
        let ft = f(t);
        if ft.abs() < 1e-15 {
            break;
        }
        // f > 0 left of the root, < 0 right of it.
        if ft > 0.0 {
            lo = lo.max(t);
        } else {
            hi = hi.min(t);
        }
        let df = t.cos() - k;
        let newton = t - ft / df;
        let next = if df != 0.0 && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - t).abs() < 1e-15 * t.max(1.0) {
            t = next;
            break;
        }
        t = next;
    }
    Some(t)
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
    fn no_arc_outside_the_open_interval() {
        for k in [0.0, -0.5, 1.0, 1.5, f64::NAN] {
            assert_eq!(arc_half_angle(k), None, "{k}");
        }
        assert_eq!(arc_radius(0.0, 0.0), None);
    }
}
