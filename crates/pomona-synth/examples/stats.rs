//! Prints the visibility histogram, fruit count and mean render time over N frames, to check the
//! scene layout (visibility should span about 0.1–1).
//!
//! `cargo run --release -p pomona-synth --example stats -- [FRAMES] [FRUIT] [narrow|wide]`
//! (the wide domain uses a Kinect v2 with its own depth noise, `tof-multipath`).

use pomona_synth::{render, CameraPreset, Domain, FruitChoice, FruitKind, NoiseModel, SceneSpec};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let frames: u64 = args.first().map(|s| s.parse()).transpose()?.unwrap_or(50);
    let fruit = match args.get(1).map(String::as_str) {
        Some("mixed") | None => FruitChoice::Mixed,
        Some(name) => FruitChoice::Only(
            FruitKind::ALL
                .into_iter()
                .find(|k| k.name() == name)
                .ok_or("unknown fruit")?,
        ),
    };
    let domain = match args.get(2).map(String::as_str) {
        Some("wide") => Domain::Wide,
        Some("narrow") | None => Domain::Narrow,
        Some(_) => return Err("domain must be narrow or wide".into()),
    };
    let noise = match domain {
        Domain::Wide | Domain::Orchard => NoiseModel::for_camera(CameraPreset::KinectV2),
        Domain::Narrow => NoiseModel::None,
    };
    let spec = SceneSpec {
        fruit,
        domain,
        noise,
        ..SceneSpec::default()
    };
    let mut sampling = std::time::Duration::ZERO;
    let mut bins = [0usize; 10];
    let (mut fruits, mut hidden, mut total) = (0, 0, std::time::Duration::ZERO);
    for i in 0..frames {
        let t = std::time::Instant::now();
        let scene = spec.sample_frame(9, i)?;
        sampling += t.elapsed();
        let t = std::time::Instant::now();
        let out = render(&scene, &spec.camera)?;
        total += t.elapsed();
        hidden += scene.fruits.len() - out.truth.fruits.len();
        for f in &out.truth.fruits {
            let v = f.visibility.unwrap_or(0.0);
            bins[((v * 10.0) as usize).min(9)] += 1;
            fruits += 1;
        }
    }
    println!("frames {frames}, visible fruit {fruits}, wholly hidden {hidden}");
    println!(
        "mean sampling {:.1} ms, mean render {:.1} ms (one thread)",
        sampling.as_secs_f64() * 1000.0 / frames as f64,
        total.as_secs_f64() * 1000.0 / frames as f64
    );
    for (i, b) in bins.iter().enumerate() {
        println!(
            "vis {:.1}-{:.1}: {:4} {}",
            i as f64 / 10.0,
            (i + 1) as f64 / 10.0,
            b,
            "#".repeat(b / 2)
        );
    }
    Ok(())
}
