//! `pomona ros` as a user starts it: it joins the domain, reports the resolved topics, runs for
//! `--duration-s`, writes its report, and refuses bad settings with a message naming them. (The
//! node's message flow is tested on loopback DDS in `pomona-ros`'s own tests.)

#![allow(clippy::unwrap_used)]

#[path = "support/run.rs"]
mod run;

use run::{pomona, stderr};

#[test]
fn node_runs_for_its_duration_and_reports() {
    let tmp = tempfile::tempdir().unwrap();
    let report = tmp.path().join("ros.json");
    let out = pomona(&[
        "ros",
        "--pipeline",
        "shape-fit",
        "--domain-id",
        "63",
        "--namespace",
        "/arm_a",
        "--duration-s",
        "0.5",
        "--status-every-s",
        "0",
        "--json",
        report.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("/arm_a/pomona/detections"), "{err}");
    assert!(err.contains("/camera/camera/color/image_raw"), "{err}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(report["pipeline"], "shape-fit");
    assert_eq!(report["published"], 0);
    assert_eq!(report["detections_topic"], "/arm_a/pomona/detections");
    assert!(report["run_s"].as_f64().unwrap() >= 0.5);
}

#[test]
fn bad_settings_are_named() {
    let cases: [(&[&str], &str); 4] = [
        (&["--domain-id", "300"], "domain id"),
        (&["--detections-topic", "/fruit//found"], "/fruit//found"),
        (&["--min-confidence", "2"], "min-confidence"),
        (&["--sync-tolerance-ms=-1"], "--sync-tolerance-ms"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["ros", "--pipeline", "shape-fit", "--duration-s", "0"];
        args.extend_from_slice(extra);
        let out = pomona(&args);
        assert!(!out.status.success(), "{extra:?}");
        assert!(stderr(&out).contains(needle), "{extra:?}: {}", stderr(&out));
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_pomona"))
        .args(["ros", "--pipeline", "shape-fit", "--duration-s", "0"])
        .env("ROS_DOMAIN_ID", "lab")
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("ROS_DOMAIN_ID is `lab`"),
        "{}",
        stderr(&out)
    );
}
