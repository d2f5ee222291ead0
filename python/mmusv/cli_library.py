"""``mmusv assets`` and ``mmusv scenarios``: the tables of what ships with mmusv, the vessel library (with
``--render``, a close-up per asset and a contact sheet) and the bundled scenarios; ``mmusv assets FILE...`` the
same table of the user's own assets, those of asset files and of the ``assets:`` lists of scenarios.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from mmusv.cli_console import rich_console, say
from mmusv.cli_paths import check_output_folder, path_arg, ready_output_folder, refuse_replacing
from mmusv.errors import ConfigError

if TYPE_CHECKING:
    from rich.table import Table

    from mmusv.world.vessels import VesselAsset

__all__ = ["UserAsset", "cmd_assets", "cmd_scenarios", "read_user_assets"]


_TABLE_COLUMNS = ("name", "category", "class", "length m", "beam m", "height m", "draft m", "triangles", "parts")
_SCENARIO_KEYS = frozenset({"seed", "map", "environment", "acquisition", "rigs", "assets", "vessels"})
"""Keys of a scenario mapping that no asset entry has (``mmusv.config.Scenario``'s fields but ``name``)."""
_ASSET_KEYS = frozenset(
    {"category", "description", "semantic_class", "mounts", "mesh", "scale", "up_axis", "forward_axis"}
    | {"waterline_z", "draft", "hull", "parts"}
)
"""Keys of an asset entry that no scenario has (``mmusv.world.asset_spec``'s specs' fields but ``name``)."""


@dataclass(frozen=True)
class UserAsset:
    """One asset of the files ``mmusv assets FILE...`` is given: built, in no library."""

    asset: VesselAsset
    file: Path
    """The asset file it comes from."""
    scenario: str | None
    """The scenario file (as given) whose ``assets:`` lists that file; ``None`` for an asset file given itself."""


def cmd_assets(args: argparse.Namespace) -> int:
    """``mmusv assets``: the built-in library's table, or with FILEs that of the user's assets they hold; with
    ``--render DIR`` a close-up of each and a contact sheet. Every file is read and checked before ``--render``'s
    folder is made: a bad one is one error naming it, and nothing is written."""
    from mmusv.world.vessels import library

    if args.overwrite and args.render is None:
        raise ConfigError("--overwrite: only with --render DIR (the files it replaces are those --render writes)")
    files = [path_arg(f, flag="FILE") for f in args.files]
    if args.render is not None:  # an empty --render, or one under a file, named before the files are read
        check_output_folder(args.render, flag="--render")
    user, bare = read_user_assets(files) if files else (None, [])
    if user is not None and args.render is not None:
        _check_renderable(user, bare, args.render)
    for given in bare:
        say(
            f"mmusv: note: {given}: the scenario lists no asset files (assets:); its vessels are built-in assets "
            "(mmusv assets lists them)"
        )
    if args.render is not None:  # its folder made first: one that cannot be was named after the table
        from mmusv.world.contact_sheet import sheet_files
        from mmusv.world.vessels import asset_names

        names = asset_names() if user is None else [u.asset.name for u in user]
        ready_output_folder(args.render, flag="--render")
        # files of the names it writes already there (a user's own contact_sheet.png) were replaced without a word
        refuse_replacing(args.render, sheet_files(names), overwrite=args.overwrite, flag="--render")
    console = rich_console()
    if user is None:
        console.print(_table("mmusv vessel library", [(a, None) for a in library()]))
    elif user:
        console.print(_table("Your vessel assets (from the files given)", [(u.asset, u) for u in user]))
    if args.materials:
        for a in library() if user is None else [u.asset for u in user]:
            console.print(_materials_table(a))
    if args.render is not None:  # one close-up per asset and a contact sheet of them all
        from mmusv.world.contact_sheet import write_contact_sheet

        drawn = None if user is None else [u.asset for u in user]
        console.print(f"wrote {write_contact_sheet(args.render, assets=drawn, overwrite=args.overwrite)}")
    return 0


def _table(title: str, rows: list[tuple[VesselAsset, UserAsset | None]]) -> Table:
    """The assets' table: the library's columns, and for the user's assets their materials and file."""
    import numpy as np
    from rich.table import Table

    mine = any(u is not None for _, u in rows)
    table = Table(title=title)
    for col in (*_TABLE_COLUMNS, *(("materials", "file") if mine else ())):
        table.add_column(col, justify="right" if col.endswith(("m", "triangles", "parts", "materials")) else "left")
    for a, u in rows:
        cells = [
            a.name,
            a.category,
            a.semantic_class.name.lower(),
            f"{a.length:.1f}",
            f"{a.beam:.1f}",
            f"{a.height:.1f}",
            f"{a.draft:.1f}",
            str(a.num_triangles),
            str(a.num_parts),
        ]
        if u is not None:
            via = f" (assets: of {u.scenario})" if u.scenario is not None else ""
            cells += [str(len(np.unique(a.mesh.materials))), f"{_shown(u.file)}{via}"]
        table.add_row(*cells)
    return table


def _materials_table(asset: VesselAsset) -> Table:
    """The materials of ``asset``'s faces, by name: the faces of each, base colour (linear RGB and the 8-bit sRGB
    it shows as), roughness, metallic, emitted radiance (cd/m², linear RGB) and a navigation lamp's arc (centre
    bearing ± half-width, degrees, body frame: 0 right ahead, +90 to port). ``class_default`` (id 0) is the look of
    the face's semantic class."""
    import numpy as np
    from rich.table import Table

    from mmusv.world.materials import all_materials
    from mmusv.world.mesh_materials import linear_to_srgb

    table = Table(title=f"Materials of {asset.name}")
    for col in ("material", "faces", "base colour (linear)", "sRGB", "roughness", "metallic", "emissive cd/m²"):
        table.add_column(col, justify="right" if col in ("faces", "roughness", "metallic") else "left")
    table.add_column("lamp arc °")
    every = all_materials()
    ids, counts = np.unique(np.asarray(asset.mesh.materials), return_counts=True)
    rows = sorted(((every[int(i)], int(c)) for i, c in zip(ids, counts, strict=True)), key=lambda r: r[0].name)
    for m, faces in rows:
        srgb = np.round(linear_to_srgb(np.asarray(m.base_color)) * 255).astype(int)
        glow = "" if not any(m.emissive) else ", ".join(f"{e:.4g}" for e in m.emissive)
        arc = "" if not m.nav_light else ("all round" if m.arc_deg[1] >= 180 else "{:g} ± {:g}".format(*m.arc_deg))
        table.add_row(
            m.name,
            str(faces),
            ", ".join(f"{c:.4g}" for c in m.base_color),
            "#{:02x}{:02x}{:02x}".format(*srgb),
            f"{m.roughness:.3g}",
            f"{m.metallic:.3g}",
            glow,
            arc,
        )
    return table


def read_user_assets(files: list[str]) -> tuple[list[UserAsset], list[str]]:
    """The assets of ``files``, each a scenario YAML (the asset files its ``assets:`` lists, read as ``mmusv run``
    of it reads them) or an asset YAML (one asset, or a list of them), built and added to no library, and the
    scenarios of ``files`` that list no asset file. :class:`~mmusv.errors.ConfigError` naming the file (and the
    entry) when one does not exist, is neither, or holds an asset that is wrong or takes a built-in asset's
    name."""
    from mmusv.scenario_assets import builtin_owner, read_asset_file, read_scenario_assets
    from mmusv.world.asset_spec import AssetSpecError
    from mmusv.world.mesh_files import _MESH_FORMATS
    from mmusv.yamlio import read_yaml

    out: list[UserAsset] = []
    bare: list[str] = []
    for given in files:
        path = Path(given).expanduser()
        if path.suffix.lower().lstrip(".") in _MESH_FORMATS and path.is_file():  # the mesh, not its asset file
            raise ConfigError(
                f"{given}: a mesh file, not an asset file: give the asset YAML that names it as mesh: {path.name} "
                "(with name:, and draft: or waterline_z:; docs/assets.md), or a scenario whose assets: lists that YAML"
            )
        data = read_yaml(path, kind="scenario or asset")
        kind = _kind_of(data)
        if kind == "scenario":
            assert isinstance(data, dict)
            if not data.get("assets"):  # (a value that is not a list is named by read_scenario_assets)
                bare.append(given)
                continue
            for file, assets in read_scenario_assets(data["assets"], base_dir=path.resolve().parent, where=given):
                out += [UserAsset(a, file, given) for a in assets]
            continue
        if kind is None:
            raise ConfigError(
                f"{given}: neither a scenario (a mapping with vessels: and assets:, the asset files of the user's "
                "vessels) nor an asset file (a mapping with name: and mesh: or hull:, or a list of them); "
                "see docs/assets.md"
            )
        try:
            assets = read_asset_file(path.resolve())
        except (AssetSpecError, ConfigError, OSError) as exc:
            raise ConfigError(f"{given}: {exc}") from None
        for i, a in enumerate(assets):
            if builtin_owner(a.name) is not None:
                field = "name" if kind == "asset" else f"vessels[{i}].name"
                raise ConfigError(
                    f"{given}: {field}: {a.name!r} is the name of a built-in asset (a scenario that lists this file "
                    "is refused); give it another name"
                )
        out += [UserAsset(a, path, None) for a in assets]
    return _once(out), bare


def _once(user: list[UserAsset]) -> list[UserAsset]:
    """``user`` without the repeats of an asset file's asset (a file given itself and listed by a scenario too)."""
    seen: set[tuple[Path, str]] = set()
    out = []
    for u in user:
        key = (u.file.resolve(), u.asset.name)
        if key not in seen:
            seen.add(key)
            out.append(u)
    return out


def _kind_of(data: object) -> str | None:
    """``"scenario"``, ``"asset"`` (one asset entry), ``"catalogue"`` (a list of them) or ``None`` (neither) for
    the YAML document ``data``."""
    if isinstance(data, list):
        return "catalogue"
    if not isinstance(data, dict):
        return None
    vessels = data.get("vessels")
    if (
        "assets" not in data
        and isinstance(vessels, list)
        and any(isinstance(v, dict) and ("mesh" in v or "hull" in v) for v in vessels)
    ):
        return "catalogue"  # a scenario's vessels have an id, a role and an asset, not a mesh or a hull
    if _SCENARIO_KEYS & set(data):
        return "scenario"
    return "asset" if _ASSET_KEYS & set(data) else None


def _check_renderable(user: list[UserAsset], bare: list[str], render: str) -> None:
    """--render of ``user``: something to draw, and no two assets of one name (one ``<name>.png`` each);
    ``bare``, the scenarios given that list no asset file, named when there is nothing."""
    if not user:
        which = f" ({', '.join(bare)} list{'s' if len(bare) == 1 else ''} no asset files under assets:)" if bare else ""
        raise ConfigError(f"--render {render}: nothing to render: the files given hold no asset of the user's{which}")
    seen: dict[str, UserAsset] = {}
    for u in user:
        first = seen.setdefault(u.asset.name, u)
        if first is not u:
            raise ConfigError(
                f"--render {render}: two assets named {u.asset.name!r} ({_shown(first.file)} and {_shown(u.file)}) "
                f"would both be drawn to {u.asset.name}.png; render them one file at a time"
            )


def _shown(path: Path) -> str:
    """``path`` relative to the current folder when it lies under it, else as it is."""
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except (ValueError, OSError):
        return str(path)


def cmd_scenarios(args: argparse.Namespace) -> int:
    from rich.table import Table

    from mmusv.bundled import bundled_scenarios

    table = Table(title="Bundled scenarios (mmusv run NAME)")
    for col in ("name", "map", "USVs", "targets", "frames", "description"):
        table.add_column(col, justify="right" if col in ("USVs", "targets", "frames") else "left")
    for b in bundled_scenarios():
        table.add_row(b.name, b.map, str(b.usvs), str(b.targets), str(b.frames), b.description)
    rich_console().print(table)
    return 0
