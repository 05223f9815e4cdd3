//! How well could *any* lookup table over a colour space separate fruit from background pixels?
//! An upper bound for the colour stage, independent of the network that fills the table.
//!
//! For each held-out `orchard` pixel set of the built-in model's example (Kinect v2, seeds
//! 1430–1434, six frames per light preset) it counts fruit and background pixels per cell of a
//! colour space, then takes the cells in order of their fruit share and keeps the prefix of best
//! F1 — the best table for those very pixels. Printed per light: that bound for a table fitted
//! to the light's own pixels, and the F1 on each light of the one table fitted to all five
//! lights pooled (what a robot carries). Two spaces: the HΣ plane of seed 004 (cells of
//! `(G − B, 2R − G − B)`) and the plane with the intensity band the colour network can take as a
//! third input (`intensity_level`). docs/results.md, "Colour with intensity", quotes the output.
//!
//! ```sh
//! cargo run --release -p pomona-colorcontour --example colour_table_bound
//! ```

use std::collections::{HashMap, HashSet};

use pomona_colorcontour::{for_each_labelled_pixel, hsigma_integers, intensity_level};
use pomona_pipeline::SyntheticFrames;
use pomona_synth::{
    CameraPreset, Domain, FruitChoice, FruitKind, LightPreset, NoiseModel, SceneSpec,
};

/// A colour's cell: `(G − B, 2R − G − B, intensity band)`, the band 0 for the plane alone.
type Cell = (i32, i32, usize);
/// Background and fruit pixels per cell.
type Counts = HashMap<Cell, [u64; 2]>;

const LIGHTS: [(LightPreset, u64); 5] = [
    (LightPreset::Day, 1430),
    (LightPreset::Dim, 1431),
    (LightPreset::Harsh, 1432),
    (LightPreset::LowSun, 1433),
    (LightPreset::Backlight, 1434),
];

fn held_out(light: LightPreset, seed: u64) -> SyntheticFrames {
    SyntheticFrames {
        spec: SceneSpec {
            fruit: FruitChoice::Only(FruitKind::Orange),
            camera: CameraPreset::KinectV2.camera(),
            noise: NoiseModel::for_camera(CameraPreset::KinectV2),
            light,
            domain: Domain::Orchard,
            backgrounds: Domain::Orchard.default_backgrounds(),
            ..SceneSpec::default()
        },
        seed,
        first: 0,
        count: 6,
    }
}

/// The cells of the best-F1 table for `counts` (cells by decreasing fruit share, best prefix).
fn best_table(counts: &Counts) -> HashSet<Cell> {
    let mut cells: Vec<(&Cell, &[u64; 2])> = counts.iter().collect();
    let share = |c: &[u64; 2]| c[1] as f64 / (c[0] + c[1]) as f64;
    cells.sort_by(|a, b| share(b.1).total_cmp(&share(a.1)).then(a.0.cmp(b.0)));
    let fruit: u64 = cells.iter().map(|c| c.1[1]).sum();
    let (mut tp, mut fp, mut best, mut best_len) = (0, 0, 0.0, 0);
    for (n, (_, c)) in cells.iter().enumerate() {
        tp += c[1];
        fp += c[0];
        let f1 = f1(tp, fp, fruit - tp);
        if f1 > best {
            (best, best_len) = (f1, n + 1);
        }
    }
    cells[..best_len].iter().map(|c| *c.0).collect()
}

fn f1(tp: u64, fp: u64, missed: u64) -> f64 {
    2.0 * tp as f64 / (2 * tp + fp + missed).max(1) as f64
}

/// Pixel F1 of the table `cells` on `counts`.
fn score(cells: &HashSet<Cell>, counts: &Counts) -> f64 {
    let (mut tp, mut fp, mut missed) = (0, 0, 0);
    for (cell, c) in counts {
        if cells.contains(cell) {
            tp += c[1];
            fp += c[0];
        } else {
            missed += c[1];
        }
    }
    f1(tp, fp, missed)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    for (name, with_intensity) in [("HΣ plane", false), ("HΣ plane + intensity band", true)] {
        let mut per_light = Vec::new();
        let mut pooled = Counts::new();
        for (light, seed) in LIGHTS {
            let set = held_out(light, seed);
            let mut counts = Counts::new();
            for_each_labelled_pixel(&set, |rgb, fruit| {
                let (gb, sigma) = hsigma_integers(rgb);
                let band = if with_intensity {
                    intensity_level(rgb)
                } else {
                    0
                };
                let k = usize::from(fruit);
                counts.entry((gb, sigma, band)).or_default()[k] += 1;
                pooled.entry((gb, sigma, band)).or_default()[k] += 1;
            })?;
            per_light.push((light, counts));
        }
        let one_table = best_table(&pooled);
        println!("{name}: pixel F1 of the best table");
        for (light, counts) in &per_light {
            println!(
                "  {light:?}: own light's table {:.3}, one table for all lights {:.3}",
                score(&best_table(counts), counts),
                score(&one_table, counts)
            );
        }
    }
    Ok(())
}
