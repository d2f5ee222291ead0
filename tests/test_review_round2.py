"""Defects found by the second review round of the MOT export and the user-mesh work (each test fails before its
fix): glTF emissive strengths found by material name alone, and OBJ ``usemtl`` names read differently from trimesh."""

from __future__ import annotations

import json
import struct
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.materials import all_materials
from mmusv.world.mesh_files import GLTF_EMISSIVE_SCALE
from mmusv.world.vessels import load_asset_file

pytest.importorskip("trimesh")


def _box(lo: list[float], hi: list[float]) -> tuple[np.ndarray, np.ndarray]:
    v = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])], np.float32)
    f = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1]]
    f += [[2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    return v, np.array(f, np.uint32)


def _glb(path: Path, parts: list[tuple[np.ndarray, np.ndarray, int]], materials: list[dict[str, object]]) -> Path:
    """A GLB with one mesh and node per part, each part's primitive using material ``parts[i][2]``."""
    blob, views, accessors, meshes = b"", [], [], []
    for i, (v, f, m) in enumerate(parts):
        for data in (v.tobytes(), f.tobytes()):
            views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
            blob += data
        accessors.append(
            {"bufferView": 2 * i, "componentType": 5126, "count": len(v), "type": "VEC3"}
            | {"min": v.min(0).tolist(), "max": v.max(0).tolist()}
        )
        accessors.append({"bufferView": 2 * i + 1, "componentType": 5125, "count": f.size, "type": "SCALAR"})
        meshes.append({"primitives": [{"attributes": {"POSITION": 2 * i}, "indices": 2 * i + 1, "material": m}]})
    doc = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": list(range(len(parts)))}],
        "nodes": [{"mesh": i} for i in range(len(parts))],
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob)}],
    }
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    blob += b"\0" * (-len(blob) % 4)
    head = struct.pack("<III", 0x46546C67, 2, 28 + len(js) + len(blob))
    path.write_bytes(
        head + struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(blob), 0x004E4942) + blob
    )
    return path


def _materials_of(asset: object) -> Counter[str]:
    table = all_materials()
    return Counter(table[i].name for i in asset.mesh.materials.tolist())  # type: ignore[attr-defined]


def test_unnamed_gltf_materials_keep_their_own_emissive_strengths(tmp_path: Path) -> None:
    """glTF names materials optionally; two unnamed materials, one a lamp with KHR_materials_emissive_strength 10,
    the other a plain green glow, are a valid file. The strengths were kept by material name alone, so the file was
    refused ('two materials named None have different KHR_materials_emissive_strength')."""
    hull, lamp, glow = (
        _box([-1.5, -0.5, -5], [1.5, 1.5, 5]),
        _box([-0.2, 1.5, 3], [0.2, 1.9, 3.4]),
        _box([-0.2, 1.5, -3], [0.2, 1.9, -2.6]),
    )
    mats: list[dict[str, object]] = [
        {"name": "Hull", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.3, 0.8, 1.0], "metallicFactor": 0.0}},
        {
            "emissiveFactor": [1.0, 0.5, 0.25],
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10}},
        },
        {"emissiveFactor": [0.0, 1.0, 0.0]},
    ]
    path = _glb(tmp_path / "unnamed_lamps.glb", [(*hull, 0), (*lamp, 1), (*glow, 2)], mats)
    asset = load_asset_file({"name": "review2_unnamed_lamps", "mesh": str(path)})
    assert (asset.length, asset.beam) == (10.0, 3.0)  # glTF's +Y up, +Z forward
    emissions = sorted(
        all_materials()[i].emissive for i in set(asset.mesh.materials.tolist()) if any(all_materials()[i].emissive)
    )
    s = GLTF_EMISSIVE_SCALE
    assert emissions == sorted([(0.0, s, 0.0), (10 * s, 5 * s, 2.5 * s)])


def test_obj_usemtl_with_a_hash_keeps_its_material(tmp_path: Path) -> None:
    """mmusv read ``usemtl``/``newmtl`` names up to a ``#``, trimesh's OBJ reader groups faces by the whole rest of
    the ``usemtl`` line: a material named ``Deck#2``, or a ``usemtl Hull Paint # red`` line, passed mmusv's check and
    then matched nothing in trimesh, so those faces took the class's default look without a word."""
    obj = tmp_path / "hashes.obj"
    v, f = _box([-5, -1.5, -0.5], [5, 1.5, 1.5])
    lines = ["# Blender 4.1.1", "mtllib hashes.mtl", "o Hull", *(f"v {x:g} {y:g} {z:g}" for x, y, z in v), "s 0"]
    lines += ["usemtl Hull Paint # red", *(f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f[:6])]
    lines += ["usemtl Deck#2", *(f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f[6:])]
    obj.write_text("\n".join(lines) + "\n")
    (tmp_path / "hashes.mtl").write_text(
        "newmtl Hull Paint\nNs 250.0\nKa 1 1 1\nKd 0.8 0.05 0.05\nKe 0 0 0\nd 1\nillum 2\n\n"
        "newmtl Deck#2\nKd 0.1 0.6 0.1\n"
    )
    asset = load_asset_file({"name": "review2_hashes", "mesh": str(obj)})
    used = _materials_of(asset)
    assert "class_default" not in used
    assert sorted(used.values()) == [6, 6]
    red = [all_materials()[i] for i in set(asset.mesh.materials.tolist()) if "Hull Paint" in all_materials()[i].name]
    assert len(red) == 1 and red[0].base_color == pytest.approx((0.8, 0.05, 0.05))


def test_a_bad_texture_is_one_line_when_another_library_patched_pillow(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ultralytics (a peer reader of the YOLO export) replaces ``PIL.Image.open`` on import with one that answers a
    file Pillow cannot identify by loading its HEIF plugin: ``ModuleNotFoundError: No module named 'pi_heif'`` came
    out of ``load_asset_file`` as a traceback instead of the one-line error naming the texture (and
    ``pytest tests/export tests/world`` failed two user-mesh tests, run after tests/export imported it)."""
    from PIL import Image, UnidentifiedImageError

    original = Image.open

    def ultralytics_like_open(filename: object, *args: object, **kwargs: object) -> object:
        try:
            return original(filename, *args, **kwargs)  # type: ignore[arg-type]
        except UnidentifiedImageError:
            raise ModuleNotFoundError("No module named 'pi_heif'") from None

    monkeypatch.setattr(Image, "open", ultralytics_like_open)
    obj = tmp_path / "badtex.obj"
    v, f = _box([-5, -1.5, -0.5], [5, 1.5, 1.5])
    lines = ["mtllib badtex.mtl", *(f"v {x:g} {y:g} {z:g}" for x, y, z in v), "usemtl hull"]
    obj.write_text("\n".join([*lines, *(f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f)]) + "\n")
    (tmp_path / "badtex.mtl").write_text("newmtl hull\nmap_Kd hull.png\n")
    (tmp_path / "hull.png").write_bytes(b"not a png at all")
    with pytest.raises(AssetSpecError, match=r"map_Kd 'hull\.png'.* is not an image") as err:
        load_asset_file({"name": "review2_badtex", "mesh": str(obj)})
    assert "\n" not in str(err.value)
