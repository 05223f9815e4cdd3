#!/usr/bin/env python3
"""Golden values for the PCD reader tests in ../pcd_ply.rs, computed independently of the Rust
reader: the header is parsed here, the LZF payload is decompressed by liblzf itself (PyPI
`python-lzf`, a C binding of Marc Lehmann's liblzf) and the field-major (SoA) buffer is decoded
with numpy.

    pip install numpy python-lzf
    python3 make_pcd_golden.py [/work/shared/data/pcl]

Prints, per file: POINTS, WIDTH/HEIGHT, the number of points with finite x, y and z, the sum of
x, y, z over finite points (float64 accumulation), a few points (x y z as float32 bit patterns
and decimal, r g b), and for labelled files the label histogram.
"""
import os
import struct
import sys

import lzf
import numpy as np

NP_TYPES = {
    ("F", 4): "<f4", ("F", 8): "<f8",
    ("U", 1): "<u1", ("U", 2): "<u2", ("U", 4): "<u4", ("U", 8): "<u8",
    ("I", 1): "<i1", ("I", 2): "<i2", ("I", 4): "<i4", ("I", 8): "<i8",
}


def read_pcd(path):
    with open(path, "rb") as f:
        raw = f.read()
    header = {}
    pos = 0
    while True:
        end = raw.index(b"\n", pos)
        line = raw[pos:end].decode("ascii").strip()
        pos = end + 1
        if not line or line.startswith("#"):
            continue
        key, *vals = line.split()
        header[key] = vals
        if key == "DATA":
            break
    fields = header["FIELDS"]
    sizes = [int(s) for s in header["SIZE"]]
    types = header["TYPE"]
    counts = [int(c) for c in header.get("COUNT", ["1"] * len(fields))]
    n = int(header["POINTS"][0])
    assert header["DATA"][0] == "binary_compressed", "this script only decodes binary_compressed"
    csize, usize = struct.unpack_from("<II", raw, pos)
    payload = raw[pos + 8:pos + 8 + csize]
    data = lzf.decompress(payload, usize)
    assert len(data) == usize == n * sum(s * c for s, c in zip(sizes, counts))
    out = {}
    off = 0
    for name, s, t, c in zip(fields, sizes, types, counts):
        nbytes = n * s * c
        arr = np.frombuffer(data[off:off + nbytes], dtype=NP_TYPES[(t, s)]).reshape(n, c)
        out[name] = arr[:, 0] if c == 1 else arr
        off += nbytes
    return header, out, n


def f32bits(v):
    return struct.unpack("<I", struct.pack("<f", float(v)))[0]


def report(path):
    header, f, n = read_pcd(path)
    print(f"== {os.path.basename(path)}")
    print(f"POINTS {n} WIDTH {header['WIDTH'][0]} HEIGHT {header['HEIGHT'][0]}")
    x, y, z = f["x"], f["y"], f["z"]
    finite = np.isfinite(x) & np.isfinite(y) & np.isfinite(z)
    print(f"finite {int(finite.sum())}")
    print("sum x %.6f y %.6f z %.6f" % tuple(float(a[finite].astype(np.float64).sum()) for a in (x, y, z)))
    col = f.get("rgb", f.get("rgba"))
    col = col.view("<u4") if col is not None else None
    idx = np.flatnonzero(finite)
    w = int(header["WIDTH"][0])
    picks = [int(idx[0]), int(idx[len(idx) // 2]), int(idx[-1]), 240 * w + 320]
    for i in picks:
        line = f"point {i}: x {str(x[i])} ({f32bits(x[i]):#010x}) y {str(y[i])} ({f32bits(y[i]):#010x}) z {str(z[i])} ({f32bits(z[i]):#010x})"
        if col is not None:
            c = int(col[i])
            line += f" rgb {(c >> 16) & 255} {(c >> 8) & 255} {c & 255} (raw {c:#010x})"
        if "label" in f:
            line += f" label {int(f['label'][i])}"
        print(line)
    if "label" in f:
        labels, counts = np.unique(f["label"], return_counts=True)
        print("labels " + " ".join(f"{int(l)}:{int(c)}" for l, c in zip(labels, counts)))


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "../../../../../shared/data/pcl")
    for rel in ["table_scene_mug_stereo_textured.pcd", "mosd/learn33.pcd", "mosd/learn36.pcd",
                "mosd/learn39.pcd", "mosd/learn42.pcd"]:
        report(os.path.join(root, rel))


if __name__ == "__main__":
    main()
