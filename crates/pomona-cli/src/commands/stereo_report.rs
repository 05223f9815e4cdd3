//! `pomona stereo --report`: how well the two shots were matched and located, against the truth
//! of both views (the fruit ids of `pomona synth --stereo` are shared by the views).
//!
//! * **Identity of a detection**: the truth fruit whose image circle contains the detected
//!   centre, the nearest such by centre distance; none when no circle contains it (a false
//!   detection).
//! * **Matching**: over matched pairs whose two detections both have an identity, precision is
//!   the share pairing the same fruit; recall is the number of fruit paired correctly over the
//!   fruit detected in both views. Pairs involving a false detection are counted apart.
//! * **Exact projections**: every fruit centre the truth has in both views is projected through
//!   the rig and located again by the same method: the error shows what the equations
//!   themselves lose (nothing, up to rounding, on an exact pinhole rig).
//! * **3D centre error**: of every correctly matched fruit, the distance between the located
//!   centre and the primary truth centre, by the truth depth (z).

use std::collections::{BTreeMap, HashSet};

use anyhow::{Context, Result};
use pomona::{LocatedPair, StereoMethod};
use pomona_arm::{EvidenceOutcome, RefinementOutcome, RotatedStereo};
use pomona_core::nalgebra::{Point2, Point3};
use pomona_core::{quantile, FrameTruth, ImageCircle, PinholeCamera};
use pomona_io::Dataset;
use serde::Serialize;

/// Edges of the depth bins of the 3D error table, metres.
pub const DEPTH_BIN_EDGES_M: [f64; 6] = [0.0, 0.5, 0.8, 1.1, 1.4, f64::INFINITY];
/// The depth from which the headline 3D error is taken (seed 004 target: ≤ 15 mm there).
pub const FAR_DEPTH_M: f64 = 0.8;
/// Edges of the visibility bands of the 3D error table (the truth's visible share of a fruit).
pub const VISIBILITY_BIN_EDGES: [f64; 5] = [0.0, 0.6, 0.8, 0.95, f64::INFINITY];

/// What the stereo run found in one frame, for the report.
#[derive(Debug, Clone)]
pub struct StereoFrameOutcome {
    /// Frame stem.
    pub stem: String,
    /// What the matching evidence did (all zero when off).
    pub evidence: EvidenceOutcome,
    /// Centres of the circles detected in the primary view.
    pub primary_centres: Vec<Point2<f64>>,
    /// Centres detected in the stereo view.
    pub stereo_centres: Vec<Point2<f64>>,
    /// Matched pairs that were located.
    pub pairs: Vec<LocatedPair>,
    /// Matched and located pairs the size test dropped (scored for matching, not for 3D).
    pub rejected_by_size: Vec<LocatedPair>,
}

/// How many located pairs (those the size test dropped included) the appearance refinement
/// moved and why the others kept their circle centres.
#[derive(Debug, Clone, Default, Serialize)]
pub struct RefinementCounts {
    /// Pairs whose stereo centre was refined.
    pub refined: usize,
    /// Pairs that kept the circle centres, by reason (`low_ncc`, `flat_patch`, ...).
    pub fallback: BTreeMap<&'static str, usize>,
}

/// Candidate pairs scored, left unscored and removed by the matching evidence, and how the
/// evidence separates candidates of one fruit from the rest.
#[derive(Debug, Clone, Default, Serialize)]
pub struct EvidenceReport {
    /// Candidate pairs inside the Eq. 10 windows.
    pub candidates: usize,
    /// Of those, pairs whose NCC could not be computed.
    pub unscored: usize,
    /// Pairs removed by the NCC floor.
    pub removed: usize,
    /// Pairs removed by the row gate.
    pub removed_by_rows: usize,
    /// Pairs removed because the primary patch matches better elsewhere along its ray.
    pub removed_elsewhere: usize,
    /// NCC of candidates whose two circles are the same fruit.
    pub ncc_same_fruit: Spread,
    /// NCC of candidates of two different fruit.
    pub ncc_other_fruit: Spread,
    /// NCC of candidates involving a false detection.
    pub ncc_false_detection: Spread,
    /// |ln(r_stereo / r_expected)| of candidates of the same fruit.
    pub radius_same_fruit: Spread,
    /// |ln(r_stereo / r_expected)| of candidates of two different fruit.
    pub radius_other_fruit: Spread,
}

/// Quantiles of a sample.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Spread {
    /// Sample size.
    pub n: usize,
    /// 10th, 25th, 50th, 75th and 90th percentiles (empty without samples).
    pub p10_25_50_75_90: Vec<f64>,
}

impl Spread {
    fn of(values: Vec<f64>) -> Self {
        let v = sorted(values);
        Self {
            n: v.len(),
            p10_25_50_75_90: [0.1, 0.25, 0.5, 0.75, 0.9]
                .iter()
                .filter_map(|&q| quantile(&v, q))
                .collect(),
        }
    }
}

/// A fruit detected in both views but not paired correctly.
#[derive(Debug, Clone, Serialize)]
pub struct MissedFruit {
    /// Frame stem.
    pub stem: String,
    /// The fruit.
    pub fruit: String,
    /// As in [`MatchingScore::missed_by_cause`].
    pub cause: &'static str,
    /// Its truth centre, primary camera frame, metres.
    pub center_m: Option<[f64; 3]>,
    /// Its circles' centres in the primary view, pixels.
    pub primary_px: Vec<[f64; 2]>,
    /// Its circles' centres in the stereo view, pixels.
    pub stereo_px: Vec<[f64; 2]>,
}

/// A pair of two different fruit.
#[derive(Debug, Clone, Serialize)]
pub struct WrongPair {
    /// Frame stem.
    pub stem: String,
    /// Primary circle centre, pixels.
    pub primary_px: [f64; 2],
    /// Stereo circle centre, pixels.
    pub stereo_px: [f64; 2],
    /// The fruit of the primary and of the stereo circle.
    pub fruit: [String; 2],
    /// As in [`MatchingScore::wrong_by_cause`].
    pub cause: &'static str,
    /// The matching evidence's NCC of the pair, if computed.
    pub ncc: Option<f64>,
    /// The matching evidence's ln(r_stereo / r_expected), if computed.
    pub radius_log_ratio: Option<f64>,
    /// With `--match-better-elsewhere`: the best NCC along the primary ray, and how many
    /// stereo-circle radii from the pair's stereo circle it lies.
    pub best_along_ray: Option<[f64; 2]>,
    /// Whether the pass over the leftover circles made the pair.
    pub from_leftovers: bool,
}

/// Matching scores.
#[derive(Debug, Clone, Default, Serialize)]
pub struct MatchingScore {
    /// Located pairs, with those the size test then dropped (`rejected_by_size`).
    pub pairs: usize,
    /// Pairs whose two detections are both real fruit.
    pub pairs_of_fruit: usize,
    /// Of those, pairs of the same fruit.
    pub correct: usize,
    /// Fruit detected in both views.
    pub both_detected: usize,
    /// `correct / pairs_of_fruit`.
    pub precision: Option<f64>,
    /// Correct pairs beyond the first of their fruit (duplicated circles paired again).
    pub repeated: usize,
    /// Located pairs made by the pass over the circles the relaxation left unpaired
    /// (`--match-leftovers`), and of those, pairs of two different fruit.
    pub from_leftovers: [usize; 2],
    /// Pairs the size test at the located depth dropped (`--fruit-radius-m`; counted in `pairs`
    /// and the matching scores, not in the 3D errors), and of those, pairs of one fruit.
    pub rejected_by_size: [usize; 2],
    /// Pairs of two different fruit, by cause: `duplicate` (the primary fruit or the stereo fruit
    /// has another circle in its view), `partner_missing` (the primary fruit has no circle in the
    /// stereo view), `rival` (neither: the relaxation preferred a neighbour).
    pub wrong_by_cause: BTreeMap<&'static str, usize>,
    /// Fruit detected in both views but not paired correctly, by what became of their circles:
    /// `with_another_fruit` (a circle of the fruit is in a pair of two different fruit),
    /// `with_a_false_detection` (else, in a pair with a detection of no fruit), `unpaired`.
    pub missed_by_cause: BTreeMap<&'static str, usize>,
    /// Every pair of two different fruit.
    pub wrong_pairs: Vec<WrongPair>,
    /// Every fruit detected in both views but not paired correctly.
    pub missed: Vec<MissedFruit>,
    /// Distinct fruit paired correctly over `both_detected`.
    pub recall: Option<f64>,
}

/// Error of the method on exact projections of the truth centres.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ExactScore {
    /// Fruit centres seen by both views.
    pub fruit: usize,
    /// Largest error, micrometres.
    pub max_error_um: Option<f64>,
    /// Median error, micrometres.
    pub median_error_um: Option<f64>,
    /// Fruit whose exact projections the method could not locate.
    pub failed: usize,
}

/// 3D centre error of correctly matched fruit in one depth band.
#[derive(Debug, Clone, Serialize)]
pub struct DepthBin {
    /// Lower edge, metres (inclusive).
    pub from_m: f64,
    /// Upper edge, metres (exclusive; `null` for no limit).
    pub to_m: Option<f64>,
    /// Fruit in the band.
    pub n: usize,
    /// Median error, millimetres.
    pub median_mm: Option<f64>,
    /// 90th percentile, millimetres.
    pub p90_mm: Option<f64>,
}

/// 3D centre error of correctly matched fruit at z ≥ [`FAR_DEPTH_M`] in one visibility band:
/// occluded fruit and fully visible ones are located with opposite biases along the ray.
#[derive(Debug, Clone, Serialize)]
pub struct VisibilityBin {
    /// Lower edge of the truth's visibility (inclusive).
    pub from: f64,
    /// Upper edge (exclusive; `null` for no limit).
    pub to: Option<f64>,
    /// Fruit in the band.
    pub n: usize,
    /// Median error, millimetres.
    pub median_mm: Option<f64>,
    /// Median signed error along the primary camera's ray through the truth centre,
    /// millimetres: positive when the fruit is located too far.
    pub along_ray_median_mm: Option<f64>,
}

/// 3D centre errors.
#[derive(Debug, Clone, Serialize)]
pub struct CentreError {
    /// Correctly matched fruit.
    pub n: usize,
    /// Median over all, millimetres.
    pub median_mm: Option<f64>,
    /// Fruit at depth ≥ [`FAR_DEPTH_M`].
    pub n_far: usize,
    /// Median over those, millimetres.
    pub median_far_mm: Option<f64>,
    /// By depth band ([`DEPTH_BIN_EDGES_M`]).
    pub by_depth: Vec<DepthBin>,
    /// Fruit at z ≥ [`FAR_DEPTH_M`] whose truth has a visibility, by visibility band
    /// ([`VISIBILITY_BIN_EDGES`]).
    pub by_visibility: Vec<VisibilityBin>,
}

/// Pixel errors of the correctly matched centres against the truth centres projected through
/// the rig: what the 3D error is made of.
#[derive(Debug, Clone, Serialize)]
pub struct PixelError {
    /// Correctly matched fruit.
    pub n: usize,
    /// Median distance of the primary view's detected centre from the projected truth, pixels.
    pub primary_centre_median_px: Option<f64>,
    /// Median signed disparity error (detected − projected truth), pixels.
    pub disparity_median_px: Option<f64>,
    /// Median absolute disparity error, pixels.
    pub disparity_median_abs_px: Option<f64>,
}

/// The report of `pomona stereo --report`.
#[derive(Debug, Clone, Serialize)]
pub struct StereoReport {
    /// `paper` or `triangulate`.
    pub method: StereoMethod,
    /// The appearance refinement's counts; `null` without `--refine`.
    pub refinement: Option<RefinementCounts>,
    /// What the matching evidence (`--match-*`) did; absent when it is off.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub matching_evidence: Option<EvidenceReport>,
    /// Half-angle between the shots, degrees.
    pub beta_deg: f64,
    /// Pivot distance, metres.
    pub pivot_m: f64,
    /// Frames with truth in both views.
    pub frames: usize,
    /// Matching.
    pub matching: MatchingScore,
    /// Exact projections.
    pub exact: ExactScore,
    /// Errors of located centres.
    pub centre_error: CentreError,
    /// Pixel errors behind them.
    pub pixel_error: PixelError,
}

/// The truth circles of a view, by fruit id.
fn truth_circles(truth: &FrameTruth, camera: &PinholeCamera) -> Vec<(String, ImageCircle)> {
    truth
        .fruits
        .iter()
        .filter_map(|f| Some((f.id.clone(), f.image_circle(camera)?)))
        .collect()
}

/// The id of the truth circle containing `centre` nearest to it.
fn identity(circles: &[(String, ImageCircle)], centre: &Point2<f64>) -> Option<String> {
    circles
        .iter()
        .map(|(id, c)| (id, (c.center_px - centre).norm(), c.radius_px))
        .filter(|(_, dist, r)| dist <= r)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(id, _, _)| id.clone())
}

fn sorted(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    v
}

impl StereoReport {
    /// Scores `outcomes` against the truth of `views` (primary, stereo).
    ///
    /// # Errors
    /// An unreadable truth file (named).
    pub fn measure(
        rig: &RotatedStereo,
        method: StereoMethod,
        (refine, evidence): (bool, bool),
        views: (&Dataset, &Dataset),
        outcomes: &[StereoFrameOutcome],
    ) -> Result<Self> {
        let mut tally = Tally::default();
        let mut counts = RefinementCounts::default();
        for pair in outcomes
            .iter()
            .flat_map(|o| o.pairs.iter().chain(&o.rejected_by_size))
        {
            match pair.refinement {
                Some(RefinementOutcome::Refined { .. }) => counts.refined += 1,
                Some(RefinementOutcome::Fallback { reason, .. }) => {
                    *counts.fallback.entry(reason.name()).or_default() += 1;
                }
                None => {}
            }
        }
        for outcome in outcomes {
            let load = |d: &Dataset| {
                d.load_truth(&outcome.stem).with_context(|| {
                    format!("truth of frame {} in {}", outcome.stem, d.root().display())
                })
            };
            let (Some(tp), Some(ts)) = (load(views.0)?, load(views.1)?) else {
                continue;
            };
            tally.frames += 1;
            tally.pairs(rig, (&tp, &ts), outcome);
            tally.exact(rig, method, (&tp, &ts));
        }
        let mut report = tally.report(rig, method);
        report.refinement = refine.then_some(counts);
        report.matching_evidence = evidence
            .then(|| evidence_report(rig, views, outcomes))
            .transpose()?;
        Ok(report)
    }

    /// A short Markdown summary.
    pub fn to_markdown(&self) -> String {
        let f = |v: Option<f64>, digits: usize| {
            v.map_or_else(|| "–".to_owned(), |v| format!("{v:.digits$}"))
        };
        let mut s = format!(
            "| frames | pairs | pairs of fruit | correct | both detected | precision | recall | exact max µm | median mm | median mm (z ≥ {FAR_DEPTH_M} m, n) |\n\
             |---|---|---|---|---|---|---|---|---|---|\n\
             | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} ({}) |\n\n",
            self.frames,
            self.matching.pairs,
            self.matching.pairs_of_fruit,
            self.matching.correct,
            self.matching.both_detected,
            f(self.matching.precision, 3),
            f(self.matching.recall, 3),
            f(self.exact.max_error_um, 4),
            f(self.centre_error.median_mm, 1),
            f(self.centre_error.median_far_mm, 1),
            self.centre_error.n_far,
        );
        if let Some(r) = &self.refinement {
            let kept: Vec<String> = r.fallback.iter().map(|(k, n)| format!("{k} {n}")).collect();
            s.push_str(&format!(
                "refined by appearance: {} pairs; circle centres kept: {}\n\n",
                r.refined,
                if kept.is_empty() {
                    "none".to_owned()
                } else {
                    kept.join(", ")
                }
            ));
        }
        let [dropped, dropped_right] = self.matching.rejected_by_size;
        if dropped > 0 {
            s.push_str(&format!(
                "dropped by the size test at the located depth: {dropped} pairs (of one fruit: \
                 {dropped_right}); the 3D errors below are over the located pairs\n\n"
            ));
        }
        let [leftover, leftover_wrong] = self.matching.from_leftovers;
        if leftover > 0 {
            s.push_str(&format!(
                "paired from the leftovers by appearance: {leftover} (of two different fruit: \
                 {leftover_wrong})\n\n"
            ));
        }
        s.push_str(&format!(
            "pixel errors of {} correct pairs: primary centre median {} px, disparity median {} px \
             (signed), {} px (absolute)\n\n",
            self.pixel_error.n,
            f(self.pixel_error.primary_centre_median_px, 2),
            f(self.pixel_error.disparity_median_px, 2),
            f(self.pixel_error.disparity_median_abs_px, 2),
        ));
        s.push_str("| depth (m) | n | median mm | p90 mm |\n|---|---|---|---|\n");
        for b in &self.centre_error.by_depth {
            let to = b.to_m.map_or_else(|| "∞".to_owned(), |t| format!("{t:.1}"));
            s.push_str(&format!(
                "| {:.1}–{to} | {} | {} | {} |\n",
                b.from_m,
                b.n,
                f(b.median_mm, 1),
                f(b.p90_mm, 1)
            ));
        }
        s.push_str(&format!(
            "\n| visibility (z ≥ {FAR_DEPTH_M} m) | n | median mm | along the ray mm (+ too far) |\n|---|---|---|---|\n"
        ));
        for b in &self.centre_error.by_visibility {
            let to = b.to.map_or_else(|| "1".to_owned(), |t| format!("{t:.2}"));
            s.push_str(&format!(
                "| {:.2}–{to} | {} | {} | {} |\n",
                b.from,
                b.n,
                f(b.median_mm, 1),
                f(b.along_ray_median_mm, 1)
            ));
        }
        s
    }
}

/// The matching evidence's counts, and its scores split by what the candidates truly are.
fn evidence_report(
    rig: &RotatedStereo,
    views: (&Dataset, &Dataset),
    outcomes: &[StereoFrameOutcome],
) -> Result<EvidenceReport> {
    let mut e = EvidenceReport::default();
    let (mut same, mut other, mut false_) = (Vec::new(), Vec::new(), Vec::new());
    let (mut radius_same, mut radius_other) = (Vec::new(), Vec::new());
    for o in outcomes {
        e.candidates += o.evidence.candidates;
        e.unscored += o.evidence.unscored;
        e.removed += o.evidence.removed;
        e.removed_by_rows += o.evidence.removed_by_rows;
        e.removed_elsewhere += o.evidence.removed_elsewhere;
        let load = |d: &Dataset| {
            d.load_truth(&o.stem)
                .with_context(|| format!("truth of frame {} in {}", o.stem, d.root().display()))
        };
        let (Some(tp), Some(ts)) = (load(views.0)?, load(views.1)?) else {
            continue;
        };
        let (cp, cs) = (
            truth_circles(&tp, &rig.camera),
            truth_circles(&ts, &rig.camera),
        );
        for (l, r, score) in &o.evidence.scores {
            let (Some(p), Some(s)) = (o.primary_centres.get(*l), o.stereo_centres.get(*r)) else {
                continue;
            };
            let (a, b) = (identity(&cp, p), identity(&cs, s));
            let (ncc_bin, radius_bin) = match (&a, &b) {
                (Some(a), Some(b)) if a == b => (&mut same, Some(&mut radius_same)),
                (Some(_), Some(_)) => (&mut other, Some(&mut radius_other)),
                _ => (&mut false_, None),
            };
            if let Some(ncc) = score.ncc {
                ncc_bin.push(ncc);
            }
            if let (Some(bin), Some(ratio)) = (radius_bin, score.radius_log_ratio) {
                bin.push(ratio.abs());
            }
        }
    }
    e.ncc_same_fruit = Spread::of(same);
    e.ncc_other_fruit = Spread::of(other);
    e.ncc_false_detection = Spread::of(false_);
    e.radius_same_fruit = Spread::of(radius_same);
    e.radius_other_fruit = Spread::of(radius_other);
    Ok(e)
}

/// Running counts of [`StereoReport::measure`] over frames.
#[derive(Default)]
struct Tally {
    frames: usize,
    matching: MatchingScore,
    /// Distinct fruit paired correctly.
    correct_fruit: usize,
    /// Located error of exact projections, micrometres.
    exact_errors: Vec<f64>,
    exact_failed: usize,
    /// (truth depth m, 3D centre error mm) of correctly matched fruit.
    errors_by_depth: Vec<(f64, f64)>,
    /// (truth visibility, signed error along the ray mm, 3D centre error mm) of correctly
    /// matched fruit at z ≥ [`FAR_DEPTH_M`] whose truth has a visibility.
    errors_by_visibility: Vec<(f64, f64, f64)>,
    /// (primary centre error, signed disparity error) of correctly matched fruit, pixels.
    pixel_errors: Vec<(f64, f64)>,
}

impl Tally {
    /// Scores one frame's matched pairs against the truth of the two views.
    fn pairs(
        &mut self,
        rig: &RotatedStereo,
        (tp, ts): (&FrameTruth, &FrameTruth),
        outcome: &StereoFrameOutcome,
    ) {
        let camera = &rig.camera;
        let (cp, cs) = (truth_circles(tp, camera), truth_circles(ts, camera));
        let ids = |circles: &[(String, ImageCircle)], centres: &[Point2<f64>]| {
            let mut n = BTreeMap::<String, usize>::new();
            for id in centres.iter().filter_map(|c| identity(circles, c)) {
                *n.entry(id).or_default() += 1;
            }
            n
        };
        let (in_primary, in_stereo) = (
            ids(&cp, &outcome.primary_centres),
            ids(&cs, &outcome.stereo_centres),
        );
        let both: HashSet<String> = in_primary
            .keys()
            .filter(|id| in_stereo.contains_key(*id))
            .cloned()
            .collect();
        self.matching.both_detected += both.len();
        let centre_of = truth_centres(tp);
        let visibility_of: BTreeMap<&str, f64> = tp
            .fruits
            .iter()
            .filter_map(|f| Some((f.id.as_str(), f.visibility?)))
            .collect();
        let mut paired = HashSet::new();
        // Per fruit id: in a pair with another fruit, in a pair with a false detection.
        let mut fates = BTreeMap::<String, (bool, bool)>::new();
        let rejected = outcome.rejected_by_size.iter().map(|p| (p, true));
        for (pair, dropped) in outcome.pairs.iter().map(|p| (p, false)).chain(rejected) {
            let (p, s, located) = (&pair.primary_px, &pair.stereo_px, &pair.center_m);
            self.matching.rejected_by_size[0] += usize::from(dropped);
            self.matching.pairs += 1;
            self.matching.from_leftovers[0] += usize::from(pair.from_leftovers);
            let (ia, ib) = (identity(&cp, p), identity(&cs, &pair.stereo_circle_px));
            for (own, other) in [(&ia, &ib), (&ib, &ia)] {
                if let Some(id) = own {
                    let fate = fates.entry(id.clone()).or_default();
                    match other {
                        Some(o) if o != id => fate.0 = true,
                        None => fate.1 = true,
                        Some(_) => {}
                    }
                }
            }
            let (Some(a), Some(b)) = (ia, ib) else {
                continue;
            };
            self.matching.pairs_of_fruit += 1;
            if a != b {
                let cause = if in_primary.get(&a).is_some_and(|&n| n > 1)
                    || in_stereo.get(&b).is_some_and(|&n| n > 1)
                {
                    "duplicate"
                } else if !in_stereo.contains_key(&a) {
                    "partner_missing"
                } else {
                    "rival"
                };
                *self.matching.wrong_by_cause.entry(cause).or_default() += 1;
                self.matching.from_leftovers[1] += usize::from(pair.from_leftovers);
                self.matching.wrong_pairs.push(WrongPair {
                    stem: outcome.stem.clone(),
                    primary_px: [p.x, p.y],
                    stereo_px: [pair.stereo_circle_px.x, pair.stereo_circle_px.y],
                    fruit: [a, b],
                    cause,
                    ncc: pair.evidence.and_then(|e| e.ncc),
                    radius_log_ratio: pair.evidence.and_then(|e| e.radius_log_ratio),
                    best_along_ray: pair.evidence.and_then(|e| {
                        Some([e.best_along_ray_ncc?, e.best_along_ray_distance_radii?])
                    }),
                    from_leftovers: pair.from_leftovers,
                });
                continue;
            }
            self.matching.correct += 1;
            self.matching.rejected_by_size[1] += usize::from(dropped);
            let first = paired.insert(a.clone());
            if !first {
                self.matching.repeated += 1;
            }
            // A pair the size test dropped was not located: no 3D error.
            if let (true, false, Some(truth)) = (first, dropped, centre_of.get(a.as_str())) {
                let error_mm = (located - truth).norm() * 1e3;
                self.errors_by_depth.push((truth.z, error_mm));
                if let (true, Some(&visibility)) =
                    (truth.z >= FAR_DEPTH_M, visibility_of.get(a.as_str()))
                {
                    let along_mm = (located - truth).dot(&truth.coords.normalize()) * 1e3;
                    self.errors_by_visibility
                        .push((visibility, along_mm, error_mm));
                }
                if let Some((ta, tb)) = rig.project_pair(truth) {
                    let disparity = (p.x - s.x) - (ta.x - tb.x);
                    self.pixel_errors.push(((p - ta).norm(), disparity));
                }
            }
        }
        self.correct_fruit += paired.len();
        let mut missed: Vec<&String> = both.difference(&paired).collect();
        missed.sort();
        for id in missed {
            let cause = match fates.get(id) {
                Some((true, _)) => "with_another_fruit",
                Some((false, true)) => "with_a_false_detection",
                _ => "unpaired",
            };
            *self.matching.missed_by_cause.entry(cause).or_default() += 1;
            let of = |circles: &[(String, ImageCircle)], centres: &[Point2<f64>]| {
                centres
                    .iter()
                    .filter(|c| identity(circles, c).as_ref() == Some(id))
                    .map(|c| [c.x, c.y])
                    .collect()
            };
            self.matching.missed.push(MissedFruit {
                stem: outcome.stem.clone(),
                fruit: id.clone(),
                cause,
                center_m: centre_of.get(id.as_str()).map(|c| [c.x, c.y, c.z]),
                primary_px: of(&cp, &outcome.primary_centres),
                stereo_px: of(&cs, &outcome.stereo_centres),
            });
        }
    }

    /// Locates again every fruit centre both views' truth has, from its exact projections.
    fn exact(
        &mut self,
        rig: &RotatedStereo,
        method: StereoMethod,
        (tp, ts): (&FrameTruth, &FrameTruth),
    ) {
        let in_stereo: HashSet<&str> = ts.fruits.iter().map(|f| f.id.as_str()).collect();
        for (id, centre) in &truth_centres(tp) {
            if !in_stereo.contains(id) {
                continue;
            }
            let Some((a, b)) = rig.project_pair(centre) else {
                continue;
            };
            if !(rig.camera.contains(&a) && rig.camera.contains(&b)) {
                continue;
            }
            match method.locate(rig, &a, &b) {
                Ok(p) => self.exact_errors.push((p - centre).norm() * 1e6),
                Err(_) => self.exact_failed += 1,
            }
        }
    }

    /// The report of everything tallied.
    fn report(self, rig: &RotatedStereo, method: StereoMethod) -> StereoReport {
        let mut matching = self.matching;
        matching.precision = (matching.pairs_of_fruit > 0)
            .then(|| matching.correct as f64 / matching.pairs_of_fruit as f64);
        matching.recall = (matching.both_detected > 0)
            .then(|| self.correct_fruit as f64 / matching.both_detected as f64);
        let exact_sorted = sorted(self.exact_errors);
        let pixel = &self.pixel_errors;
        let centre_px = sorted(pixel.iter().map(|e| e.0).collect());
        let disparity = sorted(pixel.iter().map(|e| e.1).collect());
        let disparity_abs = sorted(pixel.iter().map(|e| e.1.abs()).collect());
        let in_band = |from: f64, to: f64| {
            sorted(
                self.errors_by_depth
                    .iter()
                    .filter(|e| e.0 >= from && e.0 < to)
                    .map(|e| e.1)
                    .collect(),
            )
        };
        let all = in_band(f64::NEG_INFINITY, f64::INFINITY);
        let far = in_band(FAR_DEPTH_M, f64::INFINITY);
        let by_depth = DEPTH_BIN_EDGES_M
            .windows(2)
            .map(|w| {
                let band = in_band(w[0], w[1]);
                DepthBin {
                    from_m: w[0],
                    to_m: w[1].is_finite().then_some(w[1]),
                    n: band.len(),
                    median_mm: quantile(&band, 0.5),
                    p90_mm: quantile(&band, 0.9),
                }
            })
            .collect();
        let by_visibility = VISIBILITY_BIN_EDGES
            .windows(2)
            .map(|w| {
                let band: Vec<&(f64, f64, f64)> = self
                    .errors_by_visibility
                    .iter()
                    .filter(|e| e.0 >= w[0] && e.0 < w[1])
                    .collect();
                VisibilityBin {
                    from: w[0],
                    to: w[1].is_finite().then_some(w[1]),
                    n: band.len(),
                    median_mm: quantile(&sorted(band.iter().map(|e| e.2).collect()), 0.5),
                    along_ray_median_mm: quantile(&sorted(band.iter().map(|e| e.1).collect()), 0.5),
                }
            })
            .collect();
        StereoReport {
            method,
            refinement: None,
            matching_evidence: None,
            beta_deg: rig.beta_rad.to_degrees(),
            pivot_m: rig.pivot_distance_m,
            frames: self.frames,
            matching,
            exact: ExactScore {
                fruit: exact_sorted.len() + self.exact_failed,
                max_error_um: exact_sorted.last().copied(),
                median_error_um: quantile(&exact_sorted, 0.5),
                failed: self.exact_failed,
            },
            centre_error: CentreError {
                n: all.len(),
                median_mm: quantile(&all, 0.5),
                n_far: far.len(),
                median_far_mm: quantile(&far, 0.5),
                by_depth,
                by_visibility,
            },
            pixel_error: PixelError {
                n: pixel.len(),
                primary_centre_median_px: quantile(&centre_px, 0.5),
                disparity_median_px: quantile(&disparity, 0.5),
                disparity_median_abs_px: quantile(&disparity_abs, 0.5),
            },
        }
    }
}

/// Centre of every fruit of `truth` that has one, by id.
fn truth_centres(truth: &FrameTruth) -> BTreeMap<&str, Point3<f64>> {
    truth
        .fruits
        .iter()
        .filter_map(|f| Some((f.id.as_str(), f.center_m?)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_is_the_nearest_containing_circle() {
        let circle = |x: f64, r: f64| ImageCircle {
            center_px: Point2::new(x, 0.0),
            radius_px: r,
        };
        let circles = vec![
            ("a".to_owned(), circle(0.0, 10.0)),
            ("b".to_owned(), circle(12.0, 10.0)),
        ];
        assert_eq!(
            identity(&circles, &Point2::new(4.0, 0.0)).as_deref(),
            Some("a")
        );
        assert_eq!(
            identity(&circles, &Point2::new(8.0, 0.0)).as_deref(),
            Some("b")
        );
        assert_eq!(identity(&circles, &Point2::new(40.0, 0.0)), None);
    }
}
