"""Review of glTF ``COLOR_0`` on user meshes (a helper's round), each test failing before its fix:

* a sparse ``COLOR_0`` accessor: trimesh's glTF reader does not apply sparse substitutions (it reads the accessor's
  bufferView, or zeros without one), so the colours came out silently wrong (white or black); now one line naming
  the file, primitive and accessor;
* many glTF materials multiplied by ``COLOR_0``: the 256-material cap quantised coarser without a floor, to 1 level
  (a division by zero: NaN cast to bytes, materials named ``#-8000000000000000…`` with garbage colours) and, past
  256 such materials, never ended; now 2 levels at the least, then one colour per glTF material, with the warning.
"""

from __future__ import annotations

import json
import re
import struct
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.materials import all_materials
from mmusv.world.vessels import load_asset_file

pytest.importorskip("trimesh")

AXES = {"up_axis": "z", "forward_axis": "x"}
FLOAT, USHORT = 5126, 5123
SIDES = np.array([[1, 0, 0], [0, 0, 1], [0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1]], dtype=np.float32)
"""One colour per side of the box (a hard edge at every box edge), each its 4 corners' COLOR_0."""


def _box() -> tuple[np.ndarray, np.ndarray]:
    """A 10 × 3 × 2 m box as exporters write a flat-shaded one: 24 vertices (4 per side), 12 outward triangles."""
    lo, hi = (-5.0, -1.5, -1.0), (5.0, 1.5, 1.0)
    corners = [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    pos = np.array([corners[i] for q in quads for i in q], dtype=np.float32)
    tri = [(4 * k, 4 * k + a, 4 * k + b) for k in range(6) for a, b in ((1, 2), (2, 3))]
    return pos, np.array(tri, dtype=np.uint16)


class _Glb:
    """A GLB written by hand: buffer views and accessors appended to one binary buffer."""

    def __init__(self) -> None:
        self.blob = b""
        self.views: list[dict[str, Any]] = []
        self.accessors: list[dict[str, Any]] = []

    def view(self, raw: bytes) -> int:
        self.views.append({"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(raw)})
        self.blob += raw + b"\0" * (-len(raw) % 4)
        return len(self.views) - 1

    def accessor(self, data: np.ndarray, comp: int, kind: str, **extra: Any) -> int:
        acc = {"bufferView": self.view(data.tobytes()), "componentType": comp, "count": len(data), "type": kind}
        self.accessors.append({**acc, **extra})
        return len(self.accessors) - 1

    def save(self, path: Path, header: dict[str, Any]) -> Path:
        doc = {"asset": {"version": "2.0"}, "bufferViews": self.views, "accessors": self.accessors, **header}
        doc["buffers"] = [{"byteLength": len(self.blob)}]
        js = json.dumps(doc).encode()
        js += b" " * (-len(js) % 4)
        body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(self.blob), 0x004E4942)
        path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body) + len(self.blob)) + body + self.blob)
        return path


def _load(path: Path) -> Any:
    return load_asset_file({"name": "user_hull", "mesh": str(path), **AXES})


@pytest.mark.parametrize("with_view", [True, False])
def test_a_sparse_color_0_is_one_line_naming_the_file(tmp_path: Path, with_view: bool) -> None:
    """Base values white, the sparse part setting one side red: trimesh read all white (or, without a bufferView,
    all black) without a word."""
    g = _Glb()
    pos, tri = _box()
    position = g.accessor(pos, FLOAT, "VEC3", min=pos.min(0).tolist(), max=pos.max(0).tolist())
    indices = g.accessor(tri.reshape(-1), USHORT, "SCALAR")
    colour = g.accessor(np.ones((24, 3), dtype=np.float32), FLOAT, "VEC3")
    acc = g.accessors[colour]
    acc["sparse"] = {
        "count": 4,
        "indices": {"bufferView": g.view(np.arange(4, dtype=np.uint16).tobytes()), "componentType": USHORT},
        "values": {"bufferView": g.view(np.tile(np.array([1, 0, 0], dtype=np.float32), (4, 1)).tobytes())},
    }
    if not with_view:
        del acc["bufferView"]
    prim = {"attributes": {"POSITION": position, "COLOR_0": colour}, "indices": indices}
    header = {"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}], "meshes": [{"primitives": [prim]}]}
    path = g.save(tmp_path / "sparse.glb", header)
    with pytest.raises(AssetSpecError, match=r"meshes\[0\]\.primitives\[0\]\.attributes\.COLOR_0 \(accessors\[2\]\) "
                       r"is a sparse accessor") as info:  # fmt: skip
        _load(path)
    msg = str(info.value)
    assert repr(str(path)) in msg and "\n" not in msg
    assert ("its bufferView's values" if with_view else "zeros (black)") in msg


def test_many_materials_times_color_0_stay_within_the_cap(tmp_path: Path) -> None:
    """50 glTF materials, each on a box whose 6 sides have 6 COLOR_0 colours: 300 materials even at 2 levels per
    channel. Every face gets a proper material (a ``#rrggbb`` name, a base colour in [0, 1]), at most 256 of them,
    each glTF material one colour (its faces' mean), with the warning saying so."""
    g = _Glb()
    pos, tri = _box()
    position = g.accessor(pos, FLOAT, "VEC3", min=pos.min(0).tolist(), max=pos.max(0).tolist())
    indices = g.accessor(tri.reshape(-1), USHORT, "SCALAR")
    colour = g.accessor(np.repeat(SIDES, 4, axis=0), FLOAT, "VEC3")
    n = 50
    materials = [{"name": f"paint{k}", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0]}} for k in
                 range(n)]  # fmt: skip
    meshes = [
        {"primitives": [{"attributes": {"POSITION": position, "COLOR_0": colour}, "indices": indices, "material": k}]}
        for k in range(n)
    ]
    nodes = [{"mesh": k, "translation": [0.0, 0.0, 2.5 * k]} for k in range(n)]
    header = {"scene": 0, "scenes": [{"nodes": list(range(n))}], "nodes": nodes, "meshes": meshes,
              "materials": materials}  # fmt: skip
    path = g.save(tmp_path / "fleet.glb", header)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        asset = _load(path)
    said = [str(w.message) for w in caught]
    assert not [s for s in said if "invalid value" in s], said  # no NaN cast
    table = all_materials()
    used = [table[m] for m in sorted(set(asset.mesh.materials.tolist()))]
    assert 0 < len(used) <= 256
    for m in used:
        assert re.fullmatch(r"fleet:paint\d+:#[0-9a-f]{6}", m.name), m.name
        assert all(0.0 <= c <= 1.0 for c in m.base_color), (m.name, m.base_color)
    mean = SIDES.astype(np.float64).mean(axis=0)  # the faces' mean linear colour: 1/2, 2/3, 1/2
    assert {m.name.rsplit(":", 1)[1] for m in used} == {_hex(mean)}
    assert [s for s in said if "each glTF material they multiply takes the mean of its faces' colours" in s], said


def _hex(linear: np.ndarray) -> str:
    """``#rrggbb`` of a linear colour at 64 sRGB levels (as mmusv quantises)."""

    def enc(c: float) -> float:
        return c * 12.92 if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055

    return "#" + "".join(f"{round(round(enc(float(c)) * 63) * 255 / 63):02x}" for c in linear)
