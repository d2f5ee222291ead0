"""A glTF/GLB primitive's ``COLOR_0`` vertex colours come through: linear RGB(A) as stored (float, or unsigned
byte/short normalized), a face's colour the mean of its three vertices', times the material's ``baseColorFactor``
(glTF 2.0 section 3.9.2: "an additional linear multiplier to base color"), quantised to 64 levels per sRGB channel;
checked face by face against values computed here from the arrays written into hand-built files. A hard colour
edge (a corner written once per face, as exporters split it) survives trimesh's vertex merge, and a dark float
colour is not rounded to trimesh's 8 bits. A bad ``COLOR_0`` is a one-line error naming the file and the entry."""

from __future__ import annotations

import json
import struct
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.materials import Material, all_materials
from mmusv.world.mesh_files import GLTF_EMISSIVE_SCALE
from mmusv.world.vessels import VesselAsset, load_asset_file

pytest.importorskip("trimesh")

HULL = ((-5.0, -1.5, -1.0), (5.0, 1.5, 1.0))
"""The box, file = body frame (the entries give up_axis z, forward_axis x; waterline z = 0)."""
AXES = {"up_axis": "z", "forward_axis": "x"}

FLOAT, UBYTE, USHORT = 5126, 5121, 5123


def _srgb(c: float) -> float:
    """sRGB-encoded [0, 1] to linear (IEC 61966-2-1)."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def _srgb_encode(c: float) -> float:
    return c * 12.92 if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


def _quantised(rgb_linear: np.ndarray) -> tuple[np.ndarray, str]:
    """The linear colour and the ``#rrggbb`` of the material mmusv documents for a face of linear colour
    ``rgb_linear``: sRGB encoded, rounded to 64 levels per channel, then to the byte."""
    byte = [round(round(_srgb_encode(min(max(float(c), 0.0), 1.0)) * 63) * 255 / 63) for c in rgb_linear]
    return np.array([_srgb(b / 255) for b in byte]), "#{:02x}{:02x}{:02x}".format(*byte)


def _box_faces() -> tuple[np.ndarray, np.ndarray]:
    """The box as glTF exporters write a flat-shaded box: 4 vertices per side (each corner once per side it
    touches: 24 vertices), 12 outward triangles."""
    lo, hi = HULL
    corners = [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    pos = np.array([corners[i] for q in quads for i in q], dtype=np.float32)
    tri = [(4 * k, 4 * k + a, 4 * k + b) for k in range(6) for a, b in ((1, 2), (2, 3))]
    return pos, np.array(tri, dtype=np.uint16)


def _document(
    colours: np.ndarray | None,
    component: int = FLOAT,
    material: dict[str, Any] | None = None,
) -> tuple[dict[str, Any], bytes]:
    """A glTF JSON and its binary buffer: the box as one primitive, ``colours`` ``(24, 3 or 4)`` as its COLOR_0
    (float as given; an integer type takes them as stored, normalized), ``material`` its only material."""
    pos, tri = _box_faces()
    blobs: list[bytes] = []
    views: list[dict[str, Any]] = []
    accessors: list[dict[str, Any]] = []

    def add(data: np.ndarray, comp: int, kind: str, count: int, **extra: Any) -> int:
        offset = sum(len(b) for b in blobs)
        raw = data.tobytes()
        blobs.append(raw + b"\0" * (-len(raw) % 4))
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(raw)})
        accessors.append({"bufferView": len(views) - 1, "componentType": comp, "count": count, "type": kind, **extra})
        return len(accessors) - 1

    attrs = {"POSITION": add(pos, FLOAT, "VEC3", len(pos), min=pos.min(0).tolist(), max=pos.max(0).tolist())}
    prim: dict[str, Any] = {"attributes": attrs, "indices": add(tri, USHORT, "SCALAR", tri.size)}
    if colours is not None:
        dtype = {FLOAT: np.float32, UBYTE: np.uint8, USHORT: np.uint16}[component]
        kind = f"VEC{colours.shape[1]}"
        extra = {} if component == FLOAT else {"normalized": True}
        attrs["COLOR_0"] = add(np.asarray(colours, dtype=dtype), component, kind, len(colours), **extra)
    header: dict[str, Any] = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"name": "hull", "primitives": [prim]}],
        "bufferViews": views,
        "accessors": accessors,
    }
    if material is not None:
        header["materials"] = [material]
        prim["material"] = 0
    return header, b"".join(blobs)


def _save(path: Path, header: dict[str, Any], binary: bytes) -> Path:
    """``header`` and ``binary`` as a GLB (``.glb``) or as a ``.gltf`` with its ``.bin`` beside it."""
    header = {**header, "buffers": [{"byteLength": len(binary)}]}
    if path.suffix == ".gltf":
        (path.parent / f"{path.stem}.bin").write_bytes(binary)
        header["buffers"][0]["uri"] = f"{path.stem}.bin"
        path.write_text(json.dumps(header))
        return path
    js = json.dumps(header).encode()
    js += b" " * (-len(js) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(binary), 0x004E4942) + binary
    path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
    return path


def _load(path: Path) -> VesselAsset:
    """The asset of ``path`` (named ``user_hull``), failing on any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return load_asset_file({"name": "user_hull", "mesh": str(path), **AXES})


def _face_materials(a: VesselAsset) -> list[tuple[np.ndarray, Material]]:
    """``(index of the written triangle, material)`` of every face of ``a``, by centroid (the file's frame is the
    body frame)."""
    pos, tri = _box_faces()
    written = pos[tri].astype(np.float64).mean(axis=1)
    mats = all_materials()
    out = []
    for f, m in zip(a.mesh.faces, a.mesh.materials.tolist(), strict=True):
        c = a.mesh.vertices[f].mean(axis=0)
        k = int(np.argmin(np.linalg.norm(written - c, axis=1)))
        assert np.allclose(written[k], c, atol=1e-5)
        out.append((k, mats[m]))
    assert sorted(k for k, _ in out) == list(range(12))
    return out


def _expected(linear: np.ndarray, base: np.ndarray | None = None) -> list[tuple[np.ndarray, str]]:
    """Per written triangle: the quantised mean of its vertices' linear colours, times ``base``."""
    _, tri = _box_faces()
    mean = linear[tri.astype(np.int64)][:, :, :3].mean(axis=1)
    return [_quantised(m * (1.0 if base is None else base)) for m in mean]


def _float_colours() -> np.ndarray:
    """RGBA float colours, one per vertex, a face's corners unlike; the first side's (faces 0, 1) nearly black:
    0.0015 linear is sRGB level 1 of 63 (trimesh's 8-bit colours would make it 0)."""
    rng = np.random.default_rng(11)
    c = rng.uniform(0.0, 1.0, size=(24, 4)).astype(np.float32)
    c[:4, :3] = [0.0015, 0.3, 0.0015]
    return c


# ------------------------------------------------------------------------------------------------ colours


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_float_color_0_without_a_material_is_linear_vertex_colour(tmp_path: Path, suffix: str) -> None:
    """No material: each face is a vertex colour material (roughness 0.5, metallic 0, as the class default) of its
    corners' mean COLOR_0, taken linear as stored (not sRGB-decoded as a PLY's); alpha not read."""
    c = _float_colours()
    a = _load(_save(tmp_path / f"float{suffix}", *_document(c)))
    want = _expected(c.astype(np.float64))
    for k, m in _face_materials(a):
        np.testing.assert_allclose(m.base_color, want[k][0], atol=1e-12)
        assert (m.name, m.roughness, m.metallic, m.emissive) == (f"vertex_colour:{want[k][1]}", 0.5, 0.0, (0, 0, 0))
    first = {m.name for k, m in _face_materials(a) if k < 2}
    assert first == {"vertex_colour:#049604"}, first  # level 1 of 63 in red and blue: byte 4


def test_normalized_ubyte_color_0_multiplies_the_base_colour_factor(tmp_path: Path) -> None:
    """A material with baseColorFactor, roughness, metallic and emission: each face's base colour is the factor
    times its corners' mean COLOR_0 (bytes / 255, linear); the rest of the material is kept; the material is
    named ``<file stem>:<material name>:#rrggbb``."""
    rng = np.random.default_rng(5)
    c = rng.integers(0, 256, size=(24, 4)).astype(np.uint8)
    factor = np.array([153, 51, 255]) / 255  # 0.6, 0.2, 1: exact in trimesh's 8-bit factors
    mat = {
        "name": "paint",
        "pbrMetallicRoughness": {"baseColorFactor": [*factor.tolist(), 1.0], "roughnessFactor": 0.25,
                                 "metallicFactor": 0.5},
        "emissiveFactor": [1.0, 0.0, 0.0],
    }  # fmt: skip
    a = _load(_save(tmp_path / "tinted.glb", *_document(c, UBYTE, mat)))
    want = _expected(c.astype(np.float64) / 255.0, factor)
    assert len({m.name for _, m in _face_materials(a)}) > 6
    for k, m in _face_materials(a):
        np.testing.assert_allclose(m.base_color, want[k][0], atol=1e-12)
        assert m.name == f"tinted:paint:{want[k][1]}"
        assert (m.roughness, m.metallic) == pytest.approx((0.25, 0.5))
        np.testing.assert_allclose(m.emissive, [GLTF_EMISSIVE_SCALE, 0.0, 0.0], rtol=1e-6)


def test_normalized_ushort_color_0_with_a_material_without_factor(tmp_path: Path) -> None:
    """No baseColorFactor (1, glTF's default): the base colour is the mean COLOR_0 itself (shorts / 65535)."""
    rng = np.random.default_rng(3)
    c = rng.integers(0, 65536, size=(24, 3)).astype(np.uint16)
    a = _load(_save(tmp_path / "plain.glb", *_document(c, USHORT, {"name": "bare"})))
    want = _expected(c.astype(np.float64) / 65535.0)
    for k, m in _face_materials(a):
        np.testing.assert_allclose(m.base_color, want[k][0], atol=1e-12)
        assert m.name == f"plain:bare:{want[k][1]}" and (m.roughness, m.metallic) == (1.0, 1.0)


@pytest.mark.parametrize("with_material", [False, True])
def test_a_hard_colour_edge_survives_the_vertex_merge(tmp_path: Path, with_material: bool) -> None:
    """Each side of the box one flat colour, its corners written once per side (a hard edge at every box edge):
    trimesh merges the corners of one place, yet every face keeps its side's colour exactly."""
    side = np.array([[255, 0, 0], [0, 0, 255], [0, 255, 0], [255, 255, 0], [255, 255, 255], [0, 255, 255]])
    c = np.repeat(side, 4, axis=0).astype(np.uint8)
    mat = {"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0]}}
    a = _load(_save(tmp_path / "edge.glb", *_document(c, UBYTE, mat if with_material else None)))
    prefix = "edge:grey:" if with_material else "vertex_colour:"
    got = {k: m.name for k, m in _face_materials(a)}
    want = {k: prefix + "#{:02x}{:02x}{:02x}".format(*side[k // 2]) for k in range(12)}
    assert got == want
    assert len(a.mesh.vertices) == 8  # merged: the edges are hard in the materials, not in the geometry


def test_without_color_0_the_material_is_unchanged(tmp_path: Path) -> None:
    """A primitive without COLOR_0 keeps its glTF material as before (one material, factor as written)."""
    mat = {"name": "plain", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.2, 1.0, 1.0]}}
    a = _load(_save(tmp_path / "nocol.glb", *_document(None, material=mat)))
    names = {m.name for _, m in _face_materials(a)}
    assert names == {"nocol:plain"}


# ---------------------------------------------------------------------------------------------- bad files


def _bad(header: dict[str, Any], binary: bytes, case: str) -> tuple[dict[str, Any], bytes]:
    acc = header["accessors"][header["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"]]
    if case == "count":
        acc["count"] = 20
    elif case == "type":
        acc["type"] = "VEC2"
    elif case == "not_normalized":
        del acc["normalized"]
    elif case == "signed":
        acc["componentType"] = 5120
    elif case == "no_accessor":
        header["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 9
    elif case in ("nan", "range"):
        c = _float_colours()
        c[7, 1] = np.nan if case == "nan" else 1.5
        return _document(c)
    return header, binary


@pytest.mark.parametrize(
    ("case", "says"),
    [
        ("count", r"meshes\[0\]\.primitives\[0\]\.attributes\.COLOR_0 \(accessors\[2\]\) has 20 colours for the 24 "
                  r"vertices of its POSITION accessor"),
        ("type", r"COLOR_0 \(accessors\[2\]\) is of type 'VEC2'; a vertex colour must be VEC3 or VEC4"),
        ("not_normalized", r"COLOR_0 \(accessors\[2\]\) has componentType 5121 \(unsigned byte, not normalized\); a "
                           r"vertex colour must be float"),
        ("signed", r"COLOR_0 \(accessors\[2\]\) has componentType 5120; a vertex colour must be float"),
        ("no_accessor", r"meshes\[0\]\.primitives\[0\]\.attributes\.COLOR_0 is 9, which names no accessor"),
        ("nan", r"meshes\[0\]\.primitives\[0\]\.attributes\.COLOR_0 \(geometry 'hull'\) has non-finite \(NaN/inf\) "
                r"values at 1 of its 24 vertices"),
        ("range", r"COLOR_0 \(geometry 'hull'\) has values outside \[0, 1\] at 1 of its 24 vertices"),
    ],
)  # fmt: skip
def test_bad_color_0_is_one_line_naming_the_file_and_the_entry(tmp_path: Path, case: str, says: str) -> None:
    """trimesh would drop a COLOR_0 of the wrong count, and read the rest as colours without a word."""
    c = np.repeat(np.array([[255, 0, 0, 255]]), 24, axis=0).astype(np.uint8)
    path = _save(tmp_path / "bad.glb", *_bad(*_document(c, UBYTE), case))
    with pytest.raises(AssetSpecError, match=says) as info:
        load_asset_file({"name": "user_hull", "mesh": str(path), **AXES})
    msg = str(info.value)
    assert info.value.field == "user_hull.mesh" and repr(str(path)) in msg and "\n" not in msg


def test_a_large_texture_is_averaged_without_a_float_per_texel() -> None:
    """A review's: a 4000 x 4000 texture (a 2 kB PNG) took 2.1 GB to average, float64 per texel, so one near PIL's
    size limit would have been killed for memory. The mean is the same, counted by level (sRGB decoded per level)."""
    import tracemalloc

    from mmusv.world.mesh_materials import _srgb_to_linear, _texture_mean
    from PIL import Image

    rng = np.random.default_rng(3)
    small = Image.fromarray(rng.integers(0, 256, size=(37, 53, 3), dtype=np.uint8))
    pix = np.asarray(small, dtype=np.float64).reshape(-1, 3) / 255.0
    for srgb in (False, True):
        want = (_srgb_to_linear(pix) if srgb else pix).mean(axis=0)
        np.testing.assert_allclose(_texture_mean(small, srgb=srgb), want, rtol=1e-12, atol=1e-15)
    big = Image.new("1", (4000, 4000), 1)
    tracemalloc.start()
    try:
        mean = _texture_mean(big, srgb=True)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    np.testing.assert_allclose(mean, [1.0, 1.0, 1.0])
    assert peak < 20e6, peak  # float64 texels: 384 MB
