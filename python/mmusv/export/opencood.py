"""Ready OpenCOOD hypes files for an OPV2V export: PointPillar with early, late and intermediate fusion
(``opencood/hypes_yaml/point_pillar_{early,late,intermediate}_fusion.yaml`` of OpenCOOD, Xu et al., ICRA 2022,
with the keys its ``load_point_pillar_params`` reads), sized from the exported data instead of for cars.

:class:`HypesStats` collects, while :class:`~mmusv.export.opv2v.Opv2vWriter` writes, every listed vessel's size
and height span in its LiDAR frame and the distance between the cooperating USVs. :func:`hypes` then sets:

- ``cav_lidar_range`` ``[-R, -R, z0, R, R, z1]``: ``R`` the export's target range rounded up so that ``2R /
  voxel`` is a multiple of 8, the total stride of OpenCOOD's ``base_bev_backbone`` (``layer_strides [2, 2, 2]``):
  any other grid fails with a size mismatch (±100 m at 0.8 m: "125 vs 126"); ``z0, z1`` the lowest box bottom
  and highest box top seen, rounded out to whole metres;
- ``voxel_size`` ``[v, v, z1 - z0]`` (one pillar spans the whole height);
- the anchor ``l, w, h`` the median vessel's (OpenCOOD takes one anchor size; car anchors, 3.9 × 1.6 × 1.56 m,
  match no vessel), ``max_num`` above the most targets any agent lists in one frame;
- the paper's optimiser: Adam at 2e-3, batch 4, 30 epochs.

Constants OpenCOOD keeps in its code, not in the hypes (``COM_RANGE``, ``GT_RANGE``, the filters of
``box_utils``), go in the files' header comment with the values this export needs; ``docs/opencood.md`` lists
them all and why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["BACKBONE_STRIDE", "HypesStats", "constants", "hypes"]

BACKBONE_STRIDE = 8
"""Total stride of OpenCOOD's PointPillar ``base_bev_backbone`` (three stages of stride 2): the BEV grid must be
a multiple of it."""


@dataclass
class HypesStats:
    """What :func:`hypes` needs, gathered frame by frame: vessel sizes ``l, w, h`` (m), box bottoms and tops in
    the LiDAR frame (m), the target range, the most targets in one agent-frame and the largest distance between
    two cooperating USVs (m)."""

    range_m: float = 200.0
    sizes: list[tuple[float, float, float]] = field(default_factory=list)
    z_low: float = math.inf
    z_high: float = -math.inf
    max_targets: int = 0
    max_cav_distance_m: float = 0.0
    usv_positions: dict[tuple[str, int], list[np.ndarray]] = field(default_factory=dict)

    def add(self, *, key: tuple[str, int], lidar_world: np.ndarray, boxes_lidar: np.ndarray) -> None:
        """One agent-frame: ``key`` (scenario folder, frame), the LiDAR's world position ``(3,)`` and the listed
        targets as ``(K, 7)`` ``x, y, z, l, w, h, yaw`` in that LiDAR's frame (mmusv axes)."""
        b = np.asarray(boxes_lidar, dtype=np.float64).reshape(-1, 7)
        self.sizes += [tuple(float(v) for v in row[3:6]) for row in b]  # type: ignore[misc]
        if len(b):
            self.z_low = min(self.z_low, float((b[:, 2] - b[:, 5] / 2).min()))
            self.z_high = max(self.z_high, float((b[:, 2] + b[:, 5] / 2).max()))
        self.max_targets = max(self.max_targets, len(b))
        others = self.usv_positions.setdefault(key, [])
        for o in others:
            self.max_cav_distance_m = max(self.max_cav_distance_m, float(np.linalg.norm(o[:2] - lidar_world[:2])))
        others.append(np.asarray(lidar_world, dtype=np.float64))


def _grid_range(range_m: float, voxel_m: float) -> float:
    step = voxel_m * BACKBONE_STRIDE / 2  # half-width step keeping 2R / voxel a multiple of the stride
    return math.ceil(range_m / step - 1e-9) * step


def constants(stats: HypesStats, *, voxel_m: float = 0.4) -> dict[str, Any]:
    """The values OpenCOOD keeps in code that this export needs (``docs/opencood.md``)."""
    r = _grid_range(stats.range_m, voxel_m)
    z0, z1 = _z_span(stats)
    return {
        "COM_RANGE": math.ceil(stats.max_cav_distance_m / 10.0) * 10 + 10,
        "GT_RANGE": [-r, -r, z0, r, r, z1],
        # OpenCOOD compares a box's x and y extents, which a turned hull stretches to its footprint's diagonal: the
        # longest hull's length dropped a 20 m yacht turned by 0.01 rad (20.05 m in x).
        "remove_large_pred_bbx": f"keep boxes up to {_longest_extent(stats)} m in x and y (the longest footprint "
        "diagonal; stock: 6 m)",
        "remove_bbx_abnormal_z": f"keep z in [{z0}, {z1}] m (stock: [-3, 1] m)",
    }


def _longest_extent(stats: HypesStats) -> int:
    """Whole metres a box's x or y extent reaches at most, at any yaw: the largest ``hypot(l, w)``, rounded up."""
    return math.ceil(max((math.hypot(s[0], s[1]) for s in stats.sizes), default=6.0))


def _z_span(stats: HypesStats) -> tuple[float, float]:
    if not math.isfinite(stats.z_low):
        return -3.0, 1.0
    return float(math.floor(stats.z_low - 1.0)), float(math.ceil(stats.z_high + 1.0))


def hypes(stats: HypesStats, *, root_dir: str, validate_dir: str, voxel_m: float = 0.4) -> dict[str, dict[str, Any]]:
    """The three hypes documents by file stem (``point_pillar_early_fusion`` ...; module docstring)."""
    r = _grid_range(stats.range_m, voxel_m)
    z0, z1 = _z_span(stats)
    lidar_range = [-r, -r, z0, r, r, z1]
    sizes = np.array(stats.sizes) if stats.sizes else np.array([[3.9, 1.6, 1.56]])
    med = [round(float(v), 2) for v in np.median(sizes, axis=0)]
    out: dict[str, dict[str, Any]] = {}
    for fusion, dataset, model in (
        ("early", "EarlyFusionDataset", "point_pillar"),
        ("late", "LateFusionDataset", "point_pillar"),
        ("intermediate", "IntermediateFusionDataset", "point_pillar_intermediate"),
    ):
        anchor: dict[str, Any] = {"cav_lidar_range": lidar_range, "l": med[0], "w": med[1], "h": med[2], "r": [0, 90]}
        if fusion == "intermediate":
            anchor["feature_stride"] = 2
        anchor["num"] = 2
        backbone: dict[str, Any] = {
            "layer_nums": [3, 5, 8],
            "layer_strides": [2, 2, 2],
            "num_filters": [64, 128, 256],
            "upsample_strides": [1, 2, 4],
            "num_upsample_filter": [128, 128, 128],
        }
        if fusion == "intermediate":
            backbone["compression"] = 0
        out[f"point_pillar_{fusion}_fusion"] = {
            "name": f"point_pillar_{fusion}_fusion_mmusv",
            "root_dir": root_dir,
            "validate_dir": validate_dir,
            "yaml_parser": "load_point_pillar_params",
            "train_params": {"batch_size": 4, "epoches": 30, "eval_freq": 1, "save_freq": 1},
            "fusion": {"core_method": dataset, "args": []},
            "preprocess": {
                "core_method": "SpVoxelPreprocessor",
                "args": {
                    "voxel_size": [voxel_m, voxel_m, z1 - z0],
                    "max_points_per_voxel": 32,
                    "max_voxel_train": 32000,
                    "max_voxel_test": 70000,
                },
                "cav_lidar_range": lidar_range,
            },
            "data_augment": [
                {"NAME": "random_world_flip", "ALONG_AXIS_LIST": ["x"]},
                {"NAME": "random_world_rotation", "WORLD_ROT_ANGLE": [-0.78539816, 0.78539816]},
                {"NAME": "random_world_scaling", "WORLD_SCALE_RANGE": [0.95, 1.05]},
            ],
            "postprocess": {
                "core_method": "VoxelPostprocessor",
                "anchor_args": anchor,
                "target_args": {"pos_threshold": 0.6, "neg_threshold": 0.45, "score_threshold": 0.2},
                "order": "hwl",
                "max_num": max(100, math.ceil(stats.max_targets * 1.5)),
                "nms_thresh": 0.15,
            },
            "model": {
                "core_method": model,
                "args": {
                    "voxel_size": [voxel_m, voxel_m, z1 - z0],
                    "lidar_range": lidar_range,
                    "anchor_number": 2,
                    "pillar_vfe": {
                        "use_norm": True,
                        "with_distance": False,
                        "use_absolute_xyz": True,
                        "num_filters": [64],
                    },
                    "point_pillar_scatter": {"num_features": 64},
                    "base_bev_backbone": backbone,
                    "anchor_num": 2,
                },
            },
            "loss": {"core_method": "point_pillar_loss", "args": {"cls_weight": 1.0, "reg": 2.0}},
            "optimizer": {"core_method": "Adam", "lr": 0.002, "args": {"eps": 1e-10, "weight_decay": 1e-4}},
            "lr_scheduler": {"core_method": "multistep", "gamma": 0.1, "step_size": [20, 27]},
        }
    return out
