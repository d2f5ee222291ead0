"""Batch runs: every scenario of a folder on a local process pool or on Ray, restartable and fault-tolerant.

:func:`run_many` (also ``mmusv run DIR [--jobs N | --ray [ADDRESS]]``) plans the runs
(:mod:`~mmusv.batch.plan`: complete recordings with the same config hash are skipped, long ones can be split
into frame-range parts), runs the tasks (:mod:`~mmusv.batch.task`) on an executor (:mod:`~mmusv.batch.executors`,
:mod:`~mmusv.batch.ray_backend`), retries what failed or lost its worker, and keeps ``dataset.json``
(:mod:`~mmusv.batch.index`) up to date. :func:`build_dataset` (``mmusv dataset SPEC -o DIR``) goes from a
generation spec to an indexed OPV2V dataset (:mod:`~mmusv.batch.dataset`).
"""

from mmusv.batch.dataset import DatasetReport, build_dataset
from mmusv.batch.index import dataset_recordings, read_index
from mmusv.batch.runner import BatchReport, ScenarioOutcome, run_many

__all__ = [
    "BatchReport",
    "DatasetReport",
    "ScenarioOutcome",
    "build_dataset",
    "dataset_recordings",
    "read_index",
    "run_many",
]
