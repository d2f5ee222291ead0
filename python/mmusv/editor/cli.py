"""``mmusv editor [SCENARIO] [--port N] [--dir FOLDER] [--host H]``: serves the scenario editor on a local port.

The folder (``--dir``; default: the folder of SCENARIO when it is a file there, else the current folder) is the
only place the server reads and writes scenario files. SCENARIO (a file or a bundled name) opens when the page
loads and is saved into the folder under its file name. The server binds to 127.0.0.1 unless ``--host`` says
otherwise, prints its URL and runs until Ctrl-C.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import socket
import sys
from pathlib import Path
from typing import Any

from mmusv.errors import ConfigError, IoError, NotFoundError

__all__ = ["DEFAULT_PORT", "add_parser", "run", "serve"]

DEFAULT_PORT = 8765


def add_parser(sub: Any) -> None:
    """Adds the ``editor`` subcommand to the ``mmusv`` parser's subparsers ``sub``."""
    p = sub.add_parser(
        "editor",
        help="the scenario editor in the browser: a top-down map, vessels, routes, live checks, save, preview, run",
    )
    p.add_argument("scenario", nargs="?", default=None, help="scenario to open (a YAML file or a bundled name)")
    p.add_argument("--port", type=int, default=DEFAULT_PORT, help=f"port (default {DEFAULT_PORT}; 0 picks a free one)")
    p.add_argument(
        "--dir",
        default=None,
        help="the only folder the editor reads and saves scenarios in (default: SCENARIO's folder when SCENARIO "
        "is a file, else the current folder)",
    )
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1: this machine only)")


def _bind(host: str, port: int) -> socket.socket:
    if not 0 <= port <= 65535:
        raise ConfigError(f"--port {port}: must be in 0..65535 (0 picks a free port)")
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as exc:
        raise ConfigError(f"--host {host!r}: not an address of this machine ({exc.strerror})") from None
    except UnicodeError:  # bytes that are not UTF-8 (or a label IDNA refuses): was a traceback
        raise ConfigError(f"--host {host!r}: not a host name or address (it holds characters a name cannot)") from None
    family, _, _, _, addr = infos[0]
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind(addr)
    except OSError as exc:
        sock.close()
        raise IoError(
            f"cannot listen on {host}:{port}: {exc.strerror}; pass another --port (0 picks a free one)"
        ) from None
    sock.listen(64)
    return sock


def serve(app: Any, *, host: str, port: int, announce: bool = True) -> None:
    """Serves ``app`` on ``host``:``port`` until interrupted, printing the URL first."""
    import uvicorn

    sock = _bind(host, port)
    bound = sock.getsockname()[1]
    shown = f"[{host}]" if ":" in host else host
    if announce:
        print(
            f"mmusv editor: http://{shown}:{bound}/  (scenarios in {app.state.folder.root}; Ctrl-C stops)", flush=True
        )
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", access_log=False, lifespan="off"))
    try:
        server.run(sockets=[sock])
    finally:
        app.state.jobs.shutdown()
        sock.close()


def _assets_by_full_path(entries: list[str], files: list[Path]) -> list[str]:
    """The ``assets:`` entries of a scenario opened from outside the editor's folder, each by the full path of the
    file ``mmusv run`` reads (``files``, resolved from the scenario's own folder): the page resolves entries from the
    editor's folder, so ``boats/skiff.yaml`` beside the scenario was looked for there ("does not exist"), and a copy
    saved into the folder would have named a file that is not there. What changed is said on stderr."""
    out = [str(f) for f in files]
    if len(out) != len(entries):  # (one file per entry, as load_scenario read them)
        return entries
    for was, now in zip(entries, out, strict=True):
        if was != now:
            print(
                f"mmusv editor: assets: {was} is named {now} on the page (the folder is not the scenario's)",
                file=sys.stderr,
            )
    return out


def _new_scenario(given: str, missing: NotFoundError, *, folder: Path, dir_given: bool) -> tuple[Any, Path]:
    """The page's first scenario and the editor's folder for SCENARIO ``given``, a file that does not exist yet
    (``missing`` says so): a new scenario, saved into the folder under the file's name (``given``'s folder unless
    ``--dir`` names one). Refused, saying why, when ``given`` does not end in .yaml or .yml (a mistyped bundled
    name, more likely), when its folder does not exist, or when its name is not one the editor saves."""
    from mmusv.editor.app import InitialScenario
    from mmusv.editor.files import check_name
    from mmusv.editor.opening import new_document

    path = Path(given)
    if os.path.islink(path):  # a link that leads nowhere: said so (a save would not write through it)
        raise missing
    if path.suffix not in (".yaml", ".yml"):
        raise NotFoundError(f"{missing}; to start a new scenario, give a file name ending in .yaml") from None
    if not path.parent.is_dir():
        what = "is a file, not a folder" if path.parent.exists() else "does not exist"
        raise NotFoundError(
            f"scenario {given!r}: cannot start a new scenario there: the folder {str(path.parent)!r} {what}; "
            "create it first, or give a file name in an existing folder"
        )
    name = check_name(path.name)
    if not dir_given:
        folder = path.parent
    print(
        f"mmusv editor: {given} does not exist yet: opening a new scenario, which Save writes to "
        f"{folder.resolve() / name}",
        file=sys.stderr,
    )
    initial = InitialScenario(name=name, document=new_document(path.stem), comment="", new=True)
    return initial, folder


def run(args: argparse.Namespace) -> int:
    """Runs ``mmusv editor`` with parsed ``args``; returns the exit status."""
    from mmusv.bundled import resolve_scenario
    from mmusv.cli_paths import path_arg
    from mmusv.config import load_scenario
    from mmusv.editor.app import InitialScenario, comments_json, create_app
    from mmusv.editor.document import leading_comment, to_document
    from mmusv.editor.files import check_name, read_bounded
    from mmusv.editor.opening import load_document
    from mmusv.errors import MmusvError
    from mmusv.yamlio import decode_text

    initial = None
    asset_files: list[Path] = []  # the command line's scenario's own asset files, which may lie outside the folder
    # an empty --dir served the current folder, an empty SCENARIO read "." (a folder): both named now
    folder = Path(path_arg(args.dir, flag="--dir")) if args.dir is not None else Path.cwd()
    if args.scenario is not None:
        given = path_arg(args.scenario, flag="scenario")
        path: Path | None
        try:
            path = resolve_scenario(given)
        except NotFoundError as exc:  # a new file: it was refused as "does not exist"
            initial, folder = _new_scenario(given, exc, folder=folder, dir_given=args.dir is not None)
            path = None
        if path is not None:
            if path.is_dir():  # it was read as a file: "DIR: Is a directory"
                raise ConfigError(
                    f"scenario {args.scenario!r} is a folder, not a scenario file: give a YAML file, or --dir "
                    f"{args.scenario} to edit the scenarios in that folder"
                )
            if args.dir is None and Path(args.scenario).is_file():
                folder = path.parent
            # a binary or UTF-16 file: was read with replacement characters and refused as "not valid YAML"
            text = decode_text(read_bounded(path, str(path)), str(path))
            try:
                scenario = load_scenario(path)  # (reads its asset files, relative to its folder)
                document = to_document(scenario)
                asset_files = [(path.parent / Path(a).expanduser()).resolve() for a in scenario.assets]
                if path.resolve().parent != folder.resolve() and document.get("assets"):
                    document["assets"] = _assets_by_full_path(document["assets"], asset_files)
            except MmusvError as exc:  # opened to be fixed, as the page opens such a file: refused only when it cannot
                document, _ = load_document(text, str(path))  # draw it (a ConfigError saying why)
                print(f"mmusv editor: {exc}; the page lists what is wrong under Checks", file=sys.stderr)
            name = path.name if path.suffix in (".yaml", ".yml") else f"{path.name}.yaml"
            if name != path.name:  # the page was told it is the folder's file NAME.yaml, and saved that beside it
                print(f"mmusv editor: the editor saves .yaml files: {path.name} is saved as {name}", file=sys.stderr)
            initial = InitialScenario(
                name=check_name(name),
                document=document,
                comment=leading_comment(text),
                comments=comments_json(text),
                in_folder=path.resolve().parent == folder.resolve() and name == path.name,
            )
    host = str(args.host)
    hosts = ["*"] if host in ("0.0.0.0", "::", "") else sorted({host, "127.0.0.1", "localhost", "[::1]"})
    app = create_app(folder, initial=initial, allowed_hosts=hosts, asset_files=asset_files)
    with contextlib.suppress(KeyboardInterrupt):
        serve(app, host=host, port=int(args.port))
    print("mmusv editor: stopped", file=sys.stderr)
    return 0
