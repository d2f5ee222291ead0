"""A scenario's own vessel assets: the asset files its ``assets:`` list names, built and added to the library
when the scenario is read, so that ``mmusv run scenario.yaml`` (and a batch, the editor, ``convert``'s re-reads)
can use a user's mesh by name, as a Python session does with
:func:`mmusv.world.vessels.load_asset_file` ``(..., register=True)``.

Each entry is the path of an asset YAML file: one asset mapping (:func:`~mmusv.world.vessels.load_asset_file`'s
keys: ``name``, ``mesh``, ``scale``, ``draft``, ...) or a list of them (a catalogue,
:func:`~mmusv.world.vessels.load_asset_catalog`). A relative path is relative to the scenario file's folder (the
current folder for a scenario given as a mapping); a mesh path inside the asset file is relative to that file.

Reading the same scenario again in one process rebuilds an asset only when its file or the mesh it names changed
(size or modification time), and replaces it; an asset name that another file, a Python ``register_asset`` call or
the built-in library already holds is refused, naming both. :func:`asset_digest` gives the SHA-256 of the user
assets a scenario uses, which :func:`mmusv.config.scenario_hash` folds in: a changed mesh is a changed
configuration, so a batch records it again instead of skipping it as complete.
"""

from __future__ import annotations

import hashlib
import os
import threading
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from mmusv.errors import ConfigError

__all__ = ["asset_digest", "register_scenario_assets"]

_lock = threading.Lock()
_loaded: dict[str, tuple[tuple[Any, ...], tuple[str, ...]]] = {}
"""Resolved asset file -> (its signature, the names of the assets it registered)."""


def _stat(path: Path) -> tuple[str, int, int]:
    st = path.stat()
    return (str(path), st.st_size, st.st_mtime_ns)


def _signature(path: Path) -> tuple[Any, ...]:
    """The asset file's size and modification time, and those of every mesh file its entries name."""
    from mmusv.yamlio import read_yaml

    sig: list[Any] = [_stat(path)]
    data = read_yaml(path, kind="asset file")
    entries = data.get("vessels", data) if isinstance(data, dict) and "vessels" in data else data
    for entry in entries if isinstance(entries, list) else [entries]:
        mesh = entry.get("mesh") if isinstance(entry, dict) else None
        if isinstance(mesh, str) and mesh:
            m = (path.parent / Path(mesh).expanduser()).resolve()
            sig.append(_stat(m) if m.is_file() else (str(m), -1, -1))
    return tuple(sig)


def register_scenario_assets(entries: Any, *, base_dir: Path, where: str) -> None:
    """Builds and registers the assets of ``entries`` (the scenario's ``assets:`` value: a list of asset file
    paths), relative paths taken from ``base_dir``. :class:`~mmusv.errors.ConfigError` naming ``where`` (the
    scenario file), ``assets[i]``, the file and what is wrong; assets of earlier entries stay registered."""
    from mmusv.world.asset_spec import AssetSpecError
    from mmusv.world.vessels import get_asset, load_asset_catalog, load_asset_file, register_asset, unregister_asset
    from mmusv.yamlio import read_yaml

    if not isinstance(entries, list):
        raise ConfigError(f"{where}: invalid scenario assets = {entries!r:.60}: must be a list of asset file paths")
    for i, entry in enumerate(entries):
        field = f"{where}: invalid scenario assets[{i}] = {entry!r:.80}"
        if not isinstance(entry, str) or not entry.strip():
            raise ConfigError(f"{field}: must be the path of an asset YAML file (relative to the scenario's folder)")
        path = (base_dir / Path(entry).expanduser()).resolve()
        if not path.is_file():
            what = "is a folder" if path.is_dir() else "does not exist"
            raise ConfigError(f"{field}: {path} {what}; give an asset YAML file (docs/assets.md)")
        with _lock:
            try:
                sig = _signature(path)
                if str(path) in _loaded and _loaded[str(path)][0] == sig:  # unchanged since last read
                    continue
                data = read_yaml(path, kind="asset file")
                is_list = isinstance(data, list) or (isinstance(data, dict) and "vessels" in data)
                if not is_list and not isinstance(data, dict):  # (load_asset_file's message names its Python twin)
                    raise ConfigError(
                        f"{path} holds {_kind(data)}, not an asset: "
                        "an asset file holds one asset (a mapping with a name and a mesh or a hull) or a list of "
                        "them (docs/assets.md)"
                    )
                assets = load_asset_catalog(path) if is_list else [load_asset_file(path)]
            except (AssetSpecError, ConfigError, OSError) as exc:
                raise ConfigError(f"{field}: {exc}") from None
            previous = _loaded.pop(str(path), (None, ()))[1]
            for name in previous:  # the same file read again after a change: its assets are replaced
                unregister_asset(name)
            names: list[str] = []
            try:
                for asset in assets:
                    try:
                        held = get_asset(asset.name)
                    except KeyError:
                        held = None
                    if held is not None:
                        owner = "the built-in library" if held.source == "builtin" else held.source
                        raise ConfigError(
                            f"{field}: asset {asset.name!r} is already in the library, from {owner}; give it "
                            "another name"
                        )
                    register_asset(asset)
                    names.append(asset.name)
            except ConfigError:
                for name in names:
                    unregister_asset(name)
                raise
            _loaded[str(path)] = (sig, tuple(names))


def asset_digest(names: Iterable[str]) -> str:
    """SHA-256 of the user (non built-in) assets among ``names``, sorted by name: their meshes (vertices, faces,
    classes and materials) and mounts; the empty string when every one is built in (a scenario of built-in
    assets hashes as it always did)."""
    from mmusv.world.vessels import get_asset

    h = hashlib.sha256()
    used = False
    for name in sorted(set(names)):
        asset = get_asset(name)
        if asset.source == "builtin":
            continue
        used = True
        h.update(name.encode() + b"\0")
        for arr in (asset.mesh.vertices, asset.mesh.faces, asset.mesh.classes, asset.mesh.materials):
            h.update(str(arr.dtype).encode() + str(arr.shape).encode() + arr.tobytes())
        h.update(repr(sorted((k, repr(v)) for k, v in asset.mounts.items())).encode())
    return h.hexdigest() if used else ""


def scenario_base(source: str | os.PathLike[str] | None) -> Path:
    """The folder a scenario's relative asset paths start from: its file's folder, else the current one."""
    return Path(os.fspath(source)).expanduser().resolve().parent if source is not None else Path.cwd()


def _kind(data: object) -> str:
    """What a YAML document that is no asset holds, in words."""
    if data is None:
        return "nothing"
    if isinstance(data, bool):
        return "a true/false value"
    if isinstance(data, (int, float)):
        return "a number"
    return "text" if isinstance(data, str) else f"a {type(data).__name__}"
