"""A user's own vessel mesh keeps its colours: an OBJ's MTL materials per ``usemtl`` (Kd, map_Kd, Ns/Pr, Pm, Ke,
converted as Blender's OBJ importer does) and a PLY's or OBJ's vertex/face colours (a face's mean, quantised),
checked face by face against values computed here from the files as written; a camera sees the red hull red; a
missing .mtl or texture, or a usemtl naming no material, is a one-line error naming the OBJ and the path looked for."""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv import Simulation
from mmusv.scenario_checks import MmusvWarning
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.materials import Material, all_materials
from mmusv.world.mesh_files import GLTF_EMISSIVE_SCALE
from mmusv.world.vessels import VesselAsset, load_asset_file, unregister_asset
from PIL import Image

trimesh = pytest.importorskip("trimesh")

HULL = ((-5.0, -1.5, -1.0), (5.0, 1.5, 1.0))
"""The hull box, file = body frame (OBJ/PLY default: z up, x forward; waterline z = 0)."""
HOUSE = ((-3.0, -1.0, 1.0), (1.0, 1.0, 3.0))
"""The superstructure box on the hull's deck."""


def _srgb(c: float) -> float:
    """sRGB-encoded [0, 1] to linear (IEC 61966-2-1)."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def _srgb_encode(c: float) -> float:
    return c * 12.92 if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


def _box(lo: tuple[float, ...], hi: tuple[float, ...]) -> tuple[list[tuple[float, ...]], list[tuple[int, ...]]]:
    """A box's 8 corners (index 4 ix + 2 iy + iz) and its 6 outward quads (0-based)."""
    v = [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return v, quads


def _write_obj(path: Path, parts: list[tuple[str | None, tuple[Any, Any]]], head: str = "") -> None:
    """An OBJ of boxes, each after ``usemtl <name>`` (none for ``None``), with ``head`` lines first."""
    verts: list[tuple[float, ...]] = []
    faces: list[str] = []
    for name, (lo, hi) in parts:
        v, quads = _box(lo, hi)
        if name is not None:
            faces.append(f"usemtl {name}")
        faces += ["f " + " ".join(str(len(verts) + i + 1) for i in q) for q in quads]
        verts += v
    path.write_text(head + "".join(f"v {x:g} {y:g} {z:g}\n" for x, y, z in verts) + "\n".join(faces) + "\n")


def _load(path: Path, **entry: Any) -> VesselAsset:
    """The asset of ``path`` (named ``user_hull``), failing on any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return load_asset_file({"name": "user_hull", "mesh": str(path), **entry})


def _of_box(a: VesselAsset, box: tuple[Any, Any]) -> np.ndarray:
    """Which faces of ``a`` have every vertex at a corner of ``box`` (each coordinate its low or high one)."""
    tri = a.mesh.vertices[a.mesh.faces]
    lo, hi = np.array(box[0]), np.array(box[1])
    at = np.isclose(tri, lo, atol=1e-9) | np.isclose(tri, hi, atol=1e-9)
    return at.all(axis=(1, 2))  # type: ignore[no-any-return]


def _materials_of(a: VesselAsset, faces: np.ndarray) -> Material:
    ids = set(a.mesh.materials[faces].tolist())
    assert len(ids) == 1, ids
    return all_materials()[ids.pop()]


MTL = """# two materials, as Blender writes them
newmtl hull
Ns 250.000000
Ka 1.000000 1.000000 1.000000
Kd 0.800000 0.100000 0.050000
Ks 0.500000 0.500000 0.500000
Ke 0.000000 0.000000 0.000000
Ni 1.450000
d 1.000000
illum 2

newmtl superstructure
Kd 0.9 0.9 0.88
Ns 90
d 0.5
"""


def _two_material_obj(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "boat.mtl").write_text(MTL)
    path = folder / "boat.obj"
    _write_obj(path, [("hull", HULL), ("superstructure", HOUSE)], head="mtllib boat.mtl\n")
    return path


# ------------------------------------------------------------------------------------------------- OBJ + MTL


def test_obj_mtl_materials_come_through_per_usemtl(tmp_path: Path) -> None:
    """Kd is the linear base colour as stored; roughness = 1 - sqrt(Ns / 1000) (Blender's importer); metallic 0
    (Ka and illum not read); d ignored (opaque); one material per usemtl, named <file stem>:<newmtl>."""
    a = _load(_two_material_obj(tmp_path))
    hull, house = _of_box(a, HULL), _of_box(a, HOUSE)
    assert hull.sum() == 12 and house.sum() == 12 and a.num_triangles == 24
    mh, ms = _materials_of(a, hull), _materials_of(a, house)
    assert (mh.name, ms.name) == ("boat:hull", "boat:superstructure")
    np.testing.assert_allclose(mh.base_color, [0.8, 0.1, 0.05], rtol=1e-12)
    np.testing.assert_allclose(ms.base_color, [0.9, 0.9, 0.88], rtol=1e-12)
    assert mh.roughness == pytest.approx(1.0 - math.sqrt(0.25))
    assert ms.roughness == pytest.approx(1.0 - math.sqrt(0.09))
    assert (mh.metallic, ms.metallic, mh.emissive, ms.emissive) == (0.0, 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    again = _load(tmp_path / "boat.obj")
    assert np.array_equal(again.mesh.materials, a.mesh.materials)  # the same materials, the same ids


def test_mtl_pbr_extension_emission_and_defaults(tmp_path: Path) -> None:
    """Pr/Pm (the PBR extension) override Ns and the metallic 0; Ke glows as a glTF emissiveFactor does; Ns beyond
    1000 is clamped (roughness 0.02, the table's floor); a material without Kd or Ns is 0.8 grey, roughness 1; a
    Kd of one number is grey; faces before the first usemtl keep the class's default look."""
    (tmp_path / "m.mtl").write_text(
        "newmtl metal\nKd 0.5 0.5 0.6\nNs 10\nPr 0.25\nPm 0.75\n"
        "newmtl lamp\nKd 0.2\nKe 1.0 0.5 0.0\nNs 2000\n"
        "newmtl plain\n"
    )
    boxes = [
        ((x, -1.0, -1.0), (x + 2.0, 1.0, 1.0)) for x in (-5.0, -2.5, 0.5, 3.0)
    ]  # symmetric: midship stays at x = 0
    path = tmp_path / "m.obj"
    _write_obj(
        path,
        [(None, boxes[0]), ("metal", boxes[1]), ("lamp", boxes[2]), ("plain", boxes[3])],
        head="mtllib m.mtl\n",
    )
    a = _load(path)
    first, metal, lamp, plain = (_materials_of(a, _of_box(a, b)) for b in boxes)
    assert first.name == "class_default"
    assert (metal.base_color, metal.roughness, metal.metallic) == ((0.5, 0.5, 0.6), 0.25, 0.75)
    assert lamp.base_color == (0.2, 0.2, 0.2) and lamp.roughness == 0.02 and lamp.metallic == 0.0
    np.testing.assert_allclose(lamp.emissive, np.array([1.0, 0.5, 0.0]) * GLTF_EMISSIVE_SCALE, rtol=1e-12)
    assert (plain.base_color, plain.roughness, plain.metallic) == ((0.8, 0.8, 0.8), 1.0, 0.0)


def test_map_kd_texture_replaces_kd_by_its_linear_mean(tmp_path: Path) -> None:
    """map_Kd (after its options, a file name with a space, relative to the MTL) is the base colour by its mean in
    linear RGB (sRGB-decoded), replacing Kd as Blender and obj2gltf do."""
    (tmp_path / "mtl" / "textures").mkdir(parents=True)
    Image.fromarray(np.array([[[255, 0, 0], [0, 0, 188]]], dtype=np.uint8)).save(
        tmp_path / "mtl" / "textures" / "hull paint.png"
    )
    (tmp_path / "mtl" / "t.mtl").write_text(
        "newmtl painted\nKd 0.2 0.2 0.2\nNs 0\nmap_Kd -s 1 1 1 -clamp on textures\\hull paint.png\n"
    )
    path = tmp_path / "t.obj"
    _write_obj(path, [("painted", HULL)], head="mtllib mtl/t.mtl\n")
    m = _materials_of(_load(path), np.ones(12, dtype=bool))
    np.testing.assert_allclose(m.base_color, [0.5, 0.0, 0.5 * _srgb(188 / 255)], atol=1e-12)
    assert (m.roughness, m.metallic) == (1.0, 0.0)


def test_a_texture_path_from_another_machine_is_looked_for_beside_the_mtl(tmp_path: Path) -> None:
    """An absolute Windows path (a model exported elsewhere): the file of that name beside the .mtl (obj2gltf's
    rule); the error names both places when it is in neither."""
    Image.new("RGB", (2, 2), (0, 188, 0)).save(tmp_path / "deck.png")
    (tmp_path / "w.mtl").write_text("newmtl deck\nmap_Kd C:\\Users\\bob\\Desktop\\deck.png\n")
    path = tmp_path / "w.obj"
    _write_obj(path, [("deck", HULL)], head="mtllib w.mtl\n")
    m = _materials_of(_load(path), np.ones(12, dtype=bool))
    np.testing.assert_allclose(m.base_color, [0.0, _srgb(188 / 255), 0.0], atol=1e-12)
    (tmp_path / "deck.png").unlink()
    with pytest.raises(AssetSpecError, match=r"looked for '.*Users/bob/Desktop/deck\.png' and '.*/deck\.png'\)"):
        load_asset_file({"name": "user_hull", "mesh": str(path)})


def test_obj_without_mtllib_keeps_the_class_default(tmp_path: Path) -> None:
    """No mtllib: nothing to read, not an error (usemtl lines name nothing)."""
    path = tmp_path / "bare.obj"
    _write_obj(path, [("hull", HULL), ("superstructure", HOUSE)])
    a = _load(path)
    assert set(a.mesh.materials.tolist()) == {0}


@pytest.mark.parametrize(
    ("case", "says"),
    [
        ("no_mtl", r"boat\.obj' needs its material library 'boat\.mtl' \(mtllib, line 1\), which is missing "
         r"\(looked for '.*boat\.mtl'\)"),
        ("no_texture", r"boat\.obj': its material library 'boat\.mtl' \(map_Kd 'hull\.png', material 'hull'\) needs "
         r"the texture 'hull\.png', which is missing \(looked for '.*hull\.png'\)"),
        ("bad_texture", r"boat\.obj': its material library 'boat\.mtl' \(map_Kd 'hull\.png', material 'hull'\) is "
         r"not an image"),
        ("unknown_usemtl", r"boat\.obj': usemtl 'superstructure' \(line \d+\) names no material of its material "
         r"libraries \('hull'\)"),
        ("kd_range", r"boat\.obj': material 'hull' of 'boat\.mtl' \(line 1\): Kd \[1\.5, 0\.0, 0\.0\] must be in"),
    ],
)  # fmt: skip
def test_bad_obj_materials_are_one_line_naming_the_obj_and_the_path(tmp_path: Path, case: str, says: str) -> None:
    path = _two_material_obj(tmp_path)
    mtl = tmp_path / "boat.mtl"
    if case == "no_mtl":
        mtl.unlink()
    elif case in ("no_texture", "bad_texture", "unknown_usemtl", "kd_range"):
        body = {
            "no_texture": "newmtl hull\nKd 0.8 0.1 0.05\nmap_Kd hull.png\nnewmtl superstructure\n",
            "bad_texture": "newmtl hull\nmap_Kd hull.png\nnewmtl superstructure\n",
            "unknown_usemtl": "newmtl hull\nKd 0.8 0.1 0.05\n",
            "kd_range": "newmtl hull\nKd 1.5 0 0\nnewmtl superstructure\n",
        }[case]
        mtl.write_text(body)
        if case == "bad_texture":
            (tmp_path / "hull.png").write_bytes(b"not a png")
    with pytest.raises(AssetSpecError, match=says) as info:
        load_asset_file({"name": "user_hull", "mesh": str(path)})
    msg = str(info.value)
    assert info.value.field == "user_hull.mesh" and repr(str(path)) in msg and "\n" not in msg


# ---------------------------------------------------------------------------------------- vertex/face colours


def _quantised(rgb_linear: np.ndarray, levels: int = 64) -> np.ndarray:
    """The linear colour of the material mmusv documents for a face of mean linear colour ``rgb_linear``: sRGB
    encoded, rounded to ``levels`` levels per channel, then to the byte, decoded."""
    out = []
    for c in rgb_linear:
        byte = round(round(_srgb_encode(float(c)) * (levels - 1)) * 255 / (levels - 1))
        out.append(_srgb(byte / 255))
    return np.array(out)


def _vertex_colour(p: np.ndarray) -> np.ndarray:
    """The sRGB byte colour written for a vertex at ``p``: red hull below the deck, white above, a blue bow."""
    if p[0] > 4.0:
        return np.array([20, 40, 200])
    return np.array([200, 16, 10]) if p[2] < 0.5 else np.array([240, 240, 235])


def _expected_face_colours(a: VesselAsset) -> np.ndarray:
    lin = np.vectorize(_srgb)
    tri = a.mesh.vertices[a.mesh.faces]
    cols = np.array([[lin(_vertex_colour(p) / 255.0) for p in t] for t in tri])
    return np.array([_quantised(c.mean(axis=0)) for c in cols])


@pytest.mark.parametrize("fmt", ["ply", "obj"])
def test_vertex_colours_become_face_materials(tmp_path: Path, fmt: str) -> None:
    """PLY red/green/blue and OBJ ``v x y z r g b``: each face's material is its vertices' mean colour (linear),
    quantised to 64 levels per sRGB channel; one material per distinct colour, shared as vertex_colour:#rrggbb."""
    hull, house = trimesh.creation.box(bounds=HULL), trimesh.creation.box(bounds=HOUSE)
    m = trimesh.util.concatenate([hull.subdivide(), house])
    m.visual = trimesh.visual.ColorVisuals(
        m, vertex_colors=np.c_[[_vertex_colour(p) for p in m.vertices], np.full(len(m.vertices), 255)]
    )
    path = tmp_path / f"painted.{fmt}"
    m.export(path)
    a = _load(path)
    mats = all_materials()
    got = np.array([mats[i].base_color for i in a.mesh.materials.tolist()])
    np.testing.assert_allclose(got, _expected_face_colours(a), atol=1e-12)
    names = {mats[i].name for i in a.mesh.materials.tolist()}
    assert all(n.startswith("vertex_colour:#") for n in names) and 3 <= len(names) < 20
    assert {(mats[i].roughness, mats[i].metallic) for i in a.mesh.materials.tolist()} == {(0.5, 0.0)}
    tri = a.mesh.vertices[a.mesh.faces]
    hull_faces = (tri[:, :, 2].max(axis=1) < 0.5) & (tri[:, :, 0].max(axis=1) <= 4.0)
    assert hull_faces.sum() > 10
    assert np.all(got[hull_faces, 0] > 5 * got[hull_faces, 1])  # red below the deck


def test_split_vertices_keep_each_faces_colour(tmp_path: Path) -> None:
    """A hard colour edge (the same corner written twice, red and blue: Blender's face-corner colours) keeps both
    faces' colours (trimesh's vertex merge keeps one colour per place)."""
    v = np.array([[0, 0, 0], [10, 0, 0], [0, 3, 2], [10, 0, 0], [10, 3, 2], [0, 3, 2]], dtype=np.float64)
    v[:, 2] -= 1.0
    colours = [[255, 0, 0, 255]] * 3 + [[0, 0, 255, 255]] * 3
    m = trimesh.Trimesh(v, [[0, 1, 2], [3, 4, 5]], vertex_colors=colours, process=False)
    path = tmp_path / "edge.ply"
    m.export(path)
    a = _load(path)
    mats = all_materials()
    by_x = sorted(
        (float(a.mesh.vertices[f].mean(axis=0)[0]), mats[i].name)
        for f, i in zip(a.mesh.faces, a.mesh.materials, strict=True)
    )
    assert [n for _, n in by_x] == ["vertex_colour:#ff0000", "vertex_colour:#0000ff"]


def test_face_colours_are_bounded_with_a_warning(tmp_path: Path) -> None:
    """More than 256 distinct face colours: quantised coarser until at most 256 materials, said in a warning;
    each face within half a coarse step of its colour."""
    grid = trimesh.creation.box(bounds=HULL).subdivide().subdivide().subdivide()  # 768 faces
    rng = np.random.default_rng(7)
    colours = rng.integers(0, 256, size=(len(grid.faces), 3))
    grid.visual = trimesh.visual.ColorVisuals(grid, face_colors=np.c_[colours, np.full(len(grid.faces), 255)])
    path = tmp_path / "confetti.ply"
    grid.export(path)
    with pytest.warns(
        MmusvWarning, match=r"confetti\.ply' has more than 256 distinct face colours .* quantised to"
    ) as rec:
        a = load_asset_file({"name": "user_hull", "mesh": str(path)})
    levels = int(str(rec[0].message).split("quantised to ")[1].split()[0])
    assert 2 <= levels < 64
    assert len(set(a.mesh.materials.tolist())) <= 256
    mats = all_materials()
    centroids = a.mesh.vertices[a.mesh.faces].mean(axis=1)
    ref = grid.triangles_center
    for f, i in enumerate(a.mesh.materials.tolist()):
        k = int(np.argmin(np.linalg.norm(ref - centroids[f], axis=1)))
        srgb = np.array([_srgb_encode(c) for c in mats[i].base_color])
        assert np.all(np.abs(srgb - colours[k] / 255) <= 0.5 / (levels - 1) + 0.5 / 255 + 1e-9)


# ------------------------------------------------------------------------------------------------- camera


def test_the_camera_sees_the_obj_hull_red_and_its_superstructure_white(tmp_path: Path) -> None:
    """The two-material OBJ crossing ahead of a camera USV: its hull pixels are red (they were the class's grey
    before MTL files were read), its superstructure's are not."""
    load_asset_file({"name": "test_user_mesh_colours", "mesh": str(_two_material_obj(tmp_path))}, register=True)
    cam = {"name": "front", "resolution": [96, 64], "quality": "draft", "outputs": ["rgb"]}
    try:
        sim = Simulation(
            {
                "name": "user_mesh_colours",
                "seed": 1,
                "map": {"type": "open_sea", "seed": 0},
                "acquisition": {"frequency_hz": 5, "frames": 1},
                "rigs": {"r": {"preset": "lidar_only", "cameras": [{**cam, "mount": {"point": "camera_front"}}]}},
                "vessels": [
                    {"id": "ego", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 1.0,
                     "route": [[0, 0], [100, 0]]},
                    {"id": "t", "role": "target", "asset": "test_user_mesh_colours", "speed_mps": 1.0,
                     "route": [[16, -3], [16, 100]]},
                ],
            }
        )  # fmt: skip
        img = sim.capture(0, radar=False).agents["ego"].cameras["front"]
        target = next(v for v in sim.vessels if v.asset == "test_user_mesh_colours").instance_id
    finally:
        unregister_asset("test_user_mesh_colours")
    assert img.rgb is not None
    mask = img.instance == target
    rows = np.nonzero(mask.any(axis=1))[0]
    assert len(rows) >= 6
    rgb = img.rgb.astype(np.float64)
    low = mask & (np.arange(mask.shape[0])[:, None] >= rows.max() - 1)  # the hull's bottom two rows
    high = mask & (np.arange(mask.shape[0])[:, None] <= rows.min() + 1)  # the superstructure's top two rows
    hull, house = rgb[low].mean(axis=0), rgb[high].mean(axis=0)
    assert hull[0] > 2.0 * hull[1] and hull[0] > 2.0 * hull[2], hull
    assert house[0] < 1.2 * min(house[1], house[2]) and house.min() > 60, house
