//! What the CLI's integration tests share: running the `pomona` binary, reading its output, and
//! a small synthetic dataset.

#![allow(clippy::unwrap_used, dead_code)] // test helpers; not every test file uses each one

use std::path::Path;
use std::process::{Command, Output};

use pomona_synth::{
    generate_dataset, CameraPreset, DatasetSpec, FruitChoice, FruitKind, SceneSpec,
};

/// Runs the `pomona` binary with `args`.
pub fn pomona(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pomona"))
        .args(args)
        .output()
        .unwrap()
}

/// The run's standard output, as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The run's standard error, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A small synthetic dataset: SR4000 camera (176×144), oranges, exact depth.
pub fn synth_dataset(root: &Path, frames: u32, seed: u64) {
    let scene = SceneSpec {
        fruit: FruitChoice::Only(FruitKind::Orange),
        camera: CameraPreset::Sr4000.camera(),
        ..SceneSpec::default()
    };
    generate_dataset(&DatasetSpec::new(scene, frames, seed), root, &|_| {}).unwrap();
}
