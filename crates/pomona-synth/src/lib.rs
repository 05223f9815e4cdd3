//! # pomona-synth
//!
//! Synthetic RGB-D frames of fruit in a crop row, with exact ground truth: colour, depth (z in
//! metres), a per-fruit instance mask, and truth records (centre, diameter, symmetry axis,
//! visible-pixel box, visibility). Detectors need thousands of labelled fruit to train and a
//! controlled benchmark to be measured on; real data with 3D truth is scarce.
//!
//! ## Domains
//! [`Domain::Narrow`] (the library default) is the original crop row: fruit 0.4–0.9 m away, one
//! ovate leaf shape, a textured backdrop plane, no shadows, a level camera; it stays
//! byte-identical per seed (`tests/narrow_unchanged.rs`). Detectors trained only on it fail on
//! frames from other renderers and real cameras, because they learn the generator's few fixed
//! statistics. [`Domain::Wide`] (the CLI default) therefore draws every nuisance factor per
//! frame from wide documented ranges (the `WIDE_*` constants): camera distance 0.3–1.6 m, pitch
//! and roll, canopy density and layering, four [`LeafFamily`] outlines with bent blades and
//! petioles, stems and branches, five [`Background`]s (sky and black cloth give no depth),
//! cast shadows from a random sun, exposure / white balance / vignetting / noise, fruit aspect,
//! lobes, tilt, touching clusters, colour and gloss, and per-camera depth artefacts
//! ([`NoiseModel::for_camera`]: ToF multipath and flying pixels, stereo occlusion holes).
//! Hold-out knobs ([`SceneSpec::leaf_families`], [`SceneSpec::backgrounds`],
//! [`SceneSpec::wide_distance_m`]) restrict one factor for cross-domain validation. What each
//! wide frame drew is recorded as a [`WideDraw`] in its truth `extra["synth"]`.
//! [`Domain::Orchard`] draws citrus-orchard frames for seed 004's colour-contour method: 5–20
//! fruit with many touching clusters, orange to yellow-green, under one [`LightPreset`]
//! (including `low-sun` and `backlight`); see the `ORCHARD_*` constants.
//!
//! ## Approach sequences
//! [`generate_approach`] renders sequences of frames in which the camera moves towards one
//! target fruit at 0.2–0.5 m/s and 25 fps, optionally with the fruit swaying on their stems,
//! for the approach tracker of seed 004 §3.3 (each sequence a dataset plus an
//! [`ApproachRecord`] naming the target).
//!
//! ## Pipeline
//! [`SceneSpec`] (what to draw) → [`SceneSpec::sample`] → [`Scene`] (fruit bodies, leaves, stems,
//! background, light) → [`render`] → [`RenderedFrame`] (`RgbdFrame` + `FrameTruth` +
//! `InstanceMask`). [`generate_dataset`] does this for N frames in parallel and writes them with
//! `pomona-io`; `pomona synth` is a thin CLI over it.
//!
//! ```
//! use pomona_synth::{render, SceneSpec};
//! let spec = SceneSpec::default(); // peppers, Kinect v2, no depth noise, daylight
//! let scene = spec.sample(42).unwrap();
//! let out = render(&scene, &spec.camera).unwrap();
//! assert!(!out.truth.fruits.is_empty());
//! ```
//!
//! ## Conventions
//! * Scene frame = primary camera frame (OpenCV: x right, y down, z forward, metres).
//! * Depth is the z of the visible surface point, not the ray length.
//! * Truth lists fruit with at least one visible pixel, in scene order; mask id `k` = k-th entry
//!   (1-based). `center_m` is the midpoint of the body's extent along its axis; `axis` points
//!   from the blossom end to the stem end; `diameter_m` is the largest width through the axis;
//!   `bbox_px` spans visible pixel centres; `visibility` = visible pixels / pixels the fruit
//!   covers in the image when rendered alone (image-border truncation is not occlusion). Ids
//!   are the fruit's index in the scene, so stereo views pair up by id.
//! * Determinism: all randomness is ChaCha8 seeded from (dataset seed, frame index); no global
//!   state, no time, no thread-count dependence.
//! * Stereo: see [`StereoRig`] for the rig convention and `rig.json`.

mod approach;
mod backdrop;
mod background;
mod blush;
mod by_name;
mod camera_preset;
mod dataset;
mod depth_noise;
mod domain;
mod error;
mod fruit_body;
mod fruit_kind;
mod fruit_shape;
mod image_effects;
mod leaf;
mod leaf_family;
mod lighting;
mod material;
mod orchard_scene;
mod render;
mod rng;
mod scene;
mod scene_spec;
mod shadow;
mod stem;
mod stereo;
mod two_arm_views;
mod wide_draw;
mod wide_scene;

pub use approach::{
    generate_approach, ApproachRecord, ApproachSpec, ApproachSummary, APPROACH_END_DISTANCE_M,
    APPROACH_FILE, APPROACH_FPS, APPROACH_SPEED_M_PER_S, CORRIDOR_MARGIN_M, MIN_CLEARANCE_M,
    RIPE_MAX_GREEN_OVER_RED, START_BAND_HALF_M, SWAY_AMPLITUDE_M, SWAY_PENDULUM_M,
    TARGET_MIN_VISIBILITY,
};
pub use backdrop::{Backdrop, BackdropKind};
pub use background::Background;
pub use blush::Blush;
pub use camera_preset::CameraPreset;
pub use dataset::{generate_dataset, DatasetSpec, DatasetSummary, DEPTH_UNIT_M};
pub use depth_noise::{
    NoiseModel, LOW_SIGMA_AT_1M, STEREO_BASELINE_M, STEREO_MIN_Z_M, STEREO_SUBPIXEL_SIGMA_PX,
    TOF_DARK_AMPLITUDE, TOF_EDGE_JUMP, TOF_GRAZING_COS, TOF_MULTIPATH_MAX_M,
    TOF_MULTIPATH_RADIUS_PX, TOF_SIGMA_MAX, TOF_SIGMA_MIN,
};
pub use domain::Domain;
pub use error::SynthError;
pub use fruit_body::FruitBody;
pub use fruit_kind::{FruitChoice, FruitKind, PeduncleRange};
pub use fruit_shape::FruitShape;
pub use image_effects::ImageEffects;
pub use leaf::{Leaf, LeafHit};
pub use leaf_family::LeafFamily;
pub use lighting::{Light, LightPreset};
pub use material::Material;
pub use orchard_scene::{
    orchard_albedo, ORCHARD_CLUSTER_PROBABILITY, ORCHARD_CLUSTER_SIZE, ORCHARD_FRUIT_COUNT,
    ORCHARD_ORANGE, ORCHARD_PITCH_ROLL_MAX_DEG, ORCHARD_YELLOW, ORCHARD_YELLOW_GREEN,
};
pub use render::{render, render_view, RenderedFrame};
pub use rng::{frame_rng, SynthRng};
pub use scene::Scene;
pub use scene_spec::SceneSpec;
pub use stem::Stem;
pub use stereo::{RigFile, StereoRig};
pub use two_arm_views::{TwoArmViews, ARM_B_DATASET};
pub use wide_draw::{SunDraw, WideDraw};
pub use wide_scene::{
    WIDE_BEHIND_DEPTH_M, WIDE_BRANCHES, WIDE_BRANCH_LENGTH_M, WIDE_BRANCH_RADIUS_M,
    WIDE_CANOPY_DENSITY, WIDE_CLUSTER_PROBABILITY, WIDE_CLUSTER_SIZE, WIDE_COLOUR_MIX,
    WIDE_DISTANCE_LIMITS_M, WIDE_DISTANCE_M, WIDE_EXPOSURE, WIDE_FRONT_DEPTH_M,
    WIDE_FRONT_LEAF_FRACTION, WIDE_FRUIT_ASPECT, WIDE_FRUIT_LAYER_HALF_DEPTH_M,
    WIDE_FRUIT_TILT_MAX_DEG, WIDE_GLOSS_SCALE, WIDE_IMAGE_NOISE_SIGMA, WIDE_LEAF_BEND_ALONG,
    WIDE_LEAF_COUNT, WIDE_LEAF_CURL_ACROSS, WIDE_LEAF_LENGTH_M, WIDE_LEAF_TILT_MAX_DEG,
    WIDE_MAX_DEPTH_M, WIDE_MIN_LEAF_Z_M, WIDE_PETIOLE_LENGTH, WIDE_PETIOLE_PROBABILITY,
    WIDE_PITCH_MAX_DEG, WIDE_ROLL_MAX_DEG, WIDE_SECOND_ROW_M, WIDE_SKY_LIGHT, WIDE_STALKS,
    WIDE_STALK_RADIUS_M, WIDE_SUN_ELEVATION_DEG, WIDE_SUN_INTENSITY, WIDE_VIGNETTING,
    WIDE_WHITE_BALANCE,
};
