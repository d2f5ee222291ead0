"""TrackEval (the peer that scores multi-object tracking) run on an export, quietly: the MOT and KITTI tracking tests
score their ground truth with it the same way, each with its own dataset class and folders."""

from __future__ import annotations

from typing import Any


def trackeval_scores(dataset: str, config: dict[str, Any]) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """``trackeval.datasets.<dataset>`` built from ``config`` (printing off), scored with HOTA, CLEAR and Identity
    on one process: the dataset object, its results per tracker and its message per tracker."""
    import trackeval

    quiet = {"PRINT_CONFIG": False}
    evaluator = trackeval.Evaluator(
        {
            **quiet,
            "USE_PARALLEL": False,
            "PRINT_RESULTS": False,
            "OUTPUT_SUMMARY": False,
            "OUTPUT_DETAILED": False,
            "PLOT_CURVES": False,
            "TIME_PROGRESS": False,
            "DISPLAY_LESS_PROGRESS": True,
        }
    )
    data = getattr(trackeval.datasets, dataset)({**quiet, **config})
    metrics = [trackeval.metrics.HOTA(quiet), trackeval.metrics.CLEAR(quiet), trackeval.metrics.Identity(quiet)]
    res, msg = evaluator.evaluate([data], metrics)
    return data, res[dataset], msg[dataset]
