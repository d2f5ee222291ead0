"""Review of ``--to kitti_tracking`` (a helper's round): a sequence with frames skipped in the middle says so.

Frames are renumbered 0, 1, … over the converted frames, so where an incomplete frame in the middle of a recording
is skipped, two consecutive frames are two time steps apart; a 3D tracker stepping a motion model per frame would be
misled without a word (the report listed the skipped frame, not that a sequence's frames are no longer evenly
spaced). The conversion's notes now name the sequence and the acquisition indices missing.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from mmusv.export import convert


def test_a_gap_in_the_middle_of_a_sequence_is_noted(
    port_rec: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from mmusv.export.kitti_tracking import KittiTrackingWriter

    real = KittiTrackingWriter.missing

    def missing(self: Any, frame: Any) -> list[str]:
        return ["/made/up"] if frame.index == 1 else real(self, frame)

    monkeypatch.setattr(KittiTrackingWriter, "missing", missing)
    out = tmp_path / "o"
    report = convert(port_rec, to="kitti_tracking", out_dir=out, splits=None, extras=None, agents="usv_1")
    rec = report.recordings[0]
    assert rec.skipped == [{"frames": [1, 1], "reason": "incomplete: missing /made/up"}]
    train = out / "train"
    assert (train / "frames" / "0000.txt").read_text() == "0\n2\n"  # renumbered: frame 1 is acquisition index 2
    assert (train / "evaluate_tracking.seqmap.train").read_text() == "0000 empty 000000 000002\n"
    assert sorted(p.name for p in (train / "velodyne" / "0000").iterdir()) == ["000000.bin", "000001.bin"]
    said = [n for n in rec.notes if n.startswith("train/0000: ")]
    assert said == [
        "train/0000: acquisition index 1 is not converted, so its frames are not all 1 / frequency_hz apart "
        "(frames/0000.txt gives each frame's index)"
    ], rec.notes


def test_no_gap_no_note(port_rec: Path, tmp_path: Path) -> None:
    """``--frames 1:`` starts later: its frames are evenly spaced, nothing to say."""
    report = convert(
        port_rec, to="kitti_tracking", out_dir=tmp_path / "o", splits=None, extras=None, agents="usv_1", frames="1:"
    )
    assert not [n for n in report.recordings[0].notes if "not converted" in n]
