"""HTTP for the client: urllib only, problem answers turned into typed errors,
and the retries a busy service asks for (429/503 with Retry-After)."""
from __future__ import annotations

import http.client
import json
import random
import time
import urllib.error
import urllib.parse
import urllib.request
import uuid
from typing import Any, Callable, Dict, Iterable, Mapping, Optional, Tuple

from .errors import Busy, ProblemError, TransportError, problem_error

USER_AGENT = "voxd-client-python/0.1"


def retry_after_seconds(value: Optional[str]) -> Optional[float]:
    """Retry-After as seconds (the service sends delta-seconds)."""
    if not value:
        return None
    try:
        return max(0.0, float(value))
    except ValueError:
        return None


def multipart_body(fields: Iterable[Tuple[str, str, bytes, Optional[str]]]) -> Tuple[bytes, str]:
    """(name, filename or "", bytes, content type) parts -> (body, Content-Type)."""
    boundary = "voxd-" + uuid.uuid4().hex
    out = bytearray()
    for name, filename, data, content_type in fields:
        out += f"--{boundary}\r\n".encode()
        disposition = f'form-data; name="{name}"'
        if filename:
            safe = filename.replace('"', "_").replace("\r", "_").replace("\n", "_")
            disposition += f'; filename="{safe}"'
        out += f"Content-Disposition: {disposition}\r\n".encode()
        if content_type:
            out += f"Content-Type: {content_type}\r\n".encode()
        out += b"\r\n" + data + b"\r\n"
    out += f"--{boundary}--\r\n".encode()
    return bytes(out), f"multipart/form-data; boundary={boundary}"


class _SameOriginRedirects(urllib.request.HTTPRedirectHandler):
    """Follows redirects, but sends the API key only to the origin it was
    meant for: a redirect to another host, port or scheme drops it."""

    def redirect_request(self, req, fp, code, msg, headers, newurl):
        new = super().redirect_request(req, fp, code, msg, headers, newurl)
        if new is not None and _origin(new.full_url) != _origin(req.full_url):
            for name in list(new.headers):
                if name.lower() == "authorization":
                    del new.headers[name]
        return new


def _origin(url: str) -> Tuple[str, str, Optional[int]]:
    parts = urllib.parse.urlsplit(url)
    default = 443 if parts.scheme == "https" else 80
    return parts.scheme.lower(), (parts.hostname or "").lower(), parts.port or default


class Transport:
    def __init__(self, base_url: str, api_key: Optional[str], timeout: float, retries: int, max_retry_wait: float,
                 sleep: Callable[[float], None] = time.sleep):
        if not base_url.startswith(("http://", "https://")):
            raise ValueError(f"the server URL must start with http:// or https://, got {base_url!r}")
        self.base_url = base_url.rstrip("/")
        self.api_key = api_key
        self.timeout = timeout
        self.retries = retries
        self.max_retry_wait = max_retry_wait
        self.sleep = sleep
        self._opener = urllib.request.build_opener(_SameOriginRedirects)

    def url(self, path: str, query: Optional[Mapping[str, Any]] = None) -> str:
        if path.startswith(("http://", "https://")):
            url = path
        else:
            url = self.base_url + (path if path.startswith("/") else "/" + path)
        if query:
            # A tuple is a parameter given once per item (tag=a:1&tag=b:2).
            pairs = [(k, _query_text(item)) for k, v in query.items() if v is not None
                     for item in (v if isinstance(v, tuple) else (v,))]
            url += ("&" if "?" in url else "?") + urllib.parse.urlencode(pairs)
        return url

    def open(self, method: str, path: str, query: Optional[Mapping[str, Any]] = None, body: Optional[bytes] = None,
             headers: Optional[Dict[str, str]] = None, timeout: Optional[float] = None, retry: bool = True):
        """The open response of a 2xx answer (the caller reads and closes it);
        raises the problem's error otherwise. Busy answers are retried up to
        ``retries`` times, after the Retry-After the service names."""
        attempt = 0
        while True:
            request = urllib.request.Request(self.url(path, query), data=body, method=method)
            request.add_header("User-Agent", USER_AGENT)
            request.add_header("Accept-Encoding", "identity")
            if self.api_key:
                request.add_header("Authorization", f"Bearer {self.api_key}")
            for k, v in (headers or {}).items():
                request.add_header(k, v)
            try:
                return self._opener.open(request, timeout=timeout or self.timeout)
            except urllib.error.HTTPError as answer:
                error = self._problem_of(answer)
                if isinstance(error, Busy) and retry and attempt < self.retries:
                    attempt += 1
                    wait = error.retry_after if error.retry_after is not None else min(2.0 ** attempt, 30.0)
                    # A little jitter so a batch of clients does not come back at once.
                    self.sleep(min(wait, self.max_retry_wait) * (1.0 + 0.1 * random.random()))
                    continue
                raise error from None
            except (urllib.error.URLError, OSError) as e:
                raise TransportError(f"{method} {self.url(path)}: {getattr(e, 'reason', e)}") from e

    @staticmethod
    def read_whole(response, what: str, write: Optional[Callable[[bytes], Any]] = None) -> Optional[bytes]:
        """The answer's body, all of it: a body that ends before its
        Content-Length (the connection cut) raises TransportError rather than
        passing for a whole result. With ``write``, chunks go there instead."""
        expected = response.headers.get("Content-Length")
        got = 0
        chunks = []
        try:
            while True:
                chunk = response.read(1 << 20)
                if not chunk:
                    break
                got += len(chunk)
                if write is None:
                    chunks.append(chunk)
                else:
                    write(chunk)
        except (http.client.HTTPException, OSError) as e:
            raise TransportError(f"{what}: the answer broke off after {got} bytes: {e}") from e
        if expected is not None and expected.isdigit() and got != int(expected):
            raise TransportError(f"{what}: the answer was cut short: {got} of {expected} bytes")
        return b"".join(chunks) if write is None else None

    def json(self, method: str, path: str, **kwargs) -> Any:
        with self.open(method, path, **kwargs) as response:
            data = self.read_whole(response, f"{method} {path}")
        try:
            return json.loads(data) if data else None
        except ValueError as e:
            raise TransportError(f"{method} {path}: the answer is not JSON: {data[:200]!r}") from e

    @staticmethod
    def _problem_of(answer: urllib.error.HTTPError) -> ProblemError:
        try:
            raw = answer.read()
        finally:
            answer.close()
        retry_after = retry_after_seconds(answer.headers.get("Retry-After"))
        try:
            problem = json.loads(raw)
            if not isinstance(problem, dict):
                raise ValueError
        except ValueError:
            problem = {"type": "urn:voxd:problem:http", "title": answer.reason or "HTTP error", "status": answer.code,
                       "detail": raw[:500].decode("utf-8", "replace")}
        return problem_error(problem, answer.code, retry_after)


def _query_text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (dict, list)):
        return json.dumps(value, separators=(",", ":"))
    return str(value)
