//! Prints the visibility histogram, fruit count and mean render time over N frames, to check the
//! scene layout (visibility should span about 0.1–1).
//!
//! `cargo run --release -p pomona-synth --example stats -- [FRAMES] [FRUIT]`

use pomona_synth::{render, FruitChoice, FruitKind, SceneSpec};

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
    let spec = SceneSpec {
        fruit,
        ..SceneSpec::default()
    };
    let mut bins = [0usize; 10];
    let (mut fruits, mut hidden, mut total) = (0, 0, std::time::Duration::ZERO);
    for i in 0..frames {
        let scene = spec.sample_frame(9, i)?;
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
        "mean render {:.1} ms",
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
