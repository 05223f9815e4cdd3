//! Approach sequences: the camera on a harvesting arm moving towards one target fruit, frame by
//! frame, for the approach tracker of seed 004 §3.3.
//!
//! Each sequence `s` of a set is drawn from its own random stream ([`crate::frame_rng`] of the
//! set's seed and `s`):
//! 1. a speed from [`APPROACH_SPEED_M_PER_S`] and a final camera-to-target distance from
//!    [`APPROACH_END_DISTANCE_M`] give the start distance `end + speed · (F − 1) / fps`
//!    ([`APPROACH_FPS`] frames per second);
//! 2. one scene of the spec's domain (wide or orchard) is drawn with the fruit at that start
//!    distance (the distance band is narrowed to ±[`START_BAND_HALF_M`] around it);
//! 3. the target is the fruit nearest the image centre among the ripe ones (albedo green over
//!    red at most [`RIPE_MAX_GREEN_OVER_RED`]: a harvester picks orange fruit, not yellow or
//!    green ones) at least [`TARGET_MIN_VISIBILITY`] visible in the first frame — unhidden
//!    *and* inside the image: the truth's visibility times the share of the fruit's image disc
//!    within the frame — preferring one with no other fruit in its corridor (below); the most
//!    visible fruit if none qualifies;
//! 4. leaves whose bounding sphere reaches into the arm's corridor (the cylinder of the
//!    target's radius plus [`CORRIDOR_MARGIN_M`] around the line from the camera to the target's
//!    centre, in front of the target) are removed: an arm cannot reach a fruit through a leaf,
//!    and seed 004's tracker expects the target to be the largest orange in view. Leaves beside
//!    the corridor still hide parts of it;
//! 5. the camera moves in a straight line from its start towards the target's rest position
//!    at the constant speed (slower only if the target would come closer than its radius plus
//!    [`MIN_CLEARANCE_M`]), and turns to look at the target during the first half of the
//!    sequence (the arm centring its target);
//! 6. with `sway`, every fruit swings on its stem as a pendulum of length
//!    [`SWAY_PENDULUM_M`] (period 2π√(L/g), so about 0.9–1.8 Hz) with a peak displacement of
//!    [`SWAY_AMPLITUDE_M`] in a random horizontal direction and phase. The sway values are drawn
//!    whether or not they are used, so a set with and without `--sway` and the same seed has the
//!    same scenes, targets and camera paths.
//!
//! Leaves, stalks and the background do not move. Every frame gets its own image and depth noise.
//!
//! ```text
//! <out>/synth.json                 the parameters that made the set
//! <out>/seq-0000/camera.json  color/  depth/  truth/  mask/   one dataset per sequence
//! <out>/seq-0000/approach.json     the target's id and the motion (ApproachRecord)
//! ```
//! Truth is in each frame's camera frame, fruit ids are stable over the sequence (the scene
//! index), and each truth file also carries `approach: {target_id, time_s}`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use pomona_io::{write_json, DatasetWriter};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::dataset::in_thread_pool;
use crate::rng::{frame_rng, mix64, uniform, SynthRng};
use crate::{render_view, Domain, Scene, SceneSpec, SynthError, DEPTH_UNIT_M};

/// Frames per second of approach sequences.
pub const APPROACH_FPS: f64 = 25.0;
/// Range of the camera's speed towards the target, metres per second.
pub const APPROACH_SPEED_M_PER_S: (f64, f64) = (0.2, 0.5);
/// Range of the camera-to-target-centre distance at the last frame, metres.
pub const APPROACH_END_DISTANCE_M: (f64, f64) = (0.2, 0.32);
/// Range of the pendulum length of a swaying fruit, metres.
pub const SWAY_PENDULUM_M: (f64, f64) = (0.08, 0.3);
/// Range of the peak sway displacement of a fruit, metres.
pub const SWAY_AMPLITUDE_M: (f64, f64) = (0.01, 0.03);
/// Name of the per-sequence record.
pub const APPROACH_FILE: &str = "approach.json";
/// Visibility the target needs in the first frame (when some fruit has it): the share of its
/// image disc that is inside the frame and not hidden.
pub const TARGET_MIN_VISIBILITY: f64 = 0.6;
/// Half-width of the distance band the scene's fruit are drawn in, around the start distance.
pub const START_BAND_HALF_M: f64 = 0.05;
/// Closest the camera comes to the target's surface, metres.
pub const MIN_CLEARANCE_M: f64 = 0.08;
/// Clearance around the target's radius kept free of leaves along the approach, metres.
pub const CORRIDOR_MARGIN_M: f64 = 0.01;
/// Targets are ripe: albedo green over red at most this (orange 0.28, orange-yellow at ripeness
/// 0.3 about 0.5, yellow 0.69, yellow-green 1.2; see [`crate::orchard_albedo`]). A harvester
/// picks ripe fruit, and seed 004's tracker follows orange.
pub const RIPE_MAX_GREEN_OVER_RED: f64 = 0.5;
/// Largest start distance, metres (inside the wide domain's distance limits).
const MAX_START_M: f64 = 2.9;
/// Gravity, m/s², for the sway pendulum.
const GRAVITY_M_PER_S2: f64 = 9.81;

/// Everything that determines a set of approach sequences.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ApproachSpec {
    /// What the scenes look like (domain `wide` or `orchard`).
    pub scene: SceneSpec,
    /// Number of sequences.
    pub sequences: u32,
    /// Frames per sequence (at least 2).
    pub frames: u32,
    /// Set seed.
    pub seed: u64,
    /// Fruit sway on their stems.
    pub sway: bool,
    /// Depth unit written to `camera.json`.
    pub depth_unit_m: f64,
    /// Worker threads (`None`: rayon's default). Never changes the output.
    #[serde(skip)]
    pub threads: Option<usize>,
}

impl ApproachSpec {
    /// A spec with [`DEPTH_UNIT_M`] and the default threads.
    pub fn new(scene: SceneSpec, sequences: u32, frames: u32, seed: u64, sway: bool) -> Self {
        Self {
            scene,
            sequences,
            frames,
            seed,
            sway,
            depth_unit_m: DEPTH_UNIT_M,
            threads: None,
        }
    }

    /// The folder name of sequence `index` (`seq-0000`).
    pub fn sequence_dir(index: u32) -> String {
        format!("seq-{index:04}")
    }

    fn validate(&self) -> Result<(), SynthError> {
        let bad = |name, reason: &str| {
            Err(SynthError::InvalidParameter {
                name,
                reason: reason.to_string(),
            })
        };
        if self.scene.domain == Domain::Narrow {
            return bad(
                "domain",
                "approach sequences need the wide or orchard domain (the narrow crop row has a \
                 fixed distance)",
            );
        }
        if self.frames < 2 {
            return bad("frames", "an approach needs at least 2 frames");
        }
        if self.sequences == 0 {
            return bad("approach", "need at least 1 sequence");
        }
        if self.threads == Some(0) {
            return bad("threads", "must be at least 1");
        }
        self.scene.validate()
    }
}

/// `approach.json`: the target and the motion of one sequence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ApproachRecord {
    /// Truth id of the target fruit (stable over the sequence).
    pub target_id: String,
    /// Frames per second.
    pub fps: f64,
    /// Frames in the sequence.
    pub frames: u32,
    /// Camera speed towards the target, metres per second.
    pub speed_m_per_s: f64,
    /// Camera-to-target-centre distance at the first frame, metres.
    pub start_distance_m: f64,
    /// The same at the last frame, metres.
    pub end_distance_m: f64,
    /// Whether the fruit sway.
    pub sway: bool,
    /// Target's radius, metres (half its diameter).
    pub target_radius_m: f64,
}

/// What [`generate_approach`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct ApproachSummary {
    /// The sequences' folders, in order.
    pub sequences: Vec<PathBuf>,
    /// Frames written over all sequences.
    pub frames: u32,
}

/// Per-fruit pendulum sway.
#[derive(Debug, Clone, Copy)]
struct Sway {
    omega: f64,
    amplitude_m: f64,
    direction: Vector3<f64>,
    phase: f64,
    pendulum_m: f64,
}

impl Sway {
    fn draw(rng: &mut SynthRng) -> Self {
        let pendulum_m = uniform(rng, SWAY_PENDULUM_M.0, SWAY_PENDULUM_M.1);
        let heading = uniform(rng, 0.0, std::f64::consts::TAU);
        Self {
            omega: (GRAVITY_M_PER_S2 / pendulum_m).sqrt(),
            amplitude_m: uniform(rng, SWAY_AMPLITUDE_M.0, SWAY_AMPLITUDE_M.1),
            direction: Vector3::new(heading.cos(), 0.0, heading.sin()),
            phase: uniform(rng, 0.0, std::f64::consts::TAU),
            pendulum_m,
        }
    }

    /// Displacement at time `t`: along the swing direction, and up (−y) by the pendulum's rise.
    fn offset(&self, t: f64) -> Vector3<f64> {
        let along = self.amplitude_m * (self.omega * t + self.phase).sin();
        let angle = (along / self.pendulum_m).clamp(-1.0, 1.0).asin();
        let rise = self.pendulum_m * (1.0 - angle.cos());
        self.direction * along - Vector3::y() * rise
    }
}

/// One sequence, ready to render.
struct Plan {
    scene: Scene,
    sway: Vec<Sway>,
    record: ApproachRecord,
    /// Camera start (scene origin) to target rest position.
    direction: Vector3<f64>,
    look: Rotation3<f64>,
}

impl Plan {
    fn draw(spec: &ApproachSpec, index: u32) -> Result<Self, SynthError> {
        let mut rng = frame_rng(spec.seed, u64::from(index));
        let camera = spec.scene.camera;
        let mut speed = uniform(&mut rng, APPROACH_SPEED_M_PER_S.0, APPROACH_SPEED_M_PER_S.1);
        let end = uniform(
            &mut rng,
            APPROACH_END_DISTANCE_M.0,
            APPROACH_END_DISTANCE_M.1,
        );
        let duration_s = f64::from(spec.frames - 1) / APPROACH_FPS;
        let start = (end + speed * duration_s).min(MAX_START_M);
        let mut scene_spec = spec.scene.clone();
        scene_spec.wide_distance_m = (
            (start - START_BAND_HALF_M).max(crate::WIDE_DISTANCE_LIMITS_M.0),
            (start + START_BAND_HALF_M).min(crate::WIDE_DISTANCE_LIMITS_M.1),
        );
        scene_spec.validate()?;
        let mut scene = scene_spec.sample_with(&mut rng);
        let sway: Vec<Sway> = scene.fruits.iter().map(|_| Sway::draw(&mut rng)).collect();
        let first = crate::render(&scene, &camera)?;
        let centre = (
            0.5 * f64::from(camera.width),
            0.5 * f64::from(camera.height),
        );
        let off_centre = |t: &pomona_core::FruitTruth| {
            t.bbox_px.map_or(f64::INFINITY, |b| {
                let (u, v) = (0.5 * (b.xmin + b.xmax), 0.5 * (b.ymin + b.ymax));
                (u - centre.0).hypot(v - centre.1)
            })
        };
        // The truth's visibility counts only pixels inside the image; a fruit mostly beyond the
        // frame's edge is not visible either.
        let (width, height) = (f64::from(camera.width), f64::from(camera.height));
        let visibility = |t: &pomona_core::FruitTruth| {
            let in_view = t
                .image_circle(&camera)
                .map_or(1.0, |c| c.fraction_inside(width, height));
            t.visibility.unwrap_or(0.0) * in_view
        };
        let index_of = |t: &pomona_core::FruitTruth| t.id.parse::<usize>().ok();
        let mut candidates: Vec<&pomona_core::FruitTruth> = first
            .truth
            .fruits
            .iter()
            .filter(|t| visibility(t) >= TARGET_MIN_VISIBILITY)
            .filter(|t| index_of(t).is_some_and(|k| is_ripe(&scene.fruits[k])))
            .collect();
        candidates.sort_by(|a, b| off_centre(a).total_cmp(&off_centre(b)));
        let target_truth = candidates
            .iter()
            .find(|t| index_of(t).is_some_and(|k| corridor_free_of_fruit(&scene, k)))
            .or(candidates.first())
            .copied()
            .or_else(|| {
                first
                    .truth
                    .fruits
                    .iter()
                    .max_by(|a, b| visibility(a).total_cmp(&visibility(b)))
            })
            .ok_or_else(|| SynthError::InvalidParameter {
                name: "approach",
                reason: format!("sequence {index}: no fruit is visible in the first frame"),
            })?;
        let target = index_of(target_truth).ok_or_else(|| SynthError::InvalidParameter {
            name: "approach",
            reason: format!("unexpected truth id `{}`", target_truth.id),
        })?;
        let body = scene.fruits[target].clone();
        let distance = body.center.coords.norm();
        let radius = 0.5 * body.diameter_m();
        scene.leaves.retain(|leaf| {
            !in_corridor(
                &body.center,
                &leaf.center,
                radius + CORRIDOR_MARGIN_M + leaf.bounding_radius_m(),
            )
        });
        let travel = (speed * duration_s)
            .min(distance - radius - MIN_CLEARANCE_M)
            .max(0.0);
        speed = travel / duration_s;
        let direction = body.center.coords / distance;
        let look = Rotation3::rotation_between(&Vector3::z(), &direction)
            .unwrap_or_else(Rotation3::identity);
        let record = ApproachRecord {
            target_id: target_truth.id.clone(),
            fps: APPROACH_FPS,
            frames: spec.frames,
            speed_m_per_s: speed,
            start_distance_m: distance,
            end_distance_m: distance - travel,
            sway: spec.sway,
            target_radius_m: radius,
        };
        Ok(Self {
            scene,
            sway,
            record,
            direction,
            look,
        })
    }

    /// The scene at frame `k` (fruit displaced by their sway, fresh sensor noise) and the pose
    /// mapping it into that frame's camera.
    fn frame(&self, k: u32, sway: bool) -> (Scene, Isometry3<f64>) {
        let t = f64::from(k) / APPROACH_FPS;
        let mut scene = self.scene.clone();
        if sway {
            for (fruit, s) in scene.fruits.iter_mut().zip(&self.sway) {
                fruit.center += s.offset(t);
            }
        }
        scene.noise_seed = mix64(self.scene.noise_seed ^ u64::from(k).wrapping_mul(0x9E37));
        let position = Point3::from(self.direction * (self.record.speed_m_per_s * t));
        let turn = (2.0 * f64::from(k) / f64::from(self.record.frames.max(2) - 1)).min(1.0);
        let rotation = UnitQuaternion::from_rotation_matrix(&self.look.powf(turn));
        let scene_from_camera =
            Isometry3::from_parts(Translation3::from(position.coords), rotation);
        (scene, scene_from_camera.inverse())
    }
}

/// Whether `point` lies in front of `target` (seen from the camera at the origin) and within
/// `reach` of the segment from the camera to it.
fn in_corridor(target: &Point3<f64>, point: &Point3<f64>, reach: f64) -> bool {
    let t = target.coords;
    let along = point.coords.dot(&t) / t.norm_squared();
    along < 1.0 && (point.coords - t * along.clamp(0.0, 1.0)).norm() <= reach
}

/// Whether no other fruit sits in the corridor to fruit `k`.
fn corridor_free_of_fruit(scene: &Scene, k: usize) -> bool {
    let target = &scene.fruits[k];
    scene.fruits.iter().enumerate().all(|(j, other)| {
        j == k
            || !in_corridor(
                &target.center,
                &other.center,
                0.5 * target.diameter_m() + other.bounding_radius_m() + CORRIDOR_MARGIN_M,
            )
    })
}

/// Whether a fruit is ripe enough to be a harvesting target: its albedo's green is at most
/// [`RIPE_MAX_GREEN_OVER_RED`] of its red (orange to orange-yellow; yellow and green are not).
fn is_ripe(fruit: &crate::FruitBody) -> bool {
    let [r, g, _] = fruit.material.albedo;
    g <= RIPE_MAX_GREEN_OVER_RED * r
}

/// Renders `spec.sequences` approach sequences of `spec.frames` frames into `out/seq-NNNN/`
/// (see the module docs). Frames are rendered in parallel; the output does not depend on the
/// number of threads. `progress` gets the number of finished frames after each one.
///
/// # Errors
/// [`SynthError::InvalidParameter`] for a narrow-domain or otherwise invalid spec, or a
/// sequence whose first frame shows no fruit; [`SynthError::Dataset`] naming a file that could
/// not be written; [`SynthError::ThreadPool`] if the requested threads cannot start.
pub fn generate_approach(
    spec: &ApproachSpec,
    out: &Path,
    progress: &(dyn Fn(u32) + Sync),
) -> Result<ApproachSummary, SynthError> {
    spec.validate()?;
    let run = || -> Result<ApproachSummary, SynthError> {
        let plans: Vec<Plan> = (0..spec.sequences)
            .into_par_iter()
            .map(|s| Plan::draw(spec, s))
            .collect::<Result<_, _>>()?;
        let camera = spec.scene.camera;
        let mut writers = Vec::new();
        for (s, plan) in plans.iter().enumerate() {
            let dir = out.join(ApproachSpec::sequence_dir(s as u32));
            let writer = DatasetWriter::create(&dir, &camera, spec.depth_unit_m)?;
            write_json(&dir.join(APPROACH_FILE), &plan.record)?;
            writers.push(writer);
        }
        // The sequence folders created `out`.
        write_json(&out.join("synth.json"), &ApproachSetRecord::new(spec))?;
        let done = AtomicUsize::new(0);
        let jobs: Vec<(usize, u32)> = (0..plans.len())
            .flat_map(|s| (0..spec.frames).map(move |k| (s, k)))
            .collect();
        jobs.into_par_iter().try_for_each(|(s, k)| {
            let plan = &plans[s];
            let (scene, camera_from_scene) = plan.frame(k, spec.sway);
            let mut view = render_view(&scene, &camera, &camera_from_scene, 0)?;
            view.truth.extra.insert(
                "approach".to_string(),
                serde_json::json!({
                    "target_id": plan.record.target_id,
                    "time_s": f64::from(k) / APPROACH_FPS,
                }),
            );
            let stem = crate::DatasetSpec::frame_stem(k);
            writers[s].write_frame(&stem, &view.frame, Some(&view.truth))?;
            writers[s].write_mask(&stem, &view.mask)?;
            progress(done.fetch_add(1, Ordering::Relaxed) as u32 + 1);
            Ok::<(), SynthError>(())
        })?;
        Ok(ApproachSummary {
            sequences: writers.iter().map(|w| w.root().to_owned()).collect(),
            frames: spec.sequences * spec.frames,
        })
    };
    in_thread_pool(spec.threads, run)
}

/// Contents of the set's `synth.json`.
#[derive(Debug, Serialize)]
struct ApproachSetRecord<'a> {
    generator: &'static str,
    version: &'static str,
    approach: &'a ApproachSpec,
    fps: f64,
}

impl<'a> ApproachSetRecord<'a> {
    fn new(spec: &'a ApproachSpec) -> Self {
        Self {
            generator: "pomona-synth",
            version: env!("CARGO_PKG_VERSION"),
            approach: spec,
            fps: APPROACH_FPS,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CameraPreset, FruitChoice, FruitKind, LightPreset};

    fn spec(sway: bool) -> ApproachSpec {
        let scene = SceneSpec {
            fruit: FruitChoice::Only(FruitKind::Orange),
            domain: Domain::Orchard,
            light: LightPreset::Day,
            camera: CameraPreset::Sr4000.camera(),
            ..SceneSpec::default()
        };
        ApproachSpec::new(scene, 2, 6, 7, sway)
    }

    #[test]
    fn the_camera_closes_in_on_the_target_at_the_drawn_speed() {
        let spec = spec(false);
        let plan = Plan::draw(&spec, 0).unwrap();
        let r = &plan.record;
        assert!(r.speed_m_per_s > 0.0 && r.speed_m_per_s <= APPROACH_SPEED_M_PER_S.1);
        let travelled = r.start_distance_m - r.end_distance_m;
        assert!((travelled - r.speed_m_per_s * 5.0 / APPROACH_FPS).abs() < 1e-9);
        let target: usize = r.target_id.parse().unwrap();
        let mut last = f64::INFINITY;
        for k in 0..spec.frames {
            let (scene, camera_from_scene) = plan.frame(k, false);
            let c = camera_from_scene * scene.fruits[target].center;
            let d = c.coords.norm();
            assert!(d < last, "frame {k}: {d} m, before {last} m");
            last = d;
            if k == spec.frames - 1 {
                // Looking straight at it at the end.
                assert!(c.x.abs() < 1e-6 && c.y.abs() < 1e-6, "{c}");
                assert!((d - r.end_distance_m).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn the_target_is_in_view_not_beyond_the_frame_edge() {
        // Seed 41's orchard set as `pomona synth --approach 20 --frames 25 --seed 41 --domain
        // orchard --fruit orange` draws it (the tracker's tuning set): under a rule that counted only the
        // pixels inside the image, sequences 10 and 19 took fruit whose image centre lay 9 px
        // inside and 33 px outside the top edge.
        let spec = ApproachSpec::new(
            SceneSpec {
                fruit: FruitChoice::Only(FruitKind::Orange),
                domain: Domain::Orchard,
                noise: crate::NoiseModel::TofMultipath,
                backgrounds: Domain::Orchard.default_backgrounds(),
                ..SceneSpec::default()
            },
            20,
            25,
            41,
            false,
        );
        let camera = spec.scene.camera;
        for index in [10, 19] {
            let plan = Plan::draw(&spec, index).unwrap();
            let first = crate::render(&plan.scene, &camera).unwrap();
            let target = first
                .truth
                .fruits
                .iter()
                .find(|t| t.id == plan.record.target_id)
                .unwrap();
            let circle = target.image_circle(&camera).unwrap();
            let in_view = circle.fraction_inside(f64::from(camera.width), f64::from(camera.height));
            assert!(
                in_view * target.visibility.unwrap() >= TARGET_MIN_VISIBILITY,
                "sequence {index}: {in_view} in view, {:?} visible",
                target.visibility
            );
        }
    }

    #[test]
    fn sway_moves_fruit_but_keeps_the_scene_and_path() {
        let (still, swaying) = (
            Plan::draw(&spec(false), 1).unwrap(),
            Plan::draw(&spec(true), 1).unwrap(),
        );
        assert_eq!(still.record.target_id, swaying.record.target_id);
        assert_eq!(still.scene, swaying.scene);
        let (a, pose_a) = still.frame(3, false);
        let (b, pose_b) = swaying.frame(3, true);
        assert_eq!(pose_a, pose_b);
        let moved = (a.fruits[0].center - b.fruits[0].center).norm();
        assert!(moved > 0.0 && moved <= SWAY_AMPLITUDE_M.1 + 1e-9, "{moved}");
    }

    #[test]
    fn writes_one_dataset_per_sequence_with_the_target_record() {
        let dir = tempfile::tempdir().unwrap();
        let spec = ApproachSpec {
            threads: Some(2),
            ..spec(true)
        };
        let summary = generate_approach(&spec, dir.path(), &|_| {}).unwrap();
        assert_eq!(summary.frames, 12);
        let seq = dir.path().join("seq-0001");
        assert!(seq.join("color/000005.png").exists() && seq.join("mask/000005.png").exists());
        let record: ApproachRecord =
            serde_json::from_str(&std::fs::read_to_string(seq.join(APPROACH_FILE)).unwrap())
                .unwrap();
        let truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(seq.join("truth/000005.json")).unwrap())
                .unwrap();
        assert_eq!(truth["approach"]["target_id"], record.target_id.as_str());
        assert!(dir.path().join("synth.json").exists());
        let narrow = ApproachSpec {
            scene: SceneSpec::default(),
            ..spec.clone()
        };
        assert!(generate_approach(&narrow, dir.path(), &|_| {}).is_err());
    }
}
