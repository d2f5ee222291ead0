"""Leftovers of the earlier notes, each as a user met it; every test failed before its fix.

- A LiDAR given both ``elevations_deg`` and a ``vertical_fov_deg`` of its own fired the elevations' rings and
  ignored the field of view without a word; now the two must agree (the field of view the rings' span, or left at
  its default), else the scenario is refused naming both.
- A scenario named ``off`` (or any text field written ``no``, ``on``, ``yes`` unquoted) was refused as
  "name = False: Input should be a valid string": YAML 1.1 (PyYAML) reads those words as booleans. They are now
  refused as the YAML-1.1-only numbers are, naming the field, line and column, the text as written, what YAML 1.1
  reads and what to write instead.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml
from mmusv.cli import main
from mmusv.config import Scenario
from mmusv.errors import ConfigError
from mmusv.yamlio import parse_yaml
from tiny_scenario import lidar_scenario


def _with_lidar(**lidar: object) -> dict[str, object]:
    doc = lidar_scenario("elevations", frames=1)
    doc["rigs"]["r"]["lidar"] = {"channels": 3, "points_per_second": 3 * 5 * 360, **lidar}  # type: ignore[index]
    return doc


def test_elevations_with_another_vertical_fov_is_refused_naming_the_file_and_both_fields(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "both.yaml"
    path.write_text(yaml.safe_dump(_with_lidar(elevations_deg=[-15, -5, 2], vertical_fov_deg=[-25, 10])))
    out = tmp_path / "out"
    assert main(["run", str(path), "-o", str(out)]) != 0
    err = capsys.readouterr().err
    assert "both.yaml" in err
    assert "rigs.r.lidar" in err
    assert "vertical_fov_deg [-25.0, 10.0]" in err
    assert "elevations_deg" in err
    assert "[-15, 2]" in err  # the rings' span, which the user may give instead
    assert "Traceback" not in err
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize("fov", [None, [-25, 15], [-15, 2]])
def test_elevations_with_the_default_or_their_own_span_still_load(fov: list[float] | None) -> None:
    lidar: dict[str, object] = {"elevations_deg": [2, -15, -5]}
    if fov is not None:
        lidar["vertical_fov_deg"] = fov
    rig = Scenario.model_validate(_with_lidar(**lidar)).rigs["r"]
    assert rig.lidar is not None
    assert sorted(rig.lidar.elevations_rad()) == pytest.approx([math.radians(e) for e in (-15, -5, 2)])


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("name: off\n", "name = off at line 1, column 7 is a boolean in YAML 1.1, which reads it as false"),
        ("vessels:\n  - {id: no}\n", "vessels[0].id = no at line 2, column 10 is a boolean in YAML 1.1"),
        ("flags: [Yes]\n", "flags[0] = Yes at line 1, column 9 is a boolean in YAML 1.1, which reads it as true"),
        ("ON: 1\n", "the key ON at line 1, column 1 is a boolean in YAML 1.1"),
    ],
)
def test_yaml_11_booleans_are_refused_naming_the_field_and_what_to_write(text: str, said: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_yaml(text, "f.yaml")
    message = str(info.value)
    assert message.startswith("f.yaml: ") and said in message
    assert "write true or false or, if it is text, put it in quotes" in message


def test_true_false_and_quoted_words_still_read() -> None:
    got = parse_yaml("a: true\nb: False\nc: [TRUE, \"off\", 'no']\n", "f.yaml")
    assert got == {"a": True, "b": False, "c": [True, "off", "no"]}


def test_a_scenario_named_off_is_refused_on_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    doc = lidar_scenario("x", frames=1)
    path = tmp_path / "off.yaml"
    path.write_text(yaml.safe_dump(doc).replace("name: x", "name: off"))
    assert main(["run", str(path), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "off.yaml: name = off at line" in err and 'put it in quotes ("off")' in err


def test_an_additional_yaml_another_tool_wrote_is_not_read_as_mmusv_s(tmp_path: Path) -> None:
    """``read_opv2v`` reads mmusv's ``<ts>_additional.yaml`` for the USVs listed there (role ``usv``); a file of that
    name without an ``mmusv`` key (another tool's, beside a stock OPV2V frame) holds none of them and is not refused,
    while mmusv's own, damaged, still is."""
    from mmusv.studies.detection.data import _opv2v_additional

    def _opv2v_usvs(path: Path) -> set[str]:  # the USVs it lists (the first of what the study reads there)
        return _opv2v_additional(path)[0]

    path = tmp_path / "000000_additional.yaml"
    path.write_text("weather: rain\nvehicles: {7: {role: usv}}\n")
    assert _opv2v_usvs(path) == set()
    path.write_text("mmusv: {vehicles: {'1002': {role: usv}, '1003': {role: target}}}\n")
    assert _opv2v_usvs(path) == {"1002"}
    path.write_text("mmusv: {vehicles: [1002]}\n")
    with pytest.raises(ValueError, match="not mmusv's additional yaml"):
        _opv2v_usvs(path)
    path.write_text("- a list\n")
    with pytest.raises(ValueError, match="not mmusv's additional yaml"):
        _opv2v_usvs(path)


def test_the_background_writer_finds_an_item_whose_wake_up_was_lost() -> None:
    """A stop (SIGTERM, Ctrl-C) raised in the main thread inside ``Queue.put``, after the item went in but before the
    waiting writer thread was woken, left the writer asleep beside a full queue: ``close`` then waited for ever (a
    ``mmusv run`` killed by SIGTERM hung so in CI, its writer thread in ``queue.get``, the main thread in ``close``).
    Here the item goes in without the wake-up, as that stop left it; the writer must still write it and close."""
    import threading
    import time

    from mmusv.recording.background import BackgroundWriter

    written: list[int] = []
    writer: BackgroundWriter[int] = BackgroundWriter(written.append, depth=1)
    time.sleep(0.2)  # the writer thread is waiting for an item
    q = writer._queue
    with q.mutex:  # what Queue.put does up to its notify
        q._put(7)  # type: ignore[attr-defined]
        q.unfinished_tasks += 1
    closer = threading.Thread(target=writer.close, daemon=True)
    closer.start()
    closer.join(timeout=10)
    assert not closer.is_alive(), "close() waited for ever for a writer that was never woken"
    assert written == [7] and writer.done == 1


def test_a_close_interrupted_before_its_end_marker_went_in_still_ends_the_writer() -> None:
    """The hang CI met (a SIGTERM'd ``mmusv run``: the writer thread in ``queue.get``, the main thread joining it in
    ``close``): the stop came inside ``close`` after it marked the writer closed but before it sent the end marker;
    the second ``close`` (the run's finishing) saw it closed, sent nothing and joined for ever."""
    import threading

    from mmusv.recording.background import BackgroundWriter

    written: list[int] = []
    writer: BackgroundWriter[int] = BackgroundWriter(written.append, depth=1)
    writer.submit(3)
    writer._closed = True  # where the stop left the first close
    closer = threading.Thread(target=writer.close, daemon=True)
    closer.start()
    closer.join(timeout=10)
    assert not closer.is_alive(), "the second close() joined a writer that was never sent its end marker"
    assert written == [3]
