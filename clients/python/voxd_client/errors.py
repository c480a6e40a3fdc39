"""Typed errors carrying the service's RFC 9457 problem details.

Every error answer of voxd is ``application/problem+json`` with ``type``
(``urn:voxd:problem:<slug>``), ``title``, ``status``, ``detail`` and, for bad
parameters, ``errors`` (JSON path and message of each). ``ProblemError``
keeps them all; its subclasses let a caller catch the cases it handles.
"""
from __future__ import annotations

from typing import Any, Dict, List, Optional


class VoxdError(Exception):
    """Anything this client raises."""


class TransportError(VoxdError):
    """The service could not be reached, or answered something that is not HTTP/JSON voxd speaks."""


class ProblemError(VoxdError):
    """An error answer of the service (or a failed job's error), with its problem's fields."""

    def __init__(self, problem: Dict[str, Any], status: Optional[int] = None, retry_after: Optional[float] = None):
        self.problem = dict(problem)
        self.type: str = str(problem.get("type", "urn:voxd:problem:unknown"))
        self.slug: str = self.type.rsplit(":", 1)[-1]
        self.title: str = str(problem.get("title", ""))
        self.status: int = int(problem.get("status", status or 0))
        self.detail: str = str(problem.get("detail", ""))
        self.instance: Optional[str] = problem.get("instance")
        self.errors: List[Dict[str, str]] = list(problem.get("errors", []))
        self.retry_after = retry_after
        message = f"{self.status} {self.slug}: {self.detail or self.title}"
        for e in self.errors:
            message += f"\n  {e.get('path', '')}: {e.get('message', '')}"
        super().__init__(message)


class InvalidParams(ProblemError):
    """422 invalid-params or limit-exceeded: see ``errors`` for the JSON path of each bad parameter."""


class InvalidMesh(ProblemError):
    """422 invalid-mesh, 415 unsupported-format, 400 missing-mesh, 413 upload-too-large: the upload itself."""


class InvalidQuery(ProblemError):
    """400 invalid-query or wrong-mode (409): the route cannot answer this request for this job."""


class NotFound(ProblemError):
    """404: no such job (never submitted, deleted, or expired)."""


class NotFinished(ProblemError):
    """409 job-not-finished: ask again when the job has succeeded (``VoxdClient.wait``)."""


class Unauthorized(ProblemError):
    """401: the service wants an API key (``VoxdClient(api_key=...)``)."""


class Busy(ProblemError):
    """429 or 503 (queue-full, quota-exceeded, memory-busy, too-many-requests, shutting-down, ...): retry after ``retry_after`` seconds."""


class JobFailed(ProblemError):
    """The job ended ``failed``: ``problem`` is the job's error, ``job`` its final status."""

    def __init__(self, job: Dict[str, Any]):
        self.job = job
        error = job.get("error") or {"type": "urn:voxd:problem:internal", "title": "Job failed", "status": 500,
                                     "detail": f"job {job.get('id')} failed without saying why"}
        super().__init__(error)


class JobCancelled(ProblemError):
    """The job ended ``cancelled`` (someone cancelled it)."""

    def __init__(self, job: Dict[str, Any]):
        self.job = job
        super().__init__(job.get("error") or {"type": "urn:voxd:problem:cancelled", "title": "The job was cancelled",
                                              "status": 409, "detail": f"job {job.get('id')} was cancelled"})


class WaitTimeout(VoxdError):
    """``wait`` gave up before the job ended; ``job`` is its last status."""

    def __init__(self, job: Dict[str, Any], seconds: float):
        self.job = job
        super().__init__(f"job {job.get('id')} still {job.get('state')} after {seconds:g} s")


_BY_SLUG = {
    "invalid-params": InvalidParams,
    "limit-exceeded": InvalidParams,
    "malformed-json": InvalidParams,
    "params-too-large": InvalidParams,
    "invalid-mesh": InvalidMesh,
    "unsupported-format": InvalidMesh,
    "unsupported-media-type": InvalidMesh,
    "missing-mesh": InvalidMesh,
    "upload-too-large": InvalidMesh,
    "invalid-query": InvalidQuery,
    "wrong-mode": InvalidQuery,
    "not-found": NotFound,
    "job-not-finished": NotFinished,
    "unauthorized": Unauthorized,
    "queue-full": Busy,
    "quota-exceeded": Busy,
    "memory-busy": Busy,
    "too-many-requests": Busy,
    "too-many-streams": Busy,
    "shutting-down": Busy,
    "backend-unavailable": Busy,
    "storage-full": Busy,
}


def problem_error(problem: Dict[str, Any], status: int, retry_after: Optional[float] = None) -> ProblemError:
    """The most specific error class for a problem body."""
    slug = str(problem.get("type", "")).rsplit(":", 1)[-1]
    cls = _BY_SLUG.get(slug)
    if cls is None:
        cls = Busy if status in (429, 503) else NotFound if status == 404 else ProblemError
    return cls(problem, status, retry_after)
