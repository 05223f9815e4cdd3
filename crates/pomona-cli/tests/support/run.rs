//! What the CLI's integration tests share: running the `pomona` binary, reading its output, and
//! a small synthetic dataset.

#![allow(clippy::unwrap_used, dead_code)] // test helpers; not every test file uses each one

use std::collections::BTreeMap;
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

/// Runs `pomona detect --pipeline PIPELINE --data DATA --out OUT` with `extra` arguments.
pub fn detect(pipeline: &str, data: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "detect",
        "--pipeline",
        pipeline,
        "--data",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    pomona(&args)
}

/// Every file of `dir` by name, with its bytes (none when `dir` does not exist).
pub fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return BTreeMap::new();
    };
    entries
        .map(|e| e.unwrap().path())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect()
}
