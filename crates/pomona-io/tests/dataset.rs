//! Dataset layout: reading the real Azure Kinect orchard data, round trips through the writer,
//! and one test per way a dataset can be broken (each must give its typed error, never panic).

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use std::path::{Path, PathBuf};

use pomona_core::{ColorImage, DepthImage, FrameTruth, InstanceMask, PinholeCamera};
use pomona_io::{Dataset, DatasetError, DatasetWriter};

fn shared_data(rel: &str) -> Option<PathBuf> {
    pomona_test_support::shared_data(rel, "pomona-io/tests/dataset.rs")
}

#[test]
fn reads_real_azure_kinect_apples() {
    let Some(root) = shared_data("ak-apples") else {
        return;
    };
    let ds = Dataset::open(&root).unwrap();
    assert_eq!(ds.frames(), ["121804", "123505", "125309"]);
    let cam = ds.camera();
    assert_eq!((cam.width, cam.height), (1920, 1080));
    assert!((cam.fx - 917.122986).abs() < 1e-9);
    assert_eq!(ds.depth_unit_m(), 0.001);
    for frame in ds.frames() {
        let rgbd = ds.load_frame(frame).unwrap();
        let valid = rgbd.depth().valid_fraction();
        assert!(
            (0.2..0.35).contains(&valid),
            "frame {frame}: valid depth {valid}"
        );
        let (lo, hi) = rgbd.depth().range_m().unwrap();
        assert!(lo > 0.2 && hi < 20.0, "depth range {lo}..{hi}");
        let truth = ds.load_truth(frame).unwrap().unwrap();
        assert!(!truth.complete);
        assert_eq!(truth.fruits.len(), 28);
        // Every 3D centre projects inside (or on the edge of) its annotated box.
        for fruit in &truth.fruits {
            let (Some(c), Some(b)) = (fruit.center_m, fruit.bbox_px) else {
                continue;
            };
            let px = cam.project(&c).unwrap();
            assert!(
                px.x > b.xmin - 10.0
                    && px.x < b.xmax + 10.0
                    && px.y > b.ymin - 10.0
                    && px.y < b.ymax + 10.0,
                "fruit {} centre projects to {px} outside {b:?}",
                fruit.id
            );
        }
        assert!(ds.load_mask(frame).unwrap().is_none());
    }
}

fn camera() -> PinholeCamera {
    PinholeCamera::new(4, 3, 10.0, 10.0, 1.5, 1.0).unwrap()
}

/// A valid 4×3 dataset with two frames, colour, truth and a mask.
fn write_small(root: &Path) -> DatasetWriter {
    let w = DatasetWriter::create(root, &camera(), 0.001).unwrap();
    for (i, frame) in ["a", "b"].iter().enumerate() {
        let raw: Vec<u16> = (0..12)
            .map(|k| if k == 5 { 0 } else { 500 + 10 * k + i as u16 })
            .collect();
        w.write_depth(frame, &DepthImage::from_u16(4, 3, &raw, 0.001).unwrap())
            .unwrap();
        w.write_color(frame, &ColorImage::filled(4, 3, [200, 30, 20]))
            .unwrap();
    }
    let truth: FrameTruth = serde_json::from_str(
        r#"{"complete": true, "fruits": [{"id": "1", "kind": "pepper", "center_m": [0.0, 0.0, 0.5],
            "diameter_m": 0.08, "axis": [0, -1, 0], "bbox_px": [0, 0, 2, 2], "visibility": 0.75, "x_custom": 3}]}"#,
    )
    .unwrap();
    w.write_truth("a", &truth).unwrap();
    let mut mask = InstanceMask::background(4, 3);
    mask.set(1, 1, 1);
    w.write_mask("a", &mask).unwrap();
    w
}

#[test]
fn writer_output_reads_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    write_small(dir.path());
    let ds = Dataset::open(dir.path()).unwrap();
    assert_eq!(ds.frames(), ["a", "b"]);
    assert_eq!(ds.camera(), &camera());
    let rgbd = ds.load_frame("b").unwrap();
    assert_eq!(rgbd.depth().to_u16(0.001).unwrap()[..3], [501, 511, 521]);
    assert_eq!(rgbd.depth().get(1, 1), None);
    assert_eq!(rgbd.color().unwrap().get(3, 2), Some([200, 30, 20]));
    let truth = ds.load_truth("a").unwrap().unwrap();
    assert_eq!(truth.fruits[0].extra["x_custom"], 3);
    assert_eq!(truth.fruits[0].visibility, Some(0.75));
    assert!(ds.load_truth("b").unwrap().is_none());
    assert_eq!(ds.load_mask("a").unwrap().unwrap().get(1, 1), Some(1));
}

#[test]
fn depth_only_dataset_is_accepted() {
    let dir = tempfile::tempdir().unwrap();
    write_small(dir.path());
    std::fs::remove_dir_all(dir.path().join("color")).unwrap();
    let ds = Dataset::open(dir.path()).unwrap();
    assert!(!ds.has_color());
    assert!(ds.load_frame("a").unwrap().color().is_none());
}

#[test]
fn unknown_frame_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    write_small(dir.path());
    let ds = Dataset::open(dir.path()).unwrap();
    assert!(matches!(
        ds.load_frame("zz"),
        Err(DatasetError::UnknownFrame { .. })
    ));
}

fn broken(edit: impl FnOnce(&Path)) -> (tempfile::TempDir, Result<(), DatasetError>) {
    let dir = tempfile::tempdir().unwrap();
    write_small(dir.path());
    edit(dir.path());
    let result = Dataset::open(dir.path()).and_then(|ds| {
        for f in ds.frames() {
            ds.load_frame(f)?;
            ds.load_truth(f)?;
            ds.load_mask(f)?;
        }
        Ok(())
    });
    (dir, result)
}

fn assert_names_file(err: &DatasetError, file: &str) {
    let msg = err.to_string();
    assert!(msg.contains(file), "message `{msg}` should name {file}");
}

#[test]
fn truncated_png_is_an_image_error() {
    let (_d, r) = broken(|root| {
        let p = root.join("depth/b.png");
        let bytes = std::fs::read(&p).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    });
    let err = r.unwrap_err();
    assert!(matches!(err, DatasetError::Image { .. }), "{err:?}");
    assert_names_file(&err, "b.png");
}

#[test]
fn eight_bit_depth_is_rejected() {
    let (_d, r) = broken(|root| {
        image::GrayImage::from_raw(4, 3, vec![7; 12])
            .unwrap()
            .save(root.join("depth/a.png"))
            .unwrap();
    });
    let err = r.unwrap_err();
    assert!(
        matches!(err, DatasetError::DepthNotSixteenBit { ref found, .. } if found == "L8"),
        "{err:?}"
    );
    assert_names_file(&err, "a.png");
}

#[test]
fn colour_of_wrong_size_is_rejected() {
    let (_d, r) = broken(|root| {
        image::RgbImage::new(5, 3)
            .save(root.join("color/b.png"))
            .unwrap();
    });
    let err = r.unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::SizeMismatch {
                width: 5,
                expected_width: 4,
                ..
            }
        ),
        "{err:?}"
    );
    assert_names_file(&err, "color/b.png");
}

#[test]
fn nan_and_negative_intrinsics_are_rejected() {
    for bad in [r#""fx": NaN"#, r#""fx": -10.0"#, r#""fy": 0"#] {
        let (_d, r) = broken(|root| {
            let text = std::fs::read_to_string(root.join("camera.json")).unwrap();
            let text = text.replace(r#""fx": 10.0"#, bad).replace(
                r#""fy": 10.0"#,
                if bad.contains("fy") {
                    bad
                } else {
                    r#""fy": 10.0"#
                },
            );
            std::fs::write(root.join("camera.json"), text).unwrap();
        });
        let err = r.unwrap_err();
        // serde_json has no NaN literal: that case is a JSON error; the others are range errors.
        assert!(
            matches!(
                err,
                DatasetError::InvalidCamera { .. } | DatasetError::Json { .. }
            ),
            "{bad}: {err:?}"
        );
        assert_names_file(&err, "camera.json");
    }
}

#[test]
fn bad_depth_unit_is_rejected() {
    let (_d, r) = broken(|root| {
        let text = std::fs::read_to_string(root.join("camera.json")).unwrap();
        std::fs::write(root.join("camera.json"), text.replace("0.001", "-1")).unwrap();
    });
    assert!(matches!(r.unwrap_err(), DatasetError::InvalidCamera { .. }));
}

#[test]
fn unpaired_frames_are_rejected() {
    let (_d, r) = broken(|root| std::fs::remove_file(root.join("depth/b.png")).unwrap());
    let err = r.unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::UnpairedFrame {
                missing: "depth",
                ..
            }
        ),
        "{err:?}"
    );
    assert_names_file(&err, "b.png");
    let (_d, r) = broken(|root| std::fs::remove_file(root.join("color/a.png")).unwrap());
    assert!(matches!(
        r.unwrap_err(),
        DatasetError::UnpairedFrame {
            missing: "colour",
            ..
        }
    ));
}

#[test]
fn duplicate_stems_are_rejected() {
    let (_d, r) = broken(|root| {
        std::fs::copy(root.join("color/a.png"), root.join("color/a.jpg"))
            .map(|_| ())
            .unwrap()
    });
    assert!(matches!(
        r.unwrap_err(),
        DatasetError::DuplicateFrame { .. }
    ));
}

#[test]
fn missing_pieces_are_named() {
    let (_d, r) = broken(|root| std::fs::remove_file(root.join("camera.json")).unwrap());
    let err = r.unwrap_err();
    assert!(matches!(err, DatasetError::Missing { .. }));
    assert_names_file(&err, "camera.json");
    let (_d, r) = broken(|root| {
        std::fs::remove_dir_all(root.join("depth")).unwrap();
        std::fs::remove_dir_all(root.join("color")).unwrap();
    });
    let err = r.unwrap_err();
    assert!(matches!(err, DatasetError::Missing { .. }));
    assert_names_file(&err, "depth");
}

#[test]
fn a_dataset_without_depth_is_colour_only() {
    let dir = tempfile::tempdir().unwrap();
    write_small(dir.path());
    let with_depth = Dataset::open(dir.path()).unwrap();
    let before: Vec<_> = with_depth
        .frames()
        .iter()
        .map(|f| {
            let color = with_depth.load_color(f).unwrap();
            (f.clone(), color, with_depth.load_truth(f).unwrap())
        })
        .collect();
    std::fs::remove_dir_all(dir.path().join("depth")).unwrap();
    let ds = Dataset::open(dir.path()).unwrap();
    assert!(!ds.has_depth() && ds.has_color());
    assert_eq!(ds.frames(), with_depth.frames());
    for (f, color, truth) in before {
        let frame = ds.load_frame(&f).unwrap();
        assert!(frame.depth().as_slice().iter().all(|z| z.is_nan()));
        assert_eq!(frame.color(), color.as_ref());
        assert_eq!(ds.load_truth(&f).unwrap(), truth);
    }
    assert!(matches!(
        ds.load_frame("no-such-frame"),
        Err(DatasetError::UnknownFrame { .. })
    ));
}

#[test]
fn malformed_truth_is_a_json_error() {
    for bad in [
        r#"{"fruits": []}"#,
        r#"{"complete": true, "fruits": [{"id": "1", "kind": "x", "axis": [0,0,0]}]}"#,
        "{",
    ] {
        let (_d, r) = broken(|root| std::fs::write(root.join("truth/a.json"), bad).unwrap());
        let err = r.unwrap_err();
        assert!(matches!(err, DatasetError::Json { .. }), "{bad}: {err:?}");
        assert_names_file(&err, "a.json");
    }
}

#[test]
fn absurd_png_size_is_rejected_before_decoding() {
    // A PNG header claiming 100000 x 100000 pixels in a few bytes: the size check against
    // camera.json fires before any pixel memory is allocated.
    let (_d, r) = broken(|root| {
        let mut png = Vec::new();
        png.extend_from_slice(b"\x89PNG\r\n\x1a\n");
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(b"IHDR");
        ihdr.extend_from_slice(&100_000u32.to_be_bytes());
        ihdr.extend_from_slice(&100_000u32.to_be_bytes());
        ihdr.extend_from_slice(&[16, 0, 0, 0, 0]);
        png.extend_from_slice(&13u32.to_be_bytes());
        png.extend_from_slice(&ihdr);
        png.extend_from_slice(&crc32(&ihdr).to_be_bytes());
        std::fs::write(root.join("depth/a.png"), png).unwrap();
    });
    let err = r.unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::SizeMismatch { width: 100_000, .. } | DatasetError::Image { .. }
        ),
        "{err:?}"
    );
}

#[test]
fn failed_write_keeps_existing_file() {
    let dir = tempfile::tempdir().unwrap();
    let w = write_small(dir.path());
    let before = std::fs::read(dir.path().join("depth/a.png")).unwrap();
    let err = w.write_depth("a", &DepthImage::empty(5, 5)).unwrap_err();
    assert!(matches!(err, DatasetError::SizeMismatch { .. }));
    assert_eq!(
        std::fs::read(dir.path().join("depth/a.png")).unwrap(),
        before
    );
}

/// CRC-32 (IEEE) for hand-built PNG chunks.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}
