//! `pomona detect --rrd`: the recording is a real rerun file on disk, and decoding it back gives,
//! per frame of the `frame` timeline, the detections the run wrote and the dataset's truth; a
//! binary built without the `rerun` feature refuses `--rrd` saying so.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use std::path::Path;
use std::process::{Command, Output};

use pomona_synth::{
    generate_dataset, CameraPreset, DatasetSpec, FruitChoice, FruitKind, SceneSpec,
};

fn pomona(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pomona"))
        .args(args)
        .output()
        .unwrap()
}

/// Two SR4000 frames (176×144) of apples, with colour and truth.
fn two_frames(root: &Path) {
    let scene = SceneSpec {
        fruit: FruitChoice::Only(FruitKind::Apple),
        camera: CameraPreset::Sr4000.camera(),
        ..SceneSpec::default()
    };
    generate_dataset(&DatasetSpec::new(scene, 2, 11), root, &|_| {}).unwrap();
}

fn detect_with_rrd(data: &Path, out: &Path, rrd: &Path) -> Output {
    pomona(&[
        "detect",
        "--pipeline",
        "shape-fit",
        "--data",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "2",
        "--rrd",
        rrd.to_str().unwrap(),
    ])
}

#[cfg(feature = "rerun")]
mod with_rerun {
    use std::collections::{BTreeMap, BTreeSet};
    use std::path::Path;

    use pomona_core::{FrameDetections, FrameTruth};
    use rerun::components::{HalfSize3D, Text};
    use rerun::external::re_log_encoding::{DecoderApp, RRD_FOURCC};
    use rerun::log::{Chunk, LogMsg};
    use rerun::{Ellipsoids3D, TextDocument, TimelineName};

    use super::{detect_with_rrd, two_frames};

    /// What a recording holds: its entities (static and temporal), the number of spheres per
    /// (entity, frame index), and the per-frame text lines.
    #[derive(Default)]
    struct Recorded {
        static_entities: BTreeSet<String>,
        temporal_entities: BTreeSet<String>,
        spheres: BTreeMap<(String, i64), usize>,
        frame_texts: BTreeMap<i64, String>,
    }

    fn decode(path: &Path) -> Recorded {
        let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        let frame = TimelineName::new("frame");
        let half_sizes = Ellipsoids3D::descriptor_half_sizes().component;
        let text = TextDocument::descriptor_text().component;
        let mut recorded = Recorded::default();
        for msg in DecoderApp::decode_eager(file).unwrap() {
            let LogMsg::ArrowMsg(_, arrow) = msg.unwrap() else {
                continue;
            };
            let chunk = Chunk::from_arrow_msg(&arrow).unwrap();
            let entity = chunk.entity_path().to_string().trim_start_matches('/').to_owned();
            if chunk.is_static() {
                recorded.static_entities.insert(entity);
                continue;
            }
            recorded.temporal_entities.insert(entity.clone());
            let times = chunk.iter_component_indices(frame, half_sizes);
            for ((t, _), row) in times.zip(chunk.iter_component::<HalfSize3D>(half_sizes)) {
                *recorded
                    .spheres
                    .entry((entity.clone(), t.as_i64()))
                    .or_default() += row.len();
            }
            let times = chunk.iter_component_indices(frame, text);
            for ((t, _), row) in times.zip(chunk.iter_component::<Text>(text)) {
                recorded
                    .frame_texts
                    .insert(t.as_i64(), row.iter().map(|s| s.as_str()).collect());
            }
        }
        recorded
    }

    #[test]
    fn recording_holds_each_frames_images_cloud_truth_and_detections() {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("data");
        two_frames(&data);
        let (out, rrd) = (dir.path().join("det"), dir.path().join("run.rrd"));
        let run = detect_with_rrd(&data, &out, &rrd);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{stderr}");
        assert!(String::from_utf8_lossy(&run.stdout).contains("run.rrd"));

        let bytes = std::fs::read(&rrd).unwrap();
        assert!(bytes.len() > 50_000, "only {} bytes", bytes.len());
        assert_eq!(bytes[..4], RRD_FOURCC);

        let recorded = decode(&rrd);
        for e in ["world", "world/camera", "run"] {
            assert!(recorded.static_entities.contains(e), "static {e} missing");
        }
        for e in [
            "world/camera/rgb",
            "world/camera/depth",
            "world/points",
            "world/truth",
            "world/detections",
            "frame",
        ] {
            assert!(recorded.temporal_entities.contains(e), "{e} missing");
        }
        let stems: Vec<String> = (0..2).map(|i| format!("{i:06}")).collect();
        let mut found = 0;
        for (index, stem) in stems.iter().enumerate() {
            let index = index as i64;
            let written: FrameDetections = serde_json::from_str(
                &std::fs::read_to_string(out.join(format!("{stem}.json"))).unwrap(),
            )
            .unwrap();
            let truth: FrameTruth = serde_json::from_str(
                &std::fs::read_to_string(data.join("truth").join(format!("{stem}.json")))
                    .unwrap(),
            )
            .unwrap();
            let count = |e: &str| recorded.spheres.get(&(e.to_owned(), index)).copied();
            assert_eq!(
                count("world/detections").unwrap_or(0),
                written.detections.len(),
                "frame {stem}"
            );
            let placed = truth.fruits.iter().filter(|f| f.center_m.is_some()).count();
            assert!(placed > 0);
            assert_eq!(count("world/truth"), Some(placed), "frame {stem}");
            assert!(
                recorded.frame_texts[&index].contains(stem),
                "{}",
                recorded.frame_texts[&index]
            );
            found += written.detections.len();
        }
        assert!(found > 0, "shape-fit found nothing: the test shows too little");
    }

    #[test]
    fn an_unwritable_recording_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("data");
        two_frames(&data);
        let rrd = dir.path().join("no-such-folder").join("run.rrd");
        let run = detect_with_rrd(&data, &dir.path().join("det"), &rrd);
        assert!(!run.status.success());
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(stderr.contains("cannot create the recording"), "{stderr}");
        assert!(stderr.contains(&*rrd.to_string_lossy()), "{stderr}");
    }
}

#[cfg(not(feature = "rerun"))]
#[test]
fn without_the_rerun_feature_rrd_is_refused_saying_why() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    two_frames(&data);
    let rrd = dir.path().join("run.rrd");
    let run = detect_with_rrd(&data, &dir.path().join("det"), &rrd);
    assert!(!run.status.success());
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("without the `rerun` feature"), "{stderr}");
    assert!(!rrd.exists());
}
