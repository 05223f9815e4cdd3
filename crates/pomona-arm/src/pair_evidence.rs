//! Evidence beyond disparity for stereo matching: **an addition to seed 004**, whose relaxation
//! (Eqs. 11–16) weighs a candidate pair only by how far its disparity lies from the scene's mean.
//!
//! Why: the Eq. 10 windows widen with β, so in clustered fruit several stereo circles fall in a
//! primary circle's window at disparities as plausible as the right one, and duplicated or merged
//! circles pair with a neighbour's. Three cues tell the right partner apart:
//! * **Appearance**: the primary circle's patch, moved into the stereo view by the rig's exact
//!   motion and swept along the epipolar line around the pair's disparity
//!   ([`DisparityRefinement::refine`], its best zero-mean NCC over R, G, B), agrees with the
//!   stereo image near the right partner and not near a neighbour (other shading, a leaf, the
//!   background).
//! * **Size**: the two circles' radii agree once the scale change between the views is
//!   accounted for (the pair, triangulated, lies at different distances from the two lenses).
//! * **Rows**: for a rotation about the vertical axis, the two columns locate the fruit (Eq. 18)
//!   and the primary row then predicts the stereo row exactly
//!   ([`RotatedStereo::row_residual_px`]). Eq. 10 bounds the raw row offset by the largest one
//!   anywhere in the image (`ΔY_M`, about 13 px at the corners for β = 4° before its margin);
//!   the residual of the right partner's exact circles is zero wherever they are, so a
//!   neighbour above or below fails a much tighter gate.
//! * **Appearance elsewhere**: when the primary fruit's own circle is missing in the stereo
//!   view, the relaxation pairs it with a neighbour's circle that nobody else claims (the
//!   commonest wrong pair), and no cost can refuse an uncontested candidate. But the fruit is
//!   usually still visible there: swept over the whole working range along the primary ray
//!   ([`DisparityRefinement::best_along_ray`]), the patch matches the undetected fruit better
//!   than the neighbour.
//!
//! How they enter the matching ([`PairEvidence::apply`] on the [`DisparityMatrix`]):
//! * a **row gate**: candidates whose row residual exceeds `max_row_residual_px` are removed;
//! * a **floor**: candidates whose NCC is below `min_ncc` are removed before the relaxation;
//! * a **better match elsewhere** ([`BetterElsewhere`]): candidates whose NCC falls more than a
//!   margin below the best one of their primary circle's whole ray are removed;
//! * a **cost** added to σ = (ΔX − ΔX̄)² (pixels²): `ncc_weight_px2 · (1 − NCC)` and
//!   `radius_weight_px2 · ln(r_stereo / r_expected)²`.
//!
//! Limits (measured in docs/results.md): a right candidate can score low (a leaf in front in one
//! view), and a neighbour of the same size against contrasting foliage shares the silhouette and
//! shading of the patch and can score high; the detector's radii are too noisy for the size cue
//! to help; its circles sit several pixels off their fruit's row where the views see different
//! parts of it, so a row gate tight enough to help also removes right pairs.
//!
//! A candidate whose NCC cannot be computed (a flat patch, a sweep leaving the image, no point in
//! front of both views) is never removed and costs as NCC 0 ("no agreement shown"); a candidate
//! that does not triangulate has no size cost. With everything off ([`PairEvidence::is_off`],
//! the default) nothing is computed and the relaxation is the seed's, bit for bit.

use nalgebra::Point2;
use pomona_core::{ColorImage, ImageCircle};

use crate::{ArmError, DisparityMatrix, DisparityRefinement, RotatedStereo};

/// Parameters of the evidence added to the relaxation. The default is off (the seed's matching).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairEvidence {
    /// Candidates whose |row residual| exceeds this many pixels are removed before the
    /// relaxation; `None`: no gate (Eq. 10's vertical window only). Non-negative.
    pub max_row_residual_px: Option<f64>,
    /// Candidates whose NCC is below this floor are removed before the relaxation; `None`: no
    /// floor. In `[-1, 1]`.
    pub min_ncc: Option<f64>,
    /// Candidates whose primary patch matches better by more than a margin elsewhere along its
    /// ray are removed before the relaxation; `None`: no such check.
    pub better_elsewhere: Option<BetterElsewhere>,
    /// Weight of the appearance cost `1 − NCC` (in `[0, 2]`), pixels². Non-negative; 0 = off.
    pub ncc_weight_px2: f64,
    /// Weight of the size cost `ln(r_stereo / r_expected)²`, pixels². Non-negative; 0 = off.
    pub radius_weight_px2: f64,
    /// The patch and the epipolar sweep that score a candidate's appearance (`min_ncc` of the
    /// refinement plays no part: the best score of the sweep is taken whatever it is).
    pub appearance: DisparityRefinement,
}

impl Default for PairEvidence {
    /// Off: no row gate, no floor, no cost; the appearance sweep of the default refinement
    /// (patch 1.2 r, ±6 px) over every pixel of the patch, as the evidence was measured (the
    /// refinement's fruit-colour selection came later and was not measured here; its border
    /// trim was, and changed nothing but one more wrong pair on the seed-2 rigs).
    fn default() -> Self {
        Self {
            max_row_residual_px: None,
            better_elsewhere: None,
            min_ncc: None,
            ncc_weight_px2: 0.0,
            radius_weight_px2: 0.0,
            appearance: DisparityRefinement {
                fruit_chroma_radius: None,
                whole_patch_min_ncc: None,
                min_inside_fraction: None,
                ..DisparityRefinement::default()
            },
        }
    }
}

/// The check that removes a candidate when its primary circle's patch matches the stereo image
/// clearly better somewhere else along the primary ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BetterElsewhere {
    /// A candidate is removed when the best NCC along the ray exceeds its own by more than this.
    /// In `[0, 2]`.
    pub margin: f64,
    /// ... and the best match lies further than this many stereo-circle radii from the
    /// candidate's stereo circle centre (a right pair whose circles are a few pixels off in
    /// disparity finds its own fruit just outside the candidate's sweep). Non-negative.
    pub min_distance_radii: f64,
    /// Sphere distances from the primary lens swept along the ray, metres (the working range):
    /// `0 < nearest < farthest`.
    pub distance_range_m: (f64, f64),
}

/// [`DisparityRefinement::best_along_ray`]'s answer: best NCC and where it puts the stereo centre.
type BestAlongRay = Option<(f64, Point2<f64>)>;

/// What the evidence found for one candidate pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairScore {
    /// Best NCC of the sweep; `None` when it could not be computed.
    pub ncc: Option<f64>,
    /// `ln(r_stereo / r_expected)`; `None` when the pair does not triangulate.
    pub radius_log_ratio: Option<f64>,
    /// [`RotatedStereo::row_residual_px`]; `None` when the columns locate no point in front of
    /// both views.
    pub row_residual_px: Option<f64>,
    /// With [`PairEvidence::better_elsewhere`]: the best NCC of the primary patch anywhere along
    /// its ray (`None` when it could not be computed, or without the check).
    pub best_along_ray_ncc: Option<f64>,
    /// Where that best match puts the fruit's centre in the stereo view, in radii of the
    /// candidate's stereo circle from its centre.
    pub best_along_ray_distance_radii: Option<f64>,
}

/// What [`PairEvidence::apply`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EvidenceOutcome {
    /// Candidates inside the windows.
    pub candidates: usize,
    /// Of those, candidates whose NCC could not be computed.
    pub unscored: usize,
    /// Candidates removed by the NCC floor.
    pub removed: usize,
    /// Candidates removed by the row gate.
    pub removed_by_rows: usize,
    /// Candidates removed because their patch matches better elsewhere along the ray.
    pub removed_elsewhere: usize,
    /// Every candidate's score: `(row, column, score)`, removed ones included.
    pub scores: Vec<(usize, usize, PairScore)>,
}

impl EvidenceOutcome {
    /// The score of candidate `(l, r)`, if it was scored.
    pub fn score(&self, l: usize, r: usize) -> Option<PairScore> {
        self.scores
            .iter()
            .find(|(a, b, _)| (*a, *b) == (l, r))
            .map(|x| x.2)
    }
}

impl PairEvidence {
    /// Whether no evidence is used (then [`PairEvidence::apply`] leaves the matrix alone).
    pub fn is_off(&self) -> bool {
        self.max_row_residual_px.is_none()
            && self.better_elsewhere.is_none()
            && self.min_ncc.is_none()
            && self.ncc_weight_px2 == 0.0
            && self.radius_weight_px2 == 0.0
    }

    /// Whether the row gate removes a candidate of `score`: its residual is known and larger.
    fn fails_rows(&self, score: &PairScore) -> bool {
        self.max_row_residual_px
            .is_some_and(|gate| score.row_residual_px.is_some_and(|r| r.abs() > gate))
    }

    /// Whether a candidate of `score` is beaten by more than the margin elsewhere along its ray
    /// (both scores known).
    fn fails_elsewhere(&self, score: &PairScore) -> bool {
        self.better_elsewhere.is_some_and(|check| {
            matches!((score.ncc, score.best_along_ray_ncc, score.best_along_ray_distance_radii),
                (Some(own), Some(best), Some(away))
                    if best > own + check.margin && away > check.min_distance_radii)
        })
    }

    /// Whether the floor removes a candidate of `score`: its NCC is known and below `min_ncc`.
    fn fails_floor(&self, score: &PairScore) -> bool {
        self.min_ncc
            .is_some_and(|floor| score.ncc.is_some_and(|n| n < floor))
    }

    fn needs_ncc(&self) -> bool {
        self.min_ncc.is_some() || self.ncc_weight_px2 > 0.0 || self.better_elsewhere.is_some()
    }

    /// Checks the parameters' ranges.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] naming the first parameter out of range.
    pub fn validate(&self) -> Result<(), ArmError> {
        if let Some(gate) = self.max_row_residual_px {
            if !(gate.is_finite() && gate >= 0.0) {
                return Err(ArmError::InvalidParameter {
                    name: "max_row_residual_px",
                    value: gate,
                    reason: "must be finite and non-negative",
                });
            }
        }
        if let Some(check) = self.better_elsewhere {
            let (near, far) = check.distance_range_m;
            if !(check.min_distance_radii.is_finite() && check.min_distance_radii >= 0.0) {
                return Err(ArmError::InvalidParameter {
                    name: "better_elsewhere.min_distance_radii",
                    value: check.min_distance_radii,
                    reason: "must be finite and non-negative",
                });
            }
            if !(0.0..=2.0).contains(&check.margin) {
                return Err(ArmError::InvalidParameter {
                    name: "better_elsewhere.margin",
                    value: check.margin,
                    reason: "must be in [0, 2]",
                });
            }
            if !(near.is_finite() && far.is_finite() && 0.0 < near && near < far) {
                return Err(ArmError::InvalidParameter {
                    name: "better_elsewhere.distance_range_m",
                    value: near,
                    reason: "needs finite 0 < nearest < farthest",
                });
            }
        }
        if let Some(floor) = self.min_ncc {
            if !(-1.0..=1.0).contains(&floor) {
                return Err(ArmError::InvalidParameter {
                    name: "min_ncc",
                    value: floor,
                    reason: "must be in [-1, 1]",
                });
            }
        }
        for (name, value) in [
            ("ncc_weight_px2", self.ncc_weight_px2),
            ("radius_weight_px2", self.radius_weight_px2),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ArmError::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and non-negative",
                });
            }
        }
        self.appearance.validate()
    }

    /// Scores candidate pair (`primary`, `stereo`) in `images` (primary, stereo).
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] for parameters out of range or a non-positive radius;
    /// [`ArmError::ImageSize`] when an image's size is not the rig camera's.
    pub fn score(
        &self,
        rig: &RotatedStereo,
        images: (&ColorImage, &ColorImage),
        primary: &ImageCircle,
        stereo: &ImageCircle,
    ) -> Result<PairScore, ArmError> {
        let ncc = if self.needs_ncc() {
            self.appearance
                .refine(
                    rig,
                    images,
                    &primary.center_px,
                    primary.radius_px,
                    &stereo.center_px,
                )?
                .ncc()
        } else {
            None
        };
        Ok(PairScore {
            ncc,
            radius_log_ratio: radius_log_ratio(rig, primary, stereo),
            row_residual_px: rig
                .row_residual_px(&primary.center_px, &stereo.center_px)
                .ok(),
            best_along_ray_ncc: None,
            best_along_ray_distance_radii: None,
        })
    }

    /// Removes the candidates of `matrix` below the NCC floor and adds the appearance and size
    /// costs to the rest; `primary` and `stereo` are the circles of the matrix's rows and
    /// columns. Does nothing when [`PairEvidence::is_off`].
    ///
    /// # Errors
    /// As [`PairEvidence::score`], and [`ArmError::InvalidParameter`] when the circles do not
    /// match the matrix's shape.
    pub fn apply(
        &self,
        matrix: &mut DisparityMatrix,
        rig: &RotatedStereo,
        images: (&ColorImage, &ColorImage),
        (primary, stereo): (&[ImageCircle], &[ImageCircle]),
    ) -> Result<EvidenceOutcome, ArmError> {
        let mut outcome = EvidenceOutcome::default();
        if self.is_off() {
            return Ok(outcome);
        }
        self.validate()?;
        if matrix.shape() != (primary.len(), stereo.len()) {
            return Err(ArmError::InvalidParameter {
                name: "circles",
                value: (primary.len() * stereo.len()) as f64,
                reason: "the circles must be the rows and columns of the disparity matrix",
            });
        }
        let candidates: Vec<(usize, usize)> = matrix.candidates().map(|(l, r, _)| (l, r)).collect();
        // The best match along each primary circle's ray, swept once per circle.
        let mut along_ray: Vec<Option<BestAlongRay>> = vec![None; primary.len()];
        for (l, r) in candidates {
            outcome.candidates += 1;
            let mut score = self.score(rig, images, &primary[l], &stereo[r])?;
            if let Some(check) = self.better_elsewhere {
                let best = match along_ray[l] {
                    Some(best) => best,
                    None => {
                        let best = self.appearance.best_along_ray(
                            rig,
                            images,
                            &primary[l].center_px,
                            primary[l].radius_px,
                            check.distance_range_m,
                        )?;
                        along_ray[l] = Some(best);
                        best
                    }
                };
                score.best_along_ray_ncc = best.map(|b| b.0);
                score.best_along_ray_distance_radii =
                    best.map(|b| (b.1 - stereo[r].center_px).norm() / stereo[r].radius_px);
            }
            outcome.scores.push((l, r, score));
            if self.needs_ncc() && score.ncc.is_none() {
                outcome.unscored += 1;
            }
            if self.fails_rows(&score) {
                matrix.remove(l, r);
                outcome.removed_by_rows += 1;
                continue;
            }
            if self.fails_elsewhere(&score) {
                matrix.remove(l, r);
                outcome.removed_elsewhere += 1;
                continue;
            }
            if self.fails_floor(&score) {
                matrix.remove(l, r);
                outcome.removed += 1;
                continue;
            }
            let mut cost = 0.0;
            if self.ncc_weight_px2 > 0.0 {
                cost += self.ncc_weight_px2 * (1.0 - score.ncc.unwrap_or(0.0));
            }
            if let (true, Some(ratio)) = (self.radius_weight_px2 > 0.0, score.radius_log_ratio) {
                cost += self.radius_weight_px2 * ratio * ratio;
            }
            matrix.add_cost(l, r, cost);
        }
        Ok(outcome)
    }
}

/// `ln(r_stereo / r_expected)`: the stereo radius against the primary circle's angular size seen
/// from the stereo lens, the pair triangulated; `None` when it does not triangulate or a radius
/// is not positive.
fn radius_log_ratio(
    rig: &RotatedStereo,
    primary: &ImageCircle,
    stereo: &ImageCircle,
) -> Option<f64> {
    if !(primary.radius_px > 0.0 && stereo.radius_px > 0.0) {
        return None;
    }
    let point = rig
        .triangulate(&primary.center_px, &stereo.center_px)
        .ok()?;
    let rho_primary = point.coords.norm();
    let rho_stereo = (rig.stereo_from_camera() * point).coords.norm();
    let f = rig.camera.mean_focal_px();
    let sin_alpha = (primary.radius_px / f).atan().sin();
    let sin_stereo = sin_alpha * rho_primary / rho_stereo;
    if !(sin_stereo.is_finite() && sin_stereo > 0.0 && sin_stereo < 1.0) {
        return None;
    }
    let expected = f * sin_stereo.asin().tan();
    let ratio = (stereo.radius_px / expected).ln();
    ratio.is_finite().then_some(ratio)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::test_scenes::{backdrop_hit, radius_px, ray_to_fruit, rig, RADIUS_M};
    use crate::{match_centres, MatchingWindows, RelaxationParams, StereoMatching};
    use nalgebra::{Isometry3, Point2, Point3, Vector3};

    /// Textured spheres (centre, texture frequency) before a backdrop 2.5 m away of about the
    /// fruit's mean colour (so that the texture, not the silhouette, tells fruit apart), ray-cast
    /// into the view reached by `view_from_camera`, 2×2 supersampled. The texture and shading
    /// are fixed on the surfaces, so both views see the same fruit; fruit of different
    /// frequencies look different.
    fn render(
        rig: &RotatedStereo,
        view_from_camera: &Isometry3<f64>,
        fruit: &[(Point3<f64>, f64)],
    ) -> ColorImage {
        let camera = &rig.camera;
        let camera_from_view = view_from_camera.inverse();
        let origin = camera_from_view * Point3::origin();
        let mut image = ColorImage::filled(camera.width, camera.height, [0, 0, 0]);
        for v in 0..camera.height {
            for u in 0..camera.width {
                let mut sum = [0.0; 3];
                for (su, sv) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
                    let q = Point2::new(f64::from(u) - 0.5 + su, f64::from(v) - 0.5 + sv);
                    let n = camera.normalised(&q);
                    let dir = (camera_from_view.rotation * Vector3::new(n.x, n.y, 1.0)).normalize();
                    let hit = fruit
                        .iter()
                        .filter_map(|(centre, freq)| {
                            ray_to_fruit(&origin, &dir, centre).map(|t| (t, centre, *freq))
                        })
                        .min_by(|a, b| a.0.total_cmp(&b.0));
                    let colour = if let Some((t, centre, freq)) = hit {
                        let at = origin + dir * t;
                        let normal = (at - centre) / RADIUS_M;
                        let light = Vector3::new(-0.3, -0.5, -0.8).normalize();
                        let shade = 0.8 + 0.2 * normal.dot(&light).max(0.0);
                        let pattern = (normal.x * freq).sin() * (normal.y * 0.7 * freq).cos();
                        [
                            180.0 * shade + 70.0 * pattern,
                            100.0 * shade + 50.0 * pattern,
                            30.0,
                        ]
                    } else {
                        let at = backdrop_hit(&origin, &dir);
                        let leaf = (at.x * 90.0).sin() + (at.y * 70.0).cos();
                        [150.0 + 8.0 * leaf, 85.0 + 8.0 * leaf, 30.0]
                    };
                    for c in 0..3 {
                        sum[c] += colour[c] / 4.0;
                    }
                }
                image.set(u, v, sum.map(|x| x.round().clamp(0.0, 255.0) as u8));
            }
        }
        image
    }

    fn circle(rig: &RotatedStereo, px: Point2<f64>, centre: &Point3<f64>) -> ImageCircle {
        ImageCircle {
            center_px: px,
            radius_px: radius_px(rig, centre),
        }
    }

    fn pairs(m: &StereoMatching) -> Vec<(usize, usize)> {
        m.pairs.iter().map(|p| (p.primary, p.stereo)).collect()
    }

    /// Fruit A (primary only: its stereo circle was missed) sits 30 px right of fruit B at the
    /// same depth; a near fruit C pulls the mean disparity up, so by disparity alone A's
    /// candidate with B's stereo circle (30 px more disparity) beats B's own.
    /// (Also the scene of `leftover_pairing`'s tests.)
    pub(crate) struct Scene {
        pub(crate) rig: RotatedStereo,
        pub(crate) images: (ColorImage, ColorImage),
        pub(crate) primary: Vec<ImageCircle>,
        pub(crate) stereo: Vec<ImageCircle>,
        pub(crate) windows: MatchingWindows,
    }

    pub(crate) fn scene() -> Scene {
        let rig = rig();
        let b = Point3::new(0.0, 0.0, 1.2);
        let a = Point3::new(30.0 * 1.2 / 400.0, 0.0, 1.2);
        let c = Point3::new(0.03, 0.06, 0.42);
        let fruit = [(a, 9.0), (b, 23.0), (c, 15.0)];
        let images = (
            render(&rig, &Isometry3::identity(), &fruit),
            render(&rig, &rig.stereo_from_camera(), &fruit),
        );
        let project = |p: &Point3<f64>| rig.project_pair(p).unwrap();
        let ((pa, _), (pb, sb), (pc, sc)) = (project(&a), project(&b), project(&c));
        Scene {
            images,
            primary: vec![
                circle(&rig, pa, &a),
                circle(&rig, pb, &b),
                circle(&rig, pc, &c),
            ],
            stereo: vec![circle(&rig, sb, &b), circle(&rig, sc, &c)],
            windows: MatchingWindows {
                min_disparity_px: 20.0,
                max_disparity_px: 200.0,
                max_vertical_offset_px: 4.0,
            },
            rig,
        }
    }

    fn run(s: &Scene, evidence: &PairEvidence) -> (StereoMatching, EvidenceOutcome) {
        let centres = |c: &[ImageCircle]| c.iter().map(|c| c.center_px).collect::<Vec<_>>();
        let mut matrix =
            DisparityMatrix::from_centres(&centres(&s.primary), &centres(&s.stereo), &s.windows);
        let counts = evidence
            .apply(
                &mut matrix,
                &s.rig,
                (&s.images.0, &s.images.1),
                (&s.primary, &s.stereo),
            )
            .unwrap();
        (matrix.relax(&RelaxationParams::default()), counts)
    }

    #[test]
    fn the_row_gate_removes_a_neighbour_off_the_predicted_row() {
        let mut s = scene();
        // A sits 6 px higher than B; Eq. 10's vertical window (10 px) still admits A with B's
        // stereo circle, and by disparity alone A takes it.
        s.primary[0].center_px.y -= 6.0;
        s.windows.max_vertical_offset_px = 10.0;
        assert_eq!(
            pairs(&run(&s, &PairEvidence::default()).0),
            [(0, 0), (2, 1)]
        );
        let gate = PairEvidence {
            max_row_residual_px: Some(3.0),
            ..PairEvidence::default()
        };
        let (gated, counts) = run(&s, &gate);
        assert_eq!(pairs(&gated), [(1, 0), (2, 1)], "{gated:?}");
        assert_eq!((counts.removed_by_rows, counts.removed), (1, 0));
        let residual = |l: usize, r: usize| counts.score(l, r).and_then(|x| x.row_residual_px);
        assert!(
            (residual(0, 0).unwrap() - 6.0).abs() < 0.5,
            "{:?}",
            residual(0, 0)
        );
        assert!(residual(1, 0).unwrap().abs() < 1e-6);
        // A negative gate is refused.
        let bad = PairEvidence {
            max_row_residual_px: Some(-1.0),
            ..PairEvidence::default()
        };
        assert!(bad.validate().is_err());
    }

    #[test]
    fn disparity_alone_pairs_the_wrong_fruit_and_appearance_pairs_the_right_one() {
        let s = scene();
        // The seed's relaxation: A takes B's stereo circle, B goes unpaired.
        let (paper, counts) = run(&s, &PairEvidence::default());
        assert_eq!(pairs(&paper), [(0, 0), (2, 1)], "{paper:?}");
        assert_eq!(counts, EvidenceOutcome::default());
        // The NCC of the wrong candidate is clearly below the right one's.
        let e = PairEvidence {
            ncc_weight_px2: 1000.0,
            ..PairEvidence::default()
        };
        let images = (&s.images.0, &s.images.1);
        let wrong = e
            .score(&s.rig, images, &s.primary[0], &s.stereo[0])
            .unwrap();
        let right = e
            .score(&s.rig, images, &s.primary[1], &s.stereo[0])
            .unwrap();
        let (wrong, right) = (wrong.ncc.unwrap(), right.ncc.unwrap());
        assert!(right > 0.9 && wrong < right - 0.3, "{wrong} vs {right}");
        // As a cost: B keeps its own partner, A stays unpaired.
        let (cost, counts) = run(&s, &e);
        assert_eq!(pairs(&cost), [(1, 0), (2, 1)], "{cost:?}");
        assert_eq!((counts.candidates, counts.removed), (3, 0));
        assert_eq!(counts.score(0, 0).and_then(|s| s.ncc), Some(wrong));
        assert_eq!(counts.score(0, 1), None);
        // As a floor: A's candidate is removed before the relaxation.
        let floor = PairEvidence {
            min_ncc: Some(0.5 * (wrong + right)),
            ..PairEvidence::default()
        };
        let (pruned, counts) = run(&s, &floor);
        assert_eq!(pairs(&pruned), [(1, 0), (2, 1)], "{pruned:?}");
        assert_eq!(counts.removed, 1);
        // A weight too small to outweigh the disparity deviation changes nothing.
        let weak = PairEvidence {
            ncc_weight_px2: 1.0,
            ..PairEvidence::default()
        };
        assert_eq!(pairs(&run(&s, &weak).0), pairs(&paper));
    }

    #[test]
    fn a_fruit_seen_elsewhere_on_its_ray_refuses_a_neighbours_circle() {
        let s = scene();
        let check = PairEvidence {
            better_elsewhere: Some(BetterElsewhere {
                margin: 0.3,
                min_distance_radii: 1.0,
                distance_range_m: (0.3, 2.5),
            }),
            ..PairEvidence::default()
        };
        let (matched, counts) = run(&s, &check);
        // A's patch matches best where A is, 30 px from B's circle: A's candidate with B's
        // circle goes, and B pairs with its own.
        assert_eq!(pairs(&matched), [(1, 0), (2, 1)], "{matched:?}");
        assert_eq!((counts.removed_elsewhere, counts.removed), (1, 0));
        let wrong = counts.score(0, 0).unwrap();
        let (own, best) = (wrong.ncc.unwrap(), wrong.best_along_ray_ncc.unwrap());
        assert!(best > 0.9 && best > own + 0.3, "{own} vs {best}");
        let away = wrong.best_along_ray_distance_radii.unwrap();
        let b_radius = s.stereo[0].radius_px;
        assert!(
            (away * b_radius - 30.0).abs() < 2.0,
            "{away} radii of {b_radius} px"
        );
        // B's own candidate: the best along its ray is its own circle.
        let right = counts.score(1, 0).unwrap();
        assert!(
            right.best_along_ray_distance_radii.unwrap() < 0.2,
            "{right:?}"
        );
        // Beaten by less than a huge margin: kept, and the seed's wrong pair comes back.
        let lenient = PairEvidence {
            better_elsewhere: check
                .better_elsewhere
                .map(|c| BetterElsewhere { margin: 1.9, ..c }),
            ..check
        };
        assert_eq!(pairs(&run(&s, &lenient).0), [(0, 0), (2, 1)]);
        // Nor when the better match must lie further away than it does.
        let near_only = PairEvidence {
            better_elsewhere: check.better_elsewhere.map(|c| BetterElsewhere {
                min_distance_radii: away + 0.5,
                ..c
            }),
            ..check
        };
        assert_eq!(pairs(&run(&s, &near_only).0), [(0, 0), (2, 1)]);
        for bad in [
            BetterElsewhere {
                margin: -0.1,
                ..check.better_elsewhere.unwrap()
            },
            BetterElsewhere {
                min_distance_radii: f64::NAN,
                ..check.better_elsewhere.unwrap()
            },
            BetterElsewhere {
                distance_range_m: (1.0, 0.5),
                ..check.better_elsewhere.unwrap()
            },
            BetterElsewhere {
                distance_range_m: (0.0, 0.5),
                ..check.better_elsewhere.unwrap()
            },
        ] {
            let e = PairEvidence {
                better_elsewhere: Some(bad),
                ..check
            };
            assert!(e.validate().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn off_is_the_seeds_relaxation() {
        let s = scene();
        let centres = |c: &[ImageCircle]| c.iter().map(|c| c.center_px).collect::<Vec<_>>();
        let seed = match_centres(
            &centres(&s.primary),
            &centres(&s.stereo),
            &s.windows,
            &RelaxationParams::default(),
        );
        assert!(PairEvidence::default().is_off());
        assert_eq!(run(&s, &PairEvidence::default()).0, seed);
    }

    #[test]
    fn the_radii_agree_for_the_same_fruit_and_not_for_a_bigger_circle() {
        let rig = rig();
        for centre in [Point3::new(0.05, 0.02, 0.6), Point3::new(-0.1, 0.0, 1.5)] {
            let (p, s) = rig.project_pair(&centre).unwrap();
            let stereo_centre = rig.stereo_from_camera() * centre;
            let primary = circle(&rig, p, &centre);
            let stereo = circle(&rig, s, &stereo_centre);
            let ratio = radius_log_ratio(&rig, &primary, &stereo).unwrap();
            assert!(ratio.abs() < 1e-3, "{centre}: {ratio}");
            let bigger = ImageCircle {
                radius_px: 1.5 * stereo.radius_px,
                ..stereo
            };
            let ratio = radius_log_ratio(&rig, &primary, &bigger).unwrap();
            assert!((ratio - 1.5f64.ln()).abs() < 1e-3, "{ratio}");
        }
        let s = scene();
        let e = PairEvidence {
            radius_weight_px2: 100.0,
            ..PairEvidence::default()
        };
        let mut matrix = DisparityMatrix::from_rows(&[vec![Some(50.0)]]);
        let tiny = ImageCircle {
            radius_px: 1.0,
            ..s.primary[1]
        };
        e.apply(
            &mut matrix,
            &s.rig,
            (&s.images.0, &s.images.1),
            (&[tiny], &s.stereo[..1]),
        )
        .unwrap();
        assert!(matrix.cost(0, 0) > 100.0, "{}", matrix.cost(0, 0));
    }

    #[test]
    fn bad_parameters_and_shapes_are_errors() {
        let s = scene();
        let d = PairEvidence {
            ncc_weight_px2: 1.0,
            ..PairEvidence::default()
        };
        for bad in [
            PairEvidence {
                min_ncc: Some(1.5),
                ..d
            },
            PairEvidence {
                ncc_weight_px2: -1.0,
                ..d
            },
            PairEvidence {
                radius_weight_px2: f64::NAN,
                ..d
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
        let mut matrix = DisparityMatrix::from_rows(&[vec![Some(50.0)]]);
        assert!(d
            .apply(
                &mut matrix,
                &s.rig,
                (&s.images.0, &s.images.1),
                (&s.primary, &s.stereo),
            )
            .is_err());
    }
}
