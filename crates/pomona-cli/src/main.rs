//! `pomona`: find fruit in 3D from RGB-D data — the command-line front end.
//!
//! Each subcommand lives in `commands/<name>.rs` (in the `pomona_cli` library) with its clap
//! arguments and a `run` function; this file only dispatches and turns errors into one line on
//! stderr and an exit status (`exit_status.rs`).

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use pomona_cli::commands;

/// Find fruit in 3D from RGB-D cameras and point clouds.
#[derive(Debug, Parser)]
#[command(name = "pomona", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Summarise a dataset: frames, resolution, depth coverage, annotations.
    Info(commands::info::InfoArgs),
    /// Export one frame of a dataset as a coloured point cloud (.ply or .pcd).
    Cloud(commands::cloud::CloudArgs),
    /// Convert a point cloud between PCD and PLY.
    Convert(commands::convert::ConvertArgs),
    /// Score detections against truth: AP (VOC 11-point and all-point), precision/recall,
    /// centre and diameter errors.
    Eval(commands::eval::EvalArgs),
    /// Generate a synthetic RGB-D dataset of crop rows with exact fruit truth.
    Synth(commands::synth::SynthArgs),
    /// Train a detector (a pipeline) on labelled datasets and write its model file.
    Train(commands::train::TrainArgs),
    /// Refit a model's confidence calibration on labelled frames it did not train on
    /// (optionally over the detections' geometric cues), without retraining it.
    Calibrate(commands::calibrate::CalibrateArgs),
    /// Find fruit in every frame of a dataset or a ROS 2 recording; writes one detection file
    /// per frame.
    Detect(commands::detect::DetectArgs),
    /// Write a recording's (ROS 2 MCAP, ROS 1 bag, RealSense bag) synchronised colour/depth frames
    /// as a dataset folder.
    Extract(commands::extract::ExtractArgs),
    /// Repeated random train/test splits of one dataset: train, detect, evaluate; mean ± sd.
    Experiment(commands::experiment::ExperimentArgs),
    /// Follow the target fruit through approach sequences (`synth --approach`), or the fruit at
    /// a pixel through your own frames (`--start`), with the colour-contour tracker; reports
    /// success rate and time per frame.
    Track(commands::track::TrackArgs),
    /// Render a small synthetic scene set, run every detector with a built-in model on it,
    /// evaluate, and draw overlays.
    Demo(commands::demo::DemoArgs),
    /// Plan the picks of seed 004's two-arm robot: which arm picks which fruit, in which order.
    Plan(commands::plan::PlanArgs),
    /// Seed 004's arm: train and evaluate the network mapping a target's two image positions
    /// to encoder readings (Eq. 19), beside Eq. 18 + exact kinematics.
    Arm(commands::arm::ArmArgs),
    /// Fruit in 3D from the two colour shots of seed 004's rotating camera (`synth --stereo`):
    /// color-contour circles in both, matched by the seed's relaxation, located by Eq. 18 or
    /// triangulation; writes one detection file per frame.
    Stereo(commands::stereo::StereoArgs),
    /// Run a detector as a ROS 2 node: colour, aligned depth and camera info in,
    /// vision_msgs/Detection3DArray and RViz markers out (pure Rust DDS, no ROS installation).
    Ros(commands::ros::RosArgs),
}

fn main() -> ExitCode {
    pomona_cli::exit_status::exit_quietly_when_stdout_closes();
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Info(args) => commands::info::run(args),
        Command::Cloud(args) => commands::cloud::run(args),
        Command::Convert(args) => commands::convert::run(args),
        Command::Eval(args) => commands::eval::run(args),
        Command::Synth(args) => commands::synth::run(args),
        Command::Plan(args) => commands::plan::run(args),
        Command::Arm(args) => commands::arm::run(args),
        Command::Stereo(args) => commands::stereo::run(args),
        Command::Train(args) => commands::train::run(args),
        Command::Calibrate(args) => commands::calibrate::run(args),
        Command::Detect(args) => commands::detect::run(args),
        Command::Extract(args) => commands::extract::run(args),
        Command::Experiment(args) => commands::experiment::run(args),
        Command::Demo(args) => commands::demo::run(args),
        Command::Track(args) => commands::track::run(args).map(|_| ()),
        Command::Ros(args) => commands::ros::run(args),
    };
    if let Err(err) = &result {
        eprintln!("error: {}", pomona_cli::error_line::error_line(err));
    }
    pomona_cli::exit_status::exit_code(&result)
}
