"""``mmusv run FOLDER`` on the folder of a ``mmusv generate`` run stopped before the end (its journal
``.generate.partial`` left, no ``report.json``): the scenarios written so far were recorded and ``dataset.json``
written as for the whole set, exit 0, without a word. It is refused before anything is recorded, saying how to go
on; with the journal removed (the user's choice) the scenarios there are recorded."""

from __future__ import annotations

from pathlib import Path

import pytest
from mmusv.batch import run_many
from mmusv.cli import main
from mmusv.errors import ConfigError
from mmusv.generate.runner import JOURNAL

from .conftest import scenario, write


def _stopped_generation(tmp_path: Path) -> Path:
    src = tmp_path / "scenarios"
    src.mkdir()
    write(src / "coop_000.yaml", scenario("coop_000", frames=1))
    (src / JOURNAL).write_text("coop_000.yaml\ncoop_001.yaml\n", encoding="utf-8")
    return src


def test_a_stopped_generation_is_refused_before_anything_is_recorded(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = _stopped_generation(tmp_path)
    with pytest.raises(ConfigError, match=r"holds part of a generated set.*--force.*remove"):
        run_many(src, out_dir=tmp_path / "out")
    assert not (tmp_path / "out").exists()
    assert main(["run", str(src), "-o", str(tmp_path / "out")]) != 0
    err = capsys.readouterr().err
    assert "holds part of a generated set" in err and JOURNAL in err and "Traceback" not in err, err
    assert not (tmp_path / "out").exists()


def test_with_the_journal_removed_the_scenarios_there_are_recorded(tmp_path: Path) -> None:
    src = _stopped_generation(tmp_path)
    (src / JOURNAL).unlink()
    report = run_many(src, out_dir=tmp_path / "out")
    assert [o.status for o in report.outcomes] == ["done"]
