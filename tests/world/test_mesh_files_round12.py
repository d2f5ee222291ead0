"""A user mesh whose every face is degenerate (its corners at one point or on one line) was taken as an asset: its
bounding box gave the vessel a size, so it was labelled in every frame, but no sensor could ever see it. It is now
refused as a mesh of no triangles is, naming the field and the file; a mesh with one face of some area is kept."""

from __future__ import annotations

from pathlib import Path

import pytest
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.vessels import load_asset_file

CORNERS = "v 0 0 0\nv 6 0 0\nv 6 2 0\nv 0 2 1.5\nv 3 0 0\n"


def _entry(tmp_path: Path, faces: str) -> dict[str, object]:
    mesh = tmp_path / "hull.obj"
    mesh.write_text(CORNERS + faces, encoding="utf-8")
    return {"name": "user_hull", "mesh": str(mesh), "up_axis": "z", "forward_axis": "x", "draft": 0.4}


@pytest.mark.parametrize(
    "faces",
    [
        "f 1 1 1\nf 2 2 2\nf 4 4 4\n",  # each face one point
        "f 1 2 2\nf 3 4 3\n",  # each face two points
        "f 1 5 2\nf 2 1 5\n",  # three points on one line (x axis)
    ],
)
def test_a_mesh_of_degenerate_faces_only_is_refused(tmp_path: Path, faces: str) -> None:
    entry = _entry(tmp_path, faces)
    with pytest.raises(AssetSpecError) as info:
        load_asset_file(entry)
    msg = str(info.value)
    assert info.value.field == "user_hull.mesh" and repr(entry["mesh"]) in msg, msg
    assert "holds no triangle of any area" in msg and "\n" not in msg, msg


def test_one_face_of_some_area_among_degenerate_ones_is_kept(tmp_path: Path) -> None:
    asset = load_asset_file(_entry(tmp_path, "f 1 1 1\nf 1 5 2\nf 1 3 4\n"))
    assert asset.length == pytest.approx(6.0)


def test_a_small_mesh_in_large_units_is_not_taken_for_degenerate(tmp_path: Path) -> None:
    mesh = tmp_path / "km.obj"  # the same hull in kilometres: faces of 1e-6 square units
    mesh.write_text(
        "v 0 0 0\nv 0.006 0 0\nv 0.006 0.002 0\nv 0 0.002 0.0015\nf 1 2 3\nf 1 3 4\nf 1 2 4\n", encoding="utf-8"
    )
    asset = load_asset_file(
        {"name": "user_hull", "mesh": str(mesh), "up_axis": "z", "forward_axis": "x", "scale": 1000, "draft": 0.4}
    )
    assert asset.length == pytest.approx(6.0)


# A face naming a vertex the file does not hold was read as another vertex without a word: trimesh kept a PLY face's
# -1 (numpy then took the last vertex) and read an OBJ face's 0 as -1 (OBJ counts from 1, so 0 names none).

BOX = [(0, 0, 0), (6, 0, 0), (6, 2, 0), (0, 2, 0), (0, 0, 1.5), (6, 0, 1.5), (6, 2, 1.5), (0, 2, 1.5)]


def _ply(faces: list[tuple[int, int, int]]) -> str:
    head = (
        "ply\nformat ascii 1.0\n"
        f"element vertex {len(BOX)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    return head + "".join(f"{x} {y} {z}\n" for x, y, z in BOX) + "".join(f"3 {a} {b} {c}\n" for a, b, c in faces)


def _obj(faces: str) -> str:
    return "".join(f"v {x} {y} {z}\n" for x, y, z in BOX) + "vn 0 0 1\nvt 0 0\n" + faces


def _load_mesh(tmp_path: Path, name: str, text: str) -> object:
    mesh = tmp_path / name
    mesh.write_text(text, encoding="utf-8")
    return load_asset_file({"name": "user_hull", "mesh": str(mesh), "up_axis": "z", "forward_axis": "x", "draft": 0.4})


@pytest.mark.parametrize("bad", [-1, -8, 8])
def test_a_ply_face_past_its_vertices_is_refused(tmp_path: Path, bad: int) -> None:
    with pytest.raises(AssetSpecError) as info:
        _load_mesh(tmp_path, "hull.ply", _ply([(0, 1, 2), (0, 2, bad), (4, 5, 6)]))
    msg = str(info.value)
    assert info.value.field == "user_hull.mesh" and "hull.ply" in msg, msg
    assert f"index {bad}" in msg and "vertices are numbered 0..7" in msg and "damaged" in msg, msg


@pytest.mark.parametrize(
    ("faces", "line"),
    [
        ("f 1 2 3\nf 1 3 0\nf 5 6 7\n", 12),  # a vertex
        ("f 1/1 2/1 3/1\nf 5/0 6/1 7/1\n", 12),  # a texture coordinate
        ("f 1//1 2//1 3//1\r\nf 5//1 6//1 7//0", 12),  # a normal, CRLF, no line end at the end
        ("f 1 2 3 # 0 in a comment\nf 5 6 -0\n", 12),
    ],
)
def test_an_obj_face_naming_index_0_is_refused_naming_its_line(tmp_path: Path, faces: str, line: int) -> None:
    with pytest.raises(AssetSpecError) as info:
        _load_mesh(tmp_path, "hull.obj", _obj(faces))
    msg = str(info.value)
    assert info.value.field == "user_hull.mesh" and "hull.obj" in msg, msg
    assert f"the face on line {line} names index 0" in msg and "from 1" in msg, msg


def test_obj_faces_of_10_and_negative_indices_are_read(tmp_path: Path) -> None:
    faces = "f 1 2 3\nf 1 3 4\n# f 0 1 2\nf -4 -3 -2\nf 5/1/1 6/1/1 8/1/1\n" + "v 0 0 10\n" * 3 + "f 1 10 11\n"
    asset = _load_mesh(tmp_path, "hull.obj", _obj(faces))
    assert asset.num_triangles == 5  # type: ignore[attr-defined]


# Coordinates past about 9.2e10 file units: trimesh merges vertices by their coordinates rounded to 1e-8 as int64,
# which overflow there, so distinct vertices became one point; the mesh was refused for "no triangle of any area"
# (the wrong reason) or lost faces. It is refused for its coordinates, naming the file and what is allowed.


def test_a_mesh_with_coordinates_past_what_trimesh_can_merge_is_refused_for_them(tmp_path: Path) -> None:
    mesh = tmp_path / "far.obj"  # a 6 x 2 x 1.5 hull 1e11 units out along x
    k = 1.0e11
    mesh.write_text(
        f"v {k} 0 0\nv {k + 6e6} 0 0\nv {k + 6e6} 2e6 0\nv {k} 2e6 1.5e6\nf 1 2 3\nf 1 3 4\nf 1 2 4\n",
        encoding="utf-8",
    )
    entry = {"name": "user_hull", "mesh": str(mesh), "up_axis": "z", "forward_axis": "x", "scale": 1e-6}
    with pytest.raises(AssetSpecError) as info:
        load_asset_file({**entry, "draft": 0.4})
    msg = str(info.value)
    assert info.value.field == "user_hull.mesh" and repr(str(mesh)) in msg and "\n" not in msg, msg
    assert "1e+11 file units" in msg and "±9e+10" in msg and "no triangle" not in msg, msg


def test_a_mesh_just_within_the_coordinates_is_read_whole(tmp_path: Path) -> None:
    mesh = tmp_path / "near.obj"  # the same hull 8e10 units out: every vertex kept apart
    k = 8.0e10
    mesh.write_text(
        f"v {k} 0 0\nv {k + 6e6} 0 0\nv {k + 6e6} 2e6 0\nv {k} 2e6 1.5e6\nf 1 2 3\nf 1 3 4\nf 1 2 4\n",
        encoding="utf-8",
    )
    asset = load_asset_file(
        {"name": "user_hull", "mesh": str(mesh), "up_axis": "z", "forward_axis": "x", "scale": 1e-6, "draft": 0.4}
    )
    assert asset.length == pytest.approx(6.0)
