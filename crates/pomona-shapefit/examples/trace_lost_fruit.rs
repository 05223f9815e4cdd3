//! Traces every counted fruit of a synthetic dataset (instance masks needed) through the stages of
//! a shape-fit model, and every false positive back to what it was fitted on, to say where fruit
//! are lost or outranked:
//!
//! ```sh
//! cargo run --release -p pomona-shapefit --example trace_lost_fruit -- DATASET [MODEL.json] [--verbose]
//! ```
//!
//! Per counted fruit (visibility ≥ 0.5, as `pomona eval`): the fraction of its visible pixels in
//! the colour mask, the largest fraction in one colour cluster / one proposed depth cluster /
//! one screened proposal (proposals include the clusters regrown from covered ones), and for a
//! lost fruit the proposal holding most of it (its pixels, the fruit's share of them, the
//! screen's score); the candidates fitted mostly on its pixels and their centre errors,
//! the best score of a candidate within 50 mm, and whether a kept detection matches it. The
//! stage a fruit is lost at is the first of: `mask+proposals` (no cluster holds ≥ 20 % of its
//! pixels), `shape` (no candidate on it), `checks` (candidates on it, all refused by the
//! free-space or curvature check, as the detector runs them), `localisation` (candidates on it,
//! none within 50 mm), `merge` (a candidate within 50 mm, no kept detection), else found. False positives (kept
//! detections matching no counted fruit) are split into pieces of a counted fruit (most pixels
//! on it, centre > 50 mm away), duplicates, on hidden fruit (ignored by eval), and background.
//! Lines starting `CONTEXT` give, per kept detection, its outcome, score, the share of its
//! cluster's pixels its candidate explains and, for a cylinder, its extent over the cluster's
//! extent along its axis. Without MODEL the built-in model is used.

use std::collections::HashMap;
use std::path::PathBuf;

use pomona_consensus::Shape;
use pomona_learn::BatchedClassifier;
use pomona_pipeline::{run_stage, DatasetFrames, FrameSource, ModelFile, Pipeline, StageTimings};
use pomona_shapefit::stages::{
    drop_pieces_of_colour_fruit, BackProjectionStage, ClassifierStage, ColorMaskStage,
    DepthProposalStage, DepthProposals, DescriptorStage, ProposalScreenStage, RegionGrowingStage,
    ShapeChecks, ShapeSource, ShapeStage,
};
use pomona_shapefit::{Candidate, GpcdParams, ShapeFitPipeline, ShapeFitStageParams};

const TOL: f64 = 0.05;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let verbose = args.iter().any(|a| a == "--verbose");
    let pos: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let data = PathBuf::from(
        pos.first()
            .ok_or("usage: trace_lost_fruit DATASET [MODEL]")?,
    );
    let pipeline = ShapeFitPipeline::default();
    let model = match pos.get(1) {
        Some(p) => ModelFile::load(p, "shape-fit")?,
        None => ModelFile::from_json(
            pipeline.default_model().ok_or("no built-in model")?,
            std::path::Path::new("default.json"),
            "shape-fit",
        )?,
    };
    let sp: ShapeFitStageParams = serde_json::from_value(model.stage_params.clone())?;
    let p = &sp.params;
    let detector = pipeline.load(&model)?;
    let normals = p.normals.check()?;
    let mask_stage = ColorMaskStage {
        lut: sp.color_model.as_ref().map(|m| m.compile(p.color.lut_bits)),
        threshold: p.color.threshold as f32,
        max_depth_m: p.max_depth_m as f32,
    };
    let regions = RegionGrowingStage { params: p.regions };
    let proposals = DepthProposalStage::of_params(p);
    let screen = ProposalScreenStage {
        normals,
        gpcd: GpcdParams {
            max_points: p.depth_proposals.screen_points,
            ..p.gpcd
        },
        use_color: true,
        svm: BatchedClassifier::new(model.classifier())?,
        min_score: p.depth_proposals.screen_min_score.unwrap_or(f64::MIN),
    };
    let shapes = ShapeStage {
        normals,
        shapes: p.shapes,
        lattice: p.cluster_lattice,
    };
    let descriptor = DescriptorStage {
        params: p.gpcd,
        use_color: true,
        normals,
    };
    let classifier = ClassifierStage {
        svm: BatchedClassifier::new(model.classifier())?,
    };
    // The detector's checks on the shapes, as it runs them.
    let checks = ShapeChecks::of_params(p)?;
    let admit = |frame: &pomona_core::RgbdFrame,
                 shapes: Vec<Candidate>,
                 source: ShapeSource,
                 refused: &mut Vec<Candidate>,
                 t: &mut StageTimings|
     -> Result<Vec<Candidate>, Box<dyn std::error::Error>> {
        let all = shapes.clone();
        let kept = checks.admitted(source, frame, shapes, t)?;
        refused.extend(all.into_iter().filter(|c| !kept.contains(c)));
        Ok(kept)
    };
    let frames = DatasetFrames::new(vec![pomona_io::Dataset::open(&data)?]);
    let mut lost: HashMap<&'static str, usize> = HashMap::new();
    let mut fp_kinds: HashMap<&'static str, Vec<f64>> = HashMap::new();
    let mut tp_scores = Vec::new();
    let mut loc_errors = Vec::new();
    let mut training: HashMap<&'static str, (usize, usize, usize)> = HashMap::new();
    for fi in 0..frames.len() {
        let lf = frames.load(fi)?;
        let Some(mask) = &lf.mask else {
            return Err("the dataset has no instance masks".into());
        };
        let ids = mask.as_slice();
        let frame = &lf.frame;
        let mut t = StageTimings::default();
        let keep = run_stage(&mask_stage, frame, &mut t)?;
        let clusters = run_stage(&regions, (frame, keep.as_slice()), &mut t)?;
        let cloud = run_stage(&BackProjectionStage, frame, &mut t)?;
        let mut refused = Vec::new();
        let colour_shapes = run_stage(&shapes, (frame, &cloud, clusters.as_slice()), &mut t)?;
        let mut cands = admit(
            frame,
            colour_shapes,
            ShapeSource::ColourMask,
            &mut refused,
            &mut t,
        )?;
        let first_proposal = cands.len();
        // Proposals before and after the screen.
        let in_range = ColorMaskStage::depth_range(p.max_depth_m).run_frame(frame)?;
        let all_depth = run_stage(&regions, (frame, in_range.as_slice()), &mut t)?;
        // The proposals, then the clusters regrown from covered ones (as the detector runs
        // them: each batch screened, fitted and checked, the regrown shapes that claim a colour
        // path's fruit dropped); `proposed` and `screened` hold both batches.
        let DepthProposals {
            clusters: first,
            regrown,
        } = run_stage(&proposals, (frame, keep.as_slice()), &mut t)?;
        let (mut proposed, mut screened, mut screen_scores) = (Vec::new(), Vec::new(), Vec::new());
        for (batch, is_regrown) in [(first, false), (regrown, true)] {
            let scores = screen.scores(frame, &cloud, &batch)?;
            let kept = screen.passing(&batch, &scores);
            let batch_shapes = run_stage(&shapes, (frame, &cloud, kept.as_slice()), &mut t)?;
            let mut admitted = admit(
                frame,
                batch_shapes,
                ShapeSource::DepthProposal,
                &mut refused,
                &mut t,
            )?;
            if is_regrown {
                drop_pieces_of_colour_fruit(&cands[..first_proposal], &mut admitted);
            }
            cands.extend(admitted);
            proposed.extend(batch);
            screened.extend(kept);
            screen_scores.extend(scores);
        }
        // Which cluster each candidate was fitted in (colour clusters, then screened proposals).
        let mut cluster_of = vec![usize::MAX; ids.len()];
        let mut proposal_of = vec![usize::MAX; ids.len()];
        for (k, c) in clusters.iter().enumerate() {
            for &i in c {
                cluster_of[i] = k;
            }
        }
        for (k, c) in screened.iter().enumerate() {
            for &i in c {
                proposal_of[i] = k;
            }
        }
        let features = run_stage(&descriptor, (frame, &cloud, cands.as_slice()), &mut t)?;
        let mut scores = run_stage(&classifier, features.as_slice(), &mut t)?;
        if let Some(cal) = &p.radius_calibration {
            for c in &mut cands {
                c.shape = cal.apply(&c.shape, &c.points, p.shapes.sphere.radius_range_m);
            }
        }
        let dets = detector.detect(frame, &mut t)?;
        // Share of its cluster a candidate explains, and, for a cylinder, its extent over the
        // cluster's extent along its axis.
        let context = |c: usize| -> (f64, f64) {
            let cand = &cands[c];
            let Some(&first) = cand.pixels.first() else {
                return (0.0, 0.0);
            };
            let cluster: &[usize] = if c < first_proposal {
                &clusters[cluster_of[first]]
            } else {
                &screened[proposal_of[first]]
            };
            let share = cand.pixels.len() as f64 / cluster.len().max(1) as f64;
            let span = match &cand.shape {
                Shape::Cylinder(cy) => {
                    let along: Vec<f64> = cluster
                        .iter()
                        .map(|&i| (cloud.points()[i].cast::<f64>() - cy.axis_point).dot(&cy.axis))
                        .filter(|a| a.is_finite())
                        .collect();
                    let lo = along.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = along.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    cy.length_m().unwrap_or(0.0) / (hi - lo).max(1e-9)
                }
                Shape::Sphere(_) => f64::NAN,
            };
            (share, span)
        };
        // Training's view of the frame: the colour clusters' candidates and those of every
        // depth-only cluster, labelled by the centre rule; how many negatives are pieces of a
        // fruit (most inlier pixels on one fruit), and how many of each score inside the margin
        // (≥ −1, where mining picks its negatives).
        {
            let mut train = run_stage(&shapes, (frame, &cloud, clusters.as_slice()), &mut t)?;
            train.extend(run_stage(
                &shapes,
                (frame, &cloud, all_depth.as_slice()),
                &mut t,
            )?);
            let f = run_stage(&descriptor, (frame, &cloud, train.as_slice()), &mut t)?;
            let s = run_stage(&classifier, f.as_slice(), &mut t)?;
            for (c, score) in train.iter().zip(s) {
                let centre = c.shape.center();
                let positive = lf
                    .truth
                    .fruits
                    .iter()
                    .any(|f| f.center_m.is_some_and(|t| (t - centre).norm() <= TOL));
                let mut counts: HashMap<u16, usize> = HashMap::new();
                for &i in &c.pixels {
                    *counts.entry(ids[i]).or_default() += 1;
                }
                let on_fruit = counts
                    .iter()
                    .any(|(&id, &n)| id > 0 && 2 * n > c.pixels.len());
                let class = match (positive, on_fruit) {
                    (true, _) => "positive",
                    (false, true) => "negative-piece-of-fruit",
                    (false, false) => "negative-background",
                };
                let e = training.entry(class).or_insert((0, 0, 0));
                e.0 += 1;
                e.1 += usize::from(score >= -1.0);
                e.2 += usize::from(score >= 0.0);
            }
        }
        // Majority fruit id of each candidate's pixels.
        let owner = |pixels: &[usize]| -> (u16, f64) {
            let mut counts: HashMap<u16, usize> = HashMap::new();
            for &i in pixels {
                *counts.entry(ids[i]).or_default() += 1;
            }
            let (id, n) = counts
                .into_iter()
                .max_by_key(|&(id, n)| (n, id))
                .unwrap_or((0, 0));
            (id, n as f64 / pixels.len().max(1) as f64)
        };
        let best_fraction = |cl: &[Vec<usize>], id: u16, total: usize| -> f64 {
            cl.iter()
                .map(|c| c.iter().filter(|&&i| ids[i] == id).count())
                .max()
                .unwrap_or(0) as f64
                / total.max(1) as f64
        };
        let counted: Vec<bool> = lf
            .truth
            .fruits
            .iter()
            .map(|f| f.visibility.is_none_or(|v| v >= 0.5) && f.center_m.is_some())
            .collect();
        for (k, f) in lf.truth.fruits.iter().enumerate() {
            if !counted[k] {
                continue;
            }
            let id = (k + 1) as u16;
            let Some(tc) = f.center_m else { continue };
            let pix: Vec<usize> = (0..ids.len()).filter(|&i| ids[i] == id).collect();
            let in_mask = pix.iter().filter(|&&i| keep[i]).count() as f64 / pix.len().max(1) as f64;
            let colour_cl = best_fraction(&clusters, id, pix.len());
            let depth_cl = best_fraction(&all_depth, id, pix.len());
            let prop_cl = best_fraction(&proposed, id, pix.len());
            let scr_cl = best_fraction(&screened, id, pix.len());
            let on_it: Vec<usize> = (0..cands.len())
                .filter(|&c| owner(&cands[c].pixels).0 == id)
                .collect();
            let err = |c: usize| (cands[c].shape.center() - tc).norm();
            let near: Vec<usize> = (0..cands.len()).filter(|&c| err(c) <= TOL).collect();
            let best_near = near
                .iter()
                .map(|&c| scores[c])
                .fold(f64::NEG_INFINITY, f64::max);
            let det = dets
                .iter()
                .filter(|d| (d.center_m - tc).norm() <= TOL)
                .map(|d| d.score)
                .fold(f64::NEG_INFINITY, f64::max);
            let refused_on_it = refused.iter().filter(|c| owner(&c.pixels).0 == id).count();
            let stage = if on_it.is_empty() && near.is_empty() {
                if refused_on_it > 0 {
                    "checks"
                } else if colour_cl.max(scr_cl) < 0.2 {
                    "mask+proposals"
                } else {
                    "shape"
                }
            } else if near.is_empty() {
                "localisation"
            } else if det == f64::NEG_INFINITY {
                "merge"
            } else {
                "found"
            };
            *lost.entry(stage).or_default() += 1;
            if stage == "found" {
                tp_scores.push(det);
            }
            if let Some(best) = on_it.iter().map(|&c| err(c)).min_by(f64::total_cmp) {
                loc_errors.push(best);
            }
            if verbose || stage != "found" {
                // The proposal holding most of the fruit: its size, the fruit's share of it and
                // the screen's score.
                let proposal = proposed
                    .iter()
                    .zip(&screen_scores)
                    .map(|(c, &s)| (c.iter().filter(|&&i| ids[i] == id).count(), c.len(), s))
                    .max_by_key(|&(on, _, _)| on)
                    .filter(|&(on, _, _)| on > 0)
                    .map_or(String::new(), |(on, len, s)| {
                        format!(
                            " | proposal {len} px, {:.2} fruit, screen {s:.2}",
                            on as f64 / len as f64
                        )
                    });
                let describe: Vec<String> = on_it
                    .iter()
                    .map(|&c| {
                        let (kind, len) = match &cands[c].shape {
                            Shape::Sphere(_) => ("S", 0.0),
                            Shape::Cylinder(cy) => ("C", cy.length_m().unwrap_or(0.0)),
                        };
                        format!(
                            "{kind}{}{} r{:.0} L{:.0} e{:.0} s{:.2}",
                            if c >= first_proposal { "p" } else { "" },
                            c,
                            1e3 * cands[c].shape.radius_m(),
                            1e3 * len,
                            1e3 * err(c),
                            scores[c]
                        )
                    })
                    .collect();
                println!(
                    "{} fruit {} {} vis {:.2} z {:.2} px {} | mask {:.2} colcl {:.2} depthcl {:.2} prop {:.2} scr {:.2} | near {} best {:.2} det {:.2}{proposal} | {stage} | {}",
                    lf.name,
                    f.id,
                    f.kind,
                    f.visibility.unwrap_or(1.0),
                    tc.z,
                    pix.len(),
                    in_mask,
                    colour_cl,
                    depth_cl,
                    prop_cl,
                    scr_cl,
                    near.len(),
                    best_near,
                    det,
                    describe.join("; ")
                );
            }
        }
        // False positives, by decreasing score, greedy-matched as eval does.
        let mut order: Vec<usize> = (0..dets.len()).collect();
        order.sort_by(|&a, &b| dets[b].score.total_cmp(&dets[a].score));
        let mut taken = vec![false; lf.truth.fruits.len()];
        for di in order {
            let d = &dets[di];
            let nearest = lf
                .truth
                .fruits
                .iter()
                .enumerate()
                .filter_map(|(k, f)| Some((k, (f.center_m? - d.center_m).norm())))
                .filter(|&(k, e)| e <= TOL && !taken[k])
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((k, _)) = nearest {
                taken[k] = true;
                if let Some(c) = (0..cands.len()).find(|&c| scores[c] == d.score) {
                    let (share, span) = context(c);
                    let kind = if counted[k] {
                        "true-positive"
                    } else {
                        "ignored"
                    };
                    println!(
                        "{} CONTEXT {kind} score {:.2} share {share:.2} span {span:.2}",
                        lf.name, d.score
                    );
                }
                continue;
            }
            let any_near = lf.truth.fruits.iter().enumerate().any(|(k, f)| {
                f.center_m.is_some_and(|c| (c - d.center_m).norm() <= TOL) && counted[k]
            });
            // The candidate behind the detection: the one with the same score.
            let cand = (0..cands.len()).find(|&c| scores[c] == d.score);
            let (oid, frac) = cand.map_or((0, 0.0), |c| owner(&cands[c].pixels));
            let kind = if any_near {
                "duplicate"
            } else if oid > 0 && frac >= 0.5 && counted[(oid - 1) as usize] {
                "piece-of-counted"
            } else if oid > 0 && frac >= 0.5 {
                "on-hidden-fruit"
            } else {
                "background"
            };
            let ignored = lf.truth.fruits.iter().enumerate().any(|(k, f)| {
                !counted[k] && f.center_m.is_some_and(|c| (c - d.center_m).norm() <= TOL)
            });
            let kind = if ignored { "ignored" } else { kind };
            if verbose && d.score > -0.5 {
                let desc = cand.map(|c| {
                    let s = &cands[c].shape;
                    let fe = if oid > 0 {
                        lf.truth.fruits[(oid - 1) as usize]
                            .center_m
                            .map_or(0.0, |t| (s.center() - t).norm())
                    } else {
                        0.0
                    };
                    format!(
                        "{}{} r{:.0} L{:.0} owner {} ({:.2}) err-to-owner {:.0}",
                        match s {
                            Shape::Sphere(_) => "S",
                            Shape::Cylinder(_) => "C",
                        },
                        if c >= first_proposal { "p" } else { "" },
                        1e3 * s.radius_m(),
                        1e3 * match s {
                            Shape::Cylinder(cy) => cy.length_m().unwrap_or(0.0),
                            _ => 0.0,
                        },
                        oid,
                        frac,
                        1e3 * fe
                    )
                });
                // Relation to the kept detection on the same fruit, when both are cylinders.
                let rel = cand
                    .and_then(|c| match &cands[c].shape {
                        Shape::Cylinder(cy) => Some(*cy),
                        _ => None,
                    })
                    .map(|cy| {
                        dets.iter()
                            .filter(|o| o.score != d.score)
                            .filter(|o| (o.center_m - d.center_m).norm() < 0.25)
                            .map(|o| {
                                let ang = o.fruit_axis.map_or(f64::NAN, |a| {
                                    a.dot(&cy.axis).abs().min(1.0).acos().to_degrees()
                                });
                                let r = cy.radius_m.max(0.5 * o.diameter_m.unwrap_or(0.0));
                                format!(
                                    "[other s{:.2} {} ang {:.0} off {:.1}r dist {:.0}]",
                                    o.score,
                                    if o.fruit_axis.is_some() { "C" } else { "S" },
                                    ang,
                                    cy.distance_to_axis(&o.center_m) / r,
                                    1e3 * (o.center_m - d.center_m).norm()
                                )
                            })
                            .collect::<Vec<_>>()
                            .join(" ")
                    })
                    .unwrap_or_default();
                println!(
                    "{} FP {kind} score {:.2} {} {rel}",
                    lf.name,
                    d.score,
                    desc.unwrap_or_default()
                );
            }
            fp_kinds.entry(kind).or_default().push(d.score);
            if let Some(c) = cand {
                let (share, span) = context(c);
                println!(
                    "{} CONTEXT {kind} score {:.2} share {share:.2} span {span:.2}",
                    lf.name, d.score
                );
            }
        }
        scores.clear();
    }
    let n_fruit: usize = lost.values().sum();
    let ap_without = |drop: &[&str]| {
        let mut all: Vec<(f64, bool)> = tp_scores.iter().map(|&s| (s, true)).collect();
        for (k, v) in &fp_kinds {
            if !drop.contains(k) && *k != "ignored" {
                all.extend(v.iter().map(|&s| (s, false)));
            }
        }
        voc11(&mut all, n_fruit)
    };
    println!(
        "VOC11 AP (trace's matching): all {:.3}; without pieces of counted fruit {:.3}; without pieces of hidden fruit {:.3}; without both {:.3}; without background {:.3}; without duplicates {:.3}",
        ap_without(&[]),
        ap_without(&["piece-of-counted"]),
        ap_without(&["on-hidden-fruit"]),
        ap_without(&["piece-of-counted", "on-hidden-fruit"]),
        ap_without(&["background"]),
        ap_without(&["duplicate"]),
    );
    let mut classes: Vec<_> = training.into_iter().collect();
    classes.sort();
    for (class, (n, margin, above)) in classes {
        println!("training view: {class}: {n} (score >= -1: {margin}; >= 0: {above})");
    }
    let mut stages: Vec<_> = lost.into_iter().collect();
    stages.sort();
    println!("fruit by stage: {stages:?}");
    tp_scores.sort_by(f64::total_cmp);
    let median = |v: &[f64]| v.get(v.len() / 2).copied().unwrap_or(f64::NAN);
    println!(
        "found fruit: {} (score median {:.2}, min {:.2})",
        tp_scores.len(),
        median(&tp_scores),
        tp_scores.first().copied().unwrap_or(f64::NAN)
    );
    loc_errors.sort_by(f64::total_cmp);
    println!(
        "best centre error of a candidate on the fruit: median {:.1} mm, > 50 mm: {} of {}",
        1e3 * median(&loc_errors),
        loc_errors.iter().filter(|&&e| e > TOL).count(),
        loc_errors.len()
    );
    let min_tp = tp_scores.get(tp_scores.len() / 4).copied().unwrap_or(0.0);
    let mut kinds: Vec<_> = fp_kinds.into_iter().collect();
    kinds.sort_by_key(|(k, _)| *k);
    for (k, v) in kinds {
        println!(
            "false positives {k}: {} (scoring above the found fruit's lower quartile {:.2}: {})",
            v.len(),
            min_tp,
            v.iter().filter(|&&s| s >= min_tp).count()
        );
    }
    Ok(())
}

trait RunFrame {
    fn run_frame(
        &self,
        frame: &pomona_core::RgbdFrame,
    ) -> Result<Vec<bool>, Box<dyn std::error::Error>>;
}

impl RunFrame for ColorMaskStage {
    fn run_frame(
        &self,
        frame: &pomona_core::RgbdFrame,
    ) -> Result<Vec<bool>, Box<dyn std::error::Error>> {
        use pomona_pipeline::Stage;
        Ok(self.run(frame)?)
    }
}

/// VOC 11-point AP of `(score, true positive)` pairs against `n` fruit.
fn voc11(all: &mut [(f64, bool)], n: usize) -> f64 {
    all.sort_by(|a, b| b.0.total_cmp(&a.0));
    let (mut tp, mut pr) = (0usize, Vec::new());
    for (i, &(_, t)) in all.iter().enumerate() {
        tp += usize::from(t);
        pr.push((tp as f64 / (i + 1) as f64, tp as f64 / n.max(1) as f64));
    }
    (0..=10)
        .map(|k| {
            let r = k as f64 / 10.0;
            pr.iter()
                .filter(|p| p.1 >= r - 1e-12)
                .map(|p| p.0)
                .fold(0.0, f64::max)
        })
        .sum::<f64>()
        / 11.0
}
