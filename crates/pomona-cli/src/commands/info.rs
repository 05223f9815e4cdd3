//! `pomona info`: what is in a dataset, frame by frame, so a user can check a recording before
//! spending an hour on it (is depth there? registered? annotated?).

use std::path::PathBuf;

use anyhow::{Context, Result};
use pomona_io::Dataset;
use rayon::prelude::*;

use crate::progress::progress_bar;
use serde::Serialize;

/// Arguments of `pomona info`.
#[derive(Debug, clap::Args)]
pub struct InfoArgs {
    /// Dataset folder (camera.json, depth/, optional color/ and truth/).
    pub dataset: PathBuf,
    /// Print a JSON report instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// The report, as printed with `--json`.
#[derive(Debug, Serialize)]
struct DatasetInfo {
    dataset: PathBuf,
    width: u32,
    height: u32,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    depth_unit_m: f64,
    has_color: bool,
    has_depth: bool,
    frames: Vec<FrameInfo>,
}

#[derive(Debug, Serialize)]
struct FrameInfo {
    frame: String,
    valid_depth_fraction: f64,
    depth_min_m: Option<f32>,
    depth_max_m: Option<f32>,
    has_truth: bool,
    fruits: usize,
    complete: Option<bool>,
    has_mask: bool,
}

fn frame_info(dataset: &Dataset, frame: &str) -> Result<FrameInfo> {
    // Decoding colour too validates it (size, integrity), which is part of what info checks.
    let rgbd = dataset.load_frame(frame)?;
    let truth = dataset.load_truth(frame)?;
    let range = rgbd.depth().range_m();
    Ok(FrameInfo {
        frame: frame.to_owned(),
        valid_depth_fraction: rgbd.depth().valid_fraction(),
        depth_min_m: range.map(|r| r.0),
        depth_max_m: range.map(|r| r.1),
        has_truth: truth.is_some(),
        fruits: truth.as_ref().map_or(0, |t| t.fruits.len()),
        complete: truth.as_ref().map(|t| t.complete),
        has_mask: dataset.load_mask(frame)?.is_some(),
    })
}

fn gather(args: &InfoArgs) -> Result<DatasetInfo> {
    let dataset = Dataset::open(&args.dataset).context("cannot open dataset")?;
    let cam = *dataset.camera();
    let progress = progress_bar(dataset.frames().len(), "reading frames");
    let frames = dataset
        .frames()
        .par_iter()
        .map(|frame| {
            let info = frame_info(&dataset, frame);
            progress.inc(1);
            info
        })
        .collect::<Result<Vec<_>>>()?;
    progress.finish_and_clear();
    Ok(DatasetInfo {
        dataset: args.dataset.clone(),
        width: cam.width,
        height: cam.height,
        fx: cam.fx,
        fy: cam.fy,
        cx: cam.cx,
        cy: cam.cy,
        depth_unit_m: dataset.depth_unit_m(),
        has_color: dataset.has_color(),
        has_depth: dataset.has_depth(),
        frames,
    })
}

fn print_table(info: &DatasetInfo) {
    println!("dataset   {}", info.dataset.display());
    println!(
        "camera    {}x{}  fx {:.1}  fy {:.1}  cx {:.1}  cy {:.1}  depth unit {} m",
        info.width, info.height, info.fx, info.fy, info.cx, info.cy, info.depth_unit_m
    );
    println!(
        "frames    {}  colour: {}  depth: {}",
        info.frames.len(),
        if info.has_color {
            "yes"
        } else {
            "no (depth only)"
        },
        if info.has_depth {
            "yes"
        } else {
            "no (colour only)"
        }
    );
    println!();
    println!(
        "{:<16} {:>11} {:>17} {:>7} {:>9} {:>5}",
        "frame", "valid depth", "depth range (m)", "fruits", "complete", "mask"
    );
    for f in &info.frames {
        let range = match (f.depth_min_m, f.depth_max_m) {
            (Some(lo), Some(hi)) => format!("{lo:.3}-{hi:.3}"),
            _ => "-".to_owned(),
        };
        let (fruits, complete) = match f.complete {
            Some(c) => (f.fruits.to_string(), if c { "yes" } else { "no" }),
            None => ("-".to_owned(), "-"),
        };
        println!(
            "{:<16} {:>10.1}% {:>17} {:>7} {:>9} {:>5}",
            f.frame,
            100.0 * f.valid_depth_fraction,
            range,
            fruits,
            complete,
            if f.has_mask { "yes" } else { "no" }
        );
    }
}

/// Runs `pomona info`.
///
/// # Errors
/// Any dataset error, naming the file at fault.
pub fn run(args: &InfoArgs) -> Result<()> {
    let info = gather(args)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        print_table(&info);
    }
    Ok(())
}
