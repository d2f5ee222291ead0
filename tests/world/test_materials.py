"""The material table (mmusv.world.materials), per-face materials of TriMesh and the batched mesh builders
(mmusv.world.primitives), and glTF PBR materials read through trimesh (mmusv.world.vessels)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from mmusv.errors import ConfigError
from mmusv.world.materials import (
    BUILTIN_COUNT,
    COLREG_RANGE_INTENSITY_CD,
    LANTERN_LENS_AREA_M2,
    MATERIALS,
    Material,
    all_materials,
    lamp_ids,
    lamp_material,
    lamp_of,
    material_id,
    material_table,
    register_material,
)
from mmusv.world.primitives import TriMesh, box, boxes, lathe, merge, placed, sweep, torus, transformed, tubes
from mmusv.world.vessels import asset_names, get_asset, load_asset_file

REQUIRED = [
    "class_default",
    "antifouling_red",
    "boot_top",
    "hull_black",
    "hull_blue",
    "hull_white",
    "hull_grey",
    "superstructure_white",
    "deck_steel",
    "deck_wood",
    "glass",
    "rubber",
    "aluminium",
    "lifeboat_orange",
    "sail_cloth",
    "rope_canvas",
    "sensor_housing",
    "funnel_black",
    "nav_masthead_white",
    "nav_port_red",
    "nav_starboard_green",
    "nav_stern_white",
]


def _closed_outward(m: TriMesh) -> tuple[bool, float]:
    """Whether every edge of ``m`` is used once in each direction (closed, consistently oriented), and the
    signed volume (m³, > 0 when the normals face outwards)."""
    f = m.faces
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    n = int(m.vertices.shape[0])
    key = e[:, 0] * n + e[:, 1]
    rev = e[:, 1] * n + e[:, 0]
    ok = np.unique(key).shape[0] == key.shape[0] and bool(np.isin(rev, key).all())
    t = m.vertices[f]
    vol = float(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum() / 6.0)
    return ok, vol


# ------------------------------------------------------------------------------------------------ table


def test_table_has_the_named_materials_and_id_zero_is_the_class_default() -> None:
    names = [m.name for m in MATERIALS]
    assert names[0] == "class_default" and material_id("class_default") == 0
    assert len(set(names)) == len(names)
    for n in REQUIRED:
        assert MATERIALS[material_id(n)].name == n
    assert sum(n.startswith("container_") for n in names) >= 6
    assert sum(n.startswith("funnel_") for n in names) >= 3
    assert sum(n.startswith("hull_") for n in names) >= 4


def test_table_rows_are_the_materials() -> None:
    t = material_table()
    assert t.dtype == np.float32 and t.shape == (len(all_materials()), 11) and len(all_materials()) >= BUILTIN_COUNT
    for i, m in enumerate(MATERIALS):
        want = [*m.base_color, m.roughness, m.metallic, *m.emissive, float(m.nav_light), *m.arc_deg]
        np.testing.assert_allclose(t[i], want, rtol=1e-6)
    assert np.all((t[:, :3] >= 0) & (t[:, :3] <= 1)) and np.all((t[:, 3] >= 0.02) & (t[:, 3] <= 1))


def test_physical_character_of_key_materials() -> None:
    glass = MATERIALS[material_id("glass")]
    assert glass.roughness == pytest.approx(0.05) and glass.metallic == 0.0 and max(glass.base_color) < 0.1
    assert MATERIALS[material_id("aluminium")].metallic == 1.0
    assert MATERIALS[material_id("rubber")].roughness >= 0.8
    for n in ("nav_masthead_white", "nav_port_red", "nav_starboard_green", "nav_stern_white"):
        m = MATERIALS[material_id(n)]
        assert m.nav_light and max(m.emissive) > 0
    red, green = MATERIALS[material_id("nav_port_red")], MATERIALS[material_id("nav_starboard_green")]
    assert red.emissive[0] > 10 * red.emissive[1] and green.emissive[1] > 2 * green.emissive[0]
    assert not any(m.nav_light or max(m.emissive) > 0 for m in MATERIALS if not m.name.startswith("nav_"))


def test_lamps_have_the_colreg_intensities() -> None:
    # COLREG 1972 Annex I §8(b): 6 nautical miles (the masthead light of a vessel of 50 m or more) ask 94 cd, 3 miles
    # (its sidelights and sternlight) 12 cd. The intensity of a default lantern towards the side: its lamp faces'
    # projected area along x (half the sum of |area vector · x| over the closed lens band) times the luminance of the
    # lens radiance (Rec. 709 / sRGB weights).
    from mmusv.world.parts_super import _lantern

    lamp = material_id("nav_masthead_white")
    m = _lantern(at=np.zeros(3), size=0.3, lamp=lamp, housing=material_id("steel"), cls=3)
    tri = np.asarray(m.vertices, dtype=np.float64)[np.asarray(m.faces)]
    area = 0.5 * np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    side_on = 0.5 * np.abs(area[np.asarray(m.materials) == lamp][:, 0]).sum()
    # A 12-sided band seen along x: its model, a cylinder's 2 r h, within the polygon's width.
    assert side_on == pytest.approx(LANTERN_LENS_AREA_M2, rel=0.04)
    for name, cd in [
        ("nav_masthead_white", 94.0),
        ("nav_port_red", 12.0),
        ("nav_starboard_green", 12.0),
        ("nav_stern_white", 12.0),
    ]:
        e = MATERIALS[material_id(name)].emissive
        luminance = 0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2]
        assert luminance * LANTERN_LENS_AREA_M2 == pytest.approx(cd, rel=1e-6), name


def _rule_22(light: str, length: float) -> float:
    """COLREG 1972 Rule 22's range of visibility (nautical miles), written out here from the rule's text."""
    if length >= 50.0:  # Rule 22(a)
        return {"masthead": 6, "side": 3, "stern": 3}[light]
    if length >= 12.0:  # Rule 22(b)
        return {"masthead": 3 if length < 20.0 else 5, "side": 2, "stern": 2}[light]
    return {"masthead": 2, "side": 1, "stern": 2}[light]  # Rule 22(c)


def _annex_i(miles: float) -> float:
    """COLREG Annex I §8(a): ``I = 3.43·10⁶ T D² K^−D`` cd, ``T = 2·10⁻⁷`` lux, ``K = 0.8``."""
    return 3.43e6 * 2e-7 * miles**2 * 0.8**-miles


def test_annex_i_table_is_its_formula() -> None:
    # §8(b) tabulates the formula to a tenth below 10 cd and to the candela above (0.857 -> 0.9, 94.2 -> 94).
    assert sorted(COLREG_RANGE_INTENSITY_CD) == [1, 2, 3, 4, 5, 6]
    for miles, cd in COLREG_RANGE_INTENSITY_CD.items():
        i = _annex_i(miles)
        assert (round(i, 1) if i < 10 else round(i)) == cd, miles


_LIGHT = {"nav_masthead_white": "masthead", "nav_port_red": "side", "nav_starboard_green": "side"}


@pytest.mark.parametrize("name", asset_names())
def test_each_lamp_has_the_intensity_its_vessels_length_asks(name: str) -> None:
    """Every lantern of every catalogue asset, measured from its mesh: its lamp faces' projected area towards the
    centre of its arc (half the sum of |area vector · direction| over the closed lens band) times the luminance of
    their radiance is COLREG Annex I §8's intensity for the range Rule 22 asks of the asset's length, whatever the
    lantern's size (the lanterns scaled their intensity with their size: a 300 m ship's masthead light was 212 cd,
    a 16.5 m pilot boat's 23.5 cd for the 12 cd of its length). Within 5 %: the 12-sided band's width varies by
    3.4 % with the direction."""
    asset = get_asset(name)
    m = asset.mesh
    tri = np.asarray(m.vertices, dtype=np.float64)[np.asarray(m.faces)]
    area = 0.5 * np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    centres = tri.mean(axis=1)
    table = all_materials()
    seen = 0
    for lamp in ("nav_masthead_white", "nav_port_red", "nav_starboard_green", "nav_stern_white"):
        faces = np.flatnonzero(np.isin(m.materials, lamp_ids(lamp)))
        while faces.size:  # one lantern at a time (a long hull has two masthead lights)
            near = faces[np.linalg.norm(centres[faces] - centres[faces[0]], axis=1) < 1.0]
            faces = np.setdiff1d(faces, near)
            mats = {int(i) for i in m.materials[near]}
            assert len(mats) == 1
            mat = table[mats.pop()]
            bearing = math.radians(mat.arc_deg[0])
            d = np.array([math.cos(bearing), math.sin(bearing), 0.0])
            e = mat.emissive
            cd = (0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2]) * 0.5 * np.abs(area[near] @ d).sum()
            want = _annex_i(_rule_22(_LIGHT.get(lamp, "stern"), asset.length))
            assert cd == pytest.approx(want, rel=0.05), (lamp, cd, want, mat.name)
            seen += 1
    assert seen >= 3


def test_lamp_variants_keep_the_lamps_colour_and_arc() -> None:
    for lamp in ("nav_masthead_white", "nav_port_red", "nav_starboard_green", "nav_stern_white"):
        base = MATERIALS[material_id(lamp)]
        assert lamp_material(lamp, length_m=60.0, lantern_size=0.3) == material_id(lamp)
        i = lamp_material(lamp, length_m=8.0, lantern_size=0.07)
        assert i == lamp_material(lamp, length_m=8.0, lantern_size=0.07) != material_id(lamp)
        v = all_materials()[i]
        assert lamp_of(v) == lamp and lamp_of(base) == lamp and i in lamp_ids(lamp)
        assert v.nav_light and v.arc_deg == base.arc_deg and v.base_color == base.base_color
        ratio = np.array(v.emissive) / np.array(base.emissive).clip(1e-30)
        assert np.allclose(ratio[np.array(base.emissive) > 0], ratio.max(), rtol=1e-6)  # the same colour
    assert lamp_of(MATERIALS[material_id("glass")]) is None
    with pytest.raises(ValueError, match="unknown navigation lamp 'glass'"):
        lamp_material("glass", length_m=10.0, lantern_size=0.3)


def test_unknown_name_lists_the_known_ones() -> None:
    with pytest.raises(ConfigError, match=r"unknown material 'hull_purple'.*known materials: class_default"):
        material_id("hull_purple")


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"base_color": (1.2, 0.0, 0.0)}, "base_color"),
        ({"base_color": (0.1, 0.2)}, "base_color"),
        ({"roughness": 0.0}, "roughness"),
        ({"metallic": 1.5}, "metallic"),
        ({"emissive": (-1.0, 0.0, 0.0)}, "emissive"),
        ({"roughness": float("nan")}, "roughness"),
        ({"arc_deg": (0.0, 0.0)}, "arc_deg"),
        ({"arc_deg": (270.0, 45.0)}, "arc_deg"),
        ({"arc_deg": (0.0,)}, "arc_deg"),
    ],
)
def test_material_checks_its_fields(kwargs: dict[str, object], field: str) -> None:
    args: dict[str, object] = {"name": "bad", "base_color": (0.5, 0.5, 0.5), "roughness": 0.5, "metallic": 0.0}
    args.update(kwargs)
    with pytest.raises(ConfigError, match=f"material 'bad'.{field}"):
        Material(**args)  # type: ignore[arg-type]


def test_register_same_material_twice_gives_the_same_id() -> None:
    m = Material("test_reg:paint", (0.1, 0.2, 0.3), 0.4, 0.0)
    i = register_material(m)
    assert i >= BUILTIN_COUNT and register_material(Material("test_reg:paint", (0.1, 0.2, 0.3), 0.4, 0.0)) == i
    assert material_id("test_reg:paint") == i and all_materials()[i] == m
    np.testing.assert_allclose(material_table()[i], [0.1, 0.2, 0.3, 0.4, 0, 0, 0, 0, 0, 0, 180], rtol=1e-6)
    with pytest.raises(ConfigError, match="already registered"):
        register_material(Material("test_reg:paint", (0.9, 0.2, 0.3), 0.4, 0.0))
    assert register_material(MATERIALS[3]) == 3


# ------------------------------------------------------------------------------------------- TriMesh


def test_trimesh_materials_default_broadcast_merge_and_transform() -> None:
    a = box(center=(0.0, 0.0, 0.0), size=(1.0, 1.0, 1.0), cls=10)
    assert a.materials.dtype == np.uint16 and a.materials.shape == (12,) and not a.materials.any()
    b = TriMesh(a.vertices, a.faces, a.classes, np.array([7]))
    assert np.all(b.materials == 7)
    with pytest.raises(ValueError, match="materials has 3 entries for 12 faces"):
        TriMesh(a.vertices, a.faces, a.classes, np.array([1, 2, 3]))
    m = merge([a, b])
    assert m.materials.tolist() == [0] * 12 + [7] * 12
    t = transformed(b, rotation=np.eye(3), translation=(1.0, 2.0, 3.0))
    assert np.array_equal(t.materials, b.materials)


# ------------------------------------------------------------------------------------------ builders


def test_boxes_are_closed_with_their_volume_and_materials() -> None:
    rng = np.random.default_rng(0)
    c = rng.normal(size=(5, 3)) * 10
    s = rng.uniform(0.5, 3.0, size=(5, 3))
    m = boxes(centers=c, sizes=s, cls=3, material=np.arange(5), yaw=rng.uniform(-3, 3, 5))
    ok, vol = _closed_outward(m)
    assert ok and vol == pytest.approx(float(np.prod(s, axis=1).sum()), rel=1e-12)
    assert m.materials.tolist() == np.repeat(np.arange(5), 12).tolist()
    ref = merge([box(center=c[i], size=s[i], cls=3) for i in range(5)])  # unturned reference
    flat = boxes(centers=c, sizes=s, cls=3)
    np.testing.assert_allclose(flat.vertices, ref.vertices, atol=1e-12)


def test_tubes_are_closed_prisms_of_their_polygon_volume() -> None:
    p0 = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 3.0], [0.0, 0.0, 5.0]])
    p1 = np.array([[3.0, 0.0, 0.0], [1.0, 2.0, 7.0], [2.0, 1.0, 6.0]])
    r, n = 0.3, 8
    m = tubes(starts=p0, ends=p1, radius=r, cls=1, segments=n)
    ok, vol = _closed_outward(m)
    length = np.linalg.norm(p1 - p0, axis=1).sum()
    assert ok and vol == pytest.approx(n / 2 * r * r * math.sin(2 * math.pi / n) * length, rel=1e-9)
    assert m.num_triangles == 3 * 4 * n


def test_lathe_sweep_torus_and_placed_are_closed() -> None:
    cyl = lathe([(1.0, 0.0), (1.0, 2.0)], cls=1, segments=16, material=5)
    ok, vol = _closed_outward(cyl)
    assert ok and vol == pytest.approx(8 * math.sin(2 * math.pi / 16) * 2.0, rel=1e-12)
    banded = lathe([(0.0, 0.0), (1.0, 0.5), (0.8, 1.0), (0.0, 1.2)], cls=1, segments=10, material=np.array([1, 2, 3]))
    assert _closed_outward(banded)[0] and set(banded.materials.tolist()) == {1, 2, 3}
    path = np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [5.0, 5.0, 0.0]])
    s = sweep(path, radius=0.1, cls=1, segments=6)
    assert _closed_outward(s)[0] and _closed_outward(s)[1] > 0
    loop = sweep(
        np.array([[0.0, 0.0, 1.0], [4.0, 0.0, 1.0], [4.0, 3.0, 1.0], [0.0, 3.0, 1.0]]), radius=0.1, cls=1, closed=True
    )
    assert _closed_outward(loop)[0] and _closed_outward(loop)[1] > 0
    t = torus(major=1.0, minor=0.25, cls=1, segments=(32, 16))
    ok, vol = _closed_outward(t)
    # Pappus with the 16-gon section's area, times the 32-gon revolution's area ratio to the circle's
    section = 8 * 0.25**2 * math.sin(2 * math.pi / 16)
    ring = 16 * math.sin(2 * math.pi / 32) / math.pi
    assert ok and vol == pytest.approx(2 * math.pi * 1.0 * section * ring, rel=1e-3)
    many = placed(t, rotations=np.array([0.0, 1.0]), translations=np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0]]))
    ok2, vol2 = _closed_outward(many)
    assert ok2 and vol2 == pytest.approx(2 * vol, rel=1e-12)


# -------------------------------------------------------------------------------------------------- glTF


def test_gltf_pbr_materials_come_through_per_face(tmp_path: Path) -> None:
    trimesh = pytest.importorskip("trimesh")
    from trimesh.visual.material import PBRMaterial

    red = PBRMaterial(name="red_paint", baseColorFactor=[0.8, 0.1, 0.1, 1.0], metallicFactor=0.0, roughnessFactor=0.6)
    blue = PBRMaterial(
        name="blue_metal",
        baseColorFactor=[0.1, 0.2, 0.9, 1.0],
        metallicFactor=1.0,
        roughnessFactor=0.3,
        emissiveFactor=[0.0, 0.0, 0.5],
    )
    a = trimesh.creation.box(extents=(2.0, 1.0, 1.0))
    a.apply_translation((-1.0, 0.0, 0.0))
    a.visual = trimesh.visual.TextureVisuals(material=red)
    b = trimesh.creation.box(extents=(2.0, 1.0, 2.0))
    b.apply_translation((1.0, 0.0, 0.5))
    b.visual = trimesh.visual.TextureVisuals(material=blue)
    path = tmp_path / "two.glb"
    path.write_bytes(trimesh.Scene([a, b]).export(file_type="glb"))
    # written z-up, x forward (not glTF's +Y up, +Z front): the entry says so
    zup = {"up_axis": "z", "forward_axis": "x"}
    asset = load_asset_file({"name": "two_boxes", "mesh": str(path), "waterline_z": 0.0, **zup})
    mesh = asset.mesh
    centroid_x = mesh.vertices[mesh.faces].mean(axis=1)[:, 0]
    ids_a = set(mesh.materials[centroid_x < -0.01].tolist())
    ids_b = set(mesh.materials[centroid_x > 0.01].tolist())
    assert len(ids_a) == 1 and len(ids_b) == 1 and ids_a != ids_b
    ma, mb = all_materials()[ids_a.pop()], all_materials()[ids_b.pop()]
    assert ma.name == "two:red_paint" and mb.name == "two:blue_metal"
    # glTF's baseColorFactor is linear (stored by trimesh as 8-bit): the factors, to 1/255
    np.testing.assert_allclose(ma.base_color, [0.8, 0.1, 0.1], atol=1 / 255)
    np.testing.assert_allclose(mb.base_color, [0.1, 0.2, 0.9], atol=1 / 255)
    assert (ma.roughness, ma.metallic, mb.roughness, mb.metallic) == pytest.approx((0.6, 0.0, 0.3, 1.0))
    assert mb.emissive[2] > 0 and ma.emissive == (0.0, 0.0, 0.0)
    again = load_asset_file({"name": "two_boxes", "mesh": str(path), "waterline_z": 0.0, **zup})
    assert np.array_equal(again.mesh.materials, mesh.materials)  # the same materials, the same ids


def test_gltf_base_colour_texture_mean_is_taken_in_linear_rgb(tmp_path: Path) -> None:
    trimesh = pytest.importorskip("trimesh")
    from PIL import Image
    from trimesh.visual.material import PBRMaterial

    img = Image.fromarray(np.array([[[255, 0, 0], [0, 0, 188]]], dtype=np.uint8))  # sRGB red and a darker blue
    b = trimesh.creation.box(extents=(2.0, 1.0, 1.0))
    uv = (b.vertices[:, :2] - b.vertices[:, :2].min(axis=0)) / np.ptp(b.vertices[:, :2], axis=0)
    mat = PBRMaterial(name="textured", baseColorFactor=[1.0, 0.5, 1.0, 1.0], baseColorTexture=img)
    b.visual = trimesh.visual.TextureVisuals(uv=uv, material=mat)
    path = tmp_path / "tex.glb"
    path.write_bytes(trimesh.Scene([b]).export(file_type="glb"))
    a = load_asset_file({"name": "tex_box", "mesh": str(path), "up_axis": "z", "forward_axis": "x"})
    m = all_materials()[int(a.mesh.materials[0])]
    # sRGB 188/255 decodes to ((188/255 + 0.055) / 1.055) ** 2.4 linear; the mean of the two pixels, times the factor
    blue = ((188 / 255 + 0.055) / 1.055) ** 2.4
    np.testing.assert_allclose(m.base_color, [0.5 * 1.0, 0.0, 0.5 * blue], atol=1e-6)
