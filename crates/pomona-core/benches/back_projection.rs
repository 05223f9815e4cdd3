//! Back-projection of a full depth frame to an organised cloud, at Kinect v2 and Azure Kinect
//! colour resolutions. The depth pattern is fixed (no randomness), a quarter of pixels empty.

#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_core::{ColorImage, DepthImage, PinholeCamera, RgbdFrame};

fn frame(width: u32, height: u32, fx: f64) -> RgbdFrame {
    let cam = PinholeCamera::new(
        width,
        height,
        fx,
        fx,
        width as f64 / 2.0,
        height as f64 / 2.0,
    )
    .unwrap_or_else(|e| panic!("bench camera: {e}"));
    let raw: Vec<u16> = (0..width * height)
        .map(|i| {
            if i % 4 == 0 {
                0
            } else {
                500 + (i % 1000) as u16
            }
        })
        .collect();
    let depth = DepthImage::from_u16(width, height, &raw, 0.001).unwrap_or_else(|e| panic!("{e}"));
    let color = ColorImage::filled(width, height, [120, 40, 30]);
    RgbdFrame::new(cam, depth, Some(color)).unwrap_or_else(|e| panic!("{e}"))
}

fn back_projection(c: &mut Criterion) {
    for (name, w, h, fx) in [
        ("kinect-v2 512x424", 512, 424, 365.0),
        ("azure 1920x1080", 1920, 1080, 917.0),
    ] {
        let f = frame(w, h, fx);
        c.bench_function(&format!("to_cloud {name}"), |b| b.iter(|| f.to_cloud()));
    }
}

criterion_group!(benches, back_projection);
criterion_main!(benches);
