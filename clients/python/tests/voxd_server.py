"""A real `voxd serve` on a loopback ephemeral port, for the client's tests
(VOXD_BINARY names the binary; default build/server/voxd)."""
import os
import re
import shutil
import struct
import subprocess
import tempfile
import threading

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
VOXD = os.environ.get("VOXD_BINARY", os.path.join(REPO, "build", "server", "voxd"))
# The CAD-like parts the build writes (tests/support/test_parts.h).
TEST_PARTS = os.environ.get("VOXD_TEST_PARTS", os.path.join(REPO, "build", "test-parts"))


class VoxdServer:
    def __init__(self, *extra_args, workers=2, data_dir=None):
        self.dir = tempfile.mkdtemp(prefix="voxd-pyclient-")
        self.data_dir = data_dir or os.path.join(self.dir, "data")
        self.process = subprocess.Popen(
            [VOXD, "serve", "--host", "127.0.0.1", "--port", "0", "--data-dir", self.data_dir,
             "--workers", str(workers), *extra_args],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.log = []
        found = threading.Event()
        self.url = None

        def read():
            for line in self.process.stdout:
                self.log.append(line)
                m = re.search(r"listening on (http://127\.0\.0\.1:\d+)", line)
                if m and not found.is_set():
                    self.url = m.group(1)
                    found.set()
            found.set()

        threading.Thread(target=read, daemon=True).start()
        if not found.wait(30) or self.url is None:
            self.stop()
            raise RuntimeError("voxd serve did not start:\n" + "".join(self.log))

    def stop(self, kill=False, keep_data=False):
        if self.process.poll() is None:
            if kill:
                self.process.kill()
            else:
                self.process.terminate()
            try:
                self.process.wait(20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.process.stdout.close()
        if not keep_data:
            shutil.rmtree(self.dir, ignore_errors=True)


def box_stl(lo, hi, inside_out=False):
    """A closed box as binary STL bytes, facing outward (or inward: written inside out)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0), (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    faces = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (2, 3, 7), (2, 7, 6), (1, 2, 6),
             (1, 6, 5), (3, 0, 4), (3, 4, 7)]
    out = bytearray(80) + struct.pack("<I", len(faces))
    for f in faces:
        out += struct.pack("<3f", 0, 0, 0)
        for k in (reversed(f) if inside_out else f):
            out += struct.pack("<3f", *v[k])
        out += b"\0\0"
    return bytes(out)
