//! The cluster recipes in `deploy/` run `pomona detect --shard` as they claim: the Slurm array
//! script and the Kubernetes Indexed Job's command, run here once per task index with the
//! variables the scheduler would set, write exactly the files of one unsharded run.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

#[path = "support/run.rs"]
mod run;
use run::{detect, files, stderr, synth_dataset};

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A dataset of `frames` frames and the files of one unsharded `pomona detect` over it.
fn reference(dir: &Path, frames: u32) -> (PathBuf, BTreeMap<String, Vec<u8>>) {
    let data = dir.join("data");
    synth_dataset(&data, frames, 17);
    let whole = dir.join("whole");
    let out = detect("shape-fit", &data, &whole, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    (data, files(&whole))
}

#[test]
fn the_slurm_array_script_makes_the_unsharded_files() {
    let dir = tempfile::tempdir().unwrap();
    let (data, expected) = reference(dir.path(), 5);
    let out_dir = dir.path().join("slurm");
    let script = repo().join("deploy/slurm/pomona-detect.sbatch");
    for task in 0..3 {
        let out = Command::new("bash")
            .arg(&script)
            .env("POMONA", env!("CARGO_BIN_EXE_pomona"))
            .env("POMONA_DATA", &data)
            .env("POMONA_OUT", &out_dir)
            .env("SLURM_ARRAY_TASK_ID", task.to_string())
            .env("SLURM_ARRAY_TASK_MIN", "0")
            .env("SLURM_ARRAY_TASK_MAX", "2")
            .env("SLURM_ARRAY_TASK_COUNT", "3")
            .env("SLURM_CPUS_PER_TASK", "1")
            .output()
            .unwrap();
        assert!(out.status.success(), "task {task}: {}", stderr(&out));
    }
    assert_eq!(files(&out_dir), expected);

    // Without the variables it refuses with a message rather than running unsharded.
    let out = Command::new("bash")
        .arg(&script)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env("POMONA_DATA", &data)
        .env("POMONA_OUT", &out_dir)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(stderr(&out).contains("job array"), "{}", stderr(&out));
}

/// The value of `key: N` in the manifest.
fn yaml_number(text: &str, key: &str) -> usize {
    text.lines()
        .find_map(|l| l.trim().strip_prefix(&format!("{key}:")))
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or_else(|| panic!("no `{key}:` in the manifest"))
}

#[test]
fn the_kubernetes_indexed_job_command_makes_the_unsharded_files() {
    let manifest =
        std::fs::read_to_string(repo().join("deploy/kubernetes/pomona-detect-job.yaml")).unwrap();
    let shards = yaml_number(&manifest, "completions");
    assert_eq!(yaml_number(&manifest, "parallelism"), shards);
    assert!(manifest.contains("completionMode: Indexed"));
    // The container's command: the folded (`>-`) block after `args:`, lines joined by spaces.
    let lines: Vec<&str> = manifest.lines().collect();
    let start = lines.iter().position(|l| l.trim() == "- >-").unwrap() + 1;
    let command = lines[start..]
        .iter()
        .take_while(|l| !l.trim().ends_with(':'))
        .map(|l| l.trim())
        .collect::<Vec<_>>()
        .join(" ");
    assert!(
        command.contains(&format!("--shard \"${{JOB_COMPLETION_INDEX}}/{shards}\"")),
        "{command}"
    );

    let dir = tempfile::tempdir().unwrap();
    let (data, expected) = reference(dir.path(), 5);
    let volume = dir.path().join("volume");
    std::fs::create_dir_all(&volume).unwrap();
    std::os::unix::fs::symlink(&data, volume.join("season-2026")).unwrap();
    let command = command
        .replace("/data/", &format!("{}/", volume.display()))
        .replace(
            "exec pomona ",
            &format!("exec {} ", env!("CARGO_BIN_EXE_pomona")),
        );
    for index in 0..shards {
        let out = Command::new("sh")
            .args(["-c", &command])
            .env("JOB_COMPLETION_INDEX", index.to_string())
            .output()
            .unwrap();
        assert!(out.status.success(), "index {index}: {}", stderr(&out));
    }
    assert_eq!(files(&volume.join("detections/shape-fit")), expected);
}
