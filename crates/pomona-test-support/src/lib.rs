//! # pomona-test-support
//!
//! How the workspace's tests reach the real sensor data (`../shared/data` beside the checkout,
//! see its `NOTICE.md`), in one place so that a skipped real-data test can never pass unseen:
//!
//! * the data is found at `$POMONA_SHARED_DATA` or `<workspace>/../shared/data`;
//! * when it is absent and `POMONA_REQUIRE_DATA=1` (as CI sets it), the test fails;
//! * otherwise the test is skipped: a `SKIPPED` line goes straight to the terminal (past
//!   `cargo test`'s output capture), and, when `POMONA_SKIP_LOG` names a file, a line is
//!   appended to it so `scripts/test.sh` can print the count at the end of the run.
//!
//! A dev-dependency only: no library crate depends on it.

use std::io::Write;
use std::path::PathBuf;

/// The folder of real sensor data, wherever it is (it may not exist).
pub fn shared_data_root() -> PathBuf {
    match std::env::var_os("POMONA_SHARED_DATA") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data")),
    }
}

/// `rel` inside the real-data folder when it exists; otherwise `None` after recording the skip
/// of `test` (see the crate docs).
///
/// # Panics
/// When the path is absent and `POMONA_REQUIRE_DATA=1`: a required real-data test must fail,
/// not pass by skipping.
pub fn shared_data(rel: &str, test: &str) -> Option<PathBuf> {
    let path = shared_data_root().join(rel);
    if path.exists() {
        return Some(path);
    }
    let reason = format!(
        "{} is absent (real data lives in ../shared/data)",
        path.display()
    );
    assert!(
        std::env::var_os("POMONA_REQUIRE_DATA").is_none_or(|v| v != "1"),
        "POMONA_REQUIRE_DATA=1 but {reason} (test {test})"
    );
    record_skip(test, &reason);
    None
}

/// Writes the skip to the terminal (uncaptured) and to `$POMONA_SKIP_LOG` when set. Failing to
/// write either is ignored: the skip itself must not fail the test.
fn record_skip(test: &str, reason: &str) {
    let line = format!("SKIPPED real-data test {test}: {reason}\n");
    let _ = std::io::stderr().write_all(line.as_bytes());
    if let Some(log) = std::env::var_os("POMONA_SKIP_LOG") {
        if let Ok(mut f) = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(log)
        {
            let _ = f.write_all(line.as_bytes());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_root_is_beside_the_checkout_unless_overridden() {
        if std::env::var_os("POMONA_SHARED_DATA").is_none() {
            assert!(shared_data_root().ends_with("shared/data"));
        }
        assert_eq!(
            shared_data("", "root").is_some(),
            shared_data_root().exists()
        );
    }
}
