//! Fruit in 3D from the two colour shots of seed 004's rotating camera, using only the `pomona`
//! library (and `pomona-synth`'s rig file to read the rig of a synthetic dataset): what an arm's
//! program does after its two shots — no depth camera.
//!
//! ```text
//! pomona synth --out S --frames 4 --seed 9 --domain orchard --fruit orange --camera d435 --stereo
//! cargo run --release -p pomona --example locate_stereo -- S
//! ```
//! Prints every located fruit of every frame (primary camera frame, metres). A robot builds its
//! `RotatedStereo` from its own calibration: the half-turn β and the hub-to-lens distance.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(data) = std::env::args().nth(1) else {
        return Err("usage: locate_stereo DATASET (made by `pomona synth --stereo`)".into());
    };
    let root = std::path::Path::new(&data);
    let primary = pomona::Dataset::open(root)?;
    let stereo = pomona::Dataset::open(root.join("stereo"))?;
    let rig_file: pomona_synth::RigFile =
        serde_json::from_str(&std::fs::read_to_string(root.join("rig.json"))?)?;
    // The hub lies on the optical axis, `pivot_m[2]` (negative) along it.
    let rig =
        pomona::RotatedStereo::new(rig_file.beta_rad, -rig_file.pivot_m[2], *primary.camera())?;

    let detector = pomona::Detector::builtin("color-contour")?;
    let keep = detector.keep_rule_for(None)?;
    let locator =
        pomona::StereoLocator::new(detector, keep, rig, pomona::StereoSettings::default())?;
    for stem in primary.frames() {
        let (Some(a), Some(b)) = (primary.load_color(stem)?, stereo.load_color(stem)?) else {
            return Err(format!("frame {stem} of {data} lacks a colour view").into());
        };
        let found = locator.locate(&a, &b)?;
        println!(
            "{stem}: {} fruit located ({} and {} circles in the two views)",
            found.detections.len(),
            found.primary.len(),
            found.stereo.len()
        );
        for fruit in &found.detections {
            let c = fruit.center_m;
            println!(
                "  ({:+.3}, {:+.3}, {:.3}) m, {:.0} mm across",
                c.x,
                c.y,
                c.z,
                fruit.diameter_m.unwrap_or(0.0) * 1e3
            );
        }
    }
    Ok(())
}
