"""The check of a command's ``--help`` page that the benches' and the scripts' tests share: its description is a
whole paragraph (several stopped mid-sentence where their docstring's first line ended) and every option and
argument has a line of help, on its own line or the next, more indented one."""

from __future__ import annotations

import re

__all__ = ["check_help_page"]


def check_help_page(name: str, page: str) -> None:
    """Asserts that ``page`` (argparse's ``--help`` output of ``name``) has a whole description and a line of help
    for every option and argument other than ``-h``."""
    body = page.split("\n\n", 1)[1]  # after the usage lines
    description = " ".join(re.split(r"\n(?:positional arguments|options):\n", body)[0].split())
    assert description and description[-1] in ".):", f"{name}: description cut short: {description!r}"
    lines = body.split("\n")
    for i, line in enumerate(lines):
        m = re.match(r"^  (-\S.*?|[a-z]\w*)(?:\s{2,}(\S.*))?$", line)
        if not m or m.group(1).startswith("-h"):
            continue
        follows = i + 1 < len(lines) and re.match(r"^ {6,}\S", lines[i + 1]) is not None
        assert m.group(2) or follows, f"{name}: option without help: {line.strip()!r}"
