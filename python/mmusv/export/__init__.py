"""Converting recordings into public dataset layouts: OPV2V (``mmusv convert REC.mcap --to opv2v -o DIR``) and
KITTI-style per-agent folders (``--to kitti``).

Modules, one job each: :mod:`~mmusv.recording.reader` (recording → frames), :mod:`~mmusv.export.geometry` (sensor
poses and targets per agent, mmusv frames), :mod:`~mmusv.export.opv2v` and :mod:`~mmusv.export.kitti` (the
layouts; frame changes only through :mod:`mmusv.frames`), :mod:`~mmusv.export.pcd` (Open3D-style ASCII PCD),
:mod:`~mmusv.export.splits` (train/validate/test by sequence), :mod:`~mmusv.export.convert` (the job and its
report) and :mod:`~mmusv.export.cli` (the command).
"""

from __future__ import annotations

from mmusv.export.common import DEFAULT_EXTRAS, EXTRAS, TARGETS
from mmusv.export.convert import ConvertReport, RecordingReport, convert

__all__ = ["DEFAULT_EXTRAS", "EXTRAS", "TARGETS", "ConvertReport", "RecordingReport", "convert"]
