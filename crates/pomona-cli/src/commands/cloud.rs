//! `pomona cloud`: back-project one dataset frame to a coloured point cloud for viewing in
//! CloudCompare or MeshLab, or for feeding PCL tools.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use pomona_core::nalgebra::Point3;
use pomona_core::PointCloud;
use pomona_io::Dataset;

/// Arguments of `pomona cloud`.
#[derive(Debug, clap::Args)]
pub struct CloudArgs {
    /// Dataset folder.
    pub dataset: PathBuf,
    /// Frame stem (file name without extension); defaults to the first frame.
    #[arg(long)]
    pub frame: Option<String>,
    /// Output file; the extension (.ply or .pcd) chooses the format.
    #[arg(long)]
    pub out: PathBuf,
    /// Drop pixels without depth even for PCD (PCD keeps the organised H×W grid by default,
    /// PLY is always written without invalid points).
    #[arg(long)]
    pub dense: bool,
    /// Drop points farther than this (metres along the optical axis), e.g. a far background.
    #[arg(long, value_name = "M")]
    pub max_depth_m: Option<f32>,
}

/// Runs `pomona cloud`.
///
/// # Errors
/// Dataset errors naming the file, an unknown frame, or a failed write.
pub fn run(args: &CloudArgs) -> Result<()> {
    let dataset = Dataset::open(&args.dataset).context("cannot open dataset")?;
    if !dataset.has_depth() {
        bail!(
            "{}: a colour-only dataset (no depth/ folder) has no point cloud",
            args.dataset.display()
        );
    }
    let frame = match &args.frame {
        Some(f) if dataset.frames().contains(f) => f.clone(),
        Some(f) => bail!(
            "{}: no frame `{f}` (frames: {})",
            args.dataset.display(),
            preview(dataset.frames())
        ),
        None => match dataset.frames().first() {
            Some(f) => f.clone(),
            None => bail!("{}: dataset has no frames", args.dataset.display()),
        },
    };
    let mut cloud = dataset.load_frame(&frame)?.to_cloud();
    if let Some(max) = args.max_depth_m {
        cloud = clip_depth(cloud, max);
    }
    let is_ply = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if args.dense || is_ply {
        cloud = cloud.without_invalid();
    }
    pomona_io::write_cloud(&args.out, &cloud, None)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    eprintln!(
        "wrote {} ({} points, {} valid) from frame {frame}",
        args.out.display(),
        cloud.len(),
        cloud.valid_count()
    );
    Ok(())
}

/// Marks points beyond `max_depth_m` invalid, keeping the grid.
fn clip_depth(cloud: PointCloud, max_depth_m: f32) -> PointCloud {
    let nan = Point3::new(f32::NAN, f32::NAN, f32::NAN);
    cloud.map_points(|p| if p.z > max_depth_m { nan } else { *p })
}

fn preview(frames: &[String]) -> String {
    let mut s = frames
        .iter()
        .take(5)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if frames.len() > 5 {
        s.push_str(&format!(", … {} in all", frames.len()));
    }
    s
}
