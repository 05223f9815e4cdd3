//! `pomona arm`: seed 004 §4.2's learned mapping from a target's two image positions to the
//! arm's encoder readings (the 4-8-3 network of Eq. 19), on the simulated robot of `pomona-arm`.
//!
//! * `pomona arm train --out ARM.json [--seed S]` draws the robot's hidden calibration errors
//!   from the seed, builds the training set on a regular grid of targets seen by both shots and
//!   trains the network; the model file records the seed and magnitudes.
//! * `pomona arm eval --model ARM.json [--seed S] [--json R]` rebuilds the same robot, draws
//!   random targets off the grid (from `--seed`) and reports where the true robot's end lands
//!   (`error_mm.median`, `error_mm.p95`) with the network's readings and with Eq. 18 + exact
//!   nominal kinematics, and the latter again on the same rig with the calibration errors off.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use pomona_arm::{
    train_joint_network, ArmLimits, ArmModelFile, ArmRig, ArmSimulation, CalibrationErrors,
    CalibrationMagnitudes, EndPositionError, NetworkTraining, NominalMapping, ARM_MODEL_FORMAT,
    ARM_MODEL_VERSION,
};
use serde::Serialize;

/// Arguments of `pomona arm`.
#[derive(Debug, clap::Args)]
pub struct ArmArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: ArmCommand,
}

/// The subcommands of `pomona arm`.
#[derive(Debug, clap::Subcommand)]
pub enum ArmCommand {
    /// Train the image → encoder-reading network on a grid of targets; write the model file.
    Train(ArmTrainArgs),
    /// Measure the end-position error of a trained network on random targets, beside Eq. 18 +
    /// exact kinematics.
    Eval(ArmEvalArgs),
}

/// Arguments of `pomona arm train`.
#[derive(Debug, clap::Args)]
pub struct ArmTrainArgs {
    /// Where to write the model (JSON).
    #[arg(long, value_name = "ARM.json")]
    pub out: PathBuf,
    /// Seed of the robot's calibration errors and of the network's starting weights.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// An ideal robot: no calibration errors and no lens distortion.
    #[arg(long)]
    pub ideal: bool,
    /// Training grid: values of α, θ and r (each ≥ 2), over the joint ranges.
    #[arg(long, value_delimiter = ',', default_values_t = [17, 13, 21])]
    pub grid: Vec<usize>,
    /// Hub-to-camera distance along the link (the seed's f + Z0), metres.
    #[arg(long, default_value_t = ArmRig::default().pivot_m)]
    pub pivot_m: f64,
    /// Half the angle between the two shots, degrees.
    #[arg(long, default_value_t = ArmRig::default().beta_rad.to_degrees())]
    pub beta_deg: f64,
    /// Nearest depth in front of a shot that counts as seen, metres.
    #[arg(long, default_value_t = ArmRig::default().min_depth_m)]
    pub min_depth_m: f64,
    /// Hidden units (the seed's 8).
    #[arg(long, default_value_t = 8)]
    pub hidden: usize,
    /// Starting points tried; the best network is kept.
    #[arg(long, default_value_t = 4)]
    pub restarts: usize,
    /// Levenberg–Marquardt iterations per start at most.
    #[arg(long, default_value_t = 400)]
    pub iterations: usize,
    /// Azimuth encoder offset size, degrees.
    #[arg(long, default_value_t = 0.5)]
    pub alpha_offset_deg: f64,
    /// Elevation encoder offset size, degrees.
    #[arg(long, default_value_t = 0.5)]
    pub theta_offset_deg: f64,
    /// Extension encoder offset size, millimetres.
    #[arg(long, default_value_t = 5.0)]
    pub r_offset_mm: f64,
    /// Camera mounting offset size per axis, millimetres.
    #[arg(long, default_value_t = 5.0)]
    pub camera_offset_mm: f64,
    /// Camera mounting rotation size per axis, degrees.
    #[arg(long, default_value_t = 0.5)]
    pub camera_rotation_deg: f64,
    /// First radial distortion coefficient of the lens.
    #[arg(long, default_value_t = -0.10, allow_hyphen_values = true)]
    pub k1: f64,
    /// Second radial distortion coefficient of the lens.
    #[arg(long, default_value_t = 0.02, allow_hyphen_values = true)]
    pub k2: f64,
}

/// Arguments of `pomona arm eval`.
#[derive(Debug, clap::Args)]
pub struct ArmEvalArgs {
    /// The model file written by `pomona arm train`.
    #[arg(long, value_name = "ARM.json")]
    pub model: PathBuf,
    /// Seed of the random targets (the robot's calibration comes from the model's seed).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Random targets drawn over the joint ranges and seen by both shots.
    #[arg(long, default_value_t = 2000)]
    pub targets: usize,
    /// Also write the report as JSON here.
    #[arg(long, value_name = "R.json")]
    pub json: Option<PathBuf>,
}

/// Runs `pomona arm`.
///
/// # Errors
/// See [`train`] and [`eval`].
pub fn run(args: &ArmArgs) -> Result<()> {
    match &args.command {
        ArmCommand::Train(a) => train(a),
        ArmCommand::Eval(a) => eval(a),
    }
}

impl ArmTrainArgs {
    fn magnitudes(&self) -> CalibrationMagnitudes {
        if self.ideal {
            return CalibrationMagnitudes::none();
        }
        CalibrationMagnitudes {
            alpha_offset_rad: self.alpha_offset_deg.to_radians(),
            theta_offset_rad: self.theta_offset_deg.to_radians(),
            r_offset_m: self.r_offset_mm * 1e-3,
            camera_offset_m: self.camera_offset_mm * 1e-3,
            camera_rotation_rad: self.camera_rotation_deg.to_radians(),
            k1: self.k1,
            k2: self.k2,
        }
    }
}

/// Runs `pomona arm train`.
///
/// # Errors
/// Invalid magnitudes or training parameters, or an unwritable output.
pub fn train(args: &ArmTrainArgs) -> Result<()> {
    let magnitudes = args.magnitudes();
    magnitudes
        .validate()
        .context("invalid calibration error sizes")?;
    let grid: [usize; 3] = args
        .grid
        .as_slice()
        .try_into()
        .context("--grid takes three counts: α,θ,r")?;
    let rig = ArmRig {
        pivot_m: args.pivot_m,
        beta_rad: args.beta_deg.to_radians(),
        min_depth_m: args.min_depth_m,
        ..ArmRig::default()
    };
    rig.validate().context("invalid rig")?;
    magnitudes
        .validate_lens(&rig.camera)
        .context("invalid calibration error sizes")?;
    let sim = ArmSimulation {
        rig,
        limits: ArmLimits::default(),
        errors: CalibrationErrors::draw(&magnitudes, args.seed),
    };
    let samples = sim.grid_samples(grid).context("invalid --grid")?;
    let training = NetworkTraining {
        hidden: args.hidden,
        restarts: args.restarts,
        max_iterations: args.iterations,
        seed: args.seed,
    };
    let started = Instant::now();
    let (network, report) =
        train_joint_network(&samples, &training).context("cannot train the network")?;
    let seconds = started.elapsed().as_secs_f64();
    let model = ArmModelFile {
        format: ARM_MODEL_FORMAT.to_owned(),
        version: ARM_MODEL_VERSION,
        calibration_seed: args.seed,
        magnitudes,
        rig,
        limits: sim.limits,
        grid,
        training,
        report,
        network,
    };
    model.save(&args.out)?;
    println!(
        "trained a 4-{}-3 network on {} grid targets in {seconds:.1} s ({} iterations): scaled \
         RMS error {:.2e} (from {:.2e}); model in {}",
        args.hidden,
        report.samples,
        report.iterations,
        report.final_rms,
        report.initial_rms,
        args.out.display()
    );
    Ok(())
}

/// The report of `pomona arm eval` (`--json`).
#[derive(Debug, Serialize)]
struct EvalReport {
    model: String,
    targets: usize,
    targets_seed: u64,
    calibration_seed: u64,
    calibration_errors: CalibrationErrors,
    network: MethodReport,
    eq18_nominal: MethodReport,
    calibration_errors_off: CalibrationOffReport,
}

#[derive(Debug, Serialize)]
struct CalibrationOffReport {
    eq18_nominal: MethodReport,
}

#[derive(Debug, Serialize)]
struct MethodReport {
    error_mm: ErrorMm,
    count: usize,
    failed: usize,
}

#[derive(Debug, Serialize)]
struct ErrorMm {
    median: f64,
    p95: f64,
    max: f64,
}

impl From<EndPositionError> for MethodReport {
    fn from(e: EndPositionError) -> Self {
        Self {
            error_mm: ErrorMm {
                median: e.median,
                p95: e.p95,
                max: e.max,
            },
            count: e.count,
            failed: e.failed,
        }
    }
}

/// Runs `pomona arm eval`.
///
/// # Errors
/// An unreadable or invalid model file (naming it), a working space too small to draw the
/// targets, a mapping that fails on every target, or an unwritable `--json`.
pub fn eval(args: &ArmEvalArgs) -> Result<()> {
    let model = ArmModelFile::load(&args.model)?;
    let sim = model.simulation();
    let nominal = NominalMapping {
        stereo: model.rig.stereo()?,
    };
    let measure = |sim: &ArmSimulation, label: &str, network: bool| -> Result<MethodReport> {
        let samples = sim
            .random_samples(args.targets, args.seed)
            .context("cannot draw the evaluation targets")?;
        let errors = if network {
            EndPositionError::measure(sim, &samples, |p| Some(model.network.predict(p)))
        } else {
            EndPositionError::measure(sim, &samples, |p| nominal.readings(p).ok())
        };
        errors
            .map(MethodReport::from)
            .with_context(|| format!("{label}: no target could be mapped"))
    };
    let report = EvalReport {
        model: args.model.display().to_string(),
        targets: args.targets,
        targets_seed: args.seed,
        calibration_seed: model.calibration_seed,
        calibration_errors: sim.errors,
        network: measure(&sim, "network", true)?,
        eq18_nominal: measure(&sim, "Eq. 18", false)?,
        calibration_errors_off: CalibrationOffReport {
            eq18_nominal: measure(&sim.nominal(), "Eq. 18 without calibration errors", false)?,
        },
    };
    let line = |name: &str, m: &MethodReport| {
        println!(
            "{name:<40} median {:>8.3} mm  p95 {:>8.3} mm  max {:>8.3} mm  ({} targets, {} failed)",
            m.error_mm.median, m.error_mm.p95, m.error_mm.max, m.count, m.failed
        );
    };
    println!(
        "{} random targets (seed {}), robot of calibration seed {}:",
        args.targets, args.seed, model.calibration_seed
    );
    line(
        &format!("network 4-{}-3", model.network.hidden),
        &report.network,
    );
    line("Eq. 18 + exact nominal kinematics", &report.eq18_nominal);
    line(
        "Eq. 18, calibration errors off",
        &report.calibration_errors_off.eq18_nominal,
    );
    if let Some(path) = &args.json {
        pomona_io::write_json(path, &report)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}
