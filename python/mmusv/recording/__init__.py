"""The recording format, both ways: :mod:`~mmusv.recording.topics` (topic names and frame ids, the one place they
are spelled), :mod:`~mmusv.recording.writer` (:class:`Recording` over the core's MCAP recorder),
:mod:`~mmusv.recording.frames` (:class:`FrameRecorder`: which topic gets what, per captured frame),
:mod:`~mmusv.recording.tables` (the Parquet tables beside the MCAP), :mod:`~mmusv.recording.background` (frames
written on a writer thread while the next is captured); the one reader: :mod:`~mmusv.recording.info` (what a
recording says about itself), :mod:`~mmusv.recording.stream` (its frames, one at a time),
:mod:`~mmusv.recording.messages` (its decoded messages), :mod:`~mmusv.recording.contents` (what it holds, for
``mmusv info``), :mod:`~mmusv.recording.folders` (the recordings in a folder, and those its listings name that
are gone), all over :mod:`~mmusv.recording.scan` (damaged files read to their end), and
:mod:`~mmusv.recording.decode` (its messages as numpy arrays). The contract is ``docs/recording.md``.
"""

from mmusv.recording.contents import summary
from mmusv.recording.decode import decode_image, decode_point_cloud
from mmusv.recording.info import read_info
from mmusv.recording.messages import frame_messages, read_messages
from mmusv.recording.writer import POINT_DTYPES, Recording, to_ns

__all__ = [
    "POINT_DTYPES",
    "Recording",
    "decode_image",
    "decode_point_cloud",
    "frame_messages",
    "read_info",
    "read_messages",
    "summary",
    "to_ns",
]
