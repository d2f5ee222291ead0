"""An editor server in a thread for the browser tests (the ``live_server`` fixture, and a second server on the same
folder standing for a restart)."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass
class LiveServer:
    url: str
    folder: Path
    app: Any


@contextlib.contextmanager
def serve(folder: Path, *, initial: Any = None) -> Iterator[LiveServer]:
    """An editor server on ``folder`` at a free port of 127.0.0.1, in a thread; stopped (its runs too) on exit.
    ``initial``: the scenario of its command line (an :class:`mmusv.editor.app.InitialScenario`)."""
    import uvicorn
    from mmusv.editor.app import create_app
    from mmusv.editor.cli import _bind

    app = create_app(folder, initial=initial, allowed_hosts=["127.0.0.1", "localhost"])
    sock = _bind("127.0.0.1", 0)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", lifespan="off"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    try:
        yield LiveServer(f"http://127.0.0.1:{sock.getsockname()[1]}", folder, app)
    finally:
        server.should_exit = True
        thread.join(timeout=10)
        app.state.jobs.shutdown()
        sock.close()
