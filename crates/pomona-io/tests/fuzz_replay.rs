//! Replays the fuzz corpora (`fuzz/corpus/<target>/`, minimised with `cargo fuzz cmin`) and the
//! inputs that once crashed a reader (`tests/fuzz_regressions/<target>/`) through the same entry
//! points as the cargo-fuzz targets, on the stable toolchain: errors are fine, panics fail.
//!
//! `cargo test -p pomona-io --test fuzz_replay -- --ignored write_seeds` (re)writes the seed
//! inputs into `fuzz/corpus/`.

use std::path::{Path, PathBuf};

use pomona_io::fuzzing::{replay_target, run, seeds, TARGETS};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn corpora_and_regressions_replay_without_panics() {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    for target in TARGETS {
        replay_target(here, target, |d| run(target, d));
    }
}

#[test]
fn seeds_replay_without_panics() {
    let seeds = seeds();
    for target in TARGETS {
        assert!(seeds.iter().any(|(t, _, _)| *t == target), "{target}");
    }
    for (target, _, bytes) in seeds {
        run(target, &bytes);
    }
}

#[test]
#[ignore = "writes the seed inputs into fuzz/corpus/"]
fn write_seeds() {
    for (target, name, bytes) in seeds() {
        let dir = repo().join("fuzz/corpus").join(target);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(name), bytes).unwrap();
    }
}
