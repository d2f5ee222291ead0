"""The vessel library at real detail (issue #28): triangle floors, the part kinds each type carries, the materials
of hulls and parts, COLREG light placement, and the contact sheet of ``mmusv assets --render``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv.world.asset_spec import ProceduralAssetSpec, parse_asset
from mmusv.world.hull_form import boot_top_band
from mmusv.world.materials import all_materials, lamp_ids, material_id
from mmusv.world.part_spec import DEFAULT_MATERIALS
from mmusv.world.parts_deck import CONTAINER_COLOURS
from mmusv.world.primitives import TriMesh
from mmusv.world.vessel_shapes import build_parts
from mmusv.world.vessels import _builtin_entries, asset_names, get_asset, load_asset_file
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

NAMES = [n for n in asset_names() if n in _builtin_entries()]
NAV = ("nav_masthead_white", "nav_port_red", "nav_starboard_green", "nav_stern_white")


def _floor(length: float) -> int:
    """The issue's triangle floor for a vessel of ``length`` metres."""
    return 4000 if length < 15.0 else 15000 if length < 80.0 else 40000


def _spec(name: str) -> ProceduralAssetSpec:
    spec = parse_asset(_builtin_entries()[name], path=name)
    assert isinstance(spec, ProceduralAssetSpec)
    return spec


def _pieces(m: TriMesh, faces: np.ndarray) -> int:
    """Number of connected pieces among ``faces`` (indices into ``m.faces``)."""
    f = m.faces[faces]
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]]])
    n = m.vertices.shape[0]
    g = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, label = connected_components(g, directed=False)
    return int(np.unique(label[f[:, 0]]).shape[0])


# ------------------------------------------------------------------------------------------ floors and kinds


@pytest.mark.parametrize("name", NAMES)
def test_triangle_floor_and_part_kinds(name: str) -> None:
    a = get_asset(name)
    assert a.num_triangles >= _floor(a.length), f"{name}: {a.num_triangles} triangles"
    kinds = set(a.parts)
    assert "nav_lights" in kinds
    need = 5 if a.length < 15.0 else 8 if a.length < 80.0 else 10
    assert len(kinds) >= need, f"{name}: only {sorted(kinds)}"
    if a.length >= 15.0:
        assert "railing" in kinds
    if a.length >= 80.0:
        assert {"lifeboats", "radar", "funnel", "antennas"} <= kinds, sorted(kinds)
    by_category: dict[str, set[str]] = {
        "container_ship": {"containers", "hatches"},
        "bulk_carrier": {"hatches"},
        "general_cargo": {"hatches", "crane"},
        "tug": {"fenders", "winch"},
        "ferry": {"windows", "lifeboats"},
        "cruise_ship": {"windows", "lifeboats"},
        "tanker": {"pipes"},
        "chemical_tanker": {"pipes", "crane"},
        "fishing_boat": {"fenders", "winch"},
    }
    assert by_category.get(a.category, set()) <= kinds, sorted(kinds)


def test_ferries_have_rows_of_windows() -> None:
    glass = material_id("glass")
    for name in ("ropax_ferry_90m", "cruise_ship_300m", "catamaran_ferry_40m"):
        m = get_asset(name).mesh
        windows = _pieces(m, np.flatnonzero(m.materials == glass))
        assert windows >= 100, f"{name}: {windows} windows"


# ---------------------------------------------------------------------------------------------- materials


@pytest.mark.parametrize("name", NAMES)
def test_every_face_has_a_valid_material_and_parts_theirs(name: str) -> None:
    spec = _spec(name)
    m, origin = build_parts(hull=spec.hull, parts=spec.parts, path=name, cls=10)
    assert np.array_equal(m.materials, get_asset(name).mesh.materials)
    assert m.materials.max() < len(all_materials())
    assert 0 not in set(m.materials.tolist())  # every built-in face has a real material, none the class fallback
    for i, part in enumerate(spec.parts):
        mats = set(m.materials[origin == i].tolist())
        want = part.material or DEFAULT_MATERIALS[part.type]
        if want == "<topside>":
            want = spec.hull.topside
        if part.type == "containers":
            colours = {material_id(c) for c in CONTAINER_COLOURS}
            assert mats <= colours and len(mats) >= min(3, int((origin == i).sum() // 12))
        elif part.type == "nav_lights":
            # masthead: [] is a vessel without a masthead light (under sail, under oars or towed: COLREG Rules 24-25)
            lamps = NAV[1:] if part.masthead == () else NAV
            assert (
                all(mats & set(lamp_ids(n)) for n in lamps)
                and material_id(want if part.material else "paint_grey") in mats
            )
        else:
            assert material_id(want) in mats, f"{name}.parts[{i}] ({part.type}) lacks {want}"
        if part.type == "windows":  # panes of the part's material (glass by default) in aluminium frames
            assert {material_id(want), material_id("aluminium")} <= mats
        if part.type == "funnel":
            assert material_id("funnel_black") in mats


@pytest.mark.parametrize("name", NAMES)
def test_hull_bands_antifouling_boot_top_topside_deck(name: str) -> None:
    spec = _spec(name)
    hull = spec.hull
    m, _ = build_parts(hull=hull, parts=(), path=name, cls=10)
    t = m.vertices[m.faces]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    nz = n[:, 2] / np.linalg.norm(n, axis=1)
    z = t[:, :, 2].mean(axis=1)
    lo, hi = boot_top_band(hull)
    mat = m.materials
    side = np.abs(nz) < 0.5
    # by face centroid; above water the rings follow the sheer, so the band's top is hi scaled with the deck line
    zc, xc = t[:, :, 2].mean(axis=1), t[:, :, 0].mean(axis=1)
    deck = hull.freeboard + hull.sheer * np.clip(xc / (hull.length / 2.0), 0.0, 1.0) ** 2
    band_top = hi * deck / hull.freeboard
    below = side & (zc < lo)
    boot = side & (zc > lo) & (zc < band_top)
    above = side & (zc > band_top)
    assert np.all(mat[below] == material_id("antifouling_red")) and below.any()
    assert np.all(mat[boot] == material_id("boot_top")) and boot.any()
    assert np.all(mat[above] == material_id(hull.topside)) and above.any()
    assert below.sum() + boot.sum() + above.sum() == side.sum()  # every side face in exactly one band
    top = nz > 0.99
    assert np.all(mat[top & (z > hull.freeboard - 1e-6)] == material_id(hull.deck))
    assert np.all(mat[nz < -0.99] == material_id("antifouling_red"))


@pytest.mark.parametrize("name", NAMES)
def test_colreg_lights_port_red_starboard_green_stern_aft(name: str) -> None:
    m = get_asset(name).mesh
    c = m.vertices[m.faces].mean(axis=1)
    where = {k: c[np.isin(m.materials, lamp_ids(k))] for k in NAV}
    # masthead: [] (under sail, under oars or towed: COLREG Rules 24-25) leaves the masthead lamp out
    lamps = NAV[1:] if any(p.type == "nav_lights" and p.masthead == () for p in _spec(name).parts) else NAV
    assert all(where[k].shape[0] > 0 for k in lamps)
    assert np.all(where["nav_port_red"][:, 1] > 0.0) and np.all(where["nav_starboard_green"][:, 1] < 0.0)
    assert where["nav_stern_white"][:, 0].max() < where["nav_port_red"][:, 0].min()
    lamp = all_materials()[int(m.materials[np.isin(m.materials, lamp_ids("nav_port_red"))][0])]
    assert lamp.nav_light and lamp.emissive[0] > 0


def test_bulbous_bow_stays_inside_the_hull_length_and_below_water() -> None:
    a = get_asset("bulk_carrier_190m")
    spec = _spec("bulk_carrier_190m")
    m, _ = build_parts(hull=spec.hull, parts=(), path="b", cls=10)
    plain = build_parts(hull=spec.hull.model_copy(update={"bulb": 0.0}), parts=(), path="b", cls=10)[0]
    extra = m.vertices[m.vertices.shape[0] - (m.vertices.shape[0] - plain.vertices.shape[0]) :]
    assert extra.shape[0] > 0 and extra[:, 2].max() < 0.0 and extra[:, 0].max() < a.length / 2.0
    assert extra[:, 0].max() > 0.45 * a.length  # it is at the bow


# ------------------------------------------------------------------------------------------ part geometry

SQUARE = {"length": 40.0, "beam": 12.0, "draft": 2.0, "depth": 5.0, "bow": 0.0, "stern": 0.0, "rake": 0.0}


def _build(parts: list[dict[str, Any]]) -> tuple[TriMesh, np.ndarray]:
    spec = parse_asset({"name": "t", "hull": SQUARE, "parts": parts}, path="t")
    assert isinstance(spec, ProceduralAssetSpec)
    return build_parts(hull=spec.hull, parts=spec.parts, path="t", cls=10)


def test_containers_are_one_box_each_and_fit_drops_outer_rows() -> None:
    p = {"type": "containers", "x0": -15.0, "x1": 15.0, "bays": 2, "rows": 4, "tiers": [2, 3], "width": 10.0}
    m, origin = _build([p])
    faces = np.flatnonzero(origin == 0)
    assert faces.shape[0] == 12 * (4 * 2 + 4 * 3) and _pieces(m, faces) == 20
    narrow = dict(p, fit=2.5)  # half-width 6 - 2.5 = 3.5 m: two 2.44 m rows fit, not three
    m2, o2 = _build([narrow])
    assert _pieces(m2, np.flatnonzero(o2 == 0)) == 2 * 2 + 2 * 3
    y = m2.vertices[m2.faces[o2 == 0]][:, :, 1]
    assert np.abs(y).max() <= 3.5 and abs(y.max() + y.min()) < 1e-9  # centred


def test_railing_has_a_stanchion_every_spacing_and_its_rails() -> None:
    p = {"type": "railing", "x0": -10.0, "x1": 10.0, "spacing": 2.0, "rails": 2, "height": 1.0, "inset": 0.2}
    m, origin = _build([p])
    faces = np.flatnonzero(origin == 0)
    posts = 2 * 11  # (20 m / 2 m + 1) per side
    assert _pieces(m, faces) == posts + 2 * 2
    v = m.vertices[m.faces[faces]]
    assert v[:, :, 2].max() == pytest.approx(3.0 + 1.0, abs=1e-9)  # deck 3 m + 1 m height
    assert np.abs(v[:, :, 1]).max() <= 6.0 - 0.2 + 0.04


def test_fenders_hang_on_the_side_within_the_beam() -> None:
    m, origin = _build([{"type": "fenders", "x0": -10.0, "x1": 10.0, "count": 5, "z": 1.0, "radius": 0.5}])
    faces = np.flatnonzero(origin == 0)
    assert _pieces(m, faces) == 10
    y = np.abs(m.vertices[m.faces[faces]][:, :, 1])
    assert y.max() <= 6.0 + 1e-9 and y.min() >= 6.0 - 2 * 0.5 * 0.32 - 0.5 * 0.32 - 1e-9


def test_glb_user_mesh_keeps_per_face_materials_through_the_asset(tmp_path: Path) -> None:
    trimesh = pytest.importorskip("trimesh")
    from trimesh.visual.material import PBRMaterial

    box = trimesh.creation.box(extents=(4.0, 2.0, 2.0))
    box.visual = trimesh.visual.TextureVisuals(material=PBRMaterial(name="grey", baseColorFactor=[0.5, 0.5, 0.5, 1]))
    path = tmp_path / "one.glb"
    path.write_bytes(trimesh.Scene([box]).export(file_type="glb"))
    a = load_asset_file({"name": "one_box", "mesh": str(path), "up_axis": "z", "forward_axis": "x"})  # written z-up
    assert len(set(a.mesh.materials.tolist())) == 1 and all_materials()[int(a.mesh.materials[0])].name == "one:grey"


# ------------------------------------------------------------------------------------------- contact sheet


def test_contact_sheet_grid_labels_and_determinism(tmp_path: Path) -> None:
    from mmusv.world.contact_sheet import LABEL_H, sheet_layout, write_contact_sheet
    from PIL import Image

    names = ["jet_ski_3m", "kayak_4m", "usv_wamv"]
    path = write_contact_sheet(tmp_path / "a", names=names, tile=(80, 60), asset_size=(96, 72))
    assert sheet_layout(3, (80, 60)).size == (2 * 80, 2 * (60 + LABEL_H))
    sheet = np.asarray(Image.open(path))
    assert sheet.shape == (2 * (60 + LABEL_H), 2 * 80, 3)
    for n in names:
        img = np.asarray(Image.open(tmp_path / "a" / f"{n}.png"))
        assert img.shape == (72, 96, 3)
        centre, corner = img[30:42, 40:56].reshape(-1, 3), img[:6, :6].reshape(-1, 3)
        assert np.abs(centre.mean(axis=0) - corner.mean(axis=0)).max() > 5  # the vessel, not just sky
    again = write_contact_sheet(tmp_path / "b", names=names, tile=(80, 60), asset_size=(96, 72))
    assert again.read_bytes() == path.read_bytes()
    assert sheet_layout(37, (1, 1)).cols == 7 and sheet_layout(37, (1, 1)).rows == 6


def test_cli_assets_lists_parts_and_render_names_a_bad_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.cli import main

    afile = tmp_path / "a_file"
    afile.write_text("x")
    assert main(["assets", "--render", str(afile)]) == 2
    out, err = capsys.readouterr()
    # Named before the table is printed (the folder is checked first).
    assert "mmusv: error: --render" in err and "is a file, not a folder" in err and "parts" not in out
    assert main(["assets"]) == 0
    assert "parts" in capsys.readouterr().out
    assert not list(tmp_path.glob("*.png"))


@pytest.mark.parametrize(
    ("kwargs", "said"),
    [
        # a bare string was read as its letters: "unknown vessel asset 'u'"
        pytest.param(
            {"names": "usv_wamv"},
            "names = 'usv_wamv': must be a list of names, e.g. ['usv_wamv'], not a single string",
            id="names-string",
        ),
        # sizes were PIL's and numpy's own errors (ValueError, OverflowError, TypeError, IndexError)
        pytest.param({"tile": (0, 0)}, "tile[0] = 0: must be a whole number in 1..16384", id="tile-zero"),
        pytest.param({"tile": "a"}, "tile = 'a': must be (width, height) in pixels", id="tile-text"),
        pytest.param(
            {"asset_size": (-5, 10)}, "asset_size[0] = -5: must be a whole number in 1..16384", id="size-negative"
        ),
        pytest.param({"asset_size": (2.5, 10)}, "asset_size[0] = 2.5: must be a whole number", id="size-float"),
        pytest.param(
            {"asset_size": (16384, 16384)},
            "asset_size = (16384, 16384): 268,435,456 pixels, more than a camera's",
            id="size-huge",
        ),
        pytest.param(
            {"tile": (16384, 100), "names": ["usv_wamv", "kayak_4m"]},
            "the sheet of 2 assets would be 32768 x 122",
            id="sheet-huge",
        ),
        # the first assets were rendered and written before the unknown one was named
        pytest.param({"names": ["usv_wamv", "nope"]}, "unknown vessel asset 'nope'", id="unknown-after-known"),
    ],
)
def test_contact_sheet_refuses_bad_arguments_before_writing(tmp_path: Path, kwargs: dict[str, Any], said: str) -> None:
    from mmusv.errors import MmusvError
    from mmusv.world.contact_sheet import write_contact_sheet

    with pytest.raises(MmusvError) as err:
        write_contact_sheet(tmp_path / "sheet", **{"names": ["usv_wamv"], "asset_size": (8, 6), **kwargs})
    assert said in str(err.value)
    assert not (tmp_path / "sheet").exists()


def test_contact_sheet_takes_a_generator_of_names_and_numpy_sizes(tmp_path: Path) -> None:
    """Valid before the arguments were checked: names from a generator (refused as 'not generator') and sizes
    as numpy arrays (refused as 'must be (width, height)'); a 2-D or float array is still refused."""
    from mmusv.errors import ConfigError
    from mmusv.world.contact_sheet import write_contact_sheet
    from PIL import Image

    path = write_contact_sheet(
        tmp_path / "a",
        names=(n for n in ["usv_wamv", "kayak_4m"]),
        tile=np.array([16, 12]),
        asset_size=np.array([8, 6], dtype=np.int32),
    )
    assert sorted(p.name for p in path.parent.glob("*.png")) == ["contact_sheet.png", "kayak_4m.png", "usv_wamv.png"]
    with Image.open(tmp_path / "a" / "usv_wamv.png") as img:
        assert img.size == (8, 6)
    for bad in (np.array([[16, 12]]), np.array([16.0, 12.0])):
        with pytest.raises(ConfigError, match="tile"):
            write_contact_sheet(tmp_path / "b", names=["usv_wamv"], tile=bad, asset_size=(8, 6))
    assert not (tmp_path / "b").exists()


def test_contact_sheet_names_the_file_it_cannot_write(tmp_path: Path) -> None:
    """A PNG that cannot be written was a bare OSError naming the hidden temporary file."""
    from mmusv.errors import IoError
    from mmusv.world.contact_sheet import write_contact_sheet

    (tmp_path / ".usv_wamv.png.part").mkdir()  # in the way of the temporary file
    with pytest.raises(IoError, match=r"cannot write .*/usv_wamv\.png: Is a directory \(.*\.usv_wamv\.png\.part\)$"):
        write_contact_sheet(tmp_path, names=["usv_wamv"], asset_size=(8, 6))
    assert not (tmp_path / "usv_wamv.png").exists() and not (tmp_path / "contact_sheet.png").exists()


def test_contact_sheet_keeps_files_of_its_names_already_there(tmp_path: Path) -> None:
    """A ``contact_sheet.png`` (or ``<asset>.png``) of the user's in the folder was replaced without a word: now
    an IoError naming the folder and the files, before anything is written; ``overwrite=True`` replaces them."""
    from mmusv.errors import ConfigError, IoError
    from mmusv.world.contact_sheet import write_contact_sheet

    mine = tmp_path / "contact_sheet.png"
    mine.write_bytes(b"my own picture")
    with pytest.raises(IoError) as err:
        write_contact_sheet(tmp_path, names=["usv_wamv"], asset_size=(8, 6))
    assert str(err.value) == (
        f"out_dir {tmp_path}: contact_sheet.png is already there (from an earlier run, or files of yours); pass "
        "overwrite=True to replace it, or give another folder"
    )
    assert mine.read_bytes() == b"my own picture" and sorted(p.name for p in tmp_path.iterdir()) == [mine.name]
    path = write_contact_sheet(tmp_path, names=["usv_wamv"], asset_size=(8, 6), overwrite=True)
    assert path == mine and mine.read_bytes().startswith(b"\x89PNG")
    above = tmp_path / "a_file"
    above.write_text("x")
    with pytest.raises(ConfigError, match=r"out_dir = '.*a_file/sheet': '.*a_file' is a file, not a folder$"):
        write_contact_sheet(above / "sheet", names=["usv_wamv"], asset_size=(8, 6))  # it was mkdir's bare OSError


def test_cli_assets_render_keeps_files_of_its_names_already_there(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``mmusv assets --render DIR`` replaced a user's ``DIR/usv_wamv.png`` and ``contact_sheet.png`` without a
    word; now refused before the table, naming --render, the files and --overwrite."""
    from mmusv.cli import main

    (tmp_path / "usv_wamv.png").write_bytes(b"mine")
    (tmp_path / "contact_sheet.png").write_bytes(b"also mine")
    assert main(["assets", "--render", str(tmp_path)]) == 2
    out, err = capsys.readouterr()
    assert err.strip() == (
        f"mmusv: error: --render {tmp_path}: usv_wamv.png, contact_sheet.png are already there (from an earlier "
        "run, or files of yours); pass --overwrite to replace them, or give another folder"
    )
    assert "parts" not in out
    assert (tmp_path / "usv_wamv.png").read_bytes() == b"mine"
    assert (tmp_path / "contact_sheet.png").read_bytes() == b"also mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["contact_sheet.png", "usv_wamv.png"]
    assert main(["assets", "--overwrite"]) == 2  # nothing to overwrite without --render: said, not ignored
    assert "--overwrite: only with --render DIR" in capsys.readouterr().err
