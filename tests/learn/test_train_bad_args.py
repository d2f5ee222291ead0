"""``mmusv train`` refuses bad ``--device``, ``--workers``, ``--epochs`` and ``--time-limit`` values with one line
naming the option, before it reads a recording or writes anything (a bogus device was a torch traceback, a NaN or
negative time limit a model that looked complete after one step)."""

from __future__ import annotations

from pathlib import Path

import pytest
from mmusv.cli import main


def _train(tmp_path: Path, *extra: str) -> int:
    rec = tmp_path / "missing.mcap"  # never read: the options are checked first
    return main(["train", str(rec), "--preset", "tiny", "--no-progress", "-o", str(tmp_path / "out"), *extra])


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        (("--device", "bogus"), "--device 'bogus'"),
        (("--device", "cuda:99"), "--device 'cuda:99'"),
        (("--workers", "-1"), "--workers -1"),
        (("--epochs", "-1"), "--epochs -1"),
        (("--epochs", "0"), "--epochs 0"),
        (("--time-limit", "nan"), "--time-limit nan"),
        (("--time-limit", "-5"), "--time-limit -5"),
        (("--time-limit", "0"), "--time-limit 0"),
        (("--time-limit", "inf"), "--time-limit inf"),
    ],
)
def test_bad_training_options_are_refused_before_anything_is_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: tuple[str, ...], said: str
) -> None:
    assert _train(tmp_path, *extra) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: ") and said in err, err
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_the_device_error_says_what_is_allowed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _train(tmp_path, "--device", "bogus") == 2
    assert "cpu, cuda, cuda:N or mps" in capsys.readouterr().err
