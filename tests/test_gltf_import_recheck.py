"""An independent re-check of the glTF/GLB import against the glTF 2.0 specification (Khronos): files built here by
hand (JSON and one binary buffer, no exporter), each expectation written from the spec, not from mmusv's code.

Axes: glTF is right-handed, +Y up, the front of an asset faces +Z, +X is its left (spec 3.4), in metres; so the
body frame (x bow, y port, z up) is x = file z, y = file x, z = file y. A node's ``matrix`` is column-major, its TRS
is T * R * S with a unit quaternion ``[x, y, z, w]``, a child's transform is its parent's times its own (3.5.2-3.5.3);
a mesh two nodes name is drawn twice; ``scene`` picks the scene. Materials (3.9): ``baseColorFactor`` is linear and
defaults to 1, ``metallicFactor`` and ``roughnessFactor`` default to 1, ``emissiveFactor`` to 0; the base colour
texture is sRGB-encoded. A malformed file is one ``AssetSpecError`` naming the file and what is wrong.
"""

from __future__ import annotations

import io
import json
import struct
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import polars as pl
import pytest
import yaml
from mmusv.cli import main
from mmusv.scenario_checks import MmusvWarning
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.materials import Material, all_materials
from mmusv.world.mesh_files import GLTF_EMISSIVE_SCALE
from mmusv.world.vessels import VesselAsset, load_asset_file
from user_assets import library_restored

pytest.importorskip("trimesh")

FLOAT, UBYTE, USHORT = 5126, 5121, 5123
HULL = ((-1.0, -0.5, -5.0), (1.0, 1.5, 5.0))
"""A hull box in file coordinates: 2 m wide (x), 2 m tall with 0.5 m below y = 0, 10 m long (z)."""
MARK = ((0.2, 1.0, 3.0), (0.8, 1.4, 4.5))
"""A small box forward (+z) on the left (+x), above the waterline: where the bow and port side end up."""


class Doc:
    """A glTF 2.0 document written by hand: one buffer, boxes as indexed triangle lists (outward, counter-clockwise
    seen from outside, as the spec's front faces are)."""

    def __init__(self) -> None:
        self.blob = bytearray()
        self.j: dict[str, Any] = {
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [],
            "nodes": [],
            "meshes": [],
            "materials": [],
            "accessors": [],
            "bufferViews": [],
        }

    def view(self, raw: bytes) -> int:
        off = len(self.blob)
        self.blob += raw + b"\0" * (-len(raw) % 4)
        self.j["bufferViews"].append({"buffer": 0, "byteOffset": off, "byteLength": len(raw)})
        return len(self.j["bufferViews"]) - 1

    def accessor(self, a: np.ndarray, comp: int, kind: str) -> int:
        acc = {"bufferView": self.view(a.tobytes()), "componentType": comp, "count": len(a), "type": kind}
        if kind == "VEC3" and comp == FLOAT:
            acc |= {"min": a.min(0).tolist(), "max": a.max(0).tolist()}
        self.j["accessors"].append(acc)
        return len(self.j["accessors"]) - 1

    def box(self, lo: Any, hi: Any, material: int | None = None, uv: bool = False) -> dict[str, Any]:
        """A primitive: the box from ``lo`` to ``hi`` (8 corners, 12 triangles)."""
        corner = [[(lo, hi)[(i >> k) & 1][k] for k in range(3)] for i in range(8)]  # bit 0: x, 1: y, 2: z
        tri = [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4]]
        tri += [[2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]]
        attrs = {"POSITION": self.accessor(np.array(corner, np.float32), FLOAT, "VEC3")}
        if uv:
            attrs["TEXCOORD_0"] = self.accessor(np.linspace(0, 1, 16, dtype=np.float32).reshape(8, 2), FLOAT, "VEC2")
        prim: dict[str, Any] = {
            "attributes": attrs,
            "indices": self.accessor(np.array(tri, np.uint16).ravel(), USHORT, "SCALAR"),
        }
        if material is not None:
            prim["material"] = material
        return prim

    def add(self, kind: str, **item: Any) -> int:
        self.j[kind].append(item)
        return len(self.j[kind]) - 1

    def mesh(self, *prims: dict[str, Any]) -> int:
        return self.add("meshes", primitives=list(prims))

    def image(self, png: bytes) -> int:
        self.j.setdefault("images", []).append({"bufferView": self.view(png), "mimeType": "image/png"})
        self.j.setdefault("textures", []).append({"source": len(self.j["images"]) - 1})
        return len(self.j["textures"]) - 1

    def document(self, uri: str | None = None) -> dict[str, Any]:
        j = {k: v for k, v in json.loads(json.dumps(self.j)).items() if v != []}
        j["buffers"] = [{"byteLength": len(self.blob), **({"uri": uri} if uri else {})}]
        return j

    def glb(self, path: Path) -> Path:
        js = json.dumps(self.document()).encode()
        js += b" " * (-len(js) % 4)
        chunks = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(self.blob), 0x004E4942)
        path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks) + len(self.blob)) + chunks + self.blob)
        return path

    def gltf(self, path: Path) -> Path:
        path.with_suffix(".bin").write_bytes(bytes(self.blob))
        path.write_text(json.dumps(self.document(path.with_suffix(".bin").name)), encoding="utf-8")
        return path


def _hull_doc(material: dict[str, Any] | None = None) -> Doc:
    d = Doc()
    m = d.add("materials", **material) if material is not None else None
    d.add("scenes", nodes=[d.add("nodes", mesh=d.mesh(d.box(*HULL, material=m)))])
    return d


def _load(path: Path, **entry: Any) -> VesselAsset:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return load_asset_file({"name": path.stem, "mesh": str(path), **entry})


def _materials_of(asset: VesselAsset) -> dict[str, tuple[Material, int]]:
    """Each material of the asset by the name it has in its file (``<stem>:<name>``'s last part): (it, its faces)."""
    table = all_materials()
    ids, counts = np.unique(asset.mesh.materials, return_counts=True)
    return {table[i].name.split(":")[-1]: (table[i], int(n)) for i, n in zip(ids, counts, strict=True)}


# ------------------------------------------------------------------------------------------------------ axes


def _quat(x: float, y: float, z: float, w: float) -> np.ndarray:
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _trs(t: Any = (0, 0, 0), r: Any = (0, 0, 0, 1), s: Any = (1, 1, 1)) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = _quat(*r) @ np.diag(s)
    m[:3, 3] = t
    return m


def _expected_boxes(parts: list[tuple[str, np.ndarray]]) -> dict[str, tuple[np.ndarray, np.ndarray, int]]:
    """Body-frame bounds and face count per material of boxes HULL ("A") and MARK ("B") placed by world matrices:
    body (x, y, z) = file (z, x, y), then centred in x and y on the whole mesh's bounding box."""
    body: dict[str, list[np.ndarray]] = {}
    for name, world in parts:
        lo, hi = HULL if name == "A" else MARK
        c = np.array([[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        body.setdefault(name, []).append((c @ world.T)[:, [2, 0, 1]])
    every = np.concatenate([np.concatenate(v) for v in body.values()])
    shift = np.array([*((every.min(0) + every.max(0)) / 2)[:2], 0.0])
    return {
        k: (np.concatenate(v).min(0) - shift, np.concatenate(v).max(0) - shift, 12 * len(v)) for k, v in body.items()
    }


ROT = (0.1, 0.2, 0.05, float(np.sqrt(1 - 0.01 - 0.04 - 0.0025)))
YAW90 = (0.0, float(np.sqrt(0.5)), 0.0, float(np.sqrt(0.5)))
SPIN = _trs((0.3, 0.1, 2.0), (0.0, float(np.sin(np.pi / 12)), 0.0, float(np.cos(np.pi / 12))), (1.2, 0.9, 1.1))
PLACEMENTS: dict[str, tuple[Any, Any]] = {
    # name: (how the file places the boxes: scenes and nodes built on Doc d with meshes h (HULL) and m (MARK),
    #        the world matrices the spec gives them)
    "identity": (
        lambda d, h, m: [[d.add("nodes", mesh=h), d.add("nodes", mesh=m)]],
        [("A", np.eye(4)), ("B", np.eye(4))],
    ),
    "column-major matrix": (
        lambda d, h, m: [[d.add("nodes", mesh=h), d.add("nodes", mesh=m, matrix=SPIN.T.ravel().tolist())]],
        [("A", np.eye(4)), ("B", SPIN)],
    ),
    "TRS order": (
        lambda d, h, m: [
            [
                d.add("nodes", mesh=h),
                d.add("nodes", mesh=m, translation=[0.2, 0.3, -1], rotation=list(ROT), scale=[2, 0.5, 1]),
            ]
        ],
        [("A", np.eye(4)), ("B", _trs((0.2, 0.3, -1), ROT, (2, 0.5, 1)))],
    ),
    "nested nodes": (
        lambda d, h, m: [
            [d.add("nodes", mesh=h, translation=[0, 0.5, 1], scale=[2, 2, 2],
                   children=[d.add("nodes", mesh=m, translation=[0.1, 0, 0.5], rotation=list(YAW90))])]
        ],
        [("A", _trs((0, 0.5, 1), s=(2, 2, 2))), ("B", _trs((0, 0.5, 1), s=(2, 2, 2)) @ _trs((0.1, 0, 0.5), YAW90))],
    ),
    "one mesh, two nodes": (
        lambda d, h, m: [
            [d.add("nodes", mesh=h), d.add("nodes", mesh=m), d.add("nodes", mesh=m, translation=[-1, 0, -7])]
        ],
        [("A", np.eye(4)), ("B", np.eye(4)), ("B", _trs((-1, 0, -7)))],
    ),
    "mirrored node": (
        lambda d, h, m: [[d.add("nodes", mesh=h), d.add("nodes", mesh=m, scale=[-1, 1, 1])]],
        [("A", np.eye(4)), ("B", _trs(s=(-1, 1, 1)))],
    ),
    "second scene": (
        lambda d, h, m: [[d.add("nodes", mesh=h), d.add("nodes", mesh=m)], [d.add("nodes", mesh=h, scale=[1, 1, 2])]],
        [("A", _trs(s=(1, 1, 2)))],
    ),
}  # fmt: skip


@pytest.mark.parametrize("case", list(PLACEMENTS))
def test_node_transforms_and_axes_place_each_box_where_the_spec_says(tmp_path: Path, case: str) -> None:
    build, parts = PLACEMENTS[case]
    d = Doc()
    a, b = d.add("materials", name="A"), d.add("materials", name="B")
    h, m = d.mesh(d.box(*HULL, material=a)), d.mesh(d.box(*MARK, material=b))
    scenes = build(d, h, m)
    for nodes in scenes:
        d.add("scenes", nodes=nodes)
    d.j["scene"] = len(scenes) - 1  # the last scene: "second scene" leaves the first's nodes out
    asset = _load(d.glb(tmp_path / f"place_{case.replace(' ', '_').replace(',', '')}.glb"))
    got = _materials_of(asset)
    want = _expected_boxes(parts)
    assert set(got) == set(want)
    for name, (lo, hi, faces) in want.items():
        verts = asset.mesh.vertices[
            np.unique(asset.mesh.faces[asset.mesh.materials == all_materials().index(got[name][0])])
        ]
        np.testing.assert_allclose(verts.min(0), lo, atol=1e-5, err_msg=f"{case}: {name}")
        np.testing.assert_allclose(verts.max(0), hi, atol=1e-5, err_msg=f"{case}: {name}")
        assert got[name][1] == faces, case
    # every face faces outward (a mirrored node's winding reverses, spec 3.7.2.1): positive enclosed volume per box
    tri = asset.mesh.vertices[asset.mesh.faces]
    signed = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
    for name, (mat, _) in got.items():
        sel = asset.mesh.materials == all_materials().index(mat)
        assert signed[sel].sum() > 0.0, f"{case}: {name} faces inward"


def test_the_bow_is_plus_z_and_port_plus_x_and_the_box_is_the_meshs_extents(tmp_path: Path) -> None:
    d = Doc()
    a, b = d.add("materials", name="A"), d.add("materials", name="B")
    d.add("scenes", nodes=[d.add("nodes", mesh=d.mesh(d.box(*HULL, material=a), d.box(*MARK, material=b)))])
    asset = _load(d.glb(tmp_path / "bow.glb"))
    assert (asset.length, asset.beam, asset.height, asset.draft) == pytest.approx((10.0, 2.0, 2.0, 0.5))
    mark = asset.mesh.vertices[
        np.unique(asset.mesh.faces[asset.mesh.materials == all_materials().index(_materials_of(asset)["B"][0])])
    ]
    assert mark[:, 0].min() > 0 and mark[:, 1].min() > 0 and mark[:, 2].min() > 0  # forward, to port, above water


# ------------------------------------------------------------------------------------------------- materials


def test_material_factors_defaults_and_primitives_without_one(tmp_path: Path) -> None:
    d = Doc()
    bare = d.add("materials", name="bare")  # every factor absent: base colour 1, metallic 1, roughness 1, emission 0
    paint = d.add(
        "materials",
        name="paint",
        pbrMetallicRoughness={"baseColorFactor": [0.25, 0.5, 0.75, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.4},
    )
    lamp = d.add(
        "materials",
        name="lamp",
        emissiveFactor=[1.0, 0.5, 0.0],
        extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
    )
    prims = [d.box(*HULL, material=bare), d.box((-0.5, 1.5, -2), (0.5, 2.5, 2), material=paint)]
    prims += [d.box((-0.2, 1.5, 3), (0.2, 1.9, 3.4), material=lamp), d.box((-0.2, 1.5, -4), (0.2, 1.9, -3.6))]
    d.add("scenes", nodes=[d.add("nodes", mesh=d.mesh(*prims))])
    got = _materials_of(_load(d.glb(tmp_path / "factors.glb")))
    assert set(got) == {"bare", "paint", "lamp", "class_default"} and {n for _, n in got.values()} == {12}
    m = got["bare"][0]
    assert (m.base_color, m.metallic, m.roughness, m.emissive) == ((1.0, 1.0, 1.0), 1.0, 1.0, (0.0, 0.0, 0.0))
    m = got["paint"][0]
    assert (m.metallic, m.roughness) == (0.0, 0.4)
    np.testing.assert_allclose(m.base_color, (0.25, 0.5, 0.75), atol=1e-6)  # linear: taken as written
    m = got["lamp"][0]
    np.testing.assert_allclose(m.emissive, np.array([1.0, 0.5, 0.0]) * 4.0 * GLTF_EMISSIVE_SCALE)


def _png(pixels: np.ndarray) -> bytes:
    from PIL import Image

    out = io.BytesIO()
    Image.fromarray(pixels).save(out, "PNG")
    return out.getvalue()


def _srgb_decode(byte: np.ndarray) -> np.ndarray:
    c = np.asarray(byte, dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _textured(tmp_path: Path, name: str, png: bytes, **pbr: Any) -> Path:
    d = Doc()
    t = d.image(png)
    m = d.add("materials", name="tex", pbrMetallicRoughness={"baseColorTexture": {"index": t}, **pbr})
    d.add("scenes", nodes=[d.add("nodes", mesh=d.mesh(d.box(*HULL, material=m, uv=True)))])
    return d.glb(tmp_path / f"{name}.glb")


def test_a_base_colour_texture_is_decoded_from_srgb_averaged_and_times_the_factor(tmp_path: Path) -> None:
    texels = np.array([[[200, 100, 50], [10, 20, 30], [0, 0, 0], [255, 255, 255]]], np.uint8)
    factor = [0.5, 0.25, 1.0, 1.0]
    got = _materials_of(_load(_textured(tmp_path, "texture", _png(texels), baseColorFactor=factor)))["tex"][0]
    want = _srgb_decode(texels[0]).mean(0) * factor[:3]
    np.testing.assert_allclose(got.base_color, want, rtol=1e-6)


def test_a_16_bit_grey_base_colour_texture_is_read_at_its_level(tmp_path: Path) -> None:
    """PNG allows 16 bits a channel (glTF takes any PNG): grey 32768 of 65535 is sRGB 0.5, not white."""
    texels = np.full((2, 2), 32768, np.uint16)
    got = _materials_of(_load(_textured(tmp_path, "grey16", _png(texels))))["tex"][0]
    want = float(_srgb_decode(np.array([32768 / 65535 * 255]))[0])
    np.testing.assert_allclose(got.base_color, (want, want, want), rtol=1e-4)


@pytest.mark.parametrize(
    ("case", "edit", "words"),
    [
        ("not an image", lambda d: d.blob.__setitem__(slice(-8, None), b"notapng!"), "images[0]"),
        (
            "no such texture",
            lambda d: d.j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"].update(index=3),
            "textures",
        ),
        ("texture without image", lambda d: d.j["textures"][0].pop("source"), "textures[0]"),
    ],
)
def test_a_base_colour_texture_that_cannot_be_read_is_an_error_not_white(
    tmp_path: Path, case: str, edit: Any, words: str
) -> None:
    """trimesh leaves such a texture out without a word (the hull came out the factor's colour: white)."""
    d = Doc()
    t = d.image(b"\x89PNG\r\n\x1a\n" + b"not-really-a-png")
    m = d.add("materials", name="tex", pbrMetallicRoughness={"baseColorTexture": {"index": t}})
    d.add("scenes", nodes=[d.add("nodes", mesh=d.mesh(d.box(*HULL, material=m, uv=True)))])
    if case != "not an image":
        d = Doc()
        t = d.image(_png(np.zeros((1, 2, 3), np.uint8)))
        m = d.add("materials", name="tex", pbrMetallicRoughness={"baseColorTexture": {"index": t}})
        d.add("scenes", nodes=[d.add("nodes", mesh=d.mesh(d.box(*HULL, material=m, uv=True)))])
        edit(d)
    path = d.glb(tmp_path / f"{case.replace(' ', '_')}.glb")
    with pytest.raises(AssetSpecError) as info:
        _load(path)
    msg = str(info.value)
    assert str(path) in msg and "baseColorTexture" in msg and words in msg, msg


# ------------------------------------------------------------------------------------------- malformed files


def _patched(edit: Any) -> Any:
    def make(tmp: Path, name: str) -> Path:
        d = _hull_doc()
        edit(d)
        return d.glb(tmp / f"{name}.glb")

    return make


def _raw(data: Any, suffix: str = ".glb") -> Any:
    def make(tmp: Path, name: str) -> Path:
        p = tmp / f"{name}{suffix}"
        good = _hull_doc().glb(tmp / "whole.glb").read_bytes()
        p.write_bytes(data(good) if callable(data) else data)
        return p

    return make


def _nan(d: Doc) -> None:
    v = np.frombuffer(bytes(d.blob[:96]), np.float32).copy()
    v[4] = np.nan
    d.blob[:96] = v.tobytes()
    for k in ("min", "max"):
        d.j["accessors"][0].pop(k)


def _zero_triangles(d: Doc) -> None:
    d.j["accessors"][1]["count"] = 0


def _factor(pbr: dict[str, Any]) -> Any:
    return _patched(
        lambda d: (
            d.j.__setitem__("materials", [{"name": "m", "pbrMetallicRoughness": pbr}])
            or d.j["meshes"][0]["primitives"][0].__setitem__("material", 0)
        )
    )


def _no_uri(tmp: Path, name: str) -> Path:
    p = tmp / f"{name}.gltf"
    p.write_text(json.dumps(_hull_doc().document()), encoding="utf-8")  # a .gltf's buffer needs its uri
    return p


def _missing_bin(tmp: Path, name: str) -> Path:
    p = _hull_doc().gltf(tmp / f"{name}.gltf")
    p.with_suffix(".bin").unlink()
    return p


MALFORMED: dict[str, tuple[Any, str]] = {
    "truncated GLB": (_raw(lambda b: b[: len(b) // 2]), "truncated"),
    "bad magic": (_raw(lambda b: b"glTX" + b[4:]), "'glTF' magic"),
    "JSON that is not glTF": (_raw(b'{"hello": "world"}', ".gltf"), "not a glTF file"),
    "JSON list": (_raw(b"[1, 2]", ".gltf"), "not a glTF file"),
    "accessor past its buffer": (_patched(lambda d: d.j["accessors"][0].__setitem__("count", 1000)), "cannot read"),
    "index past the vertices": (
        _patched(lambda d: d.blob.__setitem__(slice(96, 98), struct.pack("<H", 500))), "index 500"
    ),
    "accessor index out of range": (
        _patched(lambda d: d.j["meshes"][0]["primitives"][0].__setitem__("indices", 9)), "indices is 9"
    ),
    "missing .bin": (_missing_bin, "which is missing"),
    "buffer without uri": (_no_uri, "buffers[0] has no uri"),
    "NaN vertex": (_patched(_nan), "non-finite"),
    "zero triangles": (_patched(_zero_triangles), "no triangles"),
    "a triangle fan": (_patched(lambda d: d.j["meshes"][0]["primitives"][0].__setitem__("mode", 6)), "TRIANGLE_FAN"),
    "POSITION of two numbers": (_patched(lambda d: d.j["accessors"][0].__setitem__("type", "VEC2")), "POSITION"),
    "float indices": (_patched(lambda d: d.j["accessors"][1].__setitem__("componentType", FLOAT)), "SCALAR unsigned"),
    "matrix and TRS": (
        _patched(lambda d: d.j["nodes"][0].update(matrix=np.eye(4).ravel().tolist(), translation=[0, 1, 0])), "matrix"
    ),
    "zero quaternion": (_patched(lambda d: d.j["nodes"][0].update(rotation=[0, 0, 0, 0])), "rotation"),
    "a node its own child": (_patched(lambda d: d.j["nodes"][0].update(children=[0])), "nodes[0]"),
    "huge scale": (_patched(lambda d: d.j["nodes"][0].__setitem__("scale", [1e6, 1e6, 1e6])), "out of range"),
    "baseColorFactor above 1": (_factor({"baseColorFactor": [1.5, 0.5, 0.5, 1.0]}), "baseColorFactor"),
    "negative baseColorFactor": (_factor({"baseColorFactor": [-0.1, 0.5, 0.5, 1.0]}), "baseColorFactor"),
    "roughness above 1": (_factor({"roughnessFactor": 1.5}), "roughnessFactor"),
    "negative roughness": (_factor({"roughnessFactor": -0.5}), "roughnessFactor"),
    # glTF draws what its scene's nodes place (spec 3.5.1); points and lines have no surface (3.7.2.1)
    "meshes but no scene": (_patched(lambda d: (d.j.pop("scene"), d.j.__setitem__("scenes", []))), "has no scene"),
    "a scene placing no mesh": (_patched(lambda d: d.j["nodes"][0].pop("mesh")), "place no primitive of its 1 meshes"),
    "a scene placing a mesh without primitives": (
        _patched(lambda d: d.j["meshes"].append({"primitives": []}) or d.j["nodes"][0].__setitem__("mesh", 1)),
        "scenes[0], whose nodes place no primitive of its 2 meshes",
    ),
    "points only": (_patched(lambda d: d.j["meshes"][0]["primitives"][0].__setitem__("mode", 0)), "POINTS"),
    "lines only": (_patched(lambda d: d.j["meshes"][0]["primitives"][0].__setitem__("mode", 3)), "LINE_STRIP"),
}  # fmt: skip


@pytest.mark.parametrize("case", list(MALFORMED))
def test_a_malformed_file_is_one_error_naming_the_file_and_the_fault(tmp_path: Path, case: str) -> None:
    make, words = MALFORMED[case]
    path = make(tmp_path, case.replace(" ", "_").replace(".", ""))
    with pytest.raises(AssetSpecError) as info:
        _load(path)
    msg = str(info.value)
    assert str(path) in msg and words in msg and "\n" not in msg, msg


def test_lines_beside_triangles_are_left_out_with_a_warning_naming_them(tmp_path: Path) -> None:
    # A hull's box and an outline of it as LINES (a mode glTF 2.0 defines, 3.7.2.1): the box's 12 triangles are
    # read, the lines (no surface) left out, which was without a word.
    d = _hull_doc()
    outline = dict(d.j["meshes"][0]["primitives"][0], mode=1)
    d.j["meshes"][0]["primitives"].append(outline)
    path = d.glb(tmp_path / "outlined.glb")
    with pytest.warns(
        MmusvWarning, match=r"1 primitive\(s\) of points or lines left out \(meshes\[0\]\.primitives\[1\] LINES\)"
    ):
        asset = load_asset_file({"name": "outlined", "mesh": str(path)})
    assert asset.num_triangles == 12


# ------------------------------------------------------------------------------------------ the whole path


@pytest.fixture
def _clean_library() -> Iterator[None]:
    with library_restored():
        yield


def _scenario(folder: Path, glb: Path) -> Path:
    (folder / "boats").mkdir(parents=True, exist_ok=True)
    entry = {"name": "gl_redbox", "mesh": glb.name, "semantic_class": "vessel"}
    (folder / "boats" / "redbox.yaml").write_text(yaml.safe_dump(entry), encoding="utf-8")
    cam = {
        "name": "front",
        "resolution": [64, 48],
        "hfov_deg": 60,
        "quality": "draft",
        "outputs": ["semantic", "instance"],
        "mount": {"xyz": [3.0, 0.0, 3.0], "rpy_deg": [0, 0, 0]},
    }
    scenario = {
        "name": "gl", "seed": 1, "map": {"type": "open_sea", "seed": 0},
        "acquisition": {"frequency_hz": 5, "frames": 2}, "assets": ["boats/redbox.yaml"],
        "rigs": {"r": {"cameras": [cam], "radar": None, "top_view": None,
                       "lidar": {"channels": 8, "points_per_second": 20480}}},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 0.5, "route": [[0, 0], [50, 0]]},
            {"id": "t", "asset": "gl_redbox", "speed_mps": 0.5, "route": [[30, 0], [80, 0]]},
        ],
    }  # fmt: skip
    (folder / "scen.yaml").write_text(yaml.safe_dump(scenario), encoding="utf-8")
    return folder / "scen.yaml"


@pytest.mark.usefixtures("_clean_library")
def test_a_scenario_records_the_glb_vessel_with_its_labels_and_its_extents(tmp_path: Path) -> None:
    from mmusv.classes import SemanticClass
    from mmusv.recording import decode_image, read_messages

    d = Doc()
    m = d.add("materials", name="hull", pbrMetallicRoughness={"baseColorFactor": [0.8, 0.1, 0.1, 1.0]})
    # 3 m across x (port), 3 m up y with 0.8 m below y = 0, 12 m along z (the bow): 12 x 3 x 3 m, draft 0.8 m
    d.add("scenes", nodes=[d.add("nodes", mesh=d.mesh(d.box((-1.5, -0.8, -6.0), (1.5, 2.2, 6.0), material=m)))])
    (tmp_path / "boats").mkdir()
    scen = _scenario(tmp_path, d.glb(tmp_path / "boats" / "redbox.glb"))
    out = tmp_path / "out"
    assert main(["run", str(scen), "-o", str(out)]) == 0
    boxes = pl.read_parquet(out / "tables" / "boxes_3d").filter(pl.col("target_id") == "t")
    assert boxes.height == 2
    np.testing.assert_allclose(boxes.select(["length", "beam", "height"]).to_numpy(), [[12.0, 3.0, 3.0]] * 2, atol=1e-6)
    assert set(boxes["semantic_class"]) == {int(SemanticClass.VESSEL)}
    instance = int(boxes["instance_id"][0])
    seen = 0
    for topic, _, msg in read_messages(out / "gl.mcap"):
        if topic.endswith("/instance"):
            ids = decode_image(msg)
        elif topic.endswith("/semantic"):
            classes = decode_image(msg)
        else:
            continue
        if topic.endswith("/semantic"):
            seen += 1
            # the vessel's pixels carry its class (the camera looks at it from 27 m)
            assert (classes == int(SemanticClass.VESSEL)).sum() > 20
    assert seen == 2 and (ids == instance).sum() > 20


@pytest.mark.usefixtures("_clean_library")
def test_a_scenario_naming_a_bad_glb_fails_before_writing_anything(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    d = _hull_doc()
    (tmp_path / "boats").mkdir()
    d.j["accessors"][0]["type"] = "VEC2"  # a POSITION of two numbers a vertex: not a mesh glTF allows
    glb = d.glb(tmp_path / "boats" / "redbox.glb")
    out = tmp_path / "out"
    assert main(["run", str(_scenario(tmp_path, glb)), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(glb) in err and "POSITION" in err and "Traceback" not in err, err
    assert not out.exists()
