//! Integration tests for the point-cloud formats: PCL's real PCD files against golden values
//! computed independently (`tests/golden/make_pcd_golden.py`: liblzf via PyPI `python-lzf` +
//! numpy), bit-exact round trips through every PCD and PLY encoding, and corrupt or truncated
//! input, which must give the right typed error and never panic.

// Helpers outside `#[test]` functions unwrap too; a failure there is a test failure.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use pomona_core::nalgebra::{Point3, Vector3};
use pomona_core::{CloudLayout, PointCloud};
use pomona_io::cloud_file::{read_cloud, write_cloud, CloudFileError, CloudFormat};
use pomona_io::lzf::{self, LzfError};
use pomona_io::pcd::{
    read_pcd, read_pcd_file, read_pcd_header_file, write_pcd, PcdEncoding, PcdError, PcdHeader,
};
use pomona_io::ply::{read_ply, read_ply_file, write_ply, PlyEncoding, PlyError};

const PCD_ENCODINGS: [PcdEncoding; 3] = [
    PcdEncoding::Ascii,
    PcdEncoding::Binary,
    PcdEncoding::BinaryCompressed,
];
const PLY_ENCODINGS: [PlyEncoding; 3] = [
    PlyEncoding::Ascii,
    PlyEncoding::BinaryLittleEndian,
    PlyEncoding::BinaryBigEndian,
];

// ---------------------------------------------------------------------------------------------
// Helpers

/// A file under the real-data folder's `pcl/`, or `None` when absent (skip recorded; fails
/// under `POMONA_REQUIRE_DATA=1`).
fn shared_pcl(rel: &str) -> Option<PathBuf> {
    pomona_test_support::shared_data(&format!("pcl/{rel}"), "pomona-io/tests/pcd_ply.rs")
}

fn bits3(p: &Point3<f32>) -> [u32; 3] {
    [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
}

/// Bit-for-bit equality (NaN payloads included), layout included unless `ignore_layout`.
fn assert_identical(a: &PointCloud, b: &PointCloud, ignore_layout: bool) {
    if !ignore_layout {
        assert_eq!(a.layout(), b.layout(), "layout");
    }
    assert_eq!(a.len(), b.len(), "length");
    for (i, (p, q)) in a.points().iter().zip(b.points()).enumerate() {
        assert_eq!(bits3(p), bits3(q), "point {i}: {p:?} vs {q:?}");
    }
    assert_eq!(a.colors(), b.colors(), "colours");
    assert_eq!(a.labels(), b.labels(), "labels");
    match (a.normals(), b.normals()) {
        (None, None) => {}
        (Some(x), Some(y)) => {
            for (i, (n, m)) in x.iter().zip(y).enumerate() {
                let nb = [n.x.to_bits(), n.y.to_bits(), n.z.to_bits()];
                let mb = [m.x.to_bits(), m.y.to_bits(), m.z.to_bits()];
                assert_eq!(nb, mb, "normal {i}");
            }
        }
        (x, y) => panic!(
            "normals presence differs: {} vs {}",
            x.is_some(),
            y.is_some()
        ),
    }
    match (a.intensities(), b.intensities()) {
        (None, None) => {}
        (Some(x), Some(y)) => {
            let xb: Vec<u32> = x.iter().map(|v| v.to_bits()).collect();
            let yb: Vec<u32> = y.iter().map(|v| v.to_bits()).collect();
            assert_eq!(xb, yb, "intensities");
        }
        (x, y) => panic!(
            "intensities presence differs: {} vs {}",
            x.is_some(),
            y.is_some()
        ),
    }
}

/// A 4×3 cloud with every attribute, invalid points and awkward float values.
fn rich_cloud(organized: bool) -> PointCloud {
    let nan = f32::NAN;
    let specials = [
        0.0,
        -0.0,
        1.0,
        -0.38191,
        1e-30,
        -3.4e38,
        f32::MIN_POSITIVE,
        f32::from_bits(1), // smallest denormal
        123_456.79,
        2.5e9,
        0.1,
        -7.25,
    ];
    let points: Vec<Point3<f32>> = (0..12)
        .map(|i| {
            if i % 5 == 3 {
                Point3::new(nan, nan, nan)
            } else {
                Point3::new(specials[i], specials[(i + 3) % 12], i as f32 * 0.5 + 0.25)
            }
        })
        .collect();
    let colors: Vec<[u8; 3]> = (0..12_u8)
        .map(|i| [i.wrapping_mul(21), 255 - i, i.wrapping_mul(97)])
        .collect();
    let normals: Vec<Vector3<f32>> = (0..12)
        .map(|i| {
            if i % 5 == 3 {
                Vector3::new(nan, nan, nan)
            } else {
                Vector3::new(0.0, -(i as f32) / 12.0, 1.0)
            }
        })
        .collect();
    let labels: Vec<u32> = (0..12).map(|i| [0, 1, 7, u32::MAX][i % 4]).collect();
    let intensities: Vec<f32> = (0..12).map(|i| i as f32 * 17.5 - 3.0).collect();
    let cloud = if organized {
        PointCloud::organized(4, 3, points).unwrap()
    } else {
        PointCloud::unorganized(points)
    };
    cloud
        .with_colors(colors)
        .unwrap()
        .with_normals(normals)
        .unwrap()
        .with_labels(labels)
        .unwrap()
        .with_intensities(intensities)
        .unwrap()
}

fn pcd_bytes(cloud: &PointCloud, enc: PcdEncoding) -> Vec<u8> {
    let mut out = Vec::new();
    write_pcd(cloud, &mut out, enc).unwrap();
    out
}

fn ply_bytes(cloud: &PointCloud, enc: PlyEncoding) -> Vec<u8> {
    let mut out = Vec::new();
    write_ply(cloud, &mut out, enc).unwrap();
    out
}

fn header_len(bytes: &[u8]) -> usize {
    PcdHeader::parse(bytes).unwrap().1
}

/// Deterministic xorshift bytes.
fn noise(len: usize, seed: u64) -> Vec<u8> {
    let mut s = seed.max(1);
    (0..len)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 32) as u8
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Real PCL files against independent golden values

/// One point: index, x y z bit patterns, rgb, label.
type GoldenPoint = (usize, [u32; 3], [u8; 3], Option<u32>);

/// Golden values printed by `tests/golden/make_pcd_golden.py` (see its docstring). Positions and
/// colours are compared exactly (bit patterns); the coordinate sums over finite points are
/// compared with an absolute tolerance of 1e-3 (numpy sums pairwise, we sum sequentially, both
/// in f64).
struct Golden {
    file: &'static str,
    finite: usize,
    sums: [f64; 3],
    points: [GoldenPoint; 4],
    labels: &'static [(u32, usize)],
}

const GOLDEN: [Golden; 5] = [
    Golden {
        file: "table_scene_mug_stereo_textured.pcd",
        finite: 209_280,
        sums: [19930.185865, -9814.717659, 264682.154889],
        points: [
            (
                6538,
                [0xbec389b5, 0xbee57a78, 0x4001a6b5],
                [67, 67, 62],
                None,
            ),
            (
                158452,
                [0x3d2c7da2, 0x3c9c3ac9, 0x3f473190],
                [157, 158, 105],
                None,
            ),
            (
                300789,
                [0x3e66c765, 0x3e375643, 0x3f33f291],
                [233, 235, 19],
                None,
            ),
            (
                153920,
                [0x3946035a, 0x3c856a38, 0x3f71af3a],
                [0, 0, 40],
                None,
            ),
        ],
        labels: &[],
    },
    Golden {
        file: "mosd/learn33.pcd",
        finite: 179_131,
        sums: [-10490.518140, 13396.148228, 164272.714979],
        points: [
            (
                68614,
                [0xbf152856, 0xbed5150c, 0x3fd3126f],
                [159, 134, 136],
                Some(1),
            ),
            (
                204225,
                [0xbed5734a, 0x3e055aa5, 0x3f5c28f6],
                [184, 159, 158],
                Some(1),
            ),
            (
                306586,
                [0xbeb6e70c, 0x3e95403c, 0x3f239583],
                [193, 171, 180],
                Some(1),
            ),
            (
                153920,
                [0x3a5874c0, 0x3a5874c0, 0x3f5df3b6],
                [217, 216, 190],
                Some(30),
            ),
        ],
        labels: &[
            (0, 128069),
            (1, 141517),
            (20, 15305),
            (30, 9289),
            (40, 1876),
            (41, 3859),
            (50, 2450),
            (51, 1499),
            (60, 1015),
            (61, 2321),
        ],
    },
    Golden {
        file: "mosd/learn36.pcd",
        finite: 171_863,
        sums: [-12856.746579, 13269.131310, 157711.791351],
        points: [
            (
                68609,
                [0xbf192d90, 0xbed5150c, 0x3fd3126f],
                [184, 164, 159],
                Some(1),
            ),
            (
                205890,
                [0x3e5a6494, 0x3e086416, 0x3f5ba5e3],
                [194, 178, 175],
                Some(1),
            ),
            (
                306586,
                [0xbeb73051, 0x3e957c08, 0x3f23d70a],
                [206, 188, 192],
                Some(1),
            ),
            (
                153920,
                [0x3a8272a7, 0x3a8272a7, 0x3f85c28f],
                [191, 181, 183],
                Some(1),
            ),
        ],
        labels: &[
            (0, 135337),
            (1, 138982),
            (20, 14720),
            (30, 1632),
            (31, 2969),
            (40, 4805),
            (41, 892),
            (42, 132),
            (43, 5746),
            (44, 1985),
        ],
    },
    Golden {
        file: "mosd/learn39.pcd",
        finite: 171_874,
        sums: [-13056.716304, 12860.691577, 156911.667282],
        points: [
            (
                68696,
                [0xbea67203, 0xbed5150c, 0x3fd3126f],
                [155, 142, 145],
                Some(1),
            ),
            (
                205312,
                [0x3ea1735e, 0x3e070810, 0x3f5c28f6],
                [167, 153, 140],
                Some(1),
            ),
            (
                306586,
                [0xbeb73051, 0x3e957c08, 0x3f23d70a],
                [182, 167, 176],
                Some(1),
            ),
            (
                153920,
                [0x3a8272a7, 0x3a8272a7, 0x3f85c28f],
                [170, 164, 165],
                Some(1),
            ),
        ],
        labels: &[
            (0, 135326),
            (1, 131408),
            (20, 14943),
            (30, 3023),
            (31, 2261),
            (40, 2219),
            (41, 1167),
            (50, 559),
            (51, 15705),
            (52, 589),
        ],
    },
    Golden {
        file: "mosd/learn42.pcd",
        finite: 172_189,
        sums: [-13010.718995, 13233.536769, 158679.380534],
        points: [
            (
                68616,
                [0xbf138ca5, 0xbed5150c, 0x3fd3126f],
                [157, 139, 130],
                Some(1),
            ),
            (
                205838,
                [0x3e02c208, 0x3e07c14c, 0x3f5a9fbe],
                [174, 161, 158],
                Some(1),
            ),
            (
                306586,
                [0xbeb69dc4, 0x3e950471, 0x3f2353f8],
                [182, 167, 169],
                Some(1),
            ),
            (
                153920,
                [0x3a8212c8, 0x3a8212c8, 0x3f856042],
                [169, 163, 163],
                Some(1),
            ),
        ],
        labels: &[(0, 135011), (1, 154416), (20, 12697), (30, 5076)],
    },
];

fn check_golden(g: &Golden, cloud: &PointCloud) {
    assert_eq!(cloud.len(), 307_200, "{}", g.file);
    assert_eq!(
        cloud.layout(),
        CloudLayout::Organized {
            width: 640,
            height: 480
        }
    );
    assert_eq!(cloud.valid_count(), g.finite, "{}", g.file);
    let mut sums = [0.0_f64; 3];
    for p in cloud
        .points()
        .iter()
        .filter(|p| p.iter().all(|c| c.is_finite()))
    {
        for (s, c) in sums.iter_mut().zip(p.iter()) {
            *s += f64::from(*c);
        }
    }
    for (k, (got, want)) in sums.iter().zip(g.sums).enumerate() {
        assert!(
            (got - want).abs() < 1e-3,
            "{} sum[{k}] {got} vs {want}",
            g.file
        );
    }
    let colors = cloud.colors().expect("colours");
    for &(i, xyz, rgb, label) in &g.points {
        assert_eq!(bits3(&cloud.points()[i]), xyz, "{} point {i}", g.file);
        assert_eq!(colors[i], rgb, "{} colour {i}", g.file);
        assert_eq!(cloud.labels().map(|l| l[i]), label, "{} label {i}", g.file);
    }
    // Grid addressing: index 153920 is pixel (320, 240).
    assert_eq!(bits3(cloud.at(320, 240).unwrap()), g.points[3].1);
    if !g.labels.is_empty() {
        let labels = cloud.labels().expect("labels");
        let mut hist = std::collections::BTreeMap::new();
        for &l in labels {
            *hist.entry(l).or_insert(0_usize) += 1;
        }
        let hist: Vec<(u32, usize)> = hist.into_iter().collect();
        assert_eq!(hist, g.labels, "{} label histogram", g.file);
        // Label 0 marks exactly the invalid points in these files.
        let invalid_zero = (0..cloud.len())
            .filter(|&i| !cloud.is_valid(i))
            .all(|i| labels[i] == 0);
        assert!(invalid_zero);
    }
    // Invalid points are all-NaN.
    let invalid = cloud
        .points()
        .iter()
        .filter(|p| !p.iter().all(|c| c.is_finite()))
        .all(|p| p.iter().all(|c| c.is_nan()));
    assert!(invalid, "{}: invalid points must be all-NaN", g.file);
}

#[test]
fn real_pcl_files_match_golden_values() {
    for g in &GOLDEN {
        let Some(path) = shared_pcl(g.file) else {
            continue;
        };
        let header = read_pcd_header_file(&path).unwrap();
        assert_eq!(header.encoding, PcdEncoding::BinaryCompressed);
        assert_eq!(
            (header.width, header.height, header.points),
            (640, 480, 307_200)
        );
        let cloud = read_pcd_file(&path).unwrap();
        check_golden(g, &cloud);
        // The generic entry point agrees.
        let again = read_cloud(&path).unwrap();
        assert_identical(&cloud, &again, false);
    }
}

#[test]
fn real_mug_round_trips_through_every_pcd_encoding() {
    let Some(path) = shared_pcl(GOLDEN[0].file) else {
        return;
    };
    let original = read_pcd_file(&path).unwrap();
    for enc in PCD_ENCODINGS {
        let bytes = pcd_bytes(&original, enc);
        let back = read_pcd(&bytes).unwrap();
        assert_identical(&original, &back, false);
        check_golden(&GOLDEN[0], &back);
    }
    // Through a file, binary_compressed, as the brief's round trip.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mug.pcd");
    write_cloud(
        &out,
        &original,
        Some(CloudFormat::Pcd(PcdEncoding::BinaryCompressed)),
    )
    .unwrap();
    let back = read_cloud(&out).unwrap();
    assert_identical(&original, &back, false);
    // Our compressor actually compresses PCL's data.
    let written = std::fs::metadata(&out).unwrap().len();
    assert!(written < 307_200 * 16 / 2, "{written} bytes");
}

#[test]
fn real_labelled_file_round_trips_through_ply() {
    let Some(path) = shared_pcl(GOLDEN[1].file) else {
        return;
    };
    let original = read_pcd_file(&path).unwrap();
    for enc in PLY_ENCODINGS {
        let back = read_ply(&ply_bytes(&original, enc)).unwrap();
        assert_eq!(back.layout(), CloudLayout::Unorganized);
        assert_identical(&original, &back, true);
    }
}

// ---------------------------------------------------------------------------------------------
// Synthetic round trips

#[test]
fn pcd_round_trips_bit_exact_in_every_encoding() {
    for organized in [true, false] {
        let cloud = rich_cloud(organized);
        for enc in PCD_ENCODINGS {
            let bytes = pcd_bytes(&cloud, enc);
            let back = read_pcd(&bytes).unwrap_or_else(|e| panic!("{enc}: {e}"));
            assert_identical(&cloud, &back, false);
            let (h, _) = PcdHeader::parse(&bytes).unwrap();
            assert_eq!(h.encoding, enc);
            assert_eq!(h.viewpoint, [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
            assert_eq!(h.height, if organized { 3 } else { 1 });
            let names: Vec<&str> = h.fields.iter().map(|f| f.name.as_str()).collect();
            assert_eq!(
                names,
                [
                    "x",
                    "y",
                    "z",
                    "rgb",
                    "normal_x",
                    "normal_y",
                    "normal_z",
                    "intensity",
                    "label"
                ]
            );
        }
    }
}

#[test]
fn pcd_round_trips_partial_attributes_and_empty_clouds() {
    let base = rich_cloud(false);
    let positions = PointCloud::unorganized(base.points().to_vec());
    let with_labels = positions
        .clone()
        .with_labels(base.labels().unwrap().to_vec())
        .unwrap();
    let with_colors = PointCloud::organized(3, 4, base.points().to_vec())
        .unwrap()
        .with_colors(base.colors().unwrap().to_vec())
        .unwrap();
    let empty = PointCloud::unorganized(Vec::new());
    for cloud in [positions, with_labels, with_colors, empty] {
        for enc in PCD_ENCODINGS {
            let back = read_pcd(&pcd_bytes(&cloud, enc)).unwrap();
            assert_identical(&cloud, &back, false);
        }
        for enc in PLY_ENCODINGS {
            let back = read_ply(&ply_bytes(&cloud, enc)).unwrap();
            assert_identical(&cloud, &back, true);
        }
    }
}

#[test]
fn pcd_rgb_is_written_like_pcl() {
    let cloud = PointCloud::unorganized(vec![Point3::new(1.0, 2.0, 3.0)])
        .with_colors(vec![[0x12, 0x34, 0x56]])
        .unwrap();
    let bytes = pcd_bytes(&cloud, PcdEncoding::Binary);
    let h = header_len(&bytes);
    let text = std::str::from_utf8(&bytes[..h]).unwrap();
    assert!(text.contains("FIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"));
    assert_eq!(&bytes[h + 12..], &0xFF12_3456_u32.to_le_bytes());
    let ascii = String::from_utf8(pcd_bytes(&cloud, PcdEncoding::Ascii)).unwrap();
    assert!(ascii.contains("TYPE F F F U\n"), "{ascii}");
    assert!(ascii.ends_with("DATA ascii\n1 2 3 4279383126\n"), "{ascii}");
}

#[test]
fn ply_round_trips_bit_exact_in_every_encoding() {
    for organized in [true, false] {
        let cloud = rich_cloud(organized);
        for enc in PLY_ENCODINGS {
            let bytes = ply_bytes(&cloud, enc);
            let back = read_ply(&bytes).unwrap_or_else(|e| panic!("{enc}: {e}"));
            assert_eq!(back.layout(), CloudLayout::Unorganized);
            assert_identical(&cloud, &back, true);
        }
    }
}

#[test]
fn cloud_files_dispatch_on_extension() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = rich_cloud(true);
    for (name, format) in [
        ("a.pcd", None),
        ("b.PLY", None),
        ("c.pcd", Some(CloudFormat::Pcd(PcdEncoding::Ascii))),
        ("d.ply", Some(CloudFormat::Ply(PlyEncoding::Ascii))),
        (
            "e.pcd",
            Some(CloudFormat::Pcd(PcdEncoding::BinaryCompressed)),
        ),
    ] {
        let path = dir.path().join(name);
        write_cloud(&path, &cloud, format).unwrap();
        let back = read_cloud(&path).unwrap();
        let is_ply = name.to_lowercase().ends_with(".ply");
        assert_identical(&cloud, &back, is_ply);
    }
    // Defaults: PCD binary, PLY binary little endian.
    let a = std::fs::read(dir.path().join("a.pcd")).unwrap();
    assert_eq!(
        PcdHeader::parse(&a).unwrap().0.encoding,
        PcdEncoding::Binary
    );
    let b = std::fs::read(dir.path().join("b.PLY")).unwrap();
    assert!(b.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
    // No temporary files left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 5);

    let unknown = dir.path().join("x.xyz");
    assert!(matches!(
        write_cloud(&unknown, &cloud, None),
        Err(CloudFileError::UnknownExtension { .. })
    ));
    assert!(matches!(
        read_cloud(&unknown),
        Err(CloudFileError::UnknownExtension { .. })
    ));
    assert!(!unknown.exists());
    // An explicit format overrides the extension.
    write_cloud(&unknown, &cloud, Some(CloudFormat::DEFAULT_PLY)).unwrap();
    assert!(read_ply_file(&unknown).is_ok());
}

#[test]
fn file_errors_name_the_path_and_leave_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.pcd");
    let err = read_cloud(&missing).unwrap_err();
    let CloudFileError::Pcd(e) = &err else {
        panic!("{err:?}");
    };
    assert!(matches!(e, PcdError::File { path, .. } if *path == missing));
    assert!(matches!(e.root(), PcdError::Io(_)));
    assert!(err.to_string().contains("missing.pcd"), "{err}");

    // The destination is a directory: the rename fails, nothing is left behind.
    let blocked = dir.path().join("blocked.ply");
    std::fs::create_dir(&blocked).unwrap();
    let err = write_cloud(&blocked, &rich_cloud(false), None).unwrap_err();
    assert!(matches!(err, CloudFileError::Ply(PlyError::File { .. })));
    assert!(blocked.is_dir());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);

    // A directory that does not exist.
    let nowhere = dir.path().join("no/such/dir/x.pcd");
    assert!(matches!(
        write_cloud(&nowhere, &rich_cloud(false), None),
        Err(CloudFileError::Pcd(PcdError::File { .. }))
    ));

    // A corrupt file's error names it too.
    let bad = dir.path().join("bad.pcd");
    std::fs::write(&bad, b"VERSION 0.7\nFIELDS x y z\n").unwrap();
    let err = read_pcd_file(&bad).unwrap_err();
    assert!(matches!(err.root(), PcdError::MissingHeaderLine(_)));
    assert!(err.to_string().contains("bad.pcd"));
}

// ---------------------------------------------------------------------------------------------
// Corrupt and hostile input

#[test]
fn truncated_pcd_is_an_error_in_every_encoding() {
    let cloud = rich_cloud(true);
    for enc in PCD_ENCODINGS {
        let bytes = pcd_bytes(&cloud, enc);
        let h = header_len(&bytes);
        // Every cut inside the data is an error, never a panic, except that ascii cannot tell
        // a file cut inside its very last value (or its final newline) from a complete one.
        let undetectable = match enc {
            PcdEncoding::Ascii => bytes.iter().rposition(|&b| b == b' ').unwrap_or(0) + 2,
            _ => bytes.len(),
        };
        for cut in h..bytes.len() {
            let r = read_pcd(&bytes[..cut]);
            if cut >= undetectable {
                assert!(r.is_ok(), "{enc}: cut at {cut}: {r:?}");
                continue;
            }
            let e = r
                .err()
                .unwrap_or_else(|| panic!("{enc}: cut at {cut} accepted"));
            match enc {
                PcdEncoding::Binary => assert!(matches!(e, PcdError::Truncated { .. }), "{e:?}"),
                PcdEncoding::BinaryCompressed => {
                    assert!(matches!(e, PcdError::Truncated { .. }), "{e:?}")
                }
                PcdEncoding::Ascii => assert!(
                    matches!(
                        e,
                        PcdError::Truncated { .. }
                            | PcdError::AsciiTooFewPoints { .. }
                            | PcdError::AsciiValueCount { .. }
                            | PcdError::AsciiBadNumber { .. }
                    ),
                    "cut {cut}: {e:?}"
                ),
            }
        }
        // Every cut inside the header too.
        for cut in 0..h {
            assert!(read_pcd(&bytes[..cut]).is_err(), "{enc}: header cut {cut}");
        }
    }
}

#[test]
fn ascii_with_fewer_lines_than_points() {
    let text = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n0.5 0.25 1.125\n2.5 3.5 4.5\n";
    assert!(matches!(
        read_pcd(text.as_bytes()),
        Err(PcdError::AsciiTooFewPoints {
            expected: 3,
            found: 2
        })
    ));
    let text = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n0.5 0.25 1.125\n2.5 three 4.5\n";
    assert!(matches!(
        read_pcd(text.as_bytes()),
        Err(PcdError::AsciiBadNumber { line: 9, .. })
    ));
}

#[test]
fn points_exceeding_data_fail_before_allocating() {
    let cloud = rich_cloud(false);
    // Ten times the points the data holds.
    for enc in [PcdEncoding::Binary, PcdEncoding::Ascii] {
        let bytes = pcd_bytes(&cloud, enc);
        let h = header_len(&bytes);
        let head = std::str::from_utf8(&bytes[..h]).unwrap();
        let head = head
            .replace("WIDTH 12\n", "WIDTH 120\n")
            .replace("POINTS 12\n", "POINTS 120\n");
        let file = [head.as_bytes(), &bytes[h..]].concat();
        let e = read_pcd(&file).unwrap_err();
        assert!(
            matches!(e, PcdError::Truncated { points: 120, .. }),
            "{e:?}"
        );
    }
    // Absurd sizes in a tiny file, every encoding: an error, not an allocation of gigabytes.
    for data in ["ascii", "binary", "binary_compressed"] {
        for (w, h) in [(4_000_000_000_u64, 1_u64), (4_000_000_000, 4_000_000_000)] {
            let mut file = format!(
                "# hostile\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {w}\nHEIGHT {h}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {}\nDATA {data}\n",
                w * h
            )
            .into_bytes();
            file.extend(12_u32.to_le_bytes());
            file.extend(12_u32.to_le_bytes());
            file.extend(noise(200, w ^ h));
            let e = read_pcd(&file).unwrap_err();
            match data {
                "binary_compressed" => assert!(
                    matches!(e, PcdError::CompressedSizeMismatch { .. }),
                    "{e:?}"
                ),
                _ => assert!(matches!(e, PcdError::Truncated { .. }), "{e:?}"),
            }
        }
    }
    // An uncompressed size that matches POINTS but LZF could not produce from the payload.
    let mut file = b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 100000\nHEIGHT 1\nPOINTS 100000\nDATA binary_compressed\n".to_vec();
    file.extend(10_u32.to_le_bytes());
    file.extend(1_200_000_u32.to_le_bytes());
    file.extend([0_u8; 10]);
    assert!(matches!(
        read_pcd(&file),
        Err(PcdError::ImplausibleCompression {
            compressed: 10,
            uncompressed: 1_200_000
        })
    ));
    // Compressed size larger than the file.
    let mut file = b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary_compressed\n".to_vec();
    file.extend(4_000_000_000_u32.to_le_bytes());
    file.extend(12_u32.to_le_bytes());
    file.extend([0_u8; 13]);
    assert!(matches!(read_pcd(&file), Err(PcdError::Truncated { .. })));
    // WIDTH × HEIGHT disagreeing with POINTS.
    let file = b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 4000000000\nHEIGHT 1\nPOINTS 3\nDATA binary\n";
    assert!(matches!(
        read_pcd(file),
        Err(PcdError::PointCountMismatch { .. })
    ));
}

#[test]
fn corrupt_lzf_payload_is_an_error() {
    let cloud = rich_cloud(true);
    let bytes = pcd_bytes(&cloud, PcdEncoding::BinaryCompressed);
    let h = header_len(&bytes);
    // The first chunk turned into a back-reference: nothing to refer to yet.
    let mut bad = bytes.clone();
    bad[h + 8] = 0xE0;
    assert!(matches!(
        read_pcd(&bad),
        Err(PcdError::Lzf(
            LzfError::BadBackReference { .. } | LzfError::TruncatedInput { .. }
        ))
    ));
    // A payload one byte short (compressed size adjusted): the stream stops early.
    let mut short = bytes.clone();
    let c = u32::from_le_bytes(short[h..h + 4].try_into().unwrap());
    short[h..h + 4].copy_from_slice(&(c - 1).to_le_bytes());
    assert!(matches!(read_pcd(&short), Err(PcdError::Lzf(_))));
    // Uncompressed size not matching the header.
    let mut wrong = bytes.clone();
    let u = u32::from_le_bytes(wrong[h + 4..h + 8].try_into().unwrap());
    wrong[h + 4..h + 8].copy_from_slice(&(u + 4).to_le_bytes());
    assert!(matches!(
        read_pcd(&wrong),
        Err(PcdError::CompressedSizeMismatch { .. })
    ));
    // Random flips of payload bytes never panic; those that decode keep the point count.
    let noise = noise(4000, 5);
    for k in noise.chunks(4) {
        let mut m = bytes.clone();
        let span = m.len() - h - 8;
        let pos = h + 8 + (usize::from(k[0]) << 8 | usize::from(k[1])) % span;
        m[pos] ^= k[2] | 1;
        if let Ok(c) = read_pcd(&m) {
            assert_eq!(c.len(), 12);
        }
    }
    // The LZF module on its own.
    assert!(matches!(
        lzf::decompress(&[0x20, 0], 3),
        Err(LzfError::BadBackReference { .. })
    ));
}

#[test]
fn garbage_headers_are_typed_errors() {
    assert!(matches!(
        read_pcd(b"\xff\xd8\xff\xe0JFIF\x00garbage"),
        Err(PcdError::HeaderNotText { line: 1 })
    ));
    assert!(matches!(
        read_pcd(b"hello world\n"),
        Err(PcdError::UnknownHeaderLine { line: 1, .. })
    ));
    assert!(matches!(
        read_pcd(b""),
        Err(PcdError::MissingHeaderLine("DATA"))
    ));
    assert!(matches!(
        read_pcd(b"# only a comment\n\n"),
        Err(PcdError::MissingHeaderLine("DATA"))
    ));
    let ply = ply_bytes(&rich_cloud(false), PlyEncoding::Ascii);
    assert!(matches!(
        read_pcd(&ply),
        Err(PcdError::UnknownHeaderLine { line: 1, .. })
    ));
    let pcd = pcd_bytes(&rich_cloud(false), PcdEncoding::Ascii);
    assert!(matches!(read_ply(&pcd), Err(PlyError::NotPly)));
    assert!(matches!(
        read_pcd(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA lzma\n"),
        Err(PcdError::UnknownDataType { line: 7, .. })
    ));
    assert!(matches!(
        read_pcd(b"FIELDS x y z\nFIELDS x y z\n"),
        Err(PcdError::DuplicateHeaderLine {
            keyword: "FIELDS",
            line: 2
        })
    ));
    assert!(matches!(
        read_pcd(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n"),
        Err(PcdError::FieldCountMismatch {
            keyword: "TYPE",
            ..
        })
    ));
    assert!(matches!(
        read_pcd(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n"),
        Err(PcdError::MissingHeaderLine("HEIGHT"))
    ));
    // Random bytes never panic.
    for seed in 1..300 {
        let g = noise(300, seed);
        assert!(read_pcd(&g).is_err());
        assert!(read_ply(&g).is_err());
    }
}

#[test]
fn unknown_fields_with_counts_and_padding_are_skipped() {
    // PCL-style layout with a 33-float descriptor, padding and a double, in every encoding.
    let n = 5_usize;
    let header = |data: &str| {
        format!(
            "# .PCD v0.7\nVERSION 0.7\nFIELDS x _ y fpfh z curvature rgba normal_x normal_y normal_z\nSIZE 4 1 8 4 2 8 4 4 4 4\nTYPE F U F F I F U F F F\nCOUNT 1 3 1 33 1 1 1 1 1 1\nWIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA {data}\n"
        )
    };
    let point_size = 4 + 3 + 8 + 33 * 4 + 2 + 8 + 4 + 12;
    let mut aos = Vec::new();
    let mut soa: Vec<Vec<u8>> = vec![Vec::new(); 10];
    let mut ascii = String::new();
    for i in 0..n {
        let x = i as f32 + 0.5;
        let y = -(i as f64) * 2.0;
        let z = i as i16 * 100 - 200;
        let rgba = 0x8000_0000_u32 | (i as u32 * 0x0001_0203);
        let fields: Vec<Vec<u8>> = vec![
            x.to_le_bytes().to_vec(),
            vec![0xAA, 0xBB, 0xCC],
            y.to_le_bytes().to_vec(),
            (0..33).flat_map(|k| (k as f32).to_le_bytes()).collect(),
            z.to_le_bytes().to_vec(),
            1.5_f64.to_le_bytes().to_vec(),
            rgba.to_le_bytes().to_vec(),
            0.0_f32.to_le_bytes().to_vec(),
            1.0_f32.to_le_bytes().to_vec(),
            (-1.0_f32).to_le_bytes().to_vec(),
        ];
        for (k, f) in fields.iter().enumerate() {
            aos.extend(f);
            soa[k].extend(f);
        }
        let desc: Vec<String> = (0..33).map(|k| k.to_string()).collect();
        ascii.push_str(&format!(
            "{x} 170 187 204 {y} {} {z} 1.5 {rgba} 0 1 -1\n",
            desc.join(" ")
        ));
    }
    assert_eq!(aos.len(), n * point_size);
    let soa: Vec<u8> = soa.concat();
    let compressed = lzf::compress(&soa);
    let mut files = vec![
        [header("ascii").into_bytes(), ascii.into_bytes()].concat(),
        [header("binary").into_bytes(), aos].concat(),
    ];
    let mut bc = header("binary_compressed").into_bytes();
    bc.extend((compressed.len() as u32).to_le_bytes());
    bc.extend((soa.len() as u32).to_le_bytes());
    bc.extend(compressed);
    files.push(bc);
    for file in files {
        let c = read_pcd(&file).unwrap();
        assert_eq!(c.len(), n);
        for i in 0..n {
            assert_eq!(
                c.points()[i],
                Point3::new(i as f32 + 0.5, -(i as f32) * 2.0, i as f32 * 100.0 - 200.0)
            );
            let v = i as u32 * 0x0001_0203;
            assert_eq!(
                c.colors().unwrap()[i],
                [(v >> 16) as u8, (v >> 8) as u8, v as u8]
            );
            assert_eq!(c.normals().unwrap()[i], Vector3::new(0.0, 1.0, -1.0));
        }
        assert!(c.labels().is_none() && c.intensities().is_none());
    }
}

#[test]
fn truncated_ply_is_an_error() {
    let cloud = rich_cloud(false);
    for enc in PLY_ENCODINGS {
        let bytes = ply_bytes(&cloud, enc);
        let h = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        let undetectable = match enc {
            PlyEncoding::Ascii => bytes.iter().rposition(|&b| b == b' ').unwrap_or(0) + 2,
            _ => bytes.len(),
        };
        for cut in 0..undetectable {
            let e = read_ply(&bytes[..cut]).err();
            let Some(e) = e else {
                panic!("{enc}: cut at {cut} accepted");
            };
            if cut >= h {
                assert!(
                    matches!(
                        e,
                        PlyError::Truncated { .. }
                            | PlyError::UnexpectedEof { .. }
                            // A number cut short, e.g. "-".
                            | PlyError::AsciiBadNumber { .. }
                    ),
                    "{enc} cut {cut}: {e:?}"
                );
            }
        }
    }
}

#[test]
fn ply_vertex_count_exceeding_data_fails_before_allocating() {
    for (format, count) in [
        ("binary_little_endian", "4000000000"),
        ("ascii", "4000000000"),
        ("binary_big_endian", "18446744073709551615"),
        ("binary_little_endian", "13"),
    ] {
        let mut file = format!(
            "ply\nformat {format} 1.0\nelement vertex {count}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
        )
        .into_bytes();
        file.extend([0_u8; 12 * 12]);
        assert!(
            matches!(read_ply(&file), Err(PlyError::Truncated { .. })),
            "{format} {count}"
        );
    }
    // Faces after the vertices, with list counts exceeding the data.
    let mut file = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uint int vertex_indices\nend_header\n".to_vec();
    file.extend([0_u8; 12]);
    file.extend(4_000_000_000_u32.to_le_bytes());
    file.extend([0_u8; 8]);
    assert!(matches!(
        read_ply(&file),
        Err(PlyError::UnexpectedEof { row: 0, .. })
    ));
    // Elements before the vertex element are skipped correctly.
    let mut file = b"ply\nformat binary_little_endian 1.0\nelement material 2\nproperty list uchar float c\nproperty uchar id\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
    file.extend([2_u8]);
    file.extend([0_u8; 8]);
    file.extend([9_u8, 0, 1]);
    for v in [1.0_f32, 2.0, 3.0] {
        file.extend(v.to_le_bytes());
    }
    let c = read_ply(&file).unwrap();
    assert_eq!(c.points(), &[Point3::new(1.0, 2.0, 3.0)]);
}

#[test]
fn mutated_files_never_panic() {
    let cloud = rich_cloud(true);
    let mut samples: Vec<Vec<u8>> = PCD_ENCODINGS
        .iter()
        .map(|&e| pcd_bytes(&cloud, e))
        .collect();
    samples.extend(PLY_ENCODINGS.iter().map(|&e| ply_bytes(&cloud, e)));
    let noise = noise(60_000, 11);
    for (s, sample) in samples.iter().enumerate() {
        for (k, chunk) in noise.chunks(6).enumerate().take(1500) {
            let mut m = sample.clone();
            let pos = (usize::from(chunk[0]) << 8 | usize::from(chunk[1])) % m.len();
            m[pos] = chunk[2];
            if k % 3 == 0 {
                let pos2 = (usize::from(chunk[3]) << 8 | usize::from(chunk[4])) % m.len();
                m[pos2] = chunk[5];
            }
            if s < 3 {
                let _ = read_pcd(&m);
            } else {
                let _ = read_ply(&m);
            }
        }
    }
}
