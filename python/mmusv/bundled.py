"""Scenarios and generation specs shipped with the package (``mmusv/scenarios``, package data).

In the source tree ``python/mmusv/scenarios`` is a link to the repository's ``scenarios/`` folder; a wheel holds
the files themselves. :func:`resolve_scenario` turns a user's argument into a file: an existing path wins, else a
bare name (``port_entry``, ``port_entry.yaml``, ``scenarios/port_entry.yaml``) is looked up among the bundled
scenarios, so ``mmusv run port_entry`` works from any directory. A bare name that is both a folder there and a
bundled name (the output folder of an earlier ``mmusv run port_entry -o port_entry``) is refused, naming both ways
to write it (``./port_entry``, ``port_entry.yaml``).
"""

from __future__ import annotations

import errno
import importlib.resources
import os
import re
from dataclasses import dataclass
from pathlib import Path

from mmusv.config import load_scenario
from mmusv.errors import InputError, NotFoundError

__all__ = ["BundledScenario", "bundled_dir", "bundled_scenarios", "resolve_scenario", "resolve_spec"]


def bundled_dir() -> Path:
    """The folder of the bundled scenarios (``specs/`` below it holds the bundled generation specs)."""
    return Path(str(importlib.resources.files("mmusv") / "scenarios"))


def _names(folder: Path | None = None) -> list[str]:
    return sorted(p.stem for p in (folder or bundled_dir()).glob("*.yaml"))


def _resolve(
    name: str | Path, folder: Path, parents: tuple[str, ...], noun: str, other: tuple[Path, str] | None = None
) -> Path:
    """``name`` itself when it exists, otherwise the bundled file of that stem in ``folder`` when ``name`` is bare
    or under one of the repository-relative ``parents``; else :class:`~mmusv.errors.NotFoundError`, which says so
    when ``name`` is a bundled file of the other kind (``other``: its folder and what to do with it)."""
    p = Path(name)
    stem = p.name[: -len(".yaml")] if p.name.endswith(".yaml") else p.name
    bare = p.parent == Path(".")
    typed = os.fspath(name)
    if (
        os.path.isdir(p)
        and not any(sep in typed for sep in ("/", os.sep))
        and not typed.endswith(".yaml")
        and os.path.isfile(folder / f"{stem}.yaml")
    ):  # `mmusv run port_entry` beside the folder an earlier `-o port_entry` wrote: it ran that folder as a batch
        raise InputError(
            f"{noun} {typed!r} is both a folder here and a bundled {noun}: give ./{typed} for the folder "
            f"or {typed}.yaml for the bundled {noun}"
        )
    if os.path.exists(p):  # False, where Path.exists raised OSError, for a name too long to be a file's
        return p
    if bare or p.parent in (Path(x) for x in parents):
        cand = folder / f"{stem}.yaml"
        if os.path.isfile(cand):
            return cand
    if os.path.islink(p):  # a link to nothing: "does not exist" sent the user looking for the name itself
        try:
            os.stat(p)
            why = "its target cannot be read"
        except OSError as exc:
            why = (
                "a loop of links"
                if exc.errno == errno.ELOOP
                else f"it points to {os.readlink(p)}, which does not exist"
            )
        raise NotFoundError(f"{noun} file {str(name)!r} is a link that leads nowhere: {why}")
    hint = ""
    if other is not None and bare and os.path.isfile(other[0] / f"{stem}.yaml"):  # `mmusv run island_demo`, a spec
        hint = f" ({stem} is {other[1].format(stem=stem)})"
    raise NotFoundError(
        f"{noun} file {str(name)!r} does not exist and is not a bundled {noun}; bundled: {', '.join(_names(folder))}"
        + hint
    )


def resolve_scenario(name: str | Path) -> Path:
    """``name`` as a scenario file: the path itself when it exists, otherwise the bundled scenario of that name.

    Raises :class:`~mmusv.errors.NotFoundError` naming the bundled scenarios when neither exists."""
    specs = (bundled_dir() / "specs", "a bundled generation spec: mmusv generate {stem}")
    return _resolve(name, bundled_dir(), ("scenarios",), "scenario", specs)


def resolve_spec(name: str | Path) -> Path:
    """``name`` as a generation spec: the path itself when it exists, otherwise the bundled spec of that name
    (``coop_detection``, ``scenarios/specs/coop_detection.yaml``), so bundled specs work from any folder.

    Raises :class:`~mmusv.errors.NotFoundError` naming the bundled specs when neither exists."""
    scenarios = (bundled_dir(), "a bundled scenario: mmusv run {stem}")
    return _resolve(name, bundled_dir() / "specs", ("specs", "scenarios/specs"), "spec", scenarios)


@dataclass(frozen=True)
class BundledScenario:
    """One bundled scenario, as listed by ``mmusv scenarios``."""

    name: str
    path: Path
    map: str
    usvs: int
    targets: int
    frames: int
    description: str


def _description(text: str) -> str:
    """The first sentence-line of the file's leading ``#`` comment block (empty when there is none)."""
    lines = []
    for line in text.splitlines():
        if not line.startswith("#"):
            break
        lines.append(line.lstrip("#").strip())
    first = " ".join(lines)
    m = re.search(r"(?<!Fig)\.(\s|$)", first)
    return first if m is None else first[: m.start() + 1]


def bundled_scenarios() -> list[BundledScenario]:
    """Every bundled scenario, sorted by name, loaded and validated (map type, USV/target counts, frames). A package
    whose scenarios folder is missing or empty (a copy that lost its data) is a :class:`~mmusv.errors.NotFoundError`
    naming the folder, not an empty list."""
    names = _names()
    if not names:
        raise NotFoundError(
            f"no bundled scenario in {bundled_dir()}: the package's data is missing; reinstall mmusv "
            "(pip install mmusv, or pip install -e . in a checkout)"
        )
    out = []
    for stem in names:
        path = bundled_dir() / f"{stem}.yaml"
        sc = load_scenario(path)
        usvs = sum(1 for v in sc.vessels if v.role == "usv")
        out.append(
            BundledScenario(
                name=sc.name,
                path=path,
                map=sc.map.type,
                usvs=usvs,
                targets=len(sc.vessels) - usvs,
                frames=sc.acquisition.frames,
                description=_description(path.read_text(encoding="utf-8")),
            )
        )
    return out
