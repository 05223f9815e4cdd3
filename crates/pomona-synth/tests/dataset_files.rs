//! Datasets on disk: readable by `pomona_io::Dataset`, equal to the in-memory render, with the
//! stereo layout and `rig.json`, and byte-identical across runs and thread counts.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use std::collections::BTreeMap;
use std::path::Path;

use pomona_core::FrameTruth;
use pomona_io::Dataset;
use pomona_synth::{
    generate_dataset, render, CameraPreset, DatasetSpec, FruitChoice, NoiseModel, RigFile,
    SceneSpec, StereoRig, SynthError,
};

fn small_spec(noise: NoiseModel, stereo: bool) -> DatasetSpec {
    let scene = SceneSpec {
        fruit: FruitChoice::Mixed,
        camera: CameraPreset::Sr4000.camera(),
        noise,
        green_fraction: 0.5,
        ..SceneSpec::default()
    };
    let mut spec = DatasetSpec::new(scene, 4, 77);
    if stereo {
        spec.stereo = Some(StereoRig::default());
    }
    spec
}

/// Every file under `root`, by relative path, with its bytes.
fn tree(root: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let rel = path
                    .strip_prefix(root)
                    .unwrap()
                    .to_string_lossy()
                    .into_owned();
                out.insert(rel, std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

/// Truth equality up to JSON float parsing (serde_json may differ in the last bit).
fn assert_truth_eq(a: &FrameTruth, b: &FrameTruth) {
    assert_eq!(a.complete, b.complete);
    assert_eq!(a.fruits.len(), b.fruits.len());
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (1.0 + y.abs());
    for (f, g) in a.fruits.iter().zip(&b.fruits) {
        assert_eq!((&f.id, &f.kind, f.bbox_px), (&g.id, &g.kind, g.bbox_px));
        let (c, d) = (f.center_m.unwrap(), g.center_m.unwrap());
        assert!((c - d).norm() < 1e-12);
        assert!((f.axis.unwrap().into_inner() - g.axis.unwrap().into_inner()).norm() < 1e-12);
        assert!(close(f.diameter_m.unwrap(), g.diameter_m.unwrap()));
        assert!(close(f.visibility.unwrap(), g.visibility.unwrap()));
    }
}

#[test]
fn dataset_reads_back_and_matches_the_in_memory_render() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ds");
    let spec = small_spec(NoiseModel::Tof, true);
    let calls = std::sync::atomic::AtomicU32::new(0);
    let summary = generate_dataset(&spec, &out, &|_| {
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap();
    assert_eq!(summary.frames, 4);
    assert_eq!(calls.into_inner(), 4);

    let ds = Dataset::open(&out).unwrap();
    assert_eq!(ds.frames(), ["000000", "000001", "000002", "000003"]);
    assert_eq!(ds.camera(), &spec.scene.camera);
    let mut fruits = 0;
    for (i, stem) in ds.frames().iter().enumerate() {
        let scene = spec.scene.sample_frame(spec.seed, i as u64).unwrap();
        let mem = render(&scene, &spec.scene.camera).unwrap();
        let frame = ds.load_frame(stem).unwrap();
        assert_eq!(frame.color(), mem.frame.color());
        let (a, b) = (frame.depth().as_slice(), mem.frame.depth().as_slice());
        for (x, y) in a.iter().zip(b) {
            assert_eq!(x.is_nan(), y.is_nan());
            if x.is_finite() {
                assert!((x - y).abs() <= 0.5 * spec.depth_unit_m as f32 + 1e-6);
            }
        }
        assert_truth_eq(&ds.load_truth(stem).unwrap().unwrap(), &mem.truth);
        assert_eq!(ds.load_mask(stem).unwrap().unwrap(), mem.mask);
        fruits += mem.truth.fruits.len();
    }
    assert_eq!(summary.fruits, fruits);

    // The second view is a dataset of its own, and rig.json holds the pose.
    let stereo = Dataset::open(out.join("stereo")).unwrap();
    assert_eq!(stereo.frames().len(), 4);
    assert!(stereo.load_truth("000002").unwrap().is_some());
    let rig: RigFile =
        serde_json::from_slice(&std::fs::read(out.join("rig.json")).unwrap()).unwrap();
    let expected = StereoRig::default().to_file();
    assert_eq!(rig.pivot_m, expected.pivot_m);
    assert_eq!(rig.stereo_dataset, "stereo");
    for (a, b) in rig
        .stereo_from_camera
        .iter()
        .flatten()
        .zip(expected.stereo_from_camera.iter().flatten())
    {
        assert!((a - b).abs() < 1e-15);
    }
    let synth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("synth.json")).unwrap()).unwrap();
    assert_eq!(synth["seed"], 77);
    assert_eq!(synth["scene"]["noise"], "tof");
}

#[test]
fn same_spec_gives_identical_bytes_whatever_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let mut spec = small_spec(NoiseModel::Tof, true);
    spec.threads = Some(1);
    generate_dataset(&spec, &dir.path().join("a"), &|_| {}).unwrap();
    spec.threads = Some(2);
    generate_dataset(&spec, &dir.path().join("b"), &|_| {}).unwrap();
    spec.threads = None;
    generate_dataset(&spec, &dir.path().join("c"), &|_| {}).unwrap();
    let a = tree(&dir.path().join("a"));
    // 4 frames × (colour, depth, truth, mask) × 2 views + 2 camera.json + rig + synth.
    assert_eq!(a.len(), 4 * 4 * 2 + 4);
    assert_eq!(a, tree(&dir.path().join("b")));
    assert_eq!(a, tree(&dir.path().join("c")));

    spec.seed += 1;
    generate_dataset(&spec, &dir.path().join("d"), &|_| {}).unwrap();
    assert_ne!(a, tree(&dir.path().join("d")));
}

#[test]
fn invalid_spec_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never");
    let mut spec = small_spec(NoiseModel::None, false);
    spec.scene.green_fraction = 2.0;
    let err = generate_dataset(&spec, &out, &|_| {}).unwrap_err();
    assert!(matches!(
        err,
        SynthError::InvalidParameter {
            name: "green-fraction",
            ..
        }
    ));
    assert!(!out.exists());
    let mut spec = small_spec(NoiseModel::None, false);
    spec.threads = Some(0);
    assert!(generate_dataset(&spec, &out, &|_| {}).is_err());
    assert!(!out.exists());
}
