//! Whole datasets on disk: render frames in parallel and write them in the dataset layout.
//!
//! ```text
//! <out>/camera.json  color/  depth/  truth/  mask/      primary view
//! <out>/synth.json                                      the parameters that made it
//! <out>/rig.json  <out>/stereo/{camera.json,color,…}    only with a stereo rig
//! <out>/arm-b/{camera.json,color,…,stereo/}            only with two arms (arm B's two shots)
//! ```
//!
//! Frame `i` is named `{i:06}` and drawn from its own random stream (see [`crate::frame_rng`]),
//! so the output is byte-identical for the same spec whatever the number of threads.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use pomona_io::{write_json, DatasetWriter};
use rayon::prelude::*;
use serde::Serialize;

use pomona_arm::TwoArmCell;

use crate::{render, render_view, SceneSpec, StereoRig, SynthError, TwoArmViews, ARM_B_DATASET};

/// Depth unit of generated datasets: 0.1 mm, so noise-free depth keeps its precision (the
/// largest storable depth is 6.55 m, well beyond the scene).
pub const DEPTH_UNIT_M: f64 = 0.0001;

/// Everything that determines a generated dataset.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DatasetSpec {
    /// What each scene looks like.
    pub scene: SceneSpec,
    /// Number of frames.
    pub frames: u32,
    /// Dataset seed.
    pub seed: u64,
    /// Render a second, rotated view of every frame into `<out>/stereo/`.
    pub stereo: Option<StereoRig>,
    /// Seed 004's second arm: render arm B's two shots into `<out>/arm-b/` and record in every
    /// fruit's truth which arm reaches it ([`TwoArmViews`]). Needs `stereo`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arms: Option<TwoArmCell>,
    /// Depth unit written to `camera.json`.
    pub depth_unit_m: f64,
    /// Worker threads (`None`: rayon's default). Never changes the output.
    #[serde(skip)]
    pub threads: Option<usize>,
}

impl DatasetSpec {
    /// A spec with the default scene, no stereo and [`DEPTH_UNIT_M`].
    pub fn new(scene: SceneSpec, frames: u32, seed: u64) -> Self {
        Self {
            scene,
            frames,
            seed,
            stereo: None,
            arms: None,
            depth_unit_m: DEPTH_UNIT_M,
            threads: None,
        }
    }

    /// The file stem of frame `index`.
    pub fn frame_stem(index: u32) -> String {
        format!("{index:06}")
    }
}

/// What [`generate_dataset`] wrote.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DatasetSummary {
    /// Frames written (per view).
    pub frames: u32,
    /// Fruit listed in the primary view's truth, summed over frames.
    pub fruits: usize,
}

/// Renders `spec.frames` frames and writes them under `out` (created if missing). Existing files
/// of the same names are replaced; the caller decides whether writing into `out` is allowed.
/// `progress` is called with the number of finished frames after each one (from worker threads).
///
/// # Errors
/// [`SynthError::InvalidParameter`] for an invalid spec (nothing is written);
/// [`SynthError::Dataset`] naming the file that could not be written;
/// [`SynthError::ThreadPool`] if the requested threads cannot start.
pub fn generate_dataset(
    spec: &DatasetSpec,
    out: &Path,
    progress: &(dyn Fn(u32) + Sync),
) -> Result<DatasetSummary, SynthError> {
    spec.scene.validate()?;
    if let Some(rig) = &spec.stereo {
        rig.validate()?;
    }
    if spec.threads == Some(0) {
        return Err(SynthError::InvalidParameter {
            name: "threads",
            reason: "must be at least 1".to_string(),
        });
    }
    let camera = spec.scene.camera;
    let primary = DatasetWriter::create(out, &camera, spec.depth_unit_m)?;
    write_json(&out.join("synth.json"), &SynthRecord::new(spec))?;
    let stereo = match &spec.stereo {
        Some(rig) => {
            write_json(&out.join("rig.json"), &rig.to_file())?;
            Some((
                rig.stereo_from_camera(),
                DatasetWriter::create(out.join("stereo"), &camera, spec.depth_unit_m)?,
            ))
        }
        None => None,
    };
    let arm_b = match (&spec.arms, &spec.stereo) {
        (None, _) => None,
        (Some(_), None) => {
            return Err(SynthError::InvalidParameter {
                name: "arms",
                reason: "a second arm needs the stereo rig".to_string(),
            })
        }
        (Some(cell), Some(rig)) => {
            let views = TwoArmViews::new(rig, &camera, *cell)?;
            let root = out.join(ARM_B_DATASET);
            let writers = [
                DatasetWriter::create(&root, &camera, spec.depth_unit_m)?,
                DatasetWriter::create(root.join("stereo"), &camera, spec.depth_unit_m)?,
            ];
            Some((views, writers))
        }
    };
    let done = AtomicUsize::new(0);
    let one_frame = |i: u32| -> Result<usize, SynthError> {
        let stem = DatasetSpec::frame_stem(i);
        let scene = spec.scene.sample_frame(spec.seed, i as u64)?;
        let mut view = render(&scene, &camera)?;
        let annotate = |view: &mut crate::RenderedFrame, pose: &nalgebra::Isometry3<f64>| {
            if let Some((arms, _)) = &arm_b {
                arms.annotate(&mut view.truth, pose);
            }
        };
        annotate(&mut view, &nalgebra::Isometry3::identity());
        write_view(&primary, &stem, &view)?;
        if let Some((pose, writer)) = &stereo {
            let mut second = render_view(&scene, &camera, pose, 1)?;
            annotate(&mut second, pose);
            write_view(writer, &stem, &second)?;
        }
        if let Some((arms, writers)) = &arm_b {
            let poses = [arms.arm_b_from_scene(), arms.arm_b_stereo_from_scene()];
            for (k, (pose, writer)) in poses.iter().zip(writers).enumerate() {
                let mut b_view = render_view(&scene, &camera, pose, 2 + k as u64)?;
                annotate(&mut b_view, pose);
                write_view(writer, &stem, &b_view)?;
            }
        }
        let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
        progress(finished as u32);
        Ok(view.truth.fruits.len())
    };
    let run = || -> Result<Vec<usize>, SynthError> {
        (0..spec.frames).into_par_iter().map(one_frame).collect()
    };
    let counts = in_thread_pool(spec.threads, run)?;
    Ok(DatasetSummary {
        frames: spec.frames,
        fruits: counts.iter().sum(),
    })
}

/// Runs `run` on a pool of `threads` workers (`None`: rayon's global pool).
///
/// # Errors
/// [`SynthError::ThreadPool`] if the pool cannot start, else `run`'s error.
pub(crate) fn in_thread_pool<T: Send>(
    threads: Option<usize>,
    run: impl FnOnce() -> Result<T, SynthError> + Send,
) -> Result<T, SynthError> {
    match threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| SynthError::ThreadPool {
                threads: n,
                reason: e.to_string(),
            })?
            .install(run),
        None => run(),
    }
}

fn write_view(
    writer: &DatasetWriter,
    stem: &str,
    view: &crate::RenderedFrame,
) -> Result<(), SynthError> {
    writer.write_frame(stem, &view.frame, Some(&view.truth))?;
    writer.write_mask(stem, &view.mask)?;
    Ok(())
}

/// Contents of `synth.json`: how to regenerate the dataset.
#[derive(Debug, Serialize)]
struct SynthRecord<'a> {
    generator: &'static str,
    version: &'static str,
    #[serde(flatten)]
    spec: &'a DatasetSpec,
}

impl<'a> SynthRecord<'a> {
    fn new(spec: &'a DatasetSpec) -> Self {
        Self {
            generator: "pomona-synth",
            version: env!("CARGO_PKG_VERSION"),
            spec,
        }
    }
}
