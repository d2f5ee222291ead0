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
