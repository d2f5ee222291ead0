"""The editor's HTTP API under malformed input and misuse: each test is a case an audit found failing (a 500, a
silent fallback, a file saved that does not load again, a leftover or changed file, a server out of memory)."""

from __future__ import annotations

import copy
import json
import os
import stat
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
    from fastapi.testclient import TestClient

from mmusv.editor.app import MAX_BODY_BYTES, create_app

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

JSON = {"content-type": "application/json"}

SMALL_RIG = {"preset": "lidar_only", "lidar": {"channels": 16, "points_per_second": 20000}}


@pytest.fixture
def client(folder: Path) -> Iterator[TestClient]:
    app = create_app(folder)
    yield TestClient(app, raise_server_exceptions=False)  # a 500 is an answer to look at, not an exception
    app.state.jobs.shutdown()


@pytest.fixture
def doc(client: TestClient) -> dict[str, Any]:
    """The bundled ``port_entry`` scenario as a document, with small LiDAR-only rigs (quick to run)."""
    r = client.get("/api/bundled/port_entry")
    assert r.status_code == 200, r.text
    d: dict[str, Any] = r.json()["document"]
    return {**d, "rigs": dict.fromkeys(d["rigs"], SMALL_RIG)}


def error_of(r: Any, status: int) -> str:
    """The JSON error message of ``r``, asserting its status and that no traceback leaked."""
    assert r.status_code == status, (r.status_code, r.text[:500])
    assert "Traceback" not in r.text
    message: str = r.json()["error"]
    return message


def fleet(doc: dict[str, Any], n: int) -> dict[str, Any]:
    """``doc`` with its first vessel (a USV) and ``n`` copies of its second sailing the same route."""
    out = copy.deepcopy(doc)
    out["vessels"] = [doc["vessels"][0]] + [dict(doc["vessels"][1], id=f"t{i}") for i in range(n)]
    return out


# ------------------------------------------------------------------------------------------------ saving files


@pytest.mark.parametrize("kind", ["folder", "fifo"])
def test_a_folder_or_fifo_of_that_name_is_never_replaced(
    client: TestClient, folder: Path, doc: dict[str, Any], kind: str
) -> None:
    target = folder / "taken.yaml"
    if kind == "folder":
        target.mkdir()
        (target / "inside.txt").write_text("kept")
    else:
        os.mkfifo(target)
    r = client.put("/api/files/taken.yaml", json={"document": doc, "overwrite": True})
    assert "not a scenario file" in error_of(r, 409)  # was a 500 "Is a directory" (folder), or replaced (fifo)
    if kind == "folder":
        assert (target / "inside.txt").read_text() == "kept"
    else:
        assert stat.S_ISFIFO(target.lstat().st_mode)
    assert sorted(p.name for p in folder.iterdir()) == ["taken.yaml"]


def test_a_write_that_fails_half_way_leaves_the_file_and_no_temporary_file(
    client: TestClient, folder: Path, doc: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    assert client.put("/api/files/a.yaml", json={"document": doc}).status_code == 200
    before = (folder / "a.yaml").read_bytes()

    def crash(*args: Any, **kwargs: Any) -> None:
        raise RuntimeError("simulated crash between writing and renaming")

    monkeypatch.setattr(os, "replace", crash)
    r = client.put("/api/files/a.yaml", json={"document": {**doc, "seed": 99}, "overwrite": True})
    assert r.status_code == 500 and "Traceback" not in r.text
    monkeypatch.undo()
    assert (folder / "a.yaml").read_bytes() == before
    assert sorted(p.name for p in folder.iterdir()) == ["a.yaml"]  # was: a .mmusv-editor-*.tmp left behind


def test_saved_files_get_the_usual_permissions_and_replaced_ones_keep_theirs(
    client: TestClient, folder: Path, doc: dict[str, Any]
) -> None:
    old = os.umask(0o022)
    try:
        assert client.put("/api/files/new.yaml", json={"document": doc}).status_code == 200
        assert stat.S_IMODE((folder / "new.yaml").stat().st_mode) == 0o644  # was 0o600 (a temporary file's)
        os.chmod(folder / "new.yaml", 0o640)
        assert client.put("/api/files/new.yaml", json={"document": doc, "overwrite": True}).status_code == 200
        assert stat.S_IMODE((folder / "new.yaml").stat().st_mode) == 0o640
    finally:
        os.umask(old)


@pytest.mark.parametrize("char", ["\x00", "\x07", "\x1b", "\x7f", "\x9b", "\ufffe"])
def test_a_comment_a_yaml_file_cannot_hold_is_refused(
    client: TestClient, folder: Path, doc: dict[str, Any], char: str
) -> None:
    r = client.put("/api/files/c.yaml", json={"document": doc, "comment": f"line one\nbad {char} here"})
    message = error_of(r, 422)  # was saved (200), then the file did not open again (not valid YAML)
    assert "comment" in message and f"U+{ord(char):04X}" in message
    assert not (folder / "c.yaml").exists()
    # every line break and tab are fine: the comment is written line by line
    r = client.put("/api/files/c.yaml", json={"document": doc, "comment": "a\rb\x85c\u2028d\te"})
    assert r.status_code == 200, r.text
    back = client.get("/api/files/c.yaml")
    assert back.status_code == 200 and back.json()["comment"] == "a\nb\nc\nd\te"


def test_rig_names_with_line_breaks_or_controls_are_refused(client: TestClient, doc: dict[str, Any]) -> None:
    # Were saved, and "a\x85b" read back as "a b" (folded); rig names are now letters, digits, _ and - only
    # (config.RIG_NAME), so nothing is written.
    for name in ("a\x85b", "a\u2028b", "a\u2029b", "tab\there", "bell\x07"):
        d = copy.deepcopy(doc)
        d["rigs"][name] = SMALL_RIG
        d["vessels"][0]["rig"] = name
        r = client.put("/api/files/r.yaml", json={"document": d, "overwrite": True})
        assert "rig name" in error_of(r, 422), name
        assert client.get("/api/files/r.yaml").status_code == 404


def test_a_scenario_too_large_for_a_scenario_file_is_not_saved(
    client: TestClient, folder: Path, doc: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    import mmusv.yamlio

    monkeypatch.setattr(mmusv.yamlio, "MAX_YAML_VALUES", 2000)  # the real limit (1,000,000) takes 30 s to reach
    d = copy.deepcopy(doc)
    d["vessels"][0]["route"] = [[-170.0 + 0.5 * i, -110.0 + 0.5 * (i % 2)] for i in range(1000)]
    r = client.put("/api/files/big.yaml", json={"document": d})
    message = error_of(r, 422)  # was saved, and then refused on opening ("expands to more than ... values")
    assert "2,000 values" in message and "fewer waypoints" in message
    assert not (folder / "big.yaml").exists()
    d["vessels"][0]["route"] = d["vessels"][0]["route"][:100]
    assert client.put("/api/files/big.yaml", json={"document": d}).status_code == 200
    assert client.get("/api/files/big.yaml").status_code == 200


def test_if_match_understands_star_and_lists(client: TestClient, doc: dict[str, Any]) -> None:
    tag = client.put("/api/files/m.yaml", json={"document": doc}).json()["etag"]
    for seed, header, status in [
        (5, "*", 200),  # was 412: "*" is any current version
        (6, f'"{"0" * 32}", "{{tag}}"', 200),  # was 412: a list naming the current version
        (7, 'W/"{tag}"', 200),
        (8, f'"{"0" * 32}", "{"1" * 32}"', 412),
        # no ETag at all, or not one the editor gives: it was 412 "changed since you opened it", which it was not
        (9, "", 400),
        (10, '"0000"', 400),
        (11, "garbage", 400),
    ]:
        r = client.put(
            "/api/files/m.yaml",
            json={"document": {**doc, "seed": seed}, "overwrite": True},
            headers={"If-Match": header.format(tag=tag)},
        )
        assert r.status_code == status, (header, r.text)
        if status == 400:
            assert "names no version the editor gave" in r.json()["error"], r.text
        if status == 200:
            tag = r.json()["etag"]


def test_if_match_star_needs_the_file_to_exist(client: TestClient, folder: Path, doc: dict[str, Any]) -> None:
    r = client.put("/api/files/gone.yaml", json={"document": doc}, headers={"If-Match": "*"})
    assert "does not exist" in error_of(r, 412)
    assert not (folder / "gone.yaml").exists()


def test_if_match_of_a_file_deleted_since_is_refused(client: TestClient, folder: Path, doc: dict[str, Any]) -> None:
    """An ETag of a file deleted (or renamed in another tab) since: it was created again under its old name, 200,
    where ``*`` was refused (RFC 9110: If-Match fails when no current version matches)."""
    tag = client.put("/api/files/was.yaml", json={"document": doc}).json()["etag"]
    (folder / "was.yaml").rename(folder / "renamed.yaml")
    r = client.put("/api/files/was.yaml", json={"document": doc, "overwrite": True}, headers={"If-Match": f'"{tag}"'})
    assert "does not exist" in error_of(r, 412) and "deleted or renamed" in r.text
    assert not (folder / "was.yaml").exists()
    # saved again without If-Match (the page's Overwrite), it is created
    assert client.put("/api/files/was.yaml", json={"document": doc, "overwrite": True}).status_code == 200


# ------------------------------------------------------------------------------------------------ opening files


@pytest.mark.parametrize("name", ["x.yaml%0A", "x.yml%0A"])
def test_a_name_with_a_trailing_newline_is_not_another_file(
    client: TestClient, folder: Path, doc: dict[str, Any], name: str
) -> None:
    for real in ("x.yaml", "x.yml"):
        assert client.put(f"/api/files/{real}", json={"document": doc}).status_code == 200
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    for r in (
        client.get(f"/api/files/{name}"),  # was: x.yaml served
        client.put(f"/api/files/{name}", json={"document": {**doc, "seed": 3}, "overwrite": True}),  # was: replaced
    ):
        assert "not allowed" in error_of(r, 400)
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before


def test_the_etag_is_of_the_very_bytes_whose_text_is_shown(
    client: TestClient, folder: Path, doc: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    import mmusv.editor.app as editor_app

    assert client.put("/api/files/e.yaml", json={"document": doc}).status_code == 200
    load = editor_app.load_document

    def load_while_another_program_saves(text: str, where: str, **kw: Any) -> tuple[dict[str, Any], bool]:
        (folder / "e.yaml").write_text(text.replace("seed: 7", "seed: 8"))  # between reading and answering
        return load(text, where, **kw)

    monkeypatch.setattr(editor_app, "load_document", load_while_another_program_saves)
    shown = client.get("/api/files/e.yaml").json()
    monkeypatch.undo()
    assert shown["document"]["seed"] == 7
    # Was: the ETag of the new bytes with the old text, so this save replaced the other program's edit unseen.
    r = client.put(
        "/api/files/e.yaml",
        json={"document": shown["document"], "overwrite": True},
        headers={"If-Match": f'"{shown["etag"]}"'},
    )
    assert r.status_code == 412
    assert "seed: 8" in (folder / "e.yaml").read_text()


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("name: x\nvessels:\n  - {id: a, asset: usv_wamv, speed_mps: .nan, route: [[0, 0], [9, 9]]}\n", "speed_mps"),
        ("name: x\nvessels:\n  - {id: a, asset: usv_wamv, speed_mps: 1, route: [[0, 0], [9, .inf]]}\n", "route[1][1]"),
        ("name: x\nmap: {type: port, seed: -.inf}\nvessels: []\n", "map.seed"),
        ('name: "\\ud800"\nvessels: []\n', "name"),
        ('name: x\nrigs: {"\\udc00": {}}\nvessels: []\n', "rigs"),
    ],
)
def test_files_with_values_json_cannot_carry_open_with_a_message(
    client: TestClient, folder: Path, text: str, says: str
) -> None:
    (folder / "v.yaml").write_text(text, encoding="utf-8", errors="surrogatepass")
    message = error_of(client.get("/api/files/v.yaml"), 422)  # was a 500 (the JSON answer could not be written)
    assert says in message and "fix it as text" in message


@pytest.mark.parametrize(
    ("data", "says"),
    [
        ("# café\nname: x\nvessels: []\n".encode("latin-1"), "byte 0xe9 at offset 5"),
        ("name: x\nvessels: []\n".encode("utf-16"), "UTF-16"),
        (b"\x89PNG\r\n\x1a\n\x00\x00", "NUL byte"),
    ],
)
def test_files_that_are_not_utf8_are_refused_naming_the_byte(
    client: TestClient, folder: Path, data: bytes, says: str
) -> None:
    (folder / "t.yaml").write_bytes(data)
    message = error_of(client.get("/api/files/t.yaml"), 422)  # latin-1 opened with U+FFFD in place of é
    assert says in message and "t.yaml" in message


def test_a_file_larger_than_the_editor_opens_is_refused_unread(client: TestClient, folder: Path) -> None:
    limit = 16 * 1024 * 1024
    (folder / "huge.yaml").write_bytes(b"# " + b"x" * limit + b"\nname: x\nvessels: []\n")
    message = error_of(client.get("/api/files/huge.yaml"), 422)  # was read and parsed whole (35 s at 70 MiB)
    assert "larger than 16,777,216 bytes" in message


# ------------------------------------------------------------------------------------------------ request bodies


def test_a_chunked_body_over_the_limit_gets_413(client: TestClient) -> None:
    def chunks() -> Iterator[bytes]:
        for _ in range(MAX_BODY_BYTES // (1 << 20) + 2):
            yield b" " * (1 << 20)

    r = client.post("/api/evaluate", content=chunks(), headers=JSON)  # no Content-Length: sent chunked
    assert "larger than 16777216 bytes" in error_of(r, 413)  # was 400 "There was an error parsing the body"


def test_a_content_length_that_is_not_a_number_is_named(client: TestClient) -> None:
    r = client.post("/api/evaluate", content=b"{}", headers={**JSON, "content-length": "12abc"})
    assert "Content-Length" in error_of(r, 400)  # was 413 "larger than 16777216 bytes"


@pytest.mark.parametrize(
    ("body", "says"),
    [
        (b'{"document": ' + b"[" * 100_000 + b"]" * 100_000 + b"}", "nested too deeply"),
        (b'{"document": {"seed": ' + b"9" * 5000 + b"}}", "more than 4,300 digits"),
        (b'{"document": {"name": "caf\xe9"}}', "not UTF-8 text (byte 0xe9 at offset 26)"),
    ],
)
def test_json_bodies_python_cannot_read_say_why(client: TestClient, body: bytes, says: str) -> None:
    message = error_of(client.post("/api/evaluate", content=body, headers=JSON), 400)
    assert says in message  # was "There was an error parsing the body" for all three


@pytest.mark.parametrize(
    "kwargs",
    [
        {"content": b'{"document": {}}', "headers": {"content-type": "text/plain"}},
        {"content": b'{"document": {}}'},
        {"data": {"document": "x"}},
        {"files": {"document": ("a.json", b"{}")}},
        {"content": b"name: x\n", "headers": {"content-type": "application/yaml"}},
    ],
)
def test_a_body_not_sent_as_json_says_json_is_expected(client: TestClient, kwargs: dict[str, Any]) -> None:
    message = error_of(client.post("/api/evaluate", **kwargs), 422)
    assert "application/json" in message  # was "Input should be a valid dictionary or object to extract fields"


@pytest.mark.parametrize(
    ("path", "extra", "where"),
    [
        ("/api/evaluate", {}, "document.vessels[0].id"),
        ("/api/poses", {"frame": 0}, "document.vessels[0].id"),
        ("/api/preview", {"frame": 0}, "document.vessels[0].id"),
        ("/api/files/s.yaml", {}, "document.vessels[0].id"),
    ],
)
def test_unpaired_surrogates_in_a_document_are_refused(
    client: TestClient, doc: dict[str, Any], path: str, extra: dict[str, Any], where: str
) -> None:
    d = copy.deepcopy(doc)
    d["vessels"][0]["id"] = "usv\ud800"
    body = json.dumps({"document": d, **extra}).encode()  # ASCII JSON with the escape "\ud800"
    method = "PUT" if path.startswith("/api/files") else "POST"
    message = error_of(client.request(method, path, content=body, headers=JSON), 422)  # evaluate: was a 500
    assert where in message and "surrogate" in message


def test_unpaired_surrogates_in_a_map_are_refused(client: TestClient) -> None:
    body = json.dumps({"map": {"type": "port", "seed": 3, "params": {"\udc80": 1}}}).encode()
    assert "surrogate" in error_of(client.post("/api/map", content=body, headers=JSON), 422)


@pytest.mark.parametrize(
    ("path", "body", "field"),
    [
        ("/api/poses", {"frame": True}, "frame"),
        ("/api/poses", {"frame": "3"}, "frame"),
        ("/api/preview", {"frame": True}, "frame"),
        ("/api/files/x.yaml", {"overwrite": 1}, "overwrite"),
        ("/api/files/x.yaml", {"overwrite": "true"}, "overwrite"),
        ("/api/runs", {"name": "x.yaml", "frames": True}, "frames"),
        ("/api/runs", {"name": "x.yaml", "frames": "2"}, "frames"),
    ],
)
def test_request_fields_are_not_coerced_from_other_types(
    client: TestClient, folder: Path, doc: dict[str, Any], path: str, body: dict[str, Any], field: str
) -> None:
    if path != "/api/runs":
        body = {"document": doc, **body}
    method = "PUT" if path.startswith("/api/files") else "POST"
    message = error_of(client.request(method, path, json=body), 422)  # was: true read as 1, "3" as 3 and so on
    assert message.startswith(f"malformed request: {field}:")
    assert not (folder / "x.yaml").exists() and not (folder / "out").exists()


def test_non_finite_numbers_in_a_document_are_refused_naming_the_field(client: TestClient, doc: dict[str, Any]) -> None:
    body = json.dumps({"document": doc}).replace('"speed_mps": 2.5', '"speed_mps": NaN', 1).encode()
    message = error_of(client.post("/api/evaluate", content=body, headers=JSON), 422)
    assert "document.vessels[0].speed_mps = nan: not a finite number" in message


# ------------------------------------------------------------------------------------------------ checks and preview


def test_a_fleet_too_large_to_check_pairwise_is_refused_before_the_checks(
    client: TestClient, doc: dict[str, Any]
) -> None:
    from mmusv.generate.samples import MAX_CHECK_PAIR_SAMPLES

    r = client.post("/api/evaluate", json={"document": fleet(doc, 1000)})  # a body of 170 kB
    assert r.status_code == 200, r.text[:300]
    ev = r.json()  # was: 45 s, 5.5 GB and 100 MB of answer; 5000 vessels took the server's memory
    assert ev["valid"] is False and "pairs of vessels" in ev["errors"][0]["message"]
    assert f"at most {MAX_CHECK_PAIR_SAMPLES:,}" in ev["errors"][0]["message"]


def test_problems_beyond_the_limit_are_counted_not_listed(
    client: TestClient, doc: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    import mmusv.editor.evaluate as editor_evaluate

    monkeypatch.setattr(editor_evaluate, "MAX_PROBLEMS", 5)
    ev = client.post("/api/evaluate", json={"document": fleet(doc, 8)}).json()  # 8 targets on one route: 28 pairs
    assert ev["valid"] is True and len(ev["problems"]) == 6
    more = ev["problems"][-1]
    assert more["check"] == "more" and "more problems" in more["message"] and "at most 5" in more["message"]


def test_preview_refuses_a_fleet_it_would_take_minutes_to_draw(client: TestClient, doc: dict[str, Any]) -> None:
    r = client.post("/api/preview", json={"document": fleet(doc, 1000), "frame": 0})
    assert "at most 1,000" in error_of(r, 422)  # was drawn: 40 s at 6000 vessels


# ------------------------------------------------------------------------------------------------ runs


@pytest.mark.parametrize("job", ["+1", "%201", "1_0", "01", "-1", "99999999999999999999999"])
def test_run_ids_are_plain_whole_numbers(client: TestClient, job: str) -> None:
    for method in ("GET", "DELETE"):
        message = error_of(client.request(method, f"/api/runs/{job}"), 422)  # "1_0" was run 10, "+1" run 1
        assert "job_id" in message


def test_one_output_folder_has_one_run_at_a_time(client: TestClient, folder: Path, doc: dict[str, Any]) -> None:
    for name in ("q.yaml", "q.yml"):
        assert client.put(f"/api/files/{name}", json={"document": doc}).status_code == 200
    first = client.post("/api/runs", json={"name": "q.yaml"}).json()
    try:
        for name in ("q.yaml", "q.yml"):  # both write out/q
            message = error_of(client.post("/api/runs", json={"name": name}), 409)  # was started, then failed
            assert f"run {first['id']}" in message and "out/q" in message
        assert [j["id"] for j in client.get("/api/runs").json()] == [first["id"]]
    finally:
        client.delete(f"/api/runs/{first['id']}")


def test_a_run_never_writes_through_a_link_out_of_the_folder(
    client: TestClient, folder: Path, tmp_path: Path, doc: dict[str, Any]
) -> None:
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    os.symlink(elsewhere, folder / "out")
    assert client.put("/api/files/q.yaml", json={"document": doc}).status_code == 200
    r = client.post("/api/runs", json={"name": "q.yaml", "frames": 1})
    assert "outside the editor's folder" in error_of(r, 400)  # was: the recording written into elsewhere/q
    assert client.get("/api/runs").json() == []
    assert list(elsewhere.iterdir()) == []


def test_a_bundled_name_with_a_trailing_newline_is_not_another_scenario(client: TestClient) -> None:
    # Starlette's route drops the newline: `port_entry%0A` was served as `port_entry`.
    assert client.get("/api/bundled/port_entry").status_code == 200
    r = client.get("/api/bundled/port_entry%0A")
    assert r.status_code == 404 and "no bundled scenario" in r.text


def test_a_comment_anchored_to_a_vessel_by_its_position_is_refused(
    client: TestClient, folder: Path, doc: dict[str, Any]
) -> None:
    """``["vessels", 1]`` was taken for the ``vessels:`` key: the comment saved above it, with no note."""
    for path in (["vessels", 1], ["vessels", -1, "route"], ["rigs", 0]):
        body = {"document": doc, "comments": [{"path": path, "at": "before", "text": "# v1"}]}
        r = client.put("/api/files/anchored.yaml", json=body)
        assert "is named by its id, a string" in error_of(r, 422), r.text
    assert not (folder / "anchored.yaml").exists()
    vid = doc["vessels"][0]["id"]
    body = {"document": doc, "comments": [{"path": ["vessels", vid, "route", 1], "at": "before", "text": "# ok"}]}
    assert client.put("/api/files/anchored.yaml", json=body).status_code == 200


def test_a_file_name_refused_says_the_limits_it_broke(client: TestClient, doc: dict[str, Any]) -> None:
    """A 129-character name and a name with letters outside ASCII were refused by a rule that named neither."""
    assert client.put(f"/api/files/{'a' * 123}.yaml", json={"document": doc}).status_code == 200  # 128: the most
    for name in (f"{'a' * 124}.yaml", "h\u00e4fen.yaml"):
        said = error_of(client.put(f"/api/files/{name}", json={"document": doc}), 400)
        assert "ASCII letters" in said and "at most 128 characters" in said, said
