"""A sceptical review of the last round's changes (comments kept by the editor, the Python API round): each test
failed before its fix."""

from __future__ import annotations

import numpy as np
import pytest
from mmusv.config import load_scenario
from mmusv.editor.comments import read_comments
from mmusv.editor.document import leading_comment, scenario_file
from mmusv.sea_surface import surface_tiles
from mmusv.yamlio import parse_yaml

_BODY = """name: t
seed: 1  # the seed
map: {type: open_sea}
acquisition: {frequency_hz: 5, frames: 5}
vessels:
  - {id: a, role: usv, asset: usv_wamv, speed_mps: 2.0, route: [[0, 0], [100, 0]]}
"""


def _saved(text: str) -> str:
    """What the editor writes for ``text`` opened with ``mmusv editor FILE`` (read as UTF-8 text) and saved."""
    scenario = load_scenario(parse_yaml(text, "t.yaml"))
    out, moved = scenario_file(scenario, comment=leading_comment(text), comments=read_comments(text))
    assert moved == []
    return out


def test_a_byte_order_mark_keeps_the_leading_comment_and_the_first_lines_comment() -> None:
    # Notepad's UTF-8 keeps a byte-order mark: `mmusv editor FILE` read it as text, and a save lost the file's
    # leading comment block (not '#' at the start of the first line) and a comment on its first line (no space
    # before the '#')
    out = _saved("\ufeff# The harbour at dusk.\n# Two USVs.\n" + _BODY)
    assert out.startswith("# The harbour at dusk.\n# Two USVs.\n"), out
    assert "seed: 1  # the seed" in out
    first = _saved("\ufeffname: t  # its name\n" + _BODY.split("\n", 1)[1])
    assert "name: t  # its name" in first, first


def test_bom_text_reads_the_same_comments_as_without() -> None:
    text = "# lead\nname: t  # n\n" + _BODY.split("\n", 1)[1]
    assert read_comments("\ufeff" + text) == read_comments(text)
    assert leading_comment("\ufeff" + text) == leading_comment(text) == "lead"


@pytest.mark.parametrize("foci", [[], (), np.array([])])
def test_surface_tiles_without_foci_is_zero(foci: object) -> None:
    # the docstring says "0 without foci", as before the API round's checks; `[]` became an InputError (its
    # shape (0,) is not (N, 2))
    assert surface_tiles(foci, radius_m=100.0) == 0  # type: ignore[arg-type]
    assert surface_tiles(np.zeros((0, 2)), radius_m=100.0) == 0
