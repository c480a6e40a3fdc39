#!/usr/bin/env python3
"""Every code block of README.md, run as a reader would against a real
`voxd serve` on a loopback ephemeral port.

check_readme.py REPO VOXD_BINARY TEST_PARTS

- ```json blocks are job parameters: valid under job-params.schema.json and
  accepted by `voxd voxelize`.
- ```sh blocks run line by line in a scratch folder where part.stl is a real
  mesh (the screw the build writes, tests/support/test_parts.h), part.drc its
  Draco encoding, job.json a job
  and parts/ a folder of meshes; `voxd` is the built binary,
  http://127.0.0.1:8080 the test's server, and ID the id of the job the
  last submission answered (the test waits for it to end, as a reader
  would). Each line must exit 0; a `-o FILE` must be written and not hold a
  problem; a submission must answer a job; an event stream must end.
- Lines the suite runs elsewhere are named in SKIPPED, with where; any
  other line the checker does not know fails, so a new example cannot go
  untested.
"""
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

import jsonschema

repo, voxd, parts = (os.path.abspath(a) for a in sys.argv[1:4])
README = os.path.join(repo, "README.md")
SKIPPED = {
    "./scripts/start.sh": "builds and starts the service on port 8080: what CI's own build and these tests start",
    "./scripts/test.sh": "the test command itself (.ci/run)",
    "cmake -S . -B build-lib": "tests/tools/install_consumer_test.sh (ctest install.consumer)",
    "cmake --build build-lib": "tests/tools/install_consumer_test.sh (ctest install.consumer)",
}
failures = []


def fail(where, message):
    failures.append(f"README.md:{where}: {message}")
    print(f"FAIL README.md:{where}: {message}", flush=True)


def blocks():
    """(language, first line number, [(line number, text)]) of each fenced block."""
    lines = open(README).read().split("\n")
    i = 0
    while i < len(lines):
        m = re.match(r"^```(\w*)\s*$", lines[i])
        if not m:
            i += 1
            continue
        lang, start, body = m.group(1), i + 1, []
        i += 1
        while i < len(lines) and not lines[i].startswith("```"):
            body.append((i + 1, lines[i]))
            i += 1
        i += 1
        yield lang, start, body


def start_server(data):
    p = subprocess.Popen([voxd, "serve", "--host", "127.0.0.1", "--port", "0", "--data-dir", data, "--workers", "2"],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    found, url = threading.Event(), []

    def read():
        for line in p.stdout:
            m = re.search(r"listening on (http://127\.0\.0\.1:\d+)", line)
            if m and not url:
                url.append(m.group(1))
                found.set()
        found.set()

    threading.Thread(target=read, daemon=True).start()
    found.wait(30)
    if not url:
        sys.exit("voxd serve did not start")
    return p, url[0]


def wait_for(base, job_id, where):
    for _ in range(6000):
        with urllib.request.urlopen(f"{base}/v1/jobs/{job_id}") as r:
            job = json.load(r)
        if job["state"] in ("succeeded", "failed", "cancelled"):
            if job["state"] != "succeeded":
                fail(where, f"job {job_id} ended {job['state']}: {job.get('error')}")
            return
        time.sleep(0.05)
    fail(where, f"job {job_id} did not end")


def is_problem(path):
    try:
        with open(path, "rb") as f:
            body = json.load(f)
    except (ValueError, UnicodeDecodeError):
        return False
    return isinstance(body, dict) and str(body.get("type", "")).startswith("urn:voxd:problem:")


def output_file(argv):
    for flag in ("-o", "--output"):
        if flag in argv:
            value = argv[argv.index(flag) + 1]
            return None if value == "-" else value
    return None


def main():
    schema = json.load(open(os.path.join(repo, "proto-schemas", "job-params.schema.json")))
    work = tempfile.mkdtemp(prefix="voxd-readme-")
    bin_dir = os.path.join(work, "bin")
    os.mkdir(bin_dir)
    os.symlink(os.path.abspath(voxd), os.path.join(bin_dir, "voxd"))
    scratch = os.path.join(work, "scratch")
    os.mkdir(scratch)
    shutil.copy(os.path.join(parts, "screw.stl"), os.path.join(scratch, "part.stl"))
    subprocess.run(["draco_encoder", "-i", "part.stl", "-o", "part.drc"], cwd=scratch, check=True, capture_output=True)
    with open(os.path.join(scratch, "job.json"), "w") as f:
        json.dump({"grid": {"resolution": 64, "padding": 1}}, f)
    os.mkdir(os.path.join(scratch, "parts"))
    # Parts the README's batch example passes (walls 1.2 and 5.66 mm, within
    # its --min-wall 0.8 --max-wall 6).
    for name in ("hex_nut.stl", "torus.stl"):
        shutil.copy(os.path.join(parts, name), os.path.join(scratch, "parts", name))
    server, base = start_server(os.path.join(work, "data"))
    env = dict(os.environ, PATH=bin_dir + os.pathsep + os.environ["PATH"])
    env.pop("VOXD_SERVER", None)
    job_id = None
    ran = {"sh": 0, "json": 0, "skipped": 0}
    try:
        for lang, start, body in blocks():
            if lang == "json":
                text = "\n".join(t for _, t in body)
                where = str(start)
                try:
                    params = json.loads(text)
                    jsonschema.validate(params, schema)
                except (ValueError, jsonschema.ValidationError) as e:
                    fail(where, f"json block is not valid job parameters: {str(e)[:300]}")
                    continue
                r = subprocess.run([voxd, "voxelize", "part.stl", "-o", "block.rle", "--params", text], cwd=scratch,
                                   capture_output=True, text=True)
                if r.returncode != 0:
                    fail(where, f"voxd voxelize refuses the json block: {r.stderr.strip()}")
                ran["json"] += 1
                continue
            if lang != "sh":
                continue  # cmake: the consumer project, built by install.consumer
            for number, line in body:
                command = line.strip()
                if not command or command.startswith("#"):
                    continue
                where = str(number)
                if any(command.startswith(prefix) for prefix in SKIPPED):
                    ran["skipped"] += 1
                    continue
                program = command.split()[0]
                if program not in ("curl", "voxd", "python3"):
                    fail(where, f"the README checker does not know how to run `{program}`: teach tests/tools/check_readme.py")
                    continue
                text = command.replace("http://127.0.0.1:8080", base).replace("clients/python/", os.path.join(repo, "clients", "python") + "/")
                if re.search(r"\bID\b", text):
                    if job_id is None:
                        fail(where, "uses ID before any submission")
                        continue
                    text = re.sub(r"\bID\b", job_id, text)
                argv = shlex.split(text, comments=True)
                out = output_file(argv)
                if out and os.path.exists(os.path.join(scratch, out)):
                    os.remove(os.path.join(scratch, out))
                r = subprocess.run(["bash", "-o", "pipefail", "-c", text], cwd=scratch, env=env, capture_output=True,
                                   timeout=600)
                ran["sh"] += 1
                if r.returncode != 0:
                    fail(where, f"`{command}` exited {r.returncode}: {r.stderr.decode(errors='replace')[-500:]}"
                                f"{r.stdout.decode(errors='replace')[-300:]}")
                    continue
                if out:
                    path = os.path.join(scratch, out)
                    if not os.path.exists(path) or os.path.getsize(path) == 0:
                        fail(where, f"`{command}` wrote nothing to {out}")
                    elif is_problem(path):
                        fail(where, f"`{command}` saved a problem into {out}")
                if program == "curl" and "/events" in text and b"event: end" not in r.stdout:
                    fail(where, "the event stream did not end with an end event")
                if program == "curl" and re.search(r"/v1/jobs('|\?|$|\s)", text) and ("-F" in argv or "--data-binary" in argv):
                    try:
                        job_id = json.loads(r.stdout)["id"]
                    except (ValueError, KeyError):
                        fail(where, f"a submission that answered no job: {r.stdout[:200]!r}")
                        continue
                    wait_for(base, job_id, where)
    finally:
        server.terminate()
        server.wait(30)
        shutil.rmtree(work, ignore_errors=True)
    print(f"README: {ran['sh']} commands and {ran['json']} job JSON blocks ran, {ran['skipped']} lines run elsewhere")
    if ran["sh"] < 30:
        fail("-", f"only {ran['sh']} commands found: did the checker lose the README's blocks?")
    if failures:
        print("\n".join(failures))
        sys.exit(1)


main()
