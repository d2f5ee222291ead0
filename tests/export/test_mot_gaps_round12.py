"""``--to mot``: sequences with frames skipped in the middle say so, as the KITTI tracking export's do.

MOT frames are renumbered 1, 2, … over the converted frames and ``seqinfo.ini``'s ``frameRate`` is the recording's,
so where an incomplete frame in the middle of a recording is skipped, two consecutive MOT frames are two time steps
apart: a tracker stepping its motion model by ``frameRate`` was misled without a word (the report listed the skipped
frame, not that the sequences' frames are no longer evenly spaced; ``--to kitti_tracking`` says so)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from mmusv.export import convert


def test_a_gap_in_the_middle_of_the_sequences_is_noted(
    coop_rec: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from mmusv.export.mot import MotWriter

    real = MotWriter.missing

    def missing(self: Any, frame: Any) -> list[str]:
        return ["/made/up"] if frame.index == 1 else real(self, frame)

    monkeypatch.setattr(MotWriter, "missing", missing)
    out = tmp_path / "o"
    report = convert(coop_rec, to="mot", out_dir=out, splits=None, agents="usv_a")
    rec = report.recordings[0]
    assert rec.skipped == [{"frames": [1, 1], "reason": "incomplete: missing /made/up"}]
    seq = out / "train" / "export_coop.usv_a.front"
    assert (seq / "frames.txt").read_text() == "0\n2\n"  # renumbered: MOT frame 2 is acquisition index 2
    assert "frameRate=5\n" in (seq / "seqinfo.ini").read_text()
    said = [n for n in rec.notes if "frequency_hz apart" in n]
    assert said == [
        "acquisition index 1 is not converted, so the frames of its sequences (export_coop.usv_a.front, "
        "export_coop.usv_a.left, export_coop.usv_a.rear, export_coop.usv_a.right) are not all 1 / frequency_hz "
        "apart (each sequence's frames.txt gives each frame's index)"
    ], rec.notes


def test_no_gap_no_note(coop_rec: Path, tmp_path: Path) -> None:
    """``--frames 1:`` starts later: its frames are evenly spaced, nothing to say."""
    report = convert(coop_rec, to="mot", out_dir=tmp_path / "o", splits=None, frames="1:")
    assert not [n for n in report.recordings[0].notes if "frequency_hz apart" in n], report.recordings[0].notes
