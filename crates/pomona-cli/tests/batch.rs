//! Batches of frames through the `pomona` binary: a corrupt frame is isolated and reported, a
//! killed run resumes to byte-identical output, output folders never mix two models, detections
//! do not depend on the number of threads, and the `pomona` library returns exactly what
//! `pomona detect` writes.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

#[path = "support/run.rs"]
mod run;
use run::{detect, files, pomona, stderr, synth_dataset};

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use rand::{Rng, SeedableRng};

/// How many `.json` files `dir` holds now (while a run may be writing into it).
fn json_count(dir: &Path) -> usize {
    std::fs::read_dir(dir).map_or(0, |entries| {
        entries
            .filter_map(Result::ok)
            .filter(|e| e.path().extension().is_some_and(|x| x == "json"))
            .count()
    })
}

fn frame_names(data: &Path) -> Vec<String> {
    pomona_io::Dataset::open(data).unwrap().frames().to_vec()
}

#[test]
fn a_corrupt_frame_is_listed_in_failures_json_and_every_other_frame_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth_dataset(&data, 3, 5);
    let frames = frame_names(&data);
    let bad = data.join("depth").join(format!("{}.png", frames[1]));
    std::fs::write(&bad, b"\x89PNG\r\n\x1a\n truncated").unwrap();
    let out_dir = dir.path().join("det");

    let out = detect("shape-fit", &data, &out_dir, &[]);
    assert_eq!(out.status.code(), Some(3), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("1 of 3 frame(s) failed"),
        "{}",
        stderr(&out)
    );
    let written = files(&out_dir);
    for (k, f) in frames.iter().enumerate() {
        assert_eq!(written.contains_key(&format!("{f}.json")), k != 1, "{f}");
    }
    let failures: serde_json::Value = serde_json::from_slice(&written["failures.json"]).unwrap();
    let listed = &failures["failures"];
    assert_eq!(listed.as_array().map(Vec::len), Some(1), "{failures}");
    assert_eq!(listed[0]["frame"], frames[1].as_str());
    assert_eq!(listed[0]["file"], bad.to_str().unwrap());
    assert!(
        listed[0]["error"].as_str().unwrap().contains("png"),
        "{failures}"
    );

    // `pomona eval` still reads the folder (failures.json is not a frame) and says what is missing.
    let eval = pomona(&[
        "eval",
        "--data",
        data.to_str().unwrap(),
        "--detections",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        !stderr(&eval).contains("failures"),
        "eval took failures.json for a frame: {}",
        stderr(&eval)
    );

    // Repaired, a resumed run does the missing frame only and removes the failure list.
    synth_dataset(&dir.path().join("fresh"), 3, 5);
    std::fs::copy(
        dir.path()
            .join("fresh/depth")
            .join(format!("{}.png", frames[1])),
        &bad,
    )
    .unwrap();
    let out = detect("shape-fit", &data, &out_dir, &["--resume"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("2 already done"));
    let written = files(&out_dir);
    assert!(!written.contains_key("failures.json"));
    assert_eq!(written.len(), 3);
}

#[test]
fn a_run_killed_at_random_moments_and_resumed_matches_an_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth_dataset(&data, 12, 9);
    let reference = dir.path().join("reference");
    let started = Instant::now();
    let out = detect("shape-fit", &data, &reference, &["--threads", "1"]);
    let full = started.elapsed();
    assert!(out.status.success(), "{}", stderr(&out));
    let expected = files(&reference);
    assert_eq!(expected.len(), 12);

    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2026);
    let mut interrupted = 0;
    for attempt in 0..5 {
        let out_dir = dir.path().join(format!("killed-{attempt}"));
        // A random moment: after a random number of frames are written, plus a random part of
        // one frame's time (so kills land while loading, detecting or writing).
        let after_frames = rng.gen_range(0..expected.len() - 1);
        let extra = full.mul_f64(rng.gen_range(0.0..1.0) / expected.len() as f64);
        let mut child = Command::new(env!("CARGO_BIN_EXE_pomona"))
            .args([
                "detect",
                "--pipeline",
                "shape-fit",
                "--data",
                data.to_str().unwrap(),
                "--out",
                out_dir.to_str().unwrap(),
                "--threads",
                "1",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        while json_count(&out_dir) < after_frames && child.try_wait().unwrap().is_none() {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        std::thread::sleep(extra);
        child.kill().unwrap(); // SIGKILL on Unix
        child.wait().unwrap();
        let left = files(&out_dir).len();
        interrupted += usize::from(left > 0 && left < expected.len());
        let out = detect(
            "shape-fit",
            &data,
            &out_dir,
            &["--resume", "--threads", "1"],
        );
        assert!(out.status.success(), "attempt {attempt}: {}", stderr(&out));
        assert_eq!(
            files(&out_dir),
            expected,
            "attempt {attempt} (killed after {after_frames} frames + {extra:?})"
        );
    }
    assert!(
        interrupted >= 3,
        "only {interrupted} of 5 kills landed mid-run (a run takes {full:?})"
    );
}

#[test]
fn an_output_folder_of_another_model_is_refused_unless_it_is_this_runs() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth_dataset(&data, 1, 3);
    let out_dir = dir.path().join("det");
    assert!(detect("shape-fit", &data, &out_dir, &[]).status.success());
    // Same run again: rewritten in place.
    assert!(detect("shape-fit", &data, &out_dir, &[]).status.success());
    for other in [
        vec!["--set", "params.shapes.msac.iterations=123"],
        vec!["--min-confidence", "0"],
    ] {
        let out = detect("shape-fit", &data, &out_dir, &other);
        assert_eq!(out.status.code(), Some(1), "{other:?}");
        assert!(stderr(&out).contains("refusing to mix"), "{}", stderr(&out));
        let out = detect(
            "shape-fit",
            &data,
            &out_dir,
            &[&["--resume"], &other[..]].concat(),
        );
        assert_eq!(out.status.code(), Some(1), "{other:?} with --resume");
    }
    let out = detect("symmetry", &data, &out_dir, &[]);
    assert!(
        stderr(&out).contains("pipeline `shape-fit`"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn shards_writing_into_one_folder_make_exactly_the_unsharded_files_and_resume() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth_dataset(&data, 7, 41);
    let whole = dir.path().join("whole");
    assert!(detect("shape-fit", &data, &whole, &[]).status.success());
    let expected = files(&whole);
    assert_eq!(expected.len(), 7);

    let sharded = dir.path().join("sharded");
    for i in 0..3 {
        let shard = format!("{i}/3");
        let out = detect("shape-fit", &data, &sharded, &["--shard", &shard]);
        assert!(out.status.success(), "{shard}: {}", stderr(&out));
        let done = files(&sharded).len();
        assert_eq!(done, [3, 5, 7][i], "after shard {shard}");
    }
    assert_eq!(files(&sharded), expected, "byte for byte");

    // A shard run again with --resume skips its frames; one frame lost is redone.
    let frames = frame_names(&data);
    std::fs::remove_file(sharded.join(format!("{}.json", frames[4]))).unwrap();
    let out = detect(
        "shape-fit",
        &data,
        &sharded,
        &["--shard", "1/3", "--resume"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let said = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        said.contains("1 frame(s) (shard 1/3)") && said.contains("1 already done"),
        "{said}"
    );
    assert_eq!(files(&sharded), expected);

    // Each shard lists its own failures, which `pomona eval` does not take for frames.
    for f in &frames[2..4] {
        std::fs::write(data.join("depth").join(format!("{f}.png")), b"not a png").unwrap();
    }
    let broken = dir.path().join("broken");
    for shard in ["0/2", "1/2"] {
        let out = detect("shape-fit", &data, &broken, &["--shard", shard]);
        assert_eq!(out.status.code(), Some(3), "{shard}: {}", stderr(&out));
    }
    let written = files(&broken);
    for (name, frame) in [
        ("failures.shard-0-of-2.json", &frames[2]),
        ("failures.shard-1-of-2.json", &frames[3]),
    ] {
        let listed: serde_json::Value = serde_json::from_slice(&written[name]).unwrap();
        assert_eq!(listed["failures"][0]["frame"], frame.as_str(), "{name}");
        assert_eq!(
            listed["failures"].as_array().map(Vec::len),
            Some(1),
            "{name}"
        );
    }
    assert!(!written.contains_key("failures.json"));
    let eval = pomona(&[
        "eval",
        "--data",
        data.to_str().unwrap(),
        "--detections",
        broken.to_str().unwrap(),
    ]);
    assert!(!stderr(&eval).contains("failures"), "{}", stderr(&eval));

    let out = detect("shape-fit", &data, &broken, &["--shard", "2/2"]);
    assert_eq!(out.status.code(), Some(2), "clap's usage error");
    assert!(stderr(&out).contains("0-based"), "{}", stderr(&out));
}

#[test]
fn detections_do_not_depend_on_the_number_of_threads() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth_dataset(&data, 2, 21);
    for p in pomona::pipelines() {
        let name = p.name();
        let one = dir.path().join(format!("{name}-1"));
        let two = dir.path().join(format!("{name}-2"));
        for (out_dir, threads) in [(&one, "1"), (&two, "2")] {
            let out = detect(name, &data, out_dir, &["--threads", threads]);
            assert!(out.status.success(), "{name}: {}", stderr(&out));
        }
        assert_eq!(files(&one), files(&two), "{name}");
    }
}

#[test]
fn the_library_returns_exactly_what_pomona_detect_writes_unthresholded() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth_dataset(&data, 2, 33);
    let out_dir = dir.path().join("det");
    let out = detect("shape-fit", &data, &out_dir, &["--min-confidence", "0"]);
    assert!(out.status.success(), "{}", stderr(&out));

    // What a robot program writes: the README's "Use as a library" lines.
    let dataset = pomona::Dataset::open(&data).unwrap();
    let detector = pomona::Detector::builtin("shape-fit").unwrap();
    for stem in dataset.frames() {
        let frame = dataset.load_frame(stem).unwrap();
        let found = detector.detect(&frame).unwrap();

        let path: PathBuf = out_dir.join(format!("{stem}.json"));
        let file: pomona::FrameDetections =
            serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        assert!(!found.is_empty(), "{stem}: nothing to compare");
        assert_eq!(found, file.detections, "{stem}");
        assert_eq!(file.model_id.as_deref(), Some(detector.model().id.as_str()));
    }
}
