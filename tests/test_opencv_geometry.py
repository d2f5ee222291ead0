"""mmusv's camera geometry and exported calibrations re-checked with OpenCV, the library users project with.

Every expectation here is computed with ``cv2`` (``projectPoints``, ``undistortPoints``, ``Rodrigues``) and numpy
from the documented conventions, never with mmusv's own projection code:

* pinhole intrinsics ``f = W / (2 tan(hfov / 2))``, principal point ``(W / 2, H / 2)`` in mmusv's pixel
  coordinates, where pixel ``(i, j)`` covers ``[i, i + 1) × [j, j + 1)`` (its centre at ``+0.5``); OpenCV puts pixel
  centres at whole numbers, so its camera matrix has ``(W / 2 − 0.5, H / 2 − 0.5)``;
* Brown–Conrady ``[k1, k2, p1, p2, k3]`` in OpenCV's order; optical frame x right, y down, z forward, the camera
  body x forward, y left, z up;
* exports: KITTI ``P2``/``R0_rect``/``Tr_velo_to_cam`` and OPV2V ``intrinsic``/``extrinsic`` in mmusv's pixel
  coordinates (``docs/exports.md``), ROS 2 ``CameraInfo`` in OpenCV's (ROS's ``image_geometry`` and
  ``depth_image_proc`` are OpenCV's convention), COCO/YOLO boxes the projected 3D box corners clipped to the image;
* the top view: ``metres_per_pixel`` per pixel, the USV at the image centre, bow (``heading_up``) or north
  (``north_up``) at the top, not mirrored.
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from kitti_files import read_calib

cv2 = pytest.importorskip("cv2")

REPO = Path(__file__).resolve().parents[1]
W, H, HFOV_DEG = 160, 120, 80.0
BODY_TO_OPTICAL = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
"""Camera body (x forward, y left, z up) → optical (x right, y down, z forward), written out here."""
LENSES: dict[str, list[float] | None] = {
    "front": None,
    "left": [-0.2, 0.04, 0.0, 0.0, 0.0],  # barrel
    "right": [0.15, 0.02, 0.0, 0.0, 0.0],  # pincushion
    "rear": [-0.05, 0.0, 0.01, -0.008, 0.0],  # tangential (decentred) with a little barrel
}
"""``usv_1``'s cameras (rig ``a``); rig ``b`` (``usv_2``, ``usv_3``) swaps: the front camera gets the rear's lens."""
TOP_A = {"resolution": [128, 96], "metres_per_pixel": 2.5, "orientation": "heading_up", "altitude_m": 80.0}
TOP_B = {"resolution": [128, 96], "metres_per_pixel": 3.0, "orientation": "north_up", "altitude_m": 80.0}
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-14)


def _rig(lenses: dict[str, list[float] | None], top: dict[str, Any], front_yaw_deg: float) -> dict[str, Any]:
    cams = []
    for name, dist in lenses.items():
        c: dict[str, Any] = {
            "name": name,
            "resolution": [W, H],
            "hfov_deg": HFOV_DEG,
            "mount": {"point": f"camera_{name}", "rpy_deg": [0.0, 0.0, front_yaw_deg if name == "front" else 0.0]},
            "quality": "draft",
        }
        if dist is not None:
            c["distortion"] = dist
        cams.append(c)
    lidar = {
        "channels": 64,
        "points_per_second": 460_800,
        "rotation_hz": 5,
        "range_noise_std_m": 0.0,
        "water_probability": 0.0,
        "water_probability_per_wave_m": 0.0,
    }
    return {"lidar": lidar, "cameras": cams, "radar": None, "top_view": top}


def scenario() -> dict[str, Any]:
    """``port_entry`` with small cameras of four lenses, a dense noiseless LiDAR, flat water (``motion: paper``:
    a plane, on which inverse depth is affine in the pixel coordinates), 2 frames."""
    d: dict[str, Any] = yaml.safe_load((REPO / "scenarios" / "port_entry.yaml").read_text())
    d["acquisition"]["frames"] = 2
    d["environment"]["motion"] = "paper"
    lens_b = {**LENSES, "front": LENSES["rear"], "rear": None}
    # The front cameras turned to starboard, where the targets of usv_1 and usv_3 are (KITTI labels one camera).
    d["rigs"] = {"a": _rig(LENSES, TOP_A, -40.0), "b": _rig(lens_b, TOP_B, -50.0)}
    for v in d["vessels"]:
        if v["role"] == "usv":
            v["rig"] = "a" if v["id"] == "usv_1" else "b"
    return d


FRAME = 1


# ------------------------------------------------------------------------------------------ helpers (cv2, numpy)


def focal(w: int = W, hfov_deg: float = HFOV_DEG) -> float:
    return w / (2.0 * math.tan(math.radians(hfov_deg) / 2.0))


def camera_matrix(fx: float, fy: float, cx: float, cy: float) -> np.ndarray:
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def opencv_k(intrinsics: Any) -> np.ndarray:
    """mmusv's ``[fx, fy, cx, cy]`` (pixel centres at +0.5) as OpenCV's camera matrix (pixel centres at 0)."""
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    return camera_matrix(fx, fy, cx - 0.5, cy - 0.5)


def undistort(pixels: np.ndarray, k: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``(N, 2)`` normalised undistorted coordinates of OpenCV pixel coordinates, iterated to convergence."""
    src = np.ascontiguousarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    if hasattr(cv2, "undistortPointsIter"):  # OpenCV 4
        out = cv2.undistortPointsIter(src, k, d, None, None, CRITERIA)
    else:  # OpenCV 5: undistortPoints takes the criteria
        out = cv2.undistortPoints(src, k, d, None, None, None, CRITERIA)
    return np.asarray(out, dtype=np.float64).reshape(-1, 2)


def world_to_optical(cam_to_world: np.ndarray) -> np.ndarray:
    """``(4, 4)`` world → optical frame of a camera whose body → world pose is ``cam_to_world``."""
    m = np.eye(4)
    m[:3, :3] = BODY_TO_OPTICAL @ cam_to_world[:3, :3].T
    m[:3, 3] = -m[:3, :3] @ cam_to_world[:3, 3]
    return m


def project(points: np.ndarray, to_optical: np.ndarray, k: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``(N, 2)`` ``cv2.projectPoints`` of ``points`` through the rigid ``to_optical`` ``(4, 4)``."""
    if len(points) == 0:
        return np.zeros((0, 2))
    rvec, _ = cv2.Rodrigues(np.ascontiguousarray(to_optical[:3, :3]))
    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 1, 3)
    uv, _ = cv2.projectPoints(pts, rvec, to_optical[:3, 3].astype(np.float64), k, d)
    return np.asarray(uv, dtype=np.float64).reshape(-1, 2)


def plane_inverse_depth(
    depth: np.ndarray,
    instance: np.ndarray,
    uv: np.ndarray,
    ids: np.ndarray,
    xy: np.ndarray,
    k: np.ndarray,
    d: np.ndarray,
) -> np.ndarray:
    """The image's inverse depth at the points of OpenCV pixel coordinates ``uv`` (normalised undistorted
    coordinates ``xy``), where the 2 × 2 pixels around ``uv`` are of instance ``ids`` and see one plane: on a plane
    the inverse depth is affine in the normalised coordinates, so it is fitted through those four pixels (their
    centres undistorted by ``cv2.undistortPoints`` with ``k``, ``d``) and read at ``xy``; NaN elsewhere."""
    h, w = depth.shape
    u0, v0 = np.floor(uv[:, 0]).astype(np.int64), np.floor(uv[:, 1]).astype(np.int64)
    out = np.full(len(uv), np.nan)
    ok = (u0 >= 0) & (v0 >= 0) & (u0 < w - 1) & (v0 < h - 1)
    idx = np.nonzero(ok)[0]
    if not len(idx):
        return out
    us = np.stack([u0[ok], u0[ok] + 1, u0[ok], u0[ok] + 1], axis=1)
    vs = np.stack([v0[ok], v0[ok], v0[ok] + 1, v0[ok] + 1], axis=1)
    same = np.all(instance[vs, us] == ids[idx, None], axis=1)
    with np.errstate(divide="ignore"):
        q = 1.0 / depth[vs, us].astype(np.float64)
    n = undistort(np.column_stack([us.ravel(), vs.ravel()]).astype(np.float64), k, d).reshape(-1, 4, 2)
    a = np.concatenate([n, np.ones((len(idx), 4, 1))], axis=2)
    fin = same & np.all(np.isfinite(q), axis=1)
    coef = np.full((len(idx), 3), np.nan)
    if fin.any():
        ata = np.einsum("nki,nkj->nij", a[fin], a[fin])
        atq = np.einsum("nki,nk->ni", a[fin], q[fin])
        coef[fin] = np.linalg.solve(ata, atq[..., None])[..., 0]
    resid = np.abs(np.einsum("nki,ni->nk", a, coef) - q).max(axis=1)
    plane = fin & (resid <= 1e-4 * np.abs(q).max(axis=1))
    val = coef[:, 0] * xy[idx, 0] + coef[:, 1] * xy[idx, 1] + coef[:, 2]
    out[idx[plane]] = val[plane]
    return out


def alignment(z: np.ndarray, inv_depth: np.ndarray) -> tuple[int, float]:
    """Points compared and the share whose depth agrees within 1e-5 (relative) with the image's."""
    ok = np.isfinite(inv_depth)
    rel = np.abs(1.0 / inv_depth[ok] - z[ok]) / z[ok]
    return int(ok.sum()), float(np.mean(rel < 1e-5)) if ok.any() else 0.0


def box_corners(to_frame: np.ndarray, size: np.ndarray) -> np.ndarray:
    """``(8, 3)`` corners of a centred box of full ``size`` with pose ``to_frame`` ``(4, 4)``."""
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64)
    local = signs * np.asarray(size, dtype=np.float64) / 2.0
    return np.asarray(local @ to_frame[:3, :3].T + to_frame[:3, 3])


def box_edges(corners: np.ndarray, steps: int = 256) -> np.ndarray:
    """Points along the 12 edges of a box given by :func:`box_corners`."""
    t = np.linspace(0.0, 1.0, steps + 1)[:, None]
    pairs = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
    return np.concatenate([corners[a] + t * (corners[b] - corners[a]) for a, b in pairs])


# ------------------------------------------------------------------------------------------ fixtures


@pytest.fixture(scope="module")
def sim() -> Any:
    from mmusv.simulation import Simulation

    return Simulation(scenario())


@pytest.fixture(scope="module")
def cap(sim: Any) -> Any:
    return sim.capture(FRAME, sensors=["lidar", "cameras", "top_view"])


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mmusv.acquire import run

    return Path(run(scenario(), out_dir=tmp_path_factory.mktemp("ocv_rec")).recording)


def _convert(rec: Path, out: Path, to: str, **kw: Any) -> Path:
    from mmusv.export import convert

    convert(rec, to=to, out_dir=out, splits=None, **kw)
    return out


@pytest.fixture(scope="module")
def exports(rec: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("ocv_exports")
    extras = "depth,instance"
    return {
        "kitti": _convert(rec, root / "kitti", "kitti", extras=extras, include_usvs=True),
        "opv2v": _convert(rec, root / "opv2v", "opv2v", extras=extras, include_usvs=True),
        "ros2": _convert(rec, root / "ros2", "ros2"),
        # The projected box (the recorded one, which ROS 2's Detection2D also writes): these tests check its geometry
        # against cv2; the exports' default, --box visible (the tight box of the mask), was added after them.
        "coco": _convert(rec, root / "coco", "coco", box="projected"),
        "yolo": _convert(rec, root / "yolo", "yolo", box="projected"),
    }


# ------------------------------------------------------------------------------------------ 1. pinhole + lens


def test_intrinsics_are_the_documented_pinhole(sim: Any, rec: Path) -> None:
    """``[fx, fy, cx, cy]`` = ``[f, f, W / 2, H / 2]`` in the native camera and in the recording, with the lens."""
    from mmusv.recording import read_info

    info = read_info(rec)
    for a in sim.agents:
        rec_agent = next(x for x in info.agents if x.id == a.id)
        for name, (cam, cfg, _) in a.cameras.items():
            expect = [focal(), focal(), W / 2.0, H / 2.0]
            np.testing.assert_allclose(cam.intrinsics, expect, rtol=1e-12)
            np.testing.assert_allclose(rec_agent.cameras[name].intrinsics, expect, rtol=1e-12)
            d = rec_agent.cameras[name].distortion
            assert (None if d is None else list(d)) == (None if cfg.distortion is None else list(cfg.distortion))


def test_opencv_pixel_rays_render_the_images(sim: Any, cap: Any) -> None:
    """Every pixel's ray from ``cv2.undistortPoints`` (OpenCV's camera matrix: mmusv's intrinsics less half a
    pixel), cast into the frame's scene, meets what the camera recorded there: the same instance and the same
    depth along the optical axis; and it is the ray the camera itself casts (``pixel_rays``). Barrel, pincushion,
    tangential and no distortion."""
    vv, uu = np.mgrid[0:H, 0:W]
    pix = np.column_stack([uu.ravel(), vv.ravel()]).astype(np.float64)
    checked = 0
    for a in sim.agents:
        got = cap.agents[a.id]
        for name, (cam, cfg, _) in a.cameras.items():
            img, pose = got.cameras[name], got.camera_poses[name]
            k = opencv_k([focal(), focal(), W / 2.0, H / 2.0])
            d = np.array(cfg.distortion or [0.0] * 5, dtype=np.float64)
            xy = undistort(pix, k, d)
            ray_opt = np.column_stack([xy, np.ones(len(xy))])
            ray_world = ray_opt @ BODY_TO_OPTICAL @ pose[:3, :3].T
            hits = sim.ws.scene.cast_rays(np.tile(pose[:3, 3], (len(pix), 1)), ray_world, max_range=cfg.range_m)
            depth = hits.distance.astype(np.float64) / np.linalg.norm(ray_opt, axis=1)  # along the optical axis
            instance = hits.instance_id.copy()
            # A ray going down that meets nothing within the range meets the still water (z = 0) beyond it: the
            # camera labels it the sea at that depth (ray_opt's optical-axis component is 1, so t is the depth).
            beyond = ~np.isfinite(depth) & (ray_world[:, 2] < 0.0) & (pose[2, 3] > 0.0)
            depth[beyond] = pose[2, 3] / -ray_world[beyond, 2]
            instance[beyond] = sim.ws.scene.sea_instance
            ref = img.depth.ravel().astype(np.float64)
            assert np.array_equal(np.isfinite(depth), np.isfinite(ref)), (a.id, name)
            fin = np.isfinite(ref)
            rel = np.abs(depth[fin] - ref[fin]) / ref[fin]
            # (the sea beyond the range at 1e-3: its grazing rays' float32 z component is a 1e-4 share of itself)
            assert rel.max(initial=0.0, where=~beyond[fin]) < 2e-5, (a.id, name, rel.max())
            assert rel.max(initial=0.0, where=beyond[fin]) < 1e-3, (a.id, name, rel.max())
            np.testing.assert_array_equal(instance, img.instance.ravel(), err_msg=f"{a.id} {name}")
            _, dirs = cam.pixel_rays(np.ascontiguousarray(pose), np.arange(W * H, dtype=np.int64))
            dirs = np.asarray(dirs, dtype=np.float64)
            unit = ray_world / np.linalg.norm(ray_world, axis=1, keepdims=True)
            sin = np.linalg.norm(np.cross(unit, dirs / np.linalg.norm(dirs, axis=1, keepdims=True)), axis=1)
            assert np.all(np.sum(unit * dirs, axis=1) > 0) and sin.max() < 1e-6, (a.id, name, sin.max())
            checked += 1
    assert checked == 12


def test_lidar_points_project_onto_their_pixels(sim: Any, cap: Any) -> None:
    """The LiDAR points, ``cv2.projectPoints`` into every camera (world → optical from the camera pose, OpenCV's
    camera matrix, the lens), land where the depth image sees them: on planar patches of the same instance the
    image's inverse depth, interpolated at the projected point, gives the point's depth."""
    compared, share = 0, []
    for a in sim.agents:
        got = cap.agents[a.id]
        pts = got.lidar.xyz.astype(np.float64)
        world = pts @ got.lidar_pose[:3, :3].T + got.lidar_pose[:3, 3]
        for name, (_, cfg, _) in a.cameras.items():
            img, pose = got.cameras[name], got.camera_poses[name]
            to_opt = world_to_optical(pose)
            z = world @ to_opt[2, :3] + to_opt[2, 3]
            front = z > 1.0
            k = opencv_k([focal(), focal(), W / 2.0, H / 2.0])
            d = np.array(cfg.distortion or [0.0] * 5, dtype=np.float64)
            uv = project(world[front], to_opt, k, d)
            p_opt = world[front] @ to_opt[:3, :3].T + to_opt[:3, 3]
            xy = p_opt[:, :2] / p_opt[:, 2:]
            inv = plane_inverse_depth(img.depth, img.instance, uv, got.lidar.instance[front], xy, k, d)
            n, s = alignment(z[front], inv)
            compared += n
            share.append((n, s))
    total = sum(n * s for n, s in share)
    assert compared >= 100, compared
    assert total / compared > 0.75, share


# ------------------------------------------------------------------------------------------ 2. exported calibrations


def truth_uv(sim: Any, agent_id: str, camera: str, lidar_xyz: np.ndarray) -> np.ndarray:
    """OpenCV pixel coordinates (centres at whole numbers) of LiDAR-frame points of ``agent_id`` at :data:`FRAME` in
    its ``camera``: the poses from the simulation, the camera as checked above (OpenCV's camera matrix, the lens)."""
    a = sim.agent(agent_id)
    poses = sim.sensor_poses(a, sim.world_state(FRAME))
    world = lidar_xyz @ poses["lidar"][:3, :3].T + poses["lidar"][:3, 3]
    cfg = a.cameras[camera][1]
    k = opencv_k([focal(), focal(), W / 2.0, H / 2.0])
    return project(world, world_to_optical(poses[f"camera/{camera}"]), k, np.array(cfg.distortion or [0.0] * 5))


def in_view(uv: np.ndarray, z: np.ndarray) -> np.ndarray:
    return (z > 1.0) & (uv[:, 0] > -0.5) & (uv[:, 0] < W - 0.5) & (uv[:, 1] > -0.5) & (uv[:, 1] < H - 0.5)


def test_kitti_calibration_projects_lidar_onto_the_image(sim: Any, exports: dict[str, Path]) -> None:
    """KITTI: ``x = P2 · R0_rect · Tr_velo_to_cam · X`` with ``cv2.projectPoints`` (``K`` = ``P2[:, :3]``, the lens
    from ``mmusv_kitti.yaml``) puts every in-view velodyne point where the camera sees it, in mmusv's pixel
    coordinates (OpenCV's plus half a pixel, ``docs/exports.md``): the camera whose rays
    :func:`test_opencv_pixel_rays_render_the_images` checked."""
    root = exports["kitti"] / "port_entry"
    meta = yaml.safe_load((root / "mmusv_kitti.yaml").read_text())
    ts = f"{FRAME:06d}"
    worst, n = 0.0, 0
    for cav, agent_id in meta["agents"].items():
        c = read_calib(root / str(cav) / "calib" / f"{ts}.txt")
        p2 = c["P2"].reshape(3, 4)
        assert np.allclose(p2[:, 3], 0.0) and np.allclose(c["R0_rect"].reshape(3, 3), np.eye(3))
        to_cam = np.eye(4)
        to_cam[:3, :] = c["Tr_velo_to_cam"].reshape(3, 4)
        d = np.array(meta["front_camera_distortion"][cav], dtype=np.float64)
        assert list(d) == list(sim.agent(agent_id).cameras["front"][1].distortion or [0.0] * 5)
        velo = np.fromfile(root / str(cav) / "velodyne" / f"{ts}.bin", dtype="<f4").reshape(-1, 4)[:, :3]
        xyz = velo.astype(np.float64)
        uv = project(xyz, to_cam, p2[:, :3], d)
        z = xyz @ to_cam[2, :3] + to_cam[2, 3]
        truth = truth_uv(sim, agent_id, "front", xyz)
        keep = in_view(truth, z)
        err = np.abs((uv[keep] - 0.5) - truth[keep])
        worst, n = max(worst, float(err.max(initial=0.0))), n + int(keep.sum())
    assert n >= 200 and worst < 2e-3, (n, worst)


def kitti_corners(label: list[str]) -> np.ndarray:
    """``(8, 3)`` camera-frame corners of a KITTI label (location at the bottom centre, ``rotation_y`` about y)."""
    h, w, length = (float(v) for v in label[8:11])
    x, y, z, ry = (float(v) for v in label[11:15])
    c, s = math.cos(ry), math.sin(ry)
    rot = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    xs = np.array([1, 1, -1, -1, 1, 1, -1, -1]) * length / 2.0
    ys = np.array([0, 0, 0, 0, -1, -1, -1, -1]) * h
    zs = np.array([1, -1, -1, 1, 1, -1, -1, 1]) * w / 2.0
    return np.asarray(np.column_stack([xs, ys, zs]) @ rot.T + [x, y, z])


def test_kitti_label_boxes_are_their_projected_3d_boxes(exports: dict[str, Path]) -> None:
    """A label's 2D box (``x1 y1 x2 y2``) is its 3D box (``h w l x y z rotation_y``, KITTI's conventions) through
    ``P2`` and the front camera's lens with ``cv2.projectPoints``: the bounds of its corners (of its edges through a
    lens) clipped to the image, ``[0, W] × [0, H]`` in mmusv's pixel coordinates."""
    root = exports["kitti"] / "port_entry"
    meta = yaml.safe_load((root / "mmusv_kitti.yaml").read_text())
    checked = 0
    for cav in meta["agents"]:
        d = np.array(meta["front_camera_distortion"][cav], dtype=np.float64)
        for ts in ("000000", "000001"):
            p2 = read_calib(root / str(cav) / "calib" / f"{ts}.txt")["P2"].reshape(3, 4)
            for line in (root / str(cav) / "label_2" / f"{ts}.txt").read_text().splitlines():
                f = line.split()
                if f[0] == "DontCare" or int(f[2]) == 3 or (d.any() and float(f[1]) > 0.0):  # no 3D box; not in
                    # the image; truncated by a lens
                    continue
                corners = kitti_corners(f)
                assert corners[:, 2].min() > 0.05
                uv = project(box_edges(corners) if d.any() else corners, np.eye(4), p2[:, :3], d)
                lo = np.clip(uv.min(axis=0), 0.0, [W, H])
                hi = np.clip(uv.max(axis=0), 0.0, [W, H])
                # The label's numbers have 2 decimals (rotation_y 0.005 rad: 0.1 px at the far end of a 90 m ship).
                np.testing.assert_allclose([float(v) for v in f[4:8]], [*lo, *hi], atol=0.3, err_msg=line)
                checked += 1
    assert checked >= 2, checked


def test_opv2v_calibration_projects_lidar_onto_the_image(sim: Any, exports: dict[str, Path]) -> None:
    """OPV2V: the ``.pcd`` (CARLA frame) through a camera's ``extrinsic`` (LiDAR → camera, CARLA axes x forward,
    y right, z up), CARLA's ``(y, −z, x)`` to the optical frame, and ``cv2.projectPoints`` with ``intrinsic`` and
    ``distortion`` puts every in-view point where that camera sees it (mmusv's pixel coordinates, as CARLA's
    ``K = [[f, 0, W/2], [0, f, H/2], [0, 0, 1]]``)."""
    root = exports["opv2v"] / "port_entry"
    ue_to_optical = np.eye(4)
    ue_to_optical[:3, :3] = [[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]
    cams = {0: "front", 1: "right", 2: "left", 3: "rear"}
    worst, n = 0.0, 0
    agents = {a.index: a.id for a in sim.agents}
    for folder in sorted(p for p in root.iterdir() if p.is_dir()):
        agent_id = agents[int(folder.name) - 1000]
        doc = yaml.safe_load((folder / f"{FRAME:06d}.yaml").read_text())
        text = (folder / f"{FRAME:06d}.pcd").read_text()
        rows = text.partition("DATA ascii\n")[2].split()
        carla = np.array(rows, dtype=np.float64).reshape(-1, 4)[:, :3]
        mmusv_lidar = carla * [1.0, -1.0, 1.0]  # CARLA's y is mmusv's −y
        for idx, name in cams.items():
            cam = doc[f"camera{idx}"]
            k = np.array(cam["intrinsic"], dtype=np.float64)
            d = np.array(cam["distortion"], dtype=np.float64)
            # (CARLA's frames are left-handed: their change to the optical frame is a reflection, which no rvec
            # holds, so the points are moved with numpy, as OpenCOOD does, and cv2 projects from the optical frame.)
            to_opt = ue_to_optical @ np.array(cam["extrinsic"], dtype=np.float64)
            opt = carla @ to_opt[:3, :3].T + to_opt[:3, 3]
            uv = project(opt, np.eye(4), k, d)
            z = opt[:, 2]
            truth = truth_uv(sim, agent_id, name, mmusv_lidar)
            keep = in_view(truth, z)
            err = np.abs((uv[keep] - 0.5) - truth[keep])
            worst, n = max(worst, float(err.max(initial=0.0))), n + int(keep.sum())
    # The .pcd holds 0.1 mm: some thousandths of a pixel at a few metres.
    assert n >= 500 and worst < 0.01, (n, worst)


def _tf(t: Any) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    m = np.eye(4)
    q = t.transform.rotation
    m[:3, :3] = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
    m[:3, 3] = [t.transform.translation.x, t.transform.translation.y, t.transform.translation.z]
    return m


def test_ros2_camera_info_projects_lidar_onto_the_image(sim: Any, exports: dict[str, Path]) -> None:
    """ROS 2: ``CameraInfo`` is OpenCV's (``plumb_bob``, ``D`` the lens, ``P = [K | 0]``, ``R = I``, pixel centres
    at whole numbers as in ``image_geometry`` and ``depth_image_proc``): the LiDAR's ``PointCloud2`` through the
    ``/tf_static`` chain ``lidar → base_link → camera → camera_optical`` and ``cv2.projectPoints`` with ``K``, ``D``
    lands where the camera sees each point; the ``Detection2D`` boxes are in the same pixel coordinates."""
    pytest.importorskip("rosbags")
    from mmusv.export.ros2 import TIME_OFFSET_NS
    from rosbags.highlevel import AnyReader

    stamp = round(FRAME / 5.0 * 1e9) + TIME_OFFSET_NS  # the bag's time: the sim time + the offset (never 0)
    with AnyReader([exports["ros2"] / "port_entry"]) as r:
        msgs: dict[str, Any] = {}
        static: list[Any] = []
        for c, t, raw in r.messages():
            if c.topic == "/tf_static":
                tf: Any = r.deserialize(raw, c.msgtype)
                static += tf.transforms
            elif t == stamp and (c.topic.endswith(("/camera_info", "/lidar", "/detections"))):
                msgs[c.topic] = r.deserialize(raw, c.msgtype)
    edges = {x.child_frame_id: (x.header.frame_id, _tf(x)) for x in static}

    def to_base(frame: str, agent: str) -> np.ndarray:
        m = np.eye(4)
        while frame != f"{agent}/base_link":
            parent, t = edges[frame]
            m, frame = t @ m, parent
        return m

    worst, n, boxes = 0.0, 0, 0
    coco = json.loads((exports["coco"] / "annotations" / "instances_all.json").read_text())
    image = {i["id"]: i for i in coco["images"]}
    for a in sim.agents:
        cloud = msgs[f"/{a.id}/lidar"]
        offs = {f.name: f.offset for f in cloud.fields}
        buf = np.frombuffer(bytes(cloud.data), dtype=np.uint8).reshape(-1, cloud.point_step)
        xyz = np.column_stack(
            [buf[:, offs[k] : offs[k] + 4].copy().view("<f4").ravel() for k in ("x", "y", "z")]
        ).astype(np.float64)
        for name, (_, cfg, _) in a.cameras.items():
            info = msgs[f"/{a.id}/camera/{name}/camera_info"]
            assert info.distortion_model == "plumb_bob" and (info.width, info.height) == (W, H)
            k = np.asarray(info.k, dtype=np.float64).reshape(3, 3)
            np.testing.assert_allclose(np.asarray(info.p).reshape(3, 4), np.column_stack([k, np.zeros(3)]))
            np.testing.assert_allclose(np.asarray(info.r).reshape(3, 3), np.eye(3))
            d = np.asarray(info.d, dtype=np.float64)
            np.testing.assert_allclose(d, cfg.distortion or [0.0] * 5)
            lidar_to_opt = np.linalg.inv(to_base(f"{a.id}/camera_{name}_optical", a.id)) @ to_base(
                f"{a.id}/lidar", a.id
            )
            uv = project(xyz, lidar_to_opt, k, d)
            z = xyz @ lidar_to_opt[2, :3] + lidar_to_opt[2, 3]
            truth = truth_uv(sim, a.id, name, xyz)
            keep = in_view(truth, z)
            err = np.abs(uv[keep] - truth[keep])
            assert err.max(initial=0.0) < 1e-3, (a.id, name, err.max(initial=0.0))
            worst, n = max(worst, float(err.max(initial=0.0))), n + int(keep.sum())
            # Detection2D: the recorded box (COCO's, mmusv's pixel coordinates) less half a pixel, the same size.
            dets = {x.id: x.bbox for x in msgs[f"/{a.id}/camera/{name}/detections"].detections}
            for ann in coco["annotations"]:
                img = image[ann["image_id"]]
                if (img["agent"], img["camera"], img["frame"]) != (a.id, name, FRAME):
                    continue
                x, y, bw, bh = ann["bbox"]
                b = dets[ann["mmusv_id"]]
                got = [b.center.position.x, b.center.position.y, b.size_x, b.size_y]
                np.testing.assert_allclose(got, [x + bw / 2 - 0.5, y + bh / 2 - 0.5, bw, bh], atol=2e-3)
                boxes += 1
    assert n >= 500 and worst < 1e-3 and boxes >= 3, (n, worst, boxes)


def test_coco_and_yolo_boxes_are_the_projected_3d_boxes(sim: Any, exports: dict[str, Path]) -> None:
    """COCO's ``bbox`` (``annotate``: the projected 3D-box corners, through a lens its projected edges, clipped to
    the image, mmusv's pixel coordinates) is the vessel's world box through ``cv2.projectPoints`` with the
    recorded intrinsics (centres at +0.5: no shift) and lens; every mask pixel's centre lies in it (the hull is
    inside its box); the YOLO line is the same box normalised."""
    from pycocotools import mask as mask_util

    state = sim.world_state(FRAME)
    rows = {v.id: i for i, v in enumerate(sim.vessels)}
    coco = json.loads((exports["coco"] / "annotations" / "instances_all.json").read_text())
    image = {i["id"]: i for i in coco["images"]}
    k = camera_matrix(focal(), focal(), W / 2.0, H / 2.0)
    checked = 0
    for ann in coco["annotations"]:
        img = image[ann["image_id"]]
        if img["frame"] != FRAME:
            continue
        a = sim.agent(img["agent"])
        cfg = a.cameras[img["camera"]][1]
        pose = sim.sensor_poses(a, state)[f"camera/{img['camera']}"]
        i = rows[ann["mmusv_id"]]
        box = state.matrices[i].copy()
        box[:3, 3] = state.box_centers[i]
        corners = box_corners(box, sim.vessels[i].box_size)
        to_opt = world_to_optical(pose)
        if (corners @ to_opt[2, :3] + to_opt[2, 3]).min() <= 0.05:
            continue  # cut by the near plane
        d = np.array(cfg.distortion or [0.0] * 5)
        if cfg.distortion is not None and ann["truncation"] > 0.0:
            continue  # beyond the image a lens's polynomial is not the camera's (annotate carries it outwards)
        uv = project(box_edges(corners) if cfg.distortion is not None else corners, to_opt, k, d)
        lo, hi = np.clip(uv.min(axis=0), 0.0, [W, H]), np.clip(uv.max(axis=0), 0.0, [W, H])
        x, y, bw, bh = ann["bbox"]
        np.testing.assert_allclose([x, y, x + bw, y + bh], [*lo, *hi], atol=0.01, err_msg=str(ann["mmusv_id"]))
        with warnings.catch_warnings():  # pycocotools' __array__ predates numpy 2's copy keyword (test_coco.py)
            warnings.filterwarnings("ignore", category=DeprecationWarning, message=".*copy keyword")
            m = mask_util.decode(ann["segmentation"])
        vs, us = np.nonzero(m)
        assert len(us) == ann["area"] > 0
        assert (us + 0.5 >= x - 1e-3).all() and (us + 0.5 <= x + bw + 1e-3).all()
        assert (vs + 0.5 >= y - 1e-3).all() and (vs + 0.5 <= y + bh + 1e-3).all()
        label = exports["yolo"] / "labels" / "all" / Path(img["file_name"]).with_suffix(".txt")
        lines = [[float(v) for v in line.split()[1:]] for line in label.read_text().splitlines()]
        want = [(x + bw / 2) / W, (y + bh / 2) / H, bw / W, bh / H]
        assert any(np.allclose(line, want, atol=2e-5) for line in lines), (label, want)
        checked += 1
    assert checked >= 5, checked


# ------------------------------------------------------------------------------------------ 3. the top view


def test_top_view_scale_and_orientation(sim: Any, cap: Any) -> None:
    """Top view: pixel ``(i, j)``'s centre is ``(i + 0.5 − W/2, H/2 − j − 0.5) · metres_per_pixel`` right of and
    ahead of the USV, ahead = its bow (``heading_up``) or north (``north_up``), right = starboard or east (the
    picture seen from above, not mirrored); depth is the altitude over the water. Every vessel's pixels, put back
    in the world so, fall inside its box's footprint and span it."""
    state = sim.world_state(FRAME)
    checked = 0
    for a in sim.agents:
        tv = a.rig.top_view
        img = cap.agents[a.id].top_view
        h, w = img.instance.shape
        assert (w, h) == tuple(tv.resolution)
        m = tv.metres_per_pixel
        x0, y0, yaw = state.poses[a.index, [0, 1, 5]]
        up = np.array([math.cos(yaw), math.sin(yaw)]) if tv.orientation == "heading_up" else np.array([0.0, 1.0])
        right = np.array([up[1], -up[0]])
        water = img.semantic == 1
        assert water.any()
        np.testing.assert_allclose(img.depth[water], tv.altitude_m, rtol=1e-5)
        for i, v in enumerate(sim.vessels):
            vs, us = np.nonzero(img.instance == v.instance_id)
            if len(us) < 8:
                continue
            xy = np.array([x0, y0]) + np.outer((us + 0.5 - w / 2) * m, right) + np.outer((h / 2 - vs - 0.5) * m, up)
            box = state.matrices[i]
            rel = xy - state.box_centers[i, :2]
            fwd = rel @ box[:2, 0] / np.linalg.norm(box[:2, 0])
            left = rel @ box[:2, 1] / np.linalg.norm(box[:2, 1])
            length, beam = v.box_size[:2]
            assert np.abs(fwd).max() <= length / 2 + 0.75 * m and np.abs(left).max() <= beam / 2 + 0.75 * m, v.id
            on_edge = (us == 0) | (vs == 0) | (us == w - 1) | (vs == h - 1)
            if not on_edge.any():
                assert fwd.max() - fwd.min() >= length - 2.5 * m and left.max() - left.min() >= beam - 2.5 * m, v.id
            checked += 1
    assert checked >= 3, checked
