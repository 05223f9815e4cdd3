//! `pomona convert`: point cloud from one format to another (PCD ↔ PLY, or re-encode a PCD).

use std::path::PathBuf;

use anyhow::{Context, Result};

/// Arguments of `pomona convert`.
#[derive(Debug, clap::Args)]
pub struct ConvertArgs {
    /// Input cloud (.pcd or .ply).
    pub input: PathBuf,
    /// Output cloud; the extension (.pcd or .ply) chooses the format.
    pub output: PathBuf,
}

/// Runs `pomona convert`.
///
/// # Errors
/// A read error naming the input file or a write error naming the output.
pub fn run(args: &ConvertArgs) -> Result<()> {
    let cloud = pomona_io::read_cloud(&args.input)?;
    pomona_io::write_cloud(&args.output, &cloud, None)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    eprintln!(
        "wrote {} ({} points, {} valid)",
        args.output.display(),
        cloud.len(),
        cloud.valid_count()
    );
    Ok(())
}
