//! Detect fruit on every frame of a dataset with a built-in detector, using only the `pomona`
//! library: what a robot program's detection call looks like.
//!
//! ```text
//! cargo run --release -p pomona --example detect_frame -- DATASET [PIPELINE]
//! ```
//! Prints each detection the model keeps at its operating confidence.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let Some(data) = args.next() else {
        return Err("usage: detect_frame DATASET [PIPELINE]".into());
    };
    let pipeline = args.next().unwrap_or_else(|| "shape-fit".to_owned());

    let dataset = pomona::Dataset::open(&data)?;
    let detector = pomona::Detector::builtin(&pipeline)?;
    for stem in dataset.frames() {
        let frame = dataset.load_frame(stem)?;
        for fruit in detector
            .detect(&frame)?
            .iter()
            .filter(|d| detector.keeps(d))
        {
            let c = fruit.center_m;
            let size = fruit
                .diameter_m
                .map_or("?".to_owned(), |d| format!("{:.0}", d * 1e3));
            println!(
                "{stem}: fruit at ({:.3}, {:.3}, {:.3}) m, {size} mm, confidence {:.2}",
                c.x,
                c.y,
                c.z,
                fruit.confidence.unwrap_or(f64::NAN)
            );
        }
    }
    Ok(())
}
