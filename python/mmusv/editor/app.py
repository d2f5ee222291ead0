"""The editor's web application (FastAPI): the page, its static files and the JSON API.

Endpoints (JSON in and out unless said otherwise; errors are ``{"error": "..."}`` with a 4xx status):

========================  =====================================================================================
``GET /``                 the page (``static/index.html``); ``/static/...`` its CSS and JavaScript modules
``GET /api/info``         version, folder, the scenario given on the command line (its file as it is now, when it
                          is the folder's), choices from the schema
``GET /api/assets``       the vessel library (name, category, class, sizes in metres, USV or not) of a scenario:
                          the built-in assets and, with ``?assets=PATH`` (once per entry of the scenario's
                          ``assets:``, in order), its own asset files' assets, none of another scenario's (an entry
                          that cannot be read adds nothing: the checks of the scenario say why)
``GET /api/bundled``      the bundled scenarios; ``GET /api/bundled/{name}`` one of them as a document
``GET /api/files``        the scenario files in the folder; ``GET /api/files/{name}`` one as a document, with
                          its ``etag`` (also the ``ETag`` header); both documents come with the file's leading
                          ``comment`` and its other ``comments`` (``[{path, at, text}]``, :mod:`.comments`; a
                          blank line that sets an entry apart is a comment whose ``text`` is empty)
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
the message says why), 404 nothing of that name, 405 an endpoint asked with a method it does not take (the
message and ``Allow`` say which it takes), 409 the file exists (or the name is a folder; or a run of the
same scenario is going on), 412 the file changed since the client read it (If-Match), 413 the request is larger
than :data:`MAX_BODY_BYTES`, 422 the request body or the scenario does not validate (the message names the
field). Request bodies are JSON objects sent as ``application/json``; their fields are strict (``frame: true`` or
``"3"`` is refused, not read as 1 or 3), and a text must be valid Unicode (an unpaired ``\\ud800`` escape is
refused). Nothing outside the folder is read or written (:mod:`mmusv.editor.files`); the page loads nothing from
elsewhere (a Content-Security-Policy says so to the browser).

This module assembles the application and its endpoints; the request bodies are :mod:`mmusv.editor.bodies`, the HTTP
plumbing (errors and their statuses, the body limit, the messages for unreadable requests) :mod:`mmusv.editor.web`,
opening a file's text as the page's document :mod:`mmusv.editor.opening`.
"""

from __future__ import annotations

import contextlib
import sys
import threading
import traceback
from collections.abc import Collection
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Annotated, Any

from fastapi import FastAPI, Query, Request
from fastapi import Path as PathParam
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, Response
from fastapi.routing import APIRoute
from fastapi.staticfiles import StaticFiles
from pydantic import ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.middleware.trustedhost import TrustedHostMiddleware

from mmusv import yamlio
from mmusv.config import EnvironmentConfig, MapConfig, Scenario, VesselConfig, validation_problems
from mmusv.editor.bodies import DocumentBody, FrameBody, MapBody, PreviewBody, RunBody, SaveBody
from mmusv.editor.carry import value_count
from mmusv.editor.comments import Comment, moved_note, read_comments
from mmusv.editor.document import leading_comment, scenario_file, to_document
from mmusv.editor.evaluate import MAX_BULK_FRAMES, AssetScope, evaluate, poses_at, register_assets, validate
from mmusv.editor.files import ScenarioFolder, check_name, etag
from mmusv.editor.jobs import Jobs
from mmusv.editor.maplayers import map_layers
from mmusv.editor.opening import load_document
from mmusv.editor.web import (
    CSP,
    MAX_BODY_BYTES,
    BodyLimit,
    choices,
    error,
    if_match,
    request_error,
    status_of,
    unreadable_body,
)
from mmusv.errors import ConfigError, MmusvError, NotFoundError

__all__ = ["MAX_BODY_BYTES", "STATIC_DIR", "InitialScenario", "comments_json", "create_app"]

STATIC_DIR = Path(__file__).parent / "static"
"""The page's files (HTML, CSS, JavaScript modules), shipped in the package."""


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
    new: bool = False
    """The file does not exist yet: the document is a new scenario (:func:`mmusv.editor.opening.new_document`)."""


def comments_json(text: str) -> list[dict[str, Any]]:
    """The comments of a scenario file's ``text`` but its leading block, as the API carries them."""
    return [c.as_json() for c in read_comments(text)]


_JOB_ID = r"^(0|[1-9][0-9]{0,17})$"
"""A run id as the API gives it: a whole number in decimal digits (no sign, spaces, ``_`` or leading zeros)."""


def create_app(
    folder: str | Path,
    *,
    initial: InitialScenario | None = None,
    allowed_hosts: list[str] | None = None,
    asset_files: Collection[str | Path] = (),
) -> FastAPI:
    """The editor application serving scenario files of ``folder``; ``initial`` is opened when the page loads;
    ``allowed_hosts`` are the host names requests may address (default: any; the command line passes the bound
    host and its loopback names, so other sites cannot reach the server through DNS rebinding). A scenario's own
    asset files (``assets:``) are read from the folder; ``asset_files`` are those outside it that may be read too
    (the command line's scenario's, which it read)."""
    store = ScenarioFolder(folder)
    also = frozenset(Path(p).resolve() for p in asset_files)
    if initial is not None and initial.in_folder and initial.etag is None:  # the version the page starts from
        initial = replace(initial, etag=store.etag_of(initial.name))
    jobs = Jobs(store.root)
    scope = AssetScope(store.root)  # the user assets of the scenario of each request, no other scenario's
    evaluate_lock, preview_lock = threading.Lock(), threading.Lock()
    app = FastAPI(title="mmusv editor", docs_url=None, redoc_url=None, openapi_url=None)
    app.state.jobs = jobs
    app.state.folder = store

    @app.exception_handler(MmusvError)
    async def _mmusv_error(request: Request, exc: MmusvError) -> JSONResponse:
        return error(status_of(exc), str(exc))

    @app.exception_handler(RequestValidationError)
    async def _bad_request(request: Request, exc: RequestValidationError) -> JSONResponse:
        return error(422, request_error(exc, request.headers.get("content-type")))

    @app.exception_handler(StarletteHTTPException)
    async def _http_error(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        if exc.status_code == 400 and exc.detail == "There was an error parsing the body":  # FastAPI's words
            return error(400, unreadable_body(exc.__cause__))
        return error(exc.status_code, str(exc.detail))

    @app.exception_handler(Exception)
    async def _internal(request: Request, exc: Exception) -> JSONResponse:
        traceback.print_exception(exc, file=sys.stderr)  # for the person running the server, not the client
        return error(500, f"internal error ({type(exc).__name__}); the server's console has the details")

    @app.middleware("http")
    async def _headers(request: Request, call_next: Any) -> Response:
        response: Response = await call_next(request)
        response.headers["Content-Security-Policy"] = CSP
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
            "initial": None if initial is None else _initial_now(initial).__dict__,
            "choices": {
                "map_type": choices(MapConfig, "type"),
                "weather": choices(EnvironmentConfig, "weather"),
                "wave": [{"name": k, "height_m": v} for k, v in WAVE_PRESETS.items()],
                "wave_height_m": [0.0, MAX_WAVE_HEIGHT_M],  # a custom wave's height: lowest, highest
                "motion": choices(EnvironmentConfig, "motion"),
                "role": choices(VesselConfig, "role"),
                "end": choices(VesselConfig, "end"),
                "rig_preset": sorted(RIG_PRESETS),
                "camera_quality": choices(CameraConfig, "quality"),
            },
            "limits": {"bulk_frames": MAX_BULK_FRAMES, "body_bytes": MAX_BODY_BYTES},
        }

    def _initial_now(first: InitialScenario) -> InitialScenario:
        """The command line's scenario as a page loaded now sees it: when it is the folder's file, the file as it is
        now (a tab opened after another tab or program saved it showed the version of the server's start, with
        nothing marked unsaved, and its save was refused as changed); the version of the start when it cannot be
        read now. A new scenario's file (:attr:`InitialScenario.new`) saved since is that file: a page loaded after
        the save showed the empty new scenario, said not to exist yet."""
        if first.new and store.path(first.name).is_file():
            now = replace(first, new=False, in_folder=True)
        elif first.in_folder:
            now = first
        else:
            return first
        try:
            got = store.read_text(first.name)
            document, _ = load_document(got.text, first.name, folder=store.root, also=also, scope=scope)
        except MmusvError:  # deleted, or no longer a scenario the page can show: what the server started with
            return first
        return replace(
            now,
            document=document,
            comment=leading_comment(got.text),
            comments=comments_json(got.text),
            etag=got.etag,
        )

    @app.get("/api/assets")
    def assets_(entries: Annotated[list[str], Query(alias="assets")] = []) -> list[dict[str, Any]]:  # noqa: B006
        from mmusv.world.vessels import library

        with scope.use({"assets": entries}):
            for entry in entries:  # one at a time: the assets of every file that can be read, beside one that cannot
                register_assets({"assets": [entry]}, store.root, also=also)
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
        doc, valid = load_document(text, f"bundled {files[stem].name}", scope=scope)
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
        doc, valid = load_document(text, name, folder=store.root, also=also, scope=scope)
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
        with scope.use(body.document):
            scenario, errors = validate(body.document, folder=store.root, also=also)
        if scenario is None:
            raise ConfigError(
                f"{name}: not saved, the scenario does not validate: " + "; ".join(e["message"] for e in errors)
            )
        limit = yamlio.MAX_YAML_VALUES
        if value_count(to_document(scenario), limit) > limit:  # the file would not load again
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
            name, text, overwrite=body.overwrite, if_match=if_match(request.headers.get("if-match"))
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
            text = map_layers(cfg.type, seed=cfg.seed, params=cfg.param_values())
        return Response(text, media_type="application/json")

    @app.post("/api/evaluate")
    def evaluate_(body: DocumentBody) -> dict[str, Any]:
        with scope.use(body.document), evaluate_lock:
            return evaluate(body.document, folder=store.root, also=also)

    def _valid(document: dict[str, Any]) -> Scenario:
        scenario, errors = validate(document, folder=store.root, also=also)
        if scenario is None:
            raise ConfigError("the scenario does not validate: " + "; ".join(e["message"] for e in errors))
        return scenario

    @app.post("/api/poses")
    def poses(body: FrameBody) -> dict[str, Any]:
        with scope.use(body.document):
            scenario = _valid(body.document)
            return {"frame": body.frame, "poses": poses_at(scenario, body.frame)}

    @app.post("/api/preview")
    def preview(body: PreviewBody) -> Response:
        from mmusv.editor.preview import preview_png
        from mmusv.generate.mapctx import map_context

        with scope.use(body.document):
            scenario = _valid(body.document)
            with evaluate_lock:
                world = map_context(scenario.map.type, seed=scenario.map.seed, params=scenario.map.param_values()).world
            with preview_lock:
                png = preview_png(scenario, frame=body.frame, agent=body.agent, world=world)
        return Response(png, media_type="image/png")

    @app.post("/api/runs")
    def start_run(body: RunBody) -> dict[str, Any]:
        path = store.path(body.name)
        if not path.is_file():
            raise NotFoundError(f"no scenario file {body.name!r} in the editor's folder; save it first")
        if body.frames is not None:  # more than the file records: the job started, then failed (a review's)
            from mmusv.config import load_scenario

            try:
                with scope.use(yamlio.parse_yaml(store.read_text(body.name).text, body.name)):
                    total: int | None = load_scenario(path).acquisition.frames
            except MmusvError:
                total = None  # the run says what is wrong with the file
            if total is not None and body.frames > total:
                raise ConfigError(
                    f"frames = {body.frames}: {body.name} records {total} (acquisition.frames); give 1..{total}, "
                    "or leave it empty for all"
                )
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

    @app.api_route("/api/{rest:path}", methods=["GET", "POST", "PUT", "DELETE"], include_in_schema=False)
    def unknown(rest: str, request: Request) -> Response:
        # an endpoint asked with another method (POST /api/files/a.yaml) was "no API endpoint" (404), or a bare 405
        path = f"/api/{rest}"
        takes = sorted(
            {
                m
                for r in app.routes
                if isinstance(r, APIRoute) and r.endpoint is not unknown and r.path_regex.match(path)
                for m in r.methods or ()
            }
        )
        if takes:
            answer = error(405, f"{path} takes {' or '.join(takes)}, not {request.method}")
            answer.headers["Allow"] = ", ".join(takes)
            return answer
        raise NotFoundError(f"no API endpoint {path}")

    app.add_middleware(BodyLimit)
    if allowed_hosts is not None:
        app.add_middleware(TrustedHostMiddleware, allowed_hosts=allowed_hosts)
    return app
