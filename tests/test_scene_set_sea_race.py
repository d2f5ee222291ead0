"""``Scene.set_sea`` while another thread moves instances: the sea was built on a copy of the scene with the GIL
released and the copy written back, so a ``set_poses`` made meanwhile was lost (the vessel stood where it was, and
the next frame's rays met it there). Now the grid is built on a snapshot and installed under the lock: the moves
are kept, and a grid whose fixed geometry moved meanwhile is built again."""

from __future__ import annotations

import threading
import time

import numpy as np
import numpy.typing as npt
from mmusv.scene import Scene

F64 = npt.NDArray[np.float64]


def _grid(n: int, *, centre_x: float, size: float = 800.0, z: float = 2.0) -> tuple[F64, npt.NDArray[np.int64]]:
    """An ``n`` × ``n`` quad grid (2n² triangles), ``size`` metres square at height ``z``, centred on x."""
    xs = np.linspace(-size / 2, size / 2, n + 1)
    x, y = np.meshgrid(xs + centre_x, xs)
    v = np.stack([x.ravel(), y.ravel(), np.full(x.size, z)], 1)
    r, c = np.divmod(np.arange(n * n), n)
    a = r * (n + 1) + c
    f = np.concatenate([np.stack([a, a + 1, a + n + 2], 1), np.stack([a, a + n + 2, a + n + 1], 1)])
    return v, f


def _scene(n: int) -> tuple[Scene, int, int, int]:
    """A sea plane, a fixed grid of 2n² triangles west of the origin and a 10 m box vessel at the origin."""
    s = Scene()
    h = 5000.0
    plane = s.add_mesh(np.array([[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]]), np.array([[0, 1, 2], [0, 2, 3]]))
    surface = s.add_instance(plane)
    grid = s.add_instance(s.add_mesh(*_grid(n, centre_x=-1500.0)))
    box = np.array([[x, y, z] for x in (-5, 5) for y in (-5, 5) for z in (-1, 4)], dtype=float)
    faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6]]
    faces += [[0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    vessel = s.add_instance(s.add_mesh(box, np.array(faces)))
    return s, surface, grid, vessel


def _at(x: float, y: float = 0.0) -> F64:
    m = np.eye(4)
    m[:3, 3] = (x, y, 0.0)
    return m


def test_poses_set_while_the_sea_is_built_are_kept_and_met_by_rays() -> None:
    n = 300
    while True:  # a grid whose build lasts at least 0.25 s here (at most 2·1600² triangles)
        s, surface, grid, vessel = _scene(n)
        t0 = time.perf_counter()
        s.set_sea(surface, moving=[vessel])
        if time.perf_counter() - t0 >= 0.25 or n >= 1600:
            break
        n = min(1600, int(n * 1.6))
    s.clear_sea()
    started = threading.Event()
    failed: list[BaseException] = []

    def build() -> None:
        started.set()
        try:
            s._native.set_sea(surface, np.array([vessel], np.uint32))
        except BaseException as exc:  # reported by the main thread
            failed.append(exc)

    worker = threading.Thread(target=build)
    worker.start()
    started.wait()
    time.sleep(0.02)
    # both moved while the grid is built: the vessel (declared moving) and the fixed grid
    s.set_poses([vessel, grid], np.stack([_at(600.0), _at(1500.0 + 200.0, 600.0)]))
    building = worker.is_alive()
    worker.join()
    assert not failed, failed
    assert building, "the sea was built before the poses were set: nothing raced (make the grid larger)"
    np.testing.assert_array_equal(s.instance_pose(vessel), _at(600.0))
    np.testing.assert_array_equal(s.instance_pose(grid), _at(1700.0, 600.0))
    # rays straight down: onto the vessel where it is now and where it was, onto the grid where it is now and
    # where it was; with the sea's shortcuts as without them (a full trace of every ray)
    xy = [(600.0, 0.0), (0.0, 0.0), (200.0, 600.0), (-1500.0, 0.0)]
    o = np.array([[x, y, 50.0] for x, y in xy])
    d = np.tile([0.0, 0.0, -1.0], (len(xy), 1))
    with_sea = s.cast_rays(o, d)
    assert list(with_sea.instance_id) == [vessel, surface, grid, surface]
    s.clear_sea()
    full = s.cast_rays(o, d)
    np.testing.assert_array_equal(with_sea.instance_id, full.instance_id)
    np.testing.assert_array_equal(with_sea.distance, full.distance)
