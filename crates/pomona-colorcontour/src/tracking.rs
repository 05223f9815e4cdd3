//! Approach tracking (seed 004 §3.3): while the arm closes in on a chosen fruit, follow it in
//! every camera frame with a few hundred table lookups instead of a full detection.
//!
//! Per frame, starting at the previous estimate:
//! 1. **5×5 check**: at least `check_min_fruit_px` (13, "at least half") of the 25 pixels
//!    around the expected position are fruit-coloured by the HΣ lookup table;
//! 2. **position check** ([`crate::scan_four_directions`], [`crate::circle_from_boundaries`]): scan left,
//!    right, up and down to the fruit's boundary and fit a circle; its centre is the new
//!    estimate when its radius is within the limits (below), otherwise the search goes on;
//! 3. **spiral search** ([`crate::spiral_points`]) when the check or the fit fails: probes on a
//!    rectangular spiral with growing steps, each tried with steps 1–2, until one gives a valid
//!    circle or the image is exhausted.
//!
//! Only the pixels the checks and scans touch are classified, so a frame costs well under a
//! millisecond (no full-image pass: the paper's "very fast center detection").
//!
//! Choices where the paper is silent (all in [`TrackParams`]):
//! * **radius limits**: the global range `radius_range_px`, narrowed while tracking to a factor
//!   `max_radius_change` either side of the previous radius (approaching at 0.5 m/s and 25 fps
//!   grows a fruit 0.2 m away by about 10 % per frame); scans stop after `max_scan_radii`
//!   times the largest allowed radius, so a touching neighbour cannot stretch the circle;
//! * **refinement**: the position check is repeated from the fitted centre up to
//!   `refinements` times (one pass is exact for an unoccluded disc; occlusion makes the first
//!   estimate depend on the start point);
//! * **scan hysteresis** (`scan_threshold_fraction`, 0.75): the scans continue through pixels
//!   of weaker fruit colour than the check needs, so a fruit whose far side is in shade is
//!   measured whole rather than by its lit cap;
//! * **recovery after loss**: when neither the check nor the whole spiral finds a valid circle
//!   the frame is *lost*: the last good estimate is reported with [`TrackStatus::Lost`], the
//!   next frame searches again from it, and after `relax_after_lost` lost frames in a row the
//!   radius limits fall back to the global range (the fruit may have grown or been confused
//!   with another while lost). A later valid circle resumes tracking ([`TrackStatus::Searched`]).
//!
//! Not in the paper, each off by a setting: **local contour re-detection** (`redetect`,
//! [`crate::Redetect`], [`crate::LocalRedetectParams`]): the detector's mask, contours and edge
//! fit on a window around the expected circle, and the fitted circle most consistent with the
//! track ([`TrackStatus::Redetected`]) — every frame (`always`), or only when the paper's check
//! finds no circle or one that disagrees with the expected centre or radius (`on-doubt`). Four
//! scans from one point cannot tell a touching neighbour or a leaf from the fruit's outline; the
//! edge fit sees pieces of outline and their curvature. The expected circle is the last one (a
//! constant-velocity and growth-rate prediction was tried with the re-detection and lowered the
//! success rate on the tuning set; docs/results.md, "Local contour re-detection"); and a
//! **bounded spiral search** (`max_search_radii`, default 2 radii): while tracking, the search
//! does not reach past twice the fruit's radius, so it cannot hand the track to another fruit
//! across the image; once the track is lost it searches everywhere again; and a **fruit share**
//! (`min_fruit_share`, default 0.6): a circle from the scans is taken only when that share of
//! it is fruit-coloured at the check's full threshold. The scans' weaker threshold lets them run
//! on through background of a faintly fruit-like colour, and without the share a track lost
//! once could report circles of 150–360 px fitted to such background; and an **image patch**
//! (`patch_shift`, [`crate::PatchTemplate`]): each frame's checks start where the grey patch
//! around the last estimate moved to rather than at the last estimate, so that the image sliding
//! under a turning camera does not put the 5×5 check on a neighbour, and a circle found further
//! than half a radius from there is not taken ([`TrackStatus::Predicted`]); and a **jump limit**
//! (`max_jump_radii`, default 1): where no patch says where the fruit went (the first frame, or
//! with the patch off), a circle of the check or the spiral search more than a radius from the
//! expected centre is not taken either — when the fruit's own pixels fail the check (a leaf over
//! it, an unripe colour) the search lands on a neighbour.
//! `--set 'redetect="off"' --set max_search_radii=null --set min_fruit_share=0 --set
//! patch_shift=null --set max_jump_radii=null` is the paper's tracker.

use pomona_core::nalgebra::{Point2, Vector2};
use pomona_core::ColorImage;
use pomona_pipeline::{PipelineError, StageTimings};
use serde::{Deserialize, Serialize};

use crate::disc_share::disc_share;
use crate::{
    circle_from_boundaries, most_consistent_circle, scan_four_directions, spiral_points,
    ColorContourDetector, ColorContourParams, ColorContourStageParams, EdgeScanParams, HSigmaLut,
    LocalRedetectParams, PatchShiftParams, PatchTemplate, Redetect, SampledRegion, ScanEnd,
    SpiralParams,
};

/// Every tunable of the tracker, defaulted to seed 004's values where it gives them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrackParams {
    /// Half the side of the check square (2: the paper's 5×5).
    pub check_half_px: u32,
    /// Fruit-coloured pixels the check square needs (13 of 25: "at least half").
    pub check_min_fruit_px: u32,
    /// The four-direction scan.
    pub edge_scan: EdgeScanParams,
    /// The spiral search.
    pub spiral: SpiralParams,
    /// Global fruit radius limits, pixels (the paper's "preset radius limits").
    pub radius_range_px: (f64, f64),
    /// Largest change of the radius between frames while tracking (factor either way).
    pub max_radius_change: f64,
    /// Scans stop after this many times the largest allowed radius.
    pub max_scan_radii: f64,
    /// Extra position checks from the fitted centre.
    pub refinements: u32,
    /// Lost frames in a row after which the radius limits fall back to the global range.
    pub relax_after_lost: u32,
    /// The four-direction scans run on through pixels whose table value reaches this fraction
    /// of the colour threshold (1: the paper's single threshold; the 5×5 check always uses the
    /// full threshold). Below 1 the scans cross the shaded side of a fruit, whose colour is
    /// weaker, instead of stopping at the terminator and fitting the lit cap — the same
    /// hysteresis, and the same default 0.75, as the detector's `color_grow_fraction` (chosen
    /// on approach sequences of seed 41; see docs/results.md, "Approach tracking").
    #[serde(default = "one")]
    pub scan_threshold_fraction: f64,
    /// When the local contour re-detection runs ([`crate::Redetect`], not in the paper; see
    /// [`crate::LocalRedetectParams`]). Default `on-doubt`: chosen among `always` and
    /// `on-doubt` (with and without the motion model, windows 1.5–2.5 radii, candidates within
    /// 0.6–1 radii) on 20 swaying approaches of seed 41, and better than or equal to the
    /// paper's tracker on every held-out set (docs/results.md, "Local contour re-detection").
    /// Parameters from before this setting mean `off`, the paper's tracker.
    #[serde(default)]
    pub redetect: Redetect,
    /// The local re-detection's window and choice of circle.
    #[serde(default)]
    pub local_redetect: LocalRedetectParams,
    /// Not in the paper: the spiral search stops at this many current radii from the expected
    /// position (Chebyshev distance in pixels) while tracking, so another fruit across the
    /// image cannot take over the track in one frame; after `relax_after_lost` lost frames in a
    /// row it covers the whole image again, as the paper's does. Default 2 (chosen among none,
    /// 2, 3, 5 and 8 on the approaches of seed 41; docs/results.md, "Bounded spiral search");
    /// `None` (and older files) searches the whole image every time.
    #[serde(default)]
    pub max_search_radii: Option<f64>,
    /// Not in the paper: a circle from the position check is taken only when at least this
    /// share of its part in the image is fruit-coloured at the full threshold (sampled on a
    /// grid of at most [`FRUIT_SHARE_GRID`]² points; a fruit filling the view close up is
    /// partly outside it). Default 0.6,
    /// chosen among 0.3–0.9 on the approaches of seeds 41, 43, 45 and 46 (0.5–0.7 tie;
    /// docs/results.md, "Fruit share of a tracked circle"); 0 (and older files) takes any
    /// circle, as the paper does.
    #[serde(default)]
    pub min_fruit_share: f64,
    /// Not in the paper: each frame's checks start where the grey patch around the last
    /// estimate moved to ([`crate::PatchTemplate`]) instead of at the last estimate, a circle
    /// found further than `max_offset_radii` from there is not taken (the moved circle is the
    /// estimate, [`TrackStatus::Predicted`]); the first frame, with no patch yet, is tracked
    /// as without. Default on (chosen on the approaches of seeds 41, 43–46, 48 and 49;
    /// docs/results.md, "The image slides under the tracker"); `None` (and older files)
    /// starts each frame at the last estimate, as the paper does.
    #[serde(default)]
    pub patch_shift: Option<PatchShiftParams>,
    /// Not in the paper: where no image patch says where the fruit went — the first frame, whose
    /// expected circle is the start circle, and every frame with `patch_shift` off — a circle
    /// from the 5×5 check and the spiral search whose centre lies more than this many radii from
    /// the expected centre is not taken while tracking; the expected circle is the frame's
    /// estimate ([`TrackStatus::Predicted`]). A circle further away is a neighbour the check
    /// landed on when the fruit's own pixels failed it (a leaf across its middle, an unripe
    /// colour weaker than the table's threshold). Where the patch moved, its own, tighter
    /// `max_offset_radii` decides; where a patch was not found again (the view moved beyond its
    /// range) the fruit may be anywhere the search reaches, and no limit applies. Circles of the
    /// local re-detection, which chooses the one most like the expected circle, and circles
    /// found after a lost frame are taken as before. Default 1 (chosen on the approaches of
    /// seeds 41, 43–46, 48 and 49, where 0.75, 1 and 1.5 gave the same tracks on six of the
    /// seven sets; docs/results.md, "A far circle is not a jump of the fruit"); `None` (and
    /// older files) takes any circle, as the paper does.
    #[serde(default)]
    pub max_jump_radii: Option<f64>,
}

/// Points per side of the grid on which [`TrackParams::min_fruit_share`] is measured.
pub const FRUIT_SHARE_GRID: u32 = 17;

fn one() -> f64 {
    1.0
}

impl Default for TrackParams {
    fn default() -> Self {
        Self {
            check_half_px: 2,
            check_min_fruit_px: 13,
            edge_scan: EdgeScanParams::default(),
            spiral: SpiralParams::default(),
            radius_range_px: (6.0, 1000.0),
            max_radius_change: 1.25,
            max_scan_radii: 1.2,
            refinements: 2,
            relax_after_lost: 2,
            scan_threshold_fraction: 0.75,
            redetect: Redetect::OnDoubt,
            local_redetect: LocalRedetectParams::default(),
            max_search_radii: Some(2.0),
            min_fruit_share: 0.6,
            patch_shift: Some(PatchShiftParams::default()),
            max_jump_radii: Some(1.0),
        }
    }
}

impl TrackParams {
    /// Why the parameters are unusable, if they are.
    pub fn invalid_reason(&self) -> Option<&'static str> {
        let side = (2 * self.check_half_px + 1).pow(2);
        let (lo, hi) = self.radius_range_px;
        if self.check_min_fruit_px == 0 || self.check_min_fruit_px > side {
            Some("check_min_fruit_px must lie in 1..=(2·check_half_px + 1)²")
        } else if !self.spiral.is_valid() {
            Some("spiral needs 1 ≤ first_step_px ≤ max_step_px and rings_per_step ≥ 1")
        } else if !(lo > 0.0 && lo <= hi) {
            Some("radius_range_px needs 0 < min ≤ max")
        } else if self.max_radius_change.is_nan() || self.max_radius_change < 1.0 {
            Some("max_radius_change must be at least 1")
        } else if self.max_scan_radii.is_nan() || self.max_scan_radii < 1.0 {
            Some("max_scan_radii must be at least 1")
        } else if !(self.scan_threshold_fraction > 0.0 && self.scan_threshold_fraction <= 1.0) {
            Some("scan_threshold_fraction must lie in (0, 1]")
        } else if self.max_search_radii.is_some_and(|k| k.is_nan() || k < 1.0) {
            Some("max_search_radii must be at least 1")
        } else if !(0.0..=1.0).contains(&self.min_fruit_share) {
            Some("min_fruit_share must lie in [0, 1]")
        } else if self
            .max_jump_radii
            .is_some_and(|k| !(k > 0.0 && k.is_finite()))
        {
            Some("max_jump_radii must be positive and finite")
        } else if let Some(reason) = self.patch_shift.as_ref().and_then(|p| p.invalid_reason()) {
            Some(reason)
        } else {
            self.local_redetect.invalid_reason()
        }
    }
}

/// How a frame's estimate was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TrackStatus {
    /// The 5×5 check passed at the expected position and the circle was valid.
    Confirmed,
    /// Found by the spiral search.
    Searched,
    /// Found by the local contour re-detection ([`crate::Redetect`]).
    Redetected,
    /// The circle found lay too far from where the patch around the fruit moved
    /// ([`PatchShiftParams::max_offset_radii`]) or from the expected centre
    /// ([`TrackParams::max_jump_radii`]): the last circle moved with the patch.
    Predicted,
    /// Not found: the last good estimate is repeated.
    Lost,
}

/// The tracker's answer for one frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrackEstimate {
    /// Estimated fruit centre, pixels.
    pub center_px: Point2<f64>,
    /// Estimated fruit radius, pixels.
    pub radius_px: f64,
    /// How it was obtained.
    pub status: TrackStatus,
    /// 5×5 checks made this frame (1 when the fruit was where expected; 0 when the local
    /// re-detection, run first with `redetect = always`, found it).
    pub probes: usize,
}

/// Follows one fruit from frame to frame (see the module docs).
#[derive(Debug, Clone)]
pub struct ApproachTracker {
    params: TrackParams,
    /// The detector's stages: its colour table for the checks and scans, all of them for the
    /// local re-detection.
    detector: ColorContourDetector,
    center_px: Point2<f64>,
    radius_px: f64,
    lost_in_a_row: u32,
    /// The patch around the last estimate in the last frame (with `patch_shift`).
    template: Option<PatchTemplate>,
}

/// Fruit colour of the pixels of one image, looked up on demand.
struct FruitPixels<'a> {
    image: &'a ColorImage,
    lut: &'a HSigmaLut,
    /// The colour threshold (the 5×5 check).
    threshold: u8,
    /// The scans' threshold (`scan_threshold_fraction` of it).
    scan_threshold: u8,
}

impl FruitPixels<'_> {
    fn value(&self, x: i64, y: i64) -> Option<u8> {
        let (Ok(u), Ok(v)) = (u32::try_from(x), u32::try_from(y)) else {
            return None;
        };
        self.image.get(u, v).map(|rgb| self.lut.value(rgb))
    }

    fn is_fruit(&self, x: i64, y: i64) -> bool {
        self.value(x, y).is_some_and(|t| t >= self.threshold)
    }

    fn is_scanned_fruit(&self, x: i64, y: i64) -> bool {
        self.value(x, y).is_some_and(|t| t >= self.scan_threshold)
    }

    /// Share of the disc (`center`, `radius`) that is fruit-coloured at the full threshold,
    /// from the points of a [`FRUIT_SHARE_GRID`]² grid over its bounding square that lie in it
    /// and in the image (0 when none does).
    fn fruit_share(&self, center: Point2<f64>, radius: f64) -> f64 {
        let half_steps = FRUIT_SHARE_GRID / 2;
        disc_share(
            center,
            radius,
            (radius / f64::from(half_steps), i64::from(half_steps)),
            (self.image.width() as usize, self.image.height() as usize),
            |x, y| self.is_fruit(x as i64, y as i64),
        )
    }
}

impl ApproachTracker {
    /// A tracker that classifies pixels with `lut` (fruit when the table value is at least
    /// `threshold`), starting at the circle `center_px`, `radius_px` (a detection of the
    /// target, or its truth). The local re-detection uses the detector's default stage
    /// parameters; [`ApproachTracker::from_model`] uses a model's.
    ///
    /// # Errors
    /// [`PipelineError::InvalidParameter`] when `params` are invalid (see
    /// [`TrackParams::invalid_reason`]) or the start circle is not finite and positive.
    pub fn new(
        lut: HSigmaLut,
        threshold: u8,
        params: TrackParams,
        center_px: Point2<f64>,
        radius_px: f64,
    ) -> Result<Self, PipelineError> {
        let stage = ColorContourParams {
            color_threshold: f64::from(threshold) / 255.0,
            ..ColorContourParams::default()
        };
        Self::from_table(lut, threshold, &stage, params, center_px, radius_px)
    }

    /// A tracker with a `color-contour` model's colour table and, for the local re-detection,
    /// its stage parameters (mask hysteresis, closing, edge fit), starting at the circle
    /// `center_px`, `radius_px`.
    ///
    /// # Errors
    /// As [`ApproachTracker::new`]; and those of [`ColorContourStageParams::color_table`] and
    /// [`ColorContourDetector::from_table`] for an unusable model.
    pub fn from_model(
        model: &ColorContourStageParams,
        params: TrackParams,
        center_px: Point2<f64>,
        radius_px: f64,
    ) -> Result<Self, PipelineError> {
        let (lut, threshold) = model.color_table()?;
        Self::from_table(lut, threshold, &model.params, params, center_px, radius_px)
    }

    /// As [`ApproachTracker::from_model`], from a colour table already compiled from the model
    /// (`lut`, fruit from table value `threshold`) and the model's stage parameters `stage`, so
    /// that many tracks of one model compile the table once.
    ///
    /// # Errors
    /// As [`ApproachTracker::new`], and those of [`ColorContourDetector::from_table`].
    pub fn from_table(
        lut: HSigmaLut,
        threshold: u8,
        stage: &ColorContourParams,
        params: TrackParams,
        center_px: Point2<f64>,
        radius_px: f64,
    ) -> Result<Self, PipelineError> {
        let invalid = |name: &str, reason: String| PipelineError::InvalidParameter {
            name: name.into(),
            reason,
        };
        if let Some(reason) = params.invalid_reason() {
            return Err(invalid("track", reason.to_string()));
        }
        if !(center_px.x.is_finite()
            && center_px.y.is_finite()
            && radius_px > 0.0
            && radius_px.is_finite())
        {
            return Err(invalid(
                "start circle",
                format!("must be finite with a positive radius, got {center_px} r {radius_px}"),
            ));
        }
        let detector = ColorContourDetector::from_table(lut, threshold, stage)?;
        Ok(Self {
            params,
            detector,
            center_px,
            radius_px,
            lost_in_a_row: 0,
            template: None,
        })
    }

    /// The current estimate's centre and radius, pixels.
    pub fn circle(&self) -> (Point2<f64>, f64) {
        (self.center_px, self.radius_px)
    }

    /// Tracks the fruit into `image` (the next frame) and returns the estimate.
    pub fn update(&mut self, image: &ColorImage) -> TrackEstimate {
        let (lut, threshold) = self.detector.color_table();
        let scan_threshold =
            (f64::from(threshold) * self.params.scan_threshold_fraction).ceil() as u8;
        let pixels = FruitPixels {
            image,
            lut,
            threshold,
            scan_threshold,
        };
        let limits = self.radius_limits();
        // A patch exists only with `patch_shift`, after a frame whose circle it was sampled on.
        let template = self.template.take();
        let had_patch = template.is_some();
        let shift = template.and_then(|t| t.shift_in(image));
        let predicted = (
            self.center_px + shift.unwrap_or_else(Vector2::zeros),
            self.radius_px,
        );
        let mut probes = 0;
        let mut found = None;
        let mut status = TrackStatus::Confirmed;
        if self.params.redetect == Redetect::Always {
            found = self.redetect(image, predicted, limits);
            status = TrackStatus::Redetected;
        }
        if found.is_none() {
            let (circle, searched, n) = self.paper_search(&pixels, predicted.0, limits);
            probes = n;
            status = if searched {
                TrackStatus::Searched
            } else {
                TrackStatus::Confirmed
            };
            found = circle;
            let doubted = circle.is_none_or(|c| self.params.local_redetect.doubts(c, predicted));
            if self.params.redetect == Redetect::OnDoubt && doubted {
                if let Some(c) = self.redetect(image, predicted, limits) {
                    found = Some(c);
                    status = TrackStatus::Redetected;
                }
            }
        }
        // A circle too far from the expected one is not taken. Where the patch moved to, any
        // circle beyond `max_offset_radii`; with no patch (the first frame, or `patch_shift`
        // off), a circle of the check or the search beyond `max_jump_radii`; where a patch was
        // not found again (the view moved beyond its range), the fruit may be anywhere the
        // search reaches.
        // The jump limit also spares re-detected circles and circles after a lost frame.
        let limit_radii = match (shift, &self.params.patch_shift) {
            (Some(_), Some(p)) => Some(p.max_offset_radii),
            _ if !had_patch && status != TrackStatus::Redetected && self.lost_in_a_row == 0 => {
                self.params.max_jump_radii
            }
            _ => None,
        };
        let too_far = limit_radii.is_some_and(|k| {
            found.is_some_and(|(c, _)| (c - predicted.0).norm() > k * predicted.1)
        });
        if too_far {
            found = Some(predicted);
            status = TrackStatus::Predicted;
        }
        match found {
            Some((c, r)) => {
                self.center_px = c;
                self.radius_px = r;
                self.lost_in_a_row = 0;
            }
            None => {
                status = TrackStatus::Lost;
                self.lost_in_a_row += 1;
            }
        }
        if let Some(p) = &self.params.patch_shift {
            self.template = PatchTemplate::sample(image, self.center_px, self.radius_px, p);
        }
        TrackEstimate {
            center_px: self.center_px,
            radius_px: self.radius_px,
            status,
            probes,
        }
    }

    /// The paper's step: the 5×5 check and position check at `at`, else the spiral search.
    /// Returns the circle, whether the spiral search ran, and the 5×5 checks made.
    fn paper_search(
        &self,
        pixels: &FruitPixels<'_>,
        at: Point2<f64>,
        limits: (f64, f64),
    ) -> (Option<(Point2<f64>, f64)>, bool, usize) {
        let image = pixels.image;
        let start = (at.x.round() as i64, at.y.round() as i64);
        let mut probes = 1;
        if self.check(pixels, start) {
            if let Some(c) = self.position_check(pixels, start, limits) {
                return (Some(c), false, probes);
            }
        }
        // Rings come nearest first, so the search ends at the first probe beyond the bound.
        let reach = match self.params.max_search_radii {
            Some(k) if self.lost_in_a_row < self.params.relax_after_lost => k * self.radius_px,
            _ => f64::INFINITY,
        };
        let within = |&(x, y): &(i64, i64)| {
            let d = (x - start.0).abs().max((y - start.1).abs());
            d as f64 <= reach
        };
        for p in spiral_points(start, image.width(), image.height(), &self.params.spiral)
            .take_while(within)
        {
            probes += 1;
            if !self.check(pixels, p) {
                continue;
            }
            if let Some(c) = self.position_check(pixels, p, limits) {
                return (Some(c), true, probes);
            }
        }
        (None, true, probes)
    }

    /// The local contour re-detection around the prediction (see [`crate::Redetect`]): the
    /// circle most consistent with it, when its radius is within `limits`.
    fn redetect(
        &self,
        image: &ColorImage,
        (center, radius): (Point2<f64>, f64),
        limits: (f64, f64),
    ) -> Option<(Point2<f64>, f64)> {
        let p = &self.params.local_redetect;
        let region = SampledRegion::around(
            center,
            p.half_side_radii * radius,
            (image.width(), image.height()),
            p.max_side_samples,
        )?;
        let circles = self
            .detector
            .fitted_circles_in(image, &region, &mut StageTimings::default())
            .ok()?;
        most_consistent_circle(&circles, (center, radius), p)
            .map(|c| (c.center_px, c.radius_px))
            .filter(|&(_, r)| r >= limits.0 && r <= limits.1)
    }

    /// The radius range a new circle must fall in.
    fn radius_limits(&self) -> (f64, f64) {
        let (lo, hi) = self.params.radius_range_px;
        if self.lost_in_a_row >= self.params.relax_after_lost {
            return (lo, hi);
        }
        let k = self.params.max_radius_change;
        ((self.radius_px / k).max(lo), (self.radius_px * k).min(hi))
    }

    /// The 5×5 check around `p`.
    fn check(&self, pixels: &FruitPixels<'_>, (x, y): (i64, i64)) -> bool {
        let half = i64::from(self.params.check_half_px);
        let mut hits = 0;
        for dy in -half..=half {
            for dx in -half..=half {
                hits += u32::from(pixels.is_fruit(x + dx, y + dy));
            }
        }
        hits >= self.params.check_min_fruit_px
    }

    /// Scan and fit from `start`, refined from the fitted centre; the circle when its radius is
    /// within `limits` and enough of it is fruit-coloured (`min_fruit_share`).
    fn position_check(
        &self,
        pixels: &FruitPixels<'_>,
        start: (i64, i64),
        limits: (f64, f64),
    ) -> Option<(Point2<f64>, f64)> {
        let size = (pixels.image.width(), pixels.image.height());
        let max_scan = (self.params.max_scan_radii * limits.1).ceil().max(1.0) as u32;
        let mut from = start;
        let mut circle = None;
        for _ in 0..=self.params.refinements {
            let ends = scan_four_directions(
                &mut |x, y| pixels.is_scanned_fruit(x, y),
                from,
                size,
                max_scan,
                &self.params.edge_scan,
            );
            let points: Vec<Point2<f64>> = ends.iter().filter_map(ScanEnd::boundary).collect();
            let Some((c, r)) = circle_from_boundaries(&points) else {
                break;
            };
            circle = Some((c, r));
            let next = (c.x.round() as i64, c.y.round() as i64);
            if next == from || !pixels.is_scanned_fruit(next.0, next.1) {
                break;
            }
            from = next;
        }
        let min_share = self.params.min_fruit_share;
        circle.filter(|&(c, r)| {
            r >= limits.0
                && r <= limits.1
                && (min_share <= 0.0 || pixels.fruit_share(c, r) >= min_share)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mlp;

    /// A hand-set perceptron: fruit when Y = R − (G + B)/2 exceeds about 100.
    fn orange_lut() -> HSigmaLut {
        let net = Mlp {
            hidden_weights: vec![[0.0, 20.0]],
            intensity_weights: Vec::new(),
            hidden_bias: vec![-8.0],
            output_weights: vec![10.0],
            output_bias: -5.0,
        };
        HSigmaLut::compile(&net)
    }

    const ORANGE: [u8; 3] = [230, 120, 20];
    const LEAF: [u8; 3] = [50, 120, 40];

    fn scene(w: u32, h: u32, discs: &[(f64, f64, f64)]) -> ColorImage {
        let mut img = ColorImage::filled(w, h, LEAF);
        for v in 0..h {
            for u in 0..w {
                let inside = discs.iter().any(|&(cx, cy, r)| {
                    (f64::from(u) - cx).powi(2) + (f64::from(v) - cy).powi(2) <= r * r
                });
                if inside {
                    img.set(u, v, ORANGE);
                }
            }
        }
        img
    }

    fn tracker(c: (f64, f64), r: f64) -> ApproachTracker {
        tracker_with(paper(), c, r)
    }

    fn tracker_with(params: TrackParams, c: (f64, f64), r: f64) -> ApproachTracker {
        let lut = orange_lut();
        assert!(lut.value(ORANGE) > 200 && lut.value(LEAF) < 50);
        ApproachTracker::new(lut, 128, params, Point2::new(c.0, c.1), r).unwrap()
    }

    #[test]
    fn follows_a_moving_growing_disc() {
        let mut t = tracker((40.0, 50.0), 12.0);
        for k in 0..40 {
            let k = f64::from(k);
            // Drifts right and down, swings, and grows as the camera approaches.
            let (cx, cy, r) = (
                40.0 + 2.5 * k,
                50.0 + 1.0 * k + 6.0 * (0.5 * k).sin(),
                12.0 * (1.0 + 0.03 * k),
            );
            let est = t.update(&scene(200, 160, &[(cx, cy, r), (180.0, 20.0, 10.0)]));
            assert_ne!(est.status, TrackStatus::Lost, "frame {k}");
            let err = (est.center_px - Point2::new(cx, cy)).norm();
            assert!(err < 0.3 * r, "frame {k}: error {err:.2} px, radius {r:.1}");
            assert!((est.radius_px - r).abs() < 0.15 * r, "frame {k}: {est:?}");
        }
    }

    #[test]
    fn a_jump_is_found_by_the_spiral_search() {
        let mut t = tracker((50.0, 50.0), 15.0);
        let first = t.update(&scene(160, 120, &[(50.0, 50.0, 15.0)]));
        assert_eq!((first.status, first.probes), (TrackStatus::Confirmed, 1));
        // Wind moves the fruit by more than its radius: the check fails, the spiral finds it.
        let est = t.update(&scene(160, 120, &[(78.0, 64.0, 15.0)]));
        assert_eq!(est.status, TrackStatus::Searched);
        assert!(est.probes > 1);
        assert!(
            (est.center_px - Point2::new(78.0, 64.0)).norm() < 1.5,
            "{est:?}"
        );
    }

    /// A bounded search does not jump to a fruit across the image while tracking; once the
    /// track has been lost for `relax_after_lost` frames it searches the whole image again.
    #[test]
    fn a_bounded_search_keeps_off_a_far_fruit_until_the_track_is_lost() {
        let bounded = TrackParams {
            max_search_radii: Some(3.0),
            ..paper()
        };
        let mut t = ApproachTracker::new(orange_lut(), 128, bounded, Point2::new(30.0, 30.0), 10.0)
            .unwrap();
        t.update(&scene(200, 120, &[(30.0, 30.0, 10.0)]));
        // The tracked fruit is gone; another lies 14 radii away.
        let far = scene(200, 120, &[(170.0, 90.0, 10.0)]);
        for _ in 0..2 {
            let est = t.update(&far);
            assert_eq!(est.status, TrackStatus::Lost);
            assert!((est.center_px - Point2::new(30.0, 30.0)).norm() < 1.5);
        }
        let est = t.update(&far);
        assert_eq!(est.status, TrackStatus::Searched);
        assert!((est.center_px - Point2::new(170.0, 90.0)).norm() < 1.5);
        // The paper's search takes it at once.
        let mut t = tracker((30.0, 30.0), 10.0);
        t.update(&scene(200, 120, &[(30.0, 30.0, 10.0)]));
        assert_eq!(t.update(&far).status, TrackStatus::Searched);
        let bad = TrackParams {
            max_search_radii: Some(0.5),
            ..paper()
        };
        assert!(bad.invalid_reason().is_some());
    }

    #[test]
    fn loss_repeats_the_last_estimate_and_tracking_recovers() {
        let mut t = tracker((60.0, 40.0), 14.0);
        t.update(&scene(120, 90, &[(60.0, 40.0, 14.0)]));
        // Hidden (a leaf covers the whole view) for three frames.
        for _ in 0..3 {
            let est = t.update(&scene(120, 90, &[]));
            assert_eq!(est.status, TrackStatus::Lost);
            assert!((est.center_px - Point2::new(60.0, 40.0)).norm() < 1.5);
        }
        // It reappears elsewhere and much larger (the arm kept moving): the limits were relaxed
        // after two lost frames, so the spiral search accepts it.
        let est = t.update(&scene(120, 90, &[(30.0, 50.0, 26.0)]));
        assert_eq!(est.status, TrackStatus::Searched);
        assert!(
            (est.center_px - Point2::new(30.0, 50.0)).norm() < 1.5,
            "{est:?}"
        );
        assert!((est.radius_px - 26.0).abs() < 2.0);
        let est = t.update(&scene(120, 90, &[(31.0, 50.0, 26.0)]));
        assert_eq!(est.status, TrackStatus::Confirmed);
    }

    /// A darker orange whose table value lies between 0.6 and 1 of the threshold 128.
    fn weak_orange(lut: &HSigmaLut) -> [u8; 3] {
        (40..100)
            .map(|pct| ORANGE.map(|c| (u32::from(c) * pct / 100) as u8))
            .find(|&c| (80..120).contains(&lut.value(c)))
            .unwrap()
    }

    #[test]
    fn scans_with_the_lower_threshold_cross_the_shaded_side() {
        let lut = orange_lut();
        let shade = weak_orange(&lut);
        let (cx, cy, r) = (60.0, 45.0, 20.0);
        let mut img = scene(120, 90, &[(cx, cy, r)]);
        // The sun lights the upper left: past a diagonal terminator the fruit is in shade.
        for v in 0..90u32 {
            for u in 0..120u32 {
                let (x, y) = (f64::from(u) - cx, f64::from(v) - cy);
                if x * x + y * y <= r * r && x + y > 0.0 {
                    img.set(u, v, shade);
                }
            }
        }
        let track = |fraction: f64| {
            let params = TrackParams {
                scan_threshold_fraction: fraction,
                ..paper()
            };
            let start = Point2::new(cx - 8.0, cy - 8.0);
            ApproachTracker::new(lut.clone(), 128, params, start, r)
                .unwrap()
                .update(&img)
        };
        // One threshold: two scans stop at the terminator, the circle of the lit cap is too
        // small for the radius limits, and the fruit is lost.
        assert_eq!(track(1.0).status, TrackStatus::Lost);
        let est = track(0.6);
        assert_eq!(est.status, TrackStatus::Confirmed);
        assert!(
            (est.center_px - Point2::new(cx, cy)).norm() < 1.5,
            "{est:?}"
        );
    }

    #[test]
    fn a_circle_of_faint_background_is_not_taken() {
        let lut = orange_lut();
        // Background whose colour passes the scans' weaker threshold but not the check's.
        let faint = weak_orange(&lut);
        let (cx, cy, r) = (60.0, 45.0, 30.0);
        let mut img = scene(120, 90, &[(cx, cy, 4.0)]);
        for v in 0..90u32 {
            for u in 0..120u32 {
                let (x, y) = (f64::from(u) - cx, f64::from(v) - cy);
                let d2 = x * x + y * y;
                if d2 <= r * r && d2 > 16.0 {
                    img.set(u, v, faint);
                }
            }
        }
        let track = |share: f64| {
            let params = TrackParams {
                scan_threshold_fraction: 0.6,
                min_fruit_share: share,
                ..paper()
            };
            ApproachTracker::new(lut.clone(), 128, params, Point2::new(cx, cy), r)
                .unwrap()
                .update(&img)
        };
        // The small fruit-coloured patch passes the 5×5 check, and the scans run on to the edge
        // of the faint disc: without the share, its circle is taken as the fruit.
        let any = track(0.0);
        assert_eq!(any.status, TrackStatus::Confirmed);
        assert!((any.radius_px - r).abs() < 2.0, "{any:?}");
        assert_eq!(track(0.6).status, TrackStatus::Lost);
        // A whole fruit passes the share.
        let whole = ApproachTracker::new(
            lut.clone(),
            128,
            TrackParams {
                min_fruit_share: 0.95,
                ..paper()
            },
            Point2::new(cx, cy),
            r,
        )
        .unwrap()
        .update(&scene(120, 90, &[(cx, cy, r)]));
        assert_eq!(whole.status, TrackStatus::Confirmed);
        // So does a fruit running off the image: only its part in view is counted.
        let (ex, er) = (108.0, 20.0);
        let at_edge = ApproachTracker::new(
            lut.clone(),
            128,
            TrackParams {
                min_fruit_share: 0.95,
                ..paper()
            },
            Point2::new(ex, cy),
            er,
        )
        .unwrap()
        .update(&scene(120, 90, &[(ex, cy, er)]));
        assert_eq!(at_edge.status, TrackStatus::Confirmed, "{at_edge:?}");
        assert!(
            (at_edge.center_px - Point2::new(ex, cy)).norm() < 1.5,
            "{at_edge:?}"
        );
        assert!(TrackParams {
            min_fruit_share: 1.5,
            ..paper()
        }
        .invalid_reason()
        .is_some());
    }

    #[test]
    fn a_disc_of_the_wrong_size_is_not_taken_while_tracking() {
        let mut t = tracker((60.0, 40.0), 10.0);
        t.update(&scene(120, 90, &[(60.0, 40.0, 10.0)]));
        // The target vanishes and a much larger fruit is in view: not within the radius change.
        let est = t.update(&scene(120, 90, &[(60.0, 45.0, 30.0)]));
        assert_eq!(est.status, TrackStatus::Lost);
        assert!(ApproachTracker::new(
            orange_lut(),
            128,
            TrackParams {
                check_min_fruit_px: 26,
                ..paper()
            },
            Point2::new(1.0, 1.0),
            5.0
        )
        .is_err());
    }

    /// The paper's tracker.
    fn paper() -> TrackParams {
        TrackParams {
            redetect: Redetect::Off,
            max_search_radii: None,
            min_fruit_share: 0.0,
            patch_shift: None,
            max_jump_radii: None,
            ..TrackParams::default()
        }
    }

    /// The default tracker with the re-detection in `mode` and without the image patch, so
    /// that every frame's own checks decide.
    fn redetecting(mode: Redetect) -> TrackParams {
        TrackParams {
            redetect: mode,
            patch_shift: None,
            ..TrackParams::default()
        }
    }

    /// Leaves of varied green (never fruit-coloured) with discs of orange, everything moved
    /// right by `offset_px`, as when the camera turns.
    fn sliding_scene(offset_px: f64, discs: &[(f64, f64, f64)]) -> ColorImage {
        let (w, h) = (220u32, 120u32);
        let mut img = ColorImage::filled(w, h, LEAF);
        for v in 0..h {
            for u in 0..w {
                let (x, y) = (f64::from(u) - offset_px, f64::from(v));
                let on_disc = discs
                    .iter()
                    .any(|&(cx, cy, r)| (x - cx).powi(2) + (y - cy).powi(2) <= r * r);
                let shade =
                    1.0 + 0.35 * (0.13 * x + 0.07 * y).sin() + 0.25 * (0.05 * x - 0.11 * y).sin();
                let leaf = LEAF.map(|c| (f64::from(c) * shade).min(255.0) as u8);
                img.set(u, v, if on_disc { ORANGE } else { leaf });
            }
        }
        img
    }

    #[test]
    fn the_image_sliding_under_the_tracker_does_not_hand_it_to_a_neighbour() {
        // The target (r 12) touches a larger neighbour on its left; the view slides right by
        // 14 px a frame, more than the target's radius.
        let (target, neighbour) = ((70.0, 60.0, 12.0), (44.0, 60.0, 14.0));
        let run = |params: TrackParams| {
            let mut t =
                ApproachTracker::new(orange_lut(), 128, params, Point2::new(70.0, 60.0), 12.0)
                    .unwrap();
            (0..8)
                .map(|k| {
                    let offset = 14.0 * f64::from(k);
                    let est = t.update(&sliding_scene(offset, &[target, neighbour]));
                    (est.center_px - Point2::new(70.0 + offset, 60.0)).norm() / 12.0
                })
                .fold(0.0, f64::max)
        };
        let with_patch = run(TrackParams::default());
        assert!(with_patch < 0.2, "{with_patch:.2}");
        let without = run(TrackParams {
            patch_shift: None,
            ..TrackParams::default()
        });
        assert!(without > 1.0, "{without:.2}");
    }

    #[test]
    fn a_circle_far_from_where_the_patch_went_is_not_taken() {
        // The target is hidden for a frame by a leaf while its neighbour stays in view: the
        // spiral search would take the neighbour; the moved circle is kept instead.
        let (target, neighbour) = ((70.0, 60.0, 12.0), (44.0, 60.0, 14.0));
        let mut t = ApproachTracker::new(
            orange_lut(),
            128,
            TrackParams::default(),
            Point2::new(70.0, 60.0),
            12.0,
        )
        .unwrap();
        assert_eq!(
            t.update(&sliding_scene(0.0, &[target, neighbour])).status,
            TrackStatus::Confirmed
        );
        let est = t.update(&sliding_scene(6.0, &[neighbour]));
        assert_eq!(est.status, TrackStatus::Predicted, "{est:?}");
        assert!(
            (est.center_px - Point2::new(76.0, 60.0)).norm() < 2.0,
            "{est:?}"
        );
        let est = t.update(&sliding_scene(12.0, &[target, neighbour]));
        assert_ne!(est.status, TrackStatus::Predicted, "{est:?}");
        assert!(
            (est.center_px - Point2::new(82.0, 60.0)).norm() < 0.2 * 12.0,
            "{est:?}"
        );
    }

    /// A disc and a smaller neighbour of the same colour overlapping its top right, tracked over
    /// `frames` copies of the image from the disc's centre: the centre error over the radius.
    fn touching_pair_error(params: TrackParams, n: (f64, f64, f64), frames: usize) -> f64 {
        let (cx, cy, r) = (60.0, 60.0, 20.0);
        let img = scene(140, 110, &[(cx, cy, r), n]);
        let mut t =
            ApproachTracker::new(orange_lut(), 128, params, Point2::new(cx, cy), r).unwrap();
        let mut est = t.update(&img);
        for _ in 1..frames {
            est = t.update(&img);
        }
        (est.center_px - Point2::new(cx, cy)).norm() / r
    }

    #[test]
    fn redetection_stays_on_a_fruit_touching_a_neighbour() {
        // The neighbour covers the disc's top right: the paper's upward scan ends on the
        // neighbour's outline and the circle through it grows over the pair.
        let neighbour = (66.0, 40.0, 14.0);
        let paper = touching_pair_error(paper(), neighbour, 5);
        assert!(paper > 0.3, "{paper:.2}");
        for mode in [Redetect::Always, Redetect::OnDoubt] {
            let new = touching_pair_error(redetecting(mode), neighbour, 5);
            assert!(new < 0.05, "{mode:?}: {new:.2}");
        }
    }

    #[test]
    fn redetection_finds_the_centre_of_a_fruit_cut_by_leaves() {
        let (cx, cy, r) = (80.0, 70.0, 26.0);
        let mut img = scene(180, 140, &[(cx, cy, r)]);
        // A leaf band across the fruit, left of its centre, and a second one below it.
        for v in 0..140u32 {
            for u in 0..180u32 {
                let (x, y) = (f64::from(u) - cx, f64::from(v) - cy);
                if (x + 0.3 * y + 4.0).abs() < 4.0 || (y - 10.0).abs() < 3.0 {
                    img.set(u, v, LEAF);
                }
            }
        }
        let start = Point2::new(cx + 12.0, cy - 8.0);
        let run = |params: TrackParams| {
            ApproachTracker::new(orange_lut(), 128, params, start, r)
                .unwrap()
                .update(&img)
        };
        // The paper's scans from the start see pieces: no circle within the radius limits.
        let paper = run(paper());
        assert_eq!(paper.status, TrackStatus::Lost, "{paper:?}");
        for mode in [Redetect::Always, Redetect::OnDoubt] {
            let new = run(redetecting(mode));
            assert_eq!(new.status, TrackStatus::Redetected, "{mode:?}");
            assert!(
                (new.center_px - Point2::new(cx, cy)).norm() < 0.1 * r,
                "{new:?}"
            );
            assert!((new.radius_px - r).abs() < 0.1 * r, "{new:?}");
        }
    }

    /// The fruit's own pixels fail every check (a leaf over it, or a colour weaker than the
    /// table's threshold); the search then lands on the touching neighbour, two radii away.
    /// With `max_jump_radii` that circle is not taken and the expected circle stands until
    /// the fruit shows again.
    #[test]
    fn a_neighbour_two_radii_away_is_not_a_jump_of_the_fruit() {
        let (target, neighbour) = ((60.0, 60.0, 20.0), (100.0, 60.0, 20.0));
        let covered = scene(170, 120, &[neighbour]);
        let uncovered = scene(170, 120, &[target, neighbour]);
        let run = |max_jump_radii: Option<f64>| {
            let params = TrackParams {
                max_search_radii: Some(2.0),
                max_jump_radii,
                ..paper()
            };
            let mut t = tracker_with(params, (60.0, 60.0), 20.0);
            (t.update(&covered), t.update(&uncovered))
        };
        let (jumped, after) = run(None);
        assert_eq!(jumped.status, TrackStatus::Searched);
        assert!(
            (jumped.center_px - Point2::new(100.0, 60.0)).norm() < 2.0,
            "{jumped:?}"
        );
        assert!(
            (after.center_px - Point2::new(100.0, 60.0)).norm() < 2.0,
            "{after:?}"
        );
        let (kept, after) = run(Some(1.0));
        assert_eq!(kept.status, TrackStatus::Predicted, "{kept:?}");
        assert!((kept.center_px - Point2::new(60.0, 60.0)).norm() < 1e-9);
        assert_eq!(after.status, TrackStatus::Confirmed);
        assert!(
            (after.center_px - Point2::new(60.0, 60.0)).norm() < 1.5,
            "{after:?}"
        );
        let bad = TrackParams {
            max_jump_radii: Some(0.0),
            ..TrackParams::default()
        };
        assert!(bad.invalid_reason().is_some());
    }

    /// Where the patch is not found again (the view moved beyond its range), where the fruit
    /// went is not known, and the jump limit does not refuse the circle the search finds.
    #[test]
    fn a_jump_beyond_the_patch_range_is_taken() {
        let fruit = (60.0, 60.0, 12.0);
        let mut t = tracker_with(TrackParams::default(), (60.0, 60.0), 12.0);
        let first = t.update(&sliding_scene(0.0, &[fruit]));
        assert!((first.center_px - Point2::new(60.0, 60.0)).norm() < 1.0);
        // 23 px to the right: the patch's best match falls on the edge of its ±2 radii
        // (24 px) range, which gives no shift; the fruit is within the bounded search.
        let est = t.update(&sliding_scene(23.0, &[fruit]));
        assert_eq!(est.status, TrackStatus::Searched, "{est:?}");
        assert!(
            (est.center_px - Point2::new(83.0, 60.0)).norm() < 1.5,
            "{est:?}"
        );
    }

    #[test]
    fn parameters_from_before_the_redetection_run_the_paper_tracker() {
        let mut json = serde_json::to_value(TrackParams::default()).unwrap();
        let map = json.as_object_mut().unwrap();
        for key in [
            "redetect",
            "local_redetect",
            "min_fruit_share",
            "patch_shift",
            "max_jump_radii",
        ] {
            assert!(map.remove(key).is_some(), "{key}");
        }
        let old: TrackParams = serde_json::from_value(json).unwrap();
        assert_eq!(old.patch_shift, None);
        assert_eq!(old.max_jump_radii, None);
        assert_eq!(old.redetect, Redetect::Off);
        assert_eq!(old.min_fruit_share, 0.0);
        assert_eq!(old.local_redetect, LocalRedetectParams::default());
        let bad = TrackParams {
            local_redetect: LocalRedetectParams {
                max_radius_ratio: 0.5,
                ..LocalRedetectParams::default()
            },
            ..TrackParams::default()
        };
        assert!(bad.invalid_reason().is_some());
    }
}
