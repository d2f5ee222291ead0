"""``mmusv generate -o DIR`` over a folder holding a user's ``.yml`` scenario: the foreign-file check looked at
``*.yaml`` only, so the set was generated beside it, and ``mmusv run DIR`` then recorded the user's file with the
set (a batch takes ``.yml`` too). It is refused as a foreign ``.yaml`` is, before any sampling."""

from __future__ import annotations

from pathlib import Path

import pytest
from mmusv.errors import IoError
from mmusv.generate import generate

from .test_user_round import TINY


@pytest.mark.parametrize("force", [False, True])
def test_a_users_yml_in_the_output_folder_is_refused_as_a_yaml_is(tmp_path: Path, force: bool) -> None:
    out = tmp_path / "gen"
    out.mkdir()
    (out / "mine.yml").write_text("name: mine\n", encoding="utf-8")
    with pytest.raises(IoError, match=r"holds YAML files that no earlier generate run there wrote \(mine\.yml"):
        generate(TINY, out, force=force)
    assert sorted(p.name for p in out.iterdir()) == ["mine.yml"]
