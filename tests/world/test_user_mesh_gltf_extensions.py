"""glTF extensions in user meshes: Draco-compressed geometry is decoded (DracoPy, trimesh's decoder) to the shape an
uncompressed export of the same mesh gives, within Draco's own quantisation; a file that requires an extension mmusv
does not read, or whose ``POSITION`` trimesh would misread (normalized integers, a sparse accessor), is refused with
one line naming the file, the entry and what to do, where trimesh would read on and give zeros or a wrong shape
without a word. Integer positions (``KHR_mesh_quantization`` without ``normalized``) are read as their numbers."""

from __future__ import annotations

import base64
import json
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.vessels import VesselAsset, load_asset_file

trimesh = pytest.importorskip("trimesh")

AXES = {"up_axis": "z", "forward_axis": "x"}
"""The files' frame is the body frame (z up, x forward)."""


def _load(path: Path) -> VesselAsset:
    """The asset of ``path`` (named ``user_hull``), failing on any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return load_asset_file({"name": "user_hull", "mesh": str(path), "draft": 1.0, **AXES})


def _hull() -> Any:
    """A 12 m by 4 m by 3 m hull-sized ellipsoid of 1,280 triangles (an icosphere scaled), keel at z = -1."""
    m = trimesh.creation.icosphere(subdivisions=3)
    m.apply_scale([6.0, 2.0, 1.5])
    m.apply_translation([0.0, 0.0, 0.5])
    return m


def test_draco_compressed_glb_is_decoded_to_the_uncompressed_shape(tmp_path: Path) -> None:
    """The same mesh exported as GLB with and without Draco (trimesh's exporter, DracoPy's encoder) loads to the
    same triangles: every vertex within Draco's position quantisation (14 bits over the extent: 0.8 mm here) of the
    uncompressed one, the same faces, the same box. Before, without DracoPy, the geometry came back as zeros."""
    from trimesh.exchange.gltf import export_glb

    hull = _hull()
    plain, packed = tmp_path / "plain.glb", tmp_path / "draco.glb"
    plain.write_bytes(export_glb(trimesh.Scene(hull)))
    packed.write_bytes(export_glb(trimesh.Scene(hull), extension_draco=True))
    assert b"KHR_draco_mesh_compression" in packed.read_bytes() and packed.stat().st_size < plain.stat().st_size
    a, b = _load(plain), _load(packed)
    assert a.mesh.faces.shape == b.mesh.faces.shape == (1280, 3)
    tol = 12.0 / 2**14 * 1.5
    # Vertex by vertex: each decoded vertex beside one uncompressed vertex, and the faces the same corners.
    va, vb = np.asarray(a.mesh.vertices, np.float64), np.asarray(b.mesh.vertices, np.float64)
    nearest = np.argmin(np.linalg.norm(vb[:, None, :] - va[None, :, :], axis=2), axis=1)
    assert np.abs(vb - va[nearest]).max() < tol
    assert len(set(nearest.tolist())) == len(va)
    fa = {tuple(sorted(f)) for f in a.mesh.faces.tolist()}
    fb = {tuple(sorted(nearest[f].tolist())) for f in b.mesh.faces}
    assert fa == fb
    assert abs(a.length - b.length) < 2 * tol and abs(a.beam - b.beam) < 2 * tol


def test_draco_without_its_decoder_is_a_clear_error(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Where DracoPy cannot be imported, a Draco GLB is refused naming the file and the package (trimesh would print a
    warning and give zeros)."""
    from trimesh.exchange.gltf import export_glb

    packed = tmp_path / "draco.glb"
    packed.write_bytes(export_glb(trimesh.Scene(_hull()), extension_draco=True))
    monkeypatch.setitem(sys.modules, "DracoPy", None)  # import DracoPy raises ImportError
    with pytest.raises(AssetSpecError) as err:
        _load(packed)
    msg = str(err.value)
    assert "draco.glb" in msg and "KHR_draco_mesh_compression" in msg and "pip install DracoPy" in msg
    assert "\n" not in msg


def _gltf(
    path: Path,
    positions: np.ndarray,
    *,
    component: int = 5126,
    required: Any = None,
    **accessor: Any,
) -> Path:
    """A one-primitive glTF of the triangles ``positions`` ``(3k, 3)`` written as ``component`` (5126 float, 5123
    unsigned short), with ``accessor``'s extra fields on the POSITION accessor and ``required`` as
    ``extensionsRequired``."""
    dtype = {5126: np.float32, 5123: np.uint16}[component]
    raw = positions.astype(dtype).tobytes()
    raw += b"\0" * (-len(raw) % 4)
    pos = {
        "bufferView": 0,
        "componentType": component,
        "count": len(positions),
        "type": "VEC3",
        "min": positions.min(0).tolist(),
        "max": positions.max(0).tolist(),
        **accessor,
    }
    doc: dict[str, Any] = {
        "asset": {"version": "2.0"},
        "buffers": [
            {"byteLength": len(raw), "uri": "data:application/octet-stream;base64," + base64.b64encode(raw).decode()}
        ],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(raw)}],
        "accessors": [pos],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    if required is not None:
        doc["extensionsUsed"] = required if isinstance(required, list) else []
        doc["extensionsRequired"] = required
    path.write_text(json.dumps(doc))
    return path


def _tetra() -> np.ndarray:
    """Four outward triangles of a tetrahedron 10 m long, 4 m wide, 3 m high (whole metres), as ``(12, 3)``."""
    p = np.array([[0, 0, 0], [10, 0, 0], [5, 4, 0], [5, 2, 3]], dtype=np.float64)
    return p[[0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3]]


def test_integer_positions_are_read_as_their_numbers(tmp_path: Path) -> None:
    """``KHR_mesh_quantization``'s unsigned-short positions without ``normalized`` are the numbers they store: the
    same shape as the float file."""
    f = _load(_gltf(tmp_path / "float.gltf", _tetra()))
    q = _load(_gltf(tmp_path / "quant.gltf", _tetra(), component=5123, required=["KHR_mesh_quantization"]))
    np.testing.assert_array_equal(np.sort(q.mesh.vertices, axis=0), np.sort(f.mesh.vertices, axis=0))
    assert q.length == f.length == 10.0


@pytest.mark.parametrize(
    ("label", "kwargs", "words"),
    [
        (
            "meshopt required",
            {"required": ["EXT_meshopt_compression"]},
            "requires the glTF extension 'EXT_meshopt_compression' (extensionsRequired), which mmusv does not read",
        ),
        ("required not a list", {"required": "KHR_draco_mesh_compression"}, "extensionsRequired must be a list"),
        (
            "normalized positions",
            {"component": 5123, "normalized": True, "required": ["KHR_mesh_quantization"]},
            "attributes.POSITION (accessors[0]) is a normalized integer accessor",
        ),
        (
            "sparse positions",
            {"sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5123}, "values": {"bufferView": 0}}},
            "attributes.POSITION (accessors[0]) is a sparse accessor",
        ),
    ],
)
def test_files_trimesh_would_misread_are_refused(
    tmp_path: Path, label: str, kwargs: dict[str, Any], words: str
) -> None:
    """Each is one line naming the file, the entry and what is wrong; before, each loaded a wrong shape or zeros
    without a word."""
    path = _gltf(tmp_path / "hull.gltf", _tetra(), **kwargs)
    with pytest.raises(AssetSpecError) as err:
        _load(path)
    msg = str(err.value)
    assert words in msg and "hull.gltf" in msg and "\n" not in msg, (label, msg)


def _draco_with_fallback(path: Path) -> Path:
    """A GLB of the hull whose primitive is Draco-compressed and also stored plain (every accessor has its
    bufferView), Draco in ``extensionsUsed`` only: a reader without a decoder reads the plain accessors (glTF 2.0)."""
    import struct

    import DracoPy

    hull = _hull()
    v, f = hull.vertices.astype(np.float32), hull.faces.astype(np.uint32)
    blob = DracoPy.encode(v, f, quantization_bits=14)
    position_id = DracoPy.decode(blob).attributes[0]["unique_id"]
    views, data = [], b""
    for chunk in (blob, v.tobytes(), f.tobytes()):
        views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(chunk)})
        data += chunk + b"\0" * (-len(chunk) % 4)
    draco = {"bufferView": 0, "attributes": {"POSITION": position_id}}
    doc = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_draco_mesh_compression"],
        "buffers": [{"byteLength": len(data)}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 2, "componentType": 5125, "type": "SCALAR", "count": int(f.size)},
            {
                "bufferView": 1,
                "componentType": 5126,
                "type": "VEC3",
                "count": len(v),
                "min": v.min(0).tolist(),
                "max": v.max(0).tolist(),
            },
        ],
        "meshes": [
            {
                "primitives": [
                    {"attributes": {"POSITION": 1}, "indices": 0, "extensions": {"KHR_draco_mesh_compression": draco}}
                ]
            }
        ],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(data), 0x004E4942) + data
    path.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
    return path


def test_draco_with_a_fallback_loads_with_or_without_its_decoder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Draco only in ``extensionsUsed``, the geometry also stored plain: decoded where DracoPy is installed, read
    from the plain accessors where it is not (was: refused, "needs the DracoPy package")."""
    path = _draco_with_fallback(tmp_path / "fallback.glb")
    decoded = _load(path)
    monkeypatch.setitem(sys.modules, "DracoPy", None)  # import DracoPy raises ImportError
    plain = _load(path)
    assert decoded.mesh.faces.shape == plain.mesh.faces.shape == (1280, 3)
    tol = 12.0 / 2**14 * 1.5
    assert abs(decoded.length - plain.length) < 2 * tol and abs(decoded.beam - plain.beam) < 2 * tol
    np.testing.assert_allclose(np.sort(plain.mesh.vertices, axis=0), np.sort(decoded.mesh.vertices, axis=0), atol=tol)


@pytest.mark.parametrize(
    ("label", "change", "words"),
    [
        ("scene out of range", lambda d: d.update(scene=5), "scene is 5, but the file has 1 scenes (indices 0..0)"),
        ("no scenes", lambda d: d.update(scenes=[]), "scene is 0, but the file has 0 scenes (none)"),
        (
            "material out of range",
            lambda d: d["meshes"][0]["primitives"][0].update(material=7),
            "meshes[0].primitives[0].material is 7, but the file has 0 materials (none)",
        ),
        (
            "base colour out of [0, 1]",
            lambda d: d.update(materials=[{"pbrMetallicRoughness": {"baseColorFactor": [5, -1, 0.5, 1]}}]),
            "materials[0].pbrMetallicRoughness.baseColorFactor is [5, -1, 0.5, 1]; glTF 2.0 allows 4 numbers in [0, 1]",
        ),
        (
            "roughness below 0",
            lambda d: d.update(materials=[{"pbrMetallicRoughness": {"roughnessFactor": -3}}]),
            "materials[0].pbrMetallicRoughness.roughnessFactor is -3; glTF 2.0 allows a number in [0, 1]",
        ),
        (
            "emissive too short",
            lambda d: d.update(materials=[{"emissiveFactor": [1, 1]}]),
            "materials[0].emissiveFactor is [1, 1]; glTF 2.0 allows 3 numbers in [0, 1]",
        ),
    ],
)
def test_indices_and_factors_out_of_range_are_named(tmp_path: Path, label: str, change: Any, words: str) -> None:
    """A review's: a scene or material index out of range failed inside trimesh with a bare ``IndexError: list index
    out of range``, and material factors outside glTF's [0, 1] (NaN too) were clamped without a word (trimesh keeps
    colour factors as bytes), where an OBJ's ``Kd`` out of [0, 1] is refused."""
    path = _gltf(tmp_path / "hull.gltf", _tetra())
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))
    with pytest.raises(AssetSpecError) as err:
        _load(path)
    msg = str(err.value)
    assert words in msg and "hull.gltf" in msg and "\n" not in msg, (label, msg)
