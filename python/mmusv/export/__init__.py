"""Converting recordings into public dataset layouts (``mmusv convert REC.mcap --to FORMAT -o DIR``): OPV2V, KITTI-style
per-agent folders, ROS 2 bags, COCO, YOLO, MaSTr1325-style masks, SemanticKITTI, MOTChallenge and KITTI tracking
(``docs/exports.md``).

Modules, one job each: :mod:`~mmusv.recording.stream` (recording → frames), the job of :func:`~mmusv.export.convert` in
:mod:`~mmusv.export.conversion` (the one job every format shares: reading, validation, splitting, frame selection,
progress and its report; with :mod:`~mmusv.export.convert_checks`, :mod:`~mmusv.export.convert_output` and
:mod:`~mmusv.export.convert_report`), :mod:`~mmusv.export.writer` (the writer base and its hooks),
:mod:`~mmusv.export.geometry` (sensor poses and targets per agent, mmusv frames), :mod:`~mmusv.export.splits`
(train/validate/test by sequence), :mod:`~mmusv.export.camera` (what the image datasets share: samples, 2D boxes, box
filter), the layouts (:mod:`~mmusv.export.opv2v`, :mod:`~mmusv.export.kitti`, :mod:`~mmusv.export.ros2` with
:mod:`~mmusv.export.ros2_names`, :mod:`~mmusv.export.ros2_msgs` and :mod:`~mmusv.export.ros2_types`,
:mod:`~mmusv.export.coco`, :mod:`~mmusv.export.yolo`, :mod:`~mmusv.export.mastr`, :mod:`~mmusv.export.semantickitti`,
:mod:`~mmusv.export.mot`, :mod:`~mmusv.export.kitti_tracking`; frame changes only through :mod:`mmusv.frames`),
:mod:`~mmusv.export.pcd` (Open3D-style ASCII PCD) and :mod:`~mmusv.export.cli` (the command).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mmusv._lazy import attributes

if TYPE_CHECKING:
    from mmusv.export.common import DEFAULT_EXTRAS, EXTRAS, TARGETS
    from mmusv.export.conversion import ConvertReport, RecordingReport, convert

__all__ = ["DEFAULT_EXTRAS", "EXTRAS", "TARGETS", "ConvertReport", "RecordingReport", "convert"]

_LAZY = {
    "DEFAULT_EXTRAS": "mmusv.export.common",
    "EXTRAS": "mmusv.export.common",
    "TARGETS": "mmusv.export.common",
    "ConvertReport": "mmusv.export.conversion",
    "RecordingReport": "mmusv.export.conversion",
    "convert": "mmusv.export.conversion",
}
"""The names above, loaded on first use (PEP 562), as are the submodules (``mmusv.export.cli``): ``mmusv convert``'s
parser is built by every ``mmusv`` command, and the conversion job loads the annotation and geometry modules
(scipy), 0.7 s of ``mmusv --help``'s 0.9 s."""

__getattr__ = attributes(__name__, _LAZY, submodules=True)
