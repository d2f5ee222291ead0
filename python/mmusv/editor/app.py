"""The editor's web application (FastAPI): the page, its static files and the JSON API.

Endpoints (JSON in and out unless said otherwise; errors are ``{"error": "..."}`` with a 4xx status):

========================  =====================================================================================
``GET /``                 the page (``static/index.html``); ``/static/...`` its CSS and JavaScript modules
``GET /api/info``         version, folder, the scenario given on the command line, choices from the schema
``GET /api/assets``       the vessel library (name, category, class, sizes in metres, USV or not)
``GET /api/bundled``      the bundled scenarios; ``GET /api/bundled/{name}`` one of them as a document
``GET /api/files``        the scenario files in the folder; ``GET /api/files/{name}`` one as a document, with
                          its ``etag`` (also the ``ETag`` header); both documents come with the file's leading
                          ``comment`` and its other ``comments`` (``[{path, at, text}]``, :mod:`.comments`)
``PUT /api/files/{name}`` saves ``{document, comment, comments, overwrite}`` as YAML into the folder (409 if it
                          exists); with ``If-Match: ETAG`` only if the file is still that version (412 if it
                          changed; a list of ETags and ``*``, any version, are understood). ``comments`` left
                          out: those of the file it replaces. The answer's ``comments`` are the new file's, its
                          ``note`` says which comments lost their anchor (moved to the end of the file)
``POST /api/map``         ``{map}`` -> the map's layers (:mod:`mmusv.editor.maplayers`)
``POST /api/evaluate``    ``{document}`` -> validation, checks and motion (:mod:`mmusv.editor.evaluate`)
``POST /api/poses``       ``{document, frame}`` -> every vessel's ``[x, y, yaw]`` at that index
``POST /api/preview``     ``{document, frame, agent}`` -> PNG of the ``mmusv preview`` sheet of that frame
``POST /api/runs``        ``{name, frames}`` starts ``mmusv run`` of a saved file; ``GET /api/runs[/{id}]``
                          progress (and the runs already in ``out/`` at start, ``earlier``); ``DELETE
                          /api/runs/{id}`` stops one
========================  =====================================================================================

Status codes: 400 bad input (a file name, a request the server cannot serve, a body that cannot be read as JSON:
the message says why), 404 nothing of that name, 409 the file exists (or the name is a folder; or a run of the
same scenario is going on), 412 the file changed since the client read it (If-Match), 413 the request is larger
than :data:`MAX_BODY_BYTES`, 422 the request body or the scenario does not validate (the message names the
field). Request bodies are JSON objects sent as ``application/json``; their fields are strict (``frame: true`` or
``"3"`` is refused, not read as 1 or 3), and a text must be valid Unicode (an unpaired ``\\ud800`` escape is
refused). Nothing outside the folder is read or written (:mod:`mmusv.editor.files`); the page loads nothing from
elsewhere (a Content-Security-Policy says so to the browser).
"""

from __future__ import annotations

import contextlib
import json
import math
import re
import sys
import threading
import traceback
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Annotated, Any, Literal, get_args

from fastapi import FastAPI, Request
from fastapi import Path as PathParam
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, Response
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from mmusv import yamlio
from mmusv.config import EnvironmentConfig, MapConfig, Scenario, VesselConfig, load_scenario, validation_problems
from mmusv.editor.comments import Comment, comment_problem, moved_note, read_comments
from mmusv.editor.document import leading_comment, scenario_file, to_document
from mmusv.editor.evaluate import MAX_BULK_FRAMES, evaluate, poses_at, validate
from mmusv.editor.files import ChangedInFolder, FileExistsInFolder, ScenarioFolder, check_name, etag
from mmusv.editor.jobs import Jobs, RunGoingOn
from mmusv.editor.maplayers import map_layers
from mmusv.errors import ConfigError, InputError, MmusvError, NotFoundError
from mmusv.yamlio import parse_yaml

__all__ = ["MAX_BODY_BYTES", "STATIC_DIR", "InitialScenario", "comments_json", "create_app"]

STATIC_DIR = Path(__file__).parent / "static"
"""The page's files (HTML, CSS, JavaScript modules), shipped in the package."""
MAX_BODY_BYTES = 16 * 1024 * 1024
"""Largest request body (16 MiB); larger requests get 413."""
_CSP = (
    "default-src 'self'; img-src 'self' data: blob:; style-src 'self'; script-src 'self'; connect-src 'self'; "
    "object-src 'none'; base-uri 'none'; frame-ancestors 'none'"
)


@dataclass(frozen=True)
class InitialScenario:
    """The scenario named on the command line: the file ``name`` it will be saved as in the folder, its document
    and leading comment; ``in_folder``: it is that file of the folder (saving it replaces it)."""

    name: str
    document: dict[str, Any]
    comment: str
    in_folder: bool = False
    etag: str | None = None
    """The ETag of the file when ``in_folder`` (the page saves it with ``If-Match``)."""
    comments: list[dict[str, Any]] = field(default_factory=list)
    """The file's other comments (:func:`comments_json`), which the page sends back when it saves."""


def comments_json(text: str) -> list[dict[str, Any]]:
    """The comments of a scenario file's ``text`` but its leading block, as the API carries them."""
    return [c.as_json() for c in read_comments(text)]


_NOT_YAML = re.compile("[^\x09\x0a\x0d\x20-\x7e\x85\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
"""A character a YAML file may not hold anywhere, comments included (control characters but tab and line breaks,
unpaired surrogates, U+FFFE/U+FFFF): a file with one does not load again."""
_SURROGATE = re.compile("[\ud800-\udfff]")
_JOB_ID = r"^(0|[1-9][0-9]{0,17})$"
"""A run id as the API gives it: a whole number in decimal digits (no sign, spaces, ``_`` or leading zeros)."""


def _path(parts: list[str | int]) -> str:
    """``vessels[0].route`` from the keys and indices ``parts``."""
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def _unjsonable(value: Any, root: str) -> str | None:
    """Where ``value`` (plain JSON-like data) holds what JSON cannot carry back to the page, and what it is:
    a number that is not finite (``.nan``, ``.inf`` in YAML, ``NaN`` in lenient JSON) or a text with an unpaired
    UTF-16 surrogate (``"\\ud800"``); None when there is nothing."""
    stack: list[tuple[Any, list[str | int]]] = [(value, [root] if root else [])]
    while stack:
        v, parts = stack.pop()
        if isinstance(v, float) and not math.isfinite(v):
            return f"{_path(parts) or 'the value'} = {v}: not a finite number"
        if isinstance(v, str) and _SURROGATE.search(v) is not None:
            return f"{_path(parts) or 'the value'} = {v!r}: an unpaired UTF-16 surrogate is not text"
        if isinstance(v, dict):
            for k, item in v.items():
                if isinstance(k, str) and _SURROGATE.search(k) is not None:
                    return (
                        f"{_path(parts) or 'the mapping'} has the key {k!r}: an unpaired UTF-16 surrogate is not text"
                    )
                stack.append((item, [*parts, str(k)]))
        elif isinstance(v, list):
            stack.extend((item, [*parts, i]) for i, item in enumerate(v))
    return None


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)


def _jsonable(value: dict[str, Any], name: str) -> dict[str, Any]:
    """``value`` (a request field ``name``) when JSON can carry all of it back (:func:`_unjsonable`); else the
    ``ValueError`` pydantic reports as a 422 naming the path."""
    problem = _unjsonable(value, name)
    if problem is not None:
        raise ValueError(problem)
    return value


class DocumentBody(_Strict):
    """A scenario document (the JSON form of a scenario file)."""

    document: dict[str, Any]

    @field_validator("document")
    @classmethod
    def _text_is_unicode(cls, document: dict[str, Any]) -> dict[str, Any]:
        return _jsonable(document, "document")


class CommentBody(_Strict):
    """A comment of the file and its anchor (:class:`mmusv.editor.comments.Comment`)."""

    path: list[str | int] = Field(max_length=64)
    at: Literal["before", "end"]
    text: str = Field(max_length=20_000)

    @field_validator("text")
    @classmethod
    def _one_comment_line(cls, text: str) -> str:
        problem = comment_problem(text)
        if problem is not None:
            raise ValueError(problem)
        return text

    @field_validator("path")
    @classmethod
    def _path_is_text(cls, path: list[str | int]) -> list[str | int]:
        _jsonable({"path": path}, "comments")
        return path


class SaveBody(DocumentBody):
    comment: str = Field(default="", max_length=20_000)
    comments: list[CommentBody] | None = None
    overwrite: bool = False

    @field_validator("comment")
    @classmethod
    def _comment_fits_yaml(cls, comment: str) -> str:
        bad = _NOT_YAML.search(comment)
        if bad is not None:
            raise ValueError(
                f"character U+{ord(bad.group()):04X} at position {bad.start()} cannot be written into a YAML file "
                "(the file would not load again): control characters other than tab and line breaks are not allowed"
            )
        return comment


class FrameBody(DocumentBody):
    frame: int = Field(ge=0)


class PreviewBody(FrameBody):
    agent: str | None = Field(default=None, max_length=64)


class MapBody(_Strict):
    map: dict[str, Any]

    @field_validator("map")
    @classmethod
    def _text_is_unicode(cls, value: dict[str, Any]) -> dict[str, Any]:
        return _jsonable(value, "map")


class RunBody(_Strict):
    name: str = Field(max_length=1000)
    frames: int | None = Field(default=None, ge=1)


def _error(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status)


def _status(exc: MmusvError) -> int:
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


class _BodyLimit:
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
            await _error(400, f"the Content-Length header {shown!r} is not a number of bytes")(scope, receive, send)
            return
        if length is not None and int(length) > self.limit:
            await _error(413, too_large)(scope, receive, send)
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
                await _error(413, too_large)(scope, receive, send)
                return
            chunks.append(chunk)
            if not msg.get("more_body", False):
                break
        body: list[Message] = [{"type": "http.request", "body": b"".join(chunks), "more_body": False}]

        async def replay() -> Message:
            return body.pop() if body else await receive()

        await self.app(scope, replay, send)


def _choices(model: type[BaseModel], name: str) -> list[str]:
    return list(get_args(model.model_fields[name].annotation))


def _request_error(exc: RequestValidationError, content_type: str | None) -> str:
    parts = []
    for e in exc.errors():
        loc = ".".join(str(p) for p in e.get("loc", ()) if p != "body") or "body"
        if e.get("type") == "json_invalid":
            parts.append(f"the request body is not valid JSON ({e.get('ctx', {}).get('error', 'unreadable')})")
        elif loc == "body" and not _is_json(content_type):
            got = f"Content-Type {content_type!r}" if content_type else "no Content-Type"
            parts.append(f"body: the request body must be a JSON object sent as application/json (got {got})")
        else:
            parts.append(f"{loc}: {e.get('msg', 'invalid')}")
    return "malformed request: " + "; ".join(parts)


def _is_json(content_type: str | None) -> bool:
    kind = (content_type or "").split(";", 1)[0].strip().lower()
    return kind == "application/json" or (kind.startswith("application/") and kind.endswith("+json"))


def _unreadable_body(cause: BaseException | None) -> str:
    """Why FastAPI could not read a JSON body (it says only "There was an error parsing the body")."""
    if isinstance(cause, RecursionError):
        return "the request body is not valid JSON: nested too deeply"
    if isinstance(cause, UnicodeDecodeError):
        bad = cause.object[cause.start : cause.start + 1].hex()
        return f"the request body is not valid JSON: not UTF-8 text (byte 0x{bad} at offset {cause.start})"
    if isinstance(cause, ValueError) and "digits" in str(cause):
        return "the request body is not valid JSON: an integer of more than 4,300 digits"
    return "the request body cannot be read" + (f" ({type(cause).__name__})" if cause is not None else "")


def _if_match(header: str | None) -> list[str] | None:
    """The ETags of an ``If-Match`` header (quotes and ``W/`` dropped; ``*`` kept), or None without one."""
    if header is None:
        return None
    return [t.strip().removeprefix("W/").strip('"') for t in header.split(",") if t.strip()]


def _value_count(document: Any, limit: int) -> int:
    """How many values (mappings, lists, keys and scalars) ``document`` holds, as :mod:`mmusv.yamlio` counts them
    when the file is read again; stops counting above ``limit``."""
    count, stack = 0, [document]
    while stack and count <= limit:
        v = stack.pop()
        count += 1
        if isinstance(v, dict):
            stack.extend(v.keys())
            stack.extend(v.values())
        elif isinstance(v, list):
            stack.extend(v)
    return count


def _load_document(text: str, where: str) -> tuple[dict[str, Any], bool]:
    """``(document, valid)`` of a scenario file's text: the editor's document of a valid scenario, else the raw
    mapping (the page then lists what is wrong); :class:`ConfigError` when it is not a YAML mapping."""
    data = parse_yaml(text, where)
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: a scenario must be a YAML mapping with at least `vessels:`")
    try:
        return to_document(load_scenario(data)), True
    except MmusvError as exc:
        if not _editable(data):  # the page could not show it: say what is wrong instead
            raise ConfigError(
                f"{exc}; the editor opens files whose vessels and routes are lists (fix it as text)"
            ) from None
        raw = json.loads(json.dumps(data, default=str))
        problem = _unjsonable(raw, "")
        if problem is not None:  # JSON cannot carry it to the page
            raise ConfigError(f"{where}: {problem}; the editor cannot show this value (fix it as text)") from None
        return raw, False


def _editable(data: dict[str, Any]) -> bool:
    """Whether an invalid scenario mapping still has the shape the page draws: sections are mappings, ``vessels``
    a list of mappings whose ``route`` is a list of ``[x, y]`` numbers."""
    if any(k in data and not isinstance(data[k], dict) for k in ("map", "environment", "acquisition", "rigs")):
        return False
    vessels = data.get("vessels", [])
    if not isinstance(vessels, list) or not all(isinstance(v, dict) for v in vessels):
        return False
    for v in vessels:
        route = v.get("route", [])
        if not isinstance(route, list):
            return False
        for p in route:
            if not (isinstance(p, list) and len(p) == 2 and all(isinstance(c, (int, float)) for c in p)):
                return False
    return True


def create_app(
    folder: str | Path, *, initial: InitialScenario | None = None, allowed_hosts: list[str] | None = None
) -> FastAPI:
    """The editor application serving scenario files of ``folder``; ``initial`` is opened when the page loads;
    ``allowed_hosts`` are the host names requests may address (default: any; the command line passes the bound
    host and its loopback names, so other sites cannot reach the server through DNS rebinding)."""
    store = ScenarioFolder(folder)
    if initial is not None and initial.in_folder and initial.etag is None:  # the version the page starts from
        initial = replace(initial, etag=store.etag_of(initial.name))
    jobs = Jobs(store.root)
    evaluate_lock, preview_lock = threading.Lock(), threading.Lock()
    app = FastAPI(title="mmusv editor", docs_url=None, redoc_url=None, openapi_url=None)
    app.state.jobs = jobs
    app.state.folder = store

    @app.exception_handler(MmusvError)
    async def _mmusv_error(request: Request, exc: MmusvError) -> JSONResponse:
        return _error(_status(exc), str(exc))

    @app.exception_handler(RequestValidationError)
    async def _bad_request(request: Request, exc: RequestValidationError) -> JSONResponse:
        return _error(422, _request_error(exc, request.headers.get("content-type")))

    @app.exception_handler(StarletteHTTPException)
    async def _http_error(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        if exc.status_code == 400 and exc.detail == "There was an error parsing the body":  # FastAPI's words
            return _error(400, _unreadable_body(exc.__cause__))
        return _error(exc.status_code, str(exc.detail))

    @app.exception_handler(Exception)
    async def _internal(request: Request, exc: Exception) -> JSONResponse:
        traceback.print_exception(exc, file=sys.stderr)  # for the person running the server, not the client
        return _error(500, f"internal error ({type(exc).__name__}); the server's console has the details")

    @app.middleware("http")
    async def _headers(request: Request, call_next: Any) -> Response:
        response: Response = await call_next(request)
        response.headers["Content-Security-Policy"] = _CSP
        response.headers["X-Content-Type-Options"] = "nosniff"
        response.headers["Cache-Control"] = "no-store"
        return response

    @app.get("/", include_in_schema=False)
    def index() -> FileResponse:
        return FileResponse(STATIC_DIR / "index.html", media_type="text/html")

    app.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")

    @app.get("/api/info")
    def info() -> dict[str, Any]:
        from mmusv import __version__
        from mmusv.sensors.config import RIG_PRESETS, CameraConfig
        from mmusv.world.environment import MAX_WAVE_HEIGHT_M, WAVE_PRESETS

        return {
            "version": __version__,
            "folder": str(store.root),
            "initial": None if initial is None else initial.__dict__,
            "choices": {
                "map_type": _choices(MapConfig, "type"),
                "weather": _choices(EnvironmentConfig, "weather"),
                "wave": [{"name": k, "height_m": v} for k, v in WAVE_PRESETS.items()],
                "wave_height_m": [0.0, MAX_WAVE_HEIGHT_M],  # a custom wave's height: lowest, highest
                "motion": _choices(EnvironmentConfig, "motion"),
                "role": _choices(VesselConfig, "role"),
                "end": _choices(VesselConfig, "end"),
                "rig_preset": sorted(RIG_PRESETS),
                "camera_quality": _choices(CameraConfig, "quality"),
            },
            "limits": {"bulk_frames": MAX_BULK_FRAMES, "body_bytes": MAX_BODY_BYTES},
        }

    @app.get("/api/assets")
    def assets() -> list[dict[str, Any]]:
        from mmusv.world.vessels import library

        return [
            {
                "name": a.name,
                "category": a.category,
                "class": a.semantic_class.name.lower(),
                "usv": a.is_usv,
                "length": round(a.length, 2),
                "beam": round(a.beam, 2),
                "height": round(a.height, 2),
                "draft": round(a.draft, 2),
                "description": a.description,
            }
            for a in library()
        ]

    @app.get("/api/bundled")
    def bundled() -> list[dict[str, Any]]:
        from mmusv.bundled import bundled_scenarios

        return [
            {
                "name": b.name,
                "file": b.path.name,
                "map": b.map,
                "usvs": b.usvs,
                "targets": b.targets,
                "frames": b.frames,
                "description": b.description,
            }
            for b in bundled_scenarios()
        ]

    def _as_sent(request: Request, prefix: str, name: str) -> str:
        """The path parameter after ``prefix`` as the request sent it: Starlette's route drops a trailing newline
        (``x.yaml%0A`` matches as ``x.yaml``), which must not reach another file or scenario."""
        return str(request.scope.get("path", "")).partition(prefix)[2] or name

    @app.get("/api/bundled/{name:path}")
    def bundled_one(name: str, request: Request) -> dict[str, Any]:
        from mmusv.bundled import bundled_dir

        files = {p.stem: p for p in bundled_dir().glob("*.yaml")}
        name = _as_sent(request, "/api/bundled/", name)
        stem = name.removesuffix(".yaml")
        if stem not in files:
            raise NotFoundError(f"no bundled scenario {name!r}; bundled: {', '.join(sorted(files))}")
        text = files[stem].read_text(encoding="utf-8")
        doc, valid = _load_document(text, f"bundled {files[stem].name}")
        return {
            "name": files[stem].name,
            "document": doc,
            "valid": valid,
            "comment": leading_comment(text),
            "comments": comments_json(text),
        }

    @app.get("/api/files")
    def files() -> list[dict[str, Any]]:
        return [{"name": f.name, "size": f.size} for f in store.files()]

    def _sent_name(request: Request, name: str) -> str:
        """A file ``name`` as the request sent it (:func:`_as_sent`), checked when it differs from the route's."""
        sent = _as_sent(request, "/api/files/", name)
        return check_name(sent) if sent != name else name

    @app.get("/api/files/{name:path}")
    def read_file(name: str, request: Request) -> JSONResponse:
        name = _sent_name(request, name)
        got = store.read_text(name)  # the text and the ETag of the same bytes, read once
        text, tag = got.text, got.etag
        doc, valid = _load_document(text, name)
        return JSONResponse(
            {
                "name": name,
                "document": doc,
                "valid": valid,
                "comment": leading_comment(text),
                "comments": comments_json(text),
                "etag": tag,
            },
            headers={"ETag": f'"{tag}"'},
        )

    @app.put("/api/files/{name:path}")
    def write_file(name: str, body: SaveBody, request: Request) -> JSONResponse:
        name = check_name(_sent_name(request, name))
        scenario, errors = validate(body.document)
        if scenario is None:
            raise ConfigError(
                f"{name}: not saved, the scenario does not validate: " + "; ".join(e["message"] for e in errors)
            )
        limit = yamlio.MAX_YAML_VALUES
        if _value_count(to_document(scenario), limit) > limit:  # the file would not load again
            raise ConfigError(
                f"{name}: not saved, the scenario holds more than {limit:,} values (a waypoint counts three: its list "
                "and two numbers), the most a scenario file may hold (mmusv.yamlio.MAX_YAML_VALUES), so the file "
                "would not load again: use fewer waypoints or vessels"
            )
        if body.comments is not None:
            comments = [Comment(tuple(c.path), c.at, c.text) for c in body.comments]
        else:  # a client that does not carry them: those of the file it replaces (if it can be read)
            comments = []
            if body.overwrite and store.path(name).is_file():
                with contextlib.suppress(MmusvError):
                    comments = read_comments(store.read_text(name).text)
        text, moved = scenario_file(scenario, comment=body.comment, comments=comments)
        path = store.write_text(
            name, text, overwrite=body.overwrite, if_match=_if_match(request.headers.get("if-match"))
        )
        tag = etag(text.encode("utf-8"))
        answer = {
            "name": name,
            "path": str(path),
            "bytes": path.stat().st_size,
            "etag": tag,
            "comments": comments_json(text),
        }
        note = moved_note(moved)
        if note is not None:
            answer["note"] = note
        return JSONResponse(answer, headers={"ETag": f'"{tag}"'})

    @app.post("/api/map")
    def map_(body: MapBody) -> Response:
        try:
            cfg = MapConfig.model_validate(body.map)
        except ValidationError as exc:
            raise ConfigError(
                "; ".join(
                    f"map.{f} = {shown}: {msg}" if f else msg for f, shown, msg in validation_problems(exc, root="")
                )
            ) from None
        with evaluate_lock:
            text = map_layers(cfg.type, cfg.seed, cfg.param_values())
        return Response(text, media_type="application/json")

    @app.post("/api/evaluate")
    def evaluate_(body: DocumentBody) -> dict[str, Any]:
        with evaluate_lock:
            return evaluate(body.document)

    def _valid(document: dict[str, Any]) -> Scenario:
        scenario, errors = validate(document)
        if scenario is None:
            raise ConfigError("the scenario does not validate: " + "; ".join(e["message"] for e in errors))
        return scenario

    @app.post("/api/poses")
    def poses(body: FrameBody) -> dict[str, Any]:
        scenario = _valid(body.document)
        return {"frame": body.frame, "poses": poses_at(scenario, body.frame)}

    @app.post("/api/preview")
    def preview(body: PreviewBody) -> Response:
        from mmusv.editor.preview import preview_png
        from mmusv.generate.mapctx import map_context

        scenario = _valid(body.document)
        with evaluate_lock:
            world = map_context(scenario.map.type, scenario.map.seed, scenario.map.param_values()).world
        with preview_lock:
            png = preview_png(scenario, frame=body.frame, agent=body.agent, world=world)
        return Response(png, media_type="image/png")

    @app.post("/api/runs")
    def start_run(body: RunBody) -> dict[str, Any]:
        path = store.path(body.name)
        if not path.is_file():
            raise NotFoundError(f"no scenario file {body.name!r} in the editor's folder; save it first")
        return jobs.start(path, frames=body.frames).as_dict()

    @app.get("/api/runs")
    def runs() -> list[dict[str, Any]]:
        return [j.as_dict() for j in jobs.all()]

    @app.get("/api/runs/{job_id}")
    def run_status(job_id: Annotated[str, PathParam(pattern=_JOB_ID)]) -> dict[str, Any]:
        return jobs.get(int(job_id)).as_dict()

    @app.delete("/api/runs/{job_id}")
    def run_cancel(job_id: Annotated[str, PathParam(pattern=_JOB_ID)]) -> dict[str, Any]:
        return jobs.cancel(int(job_id)).as_dict()

    @app.api_route("/api/{rest:path}", methods=["GET", "POST", "PUT"], include_in_schema=False)
    def unknown(rest: str) -> Response:
        raise NotFoundError(f"no API endpoint /api/{rest}")

    app.add_middleware(_BodyLimitMiddleware)
    if allowed_hosts is not None:
        app.add_middleware(TrustedHostMiddleware, allowed_hosts=allowed_hosts)
    return app


class _BodyLimitMiddleware(_BodyLimit):
    def __init__(self, app: ASGIApp) -> None:
        super().__init__(app, MAX_BODY_BYTES)
