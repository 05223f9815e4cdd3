//! The recording of a detection run (`pomona detect --rrd OUT.rrd`): one rerun `.rrd` file a
//! user opens in the rerun viewer (`rerun OUT.rrd`) to scrub through what a detector saw and found,
//! frame by frame, in 2D and 3D at once.
//!
//! What it holds, per frame on the sequence timeline `frame` (the frame's index in the dataset,
//! so a `--resume`d run keeps the same indices; only the frames a run processes are recorded):
//! - `world/camera/rgb`: the colour image (datasets with colour);
//! - `world/camera/depth`: the depth image (16-bit sensor units, `meter` = 1 / depth unit);
//! - `world/points`: the back-projected point cloud in the camera frame, coloured where the frame
//!   has colour, every `k`-th valid pixel so that at most [`MAX_POINTS`] remain;
//! - `world/truth`: the truth fruit with a 3D centre, green spheres of their diameter labelled
//!   `id kind ⌀ mm` (frames with a truth file);
//! - `world/detections`: the detections the run kept (those written to the detection files), red
//!   spheres of their diameter labelled with confidence, score and diameter;
//! - `world/detections_below_threshold`: the detections the run's threshold (confidence, or
//!   score ≥ 0 for a model without calibration) dropped, drawn faint (translucent pink), so a
//!   user sees what the threshold removed; a run that keeps every detection leaves it empty;
//! - `frame`: a text line naming the frame (its stem) and what was found.
//!
//! Logged once as static: `world` is the camera frame (x right, y down, z forward: rerun's
//! `RDF`), `world/camera` the dataset's pinhole camera (so the images and the 3D view line up),
//! and `run`, a note on the pipeline, model, threshold and colours. A detection or truth fruit
//! without a diameter gets a sphere of [`NO_SIZE_DIAMETER_M`] and `⌀ ?` in its label.
//!
//! Frames are recorded from the worker threads as they finish (the recording stream is
//! thread-safe; the `frame` time is set per thread), so the file's byte order depends on
//! scheduling but its content does not; the automatic wall-clock `log_time` timeline is turned
//! off for the same reason. [`RunRecording::finish`] flushes and closes the file before the
//! command returns.
//!
//! The `rerun` crate is large (about 340 extra crates), so all this sits behind the `rerun`
//! cargo feature of `pomona-cli` (off by default, on in the release binary the README installs);
//! a binary built without it refuses `--rrd` with a message saying so.

use std::path::Path;

use anyhow::Result;
use pomona_io::Dataset;

/// At most this many points of a frame's cloud are recorded (every `k`-th valid pixel).
pub const MAX_POINTS: usize = 300_000;

/// Diameter, metres, of the sphere drawn for a detection or truth fruit without one.
pub const NO_SIZE_DIAMETER_M: f64 = 0.02;

/// What the run that is recorded is: shown in the recording's `run` note.
#[derive(Debug, Clone, Copy)]
pub struct RunDescription<'a> {
    /// The pipeline's name.
    pub pipeline: &'a str,
    /// The model's identity.
    pub model_id: &'a str,
    /// Which detections the run keeps.
    pub keep: pomona::KeepRule,
}

#[cfg(feature = "rerun")]
pub use with_rerun::RunRecording;

#[cfg(not(feature = "rerun"))]
pub use without_rerun::RunRecording;

/// Opens the recording `path` of a run over `dataset`, or nothing when `path` is `None`.
///
/// # Errors
/// See [`RunRecording::create`].
pub fn open(
    path: Option<&Path>,
    dataset: &Dataset,
    run: &RunDescription<'_>,
) -> Result<Option<RunRecording>> {
    path.map(|p| RunRecording::create(p, dataset, run))
        .transpose()
}

#[cfg(feature = "rerun")]
mod with_rerun {
    use std::collections::HashMap;
    use std::path::{Path, PathBuf};

    use anyhow::{Context, Result};
    use pomona_core::nalgebra::Point3;
    use pomona_core::{Detection, FrameTruth, PinholeCamera, RgbdFrame};
    use pomona_io::Dataset;
    use rerun::{
        Color, DepthImage, Ellipsoids3D, FillMode, Image, Pinhole, Points3D, RecordingStream,
        RecordingStreamBuilder, Rgba32, TextDocument, ViewCoordinates,
    };

    use super::{RunDescription, MAX_POINTS, NO_SIZE_DIAMETER_M};

    const TIMELINE: &str = "frame";
    const TRUTH: Color = Color(Rgba32::from_rgb(40, 230, 60));
    const DETECTION: Color = Color(Rgba32::from_rgb(240, 30, 30));
    const BELOW_THRESHOLD: Color = Color(Rgba32::from_unmultiplied_rgba(240, 120, 120, 70));

    /// The label of a detection: calibrated confidence (when the model has one), score, diameter.
    fn detection_label(d: &Detection) -> String {
        let confidence = d
            .confidence
            .map(|c| format!("conf {c:.2} · "))
            .unwrap_or_default();
        format!(
            "{confidence}score {:.2} · ⌀ {}",
            d.score,
            diameter_words(d.diameter_m)
        )
    }

    /// A diameter in millimetres, `?` when unknown.
    fn diameter_words(diameter_m: Option<f64>) -> String {
        diameter_m.map_or_else(|| "?".to_owned(), |d| format!("{:.0} mm", 1e3 * d))
    }

    /// An open `.rrd` recording of a detection run; frames may be recorded from many threads.
    pub struct RunRecording {
        stream: RecordingStream,
        path: PathBuf,
        frame_index: HashMap<String, i64>,
        depth_unit_m: f64,
    }

    impl std::fmt::Debug for RunRecording {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.debug_struct("RunRecording")
                .field("path", &self.path)
                .finish_non_exhaustive()
        }
    }

    impl RunRecording {
        /// Creates (or truncates) the `.rrd` file `path` and logs the static part: the
        /// coordinate frame, the dataset's camera and a note describing `run`.
        ///
        /// # Errors
        /// The file cannot be created, or the static part cannot be logged; the message names
        /// the file.
        pub fn create(path: &Path, dataset: &Dataset, run: &RunDescription<'_>) -> Result<Self> {
            let stream = RecordingStreamBuilder::new("pomona")
                .recording_name(format!(
                    "pomona detect: {} on {}",
                    run.pipeline,
                    dataset.root().display()
                ))
                .enabled(true)
                .save(path)
                .with_context(|| format!("cannot create the recording {}", path.display()))?;
            stream.set_log_time_enabled(false);
            let recording = Self {
                stream,
                path: path.to_owned(),
                frame_index: dataset
                    .frames()
                    .iter()
                    .enumerate()
                    .map(|(i, f)| (f.clone(), i as i64))
                    .collect(),
                depth_unit_m: dataset.depth_unit_m(),
            };
            recording
                .log_static(dataset.camera(), run)
                .with_context(|| format!("cannot write the recording {}", path.display()))?;
            Ok(recording)
        }

        fn log_static(&self, camera: &PinholeCamera, run: &RunDescription<'_>) -> Result<()> {
            let s = &self.stream;
            s.log_static("world", &ViewCoordinates::RDF())?;
            let (w, h) = (camera.width as f32, camera.height as f32);
            s.log_static(
                "world/camera",
                &Pinhole::from_focal_length_and_resolution(
                    [camera.fx as f32, camera.fy as f32],
                    [w, h],
                )
                .with_principal_point([camera.cx as f32, camera.cy as f32])
                .with_camera_xyz(rerun::components::ViewCoordinates::RDF),
            )?;
            let threshold = match run.keep {
                pomona::KeepRule::All => "no threshold: every detection kept (red)".to_owned(),
                keep => format!(
                    "kept: {} (red, `world/detections`); the rest drawn faint in \
                     `world/detections_below_threshold`",
                    keep.describe()
                ),
            };
            s.log_static(
                "run",
                &TextDocument::from_markdown(format!(
                    "# pomona detect\n\npipeline `{}`, model `{}`\n\n{threshold}\n\nTruth fruit: \
                     green. Spheres have the estimated diameter ({:.0} mm when there is none).",
                    run.pipeline,
                    run.model_id,
                    1e3 * NO_SIZE_DIAMETER_M
                )),
            )?;
            Ok(())
        }

        /// Records frame `stem` of `dataset` (the one the recording was created for): its images,
        /// cloud and truth, the `detections` that are `kept` and, faint, the others.
        ///
        /// # Errors
        /// The dataset's errors reading the frame or its truth (naming the file), a frame the
        /// dataset does not list, or data the recording refuses (naming the recording).
        pub fn record_frame(
            &self,
            dataset: &Dataset,
            stem: &str,
            detections: &[Detection],
            kept: &dyn Fn(&Detection) -> bool,
        ) -> Result<()> {
            let index = *self
                .frame_index
                .get(stem)
                .with_context(|| format!("frame {stem} is not in the dataset being recorded"))?;
            let frame = dataset.load_frame(stem)?;
            let truth = dataset.load_truth(stem)?;
            let (kept, dropped): (Vec<&Detection>, Vec<&Detection>) =
                detections.iter().partition(|d| kept(d));
            let entities =
                FrameEntities::new(&frame, self.depth_unit_m, truth.as_ref(), &kept, &dropped)?;
            // Nothing between setting this thread's time and logging may yield to rayon (which
            // could start another frame on this thread), so everything is built beforehand.
            self.stream.set_time_sequence(TIMELINE, index);
            let logged = entities.log(&self.stream, stem, index);
            self.stream.reset_time();
            logged.with_context(|| format!("cannot write the recording {}", self.path.display()))
        }

        /// Flushes every frame to the file and closes it (writing the footer).
        ///
        /// # Errors
        /// The file could not be written; the message names it.
        pub fn finish(self) -> Result<()> {
            self.stream
                .flush_blocking()
                .with_context(|| format!("cannot write the recording {}", self.path.display()))?;
            self.stream.finalize_deferred_sinks();
            let written = std::fs::metadata(&self.path).map(|m| m.len()).unwrap_or(0);
            anyhow::ensure!(
                written > 0,
                "the recording {} was not written (it is empty or gone)",
                self.path.display()
            );
            Ok(())
        }
    }

    /// One frame's archetypes, built before the frame's time is set.
    struct FrameEntities {
        color: Option<Image>,
        depth: DepthImage,
        points: Points3D,
        truth: Option<Ellipsoids3D>,
        detections: Ellipsoids3D,
        below_threshold: Ellipsoids3D,
        summary: String,
    }

    impl FrameEntities {
        fn new(
            frame: &RgbdFrame,
            depth_unit_m: f64,
            truth: Option<&FrameTruth>,
            kept: &[&Detection],
            dropped: &[&Detection],
        ) -> Result<Self> {
            let (w, h) = (frame.camera().width, frame.camera().height);
            let color = frame
                .color()
                .map(|c| Image::from_rgb24(c.as_rgb().to_vec(), [w, h]));
            let raw = frame.depth().to_u16(depth_unit_m)?;
            let depth = DepthImage::from_gray16(
                raw.iter()
                    .flat_map(|r| r.to_ne_bytes())
                    .collect::<Vec<u8>>(),
                [w, h],
            )
            .with_meter((1.0 / depth_unit_m) as f32);
            let truth_spheres = truth.map(truth_spheres);
            let summary = format!(
                "{} detection(s) kept, {} below the threshold, {}",
                kept.len(),
                dropped.len(),
                truth.map_or_else(
                    || "no truth".to_owned(),
                    |t| format!("{} truth fruit", t.fruits.len())
                )
            );
            Ok(Self {
                color,
                depth,
                points: cloud_points(frame),
                truth: truth_spheres,
                detections: detection_spheres(kept, DETECTION, FillMode::MajorWireframe),
                below_threshold: detection_spheres(dropped, BELOW_THRESHOLD, FillMode::Solid),
                summary,
            })
        }

        fn log(&self, s: &RecordingStream, stem: &str, index: i64) -> Result<()> {
            if let Some(color) = &self.color {
                s.log("world/camera/rgb", color)?;
            }
            s.log("world/camera/depth", &self.depth)?;
            s.log("world/points", &self.points)?;
            if let Some(truth) = &self.truth {
                s.log("world/truth", truth)?;
            }
            s.log("world/detections", &self.detections)?;
            s.log("world/detections_below_threshold", &self.below_threshold)?;
            s.log(
                "frame",
                &TextDocument::new(format!("frame {stem} (#{index}): {}", self.summary)),
            )?;
            Ok(())
        }
    }

    /// Every `k`-th valid point of the frame's cloud (at most [`MAX_POINTS`]), with its colour.
    fn cloud_points(frame: &RgbdFrame) -> Points3D {
        let cloud = frame.to_cloud();
        let valid: Vec<usize> = (0..cloud.len()).filter(|&i| cloud.is_valid(i)).collect();
        let stride = valid.len().div_ceil(MAX_POINTS).max(1);
        let chosen: Vec<usize> = valid.into_iter().step_by(stride).collect();
        let points = Points3D::new(chosen.iter().map(|&i| {
            let p = cloud.points()[i];
            [p.x, p.y, p.z]
        }));
        match cloud.colors() {
            Some(colors) => points.with_colors(chosen.iter().map(|&i| {
                let [r, g, b] = colors[i];
                Color::from_rgb(r, g, b)
            })),
            None => points,
        }
    }

    /// A sphere of `diameter_m` (or [`NO_SIZE_DIAMETER_M`]) as its centre and half size.
    fn sphere(center_m: &Point3<f64>, diameter_m: Option<f64>) -> ([f32; 3], f32) {
        let radius = 0.5
            * diameter_m
                .filter(|d| *d > 0.0)
                .unwrap_or(NO_SIZE_DIAMETER_M);
        (
            [center_m.x as f32, center_m.y as f32, center_m.z as f32],
            radius as f32,
        )
    }

    /// The truth fruit that have a 3D centre, as labelled green spheres.
    fn truth_spheres(truth: &FrameTruth) -> Ellipsoids3D {
        let placed: Vec<_> = truth
            .fruits
            .iter()
            .filter_map(|f| f.center_m.map(|c| (f, sphere(&c, f.diameter_m))))
            .collect();
        Ellipsoids3D::from_centers_and_radii(
            placed.iter().map(|(_, (c, _))| *c),
            placed.iter().map(|(_, (_, r))| *r),
        )
        .with_colors([TRUTH])
        .with_fill_mode(FillMode::MajorWireframe)
        .with_labels(
            placed
                .iter()
                .map(|(f, _)| format!("{} {} ⌀ {}", f.id, f.kind, diameter_words(f.diameter_m))),
        )
    }

    /// Detections as spheres of `color`, labelled with confidence, score and diameter.
    fn detection_spheres(detections: &[&Detection], color: Color, fill: FillMode) -> Ellipsoids3D {
        let spheres: Vec<_> = detections
            .iter()
            .map(|d| sphere(&d.center_m, d.diameter_m))
            .collect();
        Ellipsoids3D::from_centers_and_radii(
            spheres.iter().map(|(c, _)| *c),
            spheres.iter().map(|(_, r)| *r),
        )
        .with_colors([color])
        .with_fill_mode(fill)
        .with_labels(detections.iter().map(|d| detection_label(d)))
    }
}

#[cfg(not(feature = "rerun"))]
mod without_rerun {
    use std::path::Path;

    use anyhow::{bail, Result};
    use pomona_core::Detection;
    use pomona_io::Dataset;

    use super::RunDescription;

    /// A recording cannot exist in a binary built without the `rerun` feature: this type has no
    /// values, and [`RunRecording::create`] always fails saying why.
    #[derive(Debug)]
    pub enum RunRecording {}

    impl RunRecording {
        /// Always fails: this binary was built without the `rerun` feature.
        ///
        /// # Errors
        /// Always, naming `path` and how to build a binary that records.
        pub fn create(path: &Path, _dataset: &Dataset, _run: &RunDescription<'_>) -> Result<Self> {
            bail!(
                "cannot write the recording {}: this pomona was built without the `rerun` \
                 feature (build it with `cargo build --release -p pomona-cli --features rerun` \
                 to use --rrd)",
                path.display()
            )
        }

        /// Cannot be called (there is no value to call it on).
        ///
        /// # Errors
        /// None.
        pub fn record_frame(
            &self,
            _dataset: &Dataset,
            _stem: &str,
            _detections: &[Detection],
            _kept: &dyn Fn(&Detection) -> bool,
        ) -> Result<()> {
            match *self {}
        }

        /// Cannot be called (there is no value to call it on).
        ///
        /// # Errors
        /// None.
        pub fn finish(self) -> Result<()> {
            match self {}
        }
    }
}
