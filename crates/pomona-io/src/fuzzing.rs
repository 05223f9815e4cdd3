//! The parser entry points of the coverage-guided fuzz targets in the repository's `fuzz/`
//! folder, and seed inputs for them.
//!
//! Each function takes arbitrary bytes, runs one reader on them and panics only on a bug: a
//! reader error is an expected outcome, a panic (or a re-written cloud that does not read back)
//! is not. The fuzz targets call these functions and the replay test (`tests/fuzz_replay.rs`)
//! calls the same ones on the checked-in corpora and regression inputs on the stable toolchain,
//! so the two cannot drift apart. Not part of the supported API.

use std::path::Path;

use pomona_core::{ColorImage, DepthImage, PinholeCamera, PointCloud};

use crate::{
    lzf, read_pcd, read_ply, write_pcd, write_ply, Dataset, DatasetError, DatasetWriter,
    PcdEncoding, PlyEncoding,
};

/// Names of the fuzz targets whose entry points live here, as in `fuzz/Cargo.toml`.
pub const TARGETS: [&str; 5] = ["pcd", "ply", "lzf", "dataset", "truth_json"];

/// Runs the entry point of the target called `target` on `data`.
///
/// # Panics
/// On an unknown target name, and wherever the entry point itself panics (a bug).
pub fn run(target: &str, data: &[u8]) {
    match target {
        "pcd" => pcd(data),
        "ply" => ply(data),
        "lzf" => lzf(data),
        "dataset" => dataset(data),
        "truth_json" => truth_json(data),
        other => panic!("no fuzz target {other:?}"),
    }
}

/// Reads `data` as a PCD file; a cloud that reads is written in every encoding and must read
/// back with the same points.
pub fn pcd(data: &[u8]) {
    if let Ok(cloud) = read_pcd(data) {
        let encodings = [
            PcdEncoding::Ascii,
            PcdEncoding::Binary,
            PcdEncoding::BinaryCompressed,
        ];
        round_trip(
            &cloud,
            "PCD",
            encodings,
            |c, out, e| write_pcd(c, out, e),
            read_pcd,
        );
    }
}

/// Reads `data` as a PLY file; a cloud that reads is written in every encoding and must read
/// back with the same points.
pub fn ply(data: &[u8]) {
    if let Ok(cloud) = read_ply(data) {
        let encodings = [
            PlyEncoding::Ascii,
            PlyEncoding::BinaryLittleEndian,
            PlyEncoding::BinaryBigEndian,
        ];
        round_trip(
            &cloud,
            "PLY",
            encodings,
            |c, out, e| write_ply(c, out, e),
            read_ply,
        );
    }
}

/// Writes `cloud` in each encoding and reads it back; panics when either fails or the points
/// change.
fn round_trip<E: std::fmt::Display + Copy, Err: std::fmt::Display>(
    cloud: &PointCloud,
    format: &str,
    encodings: [E; 3],
    write: impl Fn(&PointCloud, &mut Vec<u8>, E) -> Result<(), Err>,
    read: impl Fn(&[u8]) -> Result<PointCloud, Err>,
) {
    for encoding in encodings {
        let mut out = Vec::new();
        if let Err(e) = write(cloud, &mut out, encoding) {
            panic!("a cloud read from {format} cannot be written as {encoding}: {e}");
        }
        match read(&out) {
            Ok(back) => assert_same_points(cloud, &back, format, &encoding.to_string()),
            Err(e) => panic!("{format} written as {encoding} does not read back: {e}"),
        }
    }
}

/// Same count and bit-identical coordinates (NaN included).
fn assert_same_points(a: &PointCloud, b: &PointCloud, format: &str, encoding: &str) {
    assert_eq!(a.len(), b.len(), "{format} {encoding}: point count changed");
    let bits = |c: &PointCloud| -> Vec<[u32; 3]> {
        c.points()
            .iter()
            .map(|p| {
                // All NaNs are one value in a point cloud; compare them as such.
                let f = |v: f32| if v.is_nan() { u32::MAX } else { v.to_bits() };
                [f(p.x), f(p.y), f(p.z)]
            })
            .collect()
    };
    assert!(
        bits(a) == bits(b),
        "{format} {encoding}: coordinates changed on a write and read"
    );
}

/// `data` is a little-endian `u32` expected length followed by an LZF stream: decompresses it,
/// and checks that compressing the whole of `data` decompresses back to it.
pub fn lzf(data: &[u8]) {
    if let Some((len, stream)) = data.split_first_chunk::<4>() {
        let expected = u32::from_le_bytes(*len) as usize;
        if let Ok(out) = lzf::decompress(stream, expected) {
            assert_eq!(out.len(), expected, "LZF output of the wrong length");
        }
    }
    let packed = lzf::compress(data);
    assert!(
        packed.len() <= lzf::max_compressed_len(data.len()),
        "LZF output longer than its documented bound"
    );
    match lzf::decompress(&packed, data.len()) {
        Ok(back) => assert!(back == data, "LZF round trip changed the data"),
        Err(e) => panic!("LZF round trip failed: {e}"),
    }
}

/// The three files of a one-frame dataset packed into one fuzz input: see
/// [`dataset_input`].
pub struct DatasetFiles<'a> {
    /// `camera.json`.
    pub camera_json: &'a [u8],
    /// `depth/f.png`.
    pub depth_png: &'a [u8],
    /// `color/f.png`, absent when empty.
    pub color_png: &'a [u8],
}

impl<'a> DatasetFiles<'a> {
    /// Splits a fuzz input made by [`dataset_input`]; `None` when it is too short for its
    /// length fields.
    pub fn split(data: &'a [u8]) -> Option<Self> {
        let (camera_len, rest) = data.split_first_chunk::<2>()?;
        let (depth_len, rest) = rest.split_first_chunk::<4>()?;
        let camera_len = usize::from(u16::from_le_bytes(*camera_len)).min(rest.len());
        let (camera_json, rest) = rest.split_at(camera_len);
        let depth_len = (u32::from_le_bytes(*depth_len) as usize).min(rest.len());
        let (depth_png, color_png) = rest.split_at(depth_len);
        Some(Self {
            camera_json,
            depth_png,
            color_png,
        })
    }
}

/// Packs the files of a one-frame dataset into one fuzz input: the camera file's length
/// (`u16`, little endian), the depth image's length (`u32`), then the camera file, the depth
/// image and the colour image (empty for a depth-only dataset).
///
/// # Panics
/// When the camera file is longer than 65535 bytes or the depth image longer than 4 GiB.
pub fn dataset_input(camera_json: &[u8], depth_png: &[u8], color_png: &[u8]) -> Vec<u8> {
    let camera_len = u16::try_from(camera_json.len()).unwrap_or_else(|_| panic!("camera too long"));
    let depth_len = u32::try_from(depth_png.len()).unwrap_or_else(|_| panic!("depth too long"));
    let mut out = Vec::new();
    out.extend(camera_len.to_le_bytes());
    out.extend(depth_len.to_le_bytes());
    out.extend(camera_json);
    out.extend(depth_png);
    out.extend(color_png);
    out
}

/// Writes the dataset packed in `data` (see [`dataset_input`]) to a temporary folder, opens it
/// and loads its frame.
///
/// # Panics
/// When the temporary folder cannot be written (not a reader bug, but nothing to fuzz without
/// it).
pub fn dataset(data: &[u8]) {
    let Some(files) = DatasetFiles::split(data) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("temporary folder: {e}"));
    let write = |rel: &str, bytes: &[u8]| {
        let path = dir.path().join(rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).unwrap_or_else(|e| panic!("{parent:?}: {e}"));
        }
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    };
    write("camera.json", files.camera_json);
    write("depth/f.png", files.depth_png);
    if !files.color_png.is_empty() {
        write("color/f.png", files.color_png);
    }
    let _ = open_and_load(dir.path());
}

fn open_and_load(root: &Path) -> Result<(), DatasetError> {
    let dataset = Dataset::open(root)?;
    for frame in dataset.frames() {
        dataset.load_frame(frame)?;
    }
    Ok(())
}

/// Parses `data` as a truth file, through the dataset reader's own parser.
pub fn truth_json(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = crate::dataset::parse_truth(text, Path::new("fuzz/truth.json"));
    }
}

/// Small valid inputs for each target here: `(target, name, bytes)`.
///
/// # Panics
/// When a temporary folder cannot be written.
pub fn seeds() -> Vec<(&'static str, String, Vec<u8>)> {
    let mut seeds = Vec::new();
    let cloud = seed_cloud();
    for encoding in [
        PcdEncoding::Ascii,
        PcdEncoding::Binary,
        PcdEncoding::BinaryCompressed,
    ] {
        let mut out = Vec::new();
        write_pcd(&cloud, &mut out, encoding).unwrap_or_else(|e| panic!("{e}"));
        seeds.push(("pcd", format!("seed-{encoding}.pcd"), out));
    }
    for encoding in [
        PlyEncoding::Ascii,
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ] {
        let mut out = Vec::new();
        write_ply(&cloud, &mut out, encoding).unwrap_or_else(|e| panic!("{e}"));
        seeds.push(("ply", format!("seed-{encoding}.ply"), out));
    }
    let text = b"abcabcabcabcabc hello hello hello 0000000000000000".to_vec();
    let mut lzf_seed = (text.len() as u32).to_le_bytes().to_vec();
    lzf_seed.extend(lzf::compress(&text));
    seeds.push(("lzf", "seed-text.bin".into(), lzf_seed));
    let (with_color, depth_only) = seed_datasets();
    seeds.push(("dataset", "seed-rgbd.bin".into(), with_color));
    seeds.push(("dataset", "seed-depth-only.bin".into(), depth_only));
    seeds.push((
        "truth_json",
        "seed-truth.json".into(),
        SEED_TRUTH.as_bytes().to_vec(),
    ));
    seeds
}

/// A truth file with every optional field.
const SEED_TRUTH: &str = r#"{"complete": true, "fruits": [{"id": "1", "kind": "pepper",
 "center_m": [0.0, 0.0, 0.5], "diameter_m": 0.08, "axis": [0, -1, 0], "bbox_px": [0, 0, 2, 2],
 "visibility": 0.75, "x_custom": 3}]}"#;

fn seed_cloud() -> PointCloud {
    use pomona_core::nalgebra::{Point3, Vector3};
    let points = vec![
        Point3::new(0.0, 0.5, 1.0),
        Point3::new(-1.25, f32::NAN, 2.0),
        Point3::new(3.0, 4.0, 5.0),
    ];
    let cloud = PointCloud::organized(3, 1, points)
        .and_then(|c| c.with_colors(vec![[255, 0, 0], [0, 255, 0], [1, 2, 3]]))
        .and_then(|c| c.with_normals(vec![Vector3::z(); 3]))
        .and_then(|c| c.with_labels(vec![0, 7, 4_000_000_000]))
        .and_then(|c| c.with_intensities(vec![0.5, 1.0, -2.0]));
    cloud.unwrap_or_else(|e| panic!("seed cloud: {e}"))
}

/// A 4 × 3 frame with colour and the same frame without.
fn seed_datasets() -> (Vec<u8>, Vec<u8>) {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("temporary folder: {e}"));
    let fail = |e: &dyn std::fmt::Display| -> ! { panic!("seed dataset: {e}") };
    let camera = PinholeCamera::new(4, 3, 10.0, 10.0, 1.5, 1.0).unwrap_or_else(|e| fail(&e));
    let writer = DatasetWriter::create(dir.path(), &camera, 0.001).unwrap_or_else(|e| fail(&e));
    let raw: Vec<u16> = (0..12)
        .map(|k| if k == 5 { 0 } else { 500 + 10 * k })
        .collect();
    let depth = DepthImage::from_u16(4, 3, &raw, 0.001).unwrap_or_else(|e| fail(&e));
    writer.write_depth("f", &depth).unwrap_or_else(|e| fail(&e));
    let color = ColorImage::filled(4, 3, [200, 30, 20]);
    writer.write_color("f", &color).unwrap_or_else(|e| fail(&e));
    let read = |rel: &str| std::fs::read(dir.path().join(rel)).unwrap_or_else(|e| fail(&e));
    let (camera, depth, color) = (
        read("camera.json"),
        read("depth/f.png"),
        read("color/f.png"),
    );
    (
        dataset_input(&camera, &depth, &color),
        dataset_input(&camera, &depth, &[]),
    )
}

/// Replays fuzz target `target` of the crate at `crate_dir`: every file of the repository's
/// `fuzz/corpus/<target>/` and of the crate's `tests/fuzz_regressions/<target>/` through
/// `entry`. Prints the counts and returns the corpus count.
///
/// # Panics
/// As [`replay_dir`], and when the corpus is empty (a replay that runs nothing proves nothing).
pub fn replay_target(
    crate_dir: &Path,
    target: &str,
    entry: impl Fn(&[u8]) + std::panic::RefUnwindSafe + Copy,
) -> usize {
    let corpus = replay_dir(&crate_dir.join("../../fuzz/corpus").join(target), entry);
    let regressions = replay_dir(
        &crate_dir.join("tests/fuzz_regressions").join(target),
        entry,
    );
    println!("{target}: {corpus} corpus inputs, {regressions} regression inputs");
    assert!(corpus > 0, "no corpus for fuzz target {target}");
    corpus
}

/// Runs `entry` on every file in `dir` (none when it does not exist) and returns how many it
/// ran; a panic is re-raised with the file's name. Shared by the replay tests of every crate
/// with a fuzz target.
///
/// # Panics
/// When `dir` cannot be listed or a file read, and when `entry` panics on a file.
pub fn replay_dir(dir: &Path, entry: impl Fn(&[u8]) + std::panic::RefUnwindSafe) -> usize {
    let Ok(listing) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut files: Vec<_> = listing
        .map(|e| {
            e.unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
                .path()
        })
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    for file in &files {
        let bytes = std::fs::read(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        if let Err(cause) = std::panic::catch_unwind(|| entry(&bytes)) {
            let message = cause
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| cause.downcast_ref::<&str>().copied())
                .unwrap_or("(no message)");
            panic!("fuzz input {} panics: {message}", file.display());
        }
    }
    files.len()
}
