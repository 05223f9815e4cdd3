//! Leaf families and their blade outlines, in the leaf frame of [`crate::Leaf`] (x along the
//! blade from the petiole at `x = -a` to the tip at `x = +a`, y across it, half width `b`).
//!
//! Detectors trained on one leaf outline learn "fruit = the round thing that is not an ovate
//! blade"; the wide domain therefore draws the blade outline from four families seen in crops:
//!
//! | family       | outline (s = x / a)                                                          |
//! |--------------|------------------------------------------------------------------------------|
//! | `elliptic`   | ovate: `|y| <= b·sqrt(1 - s²)·(1 - 0.3·s)` (the narrow domain's only leaf)     |
//! | `lanceolate` | long, narrow, pointed: `|y| <= b·k·(1 + s)^0.5·(1 - s)^1.5`, widest at s = -0.5 |
//! | `lobed`      | palmate (maple-like): polar `r(θ) = a·(m + (1 - m)·((1 + cos 5θ) / 2)^1.5)`, five lobes, a notch at the petiole |
//! | `compound`   | a rachis along x with two pairs of elliptic leaflets and a terminal leaflet   |
//!
//! Every outline lies inside the box `|x| <= a`, `|y| <= 1.05·b` (the ovate blade is 4 % wider
//! than `b` below its middle), so the leaf's bounding sphere holds.

use serde::{Deserialize, Serialize};

/// Depth of the notches of a `lobed` blade: radius between lobes relative to a lobe tip.
pub const LOBED_NOTCH_RADIUS: f64 = 0.42;
/// Half width of a `compound` leaf's rachis relative to the leaf's half width `b`.
pub const COMPOUND_RACHIS_HALF_WIDTH: f64 = 0.04;
/// `compound` lateral leaflets: centres along the blade, as `s = x / a` (one pair each).
pub const COMPOUND_PAIRS_S: [f64; 2] = [-0.55, -0.05];
/// `compound` lateral leaflets: half length along the blade relative to `a`.
pub const COMPOUND_LEAFLET_HALF_LENGTH: f64 = 0.2;
/// `compound` terminal leaflet: centre `s` and half length relative to `a`.
pub const COMPOUND_TERMINAL: (f64, f64) = (0.66, 0.32);

/// A leaf outline family (`--leaf-families`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LeafFamily {
    /// Ovate blade (tomato leaflet, pepper): the narrow domain's leaf.
    Elliptic,
    /// Long, narrow, pointed blade (lanceolate: eggplant side shoots, citrus, willow-like).
    Lanceolate,
    /// Palmate blade with five pointed lobes (maple, vine, cucurbits).
    Lobed,
    /// Several leaflets on a rachis (tomato, rose, ash).
    Compound,
}

impl LeafFamily {
    /// All families, in CLI order.
    pub const ALL: [LeafFamily; 4] = [
        LeafFamily::Elliptic,
        LeafFamily::Lanceolate,
        LeafFamily::Lobed,
        LeafFamily::Compound,
    ];

    /// The name used on the command line and in the truth `synth` record.
    pub fn name(self) -> &'static str {
        match self {
            LeafFamily::Elliptic => "elliptic",
            LeafFamily::Lanceolate => "lanceolate",
            LeafFamily::Lobed => "lobed",
            LeafFamily::Compound => "compound",
        }
    }

    /// The family named `name` (see [`LeafFamily::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Range of the half width `b` relative to the half length `a` for this family.
    pub fn width_ratio_range(self) -> (f64, f64) {
        match self {
            LeafFamily::Elliptic => (0.35, 0.55),
            LeafFamily::Lanceolate => (0.12, 0.25),
            LeafFamily::Lobed => (0.85, 1.0),
            LeafFamily::Compound => (0.45, 0.7),
        }
    }

    /// Relative across-blade position (`y / b`, in `[-1, 1]`) if the leaf-frame point `(x, y)`
    /// lies inside the outline of a blade with half length `a` and half width `b`.
    pub fn across_at(self, x: f64, y: f64, a: f64, b: f64) -> Option<f64> {
        let s = x / a;
        match self {
            LeafFamily::Elliptic => {
                if s.abs() >= 1.0 {
                    return None;
                }
                let half = b * (1.0 - s * s).sqrt() * (1.0 - 0.3 * s);
                (y.abs() <= half).then(|| y / half)
            }
            LeafFamily::Lanceolate => {
                if s.abs() >= 1.0 {
                    return None;
                }
                // (1 + s)^0.5 (1 - s)^1.5 peaks at s = -0.5 with 0.5^0.5 · 1.5^1.5.
                const PEAK: f64 = 1.299_038_105_676_658;
                let half = b * (1.0 + s).sqrt() * (1.0 - s) * (1.0 - s).sqrt() / PEAK;
                (y.abs() <= half).then(|| y / half)
            }
            LeafFamily::Lobed => {
                let ys = y * a / b;
                let r2 = x * x + ys * ys;
                if r2 >= a * a {
                    return None;
                }
                // Inside the notch radius every direction is blade.
                let notch = LOBED_NOTCH_RADIUS * a;
                if r2 <= notch * notch {
                    return Some(y / b);
                }
                let r = r2.sqrt();
                let theta = ys.atan2(x);
                let c = 0.5 * (1.0 + (5.0 * theta).cos());
                let lobe = c * c.sqrt();
                let reach = a * (LOBED_NOTCH_RADIUS + (1.0 - LOBED_NOTCH_RADIUS) * lobe);
                (r <= reach).then(|| y / b)
            }
            LeafFamily::Compound => {
                if s.abs() >= 1.0 {
                    return None;
                }
                let across = y / b;
                let rachis_end = COMPOUND_TERMINAL.0;
                if s <= rachis_end && across.abs() <= COMPOUND_RACHIS_HALF_WIDTH {
                    return Some(across);
                }
                let inside = |cs: f64, cy: f64, hs: f64, hy: f64| {
                    let (ds, dy) = ((s - cs) / hs, (across - cy) / hy);
                    ds * ds + dy * dy <= 1.0
                };
                let lateral = COMPOUND_PAIRS_S.iter().any(|&cs| {
                    inside(cs, 0.5, COMPOUND_LEAFLET_HALF_LENGTH, 0.5)
                        || inside(cs, -0.5, COMPOUND_LEAFLET_HALF_LENGTH, 0.5)
                });
                let (ts, th) = COMPOUND_TERMINAL;
                (lateral || inside(ts, 0.0, th, 0.4)).then_some(across)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for f in LeafFamily::ALL {
            assert_eq!(LeafFamily::from_name(f.name()), Some(f));
            let json = serde_json::to_string(&f).unwrap();
            assert_eq!(json, format!("\"{}\"", f.name()));
        }
        assert_eq!(LeafFamily::from_name("ovate"), None);
    }

    #[test]
    fn outlines_stay_inside_their_box() {
        let (a, b) = (0.05, 0.03);
        for f in LeafFamily::ALL {
            let mut inside = 0;
            for i in -60..=60 {
                for j in -60..=60 {
                    let (x, y) = (i as f64 * 0.06 * a / 60.0 * 20.0, j as f64 * b / 50.0);
                    if f.across_at(x, y, a, b).is_some() {
                        inside += 1;
                        assert!(x.abs() <= a && y.abs() <= 1.05 * b, "{f:?} at {x} {y}");
                    }
                }
            }
            assert!(inside > 100, "{f:?} has almost no blade");
        }
    }
}
