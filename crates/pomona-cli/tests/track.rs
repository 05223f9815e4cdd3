//! `pomona synth --approach` and `pomona track` through the binary: approach sequences are
//! written as datasets with their target, and the tracker follows the target to the last frame;
//! `--start` follows the fruit under a pixel through one dataset.

#![allow(clippy::unwrap_used)]

#[path = "support/run.rs"]
mod run;

use run::{pomona, stderr, stdout};

#[test]
fn approach_sequences_are_tracked_to_the_target() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("approach");
    let data_s = data.to_str().unwrap();
    let out = pomona(&[
        "synth",
        "--out",
        data_s,
        "--approach",
        "3",
        "--frames",
        "12",
        "--seed",
        "21",
        "--domain",
        "orchard",
        "--fruit",
        "orange",
        "--camera",
        "sr4000",
        "--sway",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("3 approach sequences"),
        "{}",
        stdout(&out)
    );
    for s in 0..3 {
        let seq = data.join(format!("seq-{s:04}"));
        assert!(seq.join("approach.json").exists());
        assert!(seq.join("color/000011.png").exists());
    }

    let tracks = dir.path().join("tracks");
    let report = dir.path().join("report.json");
    let report_s = report.to_str().unwrap();
    let tracks_s = tracks.to_str().unwrap();
    // `pomona track` on `data` into `out`, with `extra` arguments.
    let track_into = |data: &std::path::Path, out: &str, extra: &[&str]| {
        let mut args = vec!["track", "--data", data.to_str().unwrap(), "--out", out];
        args.extend_from_slice(extra);
        pomona(&args)
    };
    // … on the sequences of `folder` into `tracks`.
    let track_in = |folder: &std::path::Path, extra: &[&str]| track_into(folder, tracks_s, extra);
    // The same on the rendered sequences from the truth; the report.
    let track_from_truth = |extra: &[&str]| {
        let out = track_in(
            &data,
            &[&["--json", report_s, "--init", "truth"], extra].concat(),
        );
        assert!(out.status.success(), "{}", stderr(&out));
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(report_s).unwrap())
            .unwrap()
    };
    let report = track_from_truth(&[]);
    assert_eq!(report["sequences"], 3);
    assert_eq!(report["frames"], 36);
    let rate = report["success_rate"].as_f64().unwrap();
    assert!(rate >= 2.0 / 3.0, "success rate {rate}: {report}");
    assert!(report["ms_per_frame"].as_f64().unwrap() > 0.0);
    let track: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tracks.join("seq-0000.json")).unwrap())
            .unwrap();
    assert_eq!(track["frames"].as_array().unwrap().len(), 12);
    assert!(track["frames"][11]["error_radii"].is_number(), "{track}");
    assert_eq!(report["params"]["scan_threshold_fraction"], 0.75);
    assert_eq!(report["params"]["redetect"], "on-doubt");
    assert_eq!(report["params"]["max_search_radii"], 2.0);
    // Started from the truth: every track starts on its target, with no error.
    assert_eq!(report["started_on_target"], 3, "{report}");
    assert_eq!(
        report["per_sequence"][0]["init_error_radii"], 0.0,
        "{report}"
    );

    // Your own frames: one sequence as a plain dataset, the fruit under a pixel followed from
    // the detection covering it, scored against the truth fruit there; overlays drawn.
    let seq = data.join("seq-0001");
    let first: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tracks.join("seq-0001.json")).unwrap())
            .unwrap();
    let at = &first["frames"][0]["truth_center_px"];
    let start = format!("{},{}", at[0], at[1]);
    let own = dir.path().join("own");
    let overlays = dir.path().join("overlays");
    // … on the one dataset `seq` into `own` (`--start` and the rest in `extra`).
    let own_track = |extra: &[&str]| track_into(&seq, own.to_str().unwrap(), extra);
    let out = own_track(&["--start", &start, "--overlay", overlays.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let track: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(own.join("track.json")).unwrap()).unwrap();
    assert_eq!(track["target_id"], first["target_id"], "{track}");
    assert_eq!(track["init"], "detection");
    assert!(
        track["init_error_radii"].as_f64().unwrap() <= 0.5,
        "{track}"
    );
    assert!(track["success"].is_boolean(), "{track}");
    assert_eq!(track["frames"].as_array().unwrap().len(), 12);
    assert!(overlays.join("000000.png").exists() && overlays.join("000011.png").exists());
    // With a radius the circle itself starts the track; a pixel outside the frames, or one no
    // detection covers, is an error that says what to do.
    let out = own_track(&["--start", &format!("{start},15")]);
    assert!(out.status.success(), "{}", stderr(&out));
    let track: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(own.join("track.json")).unwrap()).unwrap();
    assert_eq!(track["init"], "circle");
    assert_eq!(track["init_circle_px"][2], 15.0);
    // --init belongs to approach sequences.
    let out = own_track(&["--start", &start, "--init", "truth"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("--init"), "{}", stderr(&out));
    let out = own_track(&["--start", "5000,10"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("outside"), "{}", stderr(&out));
    for bad in ["1,2,-3", "1;2", "x,2"] {
        let out = own_track(&["--start", bad]);
        assert!(!out.status.success(), "{bad}");
        assert!(stderr(&out).contains("--start"), "{bad}: {}", stderr(&out));
    }
    // Truth annotated only in the image (as real frames marked by hand are) scores the track
    // too: the same frames with `center_m` and `diameter_m` removed from every fruit.
    let with_3d = own_track(&["--start", &start]);
    assert!(with_3d.status.success(), "{}", stderr(&with_3d));
    let scored_3d: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(own.join("track.json")).unwrap()).unwrap();
    for entry in std::fs::read_dir(seq.join("truth")).unwrap() {
        let path = entry.unwrap().path();
        let mut truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        for fruit in truth["fruits"].as_array_mut().unwrap() {
            let fruit = fruit.as_object_mut().unwrap();
            assert!(fruit.contains_key("center_px") && fruit.contains_key("radius_px"));
            fruit.remove("center_m");
            fruit.remove("diameter_m");
        }
        std::fs::write(&path, truth.to_string()).unwrap();
    }
    let out = own_track(&["--start", &start]);
    assert!(out.status.success(), "{}", stderr(&out));
    let scored_2d: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(own.join("track.json")).unwrap()).unwrap();
    assert_eq!(scored_2d["target_id"], scored_3d["target_id"]);
    assert!(scored_2d["success"].is_boolean(), "{scored_2d}");
    for (a, b) in scored_2d["frames"]
        .as_array()
        .unwrap()
        .iter()
        .zip(scored_3d["frames"].as_array().unwrap())
    {
        assert_eq!(a["center_px"], b["center_px"]);
        let (ea, eb) = (
            a["error_radii"].as_f64().unwrap(),
            b["error_radii"].as_f64().unwrap(),
        );
        // Both are scored against the annotated circle (`FruitTruth::image_circle` takes
        // `center_px` and `radius_px` before the sphere), so the errors agree.
        assert!((ea - eb).abs() < 0.1, "{a} {b}");
    }

    // A first frame of plain grey has no detection to start from.
    let first_png = seq.join("color/000000.png");
    let camera: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(seq.join("camera.json")).unwrap()).unwrap();
    let size = |key: &str| u32::try_from(camera[key].as_u64().unwrap()).unwrap();
    let (w, h) = (size("width"), size("height"));
    pomona_io::write_color_png(&first_png, &pomona_core::ColorImage::filled(w, h, [90; 3]))
        .unwrap();
    let out = own_track(&["--start", &start]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("no detection") && stderr(&out).contains("--start X,Y,R"),
        "{}",
        stderr(&out)
    );

    // `--set` overrides a tracker parameter, recorded in the report; a typo or an invalid
    // value is an error that says so.
    let report = track_from_truth(&[
        "--set",
        "scan_threshold_fraction=1.0",
        "--set",
        "edge_scan.gap_px=3",
    ]);
    assert_eq!(report["params"]["scan_threshold_fraction"], 1.0);
    assert_eq!(report["params"]["edge_scan"]["gap_px"], 3);
    // The local re-detection every frame (and no image patch to overrule it): most frames are
    // found by it.
    let report = track_from_truth(&["--set", r#"redetect="always""#, "--set", "patch_shift=null"]);
    assert_eq!(report["params"]["redetect"], "always");
    let redetected = report["redetected_frames"].as_u64().unwrap();
    assert!(redetected > 18, "{report}");
    let rate = report["success_rate"].as_f64().unwrap();
    assert!(rate >= 2.0 / 3.0, "success rate {rate}: {report}");
    for (set, says) in [
        ("scan_fraction=1.0", "scan_fraction"),
        ("scan_threshold_fraction=0", "scan_threshold_fraction"),
        ("local_redetect.max_radius_ratio=0.5", "max_radius_ratio"),
        (r#"redetect="sometimes""#, "sometimes"),
    ] {
        let out = track_in(&data, &["--set", set]);
        assert!(!out.status.success());
        assert!(stderr(&out).contains(says), "{set}: {}", stderr(&out));
    }

    // A sequence whose target is not in its truth is not tracked, and says so with the id; the
    // summary of no tracked frame reads 0, not -0.
    // (The rendered sequence is moved into a folder of its own: nothing below tracks `data`.)
    let only = dir.path().join("only");
    std::fs::create_dir(&only).unwrap();
    let seq = only.join("seq-0000");
    std::fs::rename(data.join("seq-0000"), &seq).unwrap();
    let record = seq.join("approach.json");
    let mut approach: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&record).unwrap()).unwrap();
    approach["target_id"] = "no-such-fruit".into();
    std::fs::write(&record, approach.to_string()).unwrap();
    let out = track_in(&only, &["--init", "truth"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("seq-0000: not tracked") && stderr(&out).contains("no-such-fruit"),
        "{}",
        stderr(&out)
    );
    assert!(
        stdout(&out).contains("0 of 1") && !stdout(&out).contains("-0.0"),
        "{}",
        stdout(&out)
    );

    // Tracking a folder without sequences is an error naming it.
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let out = track_in(&empty, &[]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("empty"), "{}", stderr(&out));
}
