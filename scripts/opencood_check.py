"""An mmusv OPV2V export and the hypes files beside it, read and trained on by OpenCOOD's own code.

OpenCOOD (github.com/DerrickXuNu/OpenCOOD) is imported from ``--opencood``, a checkout whose code constants were
changed as the hypes files' header says (``docs/opencood.md``); nothing of it is copied here. With the export's
``opencood/point_pillar_{early,late,intermediate}_fusion.yaml`` the script checks:

1. the constants: ``COM_RANGE``, ``GT_RANGE`` and the two prediction filters of ``box_utils`` against the header;
   the hypes through OpenCOOD's ``load_yaml`` (grid a multiple of the backbone's stride);
2. the data, each fusion's dataset (``build_dataset``, test mode: no augmentation) on each split: the items, the
   CAVs within ``COM_RANGE``, the object ids, centres, sizes and yaws against the OPV2V yamls (projected with
   ``mmusv.frames``, the export's own convention), the LiDAR points and intensities OpenCOOD loaded against the
   ``.pcd`` files (parsed here), the points after its masks and projection, and the points of each vessel
   (``lidar_points`` of ``_additional.yaml``) inside the box OpenCOOD made of it (with the yaw negated as a
   control);
3. training: a batch of each fusion (train mode, augmentation on) through OpenCOOD's collate, the PointPillar
   models of the hypes (``point_pillar``, ``point_pillar_intermediate``), forward, loss, backward and one
   optimiser step on the CPU;
4. post-processing: the labels OpenCOOD encoded, given back as the network output, decoded by its post-processor
   (filters, NMS, range) and scored by its ``eval_utils``: AP must be 1.0 at IoU 0.3, 0.5 and 0.7.

Run it in a virtual environment with OpenCOOD's dependencies (spconv 2.x, cumm, timm, Cython and OpenCOOD's
built ``opencood/utils/box_overlaps``) and mmusv importable::

    PYTHONPATH=/path/to/mmusv/python python scripts/opencood_check.py --opencood OpenCOOD --export EXPORT

Prints what it checked; exits 1 on any mismatch, 2 when it cannot run.
"""

from __future__ import annotations

import argparse
import copy
import io
import math
import random
import re
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml

FUSIONS = ("early", "late", "intermediate")
IOUS = (0.3, 0.5, 0.7)
CENTRE_TOL_M = 0.01
SIZE_TOL_M = 0.01
YAW_TOL_RAD = 1e-3
STOCK_COM_RANGE = 70
BORDER_M = 0.05
"""Boxes with a corner this close to the range's edge are left out of the id comparison (float rounding)."""
POINT_MARGIN_M = 0.5
"""Margin around a box for the points-in-box check."""
MIN_INSIDE = 0.9
"""Smallest fraction of a vessel's LiDAR points (``lidar_points`` of ``_additional.yaml``, vessels with 20 or more)
that must lie inside the box its yaml entry gives (all of roll, pitch and yaw). OpenCOOD's box is yaw-only in the
sensor frame: a hull rolling or pitching relative to the sensor leaves some of its points outside, which is
measured and printed, not failed."""


class Report:
    """Counts checks; prints mismatches as they come."""

    def __init__(self) -> None:
        self.passed = 0
        self.failed: list[str] = []

    def check(self, ok: bool, what: str, detail: str = "") -> bool:
        if ok:
            self.passed += 1
        else:
            self.failed.append(f"{what}: {detail}")
            print(f"  MISMATCH {what}: {detail}", flush=True)
        return ok


def header_constants(path: Path) -> dict[str, Any]:
    """The constants of the hypes file's header comment (``mmusv.export.opencood.constants``)."""
    text = path.read_text()
    out: dict[str, Any] = {}
    m = re.search(r"^#\s+COM_RANGE:\s*([-\d.]+)", text, re.M)
    out["COM_RANGE"] = float(m.group(1)) if m else None
    m = re.search(r"^#\s+GT_RANGE:\s*(\[[^\]]*\])", text, re.M)
    out["GT_RANGE"] = yaml.safe_load(m.group(1)) if m else None
    m = re.search(r"^#\s+remove_large_pred_bbx: keep boxes up to ([\d.]+) m", text, re.M)
    out["large"] = float(m.group(1)) if m else None
    m = re.search(r"^#\s+remove_bbx_abnormal_z: keep z in \[([-\d.]+), ([-\d.]+)\] m", text, re.M)
    out["z"] = (float(m.group(1)), float(m.group(2))) if m else None
    return out


PATCHES = (
    ("opencood/data_utils/datasets/__init__.py", r"^COM_RANGE = .*$", "COM_RANGE = {COM_RANGE:g}"),
    ("opencood/data_utils/datasets/__init__.py", r"^GT_RANGE = .*$", "GT_RANGE = {GT_RANGE}"),
    (
        "opencood/utils/box_utils.py",
        r"index = torch\.logical_and\(x_len <= [\d.]+, y_len <= [\d.]+\)",
        "index = torch.logical_and(x_len <= {large:g}, y_len <= {large:g})",
    ),
    (
        "opencood/utils/box_utils.py",
        r"index = torch\.logical_and\(bbx_z_min >= [-\d.]+, bbx_z_max <= [-\d.]+\)",
        "index = torch.logical_and(bbx_z_min >= {z0:g}, bbx_z_max <= {z1:g})",
    ),
)
"""``--patch``: the lines of OpenCOOD that hold the constants (commit 31ba160), as regular expressions."""


def patch(opencood: Path, h: dict[str, Any]) -> None:
    """Writes the header's constants into the OpenCOOD checkout (``--patch``)."""
    values = {"COM_RANGE": h["COM_RANGE"], "GT_RANGE": h["GT_RANGE"], "large": h["large"], "z0": h["z"][0]}
    values["z1"] = h["z"][1]
    for rel, pattern, line in PATCHES:
        path = opencood / rel
        text, n = re.subn(pattern, line.format(**values), path.read_text(), count=1, flags=re.M)
        if n != 1:
            raise SystemExit(f"--patch: no line matching {pattern!r} in {path}")
        path.write_text(text)
        print(f"patched {rel}: {line.format(**values)}")


def read_pcd(path: Path) -> tuple[int, np.ndarray, np.ndarray]:
    """``(POINTS of the header, (N, 3) points, (N,) intensity = red byte / 255)`` of an ASCII ``x y z rgb`` PCD."""
    head, _, body = path.read_text(encoding="ascii").partition("DATA ascii\n")
    if "FIELDS x y z rgb" not in head:
        raise ValueError(f"{path}: not an ASCII x y z rgb PCD")
    m = re.search(r"^POINTS (\d+)", head, re.M)
    n = int(m.group(1)) if m else -1
    arr = np.loadtxt(io.StringIO(body), dtype=np.float64, ndmin=2).reshape(-1, 4)
    return n, arr[:, :3], ((arr[:, 3].astype(np.int64) >> 16) & 0xFF) / 255.0


class Export:
    """The export as written (yamls and PCDs), read without OpenCOOD; boxes projected with ``mmusv.frames``."""

    def __init__(self, root: Path) -> None:
        from mmusv.frames import carla_matrix

        self.root = root
        self.carla_matrix = carla_matrix
        self._yaml: dict[Path, Any] = {}
        self._pcd: dict[Path, tuple[int, np.ndarray, np.ndarray]] = {}

    def items(self, split: Path) -> list[tuple[Path, str, list[str]]]:
        """``(scenario folder, timestamp, CAV folders)`` in OpenCOOD's order (sorted; the first CAV is the ego)."""
        out = []
        for scen in sorted(p for p in split.iterdir() if p.is_dir()):
            cavs = sorted(p.name for p in scen.iterdir() if p.is_dir())
            stamps = sorted(p.stem for p in (scen / cavs[0]).glob("*.yaml") if "additional" not in p.name)
            out += [(scen, ts, cavs) for ts in stamps]
        return out

    def yaml(self, path: Path) -> Any:
        if path not in self._yaml:
            self._yaml[path] = yaml.safe_load(path.read_text())
        return self._yaml[path]

    def pcd(self, path: Path) -> tuple[int, np.ndarray, np.ndarray]:
        if path not in self._pcd:
            self._pcd[path] = read_pcd(path)
        return self._pcd[path]

    def to_frame(self, pose: list[float], ref_pose: list[float]) -> np.ndarray:
        """``(4, 4)`` from the frame of CARLA pose ``pose`` to that of ``ref_pose``."""
        return np.linalg.inv(self.carla_matrix(np.array(ref_pose))) @ self.carla_matrix(np.array(pose))

    def box(self, v: dict[str, Any], ref_pose: list[float]) -> dict[str, Any]:
        """A ``vehicles`` entry in the frame of ``ref_pose`` as OpenCOOD's yaw-only box should read it: centre, the
        box axes' lengths seen from above (``l``, ``w``) and upright (``h``), yaw of the box's x axis."""
        centre = np.add(v["location"], v["center"])
        m = self.to_frame([*centre, *v["angle"]], ref_pose)
        r = m[:3, :3]
        ex, ey, ez = v["extent"]
        box = {
            "m": m,
            "extent": np.asarray(v["extent"], dtype=np.float64),
            "centre": m[:3, 3],
            "l": 2 * ex * math.hypot(r[0, 0], r[1, 0]),
            "w": 2 * ey * math.hypot(r[0, 1], r[1, 1]),
            "h": 2 * ez * abs(r[2, 2]),
            "yaw": math.atan2(r[1, 0], r[0, 0]),
        }
        c, s = math.cos(box["yaw"]), math.sin(box["yaw"])
        local = np.array([[a, b] for a in (-1, 1) for b in (-1, 1)]) * [box["l"] / 2, box["w"] / 2]
        xy = local @ np.array([[c, s], [-s, c]]) + box["centre"][:2]
        z = box["centre"][2] + np.array([-1, 1]) * box["h"] / 2
        box["lo"] = np.array([xy[:, 0].min(), xy[:, 1].min(), z[0]])
        box["hi"] = np.array([xy[:, 0].max(), xy[:, 1].max(), z[1]])
        return box


def in_range(box: dict[str, Any], rng: list[float]) -> tuple[bool, bool, bool]:
    """``(all corners inside, a corner within BORDER_M of an edge, inside in x and y but not in z)``."""
    lo, hi = np.array(rng[:3]), np.array(rng[3:])
    gap = np.minimum(box["lo"] - lo, hi - box["hi"])
    return bool((gap >= 0).all()), bool((np.abs(gap) < BORDER_M).any()), bool((gap[:2] >= 0).all() and gap[2] < 0)


def expected_objects(
    ex: Export, scen: Path, ts: str, cavs: list[str], ref_pose: list[float], rng: list[float]
) -> tuple[dict[int, dict[str, Any]], set[int], int]:
    """The objects the listed CAVs' yamls give in ``ref_pose``'s frame inside ``rng`` (first CAV listing one
    wins, as in OpenCOOD), the ids too close to the edge to compare, and how many are left out by z alone."""
    out: dict[int, dict[str, Any]] = {}
    border: set[int] = set()
    z_only = 0
    seen: set[int] = set()
    for cav in cavs:
        for oid, v in (ex.yaml(scen / cav / f"{ts}.yaml").get("vehicles") or {}).items():
            if int(oid) in seen:
                continue
            seen.add(int(oid))
            b = ex.box(v, ref_pose)
            inside, near, z_out = in_range(b, rng)
            z_only += z_out
            if near:
                border.add(int(oid))
            elif inside:
                out[int(oid)] = b
    return out, border, z_only


def compare_boxes(
    rep: Report, what: str, ids: list[int], centres: np.ndarray, want: dict[int, dict[str, Any]], border: set[int]
) -> dict[str, float]:
    """OpenCOOD's ``(x, y, z, h, w, l, yaw)`` boxes (order ``hwl``) against the expected ones."""
    got = {int(i): c for i, c in zip(ids, centres, strict=True)}
    rep.check(
        set(got) - border == set(want) - border,
        f"{what} object ids",
        f"OpenCOOD {sorted(got)} vs yamls {sorted(want)} (near the edge: {sorted(border)})",
    )
    worst = {"centre": 0.0, "size": 0.0, "yaw": 0.0}
    for oid in set(got) & set(want):
        g, w = got[oid], want[oid]
        dc = float(np.abs(g[:3] - w["centre"]).max())
        ds = float(np.abs(g[3:6] - [w["h"], w["w"], w["l"]]).max())
        dy = abs((float(g[6]) - w["yaw"] + math.pi) % (2 * math.pi) - math.pi)
        worst = {"centre": max(worst["centre"], dc), "size": max(worst["size"], ds), "yaw": max(worst["yaw"], dy)}
        rep.check(
            dc <= CENTRE_TOL_M and ds <= SIZE_TOL_M and dy <= YAW_TOL_RAD,
            f"{what} object {oid}",
            f"OpenCOOD {np.round(g, 3).tolist()} (x y z h w l yaw) vs yaml centre {np.round(w['centre'], 3).tolist()}"
            f" l w h {w['l']:.3f} {w['w']:.3f} {w['h']:.3f} yaw {w['yaw']:.4f}",
        )
    return worst


def strictly_inside(p: np.ndarray, rng: list[float]) -> np.ndarray:
    return ((p > np.array(rng[:3])) & (p < np.array(rng[3:]))).all(axis=1)


def near_edge(p: np.ndarray, rng: list[float], tol: float = 1e-3) -> int:
    return int((np.minimum(np.abs(p - np.array(rng[:3])), np.abs(p - np.array(rng[3:]))) < tol).any(axis=1).sum())


def points_in_box(p: np.ndarray, box: np.ndarray, margin: float) -> int:
    """Points inside an OpenCOOD ``hwl`` box (yaw only) grown by ``margin``."""
    d = p[:, :3] - box[:3]
    c, s = math.cos(box[6]), math.sin(box[6])
    lx, ly = d[:, 0] * c + d[:, 1] * s, -d[:, 0] * s + d[:, 1] * c
    m = (
        (np.abs(lx) <= box[5] / 2 + margin)
        & (np.abs(ly) <= box[4] / 2 + margin)
        & (np.abs(d[:, 2]) <= box[3] / 2 + margin)
    )
    return int(m.sum())


def points_in_yaml_box(p: np.ndarray, box: dict[str, Any], margin: float) -> int:
    """Points inside the box of a yaml entry (``Export.box``: all three rotations) grown by ``margin``."""
    local = (p[:, :3] - box["m"][:3, 3]) @ box["m"][:3, :3]
    return int((np.abs(local) <= box["extent"] + margin).all(axis=1).sum())


class Checker:
    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.rep = Report()
        self.export = Export(args.export)
        self.hdir = args.export / "opencood"
        self.numbers: dict[str, Any] = {}
        import opencood.data_utils.datasets as datasets
        from opencood.hypes_yaml.yaml_utils import load_yaml
        from opencood.utils import box_utils, pcd_utils

        self.datasets, self.load_yaml, self.box_utils, self.pcd_utils = datasets, load_yaml, box_utils, pcd_utils
        self.header = header_constants(self.hdir / "point_pillar_early_fusion.yaml")

    def hypes(self, fusion: str, split: str | None = None) -> dict[str, Any]:
        """OpenCOOD's reading of our hypes file (``load_yaml`` → ``load_point_pillar_params``); ``root_dir`` and
        ``validate_dir`` made absolute (relative to the export), both set to ``split`` when given."""
        h = self.load_yaml(str(self.hdir / f"point_pillar_{fusion}_fusion.yaml"))
        for k in ("root_dir", "validate_dir"):
            h[k] = str((self.args.export / (split or h[k])).resolve())
        return h

    # 1. constants and hypes ------------------------------------------------------------------------------------
    def constants(self) -> None:
        import torch

        print("== OpenCOOD's code constants against the hypes header")
        h, rep, ds = self.header, self.rep, self.datasets
        rep.check(None not in (h["COM_RANGE"], h["GT_RANGE"], h["large"], h["z"]), "header", f"parsed {h}")
        rep.check(
            float(ds.COM_RANGE) == h["COM_RANGE"], "COM_RANGE", f"OpenCOOD {ds.COM_RANGE}, header {h['COM_RANGE']}"
        )
        rep.check(
            [float(v) for v in ds.GT_RANGE] == h["GT_RANGE"],
            "GT_RANGE",
            f"OpenCOOD {ds.GT_RANGE}, header {h['GT_RANGE']}",
        )

        def cube(size: float, z0: float, z1: float) -> torch.Tensor:
            c = np.array([[x, y, z] for z in (z0, z1) for x in (0, size) for y in (0, size)], dtype=np.float32)
            return torch.from_numpy(c[None])

        large = h["large"] or 6.0
        kept = bool(self.box_utils.remove_large_pred_bbx(cube(large - 0.01, 0, 1))[0])
        dropped = not bool(self.box_utils.remove_large_pred_bbx(cube(large + 0.5, 0, 1))[0])
        rep.check(kept and dropped, "remove_large_pred_bbx", f"should keep x, y extents up to {large} m and no more")
        z0, z1 = h["z"] or (-3.0, 1.0)
        kept = bool(self.box_utils.remove_bbx_abnormal_z(cube(1, z0 + 0.01, z1 - 0.01))[0])
        dropped = not any(
            bool(self.box_utils.remove_bbx_abnormal_z(cube(1, a, b))[0]) for a, b in ((z0 - 0.5, 0), (0, z1 + 0.5))
        )
        rep.check(kept and dropped, "remove_bbx_abnormal_z", f"should keep z in [{z0}, {z1}] m and no more")
        print(f"  COM_RANGE {ds.COM_RANGE}, GT_RANGE {ds.GT_RANGE}, x/y extent <= {large} m, z in [{z0}, {z1}] m")
        for fusion in FUSIONS:
            hy = self.hypes(fusion)
            g = np.asarray(hy["model"]["args"]["point_pillar_scatter"]["grid_size"])
            a = hy["postprocess"]["anchor_args"]
            rep.check(g[0] % 8 == 0 and g[1] % 8 == 0 and g[2] == 1, f"{fusion} grid", f"grid {g.tolist()}")
            rep.check(
                [float(v) for v in hy["preprocess"]["cav_lidar_range"]] == h["GT_RANGE"],
                f"{fusion} range",
                "cav_lidar_range differs from the header's GT_RANGE",
            )
            print(
                f"  {fusion}: {hy['fusion']['core_method']} + {hy['model']['core_method']}, grid {g.tolist()}, anchors"
                f" W x H {a['W']} x {a['H']}, l w h {a['l']} {a['w']} {a['h']}, max_num {hy['postprocess']['max_num']}"
            )

    # 2. data ---------------------------------------------------------------------------------------------------
    def data(self, fusion: str, split: str) -> None:
        from opencood.data_utils.datasets import build_dataset

        ex, rep, rng = self.export, self.rep, self.header["GT_RANGE"]
        com = float(self.datasets.COM_RANGE)
        ds = build_dataset(self.hypes(fusion, split), visualize=True, train=False)
        items = ex.items(self.args.export / split)
        tag = f"{fusion}/{split}"
        rep.check(len(ds) == len(items), f"{tag} items", f"OpenCOOD {len(ds)}, export {len(items)}")
        n = min(len(items), self.args.items or len(items))
        stock: list[int] = []
        cav_counts, boxes, pts, worst = [], 0, 0, {"centre": 0.0, "size": 0.0, "yaw": 0.0}
        inside = {"points": 0, "yaml": 0, "opencood": 0, "mirror": 0, "vessels": 0, "low": [], "worst": (2.0, "")}
        t0 = time.time()
        for idx in range(n):
            scen, ts, cavs = items[idx]
            poses = {c: ex.yaml(scen / c / f"{ts}.yaml")["lidar_pose"] for c in cavs}
            ego = poses[cavs[0]]
            near = [c for c in cavs if math.hypot(poses[c][0] - ego[0], poses[c][1] - ego[1]) <= com]
            cav_counts.append(len(near))
            stock.append(sum(math.hypot(poses[c][0] - ego[0], poses[c][1] - ego[1]) <= STOCK_COM_RANGE for c in cavs))
            item = ds[idx]
            where = f"{tag} {scen.name}/{ts}"
            if fusion == "early" and split == self.args.splits[0]:
                self.lidar_loaded(ds, idx, scen, ts, cavs, where)
            if fusion in ("early", "intermediate"):
                e = item["ego"]
                ids, centres = e["object_ids"], e["object_bbx_center"][e["object_bbx_mask"] == 1]
                want, border, z_only = expected_objects(ex, scen, ts, near, ego, rng)
                rep.check(z_only == 0, f"{where} z range", f"{z_only} listed vessels outside the hypes' z range")
                w = compare_boxes(rep, where, ids, centres, want, border)
                worst = {k: max(worst[k], w[k]) for k in worst}
                boxes += len(ids)
                if fusion == "intermediate":
                    rep.check(e["cav_num"] == len(near), f"{where} cav_num", f"{e['cav_num']} vs {len(near)} in range")
                want_pts, slack = 0, 0
                for c in near:
                    p = self.pcd_utils.mask_ego_points(ex.pcd(scen / c / f"{ts}.pcd")[1].astype(np.float32))
                    q = p @ (t := ex.to_frame(poses[c], ego))[:3, :3].T + t[:3, 3]
                    want_pts += int(strictly_inside(q, rng).sum())
                    slack += near_edge(q, rng)
                got = len(e["origin_lidar"])
                pts += got
                rep.check(
                    abs(got - want_pts) <= slack, f"{where} fused points", f"OpenCOOD {got}, pcd files {want_pts}"
                )
            else:
                rep.check(
                    set(map(str, item)) == {"ego", *near[1:]},
                    f"{where} CAVs",
                    f"OpenCOOD {sorted(map(str, item))}, within COM_RANGE {near}",
                )
                for key, e in item.items():
                    c = cavs[0] if key == "ego" else str(key)
                    own = poses[c]
                    ids, centres = e["object_ids"], e["object_bbx_center"][e["object_bbx_mask"] == 1]
                    want, border, z_only = expected_objects(ex, scen, ts, [c], own, rng)
                    rep.check(z_only == 0, f"{where} cav {c} z range", f"{z_only} listed vessels outside the z range")
                    w = compare_boxes(rep, f"{where} cav {c}", ids, centres, want, border)
                    worst = {k: max(worst[k], w[k]) for k in worst}
                    boxes += len(ids)
                    t = ex.to_frame(own, ego)
                    rep.check(
                        np.allclose(e["transformation_matrix"], t, atol=1e-4),
                        f"{where} cav {c} transformation",
                        "transformation_matrix differs from the poses'",
                    )
                    p = ex.pcd(scen / c / f"{ts}.pcd")[1].astype(np.float32)
                    p = p[strictly_inside(p, rng)]
                    want_pts = len(self.pcd_utils.mask_ego_points(p))
                    got = len(e["origin_lidar"])
                    pts += got
                    rep.check(got == want_pts, f"{where} cav {c} points", f"OpenCOOD {got}, pcd file {want_pts}")
                    extra = ex.yaml(scen / c / f"{ts}_additional.yaml")["mmusv"]["vehicles"]
                    cloud = e["origin_lidar"]
                    for oid, box in zip(ids, centres, strict=True):
                        k = extra.get(oid, extra.get(str(oid), {})).get("lidar_points", 0)
                        if k < 20 or int(oid) not in want:
                            continue
                        a = min(k, points_in_yaml_box(cloud, want[int(oid)], POINT_MARGIN_M))
                        b = min(k, points_in_box(cloud, box, POINT_MARGIN_M))
                        mirrored = cloud[:, :3] * [1.0, -1.0, 1.0]  # a y-handedness mistake
                        inside["mirror"] += min(k, points_in_yaml_box(mirrored, want[int(oid)], POINT_MARGIN_M))
                        inside["vessels"] += 1
                        inside["points"] += k
                        inside["yaml"] += a
                        inside["opencood"] += b
                        if a < MIN_INSIDE * k:
                            inside["low"].append(f"{ts} cav {c} object {oid}: {a}/{k}")
                        if b / k < inside["worst"][0]:
                            inside["worst"] = (b / k, f"{ts} cav {c} object {oid}: {b}/{k}")
        rep.check(not inside["low"], f"{tag} points in boxes", f"fewer than {MIN_INSIDE:.0%}: {inside['low']}")
        line = (
            f"  {tag}: {n} items ({time.time() - t0:.1f} s), CAVs within COM_RANGE per item {cav_counts}"
            f" (stock {STOCK_COM_RANGE} m: {stock}), {boxes} boxes"
            f" (worst |d centre| {worst['centre']:.1e} m, |d size| {worst['size']:.1e} m, |d yaw| {worst['yaw']:.1e}"
            f" rad), {pts} LiDAR points after OpenCOOD's masks"
        )
        if inside["vessels"]:
            k = inside["points"]
            line += (
                f"; of {k} vessel points ({inside['vessels']} vessel-views), inside the yaml's box"
                f" {inside['yaml'] / k:.1%} (points mirrored in y: {inside['mirror'] / k:.1%}), inside OpenCOOD's"
                f" yaw-only box {inside['opencood'] / k:.1%} (worst {inside['worst'][1]})"
            )
        print(line, flush=True)
        self.numbers[f"data {tag}"] = {"items": n, "cavs": cav_counts, "boxes": boxes, "points": pts}

    def lidar_loaded(self, ds: Any, idx: int, scen: Path, ts: str, cavs: list[str], where: str) -> None:
        """The clouds OpenCOOD's ``retrieve_base_data`` loaded (Open3D) against the PCD files."""
        base = ds.retrieve_base_data(idx)
        for c in cavs:
            n, xyz, inten = self.export.pcd(scen / c / f"{ts}.pcd")
            got = base[c]["lidar_np"]
            ok = len(got) == n == len(xyz)
            if ok and n:
                ok = float(np.abs(got[:, :3] - xyz).max()) <= 1e-3 and float(np.abs(got[:, 3] - inten).max()) <= 2e-3
            self.rep.check(ok, f"{where} cav {c} cloud", f"OpenCOOD {got.shape}, PCD POINTS {n}, rows {len(xyz)}")

    # 3. training -----------------------------------------------------------------------------------------------
    def train_step(self, fusion: str) -> None:
        import torch
        from opencood.data_utils.datasets import build_dataset
        from opencood.tools import train_utils
        from torch.utils.data import DataLoader

        rep, tag = self.rep, f"{fusion} training"
        random.seed(0), np.random.seed(0), torch.manual_seed(0)
        h = self.hypes(fusion)
        ds = build_dataset(h, visualize=False, train=True)
        loader = DataLoader(ds, batch_size=self.args.batch_size, shuffle=False, collate_fn=ds.collate_batch_train)
        t0 = time.time()
        batch = next(iter(loader))["ego"]
        lab = batch["label_dict"]
        a = h["postprocess"]["anchor_args"]
        stride = a.get("feature_stride", 2)
        shape = (len(lab["pos_equal_one"]), a["H"] // stride, a["W"] // stride, a["num"])
        rep.check(tuple(lab["pos_equal_one"].shape) == shape, f"{tag} labels", f"{tuple(lab['pos_equal_one'].shape)}")
        n_gt = batch["object_bbx_mask"].sum(dim=1).tolist()
        n_pos = lab["pos_equal_one"].flatten(1).sum(dim=1).tolist()
        rep.check(
            all(p >= g for p, g in zip(n_pos, n_gt, strict=True)), f"{tag} positives", f"{n_pos} for {n_gt} boxes"
        )
        model = train_utils.create_model(h)
        criterion = train_utils.create_loss(h)
        opt = train_utils.setup_optimizer(h, model)
        model.train()
        t1 = time.time()
        out = model(batch)
        rep.check(
            tuple(out["psm"].shape) == (shape[0], shape[3], shape[1], shape[2]),
            f"{tag} output",
            f"psm {tuple(out['psm'].shape)}",
        )
        loss = criterion(out, lab)
        parts = {k: float(v.detach()) if hasattr(v, "detach") else float(v) for k, v in criterion.loss_dict.items()}
        opt.zero_grad()
        loss.backward()
        grads = [p.grad for p in model.parameters() if p.grad is not None]
        finite = all(bool(torch.isfinite(g).all()) for g in grads)
        opt.step()
        with torch.no_grad():
            after = float(criterion(model(batch), lab))
        rep.check(math.isfinite(float(loss)) and finite and math.isfinite(after), f"{tag} loss", f"{parts}, {after}")
        vox = batch["processed_lidar"]["voxel_features"].shape[0]
        print(
            f"  {fusion}: batch {shape[0]} ({n_gt} boxes, {n_pos} positive anchors, {vox} pillars"
            + (f", CAVs {batch['record_len'].tolist()}" if "record_len" in batch else "")
            + f"), {h['model']['core_method']} {sum(p.numel() for p in model.parameters()) / 1e6:.2f} M parameters;"
            f" loss {float(loss):.4f} (conf {parts.get('conf_loss', float('nan')):.4f},"
            f" reg {parts.get('reg_loss', float('nan')):.4f}), after one Adam step {after:.4f};"
            f" data {t1 - t0:.1f} s, model {time.time() - t1:.1f} s",
            flush=True,
        )
        self.numbers[tag] = {"loss": float(loss), "after": after, **parts}

    # 4. post-processing and AP ---------------------------------------------------------------------------------
    def oracle_ap(self, fusion: str, split: str) -> None:
        import torch
        from opencood.data_utils.datasets import build_dataset
        from opencood.tools import inference_utils
        from opencood.utils import eval_utils

        class Oracle(torch.nn.Module):
            """The labels OpenCOOD encoded, as the network's output."""

            def forward(self, cav: dict[str, Any]) -> dict[str, torch.Tensor]:
                lab = cav["label_dict"]
                psm = (lab["pos_equal_one"].float() * 40.0 - 20.0).permute(0, 3, 1, 2)
                return {"psm": psm, "rm": lab["targets"].float().permute(0, 3, 1, 2)}

        infer: Callable[..., Any] = getattr(inference_utils, f"inference_{fusion}_fusion")
        ds = build_dataset(self.hypes(fusion, split), visualize=False, train=False)
        stat: dict[float, dict[str, Any]] = {i: {"tp": [], "fp": [], "gt": 0, "score": []} for i in IOUS}
        tag = f"{fusion}/{split} AP"
        n = min(len(ds), self.args.ap_items)
        dropped: list[str] = []
        widest = 0.0
        for idx in range(n):
            batch = ds.collate_batch_test([ds[idx]])
            with torch.no_grad():
                pred, score, gt = infer(batch, Oracle(), ds)
            keep = self.box_utils.remove_large_pred_bbx(gt) & self.box_utils.remove_bbx_abnormal_z(gt)
            for corners in gt[~keep]:
                ext = (corners.max(dim=0).values - corners.min(dim=0).values).tolist()
                dropped.append(f"item {idx}: x, y, z extents {np.round(ext, 2).tolist()} m")
            if len(gt):
                widest = max(widest, float((gt.max(dim=1).values - gt.min(dim=1).values)[:, :2].max()))
            for i in IOUS:
                eval_utils.caluclate_tp_fp(pred, score, gt, stat, i)
        rep = self.rep
        rep.check(
            not dropped,
            f"{tag} filters",
            f"OpenCOOD's filters drop ground-truth boxes: {dropped}; the widest x or y extent of a ground-truth box is"
            f" {widest:.2f} m (remove_large_pred_bbx keeps up to {self.header['large']} m)",
        )
        if stat[0.5]["gt"] == 0:
            print(f"  {tag}: no ground truth in {n} items")
            return
        aps = {i: eval_utils.calculate_ap(copy.deepcopy(stat), i, False)[0] for i in IOUS}
        rep.check(all(abs(a - 1.0) < 1e-9 for a in aps.values()), tag, f"{aps}")
        print(
            f"  {fusion}/{split}: {n} items, {stat[0.5]['gt']} ground-truth boxes, {len(stat[0.5]['tp'])} predictions;"
            f" AP@0.3 {aps[0.3]:.3f}, AP@0.5 {aps[0.5]:.3f}, AP@0.7 {aps[0.7]:.3f}",
            flush=True,
        )
        self.numbers[tag] = {"items": n, "gt": stat[0.5]["gt"], **{f"AP@{i}": a for i, a in aps.items()}}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--opencood", type=Path, required=True, help="OpenCOOD checkout (holds the opencood package)")
    ap.add_argument("--export", type=Path, required=True, help="mmusv convert --to opv2v output folder")
    ap.add_argument("--splits", default="train,validate", help="split folders to read (default train,validate)")
    ap.add_argument("--items", type=int, default=0, help="items per dataset to check (default all)")
    ap.add_argument("--ap-items", type=int, default=4, help="items per fusion and split for the AP (default 4)")
    ap.add_argument("--batch-size", type=int, default=2, help="training batch (default 2)")
    ap.add_argument("--threads", type=int, default=2, help="torch CPU threads (default 2)")
    ap.add_argument("--no-train", action="store_true", help="skip the models")
    ap.add_argument("--patch", action="store_true", help="first write the header's constants into --opencood")
    args = ap.parse_args(argv)
    args.splits = [s for s in args.splits.split(",") if (args.export / s).is_dir()]
    if not (args.opencood / "opencood").is_dir() or not (args.export / "opencood").is_dir() or not args.splits:
        print("need --opencood with an opencood/ package and --export with opencood/ and split folders")
        return 2
    if args.patch:
        patch(args.opencood, header_constants(args.export / "opencood" / "point_pillar_early_fusion.yaml"))
    sys.path.insert(0, str(args.opencood.resolve()))
    import matplotlib
    import matplotlib.cm
    import torch

    matplotlib.use("Agg")
    if not hasattr(matplotlib.cm, "get_cmap"):  # OpenCOOD's vis_utils (imported by its post-processor), mpl >= 3.9
        matplotlib.cm.get_cmap = matplotlib.colormaps.get_cmap  # type: ignore[attr-defined]
    torch.set_num_threads(args.threads)
    t0 = time.time()
    chk = Checker(args)
    print(f"OpenCOOD {args.opencood.resolve()}, export {args.export.resolve()}, splits {args.splits}")
    chk.constants()
    print("== data: OpenCOOD's datasets (test mode) against the export")
    for split in args.splits:
        for fusion in FUSIONS:
            chk.data(fusion, split)
    if not args.no_train:
        print(f"== training: one batch of each fusion from {args.splits[0]}, forward, loss, one optimiser step (CPU)")
        for fusion in FUSIONS:
            chk.train_step(fusion)
    print("== post-processing: labels as predictions, OpenCOOD's post_process and eval_utils")
    for split in args.splits:
        for fusion in FUSIONS:
            chk.oracle_ap(fusion, split)
    rep = chk.rep
    print(f"== {rep.passed} checks passed, {len(rep.failed)} mismatches ({time.time() - t0:.0f} s)")
    for f in rep.failed:
        print(f"  {f}")
    return 1 if rep.failed else 0


if __name__ == "__main__":
    sys.exit(main())
