//! ROS 1 bags written with `BagWriter` and read back with `Recording`: frames from every chunk
//! compression, the ROS 1 driver's default topics, and the errors a user sees for bad bags
//! (never a panic, whatever byte is damaged).

#![allow(clippy::unwrap_used)]

use std::path::Path;

use pomona_core::{ColorImage, DepthImage, PinholeCamera, RadialDistortion, RgbdFrame};
use pomona_recording::{
    Bag, BagCompression, BagError, BagWriter, FrameEncodings, Recording, RecordingError,
    RecordingFormat, RecordingOptions, RecordingTopics, TopicRequest,
};

const T0: u64 = 1_700_000_000_000_000_000;
const FRAME_NS: u64 = 33_333_333;

/// A 60×40 frame whose pixels depend on `i` (large enough that a few frames span chunks).
fn frame(i: u32) -> RgbdFrame {
    let camera = PinholeCamera::new(60, 40, 50.0, 55.0, 29.5, 19.5)
        .unwrap()
        .with_distortion(Some(RadialDistortion { k1: -0.1, k2: 0.01 }))
        .unwrap();
    let mut color = ColorImage::filled(60, 40, [10, 20, 30]);
    for p in 0..60 {
        color.set(p, (p + i) % 40, [250, (i * 7) as u8, p as u8]);
    }
    let mut depth_m: Vec<f32> = (0..2400)
        .map(|p| 0.5 + 0.001 * ((p + i) % 900) as f32)
        .collect();
    depth_m[3] = f32::NAN;
    let depth = DepthImage::from_meters(60, 40, depth_m).unwrap();
    RgbdFrame::new(camera, depth, Some(color)).unwrap()
}

fn write_bag(path: &Path, n: u32, compression: BagCompression) -> Vec<RgbdFrame> {
    let topics = RecordingTopics::ros1();
    let mut w = BagWriter::create(path, compression).unwrap();
    let frames: Vec<RgbdFrame> = (0..n).map(frame).collect();
    for (i, f) in frames.iter().enumerate() {
        let stamp = T0 + i as u64 * FRAME_NS;
        w.write_frame(
            &topics,
            stamp,
            "camera_color_optical_frame",
            f,
            FrameEncodings::default(),
        )
        .unwrap();
    }
    w.finish().unwrap();
    frames
}

#[test]
fn every_compression_gives_the_frames_back_on_the_ros1_default_topics() {
    let dir = tempfile::tempdir().unwrap();
    for compression in [
        BagCompression::None,
        BagCompression::Bz2,
        BagCompression::Lz4,
    ] {
        // 80 frames of 12 kB: several 768 KiB chunks.
        let path = dir.path().join(format!("rec-{compression:?}.bag"));
        let frames = write_bag(&path, 80, compression);
        let bytes = std::fs::read(&path).unwrap();
        let bag = Bag::open(&bytes).unwrap();
        assert_eq!(bag.connections().len(), 3);
        let rec = Recording::open(&path).unwrap();
        assert_eq!(rec.format(), RecordingFormat::Ros1Bag);
        assert_eq!(rec.selected_topics(), &RecordingTopics::ros1());
        assert_eq!(rec.frame_count(), 80, "{compression:?}");
        assert_eq!(rec.message_counts(), (80, 80, 80));
        for (i, want) in frames.iter().enumerate() {
            let got = rec.load_frame(i).unwrap();
            assert_eq!(got.stamp_ns, T0 + i as u64 * FRAME_NS);
            assert_eq!(got.frame_id, "camera_color_optical_frame");
            assert_eq!(got.frame.camera(), want.camera());
            assert_eq!(got.frame.color(), want.color());
            let same = got
                .frame
                .depth()
                .as_slice()
                .iter()
                .zip(want.depth().as_slice())
                .all(|(a, b)| (a.is_nan() && b.is_nan()) || (a - b).abs() < 1e-6);
            assert!(same, "{compression:?} frame {i}");
        }
    }
}

#[test]
fn chosen_topics_and_missing_topics_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rec.bag");
    write_bag(&path, 2, BagCompression::None);
    let options = RecordingOptions {
        topics: TopicRequest {
            depth: Some("/camera/depth/image_rect_raw".into()),
            ..TopicRequest::default()
        },
        ..RecordingOptions::default()
    };
    let e = Recording::open_with(&path, &options).unwrap_err();
    assert!(matches!(e, RecordingError::MissingTopic { .. }), "{e}");
    let text = e.to_string();
    for needle in [
        "rec.bag",
        "/camera/depth/image_rect_raw",
        "--depth-topic",
        "/camera/color/image_raw (sensor_msgs/Image, 2 messages)",
        "/camera/aligned_depth_to_color/image_raw (sensor_msgs/Image, 2 messages)",
        "/camera/color/camera_info (sensor_msgs/CameraInfo, 2 messages)",
    ] {
        assert!(text.contains(needle), "{needle} not in {text}");
    }
    // The colour topic pointed at camera info: the type is named.
    let options = RecordingOptions {
        topics: TopicRequest {
            color: Some("/camera/color/camera_info".into()),
            ..TopicRequest::default()
        },
        ..RecordingOptions::default()
    };
    let text = Recording::open_with(&path, &options)
        .unwrap_err()
        .to_string();
    assert!(
        text.contains("sensor_msgs/CameraInfo") && text.contains("expected `sensor_msgs/Image`"),
        "{text}"
    );
    // A bag with neither the ROS 1 driver's topics nor RealSense streams lists what it has.
    let other = dir.path().join("other.bag");
    let mut w = BagWriter::create(&other, BagCompression::None).unwrap();
    let f = frame(0);
    let topics = RecordingTopics {
        color: "/cam/rgb".into(),
        depth: "/cam/depth".into(),
        camera_info: "/cam/info".into(),
    };
    w.write_frame(&topics, T0, "cam", &f, FrameEncodings::default())
        .unwrap();
    w.finish().unwrap();
    let text = Recording::open(&other).unwrap_err().to_string();
    assert!(
        text.contains("/camera/color/image_raw")
            && text.contains("/cam/rgb (sensor_msgs/Image, 1 messages)"),
        "{text}"
    );
    let rec = Recording::open_with(
        &other,
        &RecordingOptions {
            topics: topics.into(),
            ..RecordingOptions::default()
        },
    )
    .unwrap();
    assert_eq!(rec.frame_count(), 1);
}

#[test]
fn bad_bags_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rec.bag");
    write_bag(&path, 6, BagCompression::Lz4);
    let bytes = std::fs::read(&path).unwrap();

    // Truncated: the index lies past the end.
    let cut = dir.path().join("cut.bag");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = Recording::open(&cut).unwrap_err();
    assert!(
        matches!(
            e,
            RecordingError::Bag {
                source: BagError::Truncated { .. },
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("cut.bag"), "{e}");

    // Another bag version.
    let old = dir.path().join("old.bag");
    let mut v12 = bytes.clone();
    v12[..13].copy_from_slice(b"#ROSBAG V1.2\n");
    std::fs::write(&old, &v12).unwrap();
    let e = Recording::open(&old).unwrap_err().to_string();
    assert!(
        e.contains("old.bag") && e.contains("#ROSBAG V1.2") && e.contains("2.0"),
        "{e}"
    );

    // Neither MCAP nor a bag.
    let junk = dir.path().join("junk.bag");
    std::fs::write(&junk, b"PK\x03\x04 a zip file").unwrap();
    let e = Recording::open(&junk).unwrap_err();
    assert!(matches!(e, RecordingError::UnknownFormat { .. }), "{e}");
    assert!(e.to_string().contains("junk.bag"), "{e}");

    // A bag whose recording was killed: index_pos 0.
    let active = dir.path().join("active.bag");
    let mut unindexed = bytes.clone();
    let at = bytes.windows(10).position(|w| w == b"index_pos=").unwrap() + 10;
    unindexed[at..at + 8].fill(0);
    std::fs::write(&active, &unindexed).unwrap();
    let e = Recording::open(&active).unwrap_err().to_string();
    assert!(e.contains("active.bag") && e.contains("reindex"), "{e}");

    // Chunk data damaged: the lz4 frame no longer inflates, or inflates to other records.
    let damaged = dir.path().join("damaged.bag");
    let mut bad = bytes.clone();
    for b in &mut bad[6000..6064] {
        *b ^= 0x5A;
    }
    std::fs::write(&damaged, &bad).unwrap();
    let e = Recording::open(&damaged).unwrap_err();
    assert!(matches!(e, RecordingError::Bag { .. }), "{e}");
    assert!(e.to_string().contains("damaged.bag"), "{e}");
}

/// Every single damaged byte or cut (seeded positions, each compression): an error or frames,
/// never a panic.
#[test]
fn damaged_bytes_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut errors = 0;
    let mut cases = 0;
    for compression in [
        BagCompression::None,
        BagCompression::Bz2,
        BagCompression::Lz4,
    ] {
        let path = dir.path().join("rec.bag");
        write_bag(&path, 3, compression);
        let bytes = std::fs::read(&path).unwrap();
        let probe = dir.path().join("probe.bag");
        for case in 0..120 {
            let mut b = bytes.clone();
            let at = (next() % b.len() as u64) as usize;
            if case % 4 == 0 {
                b.truncate(at);
            } else {
                b[at] ^= 1 << (next() % 8);
            }
            std::fs::write(&probe, &b).unwrap();
            cases += 1;
            match Recording::open(&probe) {
                Err(e) => {
                    errors += 1;
                    assert!(e.to_string().contains("probe.bag"), "{e}");
                }
                Ok(rec) => {
                    for i in 0..rec.frame_count() {
                        if let Err(e) = rec.load_frame(i) {
                            assert!(e.to_string().contains("probe.bag"), "{e}");
                        }
                    }
                }
            }
        }
    }
    // Most damage is caught (pixel bytes of uncompressed chunks are not).
    assert!(errors * 3 > cases, "{errors} errors in {cases} cases");
}
