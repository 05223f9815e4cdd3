//! Throughput of the point-cloud formats on a camera-sized (640×480) cloud: LZF on its own, and
//! reading and writing PCD (every encoding) and binary PLY. Uses PCL's
//! `table_scene_mug_stereo_textured.pcd` from the shared data when present, otherwise a
//! synthetic cloud of the same shape (with invalid points and colours).

// A bench that cannot load its input should stop loudly.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use pomona_core::nalgebra::Point3;
use pomona_core::PointCloud;
use pomona_io::lzf;
use pomona_io::pcd::{read_pcd, read_pcd_file, write_pcd, PcdEncoding};
use pomona_io::ply::{read_ply, write_ply, PlyEncoding};

fn input() -> PointCloud {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/pcl/table_scene_mug_stereo_textured.pcd"
    );
    if let Ok(cloud) = read_pcd_file(path) {
        return cloud;
    }
    eprintln!("{path} not present: benchmarking a synthetic 640x480 cloud");
    let (w, h) = (640_u32, 480_u32);
    let points = (0..w * h)
        .map(|i| {
            let (u, v) = ((i % w) as f32, (i / w) as f32);
            if (u as u32 + v as u32) % 7 == 0 {
                Point3::new(f32::NAN, f32::NAN, f32::NAN)
            } else {
                let z = 0.8 + 0.001 * ((u * 0.05).sin() + (v * 0.03).cos());
                Point3::new((u - 320.0) * z / 525.0, (v - 240.0) * z / 525.0, z)
            }
        })
        .collect();
    let colors = (0..w * h)
        .map(|i| [(i % 251) as u8, (i / 640 % 256) as u8, 90])
        .collect();
    PointCloud::organized(w, h, points)
        .unwrap()
        .with_colors(colors)
        .unwrap()
}

fn benches(c: &mut Criterion) {
    let cloud = input();
    let raw = {
        let mut v = Vec::new();
        write_pcd(&cloud, &mut v, PcdEncoding::Binary).unwrap();
        v
    };
    let soa_len = raw.len();

    let mut g = c.benchmark_group("lzf");
    g.throughput(Throughput::Bytes(soa_len as u64));
    g.bench_function("compress", |b| b.iter(|| lzf::compress(black_box(&raw))));
    let packed = lzf::compress(&raw);
    g.bench_function("decompress", |b| {
        b.iter(|| lzf::decompress(black_box(&packed), raw.len()).unwrap())
    });
    g.finish();

    let mut g = c.benchmark_group("pcd");
    g.throughput(Throughput::Elements(cloud.len() as u64));
    for enc in [
        PcdEncoding::Ascii,
        PcdEncoding::Binary,
        PcdEncoding::BinaryCompressed,
    ] {
        let mut file = Vec::new();
        write_pcd(&cloud, &mut file, enc).unwrap();
        g.bench_function(format!("write {enc}"), |b| {
            b.iter(|| {
                let mut out = Vec::with_capacity(file.len());
                write_pcd(black_box(&cloud), &mut out, enc).unwrap();
                out
            })
        });
        g.bench_function(format!("read {enc}"), |b| {
            b.iter(|| read_pcd(black_box(&file)).unwrap())
        });
    }
    g.finish();

    let mut g = c.benchmark_group("ply");
    g.throughput(Throughput::Elements(cloud.len() as u64));
    let mut file = Vec::new();
    write_ply(&cloud, &mut file, PlyEncoding::BinaryLittleEndian).unwrap();
    g.bench_function("write binary_little_endian", |b| {
        b.iter(|| {
            let mut out = Vec::with_capacity(file.len());
            write_ply(black_box(&cloud), &mut out, PlyEncoding::BinaryLittleEndian).unwrap();
            out
        })
    });
    g.bench_function("read binary_little_endian", |b| {
        b.iter(|| read_ply(black_box(&file)).unwrap())
    });
    g.finish();
}

criterion_group! {
    name = cloud_io;
    config = Criterion::default().sample_size(10);
    targets = benches
}
criterion_main!(cloud_io);
