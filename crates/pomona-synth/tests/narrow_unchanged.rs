//! The narrow domain renders exactly what it rendered before the wide domain existed: the
//! checksums below were taken from frames rendered by the generator before `Domain` was added
//! (commit 5efc73a). A change to the narrow path (an extra random draw, a changed formula)
//! changes them.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use pomona_synth::{
    render, render_view, CameraPreset, FruitChoice, FruitKind, LightPreset, NoiseModel,
    RenderedFrame, SceneSpec, StereoRig,
};

/// FNV-1a over the colour bytes, the depth bits, the mask ids and the truth JSON.
fn checksum(out: &RenderedFrame) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for b in bytes {
            h ^= *b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    eat(out.frame.color().unwrap().as_rgb());
    for z in out.frame.depth().as_slice() {
        eat(&z.to_bits().to_le_bytes());
    }
    for id in out.mask.as_slice() {
        eat(&id.to_le_bytes());
    }
    // `center_px`/`radius_px` were added to the truth later; they are derived from `center_m`
    // and `diameter_m` (checked below), so the checksum leaves them out.
    let mut truth = out.truth.clone();
    for f in &mut truth.fruits {
        let circle = f.center_m.zip(f.diameter_m).and_then(|(c, d)| {
            pomona_core::ImageCircle::of_sphere(out.frame.camera(), &c, 0.5 * d)
        });
        assert_eq!(f.center_px, circle.map(|c| c.center_px));
        assert_eq!(f.radius_px, circle.map(|c| c.radius_px));
        assert!(f.center_px.is_some(), "synth truth has an image circle");
        (f.center_px, f.radius_px) = (None, None);
    }
    eat(serde_json::to_string(&truth).unwrap().as_bytes());
    h
}

fn cases() -> Vec<(SceneSpec, u64)> {
    let base = SceneSpec::default();
    vec![
        (base.clone(), 42),
        (
            SceneSpec {
                fruit: FruitChoice::Mixed,
                camera: CameraPreset::Sr4000.camera(),
                noise: NoiseModel::Tof,
                light: LightPreset::Harsh,
                green_fraction: 0.5,
                ..base.clone()
            },
            7,
        ),
        (
            SceneSpec {
                fruit: FruitChoice::Only(FruitKind::Apple),
                camera: CameraPreset::D435.camera(),
                noise: NoiseModel::Low,
                light: LightPreset::Dim,
                ..base
            },
            3,
        ),
    ]
}

#[test]
fn narrow_frames_match_the_checksums_from_before_the_wide_domain() {
    let got: Vec<u64> = cases()
        .iter()
        .map(|(spec, seed)| {
            let scene = spec.sample(*seed).unwrap();
            checksum(&render(&scene, &spec.camera).unwrap())
        })
        .collect();
    let (spec, seed) = &cases()[1];
    let scene = spec.sample(*seed).unwrap();
    let pose = StereoRig::default().stereo_from_camera();
    let stereo = checksum(&render_view(&scene, &spec.camera, &pose, 1).unwrap());
    assert_eq!(got, EXPECTED);
    assert_eq!(stereo, EXPECTED_STEREO);
}

const EXPECTED: [u64; 3] = [
    12241415777531633906,
    16387012538879405707,
    17291384771672098432,
];
const EXPECTED_STEREO: u64 = 9268908100572786812;
