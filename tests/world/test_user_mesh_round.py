"""A user's own vessel mesh, round trip: a known hull (pointed bow at +x, a mast to port and aft, keel 1 m below
the waterline) written with trimesh as GLB/glTF/OBJ/PLY/STL/OFF in several orientations, node graphs and units,
loaded through an asset entry, and checked against the geometry it was built from: length along body x with the bow
forward, up along z, the waterline, the materials as glTF 2.0 defines them, the LiDAR's points on it, and a one-line
error naming the file for every kind of bad file."""

from __future__ import annotations

import json
import struct
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv import Simulation
from mmusv.scenario_checks import MmusvWarning
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.materials import Material, all_materials
from mmusv.world.vessels import VesselAsset, load_asset_file, unregister_asset
from PIL import Image

trimesh = pytest.importorskip("trimesh")
from trimesh.visual.material import PBRMaterial  # noqa: E402  (after the skip)

LENGTH, BEAM, HEIGHT, DRAFT = 10.0, 3.0, 4.0, 1.0
"""The hull's box in the body frame: x -5..5 (bow +x), y -1.5..1.5, z -1..3 (mast top at 3), waterline z = 0."""
MAST_XY = (-3.0, 1.0)
"""The mast's centre: aft (-x) and to port (+y), z 1..3."""

AXIS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def _unit(name: str) -> np.ndarray:
    return (-1.0 if name.startswith("-") else 1.0) * np.array(AXIS[name[-1]])


def _to_file(up: str, forward: str) -> np.ndarray:
    """The 4x4 matrix taking body coordinates to those of a file whose up and bow axes are ``up`` and ``forward``
    (an independent statement of the convention: body x = forward, z = up, y = z × x)."""
    u, f = _unit(up), _unit(forward)
    left = np.cross(u, f)
    m = np.eye(4)
    m[:3, :3] = np.stack([f, left, u], axis=1)  # columns: where body x, y, z go in the file
    return m


GLTF = _to_file("y", "z")
"""glTF 2.0's frame: +Y up, an asset's front faces +Z (so body y, port, is file +X)."""


def _hull_parts() -> tuple[Any, Any]:
    """The hull (a convex solid: transom aft, pointed raked bow at +x) and the mast, in the body frame."""
    pts = [(x, y, z) for x in (-5.0, 2.0) for y in (-1.5, 1.5) for z in (-1.0, 1.0)] + [
        (5.0, 0.0, 1.0),
        (5.0, 0.0, 0.2),
    ]
    hull = trimesh.convex.convex_hull(np.array(pts))
    mast = trimesh.creation.box(extents=(0.4, 0.4, 2.0))
    mast.apply_translation((MAST_XY[0], MAST_XY[1], 2.0))
    return hull, mast


def _hull(transform: np.ndarray | None = None) -> Any:
    hull, mast = _hull_parts()
    m = trimesh.util.concatenate([hull, mast])
    if transform is not None:
        m.apply_transform(transform)
    return m


def _check_geometry(a: VesselAsset, scale: float = 1.0) -> None:
    """``a`` is the known hull (times ``scale``): its box, the bow's tip at +x, the mast aft to port, normals out."""
    want = np.array([[-LENGTH / 2, -BEAM / 2, -DRAFT], [LENGTH / 2, BEAM / 2, HEIGHT - DRAFT]]) * scale
    np.testing.assert_allclose(a.bbox, want, atol=1e-5 * scale)
    assert (a.length, a.beam, a.height, a.draft) == pytest.approx((LENGTH * scale, BEAM * scale, 4.0 * scale, scale))
    v = a.mesh.vertices
    bow = v[v[:, 0] > (LENGTH / 2 - 1e-4) * scale]
    np.testing.assert_allclose(bow[:, 1], 0.0, atol=1e-5 * scale)  # the stem: a line at y = 0
    top = v[v[:, 2] > (HEIGHT - DRAFT - 1e-4) * scale]
    np.testing.assert_allclose(top[:, :2].mean(axis=0), np.array(MAST_XY) * scale, atol=1e-5 * scale)
    tri = v[a.mesh.faces]
    volume = float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum()) / 6.0
    assert volume > 0.0  # a proper rotation: outward normals stay outward


def _load(entry: dict[str, Any]) -> VesselAsset:
    """Loads ``entry`` (named ``user_hull``), failing on any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return load_asset_file({"name": "user_hull", **entry})


def _write_gltf(scene: Any, folder: Path) -> Path:
    """``scene`` as a .gltf with its separate .bin buffers in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in scene.export(file_type="gltf").items():
        (folder / name).write_bytes(data)
    return folder / "model.gltf"


def _glb_parts(data: bytes) -> tuple[dict[str, Any], bytes]:
    """A GLB's JSON and the rest of the file after its JSON chunk."""
    n = struct.unpack_from("<I", data, 12)[0]
    return json.loads(data[20 : 20 + n]), data[20 + n :]


def _glb(header: dict[str, Any], rest: bytes) -> bytes:
    """A GLB from its JSON and the chunks after it."""
    js = json.dumps(header).encode()
    js += b" " * (-len(js) % 4)
    return (
        b"glTF" + struct.pack("<II", 2, 20 + len(js) + len(rest)) + struct.pack("<II", len(js), 0x4E4F534A) + js + rest
    )


# --------------------------------------------------------------------------------------------- orientation


@pytest.mark.parametrize("kind", ["glb", "gltf"])
def test_gltf_in_its_own_convention_loads_upright_with_the_bow_forward(tmp_path: Path, kind: str) -> None:
    """A Blender export (glTF 2.0: +Y up, front +Z) needs no axes in its entry."""
    scene = trimesh.Scene([_hull(GLTF)])
    if kind == "glb":
        path = tmp_path / "boat.glb"
        path.write_bytes(scene.export(file_type="glb"))
    else:
        path = _write_gltf(scene, tmp_path / "gl")
    _check_geometry(_load({"mesh": str(path)}))


@pytest.mark.parametrize(
    ("fmt", "up", "forward"),
    [
        ("obj", "z", "x"),
        ("obj", "y", "-z"),
        ("ply", "-y", "x"),
        ("stl", "x", "y"),
        ("off", "-z", "-x"),
        ("glb", "z", "x"),
        ("glb", "y", "z"),
        ("glb", "y", "x"),
    ],
)
def test_explicit_axes_turn_every_format_to_the_body_frame(tmp_path: Path, fmt: str, up: str, forward: str) -> None:
    path = tmp_path / f"boat.{fmt}"
    _hull(_to_file(up, forward)).export(path)
    _check_geometry(_load({"mesh": str(path), "up_axis": up, "forward_axis": forward}))


@pytest.mark.parametrize("fmt", ["obj", "ply", "stl"])
def test_formats_without_a_convention_default_to_z_up_x_forward(tmp_path: Path, fmt: str) -> None:
    path = tmp_path / f"boat.{fmt}"
    _hull().export(path)
    _check_geometry(_load({"mesh": str(path)}))


def test_a_z_up_glb_without_axes_is_read_as_gltf_and_says_so(tmp_path: Path) -> None:
    """The old default (z up, x forward for every format) is now glTF's for a .glb: a z-up GLB that relied on it
    gets a warning naming the fix, and loads as before with the axes given."""
    path = tmp_path / "zup.glb"
    _hull().export(path)
    with pytest.warns(MmusvWarning, match=r"zup\.glb.*up_axis: z, forward_axis: x") as record:
        load_asset_file({"name": "user_hull", "mesh": str(path)})
    assert len(record) == 1 and "\n" not in str(record[0].message)
    _check_geometry(_load({"mesh": str(path), "up_axis": "z", "forward_axis": "x"}))
    _check_geometry(_load({"mesh": str(path), "up_axis": "z"}))  # one axis given: the other as it always was


def test_one_axis_given_keeps_the_old_default_for_the_other(tmp_path: Path) -> None:
    """``up_axis: y`` alone still means forward x, for a GLB as for any file (as before)."""
    path = tmp_path / "yup_xfwd.glb"
    _hull(_to_file("y", "x")).export(path)
    _check_geometry(_load({"mesh": str(path), "up_axis": "y"}))


def test_a_mesh_lying_sideways_under_default_axes_is_warned_about(tmp_path: Path) -> None:
    path = tmp_path / "sideways.obj"
    _hull(_to_file("z", "y")).export(path)  # the bow along file +y
    with pytest.warns(MmusvWarning, match=r"sideways\.obj.*10 m wide but 3 m long.*set forward_axis"):
        a = load_asset_file({"name": "user_hull", "mesh": str(path)})
    assert (a.length, a.beam) == pytest.approx((BEAM, LENGTH))  # loaded as the entry says: the user decides
    _check_geometry(_load({"mesh": str(path), "up_axis": "z", "forward_axis": "y"}))


def test_a_y_up_obj_standing_on_end_under_default_axes_is_warned_about(tmp_path: Path) -> None:
    """An OBJ exported y-up (Blender's OBJ default) read z up stands on end: 10 m tall, 3 m long, no word (the
    wider-than-long warning could not see it: the length became the height, not the beam)."""
    import trimesh

    path = tmp_path / "blender.obj"
    # A low hull, 10 m long, 3 m beam, 2 m high, y up and the bow along file +z: read z up it is 3 m "long", 2 m
    # "wide" and 10 m tall, so only its height gives it away.
    trimesh.creation.box(extents=[3.0, 2.0, 10.0]).export(path)
    with pytest.warns(MmusvWarning, match=r"blender\.obj.*10 m tall but 3 m long.*give up_axis: y"):
        load_asset_file({"name": "user_hull", "mesh": str(path)})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # both axes given: no warning
        a = load_asset_file({"name": "user_hull_2", "mesh": str(path), "up_axis": "y", "forward_axis": "z"})
    assert (a.length, a.beam) == pytest.approx((10.0, 3.0))


# --------------------------------------------------------------------------------- node graphs and units


def _graph_scene(unit: float) -> Any:
    """The hull in glTF's frame as a node graph: the hull under a parent node, the mast a unit box scaled by its
    node, every length times ``unit`` (100: centimetres)."""
    hull, _ = _hull_parts()
    hull.visual = trimesh.visual.TextureVisuals(
        material=PBRMaterial(name="paint", baseColorFactor=[0.8, 0.1, 0.1, 1.0], metallicFactor=0.0)
    )
    mast = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    mast.visual = trimesh.visual.TextureVisuals(
        material=PBRMaterial(name="steel", baseColorFactor=[0.5, 0.5, 0.5, 1.0], roughnessFactor=0.3)
    )
    s = np.diag([unit, unit, unit, 1.0])
    scene = trimesh.Scene()
    scene.graph.update(frame_to="ship", frame_from=scene.graph.base_frame, matrix=s @ GLTF)
    scene.add_geometry(hull, node_name="hull", parent_node_name="ship")
    place = trimesh.transformations.translation_matrix((MAST_XY[0], MAST_XY[1], 2.0)) @ np.diag([0.4, 0.4, 2.0, 1.0])
    scene.add_geometry(mast, node_name="mast", parent_node_name="ship", transform=place)
    return scene


@pytest.mark.parametrize(("unit", "scale"), [(1.0, 1.0), (100.0, 0.01)])
def test_node_transforms_scales_and_units(tmp_path: Path, unit: float, scale: float) -> None:
    path = tmp_path / "graph.glb"
    path.write_bytes(_graph_scene(unit).export(file_type="glb"))
    a = _load({"mesh": str(path), "scale": scale})
    _check_geometry(a)
    mats = all_materials()
    centre_z = a.mesh.vertices[a.mesh.faces].mean(axis=1)[:, 2]
    hull = {mats[i].name for i in a.mesh.materials[centre_z < 0.9].tolist()}
    mast = {mats[i].name for i in a.mesh.materials[centre_z > 1.1].tolist()}
    assert (hull, mast) == ({"graph:paint"}, {"graph:steel"})


def test_a_mirrored_node_keeps_its_faces_outward(tmp_path: Path) -> None:
    """A node scaled by -1 (glTF: a negative determinant flips the winding) mirrors the mast to starboard."""
    path = tmp_path / "mirror.glb"
    scene = trimesh.Scene()
    scene.add_geometry(_hull(), node_name="hull", transform=GLTF @ np.diag([1.0, -1.0, 1.0, 1.0]))
    path.write_bytes(scene.export(file_type="glb"))
    a = _load({"mesh": str(path)})
    v = a.mesh.vertices
    top = v[v[:, 2] > HEIGHT - DRAFT - 1e-4]
    np.testing.assert_allclose(top[:, :2].mean(axis=0), [MAST_XY[0], -MAST_XY[1]], atol=1e-5)
    tri = v[a.mesh.faces]
    assert float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum()) > 0.0


def test_waterline_and_draft_in_file_units(tmp_path: Path) -> None:
    """``waterline_z`` is a file coordinate along ``up_axis`` (centimetres here), ``draft`` metres from the keel."""
    path = tmp_path / "cm.obj"
    _hull(np.diag([100.0, 100.0, 100.0, 1.0]) @ _to_file("-y", "x")).export(path)  # file -y up: keel at y = +100
    base = {"mesh": str(path), "scale": 0.01, "up_axis": "-y", "forward_axis": "x"}
    a = _load({**base, "waterline_z": 50.0})  # 50 cm above the file's zero along up: 0.5 m above the old waterline
    assert (a.draft, a.air_draft) == pytest.approx((1.5, 2.5))
    b = _load({**base, "draft": 0.25})
    assert (b.draft, b.air_draft) == pytest.approx((0.25, 3.75))


# ------------------------------------------------------------------------------------------------- materials


def _material(a: VesselAsset) -> Material:
    ids = set(a.mesh.materials.tolist())
    assert len(ids) == 1
    return all_materials()[ids.pop()]


def _textured_box(mat: Any) -> Any:
    b = trimesh.creation.box(extents=(4.0, 1.0, 1.0))
    b.visual = trimesh.visual.TextureVisuals(uv=np.zeros((len(b.vertices), 2)), material=mat)
    return b


def _srgb(c: float) -> float:
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def test_metallic_roughness_texture_multiplies_the_factors(tmp_path: Path) -> None:
    """glTF: roughness = roughnessFactor x green, metallic = metallicFactor x blue, linear (no sRGB decoding); the
    factors default to 1, so a painted hull with a metallic-roughness texture is not a mirror."""
    img = Image.fromarray(np.array([[[0, 128, 0], [0, 255, 51]]], dtype=np.uint8))
    mat = PBRMaterial(name="painted", baseColorFactor=[0.6, 0.6, 0.6, 1.0], metallicRoughnessTexture=img)
    path = tmp_path / "mr.glb"
    path.write_bytes(trimesh.Scene([_textured_box(mat)]).export(file_type="glb"))
    m = _material(_load({"mesh": str(path), "up_axis": "z", "forward_axis": "x"}))
    assert m.roughness == pytest.approx((128 + 255) / 2 / 255)
    assert m.metallic == pytest.approx(51 / 2 / 255)


def test_emissive_texture_multiplies_the_emissive_factor(tmp_path: Path) -> None:
    """glTF: emission = emissiveFactor x emissiveTexture (sRGB): one lit texel of four glows a quarter as much, not
    the whole material at full strength."""
    from mmusv.world.mesh_files import GLTF_EMISSIVE_SCALE

    img = Image.fromarray(np.array([[[0, 0, 0], [0, 0, 0], [0, 0, 0], [255, 188, 0]]], dtype=np.uint8))
    mat = PBRMaterial(name="windows", emissiveFactor=[1.0, 1.0, 0.5], emissiveTexture=img)
    path = tmp_path / "lit.glb"
    path.write_bytes(trimesh.Scene([_textured_box(mat)]).export(file_type="glb"))
    m = _material(_load({"mesh": str(path), "up_axis": "z", "forward_axis": "x"}))
    want = np.array([1.0, _srgb(188 / 255), 0.0]) / 4 * GLTF_EMISSIVE_SCALE
    np.testing.assert_allclose(m.emissive, want, rtol=1e-6)


def test_khr_materials_emissive_strength_scales_the_emission(tmp_path: Path) -> None:
    """Blender writes an emission strength above 1 as KHR_materials_emissive_strength (trimesh drops it)."""
    from mmusv.world.mesh_files import GLTF_EMISSIVE_SCALE

    mat = PBRMaterial(name="lamp", emissiveFactor=[1.0, 0.5, 0.0])
    header, rest = _glb_parts(trimesh.Scene([_textured_box(mat)]).export(file_type="glb"))
    header["materials"][0]["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": 6.0}}
    header["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    path = tmp_path / "strong.glb"
    path.write_bytes(_glb(header, rest))
    m = _material(_load({"mesh": str(path), "up_axis": "z", "forward_axis": "x"}))
    np.testing.assert_allclose(m.emissive, np.array([6.0, 3.0, 0.0]) * GLTF_EMISSIVE_SCALE, rtol=1e-6)


def test_external_texture_of_a_gltf_is_read_as_its_uri_means(tmp_path: Path) -> None:
    """A texture URI is percent-encoded and relative to the .gltf, ``../`` included (as Blender writes them); a
    missing or unreadable texture is an error, not a white hull."""
    mat = PBRMaterial(name="tex", baseColorTexture=Image.new("RGB", (2, 2), (255, 0, 0)))
    path = _write_gltf(trimesh.Scene([_textured_box(mat)]), tmp_path / "gl")
    header = json.loads(path.read_text())
    header["images"] = [{"uri": "../textures/hull%20paint.png"}]
    path.write_text(json.dumps(header))
    (tmp_path / "textures").mkdir()
    png = tmp_path / "textures" / "hull paint.png"
    Image.new("RGB", (2, 2), (0, 0, 188)).save(png)
    entry = {"name": "user_hull", "mesh": str(path), "up_axis": "z", "forward_axis": "x"}
    m = _material(_load(entry))
    np.testing.assert_allclose(m.base_color, [0.0, 0.0, _srgb(188 / 255)], atol=1e-6)
    png.write_bytes(b"not a png")
    with pytest.raises(
        AssetSpecError, match=r"model\.gltf': its texture '\.\./textures/hull%20paint\.png' .* is not an"
    ):
        load_asset_file(entry)
    png.unlink()
    with pytest.raises(AssetSpecError, match=r"model\.gltf' needs the file '\.\./textures/hull%20paint\.png' \(images"):
        load_asset_file(entry)


# ------------------------------------------------------------------------------------------------- bad files


def _bad_files(tmp: Path) -> dict[str, tuple[Path, str]]:
    """Each bad file and what its error must say."""
    glb = trimesh.Scene([_hull(GLTF)]).export(file_type="glb")
    out: dict[str, tuple[Path, str]] = {}

    def put(key: str, name: str, data: bytes | str, says: str) -> None:
        p = tmp / name
        p.write_bytes(data.encode() if isinstance(data, str) else data)
        out[key] = (p, says)

    for ext in ("glb", "gltf", "obj", "ply", "stl"):
        put(f"empty_{ext}", f"empty.{ext}", b"", r"is empty \(0 bytes\)")
    put("truncated_glb", "cut.glb", glb[: len(glb) // 2], rf"is truncated: its GLB header declares {len(glb)} bytes")
    put("header_only_glb", "stub.glb", glb[:16], "is truncated")
    put("not_a_glb", "text.glb", "solid boat\n", "is not a binary glTF")
    put("bad_json_gltf", "bad.gltf", '{"asset": {"version": "2.0"', "is not a glTF file: its JSON does not parse")
    gl = _write_gltf(trimesh.Scene([_hull(GLTF)]), tmp / "nobin")
    for b in (tmp / "nobin").glob("*.bin"):
        b.unlink()
    out["missing_bin"] = (gl, r"needs the file 'gltf_buffer_0\.bin' \(buffers\[0\]\.uri\), which is missing")
    put("no_faces_obj", "points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "holds no triangles")
    put("nan_obj", "nan.obj", "v 0 0 -1\nv nan 0 1\nv 0 1 1\nf 1 2 3\n", "non-finite")
    put("unsupported", "boat.txt", "v 0 0 0\n", r"is a '\.txt' file; mesh files are read by their extension: .*\.glb")
    put("no_extension", "boat", "v 0 0 0\n", "is a file without an extension")
    out["missing"] = (tmp / "nowhere.glb", "does not exist")
    (tmp / "folder.glb").mkdir()
    out["folder"] = (tmp / "folder.glb", "is a folder, not a mesh file")
    return out


BAD = [
    *(f"empty_{e}" for e in ("glb", "gltf", "obj", "ply", "stl")),
    "truncated_glb",
    "header_only_glb",
    "not_a_glb",
    "bad_json_gltf",
    "missing_bin",
    "no_faces_obj",
    "nan_obj",
    "unsupported",
    "no_extension",
    "missing",
    "folder",
]


@pytest.mark.parametrize("case", BAD)
def test_bad_file_is_one_line_naming_the_file_and_the_fault(tmp_path: Path, case: str) -> None:
    path, says = _bad_files(tmp_path)[case]
    with pytest.raises(AssetSpecError, match=says) as info:
        load_asset_file({"name": "user_hull", "mesh": str(path)})
    msg = str(info.value)
    assert info.value.field == "user_hull.mesh" and repr(str(path)) in msg and "\n" not in msg


def test_quads_and_polygons_are_triangulated(tmp_path: Path) -> None:
    """An OBJ of quads and hexagons (a hexagonal prism 10 m x 3 m x 2 m) loads with its faces fanned."""
    ang = np.linspace(0.0, 2.0 * np.pi, 7)[:-1]
    ring = [(5.0 * np.cos(t), 1.5 * np.sin(t)) for t in ang]
    lines = [f"v {x} {y} -1" for x, y in ring] + [f"v {x} {y} 1" for x, y in ring]
    lines += ["f 6 5 4 3 2 1", "f 7 8 9 10 11 12"]
    lines += [f"f {i + 1} {(i + 1) % 6 + 1} {(i + 1) % 6 + 7} {i + 7}" for i in range(6)]
    path = tmp_path / "prism.obj"
    path.write_text("\n".join(lines) + "\n")
    a = _load({"mesh": str(path)})
    assert a.num_triangles == 2 * 4 + 6 * 2
    assert (a.length, a.beam, a.height) == pytest.approx((10.0, 3.0 * np.sin(np.pi / 3), 2.0))


# ------------------------------------------------------------------------------------------------- sensors


def test_the_lidar_sees_the_glb_hull_where_its_box_is(tmp_path: Path) -> None:
    """A Blender-convention GLB as a target crossing ahead of a LiDAR USV: its points, taken to the target's body
    frame, lie in the recorded box, and the high ones (the mast) aft to port."""
    path = tmp_path / "target.glb"
    path.write_bytes(trimesh.Scene([_hull(GLTF)]).export(file_type="glb"))
    asset = load_asset_file({"name": "test_user_mesh_round", "mesh": str(path)}, register=True)
    try:
        sim = Simulation(
            {
                "name": "user_mesh_round",
                "seed": 1,
                "map": {"type": "open_sea", "seed": 0},
                "acquisition": {"frequency_hz": 5, "frames": 1},
                "rigs": {"r": {"preset": "lidar_only"}},
                "vessels": [
                    {
                        "id": "ego",
                        "role": "usv",
                        "asset": "usv_wamv",
                        "rig": "r",
                        "speed_mps": 1.0,
                        "route": [[0, 0], [100, 0]],
                    },
                    {
                        "id": "t",
                        "role": "target",
                        "asset": "test_user_mesh_round",
                        "speed_mps": 1.0,
                        "route": [[15, 8], [15, 100]],
                    },
                ],
            }
        )
        cap = sim.capture(0)
        ti = next(i for i, v in enumerate(sim.vessels) if v.asset == "test_user_mesh_round")
        info = sim.vessels[ti]
        np.testing.assert_allclose(info.box_size, [LENGTH, BEAM, HEIGHT])
        np.testing.assert_allclose(info.box_center_body, asset.bbox.mean(axis=0))
        lidar = cap.agents["ego"].lidar
        assert lidar is not None
        on = lidar.instance == info.instance_id
        assert int(on.sum()) > 50
        pts = np.c_[lidar.xyz[on].astype(np.float64), np.ones(int(on.sum()))]
        world_to_body = np.linalg.inv(cap.world.matrices[ti])
        body = (world_to_body @ cap.agents["ego"].lidar_pose @ pts.T).T[:, :3]
        assert np.all(body >= asset.bbox[0] - 0.1) and np.all(body <= asset.bbox[1] + 0.1)
        mast = body[body[:, 2] > 1.2]
        assert len(mast) > 5
        np.testing.assert_allclose(mast[:, 0].mean(), MAST_XY[0], atol=0.3)
        assert np.all(mast[:, 1] > 0.5)  # port side: the side facing the ego, which lies to the target's left
    finally:
        unregister_asset("test_user_mesh_round")


@pytest.mark.parametrize(
    ("entry", "field", "says"),
    [
        (
            {"up_axis": "x"},
            "forward_axis",
            "is not given, so it is x (the default), which is not perpendicular to up_axis x",
        ),
        ({"forward_axis": "-z"}, "up_axis", "is not given, so it is z (the default), which is not perpendicular"),
        ({"up_axis": "y", "forward_axis": "-y"}, "forward_axis", "must be perpendicular to up_axis"),
    ],
)
def test_axes_that_clash_say_which_one_was_defaulted(entry: dict[str, str], field: str, says: str) -> None:
    """With only ``up_axis: x`` given the error said "forward_axis: must be perpendicular to up_axis", naming a key
    the entry does not have without saying it had defaulted to x."""
    from mmusv.world.asset_spec import parse_asset

    with pytest.raises(AssetSpecError) as info:
        parse_asset({"name": "boat", "mesh": "boat.obj", **entry}, path="boat")
    assert info.value.field == f"boat.{field}" and says in str(info.value), str(info.value)
