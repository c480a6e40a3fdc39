#!/usr/bin/env python3
"""Cost curves of whole `voxd voxelize` runs (docs/benchmarks.md, issue #19).

Time (best of RUNS) and peak resident memory against the grid (N voxels
along the longest axis of the benchmark torus, 128 ... 8192) and against the
triangle count (70k, 1.1M, 4.4M), for the solid (to RLE), coverage (exact,
4 x 4 rays, u8 RLE) and the SDF band (3 voxels, f32 RLE), with the exponent
b of time ~ N^b (or ~ triangles^b) fitted by least squares to the larger
sizes. Then, with --callgrind, instruction counts (valgrind --tool=callgrind,
stable where seconds wobble) of the main stages of one run of each.

    bench/cost_curves.py [--build DIR] [--runs N] [--callgrind] [--only solid,coverage,sdf]
"""
import argparse
import math
import os
import re
import subprocess
import sys
import tempfile

GRIDS = {
    "solid": [128, 256, 512, 1024, 2048, 4096, 8192],
    "coverage": [128, 256, 512, 1024, 2048],
    "sdf": [128, 256, 512, 1024],
}
TRIANGLES = [70000, 1100000, 4400000]
# Grid of the triangle-count curve per job.
TRIANGLE_GRID = {"solid": 1024, "coverage": 512, "sdf": 512}
FLAGS = {
    "solid": ["--padding", "1", "--mode", "solid"],
    "coverage": ["--padding", "1", "--mode", "coverage"],
    "sdf": ["--padding", "3", "--mode", "sdf"],
}
# Inclusive instruction counts of these functions are the stages' (names as
# callgrind_annotate prints them; a stage whose function is absent is left
# out). Work a pool thread does is its own function's, not its caller's, so
# the stages are named where the work is, not by the CLI's phases.
STAGES = [
    ("decode STL", r"voxd::mesh_io::decode_stl_binary\("),
    ("bounds", r"voxd::bounds\("),
    ("triangle bins", r"voxd::detail::bin_triangles\("),
    ("runs from crossings", r"voxd::voxelize_runs\("),
    ("parity crossings", r"ParityVoxelizer::chunk_crossings\("),
    ("RLE from runs", r"voxd::encode::write_rle_bit_layers\(voxd::RunSlab"),
    ("parity solid (dense)", r"voxd::detail::ParityVoxelizer::fill\("),
    ("coverage", r"voxd::voxelize_coverage(_streamed)?\("),
    ("sdf", r"voxd::signed_distance_field\("),
    ("sdf slabs", r"voxd::signed_distance_field_slabs\("),
    ("band scatter (chunks)", r"voxd::sdf::scatter_band_chunk\("),
]


def run_once(voxd, mesh, res, job, out):
    cmd = ["/usr/bin/time", "-f", "%e %M", voxd, "voxelize", mesh, "--resolution", str(res), "-o", out] + FLAGS[job]
    p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{p.stderr}")
    secs, kib = p.stderr.strip().splitlines()[-1].split()
    return float(secs), int(kib) // 1024, os.path.getsize(out)


def measure(voxd, mesh, res, job, runs, work):
    out = os.path.join(work, "out.rle")
    best, peak, size = None, 0, 0
    for _ in range(runs):
        secs, mib, size = run_once(voxd, mesh, res, job, out)
        best = secs if best is None else min(best, secs)
        peak = max(peak, mib)
    os.remove(out)
    return best, peak, size


def exponent(points):
    """Least-squares slope of log(time) against log(size)."""
    xs = [math.log(x) for x, _ in points]
    ys = [math.log(max(y, 1e-3)) for _, y in points]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    den = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / den if den else float("nan")


def callgrind(voxd, mesh, res, job, work):
    out = os.path.join(work, "cg.out")
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", voxd, "voxelize", mesh,
                    "--resolution", str(res), "-o", os.path.join(work, "cg.rle")] + FLAGS[job],
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", out],
                          capture_output=True, text=True, check=True).stdout
    counts = {}
    total = None
    for line in text.splitlines():
        m = re.match(r"\s*([\d,]+)\s+(?:\([\d.]+%\)\s+)?(.*)", line)
        if not m:
            continue
        n = int(m.group(1).replace(",", ""))
        if "PROGRAM TOTALS" in m.group(2):
            total = n
        for name, pattern in STAGES:
            if name not in counts and re.search(pattern, m.group(2)):
                counts[name] = n
    os.remove(out)
    return total, counts


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--callgrind", action="store_true")
    ap.add_argument("--only", default="solid,coverage,sdf")
    args = ap.parse_args()
    jobs = args.only.split(",")
    voxd = os.path.join(args.build, "server", "voxd")
    writer = os.path.join(args.build, "bench", "write_bench_mesh")
    with tempfile.TemporaryDirectory() as work:
        meshes = {}
        for n in TRIANGLES:
            meshes[n] = os.path.join(work, f"torus_{n}.stl")
            subprocess.run([writer, meshes[n], "--triangles", str(n)], check=True)
        print(f"{'job':9} {'N':>5} {'triangles':>9} {'best s':>8} {'peak MiB':>9} {'out MiB':>8}")
        for job in jobs:
            points = []
            for res in GRIDS[job]:
                secs, mib, size = measure(voxd, meshes[1100000], res, job, args.runs, work)
                points.append((res, secs))
                print(f"{job:9} {res:>5} {1100000:>9} {secs:>8.3f} {mib:>9} {size / 2**20:>8.1f}", flush=True)
            big = [p for p in points if p[0] >= 512]
            print(f"{job:9} time ~ N^{exponent(big):.2f} over N = {big[0][0]}..{big[-1][0]}, "
                  f"N^{exponent(points[-2:]):.2f} over the last doubling", flush=True)
            tri_points = []
            res = TRIANGLE_GRID[job]
            for n in TRIANGLES:
                secs, mib, size = measure(voxd, meshes[n], res, job, args.runs, work)
                tri_points.append((n, secs))
                print(f"{job:9} {res:>5} {n:>9} {secs:>8.3f} {mib:>9} {size / 2**20:>8.1f}", flush=True)
            print(f"{job:9} time ~ triangles^{exponent(tri_points):.2f} at N = {res}", flush=True)
        if args.callgrind:
            for job, res in (("solid", 1024), ("coverage", 256), ("sdf", 256)):
                if job not in jobs:
                    continue
                total, counts = callgrind(voxd, meshes[1100000], res, job, work)
                print(f"callgrind {job} N={res}, 1.1M triangles: {total:,} instructions in all")
                for name, _ in STAGES:
                    if name in counts:
                        print(f"  {name:22} {counts[name]:>16,}")


if __name__ == "__main__":
    main()
