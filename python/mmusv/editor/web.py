"""The editor API's HTTP plumbing: errors as ``{"error": "..."}`` with the status of their kind (:func:`status_of`),
the request body size limit (:class:`BodyLimit`, 413 over :data:`MAX_BODY_BYTES`, whether or not the request says
its length), and the one-line messages for requests FastAPI cannot read (:func:`request_error`,
:func:`unreadable_body`) and for ``If-Match`` headers (:func:`if_match`).
"""

from __future__ import annotations

import re
from typing import get_args

from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from mmusv.editor.files import ChangedInFolder, FileExistsInFolder
from mmusv.editor.jobs import RunGoingOn
from mmusv.errors import ConfigError, InputError, MmusvError, NotFoundError

__all__ = [
    "CSP",
    "MAX_BODY_BYTES",
    "BodyLimit",
    "choices",
    "error",
    "if_match",
    "request_error",
    "status_of",
    "unreadable_body",
]

MAX_BODY_BYTES = 16 * 1024 * 1024
"""Largest request body (16 MiB); larger requests get 413."""
CSP = (
    "default-src 'self'; img-src 'self' data: blob:; style-src 'self'; script-src 'self'; connect-src 'self'; "
    "object-src 'none'; base-uri 'none'; frame-ancestors 'none'"
)
"""The Content-Security-Policy of every answer: the page loads nothing from elsewhere."""


def error(status: int, message: str) -> JSONResponse:
    """The API's error answer: ``{"error": message}`` with HTTP ``status``."""
    return JSONResponse({"error": message}, status_code=status)


def status_of(exc: MmusvError) -> int:
    """The HTTP status of an error of mmusv's tree: 409 a file exists or a run of it is going on, 412 the file
    changed (If-Match), 404 nothing of that name, 422 a scenario or request that does not validate, 400 other bad
    input, 500 anything else."""
    if isinstance(exc, (FileExistsInFolder, RunGoingOn)):
        return 409
    if isinstance(exc, ChangedInFolder):
        return 412
    if isinstance(exc, NotFoundError):
        return 404
    if isinstance(exc, ConfigError):
        return 422
    if isinstance(exc, InputError):
        return 400
    return 500


class _LimitedBody:
    """Refuses request bodies over ``limit`` bytes with 413, whether or not they say their length up front: the body
    is read here (at most ``limit`` bytes are kept) before the app sees the request, so a body streamed without a
    Content-Length (chunked) gets the same 413, not an error from whatever reads it."""

    def __init__(self, app: ASGIApp, limit: int) -> None:
        self.app, self.limit = app, limit

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        too_large = f"the request body is larger than {self.limit} bytes, the most the editor takes"
        length = dict(scope.get("headers") or []).get(b"content-length")
        if length is not None and not length.isdigit():
            shown = length.decode("latin-1")[:40]
            await error(400, f"the Content-Length header {shown!r} is not a number of bytes")(scope, receive, send)
            return
        if length is not None and int(length) > self.limit:
            await error(413, too_large)(scope, receive, send)
            return
        chunks: list[bytes] = []
        seen = 0
        while True:
            msg = await receive()
            if msg["type"] != "http.request":  # the client went away
                return
            chunk = msg.get("body", b"")
            seen += len(chunk)
            if seen > self.limit:
                await error(413, too_large)(scope, receive, send)
                return
            chunks.append(chunk)
            if not msg.get("more_body", False):
                break
        body: list[Message] = [{"type": "http.request", "body": b"".join(chunks), "more_body": False}]

        async def replay() -> Message:
            return body.pop() if body else await receive()

        await self.app(scope, replay, send)


def choices(model: type[BaseModel], name: str) -> list[str]:
    """The allowed values of the ``Literal`` field ``name`` of ``model`` (the page's drop-down lists)."""
    return list(get_args(model.model_fields[name].annotation))


def request_error(exc: RequestValidationError, content_type: str | None) -> str:
    parts = []
    for e in exc.errors():
        loc = ".".join(str(p) for p in e.get("loc", ()) if p != "body") or "body"
        if e.get("type") == "json_invalid":
            parts.append(f"the request body is not valid JSON ({e.get('ctx', {}).get('error', 'unreadable')})")
        elif loc == "body" and not _is_json(content_type):
            got = f"Content-Type {content_type!r}" if content_type else "no Content-Type"
            parts.append(f"body: the request body must be a JSON object sent as application/json (got {got})")
        elif e.get("type") == "string_pattern_mismatch" and loc == "path.job_id":  # it showed the regex itself
            parts.append(f"{loc} {e.get('input')!r}: a run is named by a whole number, as /api/runs lists them")
        else:
            parts.append(f"{loc}: {e.get('msg', 'invalid')}")
    return "malformed request: " + "; ".join(parts)


def _is_json(content_type: str | None) -> bool:
    kind = (content_type or "").split(";", 1)[0].strip().lower()
    return kind == "application/json" or (kind.startswith("application/") and kind.endswith("+json"))


def unreadable_body(cause: BaseException | None) -> str:
    """Why FastAPI could not read a JSON body (it says only "There was an error parsing the body")."""
    if isinstance(cause, RecursionError):
        return "the request body is not valid JSON: nested too deeply"
    if isinstance(cause, UnicodeDecodeError):
        bad = cause.object[cause.start : cause.start + 1].hex()
        return f"the request body is not valid JSON: not UTF-8 text (byte 0x{bad} at offset {cause.start})"
    if isinstance(cause, ValueError) and "digits" in str(cause):
        return "the request body is not valid JSON: an integer of more than 4,300 digits"
    return "the request body cannot be read" + (f" ({type(cause).__name__})" if cause is not None else "")


def if_match(header: str | None) -> list[str] | None:
    """The ETags of an ``If-Match`` header (quotes and ``W/`` dropped; ``*`` kept), or None without one."""
    if header is None:
        return None
    tags = [t.strip().removeprefix("W/").strip('"') for t in header.split(",") if t.strip()]
    bad = next((t for t in tags if t != "*" and not re.fullmatch(r"[0-9a-f]{32}", t)), None)
    if not tags or bad is not None:  # it was "changed since you opened it", which it was not
        shown = repr(header[:80])
        raise InputError(
            f"If-Match {shown} names no version the editor gave: send the etag of GET /api/files/NAME (32 hex "
            'digits, in quotes), "*" for any version, or no If-Match'
        )
    return tags


class BodyLimit(_LimitedBody):
    """:class:`_LimitedBody` at :data:`MAX_BODY_BYTES`, as ``app.add_middleware`` takes it."""

    def __init__(self, app: ASGIApp) -> None:
        super().__init__(app, MAX_BODY_BYTES)
