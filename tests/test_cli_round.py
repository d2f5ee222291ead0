"""The inspection commands used as a new user would (``info``, ``recover``, ``preview``, ``schema``, ``--version``),
each finding of that round a test that failed before its fix: a killed part of a split run recovered into a file
its parts manifest refused, ``info`` warning about tables that are fine (a split run's, one part's), suggesting a
recovery that refuses, calling a foreign MCAP a killed run and not naming a killed run's agents or scenario,
``preview`` of a USV without picture sensors ending in a traceback, and the JSON Schema passing values the loader
refuses on their own (a time of day, a wave, a waypoint, an image size)."""

from __future__ import annotations

import copy
import json
import shutil
from pathlib import Path
from typing import Any

import jsonschema
import pytest
import yaml
from mcap.writer import Writer
from mcap_rechunk import killed_copy
from mmusv.cli import main
from mmusv.errors import MmusvError
from tiny_scenario import lidar_scenario


def _cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """``mmusv argv`` in this process: ``(exit status, stdout, stderr)``, with rich's line breaks joined."""
    code = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err, out + err
    return code, out.replace("\n", " "), err


def _killed_copy(src: Path, dst: Path, *, messages: int) -> Path:
    """``dst``: what a run killed after the first ``messages`` messages of ``src`` leaves (``mcap_rechunk``)."""
    return killed_copy(src, dst, messages=messages)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``tiny/`` (3 frames, one LiDAR-only USV), ``split/tiny/`` (4 frames recorded as 2 parts of 2) and
    ``blind/`` (1 frame: USV ``a`` carries no sensor, USV ``u`` a LiDAR)."""
    from mmusv.acquire import run

    base = tmp_path_factory.mktemp("cli_round")
    run(lidar_scenario("tiny", frames=3), out_dir=base / "tiny")
    src = base / "tiny4.yaml"
    src.write_text(yaml.safe_dump(lidar_scenario("tiny", frames=4)), encoding="utf-8")
    assert main(["run", str(src), "-o", str(base / "split"), "--split-frames", "2"]) == 0
    blind = lidar_scenario("blind", frames=1)
    blind["rigs"]["none"] = {"preset": "lidar_only", "lidar": None}
    blind["vessels"].insert(
        0,
        {"id": "a", "role": "usv", "asset": "usv_wamv", "rig": "none", "speed_mps": 2, "route": [[0, -40], [50, -40]]},
    )
    run(blind, out_dir=base / "blind")
    return base


# ------------------------------------------------------------------------------------------------ info


def test_info_of_a_split_run_reads_the_tables_of_its_parts(runs: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`mmusv info` on a split run's folder warned "tables does not exist (a run killed before its first table
    flush...)": a split run's tables are in its parts' folders; and on one part's folder it called the frames
    before the part ("frames 0..1 have no world_state rows") missing."""
    folder = runs / "split" / "tiny4"
    assert (folder / "tiny4.parts.json").is_file() or (folder / "tiny.parts.json").is_file(), sorted(folder.iterdir())
    code, out, err = _cli(["info", str(folder)], capsys)
    assert code == 0 and "status complete, 4 frames" in out and "warning" not in out + err, out
    part = folder / "parts" / "000002-000003"
    code, out, err = _cli(["info", str(part)], capsys)
    assert code == 0 and "2 frames" in out and "warning" not in out + err, out
    # a part's tables that really lack rows are still named (frames 2..3 of that part's own range)
    for p in (part / "tables" / "world_state").glob("part-*.parquet"):
        p.unlink()
    code, out, _ = _cli(["info", str(part)], capsys)
    assert code == 0 and "frames 2..3 have no world_state rows" in out, out


def test_info_of_a_killed_run_names_its_scenario_and_agents(
    runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A killed run has no `run` metadata: `info` said "agents ?" and the file's name for the scenario, though the
    `sensors` and `scenario` metadata name them."""
    partial = _killed_copy(runs / "tiny" / "tiny.mcap", tmp_path / "renamed.mcap.partial", messages=12)
    code, out, _ = _cli(["info", str(partial)], capsys)
    assert code == 0 and "scenario tiny," in out and "agents u" in out and "2 of 3 frames" in out, out
    assert f"mmusv recover {tmp_path}" in out


def test_info_of_a_killed_run_without_a_frame_does_not_suggest_recover(
    runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Killed before its first frame reached the disk: `info` suggested `mmusv recover`, which then refuses ("holds
    no complete frame"); and warned that the (never written) tables are missing."""
    folder = tmp_path / "killed"
    folder.mkdir()
    _killed_copy(runs / "tiny" / "tiny.mcap", folder / "tiny.mcap.partial", messages=0)
    code, out, _ = _cli(["info", str(folder)], capsys)
    assert code == 1 and "0 of 3 frames" in out and "nothing to recover" in out, out  # no frame: exit 1
    assert "mmusv recover" not in out and "tables does not exist" not in out, out
    code, _, err = _cli(["recover", str(folder)], capsys)
    assert code == 2 and "no complete frame" in err  # what the hint no longer promises


def test_info_of_an_mcap_not_written_by_mmusv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A complete MCAP of another tool was "status unfinished (no run metadata: the run was killed or is still
    going), ? frames, agents ?"."""
    path = tmp_path / "other.mcap"
    with path.open("wb") as f:
        w = Writer(f)
        w.start()
        ch = w.register_channel("/a", "json", w.register_schema("s", "jsonschema", b"{}"))
        for k in range(3):
            w.add_message(ch, k * 10**9, b"{}", k * 10**9)
        w.finish()  # type: ignore[no-untyped-call]
    code, out, _ = _cli(["info", str(path)], capsys)
    assert code == 0 and "not written by mmusv run" in out and "3 messages" in out, out
    assert "killed" not in out and "agents" not in out, out


HEAD = ["scenario", "status", "frames", "agents", "problems"]


def test_info_of_a_batch_folder_lists_the_recordings_below(
    runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """`mmusv info OUT` on a batch's output folder was refused ("a folder without a recording ...; below it: ...
    (name one)"); it shows one row per recording below, a killed run's `.partial` and a damaged file included."""
    monkeypatch.setenv("COLUMNS", "250")  # one line a row
    out_dir = tmp_path / "batch"
    for run in ("tiny", "blind"):  # (an earlier test removes tables of the split run's parts)
        shutil.copytree(runs / run, out_dir / run)
    shutil.copytree(runs / "split" / "tiny4", out_dir / "split" / "tiny4", ignore=shutil.ignore_patterns("tables"))
    (out_dir / "killed").mkdir()
    _killed_copy(runs / "tiny" / "tiny.mcap", out_dir / "killed" / "tiny.mcap.partial", messages=12)
    (out_dir / "broken").mkdir()
    (out_dir / "broken" / "broken.mcap").write_bytes(b"not an mcap")
    # the review's: a bad parts manifest refused the whole overview, a name like a[/b] was rich markup (a
    # traceback), and a killed part's .partial was listed beside its manifest
    (out_dir / "bad").mkdir()
    (out_dir / "bad" / "bad.parts.json").write_text('{"parts": 3}')
    shutil.copytree(runs / "tiny", out_dir / "a[" / "b]")
    killed_part = out_dir / "split2" / "tiny4"
    shutil.copytree(runs / "split" / "tiny4", killed_part, ignore=shutil.ignore_patterns("tables"))
    last = killed_part / "parts" / "000002-000003" / "tiny.mcap"
    last.rename(last.with_name("tiny.mcap.partial"))
    code = main(["info", str(out_dir)])
    lines = capsys.readouterr().out.splitlines()
    assert code == 1  # two recordings cannot be read at all (`mmusv info` on either alone is an error)
    assert "8 recordings below" in lines[0], lines
    rows = {ln.split("│")[1].strip(): [c.strip() for c in ln.split("│")[2:-1]] for ln in lines if ln.count("│") == 7}
    assert any(ln.replace("┃", " ").split() == ["recording", *HEAD] for ln in lines), lines
    assert rows["blind/blind.mcap"] == ["blind", "complete", "1", "a,u", ""], rows
    assert rows["tiny/tiny.mcap"] == ["tiny", "complete", "3", "u", ""], rows
    assert rows["split/tiny4/tiny.parts.json"][:4] == ["tiny", "complete", "4", "u"], rows
    assert rows["split/tiny4/tiny.parts.json"][4].startswith("split/tiny4/parts/000000-000001/tables does not"), rows
    assert rows["killed/tiny.mcap.partial"][:4] == ["tiny", "unfinished", "2 of 3", "u"], rows
    assert rows["broken/broken.mcap"][1:4] == ["unreadable", "?", "?"], rows
    assert rows["broken/broken.mcap"][4].startswith("broken/broken.mcap is not an MCAP file"), rows
    assert rows["killed/tiny.mcap.partial"][4].startswith("2 of 3 frames read; frame 2 missing"), rows
    # polars read the tables of a folder a[/b] as a glob pattern, and the row called them damaged
    assert rows["a[/b]/tiny.mcap"] == ["tiny", "complete", "3", "u", ""], rows
    assert rows["bad/bad.parts.json"][1] == "unreadable" and "not a parts manifest" in rows["bad/bad.parts.json"][4]
    assert rows["split2/tiny4/tiny.parts.json"][:2] == ["tiny", "complete"], rows
    assert not any(r.startswith("split2/tiny4/parts") for r in rows), rows
    assert "5 recordings unfinished, damaged or unreadable" in " ".join(lines[-2:]), lines
    # the readable ones alone: exit 0, as `mmusv info` on a damaged or unfinished recording warns and exits 0
    shutil.rmtree(out_dir / "broken")
    shutil.rmtree(out_dir / "bad")
    assert main(["info", str(out_dir)]) == 0
    capsys.readouterr()
    # a folder with nothing below it is still refused
    (tmp_path / "empty").mkdir()
    code, _, err = _cli(["info", str(tmp_path / "empty")], capsys)
    assert code == 2 and "a folder without a recording" in err, err


def test_info_of_a_batch_folder_follows_linked_run_folders(
    runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A batch gathered from two disks, its run folders links: `mmusv info OUT` said "a folder without a
    recording" (rglob does not follow links to folders). Each linked recording is listed once, and a link back up
    the tree is no loop; the finders of the studies (`find_recordings`) see the same."""
    from mmusv.recording.folders import find_recordings

    monkeypatch.setenv("COLUMNS", "250")
    out_dir = tmp_path / "batch"
    out_dir.mkdir()
    shutil.copytree(runs / "tiny", tmp_path / "disk2" / "tiny")
    (out_dir / "tiny").symlink_to(tmp_path / "disk2" / "tiny", target_is_directory=True)
    (out_dir / "tiny_again").symlink_to(tmp_path / "disk2" / "tiny", target_is_directory=True)  # walked once
    shutil.copytree(runs / "blind", out_dir / "blind")
    (out_dir / "blind" / "up").symlink_to(out_dir, target_is_directory=True)  # a loop
    shutil.copytree(runs / "blind", out_dir / "z_runs" / "run_2")  # named by its own path, not by a_latest
    (out_dir / "a_latest").symlink_to(out_dir / "z_runs" / "run_2", target_is_directory=True)
    code, out, err = _cli(["info", str(out_dir)], capsys)
    assert code == 0 and "3 recordings below" in out, (out, err)
    assert "tiny/tiny.mcap" in out and "tiny_again" not in out and "blind/blind.mcap" in out, out
    assert "z_runs/run_2/blind.mcap" in out and "a_latest" not in out, out
    assert find_recordings(out_dir) == [
        out_dir / "blind" / "blind.mcap",
        out_dir / "tiny" / "tiny.mcap",
        out_dir / "z_runs" / "run_2" / "blind.mcap",
    ]
    # an unreadable parts manifest: the studies' finder refuses it, naming it; `info` lists it as a row
    (out_dir / "bad.parts.json").write_text('{"parts": 3}')
    with pytest.raises(MmusvError, match=r"bad\.parts\.json"):
        find_recordings(out_dir)
    assert out_dir / "bad.parts.json" in find_recordings(out_dir, unfinished=True)
    (out_dir / "bad.parts.json").unlink()
    # a broken link to a recording is listed (it was left out without a word): a row saying it cannot be read
    (out_dir / "gone").mkdir()
    (out_dir / "gone" / "gone.mcap").symlink_to(tmp_path / "nowhere.mcap")
    assert out_dir / "gone" / "gone.mcap" in find_recordings(out_dir)
    code, out, err = _cli(["info", str(out_dir)], capsys)
    assert code == 1 and "4 recordings below" in out and "gone.mcap" in out and "unreadable" in out, (out, err)


def test_a_folder_below_that_cannot_be_read_is_named(
    runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A run folder of a batch that cannot be read (its permissions; simulated, since the tests may run as root):
    the search skipped it without a word, so a study left its recordings out and `mmusv info` showed the others
    as if that were all. The studies' finder refuses, naming the folder; `info` gives it a row and exits 1."""
    import os

    from mmusv.recording.folders import find_recordings

    monkeypatch.setenv("COLUMNS", "250")
    out_dir = tmp_path / "batch"
    shutil.copytree(runs / "tiny", out_dir / "tiny")
    shutil.copytree(runs / "blind", out_dir / "locked")
    scandir = os.scandir

    def guarded(path: Any = ".") -> Any:
        if Path(path).resolve().name == "locked":  # (through a link too, as the real refusal is)
            raise PermissionError(13, "Permission denied", str(path))
        return scandir(path)

    monkeypatch.setattr(os, "scandir", guarded)
    monkeypatch.setattr(os, "listdir", lambda p=".": [e.name for e in guarded(p)])
    (out_dir / "via").symlink_to(out_dir / "locked", target_is_directory=True)  # the same folder: one row
    with pytest.raises(MmusvError, match=r"cannot read the folder .*locked below it \(Permission denied\):"):
        find_recordings(out_dir)
    assert find_recordings(out_dir, unfinished=True) == [out_dir / "locked", out_dir / "tiny" / "tiny.mcap"]
    code, out, err = _cli(["info", str(out_dir)], capsys)
    out = " ".join(out.split())  # (the title wraps)
    assert code == 1 and "1 recording below" in out and "1 folder that cannot be read" in out, (out, err)
    assert "cannot read the folder: Permission denied" in out and "via" not in out, out
    assert "1 folder below cannot be read: the recordings in it are not listed" in out, out
    # the folder given cannot be read itself: said so (it was "a folder below it" of itself, and a row ".")
    with pytest.raises(MmusvError, match=r"folder = .*locked cannot be read \(Permission denied\)$"):
        find_recordings(out_dir / "locked", unfinished=True)
    (out_dir / "via").unlink()
    # a folder gone between its listing and its reading (a batch still writing renames its folders): nothing in it
    # to leave out, so nothing refused
    monkeypatch.setattr(os, "scandir", scandir)
    shutil.copytree(runs / "blind", out_dir / "moving")
    shutil.rmtree(out_dir / "locked")

    def vanishing(path: Any = ".") -> Any:
        if Path(path).name == "moving":
            raise FileNotFoundError(2, "No such file or directory", str(path))
        return scandir(path)

    monkeypatch.setattr(os, "scandir", vanishing)
    assert find_recordings(out_dir) == [out_dir / "tiny" / "tiny.mcap"]


# ------------------------------------------------------------------------------------------------ recover


def test_recover_of_a_killed_part_keeps_its_parts_manifest_readable(
    runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A part of a split run killed, then `mmusv recover PART_FOLDER`: the recovered part lacked `first_frame`, so
    every reader of the manifest failed ("... is a whole recording, not a part (no first_frame)")."""
    import shutil

    folder = tmp_path / "tiny4"
    shutil.copytree(runs / "split" / "tiny4", folder)
    part = folder / "parts" / "000002-000003"
    done = part / "tiny.mcap"
    _killed_copy(done, part / "tiny.mcap.partial", messages=7)  # frame 2 whole, frame 3 cut short
    done.unlink()
    shutil.rmtree(part / "tables")
    code, out, err = _cli(["recover", str(part)], capsys)
    assert code == 0 and "recovered 1 of 2 frames (frame 2)" in out, (out, err)
    code, out, err = _cli(["info", str(folder)], capsys)
    assert code == 0 and "3 of 4 frames" in out and "frame 3 missing" in out, (out, err)
    assert json.loads((part / "manifest.json").read_text())["first_frame"] == 2
    code, out, err = _cli(["preview", str(folder / "tiny.parts.json"), "--frame", "2", "-o", str(tmp_path)], capsys)
    assert code == 0 and (tmp_path / "tiny_frame000002_u.png").is_file(), err


# ------------------------------------------------------------------------------------------------ preview


def test_preview_skips_a_usv_without_picture_sensors(
    runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A USV whose rig records no camera, radar, top view or LiDAR: `preview` ended in an IndexError traceback
    (by default too, when it was the first agent)."""
    rec = runs / "blind" / "blind.mcap"
    code, out, err = _cli(["preview", str(rec), "-o", str(tmp_path)], capsys)
    assert code == 0 and (tmp_path / "blind_frame000000_u.png").is_file(), (out, err)  # the first with pictures
    code, _, err = _cli(["preview", str(rec), "--agent", "a", "-o", str(tmp_path)], capsys)
    assert code == 2 and "agent 'a' recorded no picture" in err and "agents with pictures: u" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blind_frame000000_u.png"]


def test_preview_into_a_folder_that_does_not_exist(
    runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`-o previews/` (a folder, by its slash) that does not exist was "give a picture path ..., or a folder"."""
    rec = str(runs / "tiny" / "tiny.mcap")
    code, _, err = _cli(["preview", rec, "-o", f"{tmp_path / 'previews'}/"], capsys)
    assert code == 2 and "does not exist" in err and not (tmp_path / "previews").exists(), err
    (tmp_path / "previews").mkdir()
    code, out, _ = _cli(["preview", rec, "-o", f"{tmp_path / 'previews'}/"], capsys)
    assert code == 0 and (tmp_path / "previews" / "tiny_frame000000_u.png").is_file(), out


# ------------------------------------------------------------------------------------------------ the rest


def test_version_flag(capsys: pytest.CaptureFixture[str]) -> None:
    """`mmusv --version` was "the following arguments are required: command" (exit status 2)."""
    from mmusv import __version__

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code in (0, None)
    assert capsys.readouterr().out.strip() == f"mmusv {__version__}"


_BASE: dict[str, Any] = {
    "rigs": {"r": {}},
    "vessels": [{"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "route": [[0, 0], [100, 0]]}],
}
_SPEC: dict[str, Any] = {
    "map": {"type": "island", "seed": 4},
    "acquisition": {"frequency_hz": 2, "frames": 10},
    "combinations": [{"family": "crossing", "targets": ["small"]}],
}


def _doc(kind: str, path: str, value: Any) -> dict[str, Any]:
    doc = copy.deepcopy(_BASE if kind == "scenario" else _SPEC)
    *parents, last = [int(p) if p.isdigit() else p for p in path.split(".")]
    node: Any = doc
    for p in parents:
        node = node.setdefault(p, {}) if isinstance(node, dict) else node[p]
    node[last] = value
    return doc


def _loads(kind: str, doc: dict[str, Any]) -> bool:
    from mmusv.config import load_scenario
    from mmusv.errors import ConfigError
    from mmusv.generate import load_spec

    try:
        (load_scenario if kind == "scenario" else load_spec)(copy.deepcopy(doc))
    except ConfigError:
        return False
    return True


@pytest.mark.parametrize(
    ("kind", "path", "value", "good"),
    [
        ("scenario", "environment.time_of_day", "25:00", False),
        ("scenario", "environment.time_of_day", "noon", False),
        ("scenario", "environment.time_of_day", "0700", False),
        ("scenario", "environment.time_of_day", " 7:05 ", True),
        ("scenario", "environment.wave", "W9", False),
        ("scenario", "environment.wave", "2.5", False),  # a quoted height is not a preset
        ("scenario", "environment.wave", 26, False),
        ("scenario", "environment.wave", -1, False),
        ("scenario", "environment.wave", " w2 ", True),
        ("scenario", "environment.wave", 2.5, True),
        ("scenario", "environment", {"sea": {"state": 3}, "wave": "W2"}, False),
        ("scenario", "environment", {"sea": {"state": 3}, "motion": "paper"}, False),
        ("scenario", "environment", {"sea": {"state": 3}, "wave": "W0"}, True),
        ("scenario", "environment", {"rain_mm_per_h": 5}, False),  # under the default clear sky
        ("scenario", "environment", {"rain_mm_per_h": 5, "weather": "fog"}, True),
        ("scenario", "vessels.0.route", [[-2e6, 0], [100, 0]], False),
        ("scenario", "rigs.r", {"cameras": [{"name": "a", "resolution": [0, 480]}]}, False),
        ("scenario", "rigs.r", {"top_view": {"resolution": [20000, 64]}}, False),
        ("scenario", "rigs.r", {"lidar": {"vertical_fov_deg": [-90, 10]}}, False),
        ("scenario", "rigs.r", {"radar": {"elevation_fan_deg": [-10, 90]}}, False),
        ("spec", "environment.time_of_day", ["07:00", "7 pm"], False),
        ("spec", "environment.wave", ["W0", "W7"], False),
        ("spec", "environment.wave", ["w1", 3], True),
        ("spec", "difficulties", {"near": {"range_m": [-5, 100]}}, False),
        ("spec", "difficulties", {"near": {"range_m": [5, 1e6]}}, False),
    ],
    ids=lambda v: str(v)[:40],
)
def test_schema_marks_what_the_loader_refuses_on_its_own(kind: str, path: str, value: Any, good: bool) -> None:
    """Values the loader refuses by the field alone passed the emitted JSON Schema (an editor marked nothing)."""
    from mmusv.schema import json_schema

    doc = _doc(kind, path, value)
    assert _loads(kind, doc) is good, "the premise: what the loader does"
    errors = list(jsonschema.Draft202012Validator(json_schema(kind)).iter_errors(doc))  # type: ignore[arg-type]
    assert (not errors) is good, [e.message for e in errors]


def test_main_leaves_the_warning_display_as_it_was(capsys: pytest.CaptureFixture[str]) -> None:
    """``main()`` shows warnings as one line while it runs; it used to leave that display in place, so a notebook
    or a test calling it in-process lost Python's own warning display (``pytest.warns`` saw nothing after)."""
    import warnings

    before = warnings.showwarning
    assert main(["scenarios"]) == 0
    capsys.readouterr()
    assert warnings.showwarning is before
