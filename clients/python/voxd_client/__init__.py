"""Python client of the voxd voxelization service (standard library only).

    from voxd_client import VoxdClient
    client = VoxdClient("http://127.0.0.1:8080")
    job = client.run("part.stl", {"grid": {"resolution": 256}})
    client.volume(job, "nrrd", dest="part.nrrd")
    report = client.analysis(job, min_wall=0.8)
"""
from .client import DEFAULT_SERVER, TERMINAL_STATES, VoxdClient, job_id
from .errors import (Busy, InvalidMesh, InvalidParams, InvalidQuery, JobCancelled, JobFailed, NotFinished, NotFound,
                     ProblemError, TransportError, Unauthorized, VoxdError, WaitTimeout)
from .events import Event, read_events

__all__ = [
    "DEFAULT_SERVER", "TERMINAL_STATES", "VoxdClient", "job_id", "Event", "read_events",
    "VoxdError", "TransportError", "ProblemError", "InvalidParams", "InvalidMesh", "InvalidQuery", "NotFound",
    "NotFinished", "Unauthorized", "Busy", "JobFailed", "JobCancelled", "WaitTimeout",
]
__version__ = "0.1.0"
