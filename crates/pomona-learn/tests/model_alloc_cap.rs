//! Loading a hostile model file allocates at most 4 × its size + 64 MiB.
//!
//! A capping allocator (`cap`) is set, before each load, to the allowed amount above what the
//! test holds: an allocation past it aborts the test. The peak printed after each case is the
//! highest allocation so far (the counter cannot be reset), which includes building the case's
//! text (about three times its size) and earlier cases: an upper bound on the load's peak. No test harness (`main` below): one thread, nothing else allocating.
//!
//! Run: `cargo test -p pomona-learn --test model_alloc_cap`.

// A test without the harness: `main` is test code, where unwrapping is the assertion.
#![allow(clippy::unwrap_used)]

use std::alloc::System;

use cap::Cap;
use pomona_learn::fuzzing::{seed, PIPELINE};
use pomona_learn::{ModelFile, MAX_MODEL_FILE_BYTES, MAX_STAGE_PARAMS_BYTES};

#[global_allocator]
static ALLOCATOR: Cap<System> = Cap::new(System, usize::MAX);

const MIB: usize = 1 << 20;

/// The seed model with `key`'s value replaced by `value` (JSON text).
fn with(key: &str, value: &str) -> String {
    let seed = seed();
    let mut model: serde_json::Value = serde_json::from_str(&seed).unwrap();
    model[key] = serde_json::json!("@");
    model.to_string().replace("\"@\"", value)
}

/// `[0,0,…,0]` with `n` elements: two bytes of text per element.
fn zeros(n: usize) -> String {
    format!("[{}0]", "0,".repeat(n - 1))
}

fn main() {
    let dir = tempfile::tempdir().unwrap();
    let max = MAX_MODEL_FILE_BYTES as usize;
    // Texts are made one case at a time, just before it runs: building them allocates too.
    type Make = Box<dyn Fn() -> String>;
    let cases: [(&str, Make, bool); 5] = [
        (
            "stage_params at its cap",
            Box::new(|| with("stage_params", &zeros(MAX_STAGE_PARAMS_BYTES / 2 - 8))),
            true,
        ),
        (
            "stage_params over its cap",
            Box::new(|| with("stage_params", &zeros(MAX_STAGE_PARAMS_BYTES))),
            false,
        ),
        (
            "unknown key, 4M-element array",
            // Unknown keys are skipped as they are parsed: the model loads.
            Box::new(|| with("x_extra", &zeros(4_000_000))),
            true,
        ),
        (
            "svm support vectors at the file cap",
            Box::new(move || {
                let svm = format!(
                    r#"{{"n_features": 1, "gamma": 1, "rho": 0, "coef": [], "n_support_negative": 0, "n_support_positive": 0, "support_vectors": {}}}"#,
                    zeros(max / 2 - 4000)
                );
                with("svm", &svm)
            }),
            false,
        ),
        (
            "file over its cap",
            Box::new(move || with("x_extra", &zeros(max / 2 + 10))),
            false,
        ),
    ];
    println!(
        "{:<38} {:>12} {:>14} {:>14}  outcome",
        "case", "input B", "peak B", "allowed B"
    );
    for (name, make, loads) in cases {
        let text = make();
        let path = dir.path().join(format!("{}.json", name.replace(' ', "-")));
        std::fs::write(&path, &text).unwrap();
        let input = text.len();
        drop(text);
        let allowed = 4 * input + 64 * MIB;
        let base = ALLOCATOR.allocated();
        ALLOCATOR.set_limit(base + allowed).unwrap();
        let result = ModelFile::load(&path, PIPELINE);
        let peak = ALLOCATOR.max_allocated().saturating_sub(base);
        ALLOCATOR.set_limit(usize::MAX).unwrap();
        let outcome = match &result {
            Ok(_) => "Ok".to_owned(),
            Err(e) => format!("Err: {e}"),
        };
        println!("{name:<38} {input:>12} {peak:>14} {allowed:>14}  {outcome}");
        assert!(peak <= allowed, "{name}: peak {peak} > {allowed}");
        assert_eq!(result.is_ok(), loads, "{name}: {outcome}");
        if let Err(e) = result {
            assert!(e.to_string().contains(&*path.to_string_lossy()), "{e}");
        }
    }
}
