"""What a conversion reports (:func:`mmusv.export.convert`): per recording where it went and which frames were
converted or skipped, the totals, and the report file ``conversion.yaml`` (:data:`REPORT_NAME`) read back."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from mmusv.text import counted

__all__ = ["REPORT_NAME", "ConvertReport", "RecordingReport", "load_report"]

REPORT_NAME = "conversion.yaml"


@dataclass
class RecordingReport:
    """One recording's conversion: where it went and which frames were converted or skipped (``skipped``:
    ``{"frames": [first, last], "reason": ...}`` ranges)."""

    path: Path
    scenario: str
    folder: str
    split: str | None
    frames_converted: int = 0
    first_frame: int | None = None
    last_frame: int | None = None
    skipped: list[dict[str, Any]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    status: str = ""

    def as_dict(self) -> dict[str, Any]:
        """The recording's entry of ``conversion.yaml``."""
        return {
            "source": self.path.name,
            "scenario": self.scenario,
            "folder": self.folder,
            "split": self.split,
            "run_status": self.status,
            "frames_converted": self.frames_converted,
            "frames": None if self.first_frame is None else [self.first_frame, self.last_frame],
            "skipped": self.skipped,
            "notes": self.notes,
        }


@dataclass
class ConvertReport:
    """What a conversion wrote: per recording, totals, seconds (wall) and bytes on disk."""

    out_dir: Path
    target: str
    recordings: list[RecordingReport]
    agent_frames: int = 0
    files: int = 0
    bytes: int = 0
    seconds: float = 0.0

    @property
    def frames(self) -> int:
        """Frames converted (each one for every agent of its recording)."""
        return sum(r.frames_converted for r in self.recordings)

    @property
    def skipped(self) -> list[dict[str, Any]]:
        """Every skipped range, with its recording's file name."""
        return [{"recording": r.path.name, **s} for r in self.recordings for s in r.skipped]

    def lines(self) -> list[str]:
        """A human summary, one line per recording and a total."""
        out = []
        for r in self.recordings:
            where = f"{r.split}/{r.folder}" if r.split else r.folder
            out.append(f"{r.path.name} -> {where}: {counted(r.frames_converted, 'frame')}")
            out += [f"  skipped {_frames(*s['frames'])}: {s['reason']}" for s in r.skipped]
            out += [f"  note: {n}" for n in r.notes]
        taken = {r.split for r in self.recordings if r.split}
        empty = [s for s in ("train", "validate", "test") if s not in taken]
        if taken and empty:  # a split is by recording: 1 recording went to train alone, and nothing said so
            n = len(self.recordings)
            line = (
                f"note: {' and '.join(empty)} {'holds' if len(empty) == 1 else 'hold'} no recording (a split takes "
                f"whole recordings, and {counted(n, 'recording')} {'was' if n == 1 else 'were'} given)"
            )
            if self.target == "yolo" and "validate" in empty:
                line += "; data.yaml's val is the train images"
            out.append(line)
        out.append(
            f"{counted(self.frames, 'frame')} ({counted(self.agent_frames, 'agent-frame')}), "
            f"{counted(self.files, 'file')}, {self.bytes / 1e6:.1f} MB "
            f"in {self.seconds:.1f} s -> {self.out_dir}"
        )
        return out


def _frames(first: int, last: int) -> str:
    """``"frame 7"`` or ``"frames 3..9"``: "frames 7..7" was read as a range."""
    return f"frame {first}" if first == last else f"frames {first}..{last}"


def load_report(out_dir: str | Path) -> dict[str, Any]:
    """The ``conversion.yaml`` of a converted folder."""
    doc: dict[str, Any] = yaml.safe_load((Path(out_dir) / REPORT_NAME).read_text(encoding="utf-8"))
    return doc
