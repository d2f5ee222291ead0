"""Tests for the vessel library (mmusv.world.vessels / vessel_shapes / vessel_catalog.yaml)."""

from __future__ import annotations

import functools
import math
import re
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.classes import SemanticClass
from mmusv.world.primitives import TriMesh, box, merge
from mmusv.world.vessels import (
    AssetSpecError,
    MountPoint,
    UnknownAssetError,
    VesselAsset,
    asset_names,
    categories,
    get_asset,
    library,
    load_asset_catalog,
    load_asset_file,
    register_asset,
    unregister_asset,
)
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

NAMES = asset_names()
REQUIRED_MOUNTS = {"lidar", "radar", "camera_front", "camera_left", "camera_rear", "camera_right", "top_view"}


# --------------------------------------------------------------------------------------------- helpers


def _components(faces: np.ndarray, n_vertices: int) -> list[np.ndarray]:
    """Face-index arrays of the connected parts of a mesh (faces sharing vertices)."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]]])
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n_vertices, n_vertices))
    _, label = connected_components(graph, directed=False)
    piece = label[faces[:, 0]]
    order = np.argsort(piece, kind="stable")
    cuts = np.flatnonzero(np.diff(piece[order])) + 1
    return np.split(order, cuts)


def _signed_volume(v: np.ndarray, f: np.ndarray) -> float:
    t = v[f]
    return float(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum() / 6.0)


def _is_closed_and_consistent(f: np.ndarray) -> bool:
    """Every directed edge used once, and its reverse used too (closed, consistently oriented)."""
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]).astype(np.int64)
    n = int(edges.max()) + 1
    key = edges[:, 0] * n + edges[:, 1]
    if np.unique(key).shape[0] != key.shape[0]:
        return False  # an edge used twice in the same direction: inconsistent orientation
    return bool(np.isin(edges[:, 1] * n + edges[:, 0], key).all())


def _inside(point: np.ndarray, v: np.ndarray, f: np.ndarray) -> bool:
    """Ray-parity point-in-closed-mesh test (ray along a skewed direction to avoid edge hits)."""
    d = np.array([0.123, 0.345, 0.93])
    d /= np.linalg.norm(d)
    t = v[f]
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    p = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = point - t[:, 0]
    u = np.einsum("ij,ij->i", s, p) * inv
    q = np.cross(s, e1)
    w = (q @ d) * inv
    dist = np.einsum("ij,ij->i", e2, q) * inv
    hits = ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (dist > 1e-9)
    return bool(hits.sum() % 2 == 1)


def _write_obj(path: Path, mesh: TriMesh) -> None:
    lines = [f"v {float(x):.17g} {float(y):.17g} {float(z):.17g}" for x, y, z in mesh.vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces]
    path.write_text("\n".join(lines) + "\n")


@functools.lru_cache(maxsize=1)
def _catalog_entries() -> dict[str, dict[str, Any]]:
    text = resources.files("mmusv.world").joinpath("vessel_catalog.yaml").read_text(encoding="utf-8")
    loader: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    return {e["name"]: e for e in yaml.load(text, Loader=loader)["vessels"]}


# ------------------------------------------------------------------------------------------- catalogue


def test_library_has_at_least_30_distinct_vessels_sorted() -> None:
    lib = library()
    names = [a.name for a in lib]
    assert names == sorted(names)
    assert len(set(names)) == len(names)
    ordinary = [a for a in lib if a.semantic_class == SemanticClass.VESSEL]
    assert len(ordinary) >= 30
    assert len({a.category for a in ordinary}) >= 25
    assert set(categories()) >= {a.category for a in lib}
    assert [a.name for a in library(category="tug")] == ["tug_32m"]
    assert {a.name for a in library(semantic_class=SemanticClass.USV)} >= {"usv_wamv", "usv_patrol_12m"}


def test_lengths_span_jet_ski_to_vlcc() -> None:
    lengths = {a.name: a.length for a in library()}
    assert min(lengths.values()) <= 3.5
    assert max(lengths.values()) >= 290.0
    assert lengths["jet_ski_3m"] == pytest.approx(3.0)
    assert lengths["container_ship_300m"] == pytest.approx(300.0)
    assert lengths["vlcc_tanker_330m"] == pytest.approx(330.0)
    assert lengths["cruise_ship_300m"] == pytest.approx(300.0)
    assert lengths["bulk_carrier_290m"] >= 285.0


@pytest.mark.parametrize("name", NAMES)
def test_dimensions_equal_mesh_bounding_box(name: str) -> None:
    a = get_asset(name)
    v = a.mesh.vertices
    lo, hi = v.min(axis=0), v.max(axis=0)
    assert a.length == pytest.approx(hi[0] - lo[0], abs=1e-6)
    assert a.beam == pytest.approx(hi[1] - lo[1], abs=1e-6)
    assert a.height == pytest.approx(hi[2] - lo[2], abs=1e-6)
    assert a.draft == pytest.approx(-lo[2], abs=1e-6)
    np.testing.assert_allclose(a.bbox, np.stack([lo, hi]), atol=1e-6)
    # body frame: origin at the waterline centre of the x/y bounding box, hull below z = 0
    assert abs(lo[0] + hi[0]) < 1e-6 and abs(lo[1] + hi[1]) < 1e-6
    assert lo[2] < 0.0 < hi[2]
    assert a.air_draft == pytest.approx(hi[2], abs=1e-9)


@pytest.mark.parametrize("name", [n for n in NAMES if n in _catalog_entries()])
def test_hull_numbers_are_the_asset_numbers(name: str) -> None:
    hull = _catalog_entries()[name]["hull"]
    a = get_asset(name)
    assert a.length == pytest.approx(hull["length"], abs=1e-9)
    assert a.beam == pytest.approx(hull["beam"], abs=1e-9)
    assert a.draft >= hull["draft"] - 1e-9


@pytest.mark.parametrize("name", NAMES)
def test_proportions_are_plausible(name: str) -> None:
    a = get_asset(name)
    assert 0.0 < a.beam < a.length
    assert 0.0 < a.draft < a.height
    assert 0.1 <= a.beam / a.length <= 0.6
    assert a.draft / a.length < 0.2
    if not a.category.startswith("sailing"):
        assert a.height < a.length
    if a.length >= 50.0:
        assert 0.08 <= a.height / a.length <= 0.6
        assert a.air_draft > a.draft * 0.8
    m = re.search(r"_(\d+)m$", a.name)
    if m:
        assert a.length == pytest.approx(float(m.group(1)), rel=0.15)


@pytest.mark.parametrize("name", NAMES)
def test_mesh_is_valid_closed_and_outward(name: str) -> None:
    a = get_asset(name)
    v, f, c = a.mesh.vertices, a.mesh.faces, a.mesh.classes
    assert v.dtype == np.float64 and f.dtype == np.int64 and c.dtype == np.uint16
    assert np.all(np.isfinite(v))
    assert f.min() >= 0 and f.max() < v.shape[0]
    assert np.all(c == int(a.semantic_class))
    t = v[f]
    area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    assert np.all(area > 1e-12 * a.length**2)
    parts = _components(f, v.shape[0])
    assert len(parts) >= 2
    for idx in parts:
        assert _is_closed_and_consistent(f[idx]), f"{name}: a part is not closed/consistently oriented"
        assert _signed_volume(v, f[idx]) > 0.0, f"{name}: a part faces inwards"
    assert _signed_volume(v, f) > 0.0


def test_bbox_volume_orders_small_far_below_large() -> None:
    def vol(n: str) -> float:
        a = get_asset(n)
        return a.length * a.beam * a.height

    assert vol("jet_ski_3m") * 1e4 < vol("container_ship_300m")
    assert vol("jet_ski_3m") < vol("speedboat_5m") < vol("tug_32m") < vol("container_ship_300m")
    by_length = sorted(library(), key=lambda a: a.length)
    assert by_length[0].length < 5.0 and by_length[-1].name == "vlcc_tanker_330m"


def test_assets_are_cached_and_read_only() -> None:
    a = get_asset("tug_32m")
    assert get_asset("tug_32m") is a
    with pytest.raises(ValueError):
        a.mesh.vertices[0, 0] = 1.0
    with pytest.raises(ValueError):
        a.bbox[0, 0] = 1.0
    with pytest.raises(AttributeError):
        a.length = 3.0  # type: ignore[misc]


# ------------------------------------------------------------------------------------------------ USVs


@pytest.mark.parametrize("name", ["usv_wamv", "usv_patrol_12m"])
def test_usv_mounts(name: str) -> None:
    a = get_asset(name)
    assert a.semantic_class == SemanticClass.USV and a.is_usv
    assert set(a.mounts) >= REQUIRED_MOUNTS
    lo, hi = a.bbox
    parts = _components(a.mesh.faces, a.mesh.vertices.shape[0])
    for key, m in a.mounts.items():
        assert isinstance(m, MountPoint)
        x, y, z = m.xyz
        assert lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1], key
        assert 0.0 < z <= hi[2] + 0.5, key
        p = np.array(m.xyz)
        for idx in parts:
            assert not _inside(p, a.mesh.vertices, a.mesh.faces[idx]), f"{name}.{key} lies inside the hull"
    lidar_z = a.mounts["lidar"].xyz[2]
    assert all(lidar_z >= m.xyz[2] for m in a.mounts.values())
    assert lidar_z >= hi[2] - 1e-9
    yaws = sorted(a.mounts[k].rpy_deg[2] for k in ("camera_front", "camera_left", "camera_rear", "camera_right"))
    assert yaws == [-90.0, 0.0, 90.0, 180.0]
    assert a.mounts["top_view"].rpy_deg[1] == 90.0


def test_wamv_proportions() -> None:
    a = get_asset("usv_wamv")
    assert a.length == pytest.approx(4.88)
    assert a.beam == pytest.approx(2.44)
    assert 1.5 < a.air_draft < 3.5
    assert len(_components(a.mesh.faces, a.mesh.vertices.shape[0])) >= 3  # two pontoons + deck structure


def test_ordinary_vessels_have_no_mounts() -> None:
    assert all(not a.mounts for a in library(semantic_class=SemanticClass.VESSEL))


# ---------------------------------------------------------------------------------------------- errors


def test_unknown_asset_lists_suggestions() -> None:
    with pytest.raises(UnknownAssetError) as info:
        get_asset("contaner_ship_300m")
    err = info.value
    assert isinstance(err, KeyError)
    assert "container_ship_300m" in err.suggestions
    msg = str(err)
    assert "contaner_ship_300m" in msg and "container_ship_300m" in msg and "asset_names()" in msg
    with pytest.raises(KeyError) as info2:
        get_asset("tanker")
    assert any("tanker" in s for s in info2.value.suggestions)  # type: ignore[attr-defined]
    with pytest.raises(UnknownAssetError, match="no close match"):
        get_asset("qqqqqqqqqqqq")


def test_vessel_asset_rejects_uncentred_mesh() -> None:
    m = box(center=(5.0, 0.0, 0.0), size=(2.0, 1.0, 1.0), cls=10)
    with pytest.raises(ValueError, match="centre"):
        VesselAsset(name="off", category="custom", semantic_class=SemanticClass.VESSEL, mesh=m)
    above = box(center=(0.0, 0.0, 2.0), size=(2.0, 1.0, 1.0), cls=10)
    with pytest.raises(ValueError, match="waterline"):
        VesselAsset(name="floating", category="custom", semantic_class=SemanticClass.VESSEL, mesh=above)
    with pytest.raises(ValueError, match="semantic_class"):
        VesselAsset(
            name="buoyish",
            category="custom",
            semantic_class=SemanticClass.BUOY,
            mesh=box(center=(0.0, 0.0, 0.0), size=(1.0, 1.0, 1.0), cls=7),
        )


# ----------------------------------------------------------------------------------------- user assets


def _file_boat(tmp_path: Path) -> Path:
    """A y-up OBJ whose bow points along file -z: hull box 2 (x) x 2.5 (y) x 8 (z) plus a bow marker."""
    hull = box(center=(0.0, 0.75, 1.0), size=(2.0, 2.5, 8.0), cls=0)  # x [-1,1] y [-0.5,2] z [-3,5]
    marker = box(center=(0.0, 2.5, -2.5), size=(1.0, 1.0, 1.0), cls=0)  # at the -z end, on top
    p = tmp_path / "boat.obj"
    _write_obj(p, merge([hull, marker]))
    return p


def test_user_obj_round_trip_with_axis_conversion(tmp_path: Path) -> None:
    pytest.importorskip("trimesh")
    obj = _file_boat(tmp_path)
    a = load_asset_file(
        {
            "name": "file_boat",
            "mesh": str(obj),
            "scale": 2.0,
            "up_axis": "y",
            "forward_axis": "-z",
            "waterline_z": 0.5,
            "category": "custom",
        }
    )
    assert (a.length, a.beam, a.height, a.draft) == pytest.approx((16.0, 4.0, 7.0, 2.0))
    assert a.semantic_class == SemanticClass.VESSEL and a.source == "<mapping>"
    v = a.mesh.vertices
    np.testing.assert_allclose(a.bbox, [[-8.0, -2.0, -2.0], [8.0, 2.0, 5.0]], atol=1e-9)
    top = v[v[:, 2] > 5.0 - 1e-9]
    assert top.shape[0] > 0 and np.all(top[:, 0] >= 6.0 - 1e-9)  # the marker ends up at the bow (+x)
    assert _signed_volume(v, a.mesh.faces) > 0.0  # proper rotation keeps normals outward
    assert np.all(a.mesh.classes == int(SemanticClass.VESSEL))


def test_user_yaml_file_relative_mesh_register_and_duplicates(tmp_path: Path) -> None:
    pytest.importorskip("trimesh")
    _file_boat(tmp_path)
    y = tmp_path / "my_usv.yaml"
    y.write_text(
        yaml.safe_dump(
            {
                "name": "test_my_usv",
                "category": "usv",
                "semantic_class": "usv",
                "mesh": "boat.obj",
                "up_axis": "y",
                "forward_axis": "-z",
                "draft": 0.4,
                "mounts": {"lidar": {"xyz": [0.0, 0.0, 3.5]}},
            }
        )
    )
    a = load_asset_file(y, register=True)
    try:
        assert a.draft == pytest.approx(0.4) and a.height == pytest.approx(3.5)
        assert a.length == pytest.approx(8.0) and a.beam == pytest.approx(2.0)
        assert a.is_usv and a.mounts["lidar"] == MountPoint((0.0, 0.0, 3.5), (0.0, 0.0, 0.0))
        assert get_asset("test_my_usv") is a and "test_my_usv" in asset_names()
        with pytest.raises(AssetSpecError) as info:
            load_asset_file(y, register=True)
        assert info.value.field == "name"
    finally:
        unregister_asset("test_my_usv")
    with pytest.raises(UnknownAssetError):
        get_asset("test_my_usv")


def test_register_rejects_builtin_names_and_unregister_builtin() -> None:
    tug = get_asset("tug_32m")
    clone = VesselAsset(name="tug_32m", category="tug", semantic_class=SemanticClass.VESSEL, mesh=tug.mesh)
    with pytest.raises(AssetSpecError, match="built-in"):
        register_asset(clone)
    with pytest.raises(AssetSpecError, match="built-in"):
        unregister_asset("tug_32m")


def test_default_axes_z_up_x_forward(tmp_path: Path) -> None:
    pytest.importorskip("trimesh")
    p = tmp_path / "zup.obj"
    _write_obj(p, box(center=(10.0, 3.0, 1.0), size=(6.0, 2.0, 3.0), cls=0))  # z from -0.5 to 2.5
    a = load_asset_file({"name": "zup", "mesh": str(p)})
    assert (a.length, a.beam, a.height, a.draft) == pytest.approx((6.0, 2.0, 3.0, 0.5))


def test_procedural_user_entry_and_catalog_file(tmp_path: Path) -> None:
    entry = {
        "name": "test_launch",
        "category": "launch",
        "hull": {"length": 8.0, "beam": 2.6, "draft": 0.6, "depth": 1.5, "bow": 0.4, "stern": 0.0},
        "parts": [
            {"type": "house", "x": 0.5, "tiers": [[2.5, 1.8, 1.6]], "fit": 0.2},
            {"type": "mast", "x": 0.5, "base": 2.5, "top": 4.0, "width": 0.1},
        ],
    }
    a = load_asset_file(entry)
    assert (a.length, a.beam, a.draft, a.air_draft) == pytest.approx((8.0, 2.6, 0.6, 4.0))
    p = tmp_path / "fleet.yaml"
    second = dict(entry, name="test_launch_2")
    p.write_text(yaml.safe_dump({"vessels": [entry, second]}))
    fleet = load_asset_catalog(p)
    assert [x.name for x in fleet] == ["test_launch", "test_launch_2"]
    with pytest.raises(AssetSpecError, match="load_asset_catalog"):
        load_asset_file(p)


def _base_mesh_entry(tmp_path: Path) -> dict[str, Any]:
    p = tmp_path / "b.obj"
    _write_obj(p, box(center=(0.0, 0.0, 0.5), size=(4.0, 1.5, 2.0), cls=0))
    return {"name": "bad_boat", "mesh": str(p)}


HULL = {"length": 8.0, "beam": 2.6, "draft": 0.6, "depth": 1.5}


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"name": None}, "name"),
        ({"name": "has space"}, "name"),
        ({"mesh": "does/not/exist.obj"}, "bad_boat.mesh"),
        ({"up_axis": "w"}, "bad_boat.up_axis"),
        ({"forward_axis": "q"}, "bad_boat.forward_axis"),
        ({"up_axis": "y", "forward_axis": "-y"}, "bad_boat.forward_axis"),
        ({"scale": -1.0}, "bad_boat.scale"),
        ({"scale": "big"}, "bad_boat.scale"),
        ({"semantic_class": "buoy"}, "bad_boat.semantic_class"),
        ({"waterline_z": 100.0}, "bad_boat.waterline_z"),
        ({"waterline_z": 0.0, "draft": 0.3}, "bad_boat.draft"),
        ({"draft": 5.0}, "bad_boat.draft"),
        ({"colour": "red"}, "bad_boat.colour"),
        ({"mounts": {"lidar": {"xyz": [1.0, 2.0]}}}, "bad_boat.mounts.lidar.xyz"),
        ({"mounts": {"lidar": {"xyz": [1.0, 2.0, 3.0], "rpy": [0, 0, 0]}}}, "bad_boat.mounts.lidar.rpy"),
        ({"hull": HULL}, "bad_boat.mesh"),
        ({"mesh": None}, "bad_boat.mesh"),
        ({"mesh": None, "hull": dict(HULL, beam=-1.0)}, "bad_boat.hull.beam"),
        ({"mesh": None, "hull": dict(HULL, depth=0.5)}, "bad_boat.hull.depth"),
        ({"mesh": None, "hull": dict(HULL, wings=3)}, "bad_boat.hull.wings"),
        ({"mesh": None, "hull": dict(HULL, bow=0.0, bow_width=0.5)}, "bad_boat.hull.bow_width"),
        ({"mesh": None, "hull": HULL, "parts": [{"type": "spaceship"}]}, "bad_boat.parts[0].type"),
        (
            {"mesh": None, "hull": HULL, "parts": [{"type": "box", "x": 0.0, "size": [1.0, 1.0]}]},
            "bad_boat.parts[0].top",
        ),
        (
            {"mesh": None, "hull": HULL, "parts": [{"type": "box", "x": 3.9, "size": [1.0, 1.0], "height": 1.0}]},
            "bad_boat.parts[0]",
        ),
        (
            {"mesh": None, "hull": HULL, "parts": [{"type": "mast", "x": 0.0, "top": 3.0, "wdth": 0.2}]},
            "bad_boat.parts[0].wdth",
        ),
        ({"mesh": None, "hull": HULL, "parts": "mast"}, "bad_boat.parts"),
    ],
)
def test_bad_entries_name_the_field(tmp_path: Path, change: dict[str, Any], field: str) -> None:
    pytest.importorskip("trimesh")
    entry = _base_mesh_entry(tmp_path)
    for k, val in change.items():
        if val is None:
            entry.pop(k, None)
        else:
            entry[k] = val
    with pytest.raises(AssetSpecError) as info:
        load_asset_file(entry, base_dir=tmp_path)
    assert isinstance(info.value, ValueError)
    assert info.value.field == field, str(info.value)
    assert str(info.value).startswith(field)


def test_empty_and_unreadable_mesh_files(tmp_path: Path) -> None:
    pytest.importorskip("trimesh")
    empty = tmp_path / "empty.obj"
    empty.write_text("")
    with pytest.raises(AssetSpecError) as info:
        load_asset_file({"name": "e", "mesh": str(empty)})
    assert info.value.field == "e.mesh" and "no triangles" in str(info.value)
    odd = tmp_path / "boat.unknownext"
    odd.write_text("hello")
    with pytest.raises(AssetSpecError) as info2:
        load_asset_file({"name": "u", "mesh": str(odd)})
    assert info2.value.field == "u.mesh"
    with pytest.raises(AssetSpecError) as info3:
        load_asset_file(tmp_path / "nope.yaml")
    assert info3.value.field == "file"


def test_asset_spec_error_pickles() -> None:
    import pickle

    err = AssetSpecError("x.hull.beam", "must be > 0")
    back = pickle.loads(pickle.dumps(err))
    assert back.field == "x.hull.beam" and str(back) == str(err)
    unk = UnknownAssetError("tugg", ["tug_32m"])
    back2 = pickle.loads(pickle.dumps(unk))
    assert str(back2) == str(unk) and back2.suggestions == unk.suggestions


def test_mount_points_are_named_tuples() -> None:
    m = get_asset("usv_wamv").mounts["lidar"]
    xyz, rpy = m
    assert len(xyz) == 3 and len(rpy) == 3 and all(math.isfinite(x) for x in xyz + rpy)
    with pytest.raises(TypeError):
        get_asset("usv_wamv").mounts["new"] = m  # type: ignore[index]


def test_meshes_compare_by_value_and_assets_pickle() -> None:
    # `TriMesh ==` asked its arrays for a truth value (numpy's ValueError) and `hash` raised TypeError; an asset
    # could not be pickled or deep-copied (its read-only mounts), so neither could anything holding one.
    import copy
    import pickle

    import numpy as np
    import pytest
    from mmusv.world.primitives import TriMesh
    from mmusv.world.vessels import get_asset

    a = get_asset("tug_32m")
    mesh = a.mesh
    twin = TriMesh(mesh.vertices.copy(), mesh.faces.copy(), mesh.classes.copy(), mesh.materials.copy())
    assert mesh == twin
    moved = TriMesh(mesh.vertices + np.array([0.0, 0.0, 1e-9]), mesh.faces, mesh.classes, mesh.materials)
    assert mesh != moved
    assert mesh != "tug"
    with pytest.raises(TypeError):
        hash(mesh)
    for b in (pickle.loads(pickle.dumps(a)), copy.deepcopy(a)):
        assert b.mesh == a.mesh and dict(b.mounts) == dict(a.mounts) and b.name == a.name
        assert np.array_equal(b.bbox, a.bbox) and b.length == a.length
        with pytest.raises(TypeError):
            b.mounts["extra"] = None  # type: ignore[index]  # still read-only
