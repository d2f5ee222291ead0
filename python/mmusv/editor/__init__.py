"""``mmusv editor``: the bird's-eye-view scenario editor in the browser.

A local web server (FastAPI on uvicorn) serves one page, plain HTML, CSS and JavaScript modules from
``mmusv/editor/static`` (no build step, nothing fetched from elsewhere), and a JSON API over the project's own
pieces: the scenario schema (:mod:`mmusv.config`), the map priors (:mod:`mmusv.world`), the Rust kinematics
(:mod:`mmusv.motion`), the generator's named checks (:mod:`mmusv.scenario_checks`), the preview sheet
(:mod:`mmusv.preview`) and runs (:mod:`mmusv.acquire`). Modules: ``app`` (the endpoints), ``files`` (the folder,
the only place files are read and written), ``document`` (scenario <-> JSON document <-> YAML), ``maplayers``
(what is drawn of a map), ``evaluate`` (live validation and motion), ``preview`` (one frame through the run's
path), ``jobs``/``job`` (background runs), ``cli`` (the subcommand).
"""

from __future__ import annotations

__all__: list[str] = []
