"""voxd_client against a real `voxd serve`: results equal the CLI's bytes,
waits end in the job's real state, errors carry the problem's fields."""
import http.server
import json
import os
import subprocess
import sys
import tempfile
import threading
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from voxd_client import (Busy, InvalidMesh, InvalidParams, InvalidQuery, JobCancelled, JobFailed, NotFinished,  # noqa: E402
                         NotFound, TransportError, VoxdClient, WaitTimeout)
from voxd_client.events import read_events  # noqa: E402
from voxd_server import TEST_PARTS, VOXD, VoxdServer, box_stl  # noqa: E402

BOX = box_stl((0, 0, 0), (4, 3, 2))  # volume 24


class ClientAgainstVoxd(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = VoxdServer()
        cls.client = VoxdClient(cls.server.url, timeout=30)
        cls.tmp = tempfile.mkdtemp(prefix="voxd-pyclient-test-")

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    def cli_volume(self, mesh_path, params, fmt):
        out = os.path.join(self.tmp, "cli." + fmt)
        r = subprocess.run([VOXD, "voxelize", mesh_path, "-o", out, "--format", fmt, "--params", json.dumps(params)],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(out, "rb") as f:
            return f.read()

    def test_run_from_a_path_and_fetch_the_volume_the_cli_writes(self):
        mesh = os.path.join(TEST_PARTS, "torus.stl")
        params = {"grid": {"resolution": 40, "padding": 1}}
        progress = []
        job = self.client.run(mesh, params, on_progress=progress.append)
        self.assertEqual(job["state"], "succeeded")
        self.assertEqual(job["grid"]["dims"][0], 42)
        self.assertEqual(progress[-1]["state"], "succeeded")
        self.assertEqual(progress[-1]["progress"], 1)
        values = [p.get("progress", 0) for p in progress]
        self.assertEqual(values, sorted(values), "progress never goes back")
        for fmt in ("rle", "nrrd", "binvox"):
            self.assertEqual(self.client.volume(job, fmt), self.cli_volume(mesh, params, fmt), fmt)
        dest = os.path.join(self.tmp, "torus.rle")
        self.assertEqual(self.client.volume(job["id"], "rle", dest=dest), dest)
        with open(dest, "rb") as f:
            self.assertEqual(f.read(), self.cli_volume(mesh, params, "rle"))
        self.assertFalse(os.path.exists(dest + ".partial"))

    def test_bytes_and_file_objects_submit_the_same_job(self):
        by_bytes = self.client.run(BOX, {"grid": {"resolution": 16}}, filename="box.stl")
        path = os.path.join(self.tmp, "box.stl")
        with open(path, "wb") as f:
            f.write(BOX)
        with open(path, "rb") as f:
            by_file = self.client.run(f, {"grid": {"resolution": 16}})
        # The same bytes and parameters: the same content, answered from the kept result.
        self.assertEqual(by_bytes["content_hash"], by_file["content_hash"])
        self.assertEqual(by_bytes["filled_voxels"], by_file["filled_voxels"])

    def test_polling_and_events_end_in_the_same_state(self):
        params = {"grid": {"resolution": 24}, "mode": "sdf", "sdf": {"band": 2}}
        job = self.client.submit(BOX, params, filename="box.stl")
        polled = self.client.wait(job, use_events=False)
        streamed = self.client.wait(job["id"])
        self.assertEqual(polled["state"], "succeeded")
        self.assertEqual(streamed["state"], "succeeded")
        self.assertEqual(polled["filled_voxels"], streamed["filled_voxels"])
        self.assertEqual(polled["values"]["quantity"], "signed distance")

    def test_analysis_report_and_requested_analyses(self):
        params = {"grid": {"voxel_size": 0.125, "padding": 1},
                  "analyses": [{"kind": "analysis", "min_wall": 2.5},
                               {"kind": "radiography", "axis": "z", "format": "json"}]}
        job = self.client.run(BOX, params, filename="box.stl")
        report = self.client.analysis(job, min_wall=2.5)
        self.assertAlmostEqual(report["mass_properties"]["mesh"]["volume"], 24.0, places=9)
        self.assertEqual(report["thickness"]["verdict"], "fail")  # 2 thick, 2.5 asked
        self.assertEqual(json.loads(self.client.job_analysis(job, 0)), report)
        radiography = json.loads(self.client.job_analysis(job, 1))
        self.assertEqual(radiography["max"], 16.0)  # 2 / 0.125 voxels
        png = self.client.download(job, "radiography", axis="z", measure="max")
        self.assertEqual(png[:8], b"\x89PNG\r\n\x1a\n")

    def test_thickness_on_the_part_is_the_cli_s_and_reads_the_wall(self):
        # A box 4 x 3 x 2: with min_wall 2.5 its whole surface is one thin
        # region, every vertex within a voxel (0.125) of the 2 between the
        # z faces, the thinnest wall each bounds.
        params = {"grid": {"voxel_size": 0.125, "padding": 1}}
        job = self.client.run(BOX, params, filename="box.stl")
        on_part = self.client.thickness_on_part(job, min_wall=2.5)
        self.assertEqual(on_part["vertices"], 8)
        self.assertEqual(on_part["unresolved"], 0)
        for t in on_part["thickness"]:
            self.assertLessEqual(abs(t - 2.0), 0.125)
        self.assertEqual(on_part["thin_region"], [1] * 8)
        path = os.path.join(self.tmp, "box.stl")
        with open(path, "wb") as f:
            f.write(BOX)
        out = os.path.join(self.tmp, "analyze")
        r = subprocess.run([VOXD, "analyze", path, "-o", out, "--params", json.dumps(params), "--min-wall", "2.5"],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        dest = os.path.join(self.tmp, "box.glb")
        self.assertEqual(self.client.thickness_on_part(job, "glb", dest, min_wall=2.5), dest)
        for fmt, got in (("glb", open(dest, "rb").read()), ("ply", self.client.thickness_on_part(job, "ply", min_wall=2.5))):
            with open(os.path.join(out, "thickness-on-part." + fmt), "rb") as f:
                self.assertEqual(got, f.read(), fmt)

    def test_bad_parameters_raise_invalid_params_with_their_paths(self):
        with self.assertRaises(InvalidParams) as caught:
            self.client.submit(BOX, {"grid": {"resolution": -3}, "mode": "nonsense"}, filename="box.stl")
        e = caught.exception
        self.assertEqual(e.status, 422)
        self.assertEqual(e.slug, "invalid-params")
        paths = sorted(err["path"] for err in e.errors)
        self.assertEqual(paths, ["/grid/resolution", "/mode"])
        self.assertIn("/grid/resolution", str(e))

    def test_a_broken_mesh_raises_invalid_mesh(self):
        with self.assertRaises(InvalidMesh) as caught:
            self.client.submit(b"solid broken\n  facet normal 0 0 1\n", {"grid": {"resolution": 8}}, filename="x.stl")
        self.assertEqual(caught.exception.status, 422)
        self.assertTrue(caught.exception.detail)

    def test_unknown_jobs_and_wrong_queries(self):
        with self.assertRaises(NotFound):
            self.client.job("0" * 32)
        with self.assertRaises(NotFound):
            self.client.wait("0" * 32)
        job = self.client.run(BOX, {"grid": {"resolution": 8}}, filename="box.stl")
        with self.assertRaises(InvalidQuery) as caught:
            self.client.volume(job, "vox")
        self.assertIn("vox", caught.exception.detail)
        with self.assertRaises(InvalidQuery):
            self.client.download(job, "palette")  # a solid job has no palette: wrong-mode

    def test_jobs_lists_every_job_page_by_page(self):
        ids = {self.client.submit(BOX, {"grid": {"resolution": 10 + i}}, filename="box.stl")["id"] for i in range(5)}
        listed = [j["id"] for j in self.client.jobs(page_size=2)]
        self.assertTrue(ids.issubset(listed))
        self.assertEqual(len(listed), len(set(listed)))

    def test_names_and_tags_find_jobs_again(self):
        tags = {"project": "pump-%d" % os.getpid(), "rev": "b"}
        named = self.client.submit(BOX, {"grid": {"resolution": 30}}, filename="box.stl", name="housing", tags=tags)
        self.assertEqual(named["name"], "housing")
        self.assertEqual(named["tags"], tags)
        default = self.client.submit(BOX, {"grid": {"resolution": 31}}, filename="C:\\parts\\bracket.stl",
                                     tags={"project": tags["project"]})
        self.assertEqual(default["name"], "bracket.stl", "the uploaded file's name, without its directory")
        self.assertEqual([j["id"] for j in self.client.jobs(tags={"project": tags["project"]})],
                         [default["id"], named["id"]])
        self.assertEqual([j["id"] for j in self.client.jobs(tags=tags)], [named["id"]])
        self.assertEqual([j["id"] for j in self.client.jobs(name="bracket.stl", tags={"project": tags["project"]})],
                         [default["id"]])
        with self.assertRaises(InvalidParams) as caught:
            self.client.submit(BOX, {}, filename="box.stl", callback="http://127.0.0.1:1/")
        self.assertEqual(caught.exception.errors[0]["path"], "/callback")

    def test_events_parser_reads_what_the_service_streams(self):
        job = self.client.run(BOX, {"grid": {"resolution": 8}}, filename="box.stl")
        with self.client.http.open("GET", f"/v1/jobs/{job['id']}/events") as stream:
            events = list(read_events(stream))
        self.assertEqual([e.name for e in events], ["job", "end"])  # already finished: its state, then the end
        self.assertEqual(events[-1].data["id"], job["id"])
        self.assertTrue(int(events[-1].id) > int(events[0].id))


BIG_JOB = {"grid": {"resolution": 500}, "mode": "sdf", "sdf": {"band": "full"}}  # seconds of work


class JobsThatDoNotSucceed(unittest.TestCase):
    """One worker, so a second job waits in the queue behind a large one."""

    def setUp(self):
        self.server = VoxdServer(workers=1)
        self.client = VoxdClient(self.server.url, timeout=30)

    def tearDown(self):
        self.server.stop()

    def running(self, job):
        for _ in range(600):
            status = self.client.job(job)
            if status["state"] == "running":
                return status
            threading.Event().wait(0.02)
        self.fail(f"job {job['id']} never ran")

    def test_a_cancelled_job_raises_job_cancelled_and_the_queue_goes_on(self):
        big = self.client.submit(os.path.join(TEST_PARTS, "screw.stl"), BIG_JOB)
        self.running(big)
        queued = self.client.submit(BOX, {"grid": {"resolution": 9}}, filename="box.stl")
        self.assertEqual(self.client.job(queued)["state"], "queued")
        with self.assertRaises(NotFinished) as caught:
            self.client.volume(queued)
        self.assertEqual(caught.exception.status, 409)
        with self.assertRaises(WaitTimeout) as timed_out:
            self.client.wait(big, timeout=0.3, use_events=False)
        self.assertEqual(timed_out.exception.job["state"], "running")
        with self.assertRaises(WaitTimeout):
            self.client.wait(big, timeout=0.3)  # the event stream gives up too
        self.client.cancel(big)
        with self.assertRaises(JobCancelled) as caught:
            self.client.wait(big)
        self.assertEqual(caught.exception.job["state"], "cancelled")
        self.assertEqual(self.client.wait(queued)["state"], "succeeded")

    def test_a_job_interrupted_by_a_restart_raises_job_failed_with_its_problem(self):
        big = self.client.submit(os.path.join(TEST_PARTS, "screw.stl"), BIG_JOB)
        self.running(big)
        self.server.stop(kill=True, keep_data=True)
        self.server = VoxdServer(workers=1, data_dir=self.server.data_dir)
        client = VoxdClient(self.server.url, timeout=30)
        with self.assertRaises(JobFailed) as caught:
            client.wait(big)
        e = caught.exception
        self.assertEqual(e.job["state"], "failed")
        self.assertEqual(e.problem, e.job["error"])
        self.assertIn("interrupted", e.detail + e.slug)


class BusyService(unittest.TestCase):
    """The retry on 429 with Retry-After, against a stub that is busy twice."""

    def test_busy_answers_are_retried_after_retry_after_then_raised(self):
        answers = [429, 429, 200]
        seen = []

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self):  # noqa: N802
                status = answers.pop(0) if answers else 429
                seen.append(self.path)
                body = json.dumps({"status": "ok"} if status == 200 else
                                  {"type": "urn:voxd:problem:queue-full", "title": "Busy", "status": 429,
                                   "detail": "the job queue is full"}).encode()
                self.send_response(status)
                self.send_header("Content-Type", "application/json" if status == 200 else "application/problem+json")
                if status != 200:
                    self.send_header("Retry-After", "7")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, *args):
                pass

        stub = http.server.HTTPServer(("127.0.0.1", 0), Handler)
        threading.Thread(target=stub.serve_forever, daemon=True).start()
        try:
            waits = []
            client = VoxdClient(f"http://127.0.0.1:{stub.server_port}", retries=2)
            client.http.sleep = waits.append
            self.assertEqual(client.health(), {"status": "ok"})
            self.assertEqual(len(seen), 3)
            self.assertEqual(len(waits), 2)
            self.assertTrue(all(7 <= w <= 7.7 for w in waits), waits)
            answers.extend([429, 429, 429])
            with self.assertRaises(Busy) as caught:
                client.health()
            self.assertEqual(caught.exception.retry_after, 7)
            self.assertEqual(caught.exception.slug, "queue-full")
        finally:
            stub.shutdown()
            stub.server_close()

    def test_an_unreachable_server_is_a_transport_error(self):
        with self.assertRaises(TransportError):
            VoxdClient("http://127.0.0.1:9", timeout=2).health()


class StubServer:
    """An HTTP server on loopback whose handler the test writes: for answers
    no real voxd gives (a body cut short, a redirect to another host)."""

    def __init__(self, do_get, host="127.0.0.1"):
        self.seen = []
        seen = self.seen

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self):  # noqa: N802
                seen.append((self.path, self.headers.get("Authorization")))
                do_get(self)

            def log_message(self, *args):
                pass

        self.server = http.server.HTTPServer((host, 0), Handler)
        self.url = f"http://{host}:{self.server.server_port}"
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def close(self):
        self.server.shutdown()
        self.server.server_close()


class EdgeAnswers(unittest.TestCase):
    """Issue #37's finding 8: a download cut short is an error, never a
    whole file; the API key goes to no other host on a redirect."""

    def test_a_fixed_length_answer_cut_short_is_a_transport_error_and_no_file(self):
        def cut(handler):
            handler.send_response(200)
            handler.send_header("Content-Type", "application/json")
            handler.send_header("Content-Length", "100000")
            handler.end_headers()
            handler.wfile.write(b"{" + b" " * 4999)
            handler.wfile.flush()
            handler.close_connection = True

        stub = StubServer(cut)
        try:
            client = VoxdClient(stub.url, timeout=10)
            dest = os.path.join(tempfile.mkdtemp(prefix="voxd-cut-"), "report.json")
            with self.assertRaises(TransportError) as caught:
                client.download("0" * 32, "analysis", dest=dest)
            self.assertIn("5000 of 100000 bytes", str(caught.exception))
            self.assertFalse(os.path.exists(dest))
            self.assertFalse(os.path.exists(dest + ".partial"))
            with self.assertRaises(TransportError):
                client.download("0" * 32, "preview")
            with self.assertRaises(TransportError):
                client.analysis("0" * 32)
        finally:
            stub.close()

    def test_the_api_key_follows_a_redirect_only_to_the_same_origin(self):
        def target(handler):
            body = b"result"
            handler.send_response(200)
            handler.send_header("Content-Length", str(len(body)))
            handler.end_headers()
            handler.wfile.write(body)

        # Another host: 127.0.0.2 is loopback too, but not the same origin.
        other = StubServer(target, host="127.0.0.2")

        def redirect(handler):
            if handler.path.endswith("/same"):
                location = "/final"
            else:
                location = other.url + "/final"
            if handler.path == "/final":
                return target(handler)
            handler.send_response(302)
            handler.send_header("Location", location)
            handler.send_header("Content-Length", "0")
            handler.end_headers()

        home = StubServer(redirect)
        try:
            client = VoxdClient(home.url, api_key="secret-key", timeout=10)
            self.assertEqual(client.download("0" * 32, "elsewhere"), b"result")
            self.assertEqual(other.seen, [("/final", None)], "the key went to another host")
            self.assertEqual(client.download("0" * 32, "same"), b"result")
            self.assertEqual(home.seen[-1], ("/final", "Bearer secret-key"))
        finally:
            home.close()
            other.close()


if __name__ == "__main__":
    unittest.main()
