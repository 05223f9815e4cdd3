//! End-to-end tests of `pomona stereo`: a hand-made two-shot dataset (orange discs drawn where
//! the rig projects known spheres, colour only, no depth) is matched and located, and the
//! detection files score against the primary truth.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

#[path = "support/run.rs"]
mod run;
use run::{pomona, stderr, stdout};

use std::path::Path;
use std::process::Output;

use pomona_arm::RotatedStereo;
use pomona_core::nalgebra::Point3;
use pomona_core::{ColorImage, FrameDetections, FrameTruth, PinholeCamera};
use pomona_io::DatasetWriter;
use pomona_synth::StereoRig;

const LEAF: [u8; 3] = [40, 80, 30];
const ORANGE: [u8; 3] = [235, 120, 15];
const RADIUS_M: f64 = 0.04;

/// Fruit centres (primary camera frame) of the two frames.
fn fruit(frame: usize) -> Vec<Point3<f64>> {
    match frame {
        0 => vec![
            Point3::new(-0.15, -0.05, 0.9),
            Point3::new(0.05, 0.06, 1.0),
            Point3::new(0.2, -0.08, 1.1),
        ],
        _ => vec![Point3::new(-0.05, 0.0, 0.85), Point3::new(0.15, 0.1, 1.2)],
    }
}

/// Draws each sphere's image as a filled disc of radius f·R/z.
fn draw(camera: &PinholeCamera, centres: &[Point3<f64>]) -> ColorImage {
    let mut image = ColorImage::filled(camera.width, camera.height, LEAF);
    for c in centres {
        let px = camera.project(c).unwrap();
        let r = camera.fx * RADIUS_M / c.z;
        for v in 0..camera.height {
            for u in 0..camera.width {
                let (du, dv) = (f64::from(u) - px.x, f64::from(v) - px.y);
                if du * du + dv * dv <= r * r {
                    image.set(u, v, ORANGE);
                }
            }
        }
    }
    image
}

fn truth(centres: &[Point3<f64>]) -> FrameTruth {
    let fruits: Vec<serde_json::Value> = centres
        .iter()
        .enumerate()
        .map(|(i, c)| {
            serde_json::json!({"id": format!("f{i}"), "kind": "orange",
                "center_m": [c.x, c.y, c.z], "diameter_m": 2.0 * RADIUS_M, "visibility": 1.0})
        })
        .collect();
    serde_json::from_value(serde_json::json!({"complete": true, "fruits": fruits})).unwrap()
}

/// Both views of two frames, `rig.json`, truth in each view's frame; colour only.
fn stereo_dataset(root: &Path) -> RotatedStereo {
    let camera = PinholeCamera::new(320, 240, 300.0, 300.0, 159.5, 119.5).unwrap();
    let synth_rig = StereoRig {
        beta_rad: 6f64.to_radians(),
        pivot_distance_m: 0.3,
    };
    let rig = RotatedStereo::new(synth_rig.beta_rad, synth_rig.pivot_distance_m, camera).unwrap();
    let primary = DatasetWriter::create(root, &camera, 0.001).unwrap();
    let stereo = DatasetWriter::create(root.join("stereo"), &camera, 0.001).unwrap();
    for frame in 0..2 {
        let stem = format!("{frame:06}");
        let here = fruit(frame);
        let there: Vec<Point3<f64>> = here.iter().map(|p| rig.stereo_from_camera() * p).collect();
        primary.write_color(&stem, &draw(&camera, &here)).unwrap();
        primary.write_truth(&stem, &truth(&here)).unwrap();
        stereo.write_color(&stem, &draw(&camera, &there)).unwrap();
        stereo.write_truth(&stem, &truth(&there)).unwrap();
    }
    pomona_io::write_json(&root.join("rig.json"), &synth_rig.to_file()).unwrap();
    rig
}

/// Runs `pomona stereo --data ds --out det` with `extra` options.
fn stereo(ds: &Path, det: &Path, extra: &[&str]) -> Output {
    let base = [
        "stereo",
        "--data",
        ds.to_str().unwrap(),
        "--out",
        det.to_str().unwrap(),
    ];
    pomona(&[&base[..], extra].concat())
}

#[test]
fn stereo_locates_every_fruit_from_the_two_colour_shots() {
    let dir = tempfile::tempdir().unwrap();
    let (ds, det) = (dir.path().join("ds"), dir.path().join("det"));
    stereo_dataset(&ds);
    for method in ["paper", "triangulate"] {
        let report = dir.path().join(format!("{method}.json"));
        let extra = ["--method", method, "--reach-m", "0.6,2.0"];
        let out = stereo(
            &ds,
            &det,
            &[&extra[..], &["--report", report.to_str().unwrap()]].concat(),
        );
        assert!(out.status.success(), "{}", stderr(&out));
        assert!(stdout(&out).contains("5 fruit located"), "{}", stdout(&out));
        for frame in 0..2 {
            let text = std::fs::read_to_string(det.join(format!("{frame:06}.json"))).unwrap();
            let found: FrameDetections = serde_json::from_str(&text).unwrap();
            assert_eq!(found.pipeline, "color-contour-stereo");
            let truth = fruit(frame);
            assert_eq!(
                found.detections.len(),
                truth.len(),
                "{method} frame {frame}"
            );
            for t in &truth {
                let nearest = found
                    .detections
                    .iter()
                    .map(|d| (d.center_m - t).norm())
                    .fold(f64::INFINITY, f64::min);
                assert!(nearest < 0.03, "{method}: {t} found only {nearest} m away");
            }
            for d in &found.detections {
                let diameter = d.diameter_m.unwrap();
                assert!((diameter - 2.0 * RADIUS_M).abs() < 0.02, "{diameter}");
            }
        }
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert_eq!(report["matching"]["correct"], 5, "{report}");
        assert_eq!(report["matching"]["precision"], 1.0);
        assert_eq!(report["matching"]["recall"], 1.0);
        assert!(report["exact"]["max_error_um"].as_f64().unwrap() < 1.0);
        assert_eq!(report["exact"]["fruit"], 5);
        // Every fruit lies beyond 0.8 m, wholly visible: all in the last visibility band.
        let bands = report["centre_error"]["by_visibility"].as_array().unwrap();
        let counts: Vec<u64> = bands.iter().map(|b| b["n"].as_u64().unwrap()).collect();
        assert_eq!(counts, [0, 0, 0, 5], "{report}");
        let along = bands[3]["along_ray_median_mm"].as_f64().unwrap();
        let median = bands[3]["median_mm"].as_f64().unwrap();
        assert!(along.abs() <= median && median < 30.0, "{along} {median}");
        // The primary truth scores the files: every fruit found (matched in 3D).
        let eval = pomona(&[
            "eval",
            "--data",
            ds.to_str().unwrap(),
            "--detections",
            det.to_str().unwrap(),
        ]);
        assert!(eval.status.success(), "{}", stderr(&eval));
    }
    // --overlay: both shots side by side per frame, paired circles in red.
    let overlays = dir.path().join("overlays");
    let out = stereo(
        &ds,
        &det,
        &[
            "--reach-m",
            "0.6,2.0",
            "--overlay",
            overlays.to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    for frame in 0..2 {
        let png = overlays.join(format!("{frame:06}.png"));
        // The reader checks the size: both 320 × 240 shots side by side.
        let image = pomona_io::read_color_image(&png, (640, 240)).unwrap();
        let red = image
            .pixels()
            .filter(|&[r, g, b]| r > 200 && g < 60 && b < 60)
            .count();
        assert!(red > 50, "frame {frame}: {red} red pixels");
    }
}

/// The row gate keeps every pair of discs drawn where the rig puts them (their rows agree to a
/// fraction of a pixel), so does the seed's relaxation alone, and out-of-range matching
/// parameters are refused by name.
#[test]
fn the_row_gate_keeps_consistent_pairs_and_bad_matching_parameters_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (ds, det) = (dir.path().join("ds"), dir.path().join("det"));
    stereo_dataset(&ds);
    // The row gate; and the seed's relaxation alone (no check for a better match elsewhere):
    // the discs are flat, so the default check has nothing to compare and removes nothing.
    for option in [
        ["--match-max-row-px", "1.5"],
        ["--match-better-elsewhere", "off"],
        ["--match-leftovers", "off"],
        ["--match-leftovers", "2"],
    ] {
        let out = stereo(
            &ds,
            &det,
            &[&["--reach-m", "0.6,2.0"][..], &option].concat(),
        );
        assert!(out.status.success(), "{option:?}: {}", stderr(&out));
        assert!(
            stdout(&out).contains("5 fruit located"),
            "{option:?}: {}",
            stdout(&out)
        );
    }
    for (flag, name) in [
        ("--match-better-elsewhere=3", "better_elsewhere.margin"),
        (
            "--match-elsewhere-radii=-1",
            "better_elsewhere.min_distance_radii",
        ),
        ("--match-leftovers=-1", "max_distance_radii"),
        ("--match-leftovers-min-ncc=2", "min_ncc"),
        // The refinement's sweep spacing: positive and no wider than the sweep.
        ("--refine-step-px=0", "step_px"),
        ("--refine-step-px=7", "step_px"),
    ] {
        let bad = stereo(&ds, &det, &[flag]);
        assert!(!bad.status.success(), "{flag}");
        assert!(stderr(&bad).contains(name), "{flag}: {}", stderr(&bad));
    }
    let bad = stereo(&ds, &det, &["--match-max-row-px=-1"]);
    assert!(!bad.status.success());
    assert!(
        stderr(&bad).contains("max_row_residual_px"),
        "{}",
        stderr(&bad)
    );
}

#[test]
fn stereo_without_a_rig_names_the_missing_file() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dir.path().join("ds");
    stereo_dataset(&ds);
    std::fs::remove_file(ds.join("rig.json")).unwrap();
    let out = stereo(&ds, &dir.path().join("det"), &[]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("rig.json"), "{}", stderr(&out));
}

/// The refinement (the default) end to end on rendered (shaded) oranges: every located pair is
/// either refined or kept with a named reason, some are refined, and the detection files are
/// written; `--no-refine` locates from the circle centres only.
#[test]
fn refine_accounts_for_every_pair_on_rendered_oranges() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let out = pomona(&[
        "synth",
        "--out",
        ds.to_str().unwrap(),
        "--frames",
        "3",
        "--seed",
        "1",
        "--domain",
        "orchard",
        "--fruit",
        "orange",
        "--camera",
        "d435",
        "--noise",
        "none",
        "--stereo",
        "--stereo-beta-deg",
        "8",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let det = tmp.path().join("det");
    let report = tmp.path().join("report.json");
    let out = stereo(
        &ds,
        &det,
        &[
            "--method",
            "triangulate",
            "--report",
            report.to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("refined by appearance"),
        "{}",
        stdout(&out)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let refined = report["refinement"]["refined"].as_u64().unwrap();
    let kept: u64 = report["refinement"]["fallback"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    let pairs = report["matching"]["pairs"].as_u64().unwrap();
    assert!(refined > 0, "{report}");
    assert_eq!(refined + kept, pairs, "{report}");
    assert!(std::fs::read_dir(&det).unwrap().count() >= 3);
    let circles = tmp.path().join("circles.json");
    let out = stereo(
        &ds,
        &tmp.path().join("det-circles"),
        &["--no-refine", "--report", circles.to_str().unwrap()],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!stdout(&out).contains("refined"), "{}", stdout(&out));
    let circles: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&circles).unwrap()).unwrap();
    assert!(circles["refinement"].is_null(), "{circles}");
    assert_eq!(circles["matching"]["pairs"], report["matching"]["pairs"]);
}
