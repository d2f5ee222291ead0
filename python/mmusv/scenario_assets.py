"""A scenario's own vessel assets: the asset files its ``assets:`` list names, built and added to the library
when the scenario is read, so that ``mmusv run scenario.yaml`` (and a batch, the editor, ``convert``'s re-reads)
can use a user's mesh by name, as a Python session does with
:func:`mmusv.world.vessels.load_asset_file` ``(..., register=True)``.

Each entry is the path of an asset YAML file: one asset mapping (:func:`~mmusv.world.vessels.load_asset_file`'s
keys: ``name``, ``mesh``, ``scale``, ``draft``, ...) or a list of them (a catalogue,
:func:`~mmusv.world.vessels.load_asset_catalog`). A relative path is relative to the scenario file's folder (the
current folder for a scenario given as a mapping); a mesh path inside the asset file is relative to that file.

Each scenario sees the built-in library, the assets registered by Python calls and its own asset files' assets,
none of another scenario's: the library is one per process, and a batch (``mmusv run FOLDER``, in one process or in
reused workers), the editor, a study or a Python session reads several scenarios in one, so two scenarios' files may
each name an asset ``skiff`` and a scenario that lists no asset file cannot use another's (as ``mmusv run`` of it
cannot). :func:`use_scenario_assets` (:func:`mmusv.config.load_scenario`) first takes the assets of the other files
read so far out of the library (:func:`keep_scenario_assets`; taken out, they are put back without being built again
when their scenario is read next, unless their file changed), then registers the scenario's own; a
:class:`~mmusv.config.Scenario` loaded before another remembers its files (:class:`AssetHome`), and
``load_scenario`` of it (what ``mmusv.run``, :class:`~mmusv.simulation.Simulation` and the studies call) holds the
library for it again. Reading the same scenario again rebuilds an asset only when its file or the mesh it names
changed (size or modification time), and replaces it; an asset name that another of the scenario's files, a Python
``register_asset`` call or the built-in library already holds is refused, naming both.
:func:`asset_digest` gives the SHA-256 of the user assets a scenario uses, which
:func:`mmusv.config.scenario_hash` folds in: a changed mesh is a changed configuration, so a batch records it again
instead of skipping it as complete.

Threads: the library is held for one scenario at a time. :func:`holding_library` (re-entrant) is held by a thread
while it reads a scenario (:func:`mmusv.config.load_scenario`) and while a :class:`~mmusv.simulation.Simulation`
is built from it (which keeps the assets it looked up, ``Simulation.assets``), so another thread reading another
scenario waits instead of switching the library under it; the editor's requests hold it through
:class:`mmusv.editor.evaluate.AssetScope`.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import threading
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mmusv.errors import ConfigError

if TYPE_CHECKING:
    from mmusv.world.vessels import VesselAsset

__all__ = [
    "AssetHome",
    "asset_digest",
    "asset_file_path",
    "asset_files",
    "builtin_owner",
    "holding_library",
    "keep_scenario_assets",
    "read_asset_file",
    "read_scenario_assets",
    "register_scenario_assets",
    "use_scenario_assets",
]

_lock = threading.Lock()
_held = threading.RLock()
"""Held while a thread reads a scenario or builds a Simulation from it (:func:`holding_library`)."""


@contextlib.contextmanager
def holding_library() -> Iterator[None]:
    """Holds the library for the calling thread's scenario (re-entrant): no other thread reads a scenario, and so
    switches the library to that one's assets, until the block ends. Two threads building Simulations of two
    scenarios that each name an asset ``skiff`` of their own got each other's skiff without it."""
    with _held:
        yield


def _free_after_fork() -> None:
    """A child forked while another thread held the library starts with it free: that thread is not there."""
    global _held, _lock
    _held, _lock = threading.RLock(), threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_free_after_fork)
_loaded: dict[str, tuple[tuple[Any, ...], tuple[str, ...]]] = {}
"""Resolved asset file -> (its signature, the names of the assets it registered)."""
_parked: dict[str, tuple[tuple[Any, ...], list[Any]]] = {}
"""Resolved asset file -> (its signature, its assets), taken out of the library by :func:`keep_scenario_assets`."""


def asset_file_path(base_dir: Path, entry: str) -> Path:
    """The resolved path of the asset file ``entry`` (an ``assets:`` entry) relative to ``base_dir``;
    :class:`ValueError` saying why when it cannot name a file (a NUL character, ``~name`` of no user of this machine,
    a name longer than the system takes), which was an internal error (a traceback) before."""
    try:
        path = (base_dir / Path(entry).expanduser()).resolve()
        os.stat(path)
    except RuntimeError:  # expanduser: "Could not determine home directory"
        raise ValueError(f"{entry.split('/', 1)[0]!r} names no user of this machine") from None
    except ValueError:
        raise ValueError("it holds a NUL character, which no file name can") from None
    except (FileNotFoundError, NotADirectoryError):
        pass  # said by the caller: it does not exist
    except OSError as exc:  # a name too long, a folder that cannot be read
        raise ValueError(f"not a file this system can open ({exc.strerror or exc})") from None
    return path


def asset_files(entries: Any, base_dir: Path) -> frozenset[Path]:
    """The resolved asset files a scenario's ``assets:`` value ``entries`` lists, relative to ``base_dir``: those of
    its entries that can name a file (:func:`register_scenario_assets` says what is wrong with the others)."""
    out: set[Path] = set()
    for entry in entries if isinstance(entries, list) else ():
        if isinstance(entry, str) and entry.strip():
            try:
                out.add(asset_file_path(base_dir, entry))
            except ValueError:
                continue
    return frozenset(out)


@dataclass(frozen=True, eq=False)
class AssetHome:
    """Where the user assets of a loaded :class:`~mmusv.config.Scenario` come from: its ``assets:`` entries, the
    folder they are relative to and the scenario's name in messages (``where``), for :func:`use_scenario_assets` to
    hold the library for it again after another scenario was read. Not part of the scenario's value: it compares
    equal to any other (and to none), so a scenario equals another of the same fields, as before."""

    entries: tuple[str, ...]
    base_dir: Path
    where: str

    def __eq__(self, other: object) -> bool:
        return other is None or isinstance(other, AssetHome)

    def __hash__(self) -> int:
        return 0

    def held(self) -> bool:
        """Whether the library holds the assets of exactly this scenario's files, of no other scenario's."""
        with _lock:
            return set(_loaded) == {str(p) for p in asset_files(list(self.entries), self.base_dir)}


def use_scenario_assets(entries: Any, *, base_dir: Path, where: str) -> AssetHome:
    """Holds the library for one scenario (see the module docstring): the assets of other scenarios' files out
    (:func:`keep_scenario_assets`), those of ``entries`` (its ``assets:`` value, relative to ``base_dir``) in
    (:func:`register_scenario_assets`, whose :class:`~mmusv.errors.ConfigError` it raises); its :class:`AssetHome`."""
    keep_scenario_assets(asset_files(entries, base_dir))
    if entries:
        register_scenario_assets(entries, base_dir=base_dir, where=where)
    return AssetHome(tuple(entries) if isinstance(entries, list) else (), base_dir, where)


def keep_scenario_assets(paths: Iterable[Path]) -> None:
    """Takes out of the library the assets of every asset file read so far that is not among ``paths`` (resolved
    asset file paths: those of the scenario about to be read), so that its names are free for that scenario's own
    files and a name it does not list is unknown to it, as to ``mmusv run`` of that file. Assets registered by
    other means (the built-in library, a Python ``register_asset`` call) stay."""
    from mmusv.world.vessels import get_asset, unregister_asset

    keep = {str(p) for p in paths}
    with _lock:
        for key in [k for k in _loaded if k not in keep]:
            sig, names = _loaded.pop(key)
            assets = []
            for name in names:
                try:
                    assets.append(get_asset(name))
                    unregister_asset(name)
                except KeyError:  # unregistered meanwhile by other means: built again when needed
                    continue
            _parked[key] = (sig, assets)


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
    from mmusv.world.vessels import get_asset, register_asset, unregister_asset

    for i, entry in enumerate(_entry_list(entries, where)):
        path, field = _entry_file(i, entry, base_dir=base_dir, where=where)
        with _lock:
            try:
                sig = _signature(path)
                if str(path) in _loaded and _loaded[str(path)][0] == sig:  # unchanged since last read
                    continue
                parked = _parked.pop(str(path), None)
                # taken out by keep_scenario_assets: put back; else built
                assets = parked[1] if parked is not None and parked[0] == sig else read_asset_file(path)
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
                        raise ConfigError(_taken(field, asset.name, held.source))
                    register_asset(asset)
                    names.append(asset.name)
            except ConfigError:
                for name in names:
                    unregister_asset(name)
                raise
            _loaded[str(path)] = (sig, tuple(names))


def read_scenario_assets(entries: Any, *, base_dir: Path, where: str) -> list[tuple[Path, list[VesselAsset]]]:
    """The assets of ``entries`` (a scenario's ``assets:`` value, relative to ``base_dir``), built as
    :func:`register_scenario_assets` builds them but added to no library: ``(asset file, its assets)`` in the
    order listed, a file listed twice once (``mmusv assets SCENARIO`` shows a user's assets without touching the
    library). The same :class:`~mmusv.errors.ConfigError` as ``mmusv run`` of the scenario for a bad entry, a bad
    file, or a name another of its files or the built-in library already holds."""
    from mmusv.world.asset_spec import AssetSpecError

    out: list[tuple[Path, list[VesselAsset]]] = []
    owners: dict[str, str] = {}  # asset name -> the file of this scenario that holds it
    for i, entry in enumerate(_entry_list(entries, where)):
        path, field = _entry_file(i, entry, base_dir=base_dir, where=where)
        if any(path == seen for seen, _ in out):  # (register_scenario_assets skips it as unchanged)
            continue
        try:
            assets = read_asset_file(path)
        except (AssetSpecError, ConfigError, OSError) as exc:
            raise ConfigError(f"{field}: {exc}") from None
        for asset in assets:
            owner = owners.get(asset.name) or builtin_owner(asset.name)
            if owner is not None:
                raise ConfigError(_taken(field, asset.name, owner))
            owners[asset.name] = str(path)
        out.append((path, assets))
    return out


def builtin_owner(name: str) -> str | None:
    """``"builtin"`` when the built-in library holds an asset called ``name``, else ``None``."""
    from mmusv.world.vessels import get_asset

    try:
        return "builtin" if get_asset(name).source == "builtin" else None
    except KeyError:
        return None


def _taken(field: str, name: str, owner: str) -> str:
    """The message for asset ``name`` of ``field`` whose name ``owner`` (an asset file, or ``"builtin"``) holds."""
    owner = "the built-in library" if owner == "builtin" else owner
    return f"{field}: asset {name!r} is already in the library, from {owner}; give it another name"


def _entry_list(entries: Any, where: str) -> list[Any]:
    """``entries``, a scenario's ``assets:`` value, when it is a list; else the :class:`ConfigError` saying so."""
    if not isinstance(entries, list):
        raise ConfigError(f"{where}: invalid scenario assets = {entries!r:.60}: must be a list of asset file paths")
    return entries


def _entry_file(i: int, entry: Any, *, base_dir: Path, where: str) -> tuple[Path, str]:
    """``(the resolved asset file, how messages name the entry)`` of ``assets[i]`` = ``entry``; a
    :class:`ConfigError` when it names no file there."""
    field = f"{where}: invalid scenario assets[{i}] = {entry!r:.80}"
    if not isinstance(entry, str) or not entry.strip():
        raise ConfigError(f"{field}: must be the path of an asset YAML file (relative to the scenario's folder)")
    try:
        path = asset_file_path(base_dir, entry)
    except ValueError as exc:
        raise ConfigError(f"{field}: {exc}; give the path of an asset YAML file") from None
    if not path.is_file():
        what = "is a folder" if path.is_dir() else "does not exist"
        raise ConfigError(f"{field}: {path} {what}; give an asset YAML file (docs/assets.md)")
    return path, field


def read_asset_file(path: Path) -> list[VesselAsset]:
    """The assets of the asset file ``path``, built and added to no library (one mapping, or a list of them /
    ``vessels:``); an :class:`~mmusv.world.asset_spec.AssetSpecError` or :class:`ConfigError` saying what is
    wrong."""
    from mmusv.world.vessels import load_asset_catalog, load_asset_file
    from mmusv.yamlio import read_yaml

    data = read_yaml(path, kind="asset file")
    is_list = isinstance(data, list) or (isinstance(data, dict) and "vessels" in data)
    if not is_list and not isinstance(data, dict):  # (load_asset_file's message names its twin)
        raise ConfigError(
            f"{path} holds {_kind(data)}, not an asset: "
            "an asset file holds one asset (a mapping with a name and a mesh or a hull) or a list "
            "of them (docs/assets.md)"
        )
    return load_asset_catalog(path) if is_list else [load_asset_file(path)]


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
