//! `pomona extract` and `pomona detect --recording` on ROS 2 MCAP recordings and ROS 1 bags
//! written in the test from synthetic datasets (never downloaded): the recording gives the same pixels, camera
//! and detections as the dataset it was recorded from, and bad recordings fail naming the file.

#![allow(clippy::unwrap_used)]

#[path = "support/run.rs"]
mod run;

use std::path::Path;

use pomona_core::FrameDetections;
use pomona_io::Dataset;
use pomona_recording::{
    BagCompression, BagWriter, FrameEncodings, Header, Image, RecordingTopics, RecordingWriter,
};
use pomona_synth::{
    generate_dataset, CameraPreset, DatasetSpec, FruitChoice, FruitKind, SceneSpec,
};
use run::{pomona, stderr, stdout};

/// 2023-11-14T22:13:20Z, in ns.
const T0: u64 = 1_700_000_000_000_000_000;
const FRAME_NS: u64 = 33_366_700;

/// Three synthetic frames (SR4000, oranges) with depth stored in `depth_unit_m`.
fn synth(root: &Path, depth_unit_m: f64) {
    let scene = SceneSpec {
        fruit: FruitChoice::Only(FruitKind::Orange),
        camera: CameraPreset::Sr4000.camera(),
        ..SceneSpec::default()
    };
    let spec = DatasetSpec {
        depth_unit_m,
        ..DatasetSpec::new(scene, 3, 41)
    };
    generate_dataset(&spec, root, &|_| {}).unwrap();
}

/// Records every frame of the dataset at `root` into `mcap`, 30 Hz from `T0`; returns the
/// stamps in frame order.
fn record(root: &Path, mcap: &Path, encodings: FrameEncodings) -> Vec<u64> {
    let dataset = Dataset::open(root).unwrap();
    let topics = RecordingTopics::default();
    let mut writer = RecordingWriter::create(mcap).unwrap();
    let mut stamps = Vec::new();
    for (i, stem) in dataset.frames().iter().enumerate() {
        let stamp = T0 + i as u64 * FRAME_NS;
        let frame = dataset.load_frame(stem).unwrap();
        writer
            .write_frame(
                &topics,
                stamp,
                "camera_color_optical_frame",
                &frame,
                encodings,
            )
            .unwrap();
        stamps.push(stamp);
    }
    writer.finish().unwrap();
    stamps
}

fn read_detections(path: &Path) -> FrameDetections {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Records every frame of the dataset at `root` into a ROS 1 bag on the ROS 1 driver's topics,
/// 30 Hz from `T0`; returns the stamps in frame order.
fn record_bag(root: &Path, bag: &Path, compression: BagCompression) -> Vec<u64> {
    let dataset = Dataset::open(root).unwrap();
    let topics = RecordingTopics::ros1();
    let mut writer = BagWriter::create(bag, compression).unwrap();
    let mut stamps = Vec::new();
    for (i, stem) in dataset.frames().iter().enumerate() {
        let stamp = T0 + i as u64 * FRAME_NS;
        let frame = dataset.load_frame(stem).unwrap();
        writer
            .write_frame(
                &topics,
                stamp,
                "camera_color_optical_frame",
                &frame,
                FrameEncodings::default(),
            )
            .unwrap();
        stamps.push(stamp);
    }
    writer.finish().unwrap();
    stamps
}

/// `extract` of `recording` gives the dataset at `data`'s pixels and camera (depth in `unit`),
/// and `detect --recording` its detections, with stamps and frame ids.
fn check_recording(
    dir: &Path,
    data: &Path,
    recording: &Path,
    stamps: &[u64],
    unit: f64,
    case: &str,
) {
    let source = Dataset::open(data).unwrap();

    // extract → the same pixels and camera, frames named by the colour stamp.
    let extracted = dir.join(format!("extracted-{case}"));
    let out = pomona(&["extract", s(recording), "--out", s(&extracted)]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("extracted 3 frame(s)"),
        "{}",
        stdout(&out)
    );
    let copy = Dataset::open(&extracted).unwrap();
    assert_eq!(copy.camera(), source.camera());
    assert_eq!(
        copy.depth_unit_m(),
        unit,
        "the finest unit that holds the depth"
    );
    let want_stems: Vec<String> = stamps.iter().map(|t| format!("{t:019}")).collect();
    assert_eq!(copy.frames(), want_stems.as_slice());
    for (stem, original) in copy.frames().iter().zip(source.frames()) {
        let (a, b) = (
            copy.load_frame(stem).unwrap(),
            source.load_frame(original).unwrap(),
        );
        assert_eq!(a.color(), b.color(), "case {case} frame {stem}");
        let same_depth = a
            .depth()
            .as_slice()
            .iter()
            .zip(b.depth().as_slice())
            .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()));
        assert!(same_depth, "case {case} frame {stem}: depth differs");
    }

    // detect --recording → the detections of detect --data, plus stamp and frame id.
    let on_data = dir.join(format!("det-data-{case}"));
    let on_rec = dir.join(format!("det-rec-{case}"));
    for (flag, input, det) in [
        ("--data", data, &on_data),
        ("--recording", recording, &on_rec),
    ] {
        let out = pomona(&[
            "detect",
            "--pipeline",
            "shape-fit",
            flag,
            s(input),
            "--out",
            s(det),
        ]);
        assert!(out.status.success(), "{flag}: {}", stderr(&out));
    }
    let mut found = 0;
    for ((original, stem), stamp) in source.frames().iter().zip(&want_stems).zip(stamps) {
        let a = read_detections(&on_data.join(format!("{original}.json")));
        let b = read_detections(&on_rec.join(format!("{stem}.json")));
        assert_eq!(a.detections, b.detections, "case {case} frame {original}");
        assert_eq!((a.stamp_ns, a.frame_id.as_deref()), (None, None));
        assert_eq!(b.stamp_ns, Some(*stamp));
        assert_eq!(b.frame_id.as_deref(), Some("camera_color_optical_frame"));
        assert_eq!(&b.frame, stem);
        found += a.detections.len();
        let text = std::fs::read_to_string(on_data.join(format!("{original}.json"))).unwrap();
        assert!(!text.contains("stamp_ns") && !text.contains("frame_id"));
    }
    assert!(found > 0, "case {case}: the comparison needs detections");
}

#[test]
fn recording_gives_the_datasets_pixels_camera_and_detections() {
    let dir = tempfile::tempdir().unwrap();
    // 0.1 mm synthetic depth as 32FC1 metres with bgr8 colour; 1 mm depth as 16UC1 with rgb8.
    let cases = [
        (
            1e-4,
            FrameEncodings {
                bgr: true,
                float_depth: true,
            },
        ),
        (
            1e-3,
            FrameEncodings {
                bgr: false,
                float_depth: false,
            },
        ),
    ];
    for (case, (unit, encodings)) in cases.into_iter().enumerate() {
        let data = dir.path().join(format!("data{case}"));
        synth(&data, unit);
        let mcap = dir.path().join(format!("rec{case}.mcap"));
        let stamps = record(&data, &mcap, encodings);
        check_recording(
            dir.path(),
            &data,
            &mcap,
            &stamps,
            unit,
            &format!("mcap{case}"),
        );
    }
}

#[test]
fn ros1_bags_give_the_datasets_pixels_camera_and_detections() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth(&data, 1e-3);
    for compression in [
        BagCompression::None,
        BagCompression::Bz2,
        BagCompression::Lz4,
    ] {
        // The name does not decide the format: the lz4 bag is called .mcap.
        let name = match compression {
            BagCompression::Lz4 => "lz4-bag.mcap".to_owned(),
            other => format!("{other:?}.bag"),
        };
        let bag = dir.path().join(name);
        let stamps = record_bag(&data, &bag, compression);
        check_recording(
            dir.path(),
            &data,
            &bag,
            &stamps,
            1e-3,
            &format!("{compression:?}"),
        );
    }
}

#[test]
fn missing_topics_and_bad_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth(&data, 1e-3);
    let mcap = dir.path().join("rec.mcap");
    record(&data, &mcap, FrameEncodings::default());
    let out_dir = dir.path().join("out");

    // detect reads exactly one of a dataset and a recording.
    for extra in [vec![], vec!["--data", s(&data), "--recording", s(&mcap)]] {
        let mut args = vec!["detect", "--pipeline", "shape-fit", "--out", s(&out_dir)];
        args.extend(extra);
        let out = pomona(&args);
        assert!(!out.status.success());
        let err = stderr(&out);
        assert!(
            err.contains("--data") && err.contains("--recording"),
            "{err}"
        );
    }
    // Topic flags with a dataset folder are an error, not silently ignored.
    let out = pomona(&[
        "detect",
        "--pipeline",
        "shape-fit",
        "--data",
        s(&data),
        "--out",
        s(&out_dir),
        "--depth-topic",
        "/other",
    ]);
    let err = stderr(&out);
    assert!(
        !out.status.success() && err.contains("--recording") && err.contains(s(&data)),
        "{err}"
    );

    let out = pomona(&[
        "extract",
        s(&mcap),
        "--out",
        s(&out_dir),
        "--depth-topic",
        "/camera/depth/image_rect_raw",
    ]);
    assert!(!out.status.success());
    let err = stderr(&out);
    for needle in [
        "rec.mcap",
        "/camera/depth/image_rect_raw",
        "/camera/camera/aligned_depth_to_color/image_raw (sensor_msgs/msg/Image, 3 messages)",
        "/camera/camera/color/camera_info (sensor_msgs/msg/CameraInfo, 3 messages)",
    ] {
        assert!(err.contains(needle), "{needle} not in {err}");
    }

    let bytes = std::fs::read(&mcap).unwrap();
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    for args in [
        vec!["extract", s(&cut), "--out", s(&out_dir)],
        vec![
            "detect",
            "--pipeline",
            "shape-fit",
            "--recording",
            s(&cut),
            "--out",
            s(&out_dir),
        ],
    ] {
        let out = pomona(&args);
        assert!(!out.status.success());
        assert!(stderr(&out).contains("cut.mcap"), "{}", stderr(&out));
    }

    // A depth encoding Pomona does not read fails its frame, naming topic, stamp and encoding.
    let odd = dir.path().join("odd.mcap");
    let topics = RecordingTopics::default();
    let frame = Dataset::open(&data).unwrap().load_frame("000000").unwrap();
    let mut writer = RecordingWriter::create(&odd).unwrap();
    writer
        .write_frame(&topics, T0, "cam", &frame, FrameEncodings::default())
        .unwrap();
    let mut depth =
        Image::from_depth_16uc1(Header::at(T0 + FRAME_NS, "cam"), frame.depth()).unwrap();
    depth.encoding = "16SC1".into();
    let mut color = Image::from_color(
        Header::at(T0 + FRAME_NS, "cam"),
        frame.color().unwrap(),
        false,
    );
    color.header.frame_id = "cam".into();
    writer.write_image(&topics.color, &color).unwrap();
    writer.write_image(&topics.depth, &depth).unwrap();
    writer.finish().unwrap();
    let det = dir.path().join("det-odd");
    let out = pomona(&[
        "detect",
        "--pipeline",
        "shape-fit",
        "--recording",
        s(&odd),
        "--out",
        s(&det),
    ]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "one frame failed: {}",
        stderr(&out)
    );
    let err = stderr(&out);
    for needle in [
        "odd.mcap",
        "aligned_depth_to_color",
        &(T0 + FRAME_NS).to_string(),
        "16SC1",
    ] {
        assert!(err.contains(needle), "{needle} not in {err}");
    }
    assert!(
        det.join(format!("{T0:019}.json")).exists(),
        "the good frame is written"
    );
    let failures = std::fs::read_to_string(det.join("failures.json")).unwrap();
    assert!(
        failures.contains(&format!("{:019}", T0 + FRAME_NS)) && failures.contains("odd.mcap"),
        "{failures}"
    );

    let out = pomona(&[
        "detect",
        "--pipeline",
        "shape-fit",
        "--recording",
        s(&mcap),
        "--out",
        s(&det),
        "--overlay",
        s(&out_dir),
    ]);
    assert!(
        !out.status.success() && stderr(&out).contains("pomona extract"),
        "{}",
        stderr(&out)
    );
}
