//! The free-space check: a fruit is opaque, so the camera cannot see *through* a detected fruit's
//! centre. Along the rays through the middle of the fruit's image the depth camera must meet a
//! surface in front of the centre: the fruit's own near side (about 0.6–1 radius in front), or
//! a leaf that hides it (further in front). A detection whose centre has the seen surface
//! *behind* it claims a fruit in space the camera looks through — a sphere fitted to the
//! inside of a curled leaf, or spanning two leaves with the background visible between them.
//!
//! Not in the seed papers: their classifiers see a candidate's own points only, and a concave
//! fit or a floating one looks to the descriptor much like a fruit. The check is geometry, not
//! learnt, so it holds for any camera, leaf shape or light. Measured on the synthetic `wide`
//! test sets (docs/results.md, "Free-space check"): at the operating confidence, of 590 fruit
//! matched by shape-fit the smallest lead was 0.6 radius (2 % quantile), while about a fifth of
//! its false detections had the seen surface behind their centre, most of them far behind.
//!
//! The lead is measured as a median over a disc of pixels around the projected centre, so a
//! few flying pixels or a hole in the depth image do not decide it; a detection with no depth
//! reading in its disc is admitted (no evidence against it).
//!
//! The median alone admits a sphere laid over a clump of leaves: most of its disc sees the
//! leaves in front of its centre, and the gaps between them — where the camera sees the
//! background far behind — are outvoted. So the check also bounds the **see-through share**:
//! the fraction of the depth readings near the projected centre (within 0.3 of the fruit's
//! image radius) that lie more than two radii behind the centre. An opaque fruit allows none
//! there (its near side lies about a radius in front of the centre); the default allows a
//! fifth. The inner disc and the two radii leave room for what real sensors and detectors do:
//! a centre off the fruit's middle or a radius too large puts the background beyond the
//! outline into a wider disc, and time-of-flight mixed pixels read a far apple's surface up to
//! two radii behind where it is (real `ak-apples`, 1.7 m). Leaf clumps that a sphere fits
//! (their gaps show the background far behind) exceed it (docs/results.md, "See-through
//! share").
//!
//! That room is for a fruit the colour found. A detection nothing but its geometry vouches for
//! — a depth proposal of shape-fit, any detection of the colour-blind box detectors — is held
//! to [`FreeSpaceCheck::strict`] instead: a tenth of the readings over 0.7 of its disc, one
//! radius behind the centre (docs/results.md, "Depth proposals held to what an opaque solid
//! shows").

use pomona_core::nalgebra::Point3;
use pomona_core::RgbdFrame;
use serde::{Deserialize, Serialize};

use crate::{DetectionFilter, FruitCheck};

/// When a detection passes the free-space check, and how the seen surface is measured.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FreeSpaceCheck {
    /// Whether detections are checked at all.
    pub enabled: bool,
    /// Least accepted lead of the seen surface in front of the centre, in fruit radii
    /// (negative: the surface may lie that far behind). The physical bound is 0; the default
    /// −1.5 leaves room for a centre that is off the fruit's middle and for depth registered
    /// from another viewpoint. On the real `ak-apples` frames shape-fit's matched apples, some
    /// centred 30–37 mm off, lead by −1.04 radius at worst (one whose annotated centre itself
    /// leads by −0.95); on the synthetic test sets the matched fruit lead by 0.6 or more, and
    /// most false detections the check catches lie far below (−5 to −60 radii: spheres across
    /// leaves with the background seen between them).
    pub min_lead_radii: f64,
    /// Radius of the disc of pixels around the projected centre whose median depth is the seen
    /// surface, as a fraction of the fruit's image radius (default 0.5: the middle of the fruit,
    /// clear of its outline, where a depth camera's edge errors lie).
    pub disc_radius_fraction: f64,
    /// Largest accepted share of the depth readings over the inner disc
    /// ([`Self::see_through_disc_fraction`]) that lie more than [`Self::see_through_radii`]
    /// behind the centre (the camera looks through where the fruit should be); `None`: no
    /// limit, the median test alone (the check as first built). In `[0, 1]`. Absent in older
    /// model files: the default, 0.2.
    #[serde(default = "default_max_see_through_share")]
    pub max_see_through_share: Option<f64>,
    /// How far behind the centre, in fruit radii, a depth reading counts as seen through the
    /// fruit (default 2). Non-negative. Absent in older model files: the default.
    #[serde(default = "default_see_through_radii")]
    pub see_through_radii: f64,
    /// Radius of the disc around the projected centre over which the see-through share is
    /// counted, as a fraction of the fruit's image radius: smaller than the median's disc, so
    /// that a detection whose centre or radius is off does not count the background beyond
    /// the fruit's outline as seen through it (default 0.3). Positive. Absent in older model
    /// files: the default.
    #[serde(default = "default_see_through_disc_fraction")]
    pub see_through_disc_fraction: f64,
}

/// The default of [`FreeSpaceCheck::max_see_through_share`].
fn default_max_see_through_share() -> Option<f64> {
    Some(0.2)
}

/// The default of [`FreeSpaceCheck::see_through_radii`].
fn default_see_through_radii() -> f64 {
    2.0
}

/// The default of [`FreeSpaceCheck::see_through_disc_fraction`].
fn default_see_through_disc_fraction() -> f64 {
    0.3
}

/// What the depth camera sees over the disc around a fruit's projected centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeenSurface {
    /// How far the seen surface lies in front of the centre, in fruit radii:
    /// `(z_centre − median depth) / radius`.
    pub lead_radii: f64,
    /// Share of the depth readings over the inner disc
    /// ([`FreeSpaceCheck::see_through_disc_fraction`]) more than
    /// [`FreeSpaceCheck::see_through_radii`] behind the centre (0 when it has none).
    pub see_through_share: f64,
}

impl Default for FreeSpaceCheck {
    fn default() -> Self {
        Self {
            enabled: true,
            min_lead_radii: -1.5,
            disc_radius_fraction: 0.5,
            max_see_through_share: default_max_see_through_share(),
            see_through_radii: default_see_through_radii(),
            see_through_disc_fraction: default_see_through_disc_fraction(),
        }
    }
}

impl FreeSpaceCheck {
    /// The check switched off (every detection passes).
    pub fn off() -> Self {
        Self {
            enabled: false,
            ..Self::default()
        }
    }

    /// The check for detections that no colour vouches for — shape-fit's depth proposals and
    /// the colour-blind box detectors (`symmetry`, `viewer-pose`): at most a tenth of the
    /// readings within 0.7 of the fruit's image radius may lie a radius behind its centre,
    /// where [`Self::default`] allows a fifth of those within 0.3 two radii behind. A
    /// clump of leaves that a shape fits shows the background through gaps all over its disc;
    /// an opaque fruit shows none. The default's room is for a colour-found fruit's real-sensor
    /// mixed pixels; without colour, the geometry is all the evidence there is
    /// (docs/results.md, "Depth proposals held to what an opaque solid shows").
    pub fn strict() -> Self {
        Self {
            max_see_through_share: Some(0.1),
            see_through_radii: 1.0,
            see_through_disc_fraction: 0.7,
            ..Self::default()
        }
    }

    /// Which setting is unusable (its key under `free_space`), its value and why, if one is:
    /// `min_lead_radii` must be finite, `disc_radius_fraction` finite and positive,
    /// `max_see_through_share` in `[0, 1]`, `see_through_radii` finite and non-negative and
    /// `see_through_disc_fraction` finite and positive.
    pub fn invalid_reason(&self) -> Option<(&'static str, f64, &'static str)> {
        if !self.min_lead_radii.is_finite() {
            Some((
                "free_space.min_lead_radii",
                self.min_lead_radii,
                "must be finite",
            ))
        } else if !(self.disc_radius_fraction.is_finite() && self.disc_radius_fraction > 0.0) {
            Some((
                "free_space.disc_radius_fraction",
                self.disc_radius_fraction,
                "must be finite and > 0",
            ))
        } else if let Some(share) = self
            .max_see_through_share
            .filter(|s| !(0.0..=1.0).contains(s))
        {
            Some((
                "free_space.max_see_through_share",
                share,
                "must be in [0, 1]",
            ))
        } else if !(self.see_through_radii.is_finite() && self.see_through_radii >= 0.0) {
            Some((
                "free_space.see_through_radii",
                self.see_through_radii,
                "must be finite and >= 0",
            ))
        } else if !(self.see_through_disc_fraction.is_finite()
            && self.see_through_disc_fraction > 0.0)
        {
            Some((
                "free_space.see_through_disc_fraction",
                self.see_through_disc_fraction,
                "must be finite and > 0",
            ))
        } else {
            None
        }
    }

    /// What the camera sees over a fruit of `radius_m` centred at `center_m` (camera frame): the
    /// lead ([`SeenSurface::lead_radii`], the median over the disc of
    /// [`Self::disc_radius_fraction`] × the fruit's image radius, at least one pixel, around the
    /// projected centre) and the see-through share ([`SeenSurface::see_through_share`]). `None`
    /// when the centre does not project into the image, the radius is not positive, or no pixel
    /// of the disc has depth.
    pub fn seen_surface(
        &self,
        frame: &RgbdFrame,
        center_m: &Point3<f64>,
        radius_m: f64,
    ) -> Option<SeenSurface> {
        let cam = frame.camera();
        if !(radius_m > 0.0 && center_m.z > 0.0) {
            return None;
        }
        let (u0, v0) = cam.pixel_of(&cam.project(center_m)?)?;
        let (u0, v0, w, h) = (
            i64::from(u0),
            i64::from(v0),
            i64::from(cam.width),
            i64::from(cam.height),
        );
        let image_radius_px = cam.fx * radius_m / center_m.z;
        let disc_px = (self.disc_radius_fraction * image_radius_px).max(1.0);
        let inner_px = (self.see_through_disc_fraction * image_radius_px).max(1.0);
        let reach = disc_px.max(inner_px).floor() as i64;
        let through_m = center_m.z + self.see_through_radii * radius_m;
        let depth = frame.depth().as_slice();
        let mut seen: Vec<f32> = Vec::with_capacity(((2 * reach + 1) * (2 * reach + 1)) as usize);
        let (mut inner, mut inner_through) = (0_usize, 0_usize);
        for v in (v0 - reach).max(0)..=(v0 + reach).min(h - 1) {
            for u in (u0 - reach).max(0)..=(u0 + reach).min(w - 1) {
                let d = depth[(v * w + u) as usize];
                if !d.is_finite() {
                    continue;
                }
                let (du, dv) = ((u - u0) as f64, (v - v0) as f64);
                let r2 = du * du + dv * dv;
                if r2 <= disc_px * disc_px {
                    seen.push(d);
                }
                if r2 <= inner_px * inner_px {
                    inner += 1;
                    inner_through += usize::from(f64::from(d) > through_m);
                }
            }
        }
        if seen.is_empty() {
            return None;
        }
        let see_through_share = if inner == 0 {
            0.0
        } else {
            inner_through as f64 / inner as f64
        };
        let mid = seen.len() / 2;
        let (_, median, _) = seen.select_nth_unstable_by(mid, f32::total_cmp);
        Some(SeenSurface {
            lead_radii: (center_m.z - f64::from(*median)) / radius_m,
            see_through_share,
        })
    }

    /// Keeps the `items` that pass ([`Self::admits`]); `sphere` gives an item's centre and
    /// radius. Every item is kept when the check is off.
    pub fn retain_admitted<T>(
        &self,
        frame: &RgbdFrame,
        items: &mut Vec<T>,
        sphere: impl Fn(&T) -> (Point3<f64>, f64),
    ) {
        if self.enabled {
            items.retain(|item| {
                let (center_m, radius_m) = sphere(item);
                self.admits(frame, &center_m, radius_m)
            });
        }
    }

    /// Whether a fruit of `radius_m` centred at `center_m` passes: the check is off, there is no
    /// depth to judge by, or the seen surface leads the centre by at least
    /// [`Self::min_lead_radii`] and at most [`Self::max_see_through_share`] of it is seen
    /// through the fruit.
    pub fn admits(&self, frame: &RgbdFrame, center_m: &Point3<f64>, radius_m: f64) -> bool {
        !self.enabled
            || self
                .seen_surface(frame, center_m, radius_m)
                .is_none_or(|seen| {
                    seen.lead_radii >= self.min_lead_radii
                        && self
                            .max_see_through_share
                            .is_none_or(|most| seen.see_through_share <= most)
                })
    }
}

impl FruitCheck for FreeSpaceCheck {
    const STAGE: &'static str = "free-space";

    fn admits(&self, frame: &RgbdFrame, center_m: &Point3<f64>, radius_m: f64) -> bool {
        FreeSpaceCheck::admits(self, frame, center_m, radius_m)
    }
}

/// The check as a stage over a detector's output: detections the camera sees through are
/// dropped (see [`DetectionFilter`]).
pub type FreeSpaceFilter = DetectionFilter<FreeSpaceCheck>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Stage;
    use pomona_core::Detection;
    use pomona_core::{DepthImage, PinholeCamera};

    /// A 64×64 camera (focal 100 px) looking at a wall at `wall_m`, with a 40 mm ball at
    /// (0, 0, 0.8) m drawn in front of it when `ball` is set (exact ray–sphere depth).
    fn scene(wall_m: f64, ball: bool) -> RgbdFrame {
        scene_with_focal(100.0, wall_m, ball)
    }

    /// [`scene`] through a lens of `focal_px`.
    fn scene_with_focal(focal_px: f64, wall_m: f64, ball: bool) -> RgbdFrame {
        let cam = PinholeCamera::new(64, 64, focal_px, focal_px, 31.5, 31.5).unwrap();
        let (c, r) = (Point3::new(0.0, 0.0, 0.8), 0.04);
        let mut depth = vec![wall_m as f32; 64 * 64];
        if ball {
            for v in 0..64 {
                for u in 0..64 {
                    let d = cam.back_project(u as f64, v as f64, 1.0).coords.normalize();
                    let b = d.dot(&c.coords);
                    let disc = b * b - (c.coords.norm_squared() - r * r);
                    if disc >= 0.0 {
                        let t = b - disc.sqrt();
                        depth[v * 64 + u] = (d * t).z as f32;
                    }
                }
            }
        }
        let depth = DepthImage::from_meters(64, 64, depth).unwrap();
        RgbdFrame::new(cam, depth, None).unwrap()
    }

    #[test]
    fn a_seen_ball_leads_its_centre_by_most_of_a_radius() {
        let frame = scene(1.5, true);
        let check = FreeSpaceCheck::default();
        let lead = check
            .seen_surface(&frame, &Point3::new(0.0, 0.0, 0.8), 0.04)
            .map(|seen| seen.lead_radii)
            .unwrap();
        assert!((0.85..=1.0).contains(&lead), "lead {lead}");
        assert!(check.admits(&frame, &Point3::new(0.0, 0.0, 0.8), 0.04));
    }

    #[test]
    fn a_centre_in_front_of_the_seen_surface_is_refused() {
        // No ball: the camera sees the wall at 1.0 m through where a fruit at 0.8 m is claimed.
        let frame = scene(1.0, false);
        let check = FreeSpaceCheck::default();
        let centre = Point3::new(0.0, 0.0, 0.8);
        let lead = check
            .seen_surface(&frame, &centre, 0.04)
            .map(|seen| seen.lead_radii)
            .unwrap();
        assert!((lead + 5.0).abs() < 1e-6, "lead {lead}");
        // Within the tolerance behind the centre: admitted.
        assert!(check.admits(&scene(0.85, false), &centre, 0.04));
        assert!(!check.admits(&frame, &centre, 0.04));
        assert!(FreeSpaceCheck::off().admits(&frame, &centre, 0.04));
        // A leaf in front of the fruit (wall at 0.7 m) is no evidence against it.
        assert!(check.admits(&scene(0.7, false), &centre, 0.04));
    }

    /// Leaves at 0.78 m in vertical stripes, every third pixel column a gap onto a wall at
    /// 1.5 m: a clump a sphere at 0.8 m could be laid over.
    fn leaves_with_gaps() -> RgbdFrame {
        let cam = PinholeCamera::new(64, 64, 100.0, 100.0, 31.5, 31.5).unwrap();
        let depth = (0..64 * 64)
            .map(|i| if i % 64 % 3 == 0 { 1.5 } else { 0.78 })
            .collect();
        RgbdFrame::new(cam, DepthImage::from_meters(64, 64, depth).unwrap(), None).unwrap()
    }

    #[test]
    fn a_sphere_over_leaves_with_the_background_seen_between_them_is_refused() {
        let frame = leaves_with_gaps();
        let centre = Point3::new(0.0, 0.0, 0.8);
        let check = FreeSpaceCheck::default();
        let seen = check.seen_surface(&frame, &centre, 0.04).unwrap();
        // The leaves outvote the gaps in the median: the first check alone admits the sphere.
        assert!((seen.lead_radii - 0.5).abs() < 1e-5, "{seen:?}");
        assert!((0.25..0.45).contains(&seen.see_through_share), "{seen:?}");
        assert!(!check.admits(&frame, &centre, 0.04));
        let median_only = FreeSpaceCheck {
            max_see_through_share: None,
            ..check
        };
        assert!(median_only.admits(&frame, &centre, 0.04));
        let lenient = FreeSpaceCheck {
            max_see_through_share: Some(0.5),
            ..check
        };
        assert!(lenient.admits(&frame, &centre, 0.04));
        // A real ball over the same wall is seen through nowhere.
        let ball = check
            .seen_surface(&scene(1.5, true), &centre, 0.04)
            .unwrap();
        assert_eq!(ball.see_through_share, 0.0);
    }

    #[test]
    fn an_oversized_sphere_off_the_balls_middle_counts_the_ball_not_the_wall_beside_it() {
        // The ball is 10 px across its radius; the detection is 0.7 of its radius to the side
        // and a quarter too large, so half its radius reaches past the outline onto the wall.
        let frame = scene_with_focal(200.0, 1.5, true);
        let (centre, radius) = (Point3::new(0.028, 0.0, 0.8), 0.05);
        let check = FreeSpaceCheck::default();
        let seen = check.seen_surface(&frame, &centre, radius).unwrap();
        assert!(seen.see_through_share < 0.2, "{seen:?}");
        assert!(check.admits(&frame, &centre, radius));
        let wide = FreeSpaceCheck {
            see_through_disc_fraction: 0.5,
            ..check
        };
        let seen = wide.seen_surface(&frame, &centre, radius).unwrap();
        assert!(seen.see_through_share > 0.2, "{seen:?}");
        assert!(!wide.admits(&frame, &centre, radius));
    }

    #[test]
    fn model_files_without_the_see_through_keys_get_the_defaults() {
        let old: FreeSpaceCheck = serde_json::from_str(
            r#"{"enabled":true,"min_lead_radii":-1.5,"disc_radius_fraction":0.5}"#,
        )
        .unwrap();
        assert_eq!(old, FreeSpaceCheck::default());
        let none: FreeSpaceCheck = serde_json::from_str(
            r#"{"enabled":true,"min_lead_radii":-1.5,"disc_radius_fraction":0.5,
                "max_see_through_share":null}"#,
        )
        .unwrap();
        assert_eq!(none.max_see_through_share, None);
    }

    #[test]
    fn the_filter_drops_detections_the_camera_sees_through() {
        let frame = scene(1.0, false);
        let filter = FreeSpaceFilter {
            check: FreeSpaceCheck::default(),
            fallback_radius_m: Some(0.03),
        };
        let floating = Detection::new(Point3::new(0.0, 0.0, 0.8), 1.0);
        let behind_leaf = Detection {
            diameter_m: Some(0.08),
            ..Detection::new(Point3::new(0.0, 0.0, 1.05), 0.5)
        };
        let kept = filter
            .run((&frame, vec![floating.clone(), behind_leaf.clone()]))
            .unwrap();
        assert_eq!(kept, vec![behind_leaf.clone()]);
        let off = FreeSpaceFilter {
            check: FreeSpaceCheck::off(),
            ..filter
        };
        let all = off.run((&frame, vec![floating, behind_leaf])).unwrap();
        assert_eq!(all.len(), 2);
    }

    #[test]
    fn unusable_settings_are_named() {
        assert_eq!(FreeSpaceCheck::default().invalid_reason(), None);
        let d = FreeSpaceCheck::default();
        let cases = [
            (
                FreeSpaceCheck {
                    min_lead_radii: f64::NAN,
                    ..d
                },
                "free_space.min_lead_radii",
            ),
            (
                FreeSpaceCheck {
                    disc_radius_fraction: 0.0,
                    ..d
                },
                "free_space.disc_radius_fraction",
            ),
            (
                FreeSpaceCheck {
                    max_see_through_share: Some(1.5),
                    ..d
                },
                "free_space.max_see_through_share",
            ),
            (
                FreeSpaceCheck {
                    see_through_radii: -0.5,
                    ..d
                },
                "free_space.see_through_radii",
            ),
            (
                FreeSpaceCheck {
                    see_through_disc_fraction: 0.0,
                    ..d
                },
                "free_space.see_through_disc_fraction",
            ),
        ];
        for (check, key) in cases {
            assert_eq!(check.invalid_reason().map(|r| r.0), Some(key));
        }
    }

    #[test]
    fn without_depth_or_outside_the_image_there_is_no_verdict() {
        let cam = PinholeCamera::new(64, 64, 100.0, 100.0, 31.5, 31.5).unwrap();
        let depth = DepthImage::from_meters(64, 64, vec![f32::NAN; 64 * 64]).unwrap();
        let frame = RgbdFrame::new(cam, depth, None).unwrap();
        let check = FreeSpaceCheck::default();
        let centre = Point3::new(0.0, 0.0, 0.8);
        assert_eq!(check.seen_surface(&frame, &centre, 0.04), None);
        assert!(check.admits(&frame, &centre, 0.04));
        let wall = scene(1.0, false);
        let beside = Point3::new(2.0, 0.0, 0.8);
        assert_eq!(check.seen_surface(&wall, &beside, 0.04), None);
        assert_eq!(check.seen_surface(&wall, &centre, 0.0), None);
    }
}
