//! `pomona synth`: generate a synthetic RGB-D dataset of fruit in a crop row, with exact truth
//! and instance masks, for training detectors and benchmarking them.
//!
//! Thin layer over `pomona_synth::generate_dataset` (and `generate_approach` for `--approach`):
//! parses the options, guards the output folder (never mixes two datasets), and shows progress.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use pomona_synth::{
    generate_approach, generate_dataset, ApproachSpec, Background, CameraPreset, DatasetSpec,
    Domain, FruitChoice, FruitKind, LeafFamily, LightPreset, NoiseModel, SceneSpec, StereoRig,
    WIDE_DISTANCE_LIMITS_M,
};

use pomona_arm::TwoArmCell;
use pomona_core::nalgebra::Vector3;
use pomona_core::{PinholeCamera, RadialDistortion};

use crate::number_pair::parse_number_pair;
use crate::progress::progress_bar;

/// Arguments of `pomona synth`.
#[derive(Debug, Clone, clap::Args)]
pub struct SynthArgs {
    /// Output dataset folder; created if missing, and must be empty unless --force.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Number of frames to render (per sequence with --approach).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub frames: u32,
    /// Render N approach sequences instead of independent frames: the camera moves towards one
    /// target fruit at 0.2–0.5 m/s, 25 fps, into DIR/seq-0000/… (each a dataset with
    /// approach.json naming the target). Needs --domain wide or orchard.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub approach: Option<u32>,
    /// With --approach: the fruit sway on their stems (pendulums, 1–3 cm, about 1–1.8 Hz).
    #[arg(long)]
    pub sway: bool,
    /// Dataset seed: the same arguments and seed give byte-identical files.
    #[arg(long, value_name = "S")]
    pub seed: u64,
    /// Fruit kind; `mixed` draws one kind per frame.
    #[arg(long, value_enum, default_value_t = FruitArg::Pepper)]
    pub fruit: FruitArg,
    /// Camera model (image size and field of view).
    #[arg(long, value_enum, default_value_t = CameraArg::KinectV2)]
    pub camera: CameraArg,
    /// Scene family: `wide` draws domain-randomised worlds (distance, camera tilt, canopy, leaf
    /// shapes, backgrounds, shadows, exposure, fruit shape and colour, sensor artefacts);
    /// `narrow` the original crop row (byte-identical to earlier versions per seed); `orchard`
    /// citrus trees for the colour-contour method (5–20 fruit, touching clusters, orange to
    /// yellow-green, the --light preset's sun and exposure, backgrounds soil, second-row, sky).
    #[arg(long, value_enum, default_value_t = DomainArg::Wide)]
    pub domain: DomainArg,
    /// Depth noise. Default: `none` for the narrow domain; for the wide domain the camera's
    /// own model (`stereo` for d435, `tof-multipath` for the time-of-flight cameras).
    #[arg(long, value_enum)]
    pub noise: Option<NoiseArg>,
    /// Wide only: leaf families to draw from, comma-separated (default: all).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "LIST")]
    pub leaf_families: Option<Vec<LeafFamilyArg>>,
    /// Wide only: band of camera-to-fruit-centre distances in metres, `MIN,MAX`
    /// (default 0.3,1.6; allowed 0.25 to 3).
    #[arg(long, value_name = "MIN,MAX", value_parser = parse_distance_band)]
    pub distance_m: Option<(f64, f64)>,
    /// Wide only: backgrounds to draw from, comma-separated (default: all).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "LIST")]
    pub backgrounds: Option<Vec<BackgroundArg>>,
    /// Illumination (narrow and orchard domains; the wide domain draws its own sun, sky light
    /// and exposure). Ranges per preset: docs/formats.md.
    #[arg(long, value_enum, default_value_t = LightArg::Day)]
    pub light: LightArg,
    /// Fraction of peppers coloured like the leaves, 0 to 1 (narrow domain; the wide domain draws
    /// ripe, unripe green, blushed and yellow fruit of every kind).
    #[arg(long, value_name = "F", default_value_t = 0.0, value_parser = parse_fraction)]
    pub green_fraction: f64,
    /// Also render every frame from a second, rotated pose into DIR/stereo (pose in DIR/rig.json).
    #[arg(long)]
    pub stereo: bool,
    /// With --stereo: half the angle between the two views, β, degrees (seed 004 §4.2; the
    /// stereo view is turned by 2β). Default 4.
    #[arg(long, value_name = "DEG", requires = "stereo")]
    pub stereo_beta_deg: Option<f64>,
    /// With --stereo: distance from the camera back to the pivot of the rotation (the arm's
    /// hub), metres. Default 0.3.
    #[arg(long, value_name = "M", requires = "stereo")]
    pub stereo_pivot_m: Option<f64>,
    /// With --stereo: 2 adds seed 004's second arm — arm B's two shots in DIR/arm-b/ (its
    /// second shot in DIR/arm-b/stereo/) and, in every fruit's truth, which arm reaches it with
    /// which joints (`reach`).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=2), requires = "stereo")]
    pub arms: u8,
    /// Radial lens distortion of the camera, `K1,K2` (normalised coordinates scale by
    /// 1 + K1 r² + K2 r⁴; e.g. -0.2,0.05 for a wide-angle barrel lens), recorded in camera.json.
    /// Every view is rendered through it.
    #[arg(long, value_name = "K1,K2", value_parser = parse_distortion, allow_hyphen_values = true)]
    pub distortion: Option<(f64, f64)>,
    /// With --arms 2: arm B's hub is this far right of arm A's (and 0.02 m lower), metres.
    #[arg(long, value_name = "S", default_value_t = 0.6, requires = "stereo")]
    pub arm_spacing_m: f64,
    /// Worker threads (default: all cores); never changes the output.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Replace a dataset already in DIR (removes its camera.json, color/, depth/, truth/, mask/,
    /// stereo/, arm-b/, rig.json, synth.json and approach sequences seq-NNNN/; other files are left
    /// alone).
    #[arg(long)]
    pub force: bool,
}

/// `--fruit` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FruitArg {
    /// Sweet pepper.
    Pepper,
    /// Eggplant.
    Eggplant,
    /// Guava.
    Guava,
    /// Apple.
    Apple,
    /// Orange.
    Orange,
    /// One kind drawn per frame.
    Mixed,
}

/// `--camera` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CameraArg {
    /// 512×424, fx = 365.
    KinectV2,
    /// 176×144, 43.6° horizontal field of view.
    Sr4000,
    /// 640×480, fx = 615.
    D435,
    /// 1920×1080, fx = 917.
    AzureKinect,
}

/// `--noise` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum NoiseArg {
    /// Exact depth.
    None,
    /// Structured-light-like: σ grows with z².
    Low,
    /// Time-of-flight-like: 4–8 mm, flying pixels, dropouts, 1 mm steps.
    Tof,
    /// `tof` plus multipath interference (dim pixels among bright ones read too far).
    TofMultipath,
    /// Active stereo (D435): holes beside foreground edges, σ growing with z².
    Stereo,
}

/// `--domain` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DomainArg {
    /// The original crop row.
    Narrow,
    /// Domain-randomised worlds.
    Wide,
    /// Citrus orchard under the --light preset.
    Orchard,
}

/// `--leaf-families` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LeafFamilyArg {
    /// Ovate blades.
    Elliptic,
    /// Long, narrow, pointed blades.
    Lanceolate,
    /// Palmate, maple-like blades.
    Lobed,
    /// Leaflets on a rachis.
    Compound,
}

/// `--backgrounds` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BackgroundArg {
    /// Bare soil.
    Soil,
    /// Black ground cloth (no depth).
    Cloth,
    /// The next crop row, 1.5–3 m away.
    SecondRow,
    /// Open sky (no depth).
    Sky,
    /// Greenhouse plastic, posts and pipes.
    Greenhouse,
}

fn parse_distortion(s: &str) -> Result<(f64, f64), String> {
    let (k1, k2) = parse_number_pair(s, "K1,K2 (e.g. -0.2,0.05)")?;
    if !(k1.abs() <= 1.0 && k2.abs() <= 1.0) {
        return Err(format!("need |K1|, |K2| <= 1, got {k1},{k2}"));
    }
    Ok((k1, k2))
}

fn parse_distance_band(s: &str) -> Result<(f64, f64), String> {
    let (lo, hi) = parse_number_pair(s, "MIN,MAX in metres (e.g. 0.3,0.8)")?;
    let (min, max) = WIDE_DISTANCE_LIMITS_M;
    if !(lo.is_finite() && hi.is_finite() && lo >= min && lo <= hi && hi <= max) {
        return Err(format!(
            "need {min} <= MIN <= MAX <= {max} metres, got {lo},{hi}"
        ));
    }
    Ok((lo, hi))
}

/// `--light` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LightArg {
    /// Moderate daylight.
    Day,
    /// Weak light, more image noise.
    Dim,
    /// Strong sun, little ambient light.
    Harsh,
    /// Warm sun low on one side.
    LowSun,
    /// Sun behind the canopy, facing the camera.
    Backlight,
}

fn parse_fraction(s: &str) -> Result<f64, String> {
    let f: f64 = s.parse().map_err(|e| format!("not a number: {e}"))?;
    if (0.0..=1.0).contains(&f) {
        Ok(f)
    } else {
        Err(format!("must be between 0 and 1, got {f}"))
    }
}

impl SynthArgs {
    /// The approach-sequence spec these arguments describe, with `--approach`.
    pub fn to_approach_spec(&self) -> Option<ApproachSpec> {
        let n = self.approach?;
        let frames = self.to_spec();
        let mut spec = ApproachSpec::new(frames.scene, n, self.frames, self.seed, self.sway);
        spec.threads = frames.threads;
        Some(spec)
    }

    /// The library spec these arguments describe.
    pub fn to_spec(&self) -> DatasetSpec {
        let fruit = match self.fruit {
            FruitArg::Pepper => FruitChoice::Only(FruitKind::Pepper),
            FruitArg::Eggplant => FruitChoice::Only(FruitKind::Eggplant),
            FruitArg::Guava => FruitChoice::Only(FruitKind::Guava),
            FruitArg::Apple => FruitChoice::Only(FruitKind::Apple),
            FruitArg::Orange => FruitChoice::Only(FruitKind::Orange),
            FruitArg::Mixed => FruitChoice::Mixed,
        };
        let camera = match self.camera {
            CameraArg::KinectV2 => CameraPreset::KinectV2,
            CameraArg::Sr4000 => CameraPreset::Sr4000,
            CameraArg::D435 => CameraPreset::D435,
            CameraArg::AzureKinect => CameraPreset::AzureKinect,
        };
        let domain = match self.domain {
            DomainArg::Narrow => Domain::Narrow,
            DomainArg::Wide => Domain::Wide,
            DomainArg::Orchard => Domain::Orchard,
        };
        let noise = match (self.noise, domain) {
            (Some(NoiseArg::None), _) | (None, Domain::Narrow) => NoiseModel::None,
            (Some(NoiseArg::Low), _) => NoiseModel::Low,
            (Some(NoiseArg::Tof), _) => NoiseModel::Tof,
            (Some(NoiseArg::TofMultipath), _) => NoiseModel::TofMultipath,
            (Some(NoiseArg::Stereo), _) => NoiseModel::Stereo,
            (None, Domain::Wide | Domain::Orchard) => NoiseModel::for_camera(camera),
        };
        let defaults = SceneSpec::default();
        let leaf_families = self
            .leaf_families
            .as_ref()
            .map_or(defaults.leaf_families, |v| {
                v.iter()
                    .map(|f| match f {
                        LeafFamilyArg::Elliptic => LeafFamily::Elliptic,
                        LeafFamilyArg::Lanceolate => LeafFamily::Lanceolate,
                        LeafFamilyArg::Lobed => LeafFamily::Lobed,
                        LeafFamilyArg::Compound => LeafFamily::Compound,
                    })
                    .collect()
            });
        let backgrounds = self.backgrounds.as_ref().map_or_else(
            || domain.default_backgrounds(),
            |v| {
                v.iter()
                    .map(|b| match b {
                        BackgroundArg::Soil => Background::Soil,
                        BackgroundArg::Cloth => Background::Cloth,
                        BackgroundArg::SecondRow => Background::SecondRow,
                        BackgroundArg::Sky => Background::Sky,
                        BackgroundArg::Greenhouse => Background::Greenhouse,
                    })
                    .collect()
            },
        );
        let light = match self.light {
            LightArg::Day => LightPreset::Day,
            LightArg::Dim => LightPreset::Dim,
            LightArg::Harsh => LightPreset::Harsh,
            LightArg::LowSun => LightPreset::LowSun,
            LightArg::Backlight => LightPreset::Backlight,
        };
        let lens = self.distortion.map(|(k1, k2)| RadialDistortion { k1, k2 });
        let scene = SceneSpec {
            fruit,
            camera: PinholeCamera {
                distortion: lens,
                ..camera.camera()
            },
            noise,
            light,
            green_fraction: self.green_fraction,
            domain,
            leaf_families,
            backgrounds,
            wide_distance_m: self.distance_m.unwrap_or(defaults.wide_distance_m),
            ..SceneSpec::default()
        };
        let mut spec = DatasetSpec::new(scene, self.frames, self.seed);
        spec.stereo = self.stereo.then(|| self.stereo_rig());
        spec.arms = (self.arms == 2).then(|| TwoArmCell {
            b_hub_in_a: Vector3::new(self.arm_spacing_m, TwoArmCell::default().b_hub_in_a.y, 0.0),
            ..TwoArmCell::default()
        });
        spec.threads = self.threads.map(|n| n as usize);
        spec
    }
}

impl SynthArgs {
    /// The stereo rig of `--stereo-beta-deg` and `--stereo-pivot-m` (defaults elsewhere).
    pub fn stereo_rig(&self) -> StereoRig {
        let defaults = StereoRig::default();
        StereoRig {
            beta_rad: self
                .stereo_beta_deg
                .map_or(defaults.beta_rad, f64::to_radians),
            pivot_distance_m: self.stereo_pivot_m.unwrap_or(defaults.pivot_distance_m),
        }
    }

    /// Refuses wide-only options with `--domain narrow`, and repeated list entries.
    ///
    /// # Errors
    /// Names the offending option.
    pub fn check(&self) -> Result<()> {
        if self.domain == DomainArg::Narrow {
            for (given, flag) in [
                (self.leaf_families.is_some(), "--leaf-families"),
                (self.distance_m.is_some(), "--distance-m"),
                (self.backgrounds.is_some(), "--backgrounds"),
            ] {
                if given {
                    bail!(
                        "{flag} only applies to --domain wide (hold-out knobs of the wide domain)"
                    );
                }
            }
        }
        if self.sway && self.approach.is_none() {
            bail!("--sway only applies to approach sequences (--approach N)");
        }
        if self.approach.is_some() {
            if self.domain == DomainArg::Narrow {
                bail!("--approach needs --domain wide or orchard (the narrow row has a fixed distance)");
            }
            if self.stereo {
                bail!("--stereo is not available with --approach");
            }
            if self.frames < 2 {
                bail!("--approach needs --frames of at least 2");
            }
        }
        if !(self.arm_spacing_m.is_finite() && self.arm_spacing_m > 0.0) {
            bail!("--arm-spacing-m must be a positive number of metres");
        }
        if self.stereo {
            self.stereo_rig()
                .validate()
                .context("invalid --stereo-beta-deg or --stereo-pivot-m")?;
        }
        self.to_spec()
            .scene
            .validate()
            .context("invalid synth options")?;
        Ok(())
    }
}

/// What a generated dataset consists of; `--force` removes exactly these (and `seq-NNNN/`
/// approach sequences) before writing.
const DATASET_ENTRIES: [&str; 9] = [
    "camera.json",
    "synth.json",
    "rig.json",
    "color",
    "depth",
    "truth",
    "mask",
    "stereo",
    "arm-b",
];

/// Whether `name` is an approach sequence's folder (`seq-` and digits).
fn is_sequence_dir(name: &str) -> bool {
    name.strip_prefix("seq-")
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
}

/// Makes sure writing into `out` cannot mix two datasets.
fn prepare_output(out: &Path, force: bool) -> Result<()> {
    if !out.exists() {
        return Ok(());
    }
    if !out.is_dir() {
        bail!("{} exists and is not a folder", out.display());
    }
    let mut entries =
        std::fs::read_dir(out).with_context(|| format!("cannot list {}", out.display()))?;
    if entries.next().is_none() {
        return Ok(());
    }
    if !force {
        bail!(
            "{} is not empty; choose a new folder or pass --force to replace the dataset in it",
            out.display()
        );
    }
    let sequences = std::fs::read_dir(out)
        .with_context(|| format!("cannot list {}", out.display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| is_sequence_dir(n));
    let names: Vec<String> = DATASET_ENTRIES
        .iter()
        .map(|s| s.to_string())
        .chain(sequences)
        .collect();
    for name in names {
        let path = out.join(name);
        let removed = if path.is_dir() {
            std::fs::remove_dir_all(&path)
        } else if path.exists() {
            std::fs::remove_file(&path)
        } else {
            Ok(())
        };
        removed.with_context(|| format!("cannot remove {}", path.display()))?;
    }
    Ok(())
}

/// Runs `pomona synth`.
///
/// # Errors
/// A non-empty output folder without `--force`, an invalid option, or a file that could not be
/// written (the message names it).
pub fn run(args: &SynthArgs) -> Result<()> {
    args.check()?;
    prepare_output(&args.out, args.force)?;
    if let Some(spec) = args.to_approach_spec() {
        let bar = progress_bar((spec.sequences * spec.frames) as usize, "rendering");
        let started = Instant::now();
        let summary = generate_approach(&spec, &args.out, &|_| bar.inc(1))
            .with_context(|| format!("generating approach sequences in {}", args.out.display()))?;
        bar.finish_and_clear();
        println!(
            "wrote {} approach sequences ({} frames{}) to {} in {:.1} s",
            summary.sequences.len(),
            summary.frames,
            if args.sway { ", fruit swaying" } else { "" },
            args.out.display(),
            started.elapsed().as_secs_f64()
        );
        return Ok(());
    }
    let spec = args.to_spec();
    let bar = progress_bar(args.frames as usize, "rendering");
    let started = Instant::now();
    let summary = generate_dataset(&spec, &args.out, &|_| bar.inc(1))
        .with_context(|| format!("generating a synthetic dataset in {}", args.out.display()))?;
    bar.finish_and_clear();
    println!(
        "wrote {} frames{} with {} visible fruit to {} in {:.1} s",
        summary.frames,
        if args.stereo { " (+ stereo views)" } else { "" },
        summary.fruits,
        args.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, Parser)]
    struct Cli {
        #[command(flatten)]
        args: SynthArgs,
    }

    fn parse(extra: &[&str]) -> Result<SynthArgs, clap::Error> {
        let base = [
            "pomona-synth",
            "--out",
            "/tmp/x",
            "--frames",
            "3",
            "--seed",
            "9",
        ];
        Cli::try_parse_from(base.iter().chain(extra)).map(|c| c.args)
    }

    #[test]
    fn defaults_and_required_options() {
        let a = parse(&[]).unwrap();
        assert_eq!(a.out, PathBuf::from("/tmp/x"));
        assert_eq!((a.frames, a.seed), (3, 9));
        assert_eq!(a.fruit, FruitArg::Pepper);
        assert_eq!(a.camera, CameraArg::KinectV2);
        assert_eq!(a.noise, None);
        assert_eq!(a.domain, DomainArg::Wide);
        let spec = a.to_spec();
        assert_eq!(spec.scene.domain, Domain::Wide);
        assert_eq!(spec.scene.noise, NoiseModel::TofMultipath);
        assert_eq!(spec.scene.leaf_families, LeafFamily::ALL.to_vec());
        assert_eq!(spec.scene.backgrounds, Background::ALL.to_vec());
        let narrow = parse(&["--domain", "narrow"]).unwrap().to_spec();
        assert_eq!(narrow.scene.noise, NoiseModel::None);
        assert_eq!(narrow.scene.domain, Domain::Narrow);
        let d435 = parse(&["--camera", "d435"]).unwrap().to_spec();
        assert_eq!(d435.scene.noise, NoiseModel::Stereo);
        assert_eq!(a.light, LightArg::Day);
        assert_eq!(a.green_fraction, 0.0);
        assert!(!a.stereo && !a.force && a.threads.is_none());
        assert!(Cli::try_parse_from(["p", "--frames", "1", "--seed", "1"]).is_err());
        assert!(Cli::try_parse_from(["p", "--out", "d", "--seed", "1"]).is_err());
        assert!(Cli::try_parse_from(["p", "--out", "d", "--frames", "1"]).is_err());
    }

    #[test]
    fn every_option_value_parses_into_the_spec() {
        for (v, kind) in [
            ("pepper", Some(FruitKind::Pepper)),
            ("eggplant", Some(FruitKind::Eggplant)),
            ("guava", Some(FruitKind::Guava)),
            ("apple", Some(FruitKind::Apple)),
            ("orange", Some(FruitKind::Orange)),
            ("mixed", None),
        ] {
            let spec = parse(&["--fruit", v]).unwrap().to_spec();
            let expected = kind.map_or(FruitChoice::Mixed, FruitChoice::Only);
            assert_eq!(spec.scene.fruit, expected);
        }
        for preset in CameraPreset::ALL {
            let spec = parse(&["--camera", preset.name()]).unwrap().to_spec();
            assert_eq!(spec.scene.camera, preset.camera());
        }
        for model in NoiseModel::ALL {
            let spec = parse(&["--noise", model.name()]).unwrap().to_spec();
            assert_eq!(spec.scene.noise, model);
        }
        for light in LightPreset::ALL {
            let spec = parse(&["--light", light.name()]).unwrap().to_spec();
            assert_eq!(spec.scene.light, light);
        }
        let a = parse(&[
            "--green-fraction",
            "0.25",
            "--stereo",
            "--threads",
            "2",
            "--force",
        ])
        .unwrap();
        let spec = a.to_spec();
        assert_eq!(spec.scene.green_fraction, 0.25);
        assert_eq!(spec.stereo, Some(StereoRig::default()));
        assert_eq!(spec.threads, Some(2));
        assert_eq!((spec.frames, spec.seed), (3, 9));
        assert!(a.force);
    }

    #[test]
    fn bad_values_are_refused() {
        for bad in [
            &["--fruit", "banana"][..],
            &["--camera", "kinect"],
            &["--noise", "high"],
            &["--light", "night"],
            &["--green-fraction", "1.5"],
            &["--green-fraction", "-0.1"],
            &["--green-fraction", "x"],
            &["--threads", "0"],
            &["--domain", "medium"],
            &["--leaf-families", "ovate"],
            &["--backgrounds", "sea"],
            &["--distance-m", "0.8"],
            &["--distance-m", "0.8,0.3"],
            &["--distance-m", "0.1,0.5"],
            &["--distance-m", "0.3,x"],
        ] {
            assert!(parse(bad).is_err(), "{bad:?} accepted");
        }
        assert!(Cli::try_parse_from(["p", "--out", "d", "--frames", "0", "--seed", "1"]).is_err());
    }

    #[test]
    fn hold_out_knobs_parse_and_are_refused_in_the_narrow_domain() {
        let a = parse(&[
            "--leaf-families",
            "lobed,compound",
            "--distance-m",
            "0.8,1.6",
            "--backgrounds",
            "sky,second-row",
            "--noise",
            "tof",
        ])
        .unwrap();
        a.check().unwrap();
        let s = a.to_spec().scene;
        assert_eq!(
            s.leaf_families,
            vec![LeafFamily::Lobed, LeafFamily::Compound]
        );
        assert_eq!(s.backgrounds, vec![Background::Sky, Background::SecondRow]);
        assert_eq!(s.wide_distance_m, (0.8, 1.6));
        assert_eq!(s.noise, NoiseModel::Tof);
        for flag in [
            &["--leaf-families", "lobed"][..],
            &["--distance-m", "0.3,0.8"],
            &["--backgrounds", "soil"],
        ] {
            let a = parse(&[&["--domain", "narrow"][..], flag].concat()).unwrap();
            let err = format!("{:#}", a.check().unwrap_err());
            assert!(err.contains(flag[0]) && err.contains("wide"), "{err}");
        }
        let twice = parse(&["--leaf-families", "lobed,lobed"]).unwrap();
        assert!(format!("{:#}", twice.check().unwrap_err()).contains("leaf-families"));
    }

    #[test]
    fn orchard_and_approach_options() {
        let a = parse(&[
            "--domain", "orchard", "--fruit", "orange", "--light", "low-sun",
        ])
        .unwrap();
        a.check().unwrap();
        let s = a.to_spec().scene;
        assert_eq!(s.domain, Domain::Orchard);
        assert_eq!(s.light, LightPreset::LowSun);
        assert_eq!(s.backgrounds, Domain::Orchard.default_backgrounds());
        assert_eq!(s.noise, NoiseModel::TofMultipath);
        assert!(a.to_approach_spec().is_none());
        let a = parse(&["--domain", "orchard", "--approach", "4", "--sway"]).unwrap();
        a.check().unwrap();
        let spec = a.to_approach_spec().unwrap();
        assert_eq!(
            (spec.sequences, spec.frames, spec.seed, spec.sway),
            (4, 3, 9, true)
        );
        for (bad, flag) in [
            (&["--sway"][..], "--sway"),
            (&["--approach", "2", "--domain", "narrow"], "--approach"),
            (&["--approach", "2", "--stereo"], "--stereo"),
        ] {
            let err = format!("{:#}", parse(bad).unwrap().check().unwrap_err());
            assert!(err.contains(flag), "{err}");
        }
        let rig = parse(&[
            "--stereo",
            "--stereo-beta-deg",
            "6",
            "--stereo-pivot-m",
            "0.25",
        ])
        .unwrap();
        rig.check().unwrap();
        let rig = rig.to_spec().stereo.unwrap();
        assert!((rig.beta_rad - 6f64.to_radians()).abs() < 1e-15);
        assert_eq!(rig.pivot_distance_m, 0.25);
        assert!(
            parse(&["--stereo-beta-deg", "6"]).is_err(),
            "needs --stereo"
        );
        for bad in [["--stereo-beta-deg", "50"], ["--stereo-pivot-m", "0"]] {
            let a = parse(&[&["--stereo"][..], &bad].concat()).unwrap();
            assert!(format!("{:#}", a.check().unwrap_err()).contains("stereo"));
        }
        assert!(
            is_sequence_dir("seq-0012") && !is_sequence_dir("seq-") && !is_sequence_dir("seqs")
        );
    }

    #[test]
    fn run_writes_a_dataset_and_guards_the_folder() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("ds");
        let out_s = out.to_str().unwrap();
        let args = |frames: &str, extra: &[&str]| {
            let base = ["p", "--out", out_s, "--frames", frames, "--seed", "5"];
            let base = base
                .iter()
                .chain(["--camera", "sr4000", "--fruit", "mixed"].iter());
            Cli::try_parse_from(base.chain(extra)).unwrap().args
        };
        run(&args(
            "3",
            &["--noise", "tof", "--stereo", "--light", "harsh"],
        ))
        .unwrap();
        assert!(out.join("depth/000002.png").exists());
        assert!(out.join("stereo/mask/000002.png").exists());
        assert!(out.join("rig.json").exists());
        // The default domain is wide: every truth file records what its frame drew.
        let truth = std::fs::read_to_string(out.join("truth/000001.json")).unwrap();
        let truth: serde_json::Value = serde_json::from_str(&truth).unwrap();
        assert_eq!(truth["synth"]["domain"], "wide");
        assert_eq!(truth["synth"]["noise"], "tof");

        // Refuses to mix datasets, naming the folder.
        let err = run(&args("1", &[])).unwrap_err();
        assert!(format!("{err:#}").contains(out_s), "{err:#}");
        assert!(out.join("depth/000002.png").exists());

        // --force replaces the dataset: no stale frames or stereo view survive; other files do.
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        run(&args("1", &["--force"])).unwrap();
        assert!(out.join("depth/000000.png").exists());
        assert!(!out.join("depth/000002.png").exists());
        assert!(!out.join("stereo").exists() && !out.join("rig.json").exists());
        assert!(out.join("notes.txt").exists());

        // A file in the way is an error that names it.
        let file = dir.path().join("file");
        std::fs::write(&file, "x").unwrap();
        let a = Cli::try_parse_from([
            "p",
            "--out",
            file.to_str().unwrap(),
            "--frames",
            "1",
            "--seed",
            "1",
        ])
        .unwrap()
        .args;
        assert!(format!("{:#}", run(&a).unwrap_err()).contains("file"));
    }
}
