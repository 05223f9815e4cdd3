//! Recordings written with `RecordingWriter` and read back with `Recording`: frames, stamps,
//! approximate-time sync, and the errors a user sees for bad files.

#![allow(clippy::unwrap_used)]

use std::path::Path;

use pomona_core::{ColorImage, DepthImage, PinholeCamera, RadialDistortion, RgbdFrame};
use pomona_recording::{
    frame_stem, CameraInfo, FrameEncodings, Header, Image, Recording, RecordingError,
    RecordingOptions, RecordingTopics, RecordingWriter,
};

const T0: u64 = 1_700_000_000_000_000_000;
const FRAME_NS: u64 = 33_333_333;

/// A 6×4 frame whose pixels depend on `i`.
fn frame(i: u32) -> RgbdFrame {
    let camera = PinholeCamera::new(6, 4, 5.0, 5.5, 2.5, 1.5)
        .unwrap()
        .with_distortion(Some(RadialDistortion { k1: -0.1, k2: 0.01 }))
        .unwrap();
    let mut color = ColorImage::filled(6, 4, [10, 20, 30]);
    color.set(i % 6, 1, [250, (i * 7) as u8, 5]);
    let mut depth_m: Vec<f32> = (0..24).map(|p| 0.5 + 0.001 * (p + i) as f32).collect();
    depth_m[3] = f32::NAN;
    let depth = DepthImage::from_meters(6, 4, depth_m).unwrap();
    RgbdFrame::new(camera, depth, Some(color)).unwrap()
}

fn write_frames(path: &Path, n: u32, encodings: FrameEncodings) -> Vec<RgbdFrame> {
    let topics = RecordingTopics::default();
    let mut w = RecordingWriter::create(path).unwrap();
    let frames: Vec<RgbdFrame> = (0..n).map(frame).collect();
    for (i, f) in frames.iter().enumerate() {
        let stamp = T0 + i as u64 * FRAME_NS;
        w.write_frame(&topics, stamp, "camera_color_optical_frame", f, encodings)
            .unwrap();
    }
    w.finish().unwrap();
    frames
}

#[test]
fn frames_come_back_with_stamps_camera_and_pixels() {
    let dir = tempfile::tempdir().unwrap();
    for encodings in [
        FrameEncodings::default(),
        FrameEncodings {
            bgr: true,
            float_depth: true,
        },
    ] {
        let path = dir.path().join("rec.mcap");
        let frames = write_frames(&path, 3, encodings);
        let rec = Recording::open(&path).unwrap();
        assert_eq!(rec.frame_count(), 3);
        assert!(rec.unmatched_color_ns().is_empty());
        assert_eq!(rec.frame_stems()[1], format!("{:019}", T0 + FRAME_NS));
        for (i, want) in frames.iter().enumerate() {
            let got = rec.load_frame(i).unwrap();
            assert_eq!(got.stamp_ns, T0 + i as u64 * FRAME_NS);
            assert_eq!(got.frame_id, "camera_color_optical_frame");
            assert_eq!(
                rec.frame_header(i),
                Some((got.stamp_ns, "camera_color_optical_frame"))
            );
            assert_eq!(got.frame.camera(), want.camera());
            assert_eq!(got.frame.color(), want.color());
            // 16UC1 rounds to millimetres; the frames' depths are whole millimetres.
            for (a, b) in got
                .frame
                .depth()
                .as_slice()
                .iter()
                .zip(want.depth().as_slice())
            {
                assert!(
                    a == b || (a.is_nan() && b.is_nan()) || (a - b).abs() < 1e-6,
                    "{a} {b}"
                );
            }
        }
        assert!(rec.load_frame(3).is_err());
    }
}

#[test]
fn approximate_sync_matches_nearest_depth_and_counts_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("offsets.mcap");
    let topics = RecordingTopics::default();
    let f = frame(0);
    let mut w = RecordingWriter::create(&path).unwrap();
    // Camera info once, after the first colour image.
    let info = CameraInfo::from_camera(Header::at(T0 + 10, "cam"), f.camera());
    w.write_camera_info(&topics.camera_info, &info).unwrap();
    let color = |ns| Image::from_color(Header::at(ns, "cam"), f.color().unwrap(), false);
    let depth = |ns| Image::from_depth_16uc1(Header::at(ns, "cam"), f.depth()).unwrap();
    // Written out of order: colour at 0, 33, 66, 100 ms; depth 5 ms late, 15 ms early, none,
    // 30 ms late.
    for ms in [66u64, 0, 100, 33] {
        w.write_image(&topics.color, &color(T0 + ms * 1_000_000))
            .unwrap();
    }
    for ms in [5u64, 18, 130] {
        w.write_image(&topics.depth, &depth(T0 + ms * 1_000_000))
            .unwrap();
    }
    w.finish().unwrap();
    let rec = Recording::open(&path).unwrap();
    assert_eq!(rec.frame_stamps_ns(), vec![T0, T0 + 33_000_000]);
    assert_eq!(
        rec.unmatched_color_ns(),
        &[T0 + 66_000_000, T0 + 100_000_000]
    );
    assert_eq!(rec.message_counts(), (4, 3, 1));
    let loose = RecordingOptions {
        sync_tolerance_ns: 50_000_000,
        ..RecordingOptions::default()
    };
    let rec = Recording::open_with(&path, &loose).unwrap();
    assert_eq!(rec.frame_count(), 4, "{:?}", rec.unmatched_color_ns());
    assert_eq!(frame_stem(5), "0000000000000000005");
}

#[test]
fn missing_topic_lists_what_the_recording_has() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rec.mcap");
    write_frames(&path, 1, FrameEncodings::default());
    let options = RecordingOptions {
        topics: RecordingTopics {
            depth: "/depth/nope".into(),
            ..RecordingTopics::default()
        }
        .into(),
        ..RecordingOptions::default()
    };
    let e = Recording::open_with(&path, &options).unwrap_err();
    let text = e.to_string();
    assert!(matches!(e, RecordingError::MissingTopic { .. }));
    for needle in [
        path.to_str().unwrap(),
        "/depth/nope",
        "--depth-topic",
        "/camera/camera/color/image_raw (sensor_msgs/msg/Image, 1 messages)",
        "/camera/camera/color/camera_info (sensor_msgs/msg/CameraInfo, 1 messages)",
    ] {
        assert!(text.contains(needle), "{needle} not in {text}");
    }
    // A topic of the wrong type is named with what it carries.
    let options = RecordingOptions {
        topics: RecordingTopics {
            color: "/camera/camera/color/camera_info".into(),
            ..RecordingTopics::default()
        }
        .into(),
        ..RecordingOptions::default()
    };
    let text = Recording::open_with(&path, &options)
        .unwrap_err()
        .to_string();
    assert!(
        text.contains("sensor_msgs/msg/CameraInfo") && text.contains("expected"),
        "{text}"
    );
}

#[test]
fn truncated_and_corrupt_files_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rec.mcap");
    write_frames(&path, 2, FrameEncodings::default());
    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = Recording::open(&cut).unwrap_err();
    assert!(matches!(e, RecordingError::Mcap { .. }), "{e}");
    assert!(e.to_string().contains("cut.mcap"), "{e}");
    let junk = dir.path().join("junk.mcap");
    std::fs::write(&junk, b"this is not an mcap file at all").unwrap();
    let e = Recording::open(&junk).unwrap_err().to_string();
    assert!(e.contains("junk.mcap"), "{e}");
    let e = Recording::open(dir.path().join("absent.mcap")).unwrap_err();
    assert!(matches!(e, RecordingError::Io { .. }) && e.to_string().contains("absent.mcap"));
}

/// The messages of `frame(0)` stamped `T0`: camera info, `rgb8` colour, `16UC1` depth.
fn messages() -> (CameraInfo, Image, Image) {
    let f = frame(0);
    let header = Header::at(T0, "cam");
    (
        CameraInfo::from_camera(header.clone(), f.camera()),
        Image::from_color(header.clone(), f.color().unwrap(), false),
        Image::from_depth_16uc1(header, f.depth()).unwrap(),
    )
}

/// Writes one frame's messages, as given, on the default topics.
fn write_messages(path: &Path, (info, color, depth): &(CameraInfo, Image, Image)) {
    let topics = RecordingTopics::default();
    let mut w = RecordingWriter::create(path).unwrap();
    w.write_camera_info(&topics.camera_info, info).unwrap();
    w.write_image(&topics.color, color).unwrap();
    w.write_image(&topics.depth, depth).unwrap();
    w.finish().unwrap();
}

#[test]
fn bad_encoding_names_topic_stamp_and_encoding() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("yuv.mcap");
    let mut parts = messages();
    parts.1.encoding = "yuv422".into();
    write_messages(&path, &parts);
    let rec = Recording::open(&path).unwrap();
    let e = rec.load_frame(0).unwrap_err().to_string();
    for needle in [
        "yuv.mcap",
        "/camera/camera/color/image_raw",
        &T0.to_string(),
        "yuv422",
    ] {
        assert!(e.contains(needle), "{needle} not in {e}");
    }
}

#[test]
fn unsupported_distortion_is_reported_on_opening() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fisheye.mcap");
    let mut parts = messages();
    parts.0.distortion_model = "equidistant".into();
    write_messages(&path, &parts);
    let e = Recording::open(&path).unwrap_err().to_string();
    assert!(
        e.contains("fisheye.mcap") && e.contains("equidistant"),
        "{e}"
    );
}
