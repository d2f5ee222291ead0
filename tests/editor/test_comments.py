"""Comments of a scenario file survive the editor's save: read with their anchors (a key path, a vessel by its id),
written back at the same anchor, those of a removed vessel kept at the end of the file (:mod:`mmusv.editor.comments`,
``GET``/``PUT /api/files``)."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import pytest

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
    from fastapi.testclient import TestClient

from mmusv.bundled import bundled_dir
from mmusv.config import load_scenario
from mmusv.editor.app import create_app
from mmusv.editor.comments import Comment, moved_note, place_comments, read_comments
from mmusv.editor.document import leading_comment, scenario_file, scenario_yaml
from mmusv.yamlio import parse_yaml

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

HAND_WRITTEN = """\
# A hand-written scenario.
# Two vessels.

# about the name
name: demo   # the name
seed: 7
map: {type: port, seed: 3}  # the harbour
environment:
  time_of_day: "16:30"  # late afternoon
  # a clear day
  weather: clear
  wave: W1
acquisition:   # how long
  frequency_hz: 5
  frames: 20
rigs:
  # the standard rig
  usv_standard: {}   # full suite
vessels:
  # the lead
  - id: usv_1   # first
    role: usv
    asset: usv_wamv
    rig: usv_standard
    speed_mps: 2.5   # slow "#" on purpose
    route:
      - [-170, -110]  # slipway
      - [-170, -30]
  # the ferry leaves
  - {id: ferry, role: target, asset: ropax_ferry_90m, speed_mps: 4.0,
     route: [[-40, 0], [-110, -90]]}   # out of the port
# the end
"""


def _comment_lines(text: str) -> list[str]:
    """Every comment of ``text`` from its ``#`` (the leading block's too), as written."""
    return [c.text for c in read_comments(text)] + [f"# {line}".rstrip() for line in leading_comment(text).splitlines()]


def _save(text: str, edit: Any = None) -> tuple[str, list[Comment]]:
    """``text`` loaded as the editor does, ``edit`` applied to its scenario data, saved with its comments."""
    data = parse_yaml(text, "test")
    if edit is not None:
        edit(data)
    return scenario_file(load_scenario(data), comment=leading_comment(text), comments=read_comments(text))


def _line_of(text: str, start: str) -> int:
    lines = text.splitlines()
    return next(i for i, line in enumerate(lines) if line.lstrip().startswith(start))


# ------------------------------------------------------------------------------------------------ reading


def test_comments_are_read_with_their_key_paths_and_vessel_ids() -> None:
    got = [(c.path, c.at, c.text) for c in read_comments(HAND_WRITTEN)]
    assert got == [
        (("name",), "before", ""),  # the blank line between the leading block and the first key's comment
        (("name",), "before", "# about the name"),
        (("name",), "end", "# the name"),
        (("map",), "end", "# the harbour"),
        (("environment", "time_of_day"), "end", "# late afternoon"),
        (("environment", "weather"), "before", "# a clear day"),
        (("acquisition",), "end", "# how long"),
        (("rigs", "usv_standard"), "before", "# the standard rig"),
        (("rigs", "usv_standard"), "end", "# full suite"),
        (("vessels", "usv_1"), "before", "# the lead"),
        (("vessels", "usv_1"), "end", "# first"),
        (("vessels", "usv_1", "speed_mps"), "end", '# slow "#" on purpose'),
        (("vessels", "usv_1", "route", 0), "end", "# slipway"),
        (("vessels", "ferry"), "before", "# the ferry leaves"),
        (("vessels", "ferry"), "end", "# out of the port"),
        ((), "before", "# the end"),
    ]


def test_a_hash_inside_a_text_is_not_a_comment_and_the_leading_block_is_not_read() -> None:
    text = '# leading\nname: "a # b"\nseed: 1 #x\nmap: {type: port, seed: 3}\nrigs: {}\nvessels: [{id: "v #1"}]\n'
    assert read_comments(text) == [Comment(("seed",), "end", "#x")]
    assert read_comments("name: a#b\n") == []


def test_windows_line_ends_and_aliases_keep_comments_on_their_own_keys() -> None:
    text = "name: x\r\nseed: 1  # crlf\r\nbase: &b {type: port, seed: 3}  # anchor\r\nmap: *b  # alias\r\n"
    assert read_comments(text) == [
        Comment(("seed",), "end", "# crlf"),
        Comment(("base",), "end", "# anchor"),
        Comment(("map",), "end", "# alias"),
    ]


# ------------------------------------------------------------------------------------------------ writing


def test_an_unchanged_save_keeps_every_comment_at_its_anchor_and_gives_the_same_bytes_again() -> None:
    out, moved = _save(HAND_WRITTEN)
    assert moved == []
    assert leading_comment(out) == "A hand-written scenario.\nTwo vessels."
    for line in _comment_lines(HAND_WRITTEN):
        assert line in out, line
    lines = out.splitlines()
    assert lines[_line_of(out, "name:")] == "name: demo  # the name"
    assert lines[_line_of(out, "name:") - 1] == "# about the name"
    assert lines[_line_of(out, "map:")].endswith("}  # the harbour")
    assert lines[_line_of(out, "acquisition:")].endswith("}  # how long")
    # a key written inside a flow line: its comments on lines of their own above that line
    env = _line_of(out, "environment:")
    assert lines[env - 2 : env] == ["# late afternoon", "# a clear day"]
    assert lines[_line_of(out, "usv_standard:")] == "  usv_standard: {}  # full suite"
    assert lines[_line_of(out, "usv_standard:") - 1] == "  # the standard rig"
    usv_1 = _line_of(out, "- {id: usv_1")
    assert lines[usv_1 - 3 : usv_1] == ["# the lead", '# slow "#" on purpose', "# slipway"]
    assert lines[usv_1].endswith("  # first")
    ferry = _line_of(out, "- {id: ferry")
    assert lines[ferry - 1] == "# the ferry leaves" and lines[ferry].endswith("]]}  # out of the port")
    assert lines[-1] == "# the end"
    # the file loads to the same scenario, and saving it again changes nothing (same input, same bytes)
    assert load_scenario(parse_yaml(out, "out")) == load_scenario(parse_yaml(HAND_WRITTEN, "in"))
    assert _save(out) == (out, [])
    assert _save(HAND_WRITTEN)[0] == out


SPACED = """\
# Sections set apart by blank lines.

name: spaced
seed: 7

# the map
map: {type: port, seed: 3}
environment:
  time_of_day: "16:30"

  weather: clear
acquisition: {frequency_hz: 5, frames: 20}

rigs:
  usv_standard: {}

vessels:
  - {id: usv_1, role: usv, asset: usv_wamv, rig: usv_standard, speed_mps: 2.5,

     route: [[-170, -110], [-170, -30]]}

  # the ferry
  - {id: ferry, role: target, asset: ropax_ferry_90m, speed_mps: 4.0, route: [[-40, 0], [-110, -90]]}

# the end


"""


def test_blank_lines_that_set_entries_apart_are_kept_and_read_as_empty_comments() -> None:
    got = [(c.path, c.at, c.text) for c in read_comments(SPACED)]
    assert got == [
        (("name",), "before", ""),
        (("map",), "before", ""),
        (("map",), "before", "# the map"),
        (("rigs",), "before", ""),
        (("vessels",), "before", ""),
        (("vessels", "ferry"), "before", ""),
        (("vessels", "ferry"), "before", "# the ferry"),
        ((), "before", ""),
        ((), "before", "# the end"),
    ]  # not the ones inside `environment` and the first vessel's flow line, nor the two after the last line
    out, moved = _save(SPACED)
    assert moved == []
    lines = out.splitlines()
    for key in ("name:", "rigs:", "vessels:"):
        assert lines[_line_of(out, key) - 1] == "", key
    assert lines[_line_of(out, "map:") - 2 : _line_of(out, "map:")] == ["", "# the map"]
    ferry = _line_of(out, "- {id: ferry")
    assert lines[ferry - 2 : ferry] == ["", "# the ferry"]
    assert out.endswith("\n\n# the end\n")
    assert "\n\n\n" not in out and lines[_line_of(out, "name:") - 2] == "# Sections set apart by blank lines."
    assert leading_comment(out) == "Sections set apart by blank lines."
    # the same bytes again, and the same scenario
    assert _save(out) == (out, [])
    assert load_scenario(parse_yaml(out, "out")) == load_scenario(parse_yaml(SPACED, "in"))


def test_a_blank_line_inside_a_text_is_not_layout_and_a_removed_vessels_blank_line_goes_with_it() -> None:
    text = "name: |\n  two\n\n  paragraphs\nseed: 7\n\nvessels:\n\n  - {id: a}\n"
    assert [(c.path, c.text) for c in read_comments(text)] == [(("vessels",), ""), (("vessels", "a"), "")]
    body = "name: x\nvessels:\n- {id: b}\n"
    out, moved = place_comments(body, [Comment(("vessels", "a"), "before", ""), Comment(("vessels",), "before", "")])
    assert (out, moved) == ("name: x\n\nvessels:\n- {id: b}\n", [])
    assert place_comments(body, [Comment(("name",), "end", "")]) == (body, [])  # no trailing spaces


def test_a_blank_line_at_the_end_of_the_file_is_not_written_so_a_save_gives_the_same_bytes_again() -> None:
    """Blank lines after the file's last line are not read (not layout), so none is written there either: an empty
    comment last at the end of the file (a client's) gave a file whose next save lost that blank line."""
    body = "name: x\nseed: 7\n"
    for comments, want in (
        ([Comment((), "before", "")], body),
        ([Comment((), "before", ""), Comment((), "before", "")], body),
        ([Comment((), "before", ""), Comment((), "before", "# a"), Comment((), "before", "")], body[:-1] + "\n\n# a\n"),
        # a blank line before a removed vessel's comments is not the last line: kept
        (
            [Comment((), "before", ""), Comment(("vessels", "b"), "before", "# b")],
            body + "\n# [removed from the scenario: vessel b]\n# b\n",
        ),
    ):
        out, _ = place_comments(body, comments)
        assert out == want, comments
        assert place_comments(body, read_comments(out))[0] == out, comments


def test_a_vessels_comments_follow_it_when_the_list_is_reordered_and_a_waypoint_moves() -> None:
    def edit(data: dict[str, Any]) -> None:
        data["vessels"].reverse()
        data["vessels"][1]["route"][0] = [-160, -100]

    out, moved = _save(HAND_WRITTEN, edit)
    assert moved == []
    lines = out.splitlines()
    ferry, usv_1 = _line_of(out, "- {id: ferry"), _line_of(out, "- {id: usv_1")
    assert ferry < usv_1
    assert lines[ferry - 1] == "# the ferry leaves" and lines[ferry].endswith("# out of the port")
    assert lines[usv_1 - 3] == "# the lead" and lines[usv_1].endswith("# first") and "[-160, -100]" in lines[usv_1]


def test_comments_of_a_removed_vessel_are_kept_at_the_end_of_the_file_and_named() -> None:
    out, moved = _save(HAND_WRITTEN, lambda data: data["vessels"].pop())
    assert [c.text for c in moved] == ["# the ferry leaves", "# out of the port"]
    assert moved_note(moved) == "2 comments of the removed vessel ferry were moved to the end of the file"
    assert out.splitlines()[-4:] == [
        "# the end",
        "# [removed from the scenario: vessel ferry]",
        "# the ferry leaves",
        "# out of the port",
    ]
    assert "id: ferry" not in out
    assert _save(out) == (out, [])  # kept there by later saves, without a second marker


def test_comments_of_the_first_key_stay_out_of_the_leading_comment() -> None:
    text = (
        "\n# about the name\nname: demo\nseed: 1\nmap: {type: port, seed: 3}\n"
        "vessels: [{id: v, asset: tug_32m, route: [[0, 0], [10, 0]]}]\n"
    )
    out = scenario_yaml(load_scenario(parse_yaml(text, "t")), comment="", comments=read_comments(text))
    assert out.startswith("\n# about the name\nname: demo\n")
    assert leading_comment(out) == ""
    out = scenario_yaml(load_scenario(parse_yaml(text, "t")), comment="Described.", comments=read_comments(text))
    assert out.startswith("# Described.\n\n# about the name\nname: demo\n")
    assert leading_comment(out) == "Described." and read_comments(out) == read_comments(text)


def test_place_comments_writes_text_it_is_given_at_the_anchor_or_its_home() -> None:
    body = "name: x\nrigs:\n  a: {}\nvessels:\n- {id: v, role: usv}\n"
    out, moved = place_comments(
        body,
        [
            Comment(("rigs", "a", "lidar"), "end", "# deep"),
            Comment(("vessels", "v"), "end", "# one"),
            Comment(("vessels", "v"), "end", "# two"),
            Comment(("rigs", "gone"), "before", "# old rig"),
        ],
    )
    assert out == (
        "name: x\nrigs:\n  # deep\n  a: {}\nvessels:\n- {id: v, role: usv}  # one  # two\n"
        "# [removed from the scenario: rig gone]\n# old rig\n"
    )
    assert [c.text for c in moved] == ["# old rig"]


def test_bundled_scenarios_round_trip_with_every_comment_at_its_anchor() -> None:
    paths = sorted(bundled_dir().glob("*.yaml"))
    assert len(paths) >= 4
    for path in paths:
        text = path.read_text(encoding="utf-8")
        out, moved = _save(text)
        assert moved == [], path.name
        assert load_scenario(parse_yaml(out, "out")) == load_scenario(path), path.name
        assert leading_comment(out) == leading_comment(text), path.name
        assert read_comments(out) == read_comments(text), path.name  # the same comments at the same anchors
        for line in _comment_lines(text):
            assert line in out.splitlines(), (path.name, line)
        assert _save(out)[0] == out, path.name


def test_bundled_comments_sit_above_the_vessel_they_describe() -> None:
    out, _ = _save((bundled_dir() / "island_occlusion.yaml").read_text(encoding="utf-8"))
    lines = out.splitlines()
    trawler = _line_of(out, "- {id: trawler")
    assert lines[trawler - 2].startswith("# Near traffic on each flank")
    assert lines[trawler - 1].startswith("# and a sailing yacht west of usv_3")


# ------------------------------------------------------------------------------------------------ the API


@pytest.fixture
def client(folder: Path) -> TestClient:
    return TestClient(create_app(folder))


def _document_moved(doc: dict[str, Any]) -> dict[str, Any]:
    """``doc`` with the first waypoint of its first vessel moved by 10 m."""
    x, y = doc["vessels"][0]["route"][0]
    doc["vessels"][0]["route"][0] = [x + 10, y]
    return doc


def test_api_opens_a_file_with_its_comments_and_a_save_writes_them_back(client: TestClient, folder: Path) -> None:
    (folder / "hand.yaml").write_text(HAND_WRITTEN, encoding="utf-8")
    r = client.get("/api/files/hand.yaml")
    assert r.status_code == 200, r.text
    got = r.json()
    assert got["comment"] == "A hand-written scenario.\nTwo vessels."
    assert {"path": ["vessels", "ferry"], "at": "before", "text": "# the ferry leaves"} in got["comments"]
    body = {"document": _document_moved(got["document"]), "comment": got["comment"], "comments": got["comments"]}
    w = client.put("/api/files/hand.yaml", json={**body, "overwrite": True}, headers={"If-Match": got["etag"]})
    assert w.status_code == 200, w.text
    saved = (folder / "hand.yaml").read_text(encoding="utf-8")
    for line in _comment_lines(HAND_WRITTEN):
        assert line in saved, line
    assert "[-160, -110]" in saved and "note" not in w.json()
    assert w.json()["comments"] == client.get("/api/files/hand.yaml").json()["comments"]
    assert w.json()["etag"] == client.get("/api/files/hand.yaml").json()["etag"]


def test_api_carries_blank_lines_as_empty_comments_and_a_save_keeps_them(client: TestClient, folder: Path) -> None:
    (folder / "spaced.yaml").write_text(SPACED, encoding="utf-8")
    got = client.get("/api/files/spaced.yaml").json()
    assert {"path": ["vessels", "ferry"], "at": "before", "text": ""} in got["comments"]
    body = {"document": _document_moved(got["document"]), "comment": got["comment"], "comments": got["comments"]}
    assert client.put("/api/files/spaced.yaml", json={**body, "overwrite": True}).status_code == 200
    saved = (folder / "spaced.yaml").read_text(encoding="utf-8")
    assert saved == _save(SPACED, lambda d: d["vessels"][0]["route"][0].__setitem__(0, -160))[0]
    assert "\n\nrigs:" in saved and "\n\n# the ferry\n" in saved


def test_api_save_without_comments_keeps_those_of_the_file_it_replaces(client: TestClient, folder: Path) -> None:
    (folder / "hand.yaml").write_text(HAND_WRITTEN, encoding="utf-8")
    got = client.get("/api/files/hand.yaml").json()
    body = {"document": _document_moved(got["document"]), "comment": "New description.", "overwrite": True}
    assert client.put("/api/files/hand.yaml", json=body).status_code == 200
    saved = (folder / "hand.yaml").read_text(encoding="utf-8")
    assert leading_comment(saved) == "New description."
    for line in _comment_lines(HAND_WRITTEN)[:-2]:  # all but the old leading block
        assert line in saved, line
    # an empty list drops them, as asked
    assert client.put("/api/files/hand.yaml", json={**body, "comments": []}).status_code == 200
    assert read_comments((folder / "hand.yaml").read_text(encoding="utf-8")) == []


def test_api_save_says_which_comments_lost_their_vessel(client: TestClient, folder: Path) -> None:
    (folder / "hand.yaml").write_text(HAND_WRITTEN, encoding="utf-8")
    got = client.get("/api/files/hand.yaml").json()
    doc = got["document"]
    doc["vessels"] = [v for v in doc["vessels"] if v["id"] != "ferry"]
    w = client.put("/api/files/hand.yaml", json={"document": doc, "comments": got["comments"], "overwrite": True})
    assert w.status_code == 200, w.text
    assert w.json()["note"] == "2 comments of the removed vessel ferry were moved to the end of the file"
    saved = (folder / "hand.yaml").read_text(encoding="utf-8")
    assert saved.endswith("# [removed from the scenario: vessel ferry]\n# the ferry leaves\n# out of the port\n")
    assert w.json()["comments"][-3:] == [
        {"path": [], "at": "before", "text": t}
        for t in ("# [removed from the scenario: vessel ferry]", "# the ferry leaves", "# out of the port")
    ]


def test_api_bundled_scenario_saved_under_a_new_name_keeps_its_comments(client: TestClient, folder: Path) -> None:
    got = client.get("/api/bundled/island_port_waves").json()
    assert got["comments"] == [
        {
            "path": ["vessels", "escort_1"],
            "at": "before",
            "text": "# Escorts: each USV has a vessel within LiDAR range all the time (parallel routes, or trailing "
            "on a loop).",
        }
    ]
    body = {"document": got["document"], "comment": got["comment"], "comments": got["comments"]}
    assert client.put("/api/files/waves.yaml", json=body).status_code == 200
    saved = (folder / "waves.yaml").read_text(encoding="utf-8")
    original = (bundled_dir() / "island_port_waves.yaml").read_text(encoding="utf-8")
    assert read_comments(saved) == read_comments(original) and leading_comment(saved) == leading_comment(original)
    lines = saved.splitlines()
    assert lines[_line_of(saved, "- {id: escort_1") - 1].startswith("# Escorts:")


@pytest.mark.parametrize(
    "comment",
    [
        {"path": ["name"], "at": "end", "text": "no hash"},
        {"path": ["name"], "at": "end", "text": "# two\nlines"},
        {"path": ["name"], "at": "end", "text": "# a\u2028break"},
        {"path": ["name"], "at": "beside", "text": "# where?"},
        {"path": [1.5], "at": "end", "text": "# a number"},
    ],
)
def test_api_refuses_a_comment_it_cannot_write_as_one_line(client: TestClient, comment: dict[str, Any]) -> None:
    doc = client.get("/api/bundled/port_entry").json()["document"]
    good = {"path": ["name"], "at": "end", "text": "# fine"}
    assert client.put("/api/files/ok.yaml", json={"document": doc, "comments": [good]}).status_code == 200
    r = client.put("/api/files/x.yaml", json={"document": doc, "comments": [good, comment]})
    assert r.status_code == 422, r.text
    assert "comments.1" in r.json()["error"]
    assert not (Path(client.app.state.folder.root) / "x.yaml").exists()  # type: ignore[attr-defined]
