"""VoxdClient: submit a mesh with its job parameters, follow the job to its
end, fetch what it made. Standard library only."""
from __future__ import annotations

import json
import os
import socket
import time
from typing import IO, Any, Callable, Dict, Iterator, Mapping, Optional, Union

from .errors import JobCancelled, JobFailed, NotFound, ProblemError, TransportError, WaitTimeout
from .events import read_events
from .transport import Transport, multipart_body

DEFAULT_SERVER = "http://127.0.0.1:8080"
TERMINAL_STATES = ("succeeded", "failed", "cancelled")

MeshInput = Union[str, "os.PathLike[str]", bytes, bytearray, memoryview, IO[bytes]]
JobRef = Union[str, Mapping[str, Any]]
Progress = Callable[[Dict[str, Any]], None]


def job_id(job: JobRef) -> str:
    """A job's id, from its id or its status."""
    if isinstance(job, str):
        return job
    return str(job["id"])


class VoxdClient:
    """A client of one voxd service.

    ``server`` defaults to $VOXD_SERVER, then http://127.0.0.1:8080, and
    ``api_key`` to $VOXD_API_KEY. Answers of a busy service (429, 503) are
    retried up to ``retries`` times after the Retry-After it names (at most
    ``max_retry_wait`` seconds each); every other error answer raises the
    ProblemError subclass of its problem type.
    """

    def __init__(self, server: Optional[str] = None, api_key: Optional[str] = None, timeout: float = 60.0,
                 retries: int = 5, max_retry_wait: float = 60.0):
        self.server = (server or os.environ.get("VOXD_SERVER") or DEFAULT_SERVER).rstrip("/")
        self.http = Transport(self.server, api_key or os.environ.get("VOXD_API_KEY") or None, timeout, retries,
                              max_retry_wait)

    # ---- jobs -------------------------------------------------------------

    def submit(self, mesh: MeshInput, params: Optional[Mapping[str, Any]] = None,
               filename: Optional[str] = None, name: Optional[str] = None,
               tags: Optional[Mapping[str, str]] = None, callback: Optional[str] = None) -> Dict[str, Any]:
        """Uploads a mesh (a path, bytes or a binary file) with the job
        parameters (proto-schemas/job-params.schema.json) and returns the
        job's status (queued, or already succeeded when an identical job's
        result is kept). ``name`` (default: the file's name) and ``tags``
        find the job again in ``jobs()``; ``callback`` is a URL the service
        calls, signed, when the job ends (docs/security.md, Webhooks)."""
        data, file_name = _mesh_bytes(mesh, filename)
        parts = [("mesh", file_name, data, "application/octet-stream")]
        if params is not None:
            parts.append(("params", "", json.dumps(params).encode(), "application/json"))
        if name is not None:
            parts.append(("name", "", name.encode(), "text/plain; charset=utf-8"))
        if tags is not None:
            parts.append(("tags", "", json.dumps(dict(tags)).encode(), "application/json"))
        if callback is not None:
            parts.append(("callback", "", callback.encode(), "text/plain"))
        body, content_type = multipart_body(parts)
        return self.http.json("POST", "/v1/jobs", body=body, headers={"Content-Type": content_type})

    def job(self, job: JobRef) -> Dict[str, Any]:
        """The job's status now."""
        return self.http.json("GET", f"/v1/jobs/{job_id(job)}")

    def jobs(self, page_size: int = 100, name: Optional[str] = None,
             tags: Optional[Mapping[str, str]] = None) -> Iterator[Dict[str, Any]]:
        """Every job the service keeps for this key's tenant, newest first,
        page after page; only those of this ``name`` and carrying every one
        of these ``tags`` when given."""
        offset = 0
        while True:
            query: Dict[str, Any] = {"offset": offset, "limit": page_size}
            if name is not None:
                query["name"] = name
            if tags:
                query["tag"] = tuple(f"{k}:{v}" for k, v in tags.items())
            page = self.http.json("GET", "/v1/jobs", query=query)
            yield from page["jobs"]
            if not page.get("next") or not page["jobs"]:
                return
            offset += len(page["jobs"])

    def cancel(self, job: JobRef) -> Optional[Dict[str, Any]]:
        """Cancels a queued or running job, or deletes a finished one with its
        results. Returns the answer's JSON (a cancelled job's status), if any."""
        with self.http.open("DELETE", f"/v1/jobs/{job_id(job)}") as response:
            data = response.read()
        return json.loads(data) if data else None

    delete = cancel

    def wait(self, job: JobRef, timeout: Optional[float] = None, on_progress: Optional[Progress] = None,
             use_events: bool = True) -> Dict[str, Any]:
        """Waits for the job's end and returns its final status when it
        succeeded; raises JobFailed (with the job's problem) or JobCancelled
        otherwise, WaitTimeout after ``timeout`` seconds. Follows the job's
        server-sent events where the service has them, else polls with a
        growing interval. ``on_progress`` gets each status change ({"state",
        "progress", "stage", ...})."""
        deadline = None if timeout is None else time.monotonic() + timeout
        status = job if isinstance(job, Mapping) and "state" in job else None
        ident = job_id(job)
        if use_events and (status is None or status["state"] not in TERMINAL_STATES):
            final = self._follow_events(ident, deadline, on_progress)
            if final is not None:
                return _finished(final)
        return _finished(self._poll(ident, deadline, on_progress))

    def run(self, mesh: MeshInput, params: Optional[Mapping[str, Any]] = None, filename: Optional[str] = None,
            timeout: Optional[float] = None, on_progress: Optional[Progress] = None) -> Dict[str, Any]:
        """submit() then wait(): the succeeded job's status."""
        return self.wait(self.submit(mesh, params, filename), timeout=timeout, on_progress=on_progress)

    # ---- results ----------------------------------------------------------

    def download(self, job: JobRef, route: str = "volume", dest: Optional[Union[str, "os.PathLike[str]"]] = None,
                 **query: Any) -> Union[bytes, str]:
        """A finished job's result: ``route`` is volume, radiography, section,
        preview, thickness, layers/K, palette or analysis, ``query`` its
        parameters (format="nrrd", axis="z", ...). Written to ``dest`` (whole,
        or not at all) and its path returned, or returned as bytes."""
        path = f"/v1/jobs/{job_id(job)}/{route.lstrip('/')}"
        return self._fetch(path, query, dest)

    def volume(self, job: JobRef, format: str = "rle", dest: Optional[Union[str, "os.PathLike[str]"]] = None,
               **query: Any) -> Union[bytes, str]:
        """The job's volume in ``format`` (rle, binvox, raw, nrrd, vox,
        png-stack, stl, glb: the job status's links.downloads lists those it
        offers)."""
        return self.download(job, "volume", dest, format=format, **query)

    def analysis(self, job: JobRef, **query: Any) -> Dict[str, Any]:
        """The manufacturing analysis report (proto-schemas/analysis.schema.json),
        e.g. analysis(job, min_wall=0.8, max_wall=6)."""
        return json.loads(self.download(job, "analysis", **query))

    def thickness_on_part(self, job: JobRef, format: str = "json",
                          dest: Optional[Union[str, "os.PathLike[str]"]] = None,
                          **query: Any) -> Union[bytes, str, Dict[str, Any]]:
        """The wall thickness painted on the job's own mesh: ``format`` ply
        (a float ``thickness`` and a colour per vertex), glb (vertex colours
        and ``_THICKNESS``) or json (per-vertex values, the surface's
        min/max/mean and each vertex's thin region, returned as a dict);
        ``min_wall``/``max_wall`` (model units) set the colours' ends and
        the thin regions, e.g. thickness_on_part(job, "glb", "part.glb",
        min_wall=0.8, max_wall=3)."""
        result = self.download(job, "thickness", dest, format=format, **query)
        return json.loads(result) if format == "json" and dest is None else result

    def job_analysis(self, job: Mapping[str, Any], index: int,
                     dest: Optional[Union[str, "os.PathLike[str]"]] = None) -> Union[bytes, str]:
        """Entry ``index`` of the job JSON's "analyses", as the worker kept it."""
        entry = job["analyses"][index]
        if entry.get("state") == "failed":
            raise ProblemError({"type": "urn:voxd:problem:invalid-query", "status": 400, "title": "Analysis failed",
                                "detail": f"analyses/{index}: {entry.get('error') or 'failed'}"})
        return self._fetch(entry["url"], None, dest)

    # ---- the service ------------------------------------------------------

    def health(self) -> Dict[str, Any]:
        return self.http.json("GET", "/healthz")

    def ready(self) -> bool:
        try:
            return self.http.json("GET", "/readyz", retry=False).get("status") == "ready"
        except ProblemError:
            return False

    def openapi(self) -> Dict[str, Any]:
        """The service's contract (self-contained OpenAPI 3.1)."""
        return self.http.json("GET", "/openapi.json")

    # ---- internals --------------------------------------------------------

    def _fetch(self, path: str, query: Optional[Mapping[str, Any]], dest) -> Union[bytes, str]:
        with self.http.open("GET", path, query=query) as response:
            if dest is None:
                return self.http.read_whole(response, f"GET {path}")
            dest = os.fspath(dest)
            partial = dest + ".partial"
            try:
                with open(partial, "wb") as out:
                    self.http.read_whole(response, f"GET {path}", out.write)
                os.replace(partial, dest)
            except BaseException:
                if os.path.exists(partial):
                    os.remove(partial)
                raise
            return dest

    def _follow_events(self, ident: str, deadline: Optional[float], on_progress: Optional[Progress]):
        """The final status from the event stream, or None to poll instead
        (no stream on this service, or the stream broke off)."""
        status: Dict[str, Any] = {"id": ident}
        try:
            # The stream sends a keep-alive at least every 15 s.
            read_timeout = 45.0 if deadline is None else max(1.0, min(45.0, deadline - time.monotonic()))
            response = self.http.open("GET", f"/v1/jobs/{ident}/events", headers={"Accept": "text/event-stream"},
                                      timeout=read_timeout)
        except NotFound:
            raise
        except ProblemError as e:
            if e.status in (404, 405, 406, 501):
                return None
            raise
        except TransportError:
            return None
        with response:
            if response.status == 204:
                return None
            try:
                for event in read_events(response):
                    if event.name in ("job", "end"):
                        status = dict(event.data)
                    elif event.name in ("state", "progress"):
                        status.update(event.data)
                    elif event.name == "analysis":
                        continue
                    elif event.name == "gone":
                        raise NotFound({"type": "urn:voxd:problem:not-found", "title": "Not found", "status": 404,
                                        "detail": event.data.get("detail", f"job {ident} is gone")})
                    if on_progress:
                        on_progress(dict(status))
                    if event.name == "end":
                        return status
                    if deadline is not None and time.monotonic() > deadline:
                        raise WaitTimeout(status, 0)
            except (socket.timeout, OSError):
                if deadline is not None and time.monotonic() > deadline:
                    raise WaitTimeout(status, 0) from None
                return None
        return None  # the stream ended without "end": poll

    def _poll(self, ident: str, deadline: Optional[float], on_progress: Optional[Progress]) -> Dict[str, Any]:
        interval, seen = 0.2, None
        start = time.monotonic()
        while True:
            status = self.job(ident)
            key = (status.get("state"), status.get("progress"), status.get("stage"))
            if on_progress and key != seen:
                on_progress(dict(status))
            seen = key
            if status["state"] in TERMINAL_STATES:
                return status
            if deadline is not None and time.monotonic() + interval > deadline:
                raise WaitTimeout(status, time.monotonic() - start)
            time.sleep(interval)
            interval = min(interval * 1.5, 5.0)


def _finished(status: Dict[str, Any]) -> Dict[str, Any]:
    if status["state"] == "failed":
        raise JobFailed(status)
    if status["state"] == "cancelled":
        raise JobCancelled(status)
    return status


def _mesh_bytes(mesh: MeshInput, filename: Optional[str]):
    if isinstance(mesh, (bytes, bytearray, memoryview)):
        return bytes(mesh), filename or "mesh"
    if isinstance(mesh, (str, os.PathLike)):
        path = os.fspath(mesh)
        with open(path, "rb") as f:
            return f.read(), filename or os.path.basename(path)
    if hasattr(mesh, "read"):
        return mesh.read(), filename or os.path.basename(getattr(mesh, "name", "mesh"))
    raise TypeError("mesh must be a path, bytes or a binary file")
