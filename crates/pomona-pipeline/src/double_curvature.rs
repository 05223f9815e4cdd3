//! The double-curvature check: a fruit is a solid that bends away from the camera in every
//! direction, a leaf is a sheet that bends in one at most. Around a detected fruit's centre the
//! seen surface must therefore curve in both principal directions (be doubly curved); a
//! surface that is flat, folded along one line (a blade bent over its midrib, a curled leaf,
//! the long side of a branch) or saddle-shaped is not the near side of a fruit.
//!
//! Not in the seed papers: the box detectors' normal histograms describe a box's points but do
//! not single out their flattest direction, and a large leaf bent round a fruit-sized arc gives
//! histograms much like a fruit's (on our generator's `wide` scenes most of symmetry's
//! high-scoring false detections sit on leaves 13–15 cm long). Like the free-space check it is
//! geometry, not learnt, so it carries over to leaf shapes, cameras and light it never saw
//! (docs/results.md, "A fruit bends both ways").
//!
//! Shape-fit's `CurvatureCheck` asks a weaker question of a fitted shape's own inliers — is the
//! shape clearly closer to them than their best plane? — which a leaf folded round a fruit-sized
//! arc passes (a cylinder or sphere explains it far better than a plane). This one needs no
//! fitted shape, only a centre and a radius, so it serves any detector with depth.
//!
//! How: the depth readings within [`DoubleCurvatureCheck::patch_radii`] fruit radii of the
//! detection's centre are expressed in a frame whose third axis is the viewing ray through the
//! centre, and a quadric height field `z = a·x² + b·x·y + c·y² + d·x + e·y + f` is fitted to
//! them by least squares, twice more without the readings off the first fit by more than
//! [`DoubleCurvatureCheck::trim_m`] or three times its robust residual scale, whichever is
//! larger (leaves in front, the background beside the fruit; the scale keeps a noisy camera's
//! fruit readings in). The eigenvalues of its Hessian are the surface's two principal
//! curvatures seen along the ray (positive: bending away from the camera). The flattest of
//! them, times the fruit's radius, is about 1.6 for a ball seen whole (the quadric follows the
//! cap's steepening rim; 1 would be the curvature at the cap's middle), mostly 0.4–1.2 for the
//! fruit of our generator's scenes, near 0 for a leaf's fold line and negative for a saddle; a
//! detection passes when it is at least [`DoubleCurvatureCheck::min_relative_curvature`]. A
//! detection with too few readings around it is admitted (no evidence against it).

use pomona_core::nalgebra::{Matrix6, Point3, Unit, Vector3, Vector6};
use pomona_core::RgbdFrame;
use serde::{Deserialize, Serialize};

use crate::{DetectionFilter, FruitCheck};

/// When a detection passes the double-curvature check, and over which readings it is measured.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DoubleCurvatureCheck {
    /// Whether detections are checked at all.
    pub enabled: bool,
    /// Readings within this many fruit radii of the centre are fitted (default 1.4: the
    /// fruit's near cap with some of its rim, measured best among 1.2, 1.4 and 1.7 on the
    /// tuning sets).
    pub patch_radii: f64,
    /// Least accepted flattest curvature times the fruit's radius (about 1.6 for a ball seen
    /// whole, see the module docs; default 0.15: the flattest direction bends at least a
    /// tenth as much as a ball's).
    pub min_relative_curvature: f64,
    /// Readings off the first fit by more than this are left out of the next, metres
    /// (default 6 mm: twice the time-of-flight noise of our synthetic cameras at 1.5 m), or by
    /// more than [`Self::trim_sigmas`] times the first fit's robust residual scale where the
    /// camera is noisier.
    pub trim_m: f64,
    /// The trim in units of the first fit's residual scale (1.4826 × the median absolute
    /// residual) when that exceeds [`Self::trim_m`] (default 3: a noisy camera's readings on
    /// the fruit stay in the fit; a fixed 6 mm cost a 176×144 time-of-flight camera's noisy
    /// fruit their curvature).
    pub trim_sigmas: f64,
    /// Fewer readings than this in the patch (or left after trimming) admit the detection
    /// unjudged (default 20).
    pub min_readings: usize,
    /// At most this many readings per patch: the pixel grid is thinned evenly (default 2000).
    pub max_readings: usize,
}

impl Default for DoubleCurvatureCheck {
    fn default() -> Self {
        Self {
            enabled: true,
            patch_radii: 1.4,
            min_relative_curvature: 0.15,
            trim_m: 0.006,
            trim_sigmas: 3.0,
            min_readings: 20,
            max_readings: 2000,
        }
    }
}

/// The seen surface's principal curvatures around a detection (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeenCurvature {
    /// The flattest principal curvature, 1/m (positive: bending away from the camera).
    pub flattest_per_m: f64,
    /// The other principal curvature, 1/m.
    pub steepest_per_m: f64,
    /// Readings the last fit used.
    pub readings: usize,
}

impl DoubleCurvatureCheck {
    /// The check switched off (every detection passes).
    pub fn off() -> Self {
        Self {
            enabled: false,
            ..Self::default()
        }
    }

    /// Which setting is unusable (its key under `double_curvature`), its value and why, if one is:
    /// `patch_radii` and `trim_m` must be finite and positive, `min_relative_curvature`
    /// finite, `trim_sigmas` finite and non-negative, `min_readings` at least 6 (the quadric's unknowns) and `max_readings` at least
    /// `min_readings`.
    pub fn invalid_reason(&self) -> Option<(&'static str, f64, &'static str)> {
        if !(self.patch_radii.is_finite() && self.patch_radii > 0.0) {
            Some((
                "double_curvature.patch_radii",
                self.patch_radii,
                "must be finite and > 0",
            ))
        } else if !self.min_relative_curvature.is_finite() {
            Some((
                "double_curvature.min_relative_curvature",
                self.min_relative_curvature,
                "must be finite",
            ))
        } else if !(self.trim_m.is_finite() && self.trim_m > 0.0) {
            Some((
                "double_curvature.trim_m",
                self.trim_m,
                "must be finite and > 0",
            ))
        } else if !(self.trim_sigmas.is_finite() && self.trim_sigmas >= 0.0) {
            Some((
                "double_curvature.trim_sigmas",
                self.trim_sigmas,
                "must be finite and >= 0",
            ))
        } else if self.min_readings < 6 {
            Some((
                "double_curvature.min_readings",
                self.min_readings as f64,
                "must be at least 6",
            ))
        } else if self.max_readings < self.min_readings {
            Some((
                "double_curvature.max_readings",
                self.max_readings as f64,
                "must be at least min_readings",
            ))
        } else {
            None
        }
    }

    /// The principal curvatures of the surface seen within [`Self::patch_radii`] × `radius_m`
    /// of `center_m` (camera frame). `None` when the radius is not positive, the centre is not
    /// in front of the camera, or fewer than [`Self::min_readings`] readings are there.
    pub fn seen_curvature(
        &self,
        frame: &RgbdFrame,
        center_m: &Point3<f64>,
        radius_m: f64,
    ) -> Option<SeenCurvature> {
        let patch_m = self.patch_radii * radius_m;
        if !(radius_m > 0.0 && center_m.z > 0.0 && patch_m.is_finite()) {
            return None;
        }
        let readings = self.readings_near(frame, center_m, patch_m);
        if readings.len() < self.min_readings {
            return None;
        }
        // Frame of the viewing ray: `ray` forward, `across` and `up` span the image plane.
        let ray = Unit::new_normalize(center_m.coords);
        let helper = if ray.y.abs() < 0.9 {
            Vector3::y()
        } else {
            Vector3::x()
        };
        let across = Unit::new_normalize(ray.cross(&helper));
        let up = ray.cross(&across);
        let local: Vec<[f64; 3]> = readings
            .iter()
            .map(|p| {
                let d = p - center_m;
                [d.dot(&across), d.dot(&up), d.dot(&ray)]
            })
            .collect();
        let mut keep = vec![true; local.len()];
        let mut fit = None;
        let mut trim_m = self.trim_m;
        let mut residuals = Vec::with_capacity(local.len());
        for round in 0..FITS {
            let used = keep.iter().filter(|&&k| k).count();
            if used < self.min_readings {
                break;
            }
            let Some(coef) = quadric_fit(&local, &keep) else {
                break;
            };
            fit = Some((coef, used));
            if round + 1 == FITS {
                // The last fit decides; its residuals would trim nothing more.
                break;
            }
            residuals.clear();
            residuals.extend(
                local
                    .iter()
                    .map(|p| (quadric_at(&coef, p[0], p[1]) - p[2]).abs()),
            );
            if round == 0 {
                trim_m = trim_m.max(self.trim_sigmas * robust_sigma(&mut residuals.clone()));
            }
            for (k, r) in keep.iter_mut().zip(&residuals) {
                *k = *r <= trim_m;
            }
        }
        let (coef, used) = fit?;
        // Hessian [[2a, b], [b, 2c]]: eigenvalues (a + c) ∓ √((a − c)² + b²).
        let (a, b, c) = (coef[0], coef[1], coef[2]);
        let mean = a + c;
        let spread = ((a - c).powi(2) + b * b).sqrt();
        Some(SeenCurvature {
            flattest_per_m: mean - spread,
            steepest_per_m: mean + spread,
            readings: used,
        })
    }

    /// The depth readings (camera frame) within `patch_m` of `center_m`, on a pixel grid
    /// thinned to about [`Self::max_readings`] over the window that can hold them.
    fn readings_near(
        &self,
        frame: &RgbdFrame,
        center_m: &Point3<f64>,
        patch_m: f64,
    ) -> Vec<Point3<f64>> {
        let cam = frame.camera();
        let Some(pixel) = cam.project(center_m) else {
            return Vec::new();
        };
        // The nearest point of the ball lies `patch_m` in front of the centre; its image is
        // the largest.
        let nearest_z = (center_m.z - patch_m).max(0.05 * center_m.z);
        let reach = (cam.fx.max(cam.fy) * patch_m / nearest_z).ceil();
        let (w, h) = (f64::from(cam.width), f64::from(cam.height));
        let (u_lo, u_hi) = ((pixel.x - reach).max(0.0), (pixel.x + reach).min(w - 1.0));
        let (v_lo, v_hi) = ((pixel.y - reach).max(0.0), (pixel.y + reach).min(h - 1.0));
        if u_lo > u_hi || v_lo > v_hi {
            return Vec::new();
        }
        let (u_lo, u_hi, v_lo, v_hi) = (
            u_lo.ceil() as usize,
            u_hi.floor() as usize,
            v_lo.ceil() as usize,
            v_hi.floor() as usize,
        );
        let window = (u_hi + 1 - u_lo) * (v_hi + 1 - v_lo);
        let step = ((window as f64 / self.max_readings as f64).sqrt().ceil() as usize).max(1);
        let depth = frame.depth().as_slice();
        let width = cam.width as usize;
        let mut readings = Vec::new();
        for v in (v_lo..=v_hi).step_by(step) {
            for u in (u_lo..=u_hi).step_by(step) {
                let d = depth[v * width + u];
                if !(d.is_finite() && d > 0.0) {
                    continue;
                }
                let p = cam.back_project(u as f64, v as f64, f64::from(d));
                if (p - center_m).norm_squared() <= patch_m * patch_m {
                    readings.push(p);
                }
            }
        }
        readings
    }

    /// Whether a fruit of `radius_m` centred at `center_m` passes: the check is off, there are
    /// too few readings to judge, or the flattest curvature times the radius is at least
    /// [`Self::min_relative_curvature`].
    pub fn admits(&self, frame: &RgbdFrame, center_m: &Point3<f64>, radius_m: f64) -> bool {
        !self.enabled
            || self
                .seen_curvature(frame, center_m, radius_m)
                .is_none_or(|seen| seen.flattest_per_m * radius_m >= self.min_relative_curvature)
    }
}

/// Quadric fits per patch: the first on every reading, two more on the readings it and then
/// the second left within the trim.
const FITS: usize = 3;

/// Least-squares coefficients `(a, b, c, d, e, f)` of `z = a·x² + b·x·y + c·y² + d·x + e·y + f`
/// over the `points` marked in `keep`; `None` when the normal equations are singular (the
/// points lie on a line, say).
fn quadric_fit(points: &[[f64; 3]], keep: &[bool]) -> Option<Vector6<f64>> {
    let mut ata = Matrix6::<f64>::zeros();
    let mut atz = Vector6::<f64>::zeros();
    for (p, _) in points.iter().zip(keep).filter(|(_, &k)| k) {
        let row = Vector6::new(p[0] * p[0], p[0] * p[1], p[1] * p[1], p[0], p[1], 1.0);
        ata += row * row.transpose();
        atz += row * p[2];
    }
    ata.cholesky().map(|c| c.solve(&atz))
}

/// The median absolute value of `residuals` (reordered) scaled to a normal distribution's
/// standard deviation (× 1.4826).
fn robust_sigma(residuals: &mut [f64]) -> f64 {
    if residuals.is_empty() {
        return 0.0;
    }
    let mid = residuals.len() / 2;
    let (_, median, _) = residuals.select_nth_unstable_by(mid, f64::total_cmp);
    1.4826 * *median
}

/// The quadric height field `coef` at `(x, y)`.
fn quadric_at(coef: &Vector6<f64>, x: f64, y: f64) -> f64 {
    coef[0] * x * x + coef[1] * x * y + coef[2] * y * y + coef[3] * x + coef[4] * y + coef[5]
}

impl FruitCheck for DoubleCurvatureCheck {
    const STAGE: &'static str = "double-curvature";

    fn admits(&self, frame: &RgbdFrame, center_m: &Point3<f64>, radius_m: f64) -> bool {
        DoubleCurvatureCheck::admits(self, frame, center_m, radius_m)
    }
}

/// The check as a stage over a detector's output: detections on a surface that does not bend
/// both ways are dropped (see [`DetectionFilter`]).
pub type DoubleCurvatureFilter = DetectionFilter<DoubleCurvatureCheck>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Stage;
    use pomona_core::Detection;
    use pomona_core::{DepthImage, PinholeCamera};

    /// A 128×128 camera (focal 200 px) looking at a wall at 1.2 m with `surface` drawn in front
    /// of it: `surface(x, y)` is the depth of the object at the point (x, y) of the plane
    /// z = 0.8 m, or `None` where there is none (orthographic drawing: fine for the curvature
    /// test, which fits a height field along the ray).
    fn scene(surface: impl Fn(f64, f64) -> Option<f64>) -> RgbdFrame {
        let cam = PinholeCamera::new(128, 128, 200.0, 200.0, 63.5, 63.5).unwrap();
        let mut depth = vec![1.2_f32; 128 * 128];
        for v in 0..128 {
            for u in 0..128 {
                let p = cam.back_project(u as f64, v as f64, 0.8);
                if let Some(z) = surface(p.x, p.y) {
                    depth[v * 128 + u] = z as f32;
                }
            }
        }
        RgbdFrame::new(cam, DepthImage::from_meters(128, 128, depth).unwrap(), None).unwrap()
    }

    const CENTRE: Point3<f64> = Point3::new(0.0, 0.0, 0.8);

    /// A ball of 40 mm radius whose centre is at `CENTRE`.
    fn ball(x: f64, y: f64) -> Option<f64> {
        let r2 = 0.04 * 0.04 - x * x - y * y;
        (r2 >= 0.0).then(|| 0.8 - r2.sqrt())
    }

    #[test]
    fn a_ball_bends_both_ways_by_its_radius() {
        let frame = scene(ball);
        let check = DoubleCurvatureCheck::default();
        let seen = check.seen_curvature(&frame, &CENTRE, 0.04).unwrap();
        // The ball's 25 /m, read high by a quadric that follows the steepening rim of the
        // cap (about 41 /m here); the same both ways.
        for k in [seen.flattest_per_m, seen.steepest_per_m] {
            assert!((25.0..50.0).contains(&k), "{seen:?}");
        }
        assert!(
            (seen.flattest_per_m - seen.steepest_per_m).abs() < 1.0,
            "{seen:?}"
        );
        assert!(check.admits(&frame, &CENTRE, 0.04));
    }

    #[test]
    fn a_noisy_camera_s_ball_keeps_its_readings_in_the_fit() {
        // Up to ±10 mm of deterministic noise (a 176×144 time-of-flight camera's at its range):
        // the trim follows the residual scale, so the fruit's own readings stay in the fit,
        // where a fixed 6 mm trim drops more than a quarter of them.
        let noise = |x: f64, y: f64| 0.01 * ((x * 7919.0 + y * 104_729.0).sin() * 43_758.5).fract();
        let clean = DoubleCurvatureCheck::default()
            .seen_curvature(&scene(ball), &CENTRE, 0.04)
            .unwrap();
        let frame = scene(|x, y| ball(x, y).map(|z| z + noise(x, y)));
        let check = DoubleCurvatureCheck::default();
        let seen = check.seen_curvature(&frame, &CENTRE, 0.04).unwrap();
        assert_eq!(seen.readings, clean.readings, "{seen:?} {clean:?}");
        assert!(seen.flattest_per_m > 30.0, "{seen:?}");
        assert!(check.admits(&frame, &CENTRE, 0.04));
        let fixed = DoubleCurvatureCheck {
            trim_sigmas: 0.0,
            ..check
        }
        .seen_curvature(&frame, &CENTRE, 0.04)
        .unwrap();
        assert!(4 * fixed.readings < 3 * clean.readings, "{fixed:?}");
    }

    #[test]
    fn a_leaf_folded_along_one_line_is_refused_and_a_flat_one_too() {
        // A blade bent round a vertical fold line, as curved across as the ball, straight
        // along: the front of a 40 mm cylinder, 50 mm in front of the fruit centre.
        let folded = scene(|x, y| {
            let r2 = 0.04 * 0.04 - x * x;
            (r2 >= 0.0 && y.abs() < 0.08).then(|| 0.8 - r2.sqrt())
        });
        let check = DoubleCurvatureCheck::default();
        let seen = check.seen_curvature(&folded, &CENTRE, 0.04).unwrap();
        assert!(seen.flattest_per_m.abs() < 1.0, "{seen:?}");
        assert!(seen.steepest_per_m > 15.0, "{seen:?}");
        assert!(!check.admits(&folded, &CENTRE, 0.04));
        let flat = scene(|x, y| (x.abs() < 0.08 && y.abs() < 0.08).then_some(0.77));
        assert!(!check.admits(&flat, &CENTRE, 0.04));
        assert!(DoubleCurvatureCheck::off().admits(&flat, &CENTRE, 0.04));
    }

    #[test]
    fn a_saddle_is_refused() {
        let saddle = scene(|x, y| Some(0.77 + 10.0 * (x * x - y * y)));
        let seen = DoubleCurvatureCheck::default()
            .seen_curvature(&saddle, &CENTRE, 0.04)
            .unwrap();
        assert!(
            seen.flattest_per_m < -15.0 && seen.steepest_per_m > 15.0,
            "{seen:?}"
        );
    }

    #[test]
    fn a_leaf_in_front_of_part_of_a_ball_does_not_decide_it() {
        // A flat leaf 30 mm in front of the ball's near side covers its left third.
        let frame = scene(|x, y| if x < -0.015 { Some(0.73) } else { ball(x, y) });
        assert!(DoubleCurvatureCheck::default().admits(&frame, &CENTRE, 0.04));
    }

    #[test]
    fn without_readings_a_detection_is_admitted_unjudged() {
        let empty = scene(|_, _| None);
        // Far from the wall: nothing within 1.4 radii of a centre at 0.8 m.
        let check = DoubleCurvatureCheck::default();
        assert!(check.seen_curvature(&empty, &CENTRE, 0.04).is_none());
        assert!(check.admits(&empty, &CENTRE, 0.04));
        // A centre outside the view, or behind the camera.
        assert!(check.admits(&empty, &Point3::new(5.0, 0.0, 0.8), 0.04));
        assert!(check.admits(&empty, &Point3::new(0.0, 0.0, -0.8), 0.04));
    }

    #[test]
    fn the_stage_drops_only_what_the_check_refuses() {
        let folded = scene(|x, y| {
            let r2 = 0.04 * 0.04 - x * x;
            (r2 >= 0.0 && y.abs() < 0.08).then(|| 0.8 - r2.sqrt())
        });
        let on_fold = Detection::new(CENTRE, 1.0);
        let elsewhere = Detection::new(Point3::new(0.0, 0.0, 2.0), 0.5);
        let stage = DoubleCurvatureFilter {
            check: DoubleCurvatureCheck::default(),
            fallback_radius_m: Some(0.04),
        };
        let kept = stage
            .run((&folded, vec![on_fold.clone(), elsewhere.clone()]))
            .unwrap();
        assert_eq!(kept, vec![elsewhere]);
    }

    #[test]
    fn bad_settings_are_named() {
        let mut c = DoubleCurvatureCheck::default();
        assert_eq!(c.invalid_reason(), None);
        c.patch_radii = 0.0;
        assert_eq!(
            c.invalid_reason().map(|r| r.0),
            Some("double_curvature.patch_radii")
        );
        let c = DoubleCurvatureCheck {
            min_readings: 3,
            ..DoubleCurvatureCheck::default()
        };
        assert_eq!(
            c.invalid_reason().map(|r| r.0),
            Some("double_curvature.min_readings")
        );
        let c = DoubleCurvatureCheck {
            trim_m: f64::NAN,
            ..DoubleCurvatureCheck::default()
        };
        assert_eq!(
            c.invalid_reason().map(|r| r.0),
            Some("double_curvature.trim_m")
        );
    }
}
