//! Pomona's side of the building-block comparison with Open3D (`scripts/open3d_blocks.sh`): times
//! each block on one depth frame of a dataset and prints the medians as JSON.
//!
//! ```sh
//! cargo run --release -p pomona-consensus --example open3d_blocks -- \
//!     --data DIR --frame NAME --repeats 15
//! ```
//!
//! Blocks (the same inputs and parameters as `scripts/open3d_blocks.py` gives Open3D):
//! * `back_projection`: 16-bit depth → metres → cloud (`DepthImage::from_u16`,
//!   `RgbdFrame::to_cloud`); the cloud's valid points are the input of every later block;
//! * `kd_tree_build`: `KdTree::build`;
//! * `knn_normals`: `KnnNormals` with `--k` neighbours (tree build included, as in Open3D's
//!   `estimate_normals`), oriented towards the camera;
//! * `ransac_plane`: `Ransac` with `PlaneEstimator`, `--plane-iterations` hypotheses (no early
//!   stop), inlier threshold `--plane-threshold-m`, least-squares refit of the winner;
//! * `voxel_downsample`: `voxel_downsample` with side `--voxel-m`.
//!
//! Everything runs inside a one-thread rayon pool (`threads` in the output); each block is timed
//! `--repeats` times after one warm-up run, and the median is reported with the output size (points,
//! normals, inliers, voxels) so both sides can be checked to do the same work.
#![allow(clippy::unwrap_used, clippy::expect_used)]

type BoxError = Box<dyn std::error::Error + Send + Sync>;
use std::path::PathBuf;
use std::time::Instant;

use clap::Parser;
use pomona_consensus::nalgebra::Point3;
use pomona_consensus::{
    Consensus, KdTree, KnnNormalParams, PlaneEstimator, RansacParams, UniformSampler,
};
use pomona_core::{voxel_downsample, DepthImage, RgbdFrame};
use pomona_io::Dataset;

#[derive(Parser, Debug)]
struct Args {
    /// Dataset folder (camera.json, depth/).
    #[arg(long)]
    data: PathBuf,
    /// Frame name (depth/<frame>.png).
    #[arg(long)]
    frame: String,
    /// Timed runs per block (median reported).
    #[arg(long, default_value_t = 15)]
    repeats: usize,
    /// Neighbours per normal.
    #[arg(long, default_value_t = 30)]
    k: usize,
    /// RANSAC plane hypotheses.
    #[arg(long, default_value_t = 1000)]
    plane_iterations: usize,
    /// RANSAC plane inlier distance, metres.
    #[arg(long, default_value_t = 0.01)]
    plane_threshold_m: f64,
    /// Voxel side, metres.
    #[arg(long, default_value_t = 0.01)]
    voxel_m: f64,
    /// RANSAC sampler seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Median wall time in milliseconds of `repeats` runs of `f` after one warm-up run, and the
/// warm-up's result.
fn time_ms<T>(repeats: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let first = f();
    let mut ms: Vec<f64> = (0..repeats.max(1))
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(f());
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    ms.sort_by(f64::total_cmp);
    (ms[ms.len() / 2], first)
}

fn main() -> Result<(), BoxError> {
    let args = Args::parse();
    let dataset = Dataset::open(&args.data)?;
    let camera = *dataset.camera();
    let unit_m = dataset.depth_unit_m();
    let raw = dataset.load_depth(&args.frame)?.to_u16(unit_m)?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let knn = KnnNormalParams {
        k: args.k,
        ..Default::default()
    }
    .check()?;
    let ransac = RansacParams {
        inlier_threshold_m: args.plane_threshold_m,
        iterations: args.plane_iterations,
        early_stop_confidence: None,
        min_inlier_fraction: None,
        refine_threshold_m: Some(args.plane_threshold_m),
    }
    .check()?;

    let report = pool.install(|| -> Result<serde_json::Value, BoxError> {
        let (w, h) = (camera.width, camera.height);
        let project = || -> Result<_, BoxError> {
            let depth = DepthImage::from_u16(w, h, &raw, unit_m)?;
            Ok(RgbdFrame::new(camera, depth, None)?.to_cloud())
        };
        let (back_projection, cloud) = time_ms(args.repeats, project);
        let cloud = cloud?.without_invalid();
        let points: Vec<Point3<f64>> = cloud.points().iter().map(|p| p.cast::<f64>()).collect();
        let (kd_tree_build, tree) = time_ms(args.repeats, || KdTree::build(&points));
        let (knn_normals, normals) = time_ms(args.repeats, || knn.estimate(&points));
        let (ransac_plane, plane) = time_ms(args.repeats, || {
            ransac.fit(
                &PlaneEstimator,
                &points,
                &mut UniformSampler::new(args.seed),
            )
        });
        let plane_inliers = plane?.map_or(0, |f| f.inliers.len());
        let (voxel, down) = time_ms(args.repeats, || voxel_downsample(&cloud, args.voxel_m));
        Ok(serde_json::json!({
            "side": "pomona",
            "threads": "rayon pool of 1 thread (ThreadPoolBuilder::num_threads(1))",
            "points": points.len(),
            "repeats": args.repeats,
            "ms": {
                "back_projection": back_projection,
                "kd_tree_build": kd_tree_build,
                "knn_normals": knn_normals,
                "ransac_plane": ransac_plane,
                "voxel_downsample": voxel,
            },
            "outputs": {
                "back_projection": points.len(),
                "kd_tree_build": tree.len(),
                "knn_normals": normals.iter().filter(|n| n.is_some()).count(),
                "ransac_plane": plane_inliers,
                "voxel_downsample": down?.len(),
            },
        }))
    })?;
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
