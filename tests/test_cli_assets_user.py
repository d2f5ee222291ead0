"""``mmusv assets FILE...``: a user's own vessel assets, of asset files and of scenarios' ``assets:`` lists, listed
with the library's columns (and the file each comes from) and drawn by ``--render``; a bad file is one error line
naming it (exit status 2) before anything is written. The command only reads: the per-process asset library is as
it was afterwards (:mod:`mmusv.scenario_assets`)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from help_pages import check_help_page
from mmusv import scenario_assets
from mmusv.cli import main
from mmusv.cli_parser import parser
from mmusv.errors import ConfigError
from mmusv.world.contact_sheet import write_contact_sheet
from mmusv.world.vessels import asset_names, load_asset_file
from user_assets import write_boat


@pytest.fixture(autouse=True)
def library_untouched() -> Iterator[None]:
    """Every test leaves the library and the scenario-asset cache as they were: ``mmusv assets`` registers
    nothing."""
    before = (asset_names(), dict(scenario_assets._loaded), dict(scenario_assets._parked))
    yield
    assert (asset_names(), dict(scenario_assets._loaded), dict(scenario_assets._parked)) == before


@pytest.fixture
def here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A current folder holding ``models/boat.yaml`` (asset ``my_boat``, 6 m) and ``with_boat.yaml``, a scenario
    whose ``assets:`` lists it."""
    monkeypatch.chdir(tmp_path)
    write_boat(tmp_path / "models" / "boat.yaml", name="my_boat")
    _scenario(tmp_path / "with_boat.yaml", ["models/boat.yaml"])
    return tmp_path


def _scenario(path: Path, assets: object, asset: str = "my_boat") -> None:
    vessel = {"id": "usv_1", "role": "usv", "asset": asset, "speed_mps": 2, "route": [[0, 0], [200, 0]]}
    data = {"vessels": [vessel]} if assets is None else {"assets": assets, "vessels": [vessel]}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(data), encoding="utf-8")


def _rows(out: str) -> list[list[str]]:
    """The table's rows, each as its cells."""
    return [[c.strip() for c in line.strip("│ ").split("│")] for line in out.splitlines() if line.startswith("│")]


def _ok(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[str, str]:
    assert main(argv) == 0
    return capsys.readouterr()


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """Runs ``mmusv argv``; asserts exit status 2, one ``mmusv: error:`` line and nothing printed; returns it."""
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert err.startswith("mmusv: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    assert out == "", out
    return err.strip()


def test_an_asset_file_lists_its_asset_with_the_library_columns_and_its_file(
    here: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, _ = _ok(["assets", "models/boat.yaml"], capsys)
    assert "Your vessel assets" in out and "usv_wamv" not in out  # the user's only, not the library
    header = [c.strip() for c in next(x for x in out.splitlines() if x.startswith("┃")).strip("┃ ").split("┃")]
    assert header == [
        *("name", "category", "class", "length m", "beam m", "height m", "draft m", "triangles", "parts"),
        *("materials", "file"),
    ]
    assert _rows(out) == [
        ["my_boat", "custom", "vessel", "6.0", "2.4", "1.6", "0.4", "12", "0", "1", str(Path("models/boat.yaml"))]
    ]


def _cells(out: str) -> list[list[str]]:
    """The tables' rows, each as all its cells (empty ones kept)."""
    return [[c.strip() for c in line.split("│")[1:-1]] for line in out.splitlines() if line.startswith("│")]


def _srgb_hex(linear: list[float]) -> str:
    """IEC 61966-2-1's encoding of linear RGB, to 8 bits, as #rrggbb (written out here, not mmusv's)."""
    enc = [12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055 for c in linear]
    return "#" + "".join(f"{round(e * 255):02x}" for e in enc)


def test_materials_lists_what_the_importer_read_of_each_material(
    here: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # A glTF hull of two materials, as glTF 2.0 writes them (3.9.2: baseColorFactor linear, metallicFactor,
    # roughnessFactor): the table gives each by name with its faces, its values and its sRGB. Before, the asset
    # table gave the count of materials alone (2), so a user could not see what was read.
    from test_gltf_import_recheck import HULL, MARK, Doc

    monkeypatch.setenv("COLUMNS", "250")
    d = Doc()
    paint = {"baseColorFactor": [0.5, 0.05, 0.02, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.6}
    rail = {"baseColorFactor": [0.56, 0.57, 0.58, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.3}
    red = d.add("materials", name="red_paint", pbrMetallicRoughness=paint)
    steel = d.add("materials", name="rail_steel", pbrMetallicRoughness=rail)
    d.add("scenes", nodes=[d.add("nodes", mesh=d.mesh(d.box(*HULL, material=red), d.box(*MARK, material=steel)))])
    d.glb(here / "models" / "gl.glb")
    entry = {"name": "gl_boat", "mesh": "gl.glb", "semantic_class": "vessel", "draft": 0.5}
    (here / "models" / "gl.yaml").write_text(yaml.safe_dump(entry), encoding="utf-8")
    out, _ = _ok(["assets", "models/gl.yaml", "--materials"], capsys)
    assert "Materials of gl_boat" in out, out
    rows = {r[0]: r[1:] for r in _cells(out) if len(r) == 8}
    paint_row = next(v for k, v in rows.items() if "red_paint" in k)
    rail_row = next(v for k, v in rows.items() if "rail_steel" in k)
    assert paint_row[:6] == ["12", "0.5, 0.05, 0.02", _srgb_hex([0.5, 0.05, 0.02]), "0.6", "0", ""], paint_row
    assert rail_row[:6] == ["12", "0.56, 0.57, 0.58", _srgb_hex([0.56, 0.57, 0.58]), "0.3", "1", ""], rail_row
    assert paint_row[6] == rail_row[6] == ""  # no lamp


def test_materials_of_the_library_give_every_face_and_the_lamps_arcs(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # Every built-in asset's faces are those of its materials; its lamps give COLREG Rule 21's arcs (a sidelight
    # 112.5° from right ahead to its side, the sternlight 135° round right astern).
    from mmusv.world.vessels import library

    monkeypatch.setenv("COLUMNS", "250")
    out, _ = _ok(["assets", "--materials"], capsys)
    tables = out.split("Materials of ")[1:]
    assert [t.split()[0] for t in tables] == [a.name for a in library()]
    for a, t in zip(library(), tables, strict=True):
        rows = _cells(t)
        assert sum(int(r[1]) for r in rows) == a.num_triangles, a.name
        assert [r[0] for r in rows] == sorted(r[0] for r in rows)
    arcs = {r[0].split("@")[0]: r[7] for t in tables for r in _cells(t) if r[0].startswith("nav_")}
    assert arcs == {
        "nav_masthead_white": "0 ± 112.5",
        "nav_port_red": "56.25 ± 56.25",
        "nav_starboard_green": "-56.25 ± 56.25",
        "nav_stern_white": "180 ± 67.5",
    } | ({"nav_allround_white": "all round"} if "nav_allround_white" in arcs else {}), arcs


def test_a_scenario_lists_the_assets_of_its_asset_files_from_its_own_folder(
    here: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _scenario(here / "scen" / "with_boat.yaml", ["../models/boat.yaml"])  # the scenario's folder's, not the cwd's
    out, _ = _ok(["assets", "scen/with_boat.yaml"], capsys)
    assert _rows(out) == [
        [
            *("my_boat", "custom", "vessel", "6.0", "2.4", "1.6", "0.4", "12", "0", "1"),
            f"{Path('models/boat.yaml')} (assets: of scen/with_boat.yaml)",
        ]
    ]


def test_a_catalogue_and_several_files_list_every_asset_once(here: Path, capsys: pytest.CaptureFixture[str]) -> None:
    catalogue = [
        {"name": "skiff_a", "mesh": "boat.ply", "draft": 0.4},
        {"name": "skiff_b", "mesh": "boat.ply", "draft": 0.3, "scale": 2.0, "semantic_class": "usv"},
    ]
    (here / "models" / "fleet.yaml").write_text(yaml.safe_dump(catalogue), encoding="utf-8")
    # the boat's file given itself and through the scenario: one row
    out, _ = _ok(["assets", "with_boat.yaml", "models/fleet.yaml", "models/boat.yaml"], capsys)
    rows = _rows(out)
    assert [r[0] for r in rows] == ["my_boat", "skiff_a", "skiff_b"], out
    assert rows[2][2:4] == ["usv", "12.0"] and rows[2][-1] == str(Path("models/fleet.yaml"))


def test_a_scenario_without_asset_files_is_a_note(here: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _scenario(here / "plain.yaml", None, asset="usv_wamv")
    out, err = _ok(["assets", "plain.yaml", "models/boat.yaml"], capsys)
    assert [r[0] for r in _rows(out)] == ["my_boat"]
    assert err == (
        "mmusv: note: plain.yaml: the scenario lists no asset files (assets:); its vessels are built-in assets "
        "(mmusv assets lists them)\n"
    )


def test_render_draws_the_users_assets_only(here: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out, _ = _ok(["assets", "with_boat.yaml", "--render", "pics"], capsys)
    assert sorted(p.name for p in (here / "pics").iterdir()) == ["contact_sheet.png", "my_boat.png"]
    assert f"wrote {Path('pics') / 'contact_sheet.png'}" in out


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["missing.yaml"], "mmusv: error: scenario or asset file 'missing.yaml' does not exist"),
        (["models"], "mmusv: error: scenario or asset 'models' is a directory, not a file"),
        ([""], "mmusv: error: FILE is empty: give a path"),
        (["other.yaml"], "mmusv: error: other.yaml: neither a scenario (a mapping with vessels: and assets:"),
        (
            ["models/boat.ply"],
            "mmusv: error: models/boat.ply: a mesh file, not an asset file: give the asset YAML that names it as "
            "mesh: boat.ply (with name:, and draft: or waterline_z:; docs/assets.md), or a scenario whose assets: "
            "lists that YAML",
        ),
        (["models/bad_draft.yaml"], "mmusv: error: models/bad_draft.yaml: bad.draft: must be > 0.0, got -3"),
        (["models/no_mesh.yaml"], "mmusv: error: models/no_mesh.yaml: lost.mesh: mesh file '"),
        (
            ["models/tug.yaml"],
            "mmusv: error: models/tug.yaml: name: 'tug_32m' is the name of a built-in asset (a scenario that lists "
            "this file is refused); give it another name",
        ),
        (
            ["bad_scenario.yaml"],
            "mmusv: error: bad_scenario.yaml: invalid scenario assets[1] = 'models/bad_draft.yaml': bad.draft: must "
            "be > 0.0, got -3",
        ),
        (
            ["gone_scenario.yaml"],
            "mmusv: error: gone_scenario.yaml: invalid scenario assets[0] = 'models/gone.yaml': ",
        ),
        (
            ["plain.yaml"],
            "mmusv: error: --render pics: nothing to render: the files given hold no asset of the user's (plain.yaml "
            "lists no asset files under assets:)",
        ),
        (
            ["models/boat.yaml", "twin/boat.yaml"],
            f"mmusv: error: --render pics: two assets named 'my_boat' ({Path('models/boat.yaml')} and "
            f"{Path('twin/boat.yaml')}) would both be drawn to my_boat.png; render them one file at a time",
        ),
    ],
)
def test_a_bad_file_is_one_line_naming_it_and_nothing_is_written(
    argv: list[str], said: str, here: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    models = here / "models"
    (models / "bad_draft.yaml").write_text("name: bad\nmesh: boat.ply\ndraft: -3\n", encoding="utf-8")
    (models / "no_mesh.yaml").write_text("name: lost\nmesh: missing.ply\ndraft: 0.4\n", encoding="utf-8")
    write_boat(models / "tug.yaml", name="tug_32m")
    write_boat(here / "twin" / "boat.yaml", name="my_boat")
    (here / "other.yaml").write_text("colour: blue\n", encoding="utf-8")
    _scenario(here / "bad_scenario.yaml", ["models/boat.yaml", "models/bad_draft.yaml"])
    _scenario(here / "gone_scenario.yaml", ["models/gone.yaml"])
    _scenario(here / "plain.yaml", None, asset="usv_wamv")
    err = _refused(["assets", *argv, "--render", "pics"], capsys)
    assert err.startswith(said), err
    assert not (here / "pics").exists()  # nothing made, nothing rendered
    if "--render" not in said:  # without --render: the same error (the others are --render's own)
        assert _refused(["assets", *argv], capsys).startswith(said)


def test_a_bad_file_writes_nothing_into_an_existing_render_folder(
    here: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (here / "pics").mkdir()
    (here / "models" / "bad.yaml").write_text("name: bad\nmesh: boat.ply\ndraft: -3\n", encoding="utf-8")
    _refused(["assets", "models/boat.yaml", "models/bad.yaml", "--render", "pics"], capsys)
    assert list((here / "pics").iterdir()) == []


def test_the_help_names_the_files(capsys: pytest.CaptureFixture[str]) -> None:
    args = parser().parse_args(["assets", "a.yaml", "b.yaml", "--render", "d"])
    assert args.files == ["a.yaml", "b.yaml"] and args.render == "d"
    assert parser().parse_args(["assets"]).files == []
    with pytest.raises(SystemExit):
        parser().parse_args(["assets", "--help"])
    page = capsys.readouterr().out
    check_help_page("mmusv assets", page)
    assert "[FILE ...]" in page and "scenario YAML" in page and "asset YAML" in page


def test_write_contact_sheet_draws_assets_that_are_in_no_library(tmp_path: Path) -> None:
    write_boat(tmp_path / "boat.yaml", name="loose_boat")
    boat = load_asset_file(tmp_path / "boat.yaml")
    sheet = write_contact_sheet(tmp_path / "pics", assets=[boat], tile=(16, 12), asset_size=(32, 24))
    assert sorted(p.name for p in sheet.parent.iterdir()) == ["contact_sheet.png", "loose_boat.png"]
    with pytest.raises(ConfigError, match="are both named 'loose_boat'"):
        write_contact_sheet(tmp_path / "twice", assets=[boat, boat], asset_size=(32, 24))
    with pytest.raises(ConfigError, match="not both"):
        write_contact_sheet(tmp_path / "both", names=["usv_wamv"], assets=[boat])
    with pytest.raises(ConfigError, match=r"assets\[0\] = 'loose_boat': must be a VesselAsset"):
        write_contact_sheet(tmp_path / "names", assets=["loose_boat"])  # type: ignore[list-item]
    assert not (tmp_path / "twice").exists() and not (tmp_path / "both").exists()
