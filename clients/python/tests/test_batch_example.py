"""examples/batch_thickness.py as a batch user runs it: a folder of parts in,
one CSV row per part out, against a real `voxd serve`."""
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

from voxd_server import TEST_PARTS, VOXD, VoxdServer, box_stl

EXAMPLE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples", "batch_thickness.py")


class BatchThicknessExample(unittest.TestCase):
    def setUp(self):
        self.server = VoxdServer()
        self.dir = tempfile.mkdtemp(prefix="voxd-batch-")
        self.parts = os.path.join(self.dir, "parts")
        os.mkdir(self.parts)

    def tearDown(self):
        self.server.stop()
        shutil.rmtree(self.dir, ignore_errors=True)

    def run_example(self, *args):
        out = os.path.join(self.dir, "report.csv")
        r = subprocess.run([sys.executable, EXAMPLE, self.parts, "-o", out, "--server", self.server.url, *args],
                           capture_output=True, text=True, timeout=600)
        with open(out, newline="") as f:
            return r, {row["part"]: row for row in csv.DictReader(f)}

    def test_a_row_per_part_with_volume_mass_walls_and_verdict(self):
        # A slab 2 thick (volume 8 x 6 x 2 = 96), a thin hex nut, and a broken file.
        with open(os.path.join(self.parts, "slab.stl"), "wb") as f:
            f.write(box_stl((0, 0, 0), (8, 6, 2)))
        shutil.copy(os.path.join(TEST_PARTS, "hex_nut.stl"), self.parts)
        with open(os.path.join(self.parts, "broken.stl"), "w") as f:
            f.write("solid broken\n")
        with open(os.path.join(self.parts, "notes.txt"), "w") as f:
            f.write("not a mesh\n")
        r, rows = self.run_example("--voxel-size", "0.25", "--min-wall", "2.5", "--density", "0.5")
        self.assertEqual(r.returncode, 1, r.stderr)  # the slab fails its check
        self.assertEqual(sorted(rows), ["broken.stl", "hex_nut.stl", "slab.stl"])

        slab = rows["slab.stl"]
        self.assertEqual(slab["volume_source"], "mesh")
        self.assertAlmostEqual(float(slab["volume"]), 96.0, places=9)
        self.assertAlmostEqual(float(slab["mass"]), 48.0, places=9)
        self.assertAlmostEqual(float(slab["surface_area"]), 2 * (48 + 16 + 12), places=9)
        self.assertEqual([float(slab[c]) for c in ("centroid_x", "centroid_y", "centroid_z")], [4.0, 3.0, 1.0])
        self.assertEqual((slab["parts"], slab["voids"]), ("1", "0"))
        self.assertEqual(float(slab["min_wall"]), 2.0)  # 8 voxels of 0.25
        self.assertEqual(slab["verdict"], "fail")
        self.assertGreaterEqual(int(slab["thin_regions"]), 1)
        self.assertEqual(float(slab["thinnest_region_wall"]), 2.0)

        # The nut's volume is its mesh's, as `voxd inspect` computes it.
        inspect = subprocess.run([VOXD, "inspect", os.path.join(TEST_PARTS, "hex_nut.stl")],
                                 capture_output=True, text=True)

        self.assertAlmostEqual(float(rows["hex_nut.stl"]["volume"]), json.loads(inspect.stdout)["volume"], places=9)
        self.assertEqual(rows["hex_nut.stl"]["verdict"], "fail")  # 1.2 thick, under 2.5

        broken = rows["broken.stl"]
        self.assertEqual(broken["verdict"], "error")
        self.assertIn("invalid-mesh", broken["error"])
        self.assertEqual(broken["volume"], "")

    def test_a_wall_within_a_voxel_of_the_limit_is_inconclusive_and_warnings_come_with_the_row(self):
        # The slab is 2 thick; 2.1 is under half a voxel of 0.25 away: the
        # wall could be either side. The same slab written inside out is
        # turned round and says so; a slab in centimetres is read in mm.
        with open(os.path.join(self.parts, "slab.stl"), "wb") as f:
            f.write(box_stl((0, 0, 0), (8, 6, 2)))
        with open(os.path.join(self.parts, "inside_out.stl"), "wb") as f:
            f.write(box_stl((0, 0, 0), (8, 6, 2), inside_out=True))
        r, rows = self.run_example("--voxel-size", "0.25", "--min-wall", "2.1")
        self.assertEqual(r.returncode, 1, r.stderr)  # inconclusive is not a pass
        for name in ("slab.stl", "inside_out.stl"):
            row = rows[name]
            self.assertEqual(row["verdict"], "inconclusive", row)
            self.assertGreater(float(row["voxel_size_to_decide"]), 0.0)
            self.assertLess(float(row["voxel_size_to_decide"]), 0.25)
            self.assertEqual(row["inside"], "parity")
            self.assertAlmostEqual(float(row["volume"]), 96.0, places=9)
        self.assertEqual(rows["slab.stl"]["warnings"], "")
        self.assertEqual(rows["inside_out.stl"]["warnings"], "mesh-inverted")
        self.assertIn("slab.stl: inconclusive", r.stderr)

        r, rows = self.run_example("--voxel-size", "2.5", "--min-wall", "15", "--units", "cm")
        slab = rows["slab.stl"]
        self.assertAlmostEqual(float(slab["volume"]), 96000.0, places=6)  # mm^3
        self.assertEqual(float(slab["min_wall"]), 20.0)
        self.assertEqual(slab["verdict"], "pass")

    def test_every_part_passing_exits_zero(self):
        with open(os.path.join(self.parts, "slab.stl"), "wb") as f:
            f.write(box_stl((0, 0, 0), (8, 6, 2)))
        r, rows = self.run_example("--voxel-size", "0.25", "--min-wall", "1.5", "--max-wall", "3")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(rows["slab.stl"]["verdict"], "pass")
        self.assertEqual(rows["slab.stl"]["mass"], "")  # no --density


if __name__ == "__main__":
    unittest.main()
