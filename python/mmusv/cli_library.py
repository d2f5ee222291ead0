"""``mmusv assets`` and ``mmusv scenarios``: the tables of what ships with mmusv, the vessel library (with
``--render``, a close-up per asset and a contact sheet) and the bundled scenarios.
"""

from __future__ import annotations

import argparse

from mmusv.cli_console import rich_console
from mmusv.cli_paths import ready_output_folder, refuse_replacing
from mmusv.errors import ConfigError

__all__ = ["cmd_assets", "cmd_scenarios"]


def cmd_assets(args: argparse.Namespace) -> int:
    from rich.table import Table

    from mmusv.world.vessels import library

    if args.overwrite and args.render is None:
        raise ConfigError("--overwrite: only with --render DIR (the files it replaces are those --render writes)")
    if args.render is not None:  # its folder made first: one that cannot be was named after the table
        from mmusv.world.contact_sheet import sheet_files
        from mmusv.world.vessels import asset_names

        ready_output_folder(args.render, flag="--render")
        # files of the names it writes already there (a user's own contact_sheet.png) were replaced without a word
        refuse_replacing(args.render, sheet_files(asset_names()), overwrite=args.overwrite, flag="--render")
    table = Table(title="mmusv vessel library")
    for col in ("name", "category", "class", "length m", "beam m", "height m", "draft m", "triangles", "parts"):
        table.add_column(col, justify="right" if col.endswith(("m", "triangles", "parts")) else "left")
    for a in library():
        table.add_row(
            a.name,
            a.category,
            a.semantic_class.name.lower(),
            f"{a.length:.1f}",
            f"{a.beam:.1f}",
            f"{a.height:.1f}",
            f"{a.draft:.1f}",
            str(a.num_triangles),
            str(a.num_parts),
        )
    rich_console().print(table)
    if args.render is not None:  # one close-up per asset and a contact sheet of them all
        from mmusv.world.contact_sheet import write_contact_sheet

        rich_console().print(f"wrote {write_contact_sheet(args.render, overwrite=args.overwrite)}")
    return 0


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
