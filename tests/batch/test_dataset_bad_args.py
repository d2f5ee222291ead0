"""``mmusv dataset`` (and ``mmusv run``'s batch options) refuse a bad ``--split-frames``, ``--retries`` or
``--cpus-per-task`` before the scenario set is generated or anything recorded."""

from __future__ import annotations

from pathlib import Path

import pytest
from mmusv.cli import main

from .conftest import SPEC, write


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        (("--split-frames", "0"), "--split-frames 0"),
        (("--split-frames", "-3"), "--split-frames -3"),
        (("--retries", "-1"), "--retries -1"),
        (("--cpus-per-task", "0"), "--cpus-per-task 0"),
    ],
)
def test_bad_batch_options_are_refused_before_generating(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: tuple[str, ...], said: str
) -> None:
    spec = write(tmp_path / "tinyset.yaml", SPEC)
    out = tmp_path / "ds"
    assert main(["dataset", str(spec), "-o", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: ") and said in err, err
    assert not out.exists()
