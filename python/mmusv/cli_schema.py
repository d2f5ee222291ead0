"""``mmusv schema``: the JSON Schema of scenario or spec files on the standard output, or written to a file (never
over a file that is not a schema mmusv wrote).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mmusv.cli_paths import output_arg

__all__ = ["cmd_schema"]


def cmd_schema(args: argparse.Namespace) -> int:
    from mmusv.errors import ConfigError, IoError
    from mmusv.jsonio import write_bytes_atomic
    from mmusv.schema import schema_text

    text = schema_text(args.kind)
    if args.output is None or args.output == "-":  # `-o -`: the standard output, as for most tools (it wrote "./-")
        sys.stdout.write(text)
        return 0
    if not args.output:  # output_arg's hint, "." for the current folder, is no file name
        raise ConfigError("-o/--output is empty: give the schema's file name (or leave -o out for the standard output)")
    out = Path(output_arg(args.output, flag="-o/--output"))
    if out.is_file() and not _is_our_schema(out):  # `-o my_scenario.yaml` replaced the scenario, for good
        raise IoError(
            f"-o/--output {args.output}: the file exists and is not a schema mmusv wrote; choose another name or "
            "remove it first"
        )
    try:  # through a temporary beside it and a rename: an editor never reads half a schema
        if out.is_dir():
            raise IsADirectoryError(21, "is a folder, not a file")
        write_bytes_atomic(out, text.encode("utf-8"))
    except OSError as exc:
        raise IoError(f"-o/--output {args.output}: cannot write the schema: {exc.strerror or exc}") from None
    print(f"wrote {out}")
    return 0


def _is_our_schema(path: Path) -> bool:
    """Whether ``path`` holds a JSON Schema ``mmusv schema`` wrote (one it may replace with a newer one)."""
    import json

    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return False
    return isinstance(doc, dict) and "$schema" in doc and str(doc.get("title", "")).startswith("mmusv ")
