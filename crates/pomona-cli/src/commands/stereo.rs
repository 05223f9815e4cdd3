//! `pomona stereo`: fruit in 3D from the two colour shots of seed 004's rotating camera
//! (§4.1–4.2), without any depth image.
//!
//! For every frame of `--data` and its second view `--data/stereo` (as `pomona synth --stereo`
//! writes them, the rig in `rig.json`), color-contour (through the `pomona::Detector` facade)
//! finds circles in both colour images (depth images, if the dataset has them, are not read: the
//! detector sees exactly what a 2D camera gives); the circles are matched by the seed's relaxation
//! ([`pomona_arm::match_centres`], Eq. 10 windows derived from the rig and the working volume
//! `--reach-m`), and each matched pair is located by Eq. 18 (`--method paper`) or by
//! triangulation (`--method triangulate`) in the primary camera frame. By default each pair's
//! stereo-view centre is first refined by appearance ([`pomona_arm::DisparityRefinement`], beyond
//! the seed: the fruit-coloured pixels of the primary view's patch are found in the stereo image
//! to sub-pixel, the whole patch as a second try; the circle centres are kept where neither
//! matches well); it located better than the circle centres on 14 of 15 held-out rigs
//! (docs/results.md, "Error against the lever d and β" and after). `--no-refine` is the seed's
//! method. Before the relaxation, every candidate pair is scored by appearance and, by default,
//! removed when its primary circle's patch matches the stereo view clearly better elsewhere along
//! its ray (`--match-better-elsewhere`, beyond the seed: the fruit's own stereo circle is missing
//! and the candidate is a neighbour's; fewer wrong pairs on held-out rigs, docs/results.md,
//! "A better match elsewhere on the ray"); `--match-better-elsewhere off` is the seed's
//! relaxation bit for bit. After the relaxation, by default, a primary circle it left unpaired is
//! paired with an unpaired stereo circle where its patch, swept along its whole ray, lands within
//! half a radius of that circle's centre (`--match-leftovers`, beyond the seed: a fruit whose two
//! circles sit too far apart in height for Eq. 10's row window; `off` is the seed's;
//! [`pomona_arm::LeftoverPairing`], docs/results.md, "Leftover circles paired by appearance").
//! `--match-min-ncc` (a floor), `--match-ncc-weight` /
//! `--match-radius-weight` (costs added to the relaxation's σ) and `--match-max-row-px` (a row
//! gate) are further evidence, off by default ([`pomona_arm::PairEvidence`]). The detection files have
//! the format of `pomona detect`, so `pomona eval --data DIR` scores them against the primary
//! view's truth. A fruit's diameter is its primary circle's radius scaled to the located depth.
//!
//! `--report R.json` also measures the matching and the 3D error against the truth of both views
//! (see `stereo_report.rs`). Each frame goes through [`pomona::StereoLocator`], the library's
//! entry point for the same work; this module turns options into its settings and writes files.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use pomona::{Detection, StereoLocator, StereoMethod, StereoSettings};
use pomona_arm::{
    BetterElsewhere, DisparityRefinement, LeftoverPairing, PairEvidence, RefinementOutcome,
    RotatedStereo,
};
use pomona_core::ColorImage;
use pomona_io::Dataset;
use pomona_synth::RigFile;
use rayon::prelude::*;

use crate::commands::stereo_report::{StereoFrameOutcome, StereoReport};
use crate::detection_run::{keep_rule, load_detector, thread_pool};
use crate::number_pair::parse_number_pair;
use crate::overlay::write_stereo_overlay;

/// The pipeline whose circles are matched.
pub const STEREO_PIPELINE: &str = "color-contour";
/// The `pipeline` recorded in the detection files.
pub const STEREO_RECORD_PIPELINE: &str = "color-contour-stereo";

/// Arguments of `pomona stereo`.
#[derive(Debug, Clone, clap::Args)]
pub struct StereoArgs {
    /// Dataset folder with `rig.json` and the second view in `stereo/` (`pomona synth --stereo`).
    #[arg(long, value_name = "DIR")]
    pub data: PathBuf,
    /// Output folder for `<frame>.json` detection files (created if missing).
    #[arg(long, value_name = "DETDIR")]
    pub out: PathBuf,
    /// How a matched pair becomes a 3D point.
    #[arg(long, value_name = "paper|triangulate", default_value = "paper", value_parser = str::parse::<StereoMethod>)]
    pub method: StereoMethod,
    /// color-contour model file (default: the built-in model).
    #[arg(long, value_name = "M")]
    pub model: Option<PathBuf>,
    /// Override a stage parameter of the model, KEY=VALUE (dotted keys, JSON values); repeat.
    /// The ray and Hough circles are off here unless set (`--set 'params.ray_circles={}'`,
    /// `--set 'params.hough_circles={}'`): matching pairs the circles' image centres, and a
    /// circle on a piece of fruit is centred on the piece, not the fruit, differently in the two
    /// views (the RGB-D path refits the centre to the depth points instead); docs/results.md,
    /// "Ray circles from inscribed discs" and "Hough circles from the outline".
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<pomona::ParamOverride>,
    /// Keep 2D detections whose calibrated confidence is at least C before matching. Default:
    /// the model's operating confidence; a model without calibration keeps those scoring ≥ 0.
    #[arg(long, value_name = "C")]
    pub min_confidence: Option<f64>,
    /// The working volume, distances from the hub (the pivot) in metres, `NEAR,FAR`, from which
    /// the disparity windows are derived. Default: pivot + 0.2 to pivot + 2.0 m.
    #[arg(long, value_name = "NEAR,FAR", value_parser = parse_reach)]
    pub reach_m: Option<(f64, f64)>,
    /// Pixels added to every disparity window (detector centre error, lens effects).
    #[arg(long, value_name = "PX", default_value_t = 4.0)]
    pub margin_px: f64,
    /// The size test at the located depth (seed 004's 25–55 mm, on the stereo depth): a pair
    /// whose primary circle, at its located depth, has a radius outside `MIN,MAX` metres is
    /// dropped. Default: the color-contour detector's accepted radii (0.0227,0.0605). `off`:
    /// no test.
    #[arg(long, value_name = "MIN,MAX|off", value_parser = parse_radius_range)]
    pub fruit_radius_m: Option<OrOff<(f64, f64)>>,
    /// Refine each pair's stereo-view centre by appearance before locating it (beyond the seed;
    /// the default).
    #[arg(long, overrides_with = "no_refine")]
    pub refine: bool,
    /// Locate each pair from its two circle centres only, as the seed does (no refinement).
    #[arg(long)]
    pub no_refine: bool,
    /// Refinement: radius of the matched patch as a multiple of the primary circle's radius
    /// (above 1 the silhouette is included).
    #[arg(long, value_name = "S", default_value_t = DisparityRefinement::default().patch_scale)]
    pub refine_patch_scale: f64,
    /// Refinement: how far the stereo-view centre is searched either side of the circles'
    /// prediction along the epipolar line, pixels.
    #[arg(long, value_name = "PX", default_value_t = DisparityRefinement::default().search_px)]
    pub refine_search_px: f64,
    /// Refinement: spacing of the searched positions along the epipolar line, pixels (a
    /// parabola through the best three places the peak between them).
    #[arg(long, value_name = "PX", default_value_t = DisparityRefinement::default().step_px)]
    pub refine_step_px: f64,
    /// Refinement: lowest normalised cross-correlation accepted; below it the circle centres
    /// are kept.
    #[arg(long, value_name = "NCC", default_value_t = DisparityRefinement::default().min_ncc)]
    pub refine_min_ncc: f64,
    /// Refinement: match only the patch pixels of the fruit's colour, chromaticity within D of
    /// the circle core's median (leaves and background move against the fruit between the
    /// views), and only where they land on that colour; `off` matches every pixel of the patch
    /// (the earlier default, measured with --refine-min-ncc 0.5).
    #[arg(long, value_name = "D|off", value_parser = parse_or_off, default_value = "0.1")]
    pub refine_fruit_chroma: OrOff,
    /// Refinement: when the fruit-coloured pixels do not match, try every pixel of the patch
    /// with this NCC floor before keeping the circle centres; `off`: no second try.
    #[arg(long, value_name = "NCC|off", value_parser = parse_or_off, default_value = "0.5")]
    pub refine_whole_patch_min_ncc: OrOff,
    /// Refinement: a fruit near the stereo image's border is matched on the patch pixels that
    /// stay inside the image over the whole sweep, when they are at least this fraction of the
    /// patch; `off`: the whole patch must stay inside (the circle centres are kept otherwise).
    #[arg(long, value_name = "FRACTION|off", value_parser = parse_or_off, default_value = "0.25")]
    pub refine_min_inside: OrOff,
    /// Refinement, with the fruit's colour: score a hypothesis only on the stereo samples whose
    /// saturation (1 − min/max of R, G, B) is at least the patch's median less D — the fruit's
    /// surface, not leaves, background or a specular highlight; `off`: every sample.
    #[arg(long, value_name = "D|off", value_parser = parse_or_off, default_value = "0.02")]
    pub refine_saturation_margin: OrOff,
    /// Matching (beyond the seed): remove candidate pairs whose stereo row lies more than PX
    /// from the row that the primary row and the two columns predict (the epipolar constraint;
    /// Eq. 10 only bounds the row offset by its largest value anywhere in the image). Default:
    /// no gate (the seed's matching).
    #[arg(long, value_name = "PX")]
    pub match_max_row_px: Option<f64>,
    /// Matching (beyond the seed): remove candidate pairs whose appearance NCC (the primary
    /// patch moved into the stereo view by the rig's motion, best of the epipolar sweep) is
    /// below this floor before the relaxation. Default: no floor (the seed's matching).
    #[arg(long, value_name = "NCC")]
    pub match_min_ncc: Option<f64>,
    /// Matching (beyond the seed): sweep each primary circle's patch along its whole ray over
    /// the working range (`--reach-m`) and remove candidate pairs whose own NCC falls more than
    /// MARGIN below the best found there, further than --match-elsewhere-radii from the
    /// candidate's circle: the fruit is visible elsewhere in the stereo view, so the candidate
    /// circle is another fruit's (the pair the relaxation makes when the fruit's own stereo
    /// circle is missing). `off`: the seed's matching.
    #[arg(long, value_name = "MARGIN|off", value_parser = parse_or_off, default_value = "0.5")]
    pub match_better_elsewhere: OrOff,
    /// With --match-better-elsewhere: only a better match further than this many stereo-circle
    /// radii from the candidate's circle counts.
    #[arg(long, value_name = "RADII", default_value_t = 1.0)]
    pub match_elsewhere_radii: f64,
    /// Matching (beyond the seed): after the relaxation, sweep each unpaired primary circle's
    /// patch along its whole ray over the working range and pair it with an unpaired stereo
    /// circle whose centre lies within RADII of its radii from the best match, inside the
    /// disparity window (a fruit whose two circles sit too far apart in height for Eq. 10's
    /// row window). `off`: the seed's matching.
    #[arg(long, value_name = "RADII|off", value_parser = parse_or_off, default_value = "0.5")]
    pub match_leftovers: OrOff,
    /// With --match-leftovers: the lowest NCC of the best match along the ray that pairs.
    #[arg(long, value_name = "NCC", default_value_t = 0.5)]
    pub match_leftovers_min_ncc: f64,
    /// Matching: weight (pixels²) of the appearance cost 1 − NCC added to each candidate's
    /// squared disparity deviation in the relaxation. 0 (default) = the seed's matching.
    #[arg(long, value_name = "PX2", default_value_t = PairEvidence::default().ncc_weight_px2)]
    pub match_ncc_weight: f64,
    /// Matching: weight (pixels²) of the size cost ln(r_stereo / r_expected)² (the primary
    /// radius scaled to the stereo view's distance). 0 (default) = the seed's matching.
    #[arg(long, value_name = "PX2", default_value_t = PairEvidence::default().radius_weight_px2)]
    pub match_radius_weight: f64,
    /// Matching: how far the appearance sweep searches either side of each candidate's
    /// disparity along the epipolar line, pixels.
    #[arg(long, value_name = "PX", default_value_t = PairEvidence::default().appearance.search_px)]
    pub match_search_px: f64,
    /// Draw each frame's two shots side by side into DIR/<frame>.png: both views' truth circles
    /// (green), their circles (white when unpaired) and a line per located pair (red from the
    /// relaxation, orange from the pass over its leftovers) labelled with its depth.
    #[arg(long, value_name = "DIR")]
    pub overlay: Option<PathBuf>,
    /// Also measure matching and 3D error against the truth of both views; write them here.
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    /// Worker threads (default: all cores); never changes the output.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
}

/// A value, or `None` for `off`: a number (`--refine-fruit-chroma`,
/// `--refine-whole-patch-min-ncc`, ...; its range is checked with the other refinement
/// parameters, [`DisparityRefinement::validate`]) or a range (`--fruit-radius-m`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrOff<T = f64>(pub Option<T>);

/// The refinement the `--refine*` options ask for (`None` with `--no-refine`).
fn refinement(args: &StereoArgs) -> Result<Option<DisparityRefinement>> {
    if args.no_refine {
        return Ok(None);
    }
    let r = DisparityRefinement {
        patch_scale: args.refine_patch_scale,
        search_px: args.refine_search_px,
        step_px: args.refine_step_px,
        min_ncc: args.refine_min_ncc,
        fruit_chroma_radius: args.refine_fruit_chroma.0,
        whole_patch_min_ncc: args.refine_whole_patch_min_ncc.0,
        min_inside_fraction: args.refine_min_inside.0,
        sample_saturation_margin: args.refine_saturation_margin.0,
        ..DisparityRefinement::default()
    };
    r.validate().context("bad --refine-* option")?;
    Ok(Some(r))
}

/// `off`, else what `parse` makes of `s`.
fn off_or<T>(s: &str, parse: impl Fn(&str) -> Result<T, String>) -> Result<OrOff<T>, String> {
    if s == "off" {
        return Ok(OrOff(None));
    }
    parse(s).map(|v| OrOff(Some(v)))
}

fn parse_or_off(s: &str) -> Result<OrOff, String> {
    off_or(s, |s| {
        s.parse::<f64>()
            .map_err(|_| format!("need a number or `off`, got {s}"))
    })
}

fn parse_radius_range(s: &str) -> Result<OrOff<(f64, f64)>, String> {
    off_or(s, |s| {
        positive_range(
            s,
            ("MIN", "MAX"),
            "MIN,MAX in metres (e.g. 0.02,0.06) or `off`",
        )
    })
}

fn parse_reach(s: &str) -> Result<(f64, f64), String> {
    positive_range(s, ("NEAR", "FAR"), "NEAR,FAR in metres (e.g. 0.5,2.0)")
}

/// Two finite numbers `0 < lo < hi`, named `names` in the error (`example` shows the form).
fn positive_range(s: &str, names: (&str, &str), example: &str) -> Result<(f64, f64), String> {
    let (lo, hi) = parse_number_pair(s, example)?;
    if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo < hi) {
        let (a, b) = names;
        return Err(format!("need 0 < {a} < {b}, got {lo},{hi}"));
    }
    Ok((lo, hi))
}

/// The rig of a dataset: `rig.json` beside the primary view's camera.
///
/// # Errors
/// A missing or unreadable `rig.json`, or one whose pose is not a rotation about a vertical axis
/// through a pivot behind the camera (the rig of `pomona synth --stereo`).
pub fn read_rig(data: &Path, dataset: &Dataset) -> Result<RotatedStereo> {
    let path = data.join("rig.json");
    let text = std::fs::read_to_string(&path).with_context(|| {
        format!(
            "cannot read {} (make the dataset with `pomona synth --stereo`)",
            path.display()
        )
    })?;
    let file: RigFile = serde_json::from_str(&text)
        .with_context(|| format!("{} is not a rig file", path.display()))?;
    let rig = RotatedStereo::new(file.beta_rad, -file.pivot_m[2], *dataset.camera())
        .with_context(|| format!("{}: unusable rig", path.display()))?;
    let expected = rig.stereo_from_camera().to_homogeneous();
    let mut worst: f64 = 0.0;
    for (r, row) in file.stereo_from_camera.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            worst = worst.max((v - expected[(r, c)]).abs());
        }
    }
    if !(worst < 1e-9 && file.pivot_m[0] == 0.0 && file.pivot_m[1] == 0.0) {
        bail!(
            "{}: stereo_from_camera is not the rotation by 2·beta_rad about the vertical axis \
             through pivot_m (differs by {worst:e}); only that rig is supported",
            path.display()
        );
    }
    Ok(rig)
}

/// What one frame's stereo run produced: the located detections and what the report needs.
struct FrameRun {
    detections: Vec<Detection>,
    outcome: StereoFrameOutcome,
}

/// Locates the fruit of frame `stem` (its two colour views) with `locator`; draws them into
/// `overlay/<stem>.png` when given.
fn run_frame(
    stem: &str,
    views: (&Dataset, &Dataset),
    locator: &StereoLocator,
    overlay: Option<&Path>,
) -> Result<FrameRun> {
    let load = |dataset: &Dataset| -> Result<ColorImage> {
        let where_ = || format!("frame {stem} of {}", dataset.root().display());
        dataset
            .load_color(stem)
            .with_context(where_)?
            .with_context(|| format!("{} has no colour image", where_()))
    };
    let images = (load(views.0)?, load(views.1)?);
    let found = locator.locate(&images.0, &images.1).with_context(|| {
        format!(
            "locating the fruit of frame {stem} of {}",
            views.0.root().display()
        )
    })?;
    if let Some(dir) = overlay {
        let truth = (views.0.load_truth(stem)?, views.1.load_truth(stem)?);
        write_stereo_overlay(
            &dir.join(format!("{stem}.png")),
            (&images.0, &images.1),
            &locator.rig().camera,
            (truth.0.as_ref(), truth.1.as_ref()),
            &found,
            &format!("{stem}: {} located", found.detections.len()),
        )?;
    }
    let centres = |d: &[Detection]| d.iter().filter_map(|d| d.center_px).collect::<Vec<_>>();
    Ok(FrameRun {
        outcome: StereoFrameOutcome {
            stem: stem.to_owned(),
            evidence: found.evidence,
            primary_centres: centres(&found.primary),
            stereo_centres: centres(&found.stereo),
            pairs: found.pairs,
            rejected_by_size: found.rejected_by_size,
        },
        detections: found.detections,
    })
}

/// Runs `pomona stereo`.
///
/// # Errors
/// A dataset without `rig.json` or `stereo/`, a model that is not color-contour's, unreadable
/// frames, and unwritable output, each naming the file.
pub fn run(args: &StereoArgs) -> Result<()> {
    let dataset = Dataset::open(&args.data)
        .with_context(|| format!("cannot open dataset {}", args.data.display()))?;
    let stereo_dir = args.data.join("stereo");
    let stereo = Dataset::open(&stereo_dir).with_context(|| {
        format!(
            "cannot open the second view {} (make the dataset with `pomona synth --stereo`)",
            stereo_dir.display()
        )
    })?;
    if !(dataset.has_color() && stereo.has_color()) {
        bail!(
            "{} and {} must both have colour images",
            args.data.display(),
            stereo_dir.display()
        );
    }
    let rig = read_rig(&args.data, &dataset)?;
    let registry = pomona::pipelines();
    let pipeline = pomona::find_pipeline(&registry, STEREO_PIPELINE)?;
    let overrides = StereoLocator::detector_overrides(args.set.iter().cloned());
    let detector = load_detector(pipeline, args.model.as_deref(), &overrides)?;
    let keep = keep_rule(&detector, args.min_confidence)?;
    for dir in std::iter::once(&args.out).chain(&args.overlay) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let refinement = refinement(args)?;
    let distance_range_m = StereoSettings::sweep_range_m(args.reach_m, &rig);
    let evidence = PairEvidence {
        max_row_residual_px: args.match_max_row_px,
        better_elsewhere: args.match_better_elsewhere.0.map(|margin| BetterElsewhere {
            margin,
            min_distance_radii: args.match_elsewhere_radii,
            distance_range_m,
        }),
        min_ncc: args.match_min_ncc,
        ncc_weight_px2: args.match_ncc_weight,
        radius_weight_px2: args.match_radius_weight,
        appearance: DisparityRefinement {
            search_px: args.match_search_px,
            ..PairEvidence::default().appearance
        },
    };
    evidence.validate().context("bad --match-* option")?;
    let leftovers = args.match_leftovers.0.map(|radii| LeftoverPairing {
        max_distance_radii: radii,
        min_ncc: args.match_leftovers_min_ncc,
        ..LeftoverPairing::new(distance_range_m)
    });
    if let Some(pass) = &leftovers {
        pass.validate()
            .context("bad --match-leftovers or --match-leftovers-min-ncc")?;
    }
    let settings = StereoSettings {
        method: args.method,
        reach_m: args.reach_m,
        margin_px: args.margin_px,
        evidence,
        leftovers,
        refinement,
        fruit_radius_m: args
            .fruit_radius_m
            .map_or(StereoSettings::default().fruit_radius_m, |r| r.0),
    };
    let locator = StereoLocator::new(detector, keep, rig, settings)
        .context("bad --reach-m, --margin-px or --fruit-radius-m")?;
    let (rig, windows, detector) = (locator.rig(), locator.windows(), locator.detector());
    let pool = thread_pool(args.threads.map(|n| n as usize))?;
    let runs: Vec<FrameRun> = pool.install(|| {
        dataset
            .frames()
            .par_iter()
            .map(|stem| -> Result<FrameRun> {
                let run = run_frame(stem, (&dataset, &stereo), &locator, args.overlay.as_deref())?;
                let mut record =
                    detector.frame_record(stem, true, &run.detections, pomona::KeepRule::All);
                record.pipeline = STEREO_RECORD_PIPELINE.to_owned();
                pomona_io::write_json(&args.out.join(format!("{stem}.json")), &record)?;
                Ok(run)
            })
            .collect::<Result<Vec<FrameRun>>>()
    })?;
    let located: usize = runs.iter().map(|r| r.detections.len()).sum();
    let refined = runs
        .iter()
        .flat_map(|r| &r.outcome.pairs)
        .filter(|p| matches!(p.refinement, Some(RefinementOutcome::Refined { .. })))
        .count();
    println!(
        "{} frames: {located} fruit located by {}{} (β = {:.2}°, pivot {:.3} m, disparity window \
         {:.1}–{:.1} px, |Δv| ≤ {:.1} px) into {}",
        runs.len(),
        match args.method {
            StereoMethod::Paper => "Eq. 18",
            StereoMethod::Triangulate => "triangulation",
        },
        if refinement.is_some() {
            format!(", {refined} of them refined by appearance")
        } else {
            String::new()
        },
        rig.beta_rad.to_degrees(),
        rig.pivot_distance_m,
        windows.min_disparity_px,
        windows.max_disparity_px,
        windows.max_vertical_offset_px,
        args.out.display()
    );
    if let Some(path) = &args.report {
        let outcomes: Vec<StereoFrameOutcome> = runs.into_iter().map(|r| r.outcome).collect();
        let report = StereoReport::measure(
            rig,
            args.method,
            (refinement.is_some(), !evidence.is_off()),
            (&dataset, &stereo),
            &outcomes,
        )?;
        pomona_io::write_json(path, &report)?;
        print!("{}", report.to_markdown());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        args: StereoArgs,
    }

    fn parse(extra: &[&str]) -> StereoArgs {
        let base = ["pomona-stereo", "--data", "d", "--out", "o"];
        <Cli as clap::Parser>::parse_from(base.iter().chain(extra)).args
    }

    #[test]
    fn the_refine_options_default_to_the_librarys_refinement() {
        // The flags' defaults are written as strings for `off`; they must stay the library's.
        assert_eq!(
            refinement(&parse(&[])).unwrap(),
            Some(DisparityRefinement::default())
        );
        assert_eq!(refinement(&parse(&["--no-refine"])).unwrap(), None);
        let off = refinement(&parse(&["--refine-saturation-margin", "off"]))
            .unwrap()
            .unwrap();
        assert_eq!(off.sample_saturation_margin, None);
        let err = refinement(&parse(&["--refine-saturation-margin", "1.5"])).unwrap_err();
        assert!(
            format!("{err:#}").contains("sample_saturation_margin"),
            "{err:#}"
        );
    }

    #[test]
    fn reach_parses_and_rejects_bad_bands() {
        assert_eq!(parse_reach("0.5,2").unwrap(), (0.5, 2.0));
        for bad in ["0.5", "2,0.5", "0,1", "x,1", "1,inf"] {
            assert!(parse_reach(bad).is_err(), "{bad}");
        }
    }
}
