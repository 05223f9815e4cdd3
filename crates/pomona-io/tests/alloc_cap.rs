//! Every reader on hostile inputs allocates at most 4 × the input size + 64 MiB.
//!
//! Each case runs in a child process of this test binary (no test harness: `main` below), so the
//! capping allocator's peak counter (`cap::Cap::max_allocated`, which cannot be reset) measures
//! that case alone. The child caps allocation at the allowed amount above what it holds when
//! the reader starts: an attempt to allocate more aborts it, which fails the case. The parent
//! writes the hostile files, runs the cases one after another, prints a table of the peaks and
//! checks that each reader returned an error naming the file (or, where the input is valid, a
//! result).
//!
//! Run: `cargo test -p pomona-io --test alloc_cap` (the table is printed either way).

// A test without the harness: `main` is test code, where unwrapping is the assertion.
#![allow(clippy::unwrap_used)]

use std::alloc::System;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use cap::Cap;
use pomona_io::{lzf, read_pcd_file, read_ply_file, Dataset};

#[global_allocator]
static ALLOCATOR: Cap<System> = Cap::new(System, usize::MAX);

const MIB: u64 = 1 << 20;

/// What a case reads.
#[derive(Debug, Clone, Copy)]
enum Reader {
    Pcd,
    Ply,
    Lzf,
    /// Open the dataset and load every frame (depth and colour).
    Frame,
    /// Open the dataset and load frame `f`'s colour image only.
    Color,
    /// Open the dataset and load frame `f`'s truth.
    Truth,
}

impl Reader {
    fn name(self) -> &'static str {
        match self {
            Reader::Pcd => "pcd",
            Reader::Ply => "ply",
            Reader::Lzf => "lzf",
            Reader::Frame => "frame",
            Reader::Color => "color",
            Reader::Truth => "truth",
        }
    }

    fn from_name(name: &str) -> Reader {
        [
            Reader::Pcd,
            Reader::Ply,
            Reader::Lzf,
            Reader::Frame,
            Reader::Color,
            Reader::Truth,
        ]
        .into_iter()
        .find(|r| r.name() == name)
        .unwrap()
    }

    /// Runs the reader on `path`: `Ok(summary)` or `Err(error chain)`.
    fn run(self, path: &Path) -> Result<String, String> {
        let chain = |e: &dyn std::error::Error| {
            let mut text = e.to_string();
            let mut source = e.source();
            while let Some(s) = source {
                let cause = s.to_string();
                if !text.contains(&cause) {
                    text.push_str(&format!(": {cause}"));
                }
                source = s.source();
            }
            text
        };
        match self {
            Reader::Pcd => read_pcd_file(path)
                .map(|c| format!("{} points", c.len()))
                .map_err(|e| chain(&e)),
            Reader::Ply => read_ply_file(path)
                .map(|c| format!("{} points", c.len()))
                .map_err(|e| chain(&e)),
            Reader::Lzf => {
                let bytes = std::fs::read(path).map_err(|e| chain(&e))?;
                let (len, stream) = bytes.split_first_chunk::<4>().unwrap();
                lzf::decompress(stream, u32::from_le_bytes(*len) as usize)
                    .map(|b| format!("{} bytes", b.len()))
                    .map_err(|e| format!("{}: {}", path.display(), chain(&e)))
            }
            Reader::Frame | Reader::Color | Reader::Truth => {
                let dataset = Dataset::open(path).map_err(|e| chain(&e))?;
                let loaded = match self {
                    Reader::Frame => dataset.load_frame("f").map(|_| "frame".to_owned()),
                    Reader::Color => dataset.load_color("f").map(|_| "colour".to_owned()),
                    _ => dataset.load_truth("f").map(|_| "truth".to_owned()),
                };
                loaded.map_err(|e| chain(&e))
            }
        }
    }
}

/// One hostile input.
struct Case {
    name: &'static str,
    reader: Reader,
    /// The file (or dataset folder) the reader is given.
    path: PathBuf,
    /// Total bytes of the input files.
    input_len: u64,
    /// `Some(file name)`: an error naming this file is expected; `None`: a result is expected.
    error_names: Option<String>,
}

fn main() {
    if let Ok(reader) = std::env::var("POMONA_ALLOC_READER") {
        child(Reader::from_name(&reader));
    } else {
        parent();
    }
}

/// Runs one reader under the cap and prints `peak<TAB>Ok|Err<TAB>text`.
fn child(reader: Reader) {
    let path = PathBuf::from(std::env::var("POMONA_ALLOC_PATH").unwrap());
    let input_len: u64 = std::env::var("POMONA_ALLOC_INPUT_LEN")
        .unwrap()
        .parse()
        .unwrap();
    let allowed = (4 * input_len + 64 * MIB) as usize;
    let base = ALLOCATOR.allocated();
    ALLOCATOR.set_limit(base + allowed).unwrap();
    let outcome = reader.run(&path);
    // An upper bound on what the reader held at its peak.
    let peak = ALLOCATOR.max_allocated() - base;
    ALLOCATOR.set_limit(usize::MAX).unwrap();
    let (status, text) = match outcome {
        Ok(t) => ("Ok", t),
        Err(t) => ("Err", t),
    };
    println!("{peak}\t{status}\t{}", text.replace(['\n', '\t'], " "));
}

fn parent() {
    let dir = tempfile::tempdir().unwrap();
    let cases = hostile_cases(dir.path());
    println!(
        "{:<34} {:>12} {:>14} {:>14}  outcome",
        "case", "input B", "peak B", "allowed B"
    );
    let mut failures = Vec::new();
    for case in &cases {
        let out = Command::new(std::env::current_exe().unwrap())
            .env("POMONA_ALLOC_READER", case.reader.name())
            .env("POMONA_ALLOC_PATH", &case.path)
            .env("POMONA_ALLOC_INPUT_LEN", case.input_len.to_string())
            .output()
            .unwrap();
        let allowed = 4 * case.input_len + 64 * MIB;
        let stdout = String::from_utf8_lossy(&out.stdout);
        let fields: Vec<&str> = stdout.trim_end().splitn(3, '\t').collect();
        let [peak, status, text] = fields.as_slice() else {
            failures.push(format!(
                "{}: child failed ({}): {}",
                case.name,
                out.status,
                String::from_utf8_lossy(&out.stderr).trim()
            ));
            continue;
        };
        let peak: u64 = peak.parse().unwrap();
        println!(
            "{:<34} {:>12} {:>14} {:>14}  {status}: {text}",
            case.name, case.input_len, peak, allowed
        );
        if peak > allowed {
            failures.push(format!("{}: peak {peak} > allowed {allowed}", case.name));
        }
        match (&case.error_names, *status) {
            (Some(file), "Err") if text.contains(file.as_str()) => {}
            (None, "Ok") => {}
            (expected, _) => failures.push(format!(
                "{}: expected {} but got {status}: {text}",
                case.name,
                expected
                    .as_ref()
                    .map_or("a result".to_owned(), |f| format!("an error naming {f}"))
            )),
        }
    }
    std::io::stdout().flush().unwrap();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    println!(
        "{} hostile inputs, every peak within 4 × input + 64 MiB",
        cases.len()
    );
}

/// Writes `bytes` to `dir/name` and describes the case.
fn file_case(dir: &Path, name: &'static str, reader: Reader, file: &str, bytes: &[u8]) -> Case {
    let path = dir.join(file);
    std::fs::write(&path, bytes).unwrap();
    Case {
        name,
        reader,
        path,
        input_len: bytes.len() as u64,
        error_names: Some(file.to_owned()),
    }
}

/// Writes a one-frame dataset folder `dir/folder` from `(relative path, bytes)` files; errors
/// are expected to name `blamed`.
fn dataset_case(
    dir: &Path,
    name: &'static str,
    reader: Reader,
    files: &[(&str, Vec<u8>)],
    blamed: Option<&str>,
) -> Case {
    let root = dir.join(name);
    let mut input_len = 0;
    for (rel, bytes) in files {
        let path = root.join(rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, bytes).unwrap();
        input_len += bytes.len() as u64;
    }
    Case {
        name,
        reader,
        path: root,
        input_len,
        error_names: blamed.map(str::to_owned),
    }
}

fn pcd_header(fields: &str, points: u64, data: &str) -> String {
    format!("VERSION .7\n{fields}\nWIDTH {points}\nHEIGHT 1\nPOINTS {points}\nDATA {data}\n")
}

fn hostile_cases(dir: &Path) -> Vec<Case> {
    let mut cases = pcd_cases(dir);
    cases.extend(ply_cases(dir));
    cases.extend(image_and_json_cases(dir));
    cases
}

fn pcd_cases(dir: &Path) -> Vec<Case> {
    let huge_count = "FIELDS x y z _\nSIZE 4 4 4 1\nTYPE F F F U\nCOUNT 1 1 1 1000000000";
    let xyz = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F";
    let mut empty = file_case(
        dir,
        "pcd ascii COUNT 1e9, 0 points",
        Reader::Pcd,
        "count0.pcd",
        pcd_header(huge_count, 0, "ascii").as_bytes(),
    );
    empty.error_names = None;
    let mut compressed_lie = pcd_header(xyz, 1_000_000, "binary_compressed").into_bytes();
    compressed_lie.extend(100_u32.to_le_bytes());
    compressed_lie.extend(12_000_000_u32.to_le_bytes());
    compressed_lie.extend([0_u8; 100]);
    // A real LZF bomb: 8 M zero points decode to 96 MB from about 1 MB.
    let points = 8_000_000_u64;
    let zeros = vec![0_u8; (points * 12) as usize];
    let packed = lzf::compress(&zeros);
    let mut bomb = pcd_header(xyz, points, "binary_compressed").into_bytes();
    bomb.extend((packed.len() as u32).to_le_bytes());
    bomb.extend((zeros.len() as u32).to_le_bytes());
    bomb.extend(packed);
    let mut lzf_lie = u32::MAX.to_le_bytes().to_vec();
    lzf_lie.extend(lzf::compress(b"abcabcabcabc"));
    vec![
        file_case(
            dir,
            "pcd ascii COUNT 1e9, 1 point",
            Reader::Pcd,
            "count1.pcd",
            format!("{}1 2 3 4\n", pcd_header(huge_count, 1, "ascii")).as_bytes(),
        ),
        empty,
        file_case(
            dir,
            "pcd ascii 2^32-1 points",
            Reader::Pcd,
            "points.pcd",
            format!("{}1 2 3\n", pcd_header(xyz, u64::from(u32::MAX), "ascii")).as_bytes(),
        ),
        file_case(
            dir,
            "pcd binary 2^32-1 points",
            Reader::Pcd,
            "points-bin.pcd",
            pcd_header(xyz, u64::from(u32::MAX), "binary").as_bytes(),
        ),
        file_case(
            dir,
            "pcd compressed size lie",
            Reader::Pcd,
            "lie.pcd",
            &compressed_lie,
        ),
        file_case(
            dir,
            "pcd compressed LZF bomb",
            Reader::Pcd,
            "bomb.pcd",
            &bomb,
        ),
        file_case(dir, "lzf declares 4 GiB", Reader::Lzf, "lie.lzf", &lzf_lie),
    ]
}

fn ply_cases(dir: &Path) -> Vec<Case> {
    let vertex = |format: &str, count: u64| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex {count}\nproperty float x\nproperty float y\nproperty float z\n"
        )
    };
    let mut faces = format!(
        "{}element face 1\nproperty list uint uchar v\nend_header\n",
        vertex("binary_little_endian", 1)
    )
    .into_bytes();
    faces.extend([0_u8; 12]);
    faces.extend(u32::MAX.to_le_bytes());
    vec![
        file_case(
            dir,
            "ply ascii 10^18 vertices",
            Reader::Ply,
            "many.ply",
            format!(
                "{}end_header\n1 2 3\n",
                vertex("ascii", 1_000_000_000_000_000_000)
            )
            .as_bytes(),
        ),
        file_case(
            dir,
            "ply binary 2^64-1 vertices",
            Reader::Ply,
            "many-bin.ply",
            format!("{}end_header\n", vertex("binary_little_endian", u64::MAX)).as_bytes(),
        ),
        file_case(
            dir,
            "ply face list of 2^32-1 items",
            Reader::Ply,
            "faces.ply",
            &faces,
        ),
    ]
}

fn image_and_json_cases(dir: &Path) -> Vec<Case> {
    let camera = |w: u32, h: u32| {
        format!(
            r#"{{"width": {w}, "height": {h}, "fx": 500.0, "fy": 500.0, "cx": 2.0, "cy": 1.0, "depth_unit_m": 0.001}}"#
        )
        .into_bytes()
    };
    let small_png = png_header(4, 3, 16, 0);
    let mut deep = b"{\"complete\": true, \"fruits\": [], \"x\": ".to_vec();
    deep.extend(vec![b'['; 1 << 20]);
    // The worst JSON for memory: a generic array of one-digit numbers (2 bytes of text, a
    // 32-byte value each), just under the size cap and well over it.
    let wide = |n: usize| {
        let mut t = b"{\"complete\": true, \"fruits\": [], \"x\": [".to_vec();
        t.extend("0,".repeat(n).as_bytes());
        t.extend(b"0]}");
        t
    };
    vec![
        dataset_case(
            dir,
            "depth png 60000x60000",
            Reader::Frame,
            &[
                ("camera.json", camera(60_000, 60_000)),
                ("depth/f.png", png_header(60_000, 60_000, 16, 0)),
            ],
            Some("f.png"),
        ),
        dataset_case(
            dir,
            "colour png 30000x30000 rgba16",
            Reader::Color,
            &[
                ("camera.json", camera(30_000, 30_000)),
                ("depth/f.png", small_png.clone()),
                ("color/f.png", png_header(30_000, 30_000, 16, 6)),
            ],
            Some("f.png"),
        ),
        dataset_case(
            dir,
            "colour jpeg 60000x60000",
            Reader::Color,
            &[
                ("camera.json", camera(60_000, 60_000)),
                ("depth/f.png", small_png.clone()),
                ("color/f.jpg", jpeg_header(60_000, 60_000)),
            ],
            Some("f.jpg"),
        ),
        dataset_case(
            dir,
            "truth json nested 1 MiB deep",
            Reader::Truth,
            &[
                ("camera.json", camera(4, 3)),
                ("depth/f.png", small_png.clone()),
                ("truth/f.json", deep),
            ],
            Some("f.json"),
        ),
        dataset_case(
            dir,
            "truth json 1M-element extra key",
            Reader::Truth,
            &[
                ("camera.json", camera(4, 3)),
                ("depth/f.png", small_png.clone()),
                ("truth/f.json", wide(1_048_000)),
            ],
            None,
        ),
        dataset_case(
            dir,
            "truth json 2M-element extra key",
            Reader::Truth,
            &[
                ("camera.json", camera(4, 3)),
                ("depth/f.png", small_png),
                ("truth/f.json", wide(2_000_000)),
            ],
            Some("f.json"),
        ),
    ]
}

/// A PNG signature, an IHDR chunk for the given size, bit depth and colour type, a tiny IDAT
/// and IEND: the header promises far more pixels than the data holds.
fn png_header(width: u32, height: u32, bit_depth: u8, color_type: u8) -> Vec<u8> {
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend(width.to_be_bytes());
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([bit_depth, color_type, 0, 0, 0]);
    chunk(&mut png, b"IHDR", &ihdr);
    chunk(
        &mut png,
        b"IDAT",
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    );
    chunk(&mut png, b"IEND", &[]);
    png
}

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend((data.len() as u32).to_be_bytes());
    let mut crc_input = kind.to_vec();
    crc_input.extend(data);
    out.extend(&crc_input);
    out.extend(crc32(&crc_input).to_be_bytes());
}

/// CRC-32 (IEEE), bit by bit: a few bytes per case, speed does not matter.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = u32::MAX;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A baseline JPEG's start and frame header for the given size, then its end marker.
fn jpeg_header(width: u16, height: u16) -> Vec<u8> {
    let mut jpeg = vec![0xFF, 0xD8, 0xFF, 0xC0, 0x00, 0x11, 0x08];
    jpeg.extend(height.to_be_bytes());
    jpeg.extend(width.to_be_bytes());
    jpeg.extend([3, 1, 0x11, 0, 2, 0x11, 0, 3, 0x11, 0]);
    jpeg.extend([0xFF, 0xD9]);
    jpeg
}
