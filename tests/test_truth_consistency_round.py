"""Every sensor and every label of one frame tell the same truth, in the hard cases, each checked here by an
independent computation (own projections, own lens undistortion, own ray casts against the hull meshes).

One small recording (module-scoped, 3 frames): the port map at dusk (20:45) on the physical W3 sea, one 12 m USV
with a 32-channel LiDAR, a radar, a top view and four 160 × 120 cameras, two of them with Brown–Conrady lens
distortion; a 120 m cargo ship passing within about 30 m, four moored ships (riding the W3 sea at their berths)
and a 5 m speedboat 160 m astern, heaving in and out of the troughs (in frame 2 a trough
hides it wholly from the rear camera).
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from mmusv.classes import SemanticClass
from mmusv.frames import BODY_TO_OPTICAL, pose_matrices
from mmusv.recording.decode import decode_image, decode_point_cloud
from mmusv.recording.info import AgentInfo, CameraInfo, RecordingInfo, read_info
from mmusv.recording.stream import Frame, FrameStream
from mmusv.scene import Scene
from mmusv.wave_occlusion import exposed_hidden
from mmusv.world.vessels import get_asset
from scipy.spatial.transform import Rotation

DISTORTION = {"left": [-0.2, 0.04, 0.0, 0.0, 0.0], "right": [0.1, 0.01, 0.002, -0.003, 0.0]}


def _rig() -> dict[str, Any]:
    cams = []
    for name in ("front", "left", "right", "rear"):
        c: dict[str, Any] = {
            "name": name,
            "resolution": [160, 120],
            "hfov_deg": 90,
            "mount": {"point": f"camera_{name}"},
        }
        if name in DISTORTION:
            c["distortion"] = DISTORTION[name]
        cams.append(c)
    return {
        "lidar": {"channels": 32, "points_per_second": 57600, "rotation_hz": 5, "range_noise_std_m": 0.0},
        "cameras": cams,
        "radar": {"azimuth_bins": 256, "rays_el": 4, "rays_az": 1, "ppi_size_px": 64, "range_m": 1000},
        "top_view": {"resolution": [64, 64], "metres_per_pixel": 2.0},
    }


SCENARIO: dict[str, Any] = {
    "name": "truth_round",
    "seed": 21,
    "map": {"type": "port", "seed": 3},
    "environment": {"time_of_day": "20:45", "weather": "clear", "wave": "W3"},
    "acquisition": {"frequency_hz": 5, "frames": 3},
    "rigs": {"r": _rig()},
    "vessels": [
        {"id": "ego", "role": "usv", "asset": "usv_patrol_12m", "rig": "r", "speed_mps": 2.0,
         "route": [[330, 130], [330, 160]]},
        {"id": "cargo", "role": "target", "asset": "general_cargo_120m", "speed_mps": 3.0,
         "route": [[250, 95], [300, 95]]},
        {"id": "boat", "role": "target", "asset": "speedboat_5m", "speed_mps": 4.0,
         "route": [[345, -30], [300, -30]]},
    ],
}  # fmt: skip


class Rec:
    """The recording, read once: its info, the one agent and the decoded frames."""

    def __init__(self, path: Path) -> None:
        self.info: RecordingInfo = read_info(path)
        self.agent: AgentInfo = self.info.agents[0]
        self.frames: list[Frame] = list(FrameStream(self.info, lambda _t: True))


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Rec:
    import warnings

    from mmusv.acquire import run

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the cargo's route passes near the quay (a route-check warning)
        res = run(SCENARIO, out_dir=tmp_path_factory.mktemp("truth"))
    r = Rec(Path(res.recording))
    assert len(r.frames) == 3
    return r


# --- independent geometry ------------------------------------------------------------------------------------------

SIGNS = np.array([[(i & 1) * 2 - 1, ((i >> 1) & 1) * 2 - 1, ((i >> 2) & 1) * 2 - 1] for i in range(8)], float)


def _box_matrix(w: Any, i: int) -> np.ndarray:
    """Box → world of vessel row ``i``: the world-state pose's rotation (roll, pitch, yaw) at the box centre."""
    m: np.ndarray = np.array(pose_matrices(w.poses[i]), dtype=np.float64)
    m[:3, 3] = w.box_centers[i]
    return m


def _excess(points_world: np.ndarray, box: np.ndarray, size: np.ndarray) -> np.ndarray:
    """Per point, how far (m) it lies outside the oriented box along the worst axis (negative: inside)."""
    inv = np.linalg.inv(box)
    p = points_world @ inv[:3, :3].T + inv[:3, 3]
    out: np.ndarray = np.max(np.abs(p) - np.asarray(size) / 2.0, axis=1)
    return out


def _undistort(cam: CameraInfo, uv: np.ndarray) -> np.ndarray:
    """Normalised undistorted ``(x, y)`` of pixel positions ``uv`` (OpenCV's fixed-point inversion of Brown–Conrady,
    run to convergence)."""
    fx, fy, cx, cy = cam.intrinsics
    xd, yd = (uv[:, 0] - cx) / fx, (uv[:, 1] - cy) / fy
    if cam.distortion is None:
        return np.column_stack([xd, yd])
    k1, k2, p1, p2, k3 = cam.distortion
    x, y = xd.copy(), yd.copy()
    for _ in range(200):
        r2 = x * x + y * y
        radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2**3
        dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        x, y = (xd - dx) / radial, (yd - dy) / radial
    return np.column_stack([x, y])


def _pixel_rays(cam: CameraInfo, pose: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """World directions (unit) of the rays through pixel positions ``uv`` of ``cam`` at ``pose`` (camera body →
    world); their z-component along the optical axis is 1 before normalising."""
    xn = _undistort(cam, uv)
    opt = np.column_stack([xn, np.ones(len(xn))])
    d = (opt @ BODY_TO_OPTICAL) @ pose[:3, :3].T
    out: np.ndarray = d / np.linalg.norm(d, axis=1, keepdims=True)
    return out


def _ray_mesh(o: np.ndarray, d: np.ndarray, v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Nearest hit distance of rays ``o + t d`` (``d`` ``(R, 3)`` unit) on a triangle mesh (Möller–Trumbore), inf
    where a ray misses."""
    v0, e1, e2 = v[f[:, 0]], v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]
    best = np.full(len(d), np.inf)
    s = o - v0
    q = np.cross(s, e1)
    for k in range(len(d)):
        p = np.cross(d[k], e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        u = np.einsum("ij,ij->i", s, p) * inv
        vv = (q @ d[k]) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        good = ok & (u >= 0) & (vv >= 0) & (u + vv <= 1) & (t > 1e-6)
        if good.any():
            best[k] = t[good].min()
    return best


def _qm(t: Any, q: Any) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat(q).as_matrix()
    m[:3, 3] = t
    return m


def _images(f: Frame, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    g = f.messages
    inst = decode_image(g[f"/ego/camera/{name}/instance"]).astype(np.int64)
    sem = decode_image(g[f"/ego/camera/{name}/semantic"]).astype(np.int64)
    dep = decode_image(g[f"/ego/camera/{name}/depth"]).astype(np.float64)
    return inst, sem, dep


def _water_instance(rec: Rec) -> int:
    ids = set()
    for f in rec.frames:
        lid = decode_point_cloud(f.messages["/ego/lidar"])
        ids |= set(np.unique(lid["instance"][lid["class"] == SemanticClass.WATER]).tolist())
    assert len(ids) == 1, ids
    return int(ids.pop())


# --- the checks ----------------------------------------------------------------------------------------------------


def test_the_scene_is_the_hard_case(rec: Rec) -> None:
    """The recording is what the checks below rely on: the ego hull rolls and pitches by degrees, a 120 m ship
    within 40 m, a moored ship, a 5 m craft 100–200 m off, lens distortion."""
    w = rec.frames[0].world
    assert w is not None
    ego = w.ids.index("ego")
    assert max(abs(np.degrees(fr.world.poses[ego][3:5])).max() for fr in rec.frames if fr.world) > 2.0
    body = pose_matrices(w.poses[ego])
    cargo = w.ids.index("cargo")
    corners = SIGNS * w.box_sizes[cargo] / 2 @ _box_matrix(w, cargo)[:3, :3].T + w.box_centers[cargo]
    assert np.hypot(*(corners[:, :2] - body[:2, 3]).T).min() < 40.0 and w.box_sizes[cargo][0] >= 100
    assert "moored" in w.roles
    boat = w.ids.index("boat")
    assert 100 < np.hypot(*(w.poses[boat][:2] - w.poses[ego][:2])) < 200
    assert {n for n, c in rec.agent.cameras.items() if c.distortion is not None} == set(DISTORTION)


def test_every_stamp_and_every_box_is_of_the_frame_s_instant(rec: Rec) -> None:
    """Every message of frame k carries k / f (log time and stamps); /tf gives the world state's poses and the
    mounts; each 3D box is the world state's box (its pose with roll and pitch) in the LiDAR frame of that
    instant."""
    for f in rec.frames:
        w = f.world
        assert w is not None
        t_ns = round(f.index / rec.info.frequency_hz * 1e9)
        assert f.log_time_ns == t_ns and round(w.time_s * 1e9) == t_ns
        for topic, m in f.messages.items():
            ts = getattr(m, "timestamp", None)
            if ts is not None and hasattr(ts, "seconds"):
                assert ts.seconds * 10**9 + ts.nanos == t_ns, topic
        tf = {}
        for tr in f.messages["/tf"].transforms:
            assert tr.timestamp.seconds * 10**9 + tr.timestamp.nanos == t_ns
            r, t = tr.rotation, tr.translation
            tf[(tr.parent_frame_id, tr.child_frame_id)] = _qm([t.x, t.y, t.z], [r.x, r.y, r.z, r.w])
        for i, vid in enumerate(w.ids):
            np.testing.assert_allclose(tf[("world", vid)], pose_matrices(w.poses[i]), atol=1e-9)
        assert rec.agent.lidar_mount is not None
        np.testing.assert_allclose(tf[("ego", "ego/lidar")], rec.agent.lidar_mount, atol=1e-12)
        ann = f.messages["/ego/annotations"]
        assert ann.time_s == w.time_s
        _, lidar, _ = rec.agent.sensor_poses(w)
        assert lidar is not None
        for b in ann.boxes_lidar:
            i = list(w.instance_ids).index(b.instance_id)
            np.testing.assert_allclose(lidar @ _qm(list(b.center), list(b.rotation)), _box_matrix(w, i), atol=1e-9)
            np.testing.assert_allclose(list(b.size), w.box_sizes[i], atol=1e-12)


def test_lidar_points_lie_in_their_tilted_boxes(rec: Rec) -> None:
    """Each LiDAR point of instance k lies inside vessel k's 3D box as recorded (roll and pitch included) within
    1 cm (measured: 0.0 m, float32 rounding); the box's ``lidar_points`` is their count and their class is the
    box's; no vessel-class point lacks an instance."""
    checked = 0
    for f in rec.frames:
        w = f.world
        assert w is not None
        _, lidar, _ = rec.agent.sensor_poses(w)
        assert lidar is not None
        lid = decode_point_cloud(f.messages["/ego/lidar"])
        p = np.column_stack([lid["x"], lid["y"], lid["z"]]).astype(np.float64)
        pw = p @ lidar[:3, :3].T + lidar[:3, 3]
        vessel = np.isin(lid["class"], [SemanticClass.VESSEL, SemanticClass.USV])
        assert not (vessel & (lid["instance"] < 0)).any()
        for b in f.messages["/ego/annotations"].boxes_lidar:
            sel = lid["instance"] == b.instance_id
            assert b.lidar_points == int(sel.sum())
            if sel.any():
                box = lidar @ _qm(list(b.center), list(b.rotation))
                assert _excess(pw[sel], box, np.array(list(b.size))).max() < 0.01, b.target_id
                assert set(lid["class"][sel].tolist()) == {b.semantic_class}
                checked += int(sel.sum())
    assert checked > 1000


def test_camera_pixels_agree_with_the_boxes_through_the_lens(rec: Rec) -> None:
    """Per camera, with and without lens distortion: each vessel's instance pixels have their centres inside its 2D
    box, ``visible_pixels`` is their count over the whole image, their semantic class is the vessel's, sky is
    exactly where the depth is infinite, and each pixel's depth, taken back through the lens (own undistortion)
    to a world point, lies inside the vessel's 3D box within 5 cm (measured: 0.0 m)."""
    n_px = {True: 0, False: 0}
    for f in rec.frames:
        w = f.world
        assert w is not None
        _, _, poses = rec.agent.sensor_poses(w)
        for name, cam in rec.agent.cameras.items():
            inst, sem, dep = _images(f, name)
            assert np.array_equal(np.isinf(dep), inst == 65535)
            boxes = {b.target_id: b for b in f.messages["/ego/annotations"].boxes_camera if b.camera == name}
            for i, vid in enumerate(w.ids):
                if vid == rec.agent.id:
                    continue
                vv, uu = np.nonzero(inst == w.instance_ids[i])
                if not len(vv):
                    continue
                b = boxes[vid]
                assert b.visible_pixels == len(vv)
                assert uu.min() + 0.5 >= b.x_min and uu.max() + 0.5 <= b.x_max, (name, vid)
                assert vv.min() + 0.5 >= b.y_min and vv.max() + 0.5 <= b.y_max, (name, vid)
                assert set(sem[vv, uu].tolist()) == {int(w.classes[i])}
                xn = _undistort(cam, np.column_stack([uu + 0.5, vv + 0.5]))
                z = dep[vv, uu]
                opt = np.column_stack([xn[:, 0] * z, xn[:, 1] * z, z])
                pw = (opt @ BODY_TO_OPTICAL) @ poses[name][:3, :3].T + poses[name][:3, 3]
                assert _excess(pw, _box_matrix(w, i), w.box_sizes[i]).max() < 0.05, (name, vid)
                n_px[cam.distortion is not None] += len(vv)
    assert n_px[True] > 500 and n_px[False] > 500


def test_2d_boxes_bound_the_pixels_whose_rays_meet_the_3d_box(rec: Rec) -> None:
    """A 2D box is the projected 3D box's part in the image: it holds every pixel centre whose ray (own lens
    model) meets the 3D box, and reaches at most 2 px beyond them (a box's image is a hexagon, not its
    bounding box; measured ≤ 1.8 px). A box cut by the border was the projected box's bounding box clipped to the
    image (the cargo's in the rear camera reached 16.5 px below its image, 5–12 px through the distorted lenses);
    it is the bounding box of the image's part inside the border now."""
    checked, cut = 0, 0
    for f in rec.frames:
        w = f.world
        assert w is not None
        _, _, poses = rec.agent.sensor_poses(w)
        for name, cam in rec.agent.cameras.items():
            vv, uu = np.mgrid[0 : cam.height, 0 : cam.width]
            uv = np.column_stack([uu.ravel() + 0.5, vv.ravel() + 0.5])
            d = _pixel_rays(cam, poses[name], uv)
            for b in f.messages["/ego/annotations"].boxes_camera:
                if b.camera != name:
                    continue
                i = w.ids.index(b.target_id)
                inv = np.linalg.inv(_box_matrix(w, i))
                o = inv[:3, :3] @ poses[name][:3, 3] + inv[:3, 3]
                dd = d @ inv[:3, :3].T
                h = w.box_sizes[i] / 2
                with np.errstate(divide="ignore", invalid="ignore"):
                    t1, t2 = (-h - o) / dd, (h - o) / dd
                near = np.nanmax(np.minimum(t1, t2), axis=1)
                far = np.nanmin(np.maximum(t1, t2), axis=1)
                hit = far >= np.maximum(near, 0.0)
                assert hit.any(), (name, b.target_id)
                tight = np.array([uv[hit, 0].min(), uv[hit, 1].min(), uv[hit, 0].max(), uv[hit, 1].max()])
                rec_box = np.array([b.x_min, b.y_min, b.x_max, b.y_max])
                assert (tight[:2] >= rec_box[:2] - 1e-6).all() and (tight[2:] <= rec_box[2:] + 1e-6).all()
                assert (tight[:2] - rec_box[:2]).max() < 2.0 and (rec_box[2:] - tight[2:]).max() < 2.0, (
                    name,
                    b.target_id,
                    tight,
                    rec_box,
                )
                checked += 1
                cut += b.truncation > 0
    assert checked >= 10 and cut >= 3, (checked, cut)


def test_radar_returns_fall_within_their_box_s_range_and_azimuth(rec: Rec) -> None:
    """Each radar return of instance k lies within vessel k's box's span of range (± half a range bin) and azimuth
    (± half an azimuth bin) seen from the radar, and its x, y, z are its range, azimuth and elevation."""
    radar_cfg = rec.agent.rig["radar"]
    half_bin = np.pi / radar_cfg["azimuth_bins"] + 1e-6
    half_range = radar_cfg["range_resolution_m"] / 2 + 1e-3
    g = np.linspace(-0.5, 0.5, 21)
    grid = np.array(np.meshgrid(g, g, g)).reshape(3, -1).T
    checked = 0
    for f in rec.frames:
        w = f.world
        assert w is not None
        body, _, _ = rec.agent.sensor_poses(w)
        assert rec.agent.radar_mount is not None
        inv = np.linalg.inv(body @ rec.agent.radar_mount)
        r = decode_point_cloud(f.messages["/ego/radar/returns"])
        p = np.column_stack([r["x"], r["y"], r["z"]]).astype(np.float64)
        rng = np.linalg.norm(p, axis=1)
        np.testing.assert_allclose(rng, r["range"], atol=1e-3)
        np.testing.assert_allclose(np.angle(np.exp(1j * (np.arctan2(p[:, 1], p[:, 0]) - r["azimuth"]))), 0, atol=1e-5)
        for i in range(len(w.ids)):
            sel = r["instance"] == w.instance_ids[i]
            if not sel.any():
                continue
            box = _box_matrix(w, i)
            s = (grid * w.box_sizes[i]) @ box[:3, :3].T + box[:3, 3]
            s = s @ inv[:3, :3].T + inv[:3, 3]
            srng, saz = np.linalg.norm(s, axis=1), np.arctan2(s[:, 1], s[:, 0])
            mid = np.angle(np.exp(1j * saz).mean())
            rel = np.angle(np.exp(1j * (saz - mid)))
            rrel = np.angle(np.exp(1j * (r["azimuth"][sel] - mid)))
            assert r["range"][sel].min() >= srng.min() - half_range and r["range"][sel].max() <= srng.max() + half_range
            assert rrel.min() >= rel.min() - half_bin and rrel.max() <= rel.max() + half_bin
            checked += int(sel.sum())
    assert checked > 100


def test_top_view_pixels_lie_on_their_bev_boxes(rec: Rec) -> None:
    """Each top-view pixel of vessel k (its centre taken through the recorded optical frame of the top view and
    ``metres_per_pixel``) lies on vessel k's BEV footprint within 0.25 m (measured 0.02 m: the cargo's roll)."""
    m = rec.agent.rig["top_view"]["metres_per_pixel"]
    checked = 0
    for f in rec.frames:
        w = f.world
        assert w is not None
        tv = None
        for tr in f.messages["/tf"].transforms:
            if tr.child_frame_id == "ego/top_view":
                r, t = tr.rotation, tr.translation
                tv = _qm([t.x, t.y, t.z], [r.x, r.y, r.z, r.w])
        assert tv is not None
        ins = decode_image(f.messages["/ego/top_view/instance"]).astype(np.int64)
        h, wd = ins.shape
        vv, uu = np.mgrid[0:h, 0:wd]
        opt = np.stack([(uu + 0.5 - wd / 2) * m, (vv + 0.5 - h / 2) * m, np.zeros((h, wd))], -1).reshape(-1, 3)
        pw = opt @ tv[:3, :3].T + tv[:3, 3]
        for i in range(len(w.ids)):
            mk = ins.ravel() == w.instance_ids[i]
            if not mk.any():
                continue
            yaw = w.poses[i][5]
            dx, dy = pw[mk, 0] - w.box_centers[i][0], pw[mk, 1] - w.box_centers[i][1]
            lu, lv = np.cos(yaw) * dx + np.sin(yaw) * dy, -np.sin(yaw) * dx + np.cos(yaw) * dy
            ex = np.maximum(np.abs(lu) - w.box_sizes[i][0] / 2, np.abs(lv) - w.box_sizes[i][1] / 2)
            assert ex.max() < 0.25, w.ids[i]
            checked += int(mk.sum())
    assert checked > 300


def _above_part_out_of_image(cam: CameraInfo, pose: np.ndarray, box: np.ndarray, size: np.ndarray) -> bool:
    """Whether the box (``box`` → world, ``size`` metres) has a part above the still level and none of it shows in
    the image: its surface above z = 0 sampled on a fine grid and projected by the lens model here (forward
    Brown–Conrady within the reach the image corners see)."""
    g = np.linspace(-0.5, 0.5, 41)
    a, b = np.meshgrid(g, g)
    a, b = a.ravel(), b.ravel()
    faces = []
    for axis in range(3):
        for side in (-0.5, 0.5):
            p = np.zeros((a.size, 3))
            p[:, axis] = side
            p[:, (axis + 1) % 3], p[:, (axis + 2) % 3] = a, b
            faces.append(p)
    pts = (np.concatenate(faces) * np.asarray(size)) @ box[:3, :3].T + box[:3, 3]
    pts = pts[pts[:, 2] > 0.0]
    if len(pts) == 0:
        return False  # wholly below the still level: a craft in a trough
    inv = np.linalg.inv(pose)
    opt = (pts @ inv[:3, :3].T + inv[:3, 3]) @ BODY_TO_OPTICAL.T
    opt = opt[opt[:, 2] > 1e-3]
    x, y = opt[:, 0] / opt[:, 2], opt[:, 1] / opt[:, 2]
    fx, fy, cx, cy = cam.intrinsics
    corners = np.array([[0.0, 0.0], [cam.width, 0.0], [0.0, cam.height], [cam.width, cam.height]])
    reach = float(np.max(np.hypot(*_undistort(cam, corners).T)))
    keep = np.hypot(x, y) <= reach
    x, y = x[keep], y[keep]
    if cam.distortion is not None:
        k1, k2, p1, p2, k3 = cam.distortion
        r2 = x * x + y * y
        radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2**3
        x, y = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x), y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    u, v = fx * x + cx, fy * y + cy
    return not bool(((u >= 0) & (u <= cam.width) & (v >= 0) & (v <= cam.height)).any())


def test_occlusion_and_wave_share_agree_with_an_own_ray_count(rec: Rec) -> None:
    """For every small 2D box (≤ 150 box pixels: the speedboat, the moored pilot and fishing boats, the moored
    ferry 400 m off), the pixels' rays cast here against the hull mesh alone (Möller–Trumbore) give the
    silhouette; above the still level (all of it when the vessel is met only below it), the share whose pixel
    shows the vessel is 1 − ``occlusion`` and the share whose pixel shows the water is ``wave_occlusion``
    (measured: equal, box by box).

    In frame 2 a trough hides the speedboat wholly from the rear camera (its one silhouette pixel shows water):
    it was labelled ``occlusion`` 1 but ``wave_occlusion`` 0 (the share of an empty silhouette above the still
    level), though nothing but the water hid it."""
    water = _water_instance(rec)
    meshes: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    trough_hidden = 0
    checked = 0
    for f in rec.frames:
        w = f.world
        assert w is not None
        _, _, poses = rec.agent.sensor_poses(w)
        for b in f.messages["/ego/annotations"].boxes_camera:
            if b.box_pixels > 150:
                continue
            i = w.ids.index(b.target_id)
            if w.assets[i] not in meshes:
                a = get_asset(w.assets[i])
                meshes[w.assets[i]] = (np.asarray(a.mesh.vertices, float), np.asarray(a.mesh.faces).reshape(-1, 3))
            v0, faces = meshes[w.assets[i]]
            pm = pose_matrices(w.poses[i])
            cam, pose = rec.agent.cameras[b.camera], poses[b.camera]
            inst, _, _ = _images(f, b.camera)
            u0, y0 = int(np.floor(b.x_min)), int(np.floor(b.y_min))
            u1, y1 = int(np.ceil(b.x_max)), int(np.ceil(b.y_max))
            vv, uu = np.mgrid[y0:y1, u0:u1]
            d = _pixel_rays(cam, pose, np.column_stack([uu.ravel() + 0.5, vv.ravel() + 0.5]))
            t = _ray_mesh(pose[:3, 3], d, v0 @ pm[:3, :3].T + pm[:3, 3], faces)
            sil = np.isfinite(t)
            above = sil & (pose[2, 3] + d[:, 2] * np.where(sil, t, 0.0) > 0.0)
            # met only below the still level: all of the silhouette, unless the image holds nothing of the 3D
            # box's part above that level (a ship's upper part out of the picture)
            box = _box_matrix(w, i)
            if above.any():
                exposed = above
            else:
                exposed = np.zeros_like(sil) if _above_part_out_of_image(cam, pose, box, w.box_sizes[i]) else sil
            first = inst[vv.ravel(), uu.ravel()]
            n = int(exposed.sum())
            if n == 0:
                assert b.wave_occlusion == 0.0, (f.index, b.camera, b.target_id)
                continue
            seen = int((exposed & (first == w.instance_ids[i])).sum())
            hidden = int((exposed & (first == water)).sum())
            tol = (1.0 / n if n >= 10 else 0.0) + 1e-9  # a grazing ray of a larger silhouette may go either way
            assert b.occlusion == pytest.approx(1 - seen / n, abs=tol), (f.index, b.camera, b.target_id)
            assert b.wave_occlusion == pytest.approx(hidden / n, abs=tol), (f.index, b.camera, b.target_id)
            trough_hidden += int(not above.any() and hidden == n)
            checked += 1
    assert checked >= 10 and trough_hidden >= 1


def test_a_craft_met_only_below_the_still_level_is_counted_hidden_by_the_water() -> None:
    """``exposed_hidden`` of rays that meet a target only below z = 0, every one stopped first by the water (a
    crest): the silhouette stands in for the empty exposed one, so the share is 1, not 0 (it was ``(0, 0)``)."""
    s = Scene()
    e = 500.0
    water = s.add_instance(
        s.add_mesh(np.array([[-e, -e, 0], [e, -e, 0], [e, e, 0], [-e, e, 0]], float), np.array([[0, 1, 2], [0, 2, 3]]))
    )
    s.set_sea(water)
    s.set_wave_surface(
        SimpleNamespace(hs_m=3.5, tp_s=9.0, gamma=3.3, direction_rad=0.0, spread_s=20.0),
        scenario_seed=3,
        time_s=12.0,
        foci=np.array([[0.0, 0.0]]),
    )
    n = 6
    origins = np.tile(np.array([0.0, 0.0, 2.0], np.float32), (n, 1))
    # Rays meeting a (notional) hull 150 m off, 0.2–0.7 m below the still level.
    target = np.column_stack([np.full(n, 150.0), np.linspace(-1, 1, n), np.linspace(-0.7, -0.2, n)])
    dirs = (target - origins).astype(np.float32)
    t = np.linalg.norm(dirs, axis=1).astype(np.float32)
    dirs /= t[:, None]
    assert exposed_hidden(s, origins=origins, directions=dirs, vessel_t=t, scene_instance=np.full(n, water)) == (n, n)
    # Rays that meet the water first at another instance (the craft seen): exposed, not hidden.
    assert exposed_hidden(s, origins=origins, directions=dirs, vessel_t=t, scene_instance=np.full(n, 99)) == (n, 0)


@pytest.mark.parametrize("distortion", [None, [0.2, 0.05, 0.0, 0.0, 0.0], [-0.3, 0.1, 0.0, 0.0, 0.0]])
def test_cut_2d_boxes_bound_the_pixels_whose_rays_meet_random_boxes(distortion: list[float] | None) -> None:
    """The review's: through a lens, a face cut at the near plane had its edges sampled evenly in 3D, most samples
    ~10^5 px out, and the chords between them crossed the image inside the curved edge: a box 7 px smaller than the
    pixels whose rays meet the 3D box. Random boxes cut by the border, against the camera's own pixel rays (slab
    test): the box holds them to within the pixel grid's quantisation and, 5 px wide and tall, reaches at most 2 px
    beyond."""
    from mmusv import _core as core
    from mmusv.boxes3d import box_corners
    from mmusv.frames import BODY_TO_OPTICAL
    from mmusv.image_boxes import NEAR_M, camera_lens, in_image_box, project_box

    w, h = 160, 90
    cam = core.Camera(width=w, height=h, rgb=False, hfov=np.radians(100), distortion=distortion)
    pose = np.eye(4)
    lens = camera_lens(cam, pose=pose, world_to_body=pose)
    o0, d0 = cam.pixel_rays(pose, np.arange(w * h, dtype=np.int64))
    o0, d0 = np.asarray(o0, dtype=np.float64), np.asarray(d0, dtype=np.float64)
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(120):
        c = [rng.uniform(-5, 60), rng.uniform(-60, 60), rng.uniform(-8, 2)]
        size = np.array([rng.uniform(5, 200), rng.uniform(3, 30), rng.uniform(2, 20)])
        m = pose_matrices(np.array([*c, 0.0, 0.0, rng.uniform(-np.pi, np.pi)]))
        inv = np.linalg.inv(m)
        if np.all(np.abs(inv[:3, 3]) < size / 2 + 0.1):
            continue  # the camera inside the box
        corners = box_corners(m, size) @ BODY_TO_OPTICAL.T
        b = project_box(corners, intrinsics=cam.intrinsics, lens=lens)
        if b is None or not (b[0] < 0 or b[1] < 0 or b[2] > w or b[3] > h):
            continue
        got = in_image_box(corners, intrinsics=cam.intrinsics, lens=lens, width=w, height=h)
        o, d = o0 @ inv[:3, :3].T + inv[:3, 3], d0 @ inv[:3, :3].T
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = (-size / 2 - o) / d, (size / 2 - o) / d
        near = np.nanmax(np.minimum(t1, t2), axis=1)
        far = np.nanmin(np.maximum(t1, t2), axis=1)
        hit = far >= np.maximum(near, 3 * NEAR_M)
        if not hit.any():
            continue
        assert got is not None
        vv, uu = np.divmod(np.nonzero(hit)[0], w)
        truth = np.array([uu.min(), vv.min(), uu.max() + 1, vv.max() + 1], dtype=np.float64)
        shrink = max(got[0] - truth[0], got[1] - truth[1], truth[2] - got[2], truth[3] - got[3])
        grow = max(truth[0] - got[0], truth[1] - got[1], got[2] - truth[2], got[3] - truth[3])
        # (a sliver between pixel centres may reach further than any centre it meets: the growth of wider boxes)
        wide = min(truth[2] - truth[0], truth[3] - truth[1]) >= 5
        assert shrink < 1.0 and (grow < 2.0 or not wide), (distortion, got, truth)
        checked += 1
    assert checked >= 20, checked
