//! Pairs for the circles the relaxation leaves unpaired, found by appearance: **an addition to
//! seed 004**, run after its relaxation (Eqs. 11–16), which it never changes.
//!
//! Why: the seed pairs two circles only when their offset lies inside the Eq. 10 windows. The
//! detector's circles of one fruit can sit a fraction of a radius apart in the two views (each
//! view sees a different part of the outline: a near fruit half behind a leaf), so the vertical
//! offset of a fruit's own two circles can exceed the row window `ΔY_M` and both stay unpaired.
//! Widening the window lets neighbours above and below compete with every pair (measured in
//! docs/results.md: about one wrong pair for every two or three recovered). This pass looks at the
//! *leftovers* only and asks the image, not the circle centres, where the fruit went:
//! * each unpaired primary circle's patch is swept along its whole ray over the working range
//!   ([`DisparityRefinement::best_along_ray`], the sweep of the better-elsewhere check of
//!   [`crate::PairEvidence`]); when its best NCC reaches `min_ncc`, that best place is where
//!   the fruit's centre lies in the stereo view;
//! * an unpaired stereo circle whose centre lies within `max_distance_radii` of its own radius
//!   from that place, and whose disparity lies inside the Eq. 10 disparity window, is a
//!   candidate;
//! * candidates are taken nearest first (then by primary and stereo index, so the result does
//!   not depend on the order of equal distances), each circle at most once.
//!
//! A pair made here cannot take a partner from a pair the relaxation made, and a neighbour's
//! circle qualifies only when the fruit's own appearance lands on it. Limits: when the fruit's
//! stereo circle is missing and a touching neighbour's leftover circle lies within the distance,
//! the pair is wrong (the default half radius was chosen on tuning rigs where it added one
//! wrong pair for nine right ones).

use nalgebra::Point2;
use pomona_core::{ColorImage, ImageCircle};

use crate::{ArmError, DisparityRefinement, MatchingWindows, RotatedStereo, StereoPair};

/// Parameters of the leftover pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeftoverPairing {
    /// A stereo circle is a candidate when its centre lies within this many of its radii from
    /// where the primary patch matches best. Finite, non-negative.
    pub max_distance_radii: f64,
    /// The primary patch's best NCC along its ray must reach this. In `[-1, 1]`.
    pub min_ncc: f64,
    /// Sphere distances from the primary lens swept along the ray, metres (the working range):
    /// `0 < nearest < farthest`.
    pub distance_range_m: (f64, f64),
    /// The patch and the sweep (only `patch_scale`, `step_px` and the patch's pixel selection
    /// matter: the whole range is swept).
    pub appearance: DisparityRefinement,
}

impl LeftoverPairing {
    /// The pass as measured in docs/results.md ("Leftover circles paired by appearance"):
    /// half a radius, NCC ≥ 0.5, the appearance sweep of [`crate::PairEvidence`]'s default, over
    /// `distance_range_m`.
    pub fn new(distance_range_m: (f64, f64)) -> Self {
        Self {
            max_distance_radii: 0.5,
            min_ncc: 0.5,
            distance_range_m,
            appearance: crate::PairEvidence::default().appearance,
        }
    }

    /// Checks the parameters' ranges.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] naming the first parameter out of range.
    pub fn validate(&self) -> Result<(), ArmError> {
        if !(self.max_distance_radii.is_finite() && self.max_distance_radii >= 0.0) {
            return Err(ArmError::InvalidParameter {
                name: "max_distance_radii",
                value: self.max_distance_radii,
                reason: "must be finite and non-negative",
            });
        }
        if !(-1.0..=1.0).contains(&self.min_ncc) {
            return Err(ArmError::InvalidParameter {
                name: "min_ncc",
                value: self.min_ncc,
                reason: "must be in [-1, 1]",
            });
        }
        let (near, far) = self.distance_range_m;
        if !(near.is_finite() && far.is_finite() && 0.0 < near && near < far) {
            return Err(ArmError::InvalidParameter {
                name: "distance_range_m",
                value: near,
                reason: "needs finite 0 < nearest < farthest",
            });
        }
        self.appearance.validate()
    }

    /// New pairs among the circles that no pair of `made` uses; `primary` and `stereo` are the
    /// circles `made` indexes, `windows` the Eq. 10 windows whose disparity range a new pair
    /// must respect. The pairs of `made` are not changed; the new ones are returned sorted by
    /// primary index.
    ///
    /// # Errors
    /// As [`LeftoverPairing::validate`]; [`ArmError::InvalidParameter`] for a non-positive
    /// radius and [`ArmError::ImageSize`] when an image's size is not the rig camera's.
    pub fn pair(
        &self,
        rig: &RotatedStereo,
        images: (&ColorImage, &ColorImage),
        (primary, stereo): (&[ImageCircle], &[ImageCircle]),
        windows: &MatchingWindows,
        made: &[StereoPair],
    ) -> Result<Vec<StereoPair>, ArmError> {
        self.validate()?;
        let mut primary_used = vec![false; primary.len()];
        let mut stereo_used = vec![false; stereo.len()];
        for p in made {
            if let Some(u) = primary_used.get_mut(p.primary) {
                *u = true;
            }
            if let Some(u) = stereo_used.get_mut(p.stereo) {
                *u = true;
            }
        }
        let in_window = |p: &ImageCircle, s: &ImageCircle| {
            windows.admits_disparity(p.center_px.x - s.center_px.x)
        };
        let mut candidates: Vec<(f64, usize, usize)> = Vec::new();
        for (l, p) in primary.iter().enumerate() {
            // The sweep only when some unpaired stereo circle could be the partner.
            let open = |(r, s): (usize, &ImageCircle)| !stereo_used[r] && in_window(p, s);
            if primary_used[l] || !stereo.iter().enumerate().any(open) {
                continue;
            }
            let Some((ncc, at)) = self.appearance.best_along_ray(
                rig,
                images,
                &p.center_px,
                p.radius_px,
                self.distance_range_m,
            )?
            else {
                continue;
            };
            if ncc < self.min_ncc {
                continue;
            }
            for (r, s) in stereo.iter().enumerate() {
                let away = distance_radii(&at, s);
                if open((r, s)) && away <= self.max_distance_radii {
                    candidates.push((away, l, r));
                }
            }
        }
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
        let mut new = Vec::new();
        for (_, l, r) in candidates {
            if primary_used[l] || stereo_used[r] {
                continue;
            }
            primary_used[l] = true;
            stereo_used[r] = true;
            new.push(StereoPair {
                primary: l,
                stereo: r,
                disparity_px: primary[l].center_px.x - stereo[r].center_px.x,
            });
        }
        new.sort_by_key(|p| p.primary);
        Ok(new)
    }
}

/// How far `at` lies from `circle`'s centre, in its radii.
fn distance_radii(at: &Point2<f64>, circle: &ImageCircle) -> f64 {
    (at - circle.center_px).norm() / circle.radius_px
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pair_evidence::tests::{scene, Scene};
    use crate::{DisparityMatrix, RelaxationParams, StereoMatching};

    fn relax(s: &Scene) -> StereoMatching {
        let centres = |c: &[ImageCircle]| c.iter().map(|c| c.center_px).collect::<Vec<_>>();
        DisparityMatrix::from_centres(&centres(&s.primary), &centres(&s.stereo), &s.windows)
            .relax(&RelaxationParams::default())
    }

    fn pass_with(s: &Scene, made: &[StereoPair], k: f64) -> Vec<StereoPair> {
        let pairing = LeftoverPairing {
            max_distance_radii: k,
            ..LeftoverPairing::new((0.3, 2.5))
        };
        let images = (&s.images.0, &s.images.1);
        let circles = (&s.primary[..], &s.stereo[..]);
        pairing
            .pair(&s.rig, images, circles, &s.windows, made)
            .unwrap()
    }

    /// The new pairs at the default distance.
    fn pass_pairs(s: &Scene, made: &[StereoPair]) -> Vec<StereoPair> {
        pass_with(s, made, LeftoverPairing::new((0.3, 2.5)).max_distance_radii)
    }

    fn pass(s: &Scene, made: &[StereoPair], k: f64) -> Vec<(usize, usize)> {
        pass_with(s, made, k)
            .iter()
            .map(|p| (p.primary, p.stereo))
            .collect()
    }

    /// B's stereo circle (radius about 13 px) sits 5 px below where B is (its circle cut
    /// differently in that view), outside the 4 px row window: the relaxation leaves B
    /// unpaired; its appearance finds it 5 px (under 0.4 radii) from that circle.
    fn shifted_scene() -> Scene {
        let mut s = scene();
        s.stereo[0].center_px.y += 5.0;
        s
    }

    #[test]
    fn a_fruit_outside_the_row_window_is_paired_by_its_appearance() {
        let s = shifted_scene();
        let seed = relax(&s);
        let made: Vec<(usize, usize)> = seed.pairs.iter().map(|p| (p.primary, p.stereo)).collect();
        assert_eq!(made, [(2, 1)], "{seed:?}");
        let new = pass_pairs(&s, &seed.pairs);
        assert_eq!(pass(&s, &seed.pairs, 0.5), [(1, 0)]);
        let disparity = s.primary[1].center_px.x - s.stereo[0].center_px.x;
        assert!((new[0].disparity_px - disparity).abs() < 1e-12, "{new:?}");
        // A (primary only) lands where A is, about 30 px (2.3 radii) from B's circle: even at
        // 3 radii B, nearer, wins the circle, and A stays unpaired.
        assert_eq!(pass(&s, &seed.pairs, 3.0), [(1, 0)]);
        // Without B, A would take it at 3 radii and not at half a radius.
        let a_only = |k| {
            let mut s = shifted_scene();
            s.primary.remove(1);
            pass(&s, &relax(&s).pairs, k)
        };
        assert_eq!((a_only(3.0), a_only(0.5)), (vec![(0, 0)], vec![]));
        // Closer than a quarter of a radius is not enough.
        assert_eq!(pass(&s, &seed.pairs, 0.25), []);
        // With B's circle already taken by B, A has no leftover to take.
        let mut b_taken = seed.pairs.clone();
        b_taken.extend(pass_pairs(&s, &seed.pairs));
        assert_eq!(b_taken.len(), 2);
        assert_eq!(pass(&s, &b_taken, 3.0), []);
    }

    #[test]
    fn a_pair_outside_the_disparity_window_is_not_made() {
        let mut s = shifted_scene();
        s.windows.max_disparity_px = s.primary[1].center_px.x - s.stereo[0].center_px.x - 1.0;
        assert_eq!(pass(&s, &relax(&s).pairs, 0.5), []);
    }

    #[test]
    fn a_poor_match_pairs_nothing_and_bad_parameters_are_errors() {
        let s = shifted_scene();
        let strict = LeftoverPairing {
            min_ncc: 1.0,
            ..LeftoverPairing::new((0.3, 2.5))
        };
        let images = (&s.images.0, &s.images.1);
        let circles = (&s.primary[..], &s.stereo[..]);
        let none = strict.pair(&s.rig, images, circles, &s.windows, &relax(&s).pairs);
        assert_eq!(none.unwrap(), []);
        for bad in [
            LeftoverPairing {
                max_distance_radii: -0.1,
                ..strict
            },
            LeftoverPairing {
                min_ncc: 1.5,
                ..strict
            },
            LeftoverPairing {
                distance_range_m: (1.0, 0.5),
                ..strict
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
            assert!(bad.pair(&s.rig, images, circles, &s.windows, &[]).is_err());
        }
    }
}
