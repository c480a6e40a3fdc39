#!/usr/bin/env python3
"""Wall-thickness batch report: every part in a folder through voxd, one CSV row each.

    python3 batch_thickness.py PARTS_DIR -o report.csv --min-wall 0.8 --max-wall 6 \\
        [--server http://127.0.0.1:8080] [--voxel-size 0.2 | --resolution 256] [--density 7.85e-3] [--units mm]

For each mesh (STL, Draco, OBJ, PLY) it submits a job whose JSON asks for the
analysis, waits for it, and writes: the part, its volume (from the mesh when
it is closed, else from the voxels), surface area, centroid, mass (with
--density, in mass per cubic millimetre), connected parts, enclosed voids, the
thinnest and thickest wall, the thin and thick regions, and the verdict
against --min-wall/--max-wall: pass, fail, or inconclusive when a wall reads
within the error bound (a voxel) of a limit, with the voxel size that would
decide it. Every length is in millimetres (--units gives the files' unit).
The inside test voxd chose for the mesh and the codes of the job's warnings
(an open or inside-out mesh, an implausible size) come with each row. A part
voxd cannot read gets its error in the row; the batch goes on. Exit status:
0 when every part passed, 1 when any failed, was inconclusive or could not be
analysed, 2 on a usage error.
"""
import argparse
import csv
import os
import sys

try:
    from voxd_client import VoxdClient, VoxdError
except ImportError:  # run from the repository without installing the client
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    from voxd_client import VoxdClient, VoxdError

MESH_EXTENSIONS = (".stl", ".drc", ".obj", ".ply")
COLUMNS = ["part", "volume", "volume_source", "surface_area", "centroid_x", "centroid_y", "centroid_z", "mass",
           "parts", "voids", "void_volume", "min_wall", "max_wall", "thin_regions", "thinnest_region_wall",
           "thick_regions", "verdict", "voxel_size_to_decide", "voxel_size", "inside", "warnings", "job", "error"]


def job_params(args):
    grid = {"voxel_size": args.voxel_size} if args.voxel_size else {"resolution": args.resolution}
    grid["padding"] = 1
    analysis = {"kind": "analysis"}
    if args.min_wall:
        analysis["min_wall"] = args.min_wall
    if args.max_wall:
        analysis["max_wall"] = args.max_wall
    return {"grid": grid, "units": args.units, "analyses": [analysis]}


def row_for(client, path, args):
    row = {"part": os.path.basename(path)}
    try:
        job = client.run(path, job_params(args), timeout=args.timeout)
        row["job"] = job["id"]
        row["inside"] = (job.get("inside") or {}).get("test", "")
        row["warnings"] = ";".join(w["code"] for w in job.get("warnings", []))
        report = client.analysis(job, **{k: v for k, v in (("min_wall", args.min_wall), ("max_wall", args.max_wall)) if v})
    except VoxdError as e:
        row["error"] = str(e).replace("\n", " ")
        row["verdict"] = "error"
        return row
    mass = report["mass_properties"]
    mesh = mass.get("mesh") or {}
    source = mesh if mesh.get("available") else mass["voxels"]
    row["volume"] = source["volume"]
    row["volume_source"] = "mesh" if source is mesh else "voxels"
    row["surface_area"] = mesh.get("surface_area", "")
    row["centroid_x"], row["centroid_y"], row["centroid_z"] = source["centroid"]
    if args.density:
        row["mass"] = source["volume"] * args.density
    row["parts"] = report["parts"]["count"]
    row["voids"] = report["voids"]["count"]
    row["void_volume"] = report["voids"]["total_volume"]
    row["voxel_size"] = report["voxel_size"]
    thickness = report.get("thickness")
    if thickness:
        row["min_wall"] = thickness.get("min")
        row["max_wall"] = thickness.get("max")
        thin = thickness.get("thin_regions") or {"count": 0, "items": []}
        row["thin_regions"] = thin["count"]
        if thin["items"]:
            row["thinnest_region_wall"] = min(r["min_thickness"] for r in thin["items"])
        row["thick_regions"] = (thickness.get("thick_regions") or {"count": 0})["count"]
        row["verdict"] = thickness.get("verdict") or ""
        if thickness.get("voxel_size_to_decide") is not None:
            row["voxel_size_to_decide"] = thickness["voxel_size_to_decide"]
    return row


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", help="folder of meshes (.stl, .drc, .obj, .ply)")
    parser.add_argument("-o", "--output", default="-", help="CSV file (default: standard output)")
    parser.add_argument("--server", help="voxd URL (default: $VOXD_SERVER or http://127.0.0.1:8080)")
    parser.add_argument("--api-key", help="API key (default: $VOXD_API_KEY)")
    size = parser.add_mutually_exclusive_group()
    size.add_argument("--voxel-size", type=float, help="voxel edge in mm")
    size.add_argument("--resolution", type=int, default=256, help="voxels along the longest axis (default 256)")
    parser.add_argument("--min-wall", type=float, help="walls thinner than this fail (mm)")
    parser.add_argument("--max-wall", type=float, help="walls thicker than this fail: casting hot spots (mm)")
    parser.add_argument("--units", default="mm", choices=["mm", "cm", "m", "in", "ft"],
                        help="the unit of the mesh files' coordinates (default mm)")
    parser.add_argument("--density", type=float, help="mass per cubic millimetre, for the mass column")
    parser.add_argument("--timeout", type=float, default=3600, help="seconds to wait for one part (default 3600)")
    args = parser.parse_args(argv)
    if not os.path.isdir(args.folder):
        parser.error(f"{args.folder} is not a folder")
    parts = sorted(os.path.join(args.folder, f) for f in os.listdir(args.folder) if f.lower().endswith(MESH_EXTENSIONS))
    if not parts:
        parser.error(f"no meshes ({', '.join(MESH_EXTENSIONS)}) in {args.folder}")

    client = VoxdClient(args.server, api_key=args.api_key)
    out = sys.stdout if args.output == "-" else open(args.output, "w", newline="")
    ok = True
    try:
        writer = csv.DictWriter(out, fieldnames=COLUMNS)
        writer.writeheader()
        for path in parts:
            row = row_for(client, path, args)
            ok = ok and row.get("verdict") in ("pass", "")
            writer.writerow(row)
            out.flush()
            print(f"{row['part']}: {row.get('verdict') or 'done'}{' - ' + row['error'] if row.get('error') else ''}",
                  file=sys.stderr)
    finally:
        if out is not sys.stdout:
            out.close()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
