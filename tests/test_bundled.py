"""Bundled scenarios as package data (:mod:`mmusv.bundled`): names resolve from any directory."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml
from mmusv.bundled import bundled_dir, bundled_scenarios, resolve_scenario
from mmusv.cli import main
from mmusv.errors import NotFoundError

REPO_SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def test_bundled_dir_holds_the_repo_scenarios() -> None:
    names = sorted(p.name for p in bundled_dir().glob("*.yaml"))
    assert names == sorted(p.name for p in REPO_SCENARIOS.glob("*.yaml"))
    assert (bundled_dir() / "specs" / "island_demo.yaml").is_file()


def test_bare_name_resolves_from_another_directory(tmp_path: Path) -> None:
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        for arg in ("port_entry", "port_entry.yaml", "scenarios/port_entry.yaml"):
            p = resolve_scenario(arg)
            assert p.is_file() and p.read_bytes() == (REPO_SCENARIOS / "port_entry.yaml").read_bytes()
        with pytest.raises(NotFoundError, match=r"bundled: .*port_entry"):
            resolve_scenario("no_such_scenario")
        with pytest.raises(NotFoundError):
            resolve_scenario("elsewhere/port_entry.yaml")  # a real path that is not there is not rewritten
    finally:
        os.chdir(cwd)


def test_existing_file_wins(tmp_path: Path) -> None:
    own = tmp_path / "port_entry.yaml"
    own.write_text("name: mine\n")
    assert resolve_scenario(own) == own


def test_listing_counts_match_the_yaml() -> None:
    rows = {b.name: b for b in bundled_scenarios()}
    assert set(rows) == {p.stem for p in REPO_SCENARIOS.glob("*.yaml")}
    doc = yaml.safe_load((REPO_SCENARIOS / "port_entry.yaml").read_text())
    roles = [v["role"] for v in doc["vessels"]]
    b = rows["port_entry"]
    assert (b.map, b.usvs, b.targets, b.frames) == ("port", roles.count("usv"), roles.count("target"), 50)
    assert b.description.startswith("Port map: three USVs") and b.description.endswith(".")
    assert rows["island_occlusion"].description.startswith("Fig. 1 of the paper")


def test_cli_scenarios_lists_every_bundled_scenario(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["scenarios"]) == 0
    out = capsys.readouterr().out
    for p in REPO_SCENARIOS.glob("*.yaml"):
        assert p.stem in out


def test_bundled_specs_resolve_from_another_directory(tmp_path: Path) -> None:
    """`mmusv study detection --generate` and `mmusv generate` find the bundled specs outside the repository."""
    from mmusv.bundled import resolve_spec

    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        for arg in ("coop_detection", "scenarios/specs/coop_detection.yaml", "specs/coop_detection.yaml"):
            p = resolve_spec(arg)
            assert p == bundled_dir() / "specs" / "coop_detection.yaml" and p.is_file()
        bundled = "coop_detection, coop_detection_shift, coop_detection_w1, coop_detection_w3, impossible_port"
        with pytest.raises(NotFoundError, match=f"not a bundled spec; bundled: {bundled}"):
            resolve_spec("no_such_spec")
    finally:
        os.chdir(cwd)


def test_python_api_takes_bundled_names(tmp_path: Path) -> None:
    import mmusv
    from mmusv.config import load_scenario
    from mmusv.errors import ConfigError

    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        want = load_scenario(REPO_SCENARIOS / "port_entry.yaml")
        assert load_scenario("port_entry") == want == mmusv.Simulation("port_entry").scenario
        res = mmusv.run("port_entry", out_dir=tmp_path / "out", frames=1)
        assert Path(res.recording).name == "port_entry.mcap"
        with pytest.raises(ConfigError, match="'no_such_scenario' does not exist"):
            load_scenario("no_such_scenario")
    finally:
        os.chdir(cwd)


def test_a_link_that_leads_nowhere_is_named_as_one(tmp_path: Path) -> None:
    """A dangling link or a loop of links given as the scenario "does not exist and is not a bundled scenario"."""
    from mmusv.bundled import resolve_spec

    (tmp_path / "a.yaml").symlink_to(tmp_path / "b.yaml")
    (tmp_path / "b.yaml").symlink_to(tmp_path / "a.yaml")
    (tmp_path / "gone.yaml").symlink_to("nothere.yaml")
    with pytest.raises(NotFoundError, match=r"'.*a\.yaml' is a link that leads nowhere: a loop of links"):
        resolve_scenario(tmp_path / "a.yaml")
    with pytest.raises(NotFoundError, match=r"gone\.yaml' is a link that leads nowhere: it points to nothere\.yaml"):
        resolve_spec(tmp_path / "gone.yaml")


def test_a_package_without_its_scenarios_says_so(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A copy of the package that lost its data (a broken link to ``scenarios/``) listed an empty table, exit 0."""
    import mmusv.bundled

    monkeypatch.setattr(mmusv.bundled, "bundled_dir", lambda: tmp_path / "scenarios")
    with pytest.raises(NotFoundError, match=r"no bundled scenario in .*scenarios: the package's data is missing"):
        mmusv.bundled.bundled_scenarios()
    assert main(["scenarios"]) != 0
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: no bundled scenario in ") and "Traceback" not in err, err


def test_a_folder_of_a_bundled_name_is_not_taken_for_it_silently(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``mmusv run port_entry -o port_entry`` twice: the second run took the first's output folder for a folder of
    scenarios and recorded its ``scenario.yaml`` as a batch into it (``port_entry/scenario/``, a ``dataset.json``
    beside the run), and the editor and ``mmusv study agreement`` said "is a folder". Both meanings are named."""
    from mmusv.bundled import resolve_spec
    from mmusv.errors import InputError

    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        (tmp_path / "port_entry").mkdir()
        (tmp_path / "port_entry" / "scenario.yaml").write_bytes((REPO_SCENARIOS / "port_entry.yaml").read_bytes())
        (tmp_path / "coop_detection").mkdir()
        said = r"'port_entry' is both a folder here and a bundled scenario: give ./port_entry for the folder or "
        with pytest.raises(InputError, match=said + r"port_entry\.yaml for the bundled scenario"):
            resolve_scenario("port_entry")
        with pytest.raises(InputError, match=r"'coop_detection' is both a folder here and a bundled spec"):
            resolve_spec("coop_detection")
        assert resolve_scenario("./port_entry") == Path("port_entry")  # the folder, as typed
        assert resolve_scenario("port_entry.yaml").read_bytes() == (REPO_SCENARIOS / "port_entry.yaml").read_bytes()
        from mmusv.config import load_scenario

        with pytest.raises(InputError, match=said):  # it said "'port_entry' is a directory, not a file"
            load_scenario("port_entry")
        assert main(["run", "port_entry", "-o", "out", "--frames", "1"]) == 2
        assert "is both a folder here and a bundled scenario" in capsys.readouterr().err
        assert not (tmp_path / "out").exists()
        assert sorted(p.name for p in (tmp_path / "port_entry").iterdir()) == ["scenario.yaml"]
    finally:
        os.chdir(cwd)
