"""A reader of server-sent events (the job's /events stream), as EventSource
parses them: ``event:``, ``data:`` (joined by newlines), ``id:``, comments and
``retry:`` ignored, an event dispatched at each blank line."""
from __future__ import annotations

import json
from typing import IO, Any, Iterator, NamedTuple, Optional


class Event(NamedTuple):
    name: str
    data: Any          # the JSON the service sends as data
    id: Optional[str]


def read_events(stream: IO[bytes]) -> Iterator[Event]:
    name, data, last_id = "message", [], None
    while True:
        raw = stream.readline()
        if not raw:
            return  # the server closed the stream
        line = raw.decode("utf-8").rstrip("\r\n")
        if not line:
            if data:
                text = "\n".join(data)
                try:
                    payload = json.loads(text)
                except ValueError:
                    payload = text
                yield Event(name, payload, last_id)
            name, data = "message", []
            continue
        if line.startswith(":"):
            continue  # keep-alive comment
        field, _, value = line.partition(":")
        if value.startswith(" "):
            value = value[1:]
        if field == "event":
            name = value
        elif field == "data":
            data.append(value)
        elif field == "id":
            last_id = value
