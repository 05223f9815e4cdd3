"""Open3D's side of the building-block comparison, and the table of both sides.

Run by scripts/open3d_blocks.sh (which installs Open3D, pins threads and runs Pomona's side);
not meant to be run alone. Times the same blocks, with the same parameters, on the same depth
frame as Pomona's example `open3d_blocks` (crates/pomona-consensus/examples/open3d_blocks.rs):

  back_projection   uint16 depth image -> valid points (create_from_depth_image)
  kd_tree_build     KDTreeFlann on those points
  knn_normals       estimate_normals(KNN(k)) (its kd-tree build included) and
                    orient_normals_towards_camera_location(origin), as Pomona orients them
  ransac_plane      segment_plane(threshold, 3, iterations, probability=1.0: no early stop)
  voxel_downsample  voxel_down_sample(voxel)

`measure`: each block gets one warm-up run, then the median of --repeats timed runs, printed as
JSON. `table`: the median over rounds (the shell script alternates the two sides, so both see
the same machine load) of each side's medians, as a Markdown table (Pomona ms, Open3D ms, ratio
Pomona / Open3D, output sizes of both), also written to --out.
"""

import argparse
import json
import statistics
import sys
import time

import numpy as np

try:
    import open3d as o3d
except ImportError:  # `table` needs only the standard library
    o3d = None

BLOCKS = [
    ("back_projection", "back-projection (depth → cloud)"),
    ("kd_tree_build", "kd-tree build"),
    ("knn_normals", "kNN normals (PCA), tree build included"),
    ("ransac_plane", "RANSAC plane"),
    ("voxel_downsample", "voxel grid downsample"),
]


def time_ms(repeats, f, setup=lambda: None):
    """Median ms of `repeats` runs of f(setup()) after one warm-up; and the warm-up's result."""
    first = f(setup())
    times = []
    for _ in range(max(1, repeats)):
        arg = setup()
        t = time.perf_counter()
        f(arg)
        times.append((time.perf_counter() - t) * 1e3)
    return statistics.median(times), first


def open3d_side(args):
    cam = json.load(open(f"{args.data}/camera.json"))
    depth = o3d.io.read_image(f"{args.data}/depth/{args.frame}.png")
    if np.asarray(depth).dtype != np.uint16:
        sys.exit(f"{args.data}/depth/{args.frame}.png: expected a 16-bit depth PNG")
    intrinsic = o3d.camera.PinholeCameraIntrinsic(
        cam["width"], cam["height"], cam["fx"], cam["fy"], cam["cx"], cam["cy"]
    )
    scale = 1.0 / cam["depth_unit_m"]
    r = args.repeats
    bp, pcd = time_ms(
        r,
        lambda _: o3d.geometry.PointCloud.create_from_depth_image(
            depth, intrinsic, depth_scale=scale, depth_trunc=1e9
        ),
    )
    kd, tree = time_ms(r, lambda _: o3d.geometry.KDTreeFlann(pcd))

    def normals(c):
        c.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(args.k))
        c.orient_normals_towards_camera_location(np.zeros(3))
        return c

    # A fresh copy per run (outside the timer): estimate_normals reuses existing normals.
    nm, with_normals = time_ms(r, normals, setup=lambda: o3d.geometry.PointCloud(pcd))
    rp, (_, inliers) = time_ms(
        r,
        lambda _: pcd.segment_plane(
            args.plane_threshold_m, 3, args.plane_iterations, probability=1.0
        ),
    )
    vx, down = time_ms(r, lambda _: pcd.voxel_down_sample(args.voxel_m))
    finite = np.isfinite(np.asarray(with_normals.normals)).all(axis=1)
    return {
        "side": "open3d",
        "threads": "o3d.utility.set_max_threads(1) (oneTBB) and OMP_NUM_THREADS=1, open3d "
        + o3d.__version__,
        "points": len(pcd.points),
        "ms": {
            "back_projection": bp,
            "kd_tree_build": kd,
            "knn_normals": nm,
            "ransac_plane": rp,
            "voxel_downsample": vx,
        },
        "outputs": {
            "back_projection": len(pcd.points),
            "kd_tree_build": len(pcd.points) if tree is not None else 0,
            "knn_normals": int(finite.sum()),
            "ransac_plane": len(inliers),
            "voxel_downsample": len(down.points),
        },
    }


def table(args):
    """Median over rounds of each side's per-round medians, as a Markdown table."""
    sides = {}
    for side, files in (("pomona", args.pomona_json), ("open3d", args.open3d_json)):
        runs = [json.load(open(f)) for f in files]
        sides[side] = {
            "runs": runs,
            "ms": {k: statistics.median(r["ms"][k] for r in runs) for k, _ in BLOCKS},
        }
    pomona, other = sides["pomona"]["runs"][0], sides["open3d"]["runs"][0]
    rounds = len(sides["pomona"]["runs"])
    lines = [
        f"**{args.label}** (frame `{args.frame}`): {pomona['points']} valid points; "
        f"median over {rounds} alternating rounds of each side's median of {args.repeats} runs; "
        f"Pomona: {pomona['threads']}; Open3D: {other['threads']}",
        "",
        "| block | Pomona ms | Open3D ms | ratio Pomona / Open3D | output Pomona / Open3D |",
        "|---|---:|---:|---:|---|",
    ]
    for key, name in BLOCKS:
        a, b = sides["pomona"]["ms"][key], sides["open3d"]["ms"][key]
        lines.append(
            f"| {name} | {a:.1f} | {b:.1f} | {a / b:.2f} | "
            f"{pomona['outputs'][key]} / {other['outputs'][key]} |"
        )
    text = "\n".join(lines) + "\n"
    print(text)
    with open(args.out, "w") as f:
        f.write(text)


def main():
    p = argparse.ArgumentParser()
    sub = p.add_subparsers(dest="mode", required=True)
    m = sub.add_parser("measure", help="time Open3D's blocks once, print JSON")
    m.add_argument("--data", required=True)
    m.add_argument("--frame", required=True)
    m.add_argument("--repeats", type=int, default=15)
    m.add_argument("--k", type=int, default=30)
    m.add_argument("--plane-iterations", type=int, default=1000)
    m.add_argument("--plane-threshold-m", type=float, default=0.01)
    m.add_argument("--voxel-m", type=float, default=0.01)
    t = sub.add_parser("table", help="combine both sides' JSON files into a table")
    t.add_argument("--label", required=True)
    t.add_argument("--frame", required=True)
    t.add_argument("--repeats", type=int, required=True)
    t.add_argument("--pomona-json", nargs="+", required=True)
    t.add_argument("--open3d-json", nargs="+", required=True)
    t.add_argument("--out", required=True)
    args = p.parse_args()
    if args.mode == "table":
        table(args)
        return
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    # Open3D 0.20 parallelises with oneTBB, which ignores OMP_NUM_THREADS (the machine's core
    # count is used otherwise: normals and RANSAC ran on two threads here).
    o3d.utility.set_max_threads(1)
    if o3d.utility.get_max_threads() != 1:
        sys.exit("could not limit Open3D to one thread")
    print(json.dumps(open3d_side(args), indent=1))


if __name__ == "__main__":
    main()
