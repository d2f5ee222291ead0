"""User mesh assets: non-finite vertices, out-of-range sizes (``scale``) and far-away mounts are refused by name."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from mmusv.world.asset_spec import DIMENSION_RANGES, AssetSpecError
from mmusv.world.vessels import asset_names, get_asset, load_asset_file

_BOX_V = [(x, y, z) for x in (-5.0, 5.0) for y in (-1.5, 1.5) for z in (-1.0, 1.0)]
_BOX_F = [(1, 2, 4), (1, 4, 3), (5, 7, 8), (5, 8, 6), (1, 5, 6), (1, 6, 2), (3, 4, 8), (3, 8, 7), (1, 3, 7)]
_BOX_F += [(1, 7, 5), (2, 6, 8), (2, 8, 4)]


def _obj(path: Path, vertices: list[tuple[float, float, float]], faces: list[tuple[int, int, int]]) -> Path:
    lines = [f"v {x} {y} {z}" for x, y, z in vertices] + [f"f {a} {b} {c}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def box_obj(tmp_path: Path) -> Path:
    """A 10 x 3 x 2 m box, z from -1 to 1."""
    return _obj(tmp_path / "box.obj", _BOX_V, _BOX_F)


def test_box_loads(box_obj: Path) -> None:
    a = load_asset_file({"name": "userboat", "mesh": str(box_obj)})
    assert (a.length, a.beam, a.height, a.num_triangles) == (10.0, 3.0, 2.0, 12)


@pytest.mark.parametrize("bad", ["nan", "inf", "-inf"])
def test_non_finite_vertex_in_box_is_refused(tmp_path: Path, bad: str) -> None:
    verts: list[tuple[float, float, float]] = list(_BOX_V)
    verts[0] = (float(bad), verts[0][1], verts[0][2])
    p = _obj(tmp_path / "boxnan.obj", verts, _BOX_F)
    with pytest.raises(AssetSpecError, match="non-finite") as info:
        load_asset_file({"name": "userboat", "mesh": str(p)})
    assert info.value.field == "userboat.mesh"
    assert "boxnan.obj" in str(info.value)


def test_single_nan_triangle_is_not_called_empty(tmp_path: Path) -> None:
    p = _obj(tmp_path / "nan.obj", [(0.0, 0.0, -1.0), (float("nan"), 0.0, 1.0), (0.0, 1.0, 1.0)], [(1, 2, 3)])
    with pytest.raises(AssetSpecError, match="non-finite") as info:
        load_asset_file({"name": "userboat", "mesh": str(p)})
    assert info.value.field == "userboat.mesh"
    assert "no triangles" not in str(info.value)


def test_nan_vertex_in_glb_is_refused(tmp_path: Path) -> None:
    trimesh = pytest.importorskip("trimesh")
    v = np.array(_BOX_V, dtype=np.float64)
    m = trimesh.Trimesh(v, np.array(_BOX_F) - 1, process=False)
    m.vertices[0, 1] = np.nan
    p = tmp_path / "boxnan.glb"
    m.export(p)
    with pytest.raises(AssetSpecError, match="non-finite") as info:
        load_asset_file({"name": "userboat", "mesh": str(p)})
    assert info.value.field == "userboat.mesh"


@pytest.mark.parametrize("scale", [1e30, 1e200, 1e308, 1e-300, 1e-3, 100.0])
def test_extreme_scale_is_refused(box_obj: Path, scale: float) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy overflow warnings on the way
        with pytest.raises(AssetSpecError, match=r"allowed: length 0\.5\.\.500 m") as info:
            load_asset_file({"name": "userboat", "mesh": str(box_obj), "scale": scale})
    assert info.value.field == "userboat.scale"


@pytest.mark.parametrize("scale", [0.05, 1.0, 50.0])
def test_sane_scales_load(box_obj: Path, scale: float) -> None:
    a = load_asset_file({"name": "userboat", "mesh": str(box_obj), "scale": scale})
    assert a.length == pytest.approx(10.0 * scale)


def test_far_mount_is_refused(box_obj: Path) -> None:
    entry = {"name": "userboat", "mesh": str(box_obj), "mounts": {"lidar": {"xyz": [1e9, 0.0, 0.0]}}}
    with pytest.raises(AssetSpecError, match="50 m") as info:
        load_asset_file(entry)
    assert info.value.field == "userboat.mounts.lidar.xyz"
    near = {"name": "userboat", "mesh": str(box_obj), "mounts": {"lidar": {"xyz": [0.0, 0.0, 40.0]}}}
    assert load_asset_file(near).mounts["lidar"].xyz == (0.0, 0.0, 40.0)


def test_procedural_hull_length_is_bounded() -> None:
    hull = {"length": 1e30, "beam": 3.0, "draft": 0.5, "depth": 1.5}
    with pytest.raises(AssetSpecError, match="500") as info:
        load_asset_file({"name": "huge", "hull": hull})
    assert info.value.field == "huge.hull.length"


def test_catalogue_within_bounds() -> None:
    for name in asset_names():
        a = get_asset(name)
        for dim, (lo, hi) in DIMENSION_RANGES.items():
            assert lo <= getattr(a, dim) <= hi, (name, dim)


def test_a_folder_given_as_a_mesh_is_named_as_a_folder(tmp_path: Path) -> None:
    (tmp_path / "boat.obj").mkdir()
    with pytest.raises(AssetSpecError, match="is a folder, not a mesh file"):
        load_asset_file({"name": "userboat", "mesh": str(tmp_path / "boat.obj")})
    with pytest.raises(AssetSpecError, match="does not exist"):
        load_asset_file({"name": "userboat", "mesh": str(tmp_path / "missing.obj")})
