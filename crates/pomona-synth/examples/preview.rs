//! Renders one frame and writes a colour PNG, a false-colour depth PNG and a mask overlay PNG,
//! for looking at the generator's output.
//!
//! `cargo run --release -p pomona-synth --example preview -- OUT_PREFIX [SEED] [FRUIT] [NOISE] [LIGHT] [CAMERA]`

use std::path::PathBuf;

use pomona_core::{ColorImage, DepthImage, FrameTruth, InstanceMask};
use pomona_synth::{
    render, CameraPreset, FruitChoice, FruitKind, LightPreset, NoiseModel, SceneSpec,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let prefix = args
        .first()
        .cloned()
        .unwrap_or_else(|| "/tmp/synth".to_string());
    let seed: u64 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(1);
    let fruit: FruitChoice = args
        .get(2)
        .map_or(Ok(FruitChoice::Only(FruitKind::Pepper)), |s| s.parse())?;
    let noise: NoiseModel = args.get(3).map_or(Ok(NoiseModel::None), |s| s.parse())?;
    let light = match args.get(4).map(String::as_str) {
        Some(n) => LightPreset::ALL
            .into_iter()
            .find(|m| m.name() == n)
            .ok_or("unknown light")?,
        None => LightPreset::Day,
    };
    let camera: CameraPreset = args
        .get(5)
        .map_or(Ok(CameraPreset::KinectV2), |s| s.parse())?;
    let spec = SceneSpec {
        fruit,
        noise,
        light,
        camera: camera.camera(),
        green_fraction: 0.3,
        ..SceneSpec::default()
    };
    let scene = spec.sample(seed)?;
    let start = std::time::Instant::now();
    let out = render(&scene, &spec.camera)?;
    eprintln!("rendered in {:?}", start.elapsed());
    let color = out.frame.color().ok_or("no colour")?;
    pomona_io::write_color_png(&PathBuf::from(format!("{prefix}_color.png")), color)?;

    let vis = depth_picture(out.frame.depth());
    pomona_io::write_color_png(&PathBuf::from(format!("{prefix}_depth.png")), &vis)?;

    let overlay = mask_overlay(color, &out.mask, &out.truth);
    for f in &out.truth.fruits {
        eprintln!(
            "fruit {} {} d={:.3} vis={:.2} z={:.3}",
            f.id,
            f.kind,
            f.diameter_m.unwrap_or(0.0),
            f.visibility.unwrap_or(0.0),
            f.center_m.map(|c| c.z).unwrap_or(0.0)
        );
    }
    pomona_io::write_color_png(&PathBuf::from(format!("{prefix}_mask.png")), &overlay)?;
    Ok(())
}

/// Depth in false colour: near = bright yellow, far = dark blue, no reading = black.
fn depth_picture(depth: &DepthImage) -> ColorImage {
    let (lo, hi) = depth.range_m().unwrap_or((0.0, 1.0));
    let mut vis = ColorImage::filled(depth.width(), depth.height(), [0, 0, 0]);
    for v in 0..depth.height() {
        for u in 0..depth.width() {
            if let Some(z) = depth.get(u, v) {
                let s = 1.0 - ((z - lo) / (hi - lo).max(1e-6)).clamp(0.0, 1.0);
                vis.set(
                    u,
                    v,
                    [
                        (255.0 * s) as u8,
                        (200.0 * s * s) as u8,
                        (255.0 * (1.0 - s)) as u8 / 2,
                    ],
                );
            }
        }
    }
    vis
}

/// `color` tinted by fruit id where the mask has one, with the truth boxes in white.
fn mask_overlay(color: &ColorImage, mask: &InstanceMask, truth: &FrameTruth) -> ColorImage {
    let mut overlay = color.clone();
    for v in 0..color.height() {
        for u in 0..color.width() {
            let id = mask.get(u, v).unwrap_or(0);
            if id > 0 {
                let c = overlay.get(u, v).unwrap_or([0; 3]);
                let tint = [
                    (id as u32 * 97 % 256) as u8,
                    (id as u32 * 57 % 256) as u8,
                    255,
                ];
                overlay.set(
                    u,
                    v,
                    [
                        c[0] / 2 + tint[0] / 2,
                        c[1] / 2 + tint[1] / 2,
                        c[2] / 2 + tint[2] / 2,
                    ],
                );
            }
        }
    }
    for b in truth.fruits.iter().filter_map(|f| f.bbox_px) {
        for u in b.xmin as u32..=b.xmax as u32 {
            overlay.set(u, b.ymin as u32, [255, 255, 255]);
            overlay.set(u, b.ymax as u32, [255, 255, 255]);
        }
        for v in b.ymin as u32..=b.ymax as u32 {
            overlay.set(b.xmin as u32, v, [255, 255, 255]);
            overlay.set(b.xmax as u32, v, [255, 255, 255]);
        }
    }
    overlay
}
