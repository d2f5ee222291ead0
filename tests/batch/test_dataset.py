"""`mmusv dataset SPEC -o DIR` (generate → record → OPV2V → dataset.json) and the dataset.json index: what it
lists agrees with the files, a re-run is a no-op, an unfinished dataset is finished, consumers read it."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from mmusv.batch import build_dataset, dataset_recordings, read_index, run_many
from mmusv.batch.index import Entry, write_index
from mmusv.cli import main
from mmusv.config import load_scenario, scenario_hash
from mmusv.errors import IoError
from mmusv.export import convert
from mmusv.studies.detection.sources import resolve_dataset

from .conftest import SPEC, good_folder, scenario, stamps, tree, write


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, str]:
    """``mmusv dataset`` of the tiny spec with a pool of 2: the spec file, the dataset folder, what it printed."""
    base = tmp_path_factory.mktemp("dataset")
    spec = write(base / "tinyset.yaml", SPEC)
    out = base / "ds"
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["dataset", str(spec), "-o", str(out), "--jobs", "2"]) == 0
    return spec, out, buf.getvalue()


def test_dataset_generates_records_converts_and_indexes(built: tuple[Path, Path, str]) -> None:
    _spec, out, printed = built
    assert "scenarios: generated" in printed and "3 done, 0 failed, 0 skipped, 0 retried" in printed
    doc = read_index(out)
    assert doc["spec"]["name"] == "tinyset" and doc["totals"]["complete"] == 3 == len(doc["recordings"])
    for r in doc["recordings"]:
        sc = load_scenario(out / "scenarios" / r["scenario_file"])
        folder = out / "recordings" / r["name"]
        assert r["status"] == "complete" and r["config_hash"] == scenario_hash(sc) and r["seed"] == sc.seed
        assert r["recording"] == f"recordings/{r['name']}/{sc.name}.mcap" and r["frames"] == 6 == r["frames_requested"]
        assert r["bytes"] == sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())
        manifest = json.loads((folder / "manifest.json").read_text())
        assert manifest["config_hash"] == r["config_hash"] and manifest["frames_written"] == r["frames"]
    conv = (out / "opv2v/conversion.yaml").read_text()
    assert "status: complete" in conv and f"frames_converted: {doc['opv2v']['frames']}" in conv
    assert doc["opv2v"]["sources"] == {r["name"]: r["config_hash"] for r in doc["recordings"]}


def test_dataset_rerun_changes_nothing(
    built: tuple[Path, Path, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec, out, _ = built
    before = tree(out)
    names = [p.name for p in (out / "recordings").iterdir() if p.is_dir() and not p.name.startswith(".")]
    rec_stamps = stamps(out / "recordings", names)
    assert main(["dataset", str(spec), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "kept (same spec)" in printed and "0 done, 0 failed, 3 skipped" in printed and "is up to date" in printed
    assert tree(out) == before and stamps(out / "recordings", names) == rec_stamps


def test_an_unfinished_dataset_is_finished(built: tuple[Path, Path, str], tmp_path: Path) -> None:
    """A dataset whose run stopped (a recording without its manifest, the conversion not written) is finished by
    the same call, redoing only what was missing, into the same bytes."""
    spec, done, _ = built
    out = tmp_path / "ds"
    shutil.copytree(done, out)
    first = sorted(p for p in (out / "recordings").iterdir() if p.is_dir() and not p.name.startswith("."))[0]
    (first / "manifest.json").unlink()
    shutil.rmtree(out / "opv2v")
    others = [
        p.name for p in (out / "recordings").iterdir() if p.is_dir() and p != first and not p.name.startswith(".")
    ]
    keep = stamps(out / "recordings", others)
    rep = build_dataset(spec, out_dir=out)
    assert not rep.generated and rep.batch.summary() == "1 done, 0 failed, 2 skipped, 0 retried" and rep.converted
    assert stamps(out / "recordings", others) == keep and tree(out) == tree(done)


def test_a_combination_added_before_the_others_records_only_its_own(
    built: tuple[Path, Path, str], tmp_path: Path
) -> None:
    """A combination put first in the spec: the draws were keyed by the combinations' places in the list, so every
    scenario changed and the whole dataset was recorded again; they are keyed by name, so only the new one is."""
    _spec, done, _ = built
    out = tmp_path / "ds"
    shutil.copytree(done, out)
    names = [p.name for p in (out / "recordings").iterdir() if p.is_dir() and not p.name.startswith(".")]
    keep = stamps(out / "recordings", names)
    added = {"family": "overtaking", "difficulty": "near", "cooperating": 1, "targets": ["small"], "quota": 1}
    edited = write(tmp_path / "tinyset.yaml", dict(SPEC, combinations=[added, *SPEC["combinations"]]))
    rep = build_dataset(edited, out_dir=out)
    assert rep.generated and rep.batch.summary() == "1 done, 0 failed, 3 skipped, 0 retried"
    assert stamps(out / "recordings", names) == keep


def test_a_sequence_removed_by_hand_is_converted_again(built: tuple[Path, Path, str], tmp_path: Path) -> None:
    """A converted sequence's folder removed by hand (``conversion.yaml`` still says complete): the re-run said
    "opv2v: ... is up to date" and left it missing; it converts again, into the same bytes, the recordings kept."""
    spec, done, _ = built
    out = tmp_path / "ds"
    shutil.copytree(done, out)
    seq = sorted(p for p in (out / "opv2v").glob("*/*") if p.is_dir() and p.parent.name != "opencood")[0]
    shutil.rmtree(seq)
    names = [p.name for p in (out / "recordings").iterdir() if p.is_dir() and not p.name.startswith(".")]
    keep = stamps(out / "recordings", names)
    rep = build_dataset(spec, out_dir=out)
    assert rep.converted and rep.batch.summary() == "0 done, 0 failed, 3 skipped, 0 retried"
    assert seq.is_dir() and tree(out) == tree(done) and stamps(out / "recordings", names) == keep


def test_consumers_read_the_index(built: tuple[Path, Path, str], tmp_path: Path) -> None:
    _spec, out, _ = built
    recs = dataset_recordings(out)
    assert [p.relative_to(out).parts[0] for p in recs] == ["recordings"] * 3
    ds = resolve_dataset([out], opv2v=None, split="all")
    assert sorted(ds.sources.values()) == sorted(recs)
    convert(out, out_dir=tmp_path / "again")  # the folder: the recordings of its dataset.json, default options
    assert tree(tmp_path / "again") == tree(out / "opv2v")


def test_failed_and_pending_recordings_are_not_read(tmp_path: Path) -> None:
    src = tmp_path / "src"
    src.mkdir()
    write(src / "a.yaml", scenario("a", frames=3))
    write(src / "b.yaml", {**scenario("b", frames=3), "rigs": {"r": {"lidar": {"channels": 0}}}})
    out = tmp_path / "out"
    assert not run_many(src, out_dir=out).ok
    assert dataset_recordings(out) == [out / "a/a.mcap"]
    assert dataset_recordings(out, statuses=("failed",)) == []  # b has no recording at all
    assert [r["status"] for r in read_index(out)["recordings"]] == ["complete", "failed"]
    assert list(resolve_dataset([out], opv2v=None, split="all").sources) == ["a"]


def test_a_bad_index_is_named(tmp_path: Path) -> None:
    (tmp_path / "dataset.json").write_text("[1, 2]")
    with pytest.raises(IoError, match=r"dataset.json: expected a JSON object"):
        read_index(tmp_path)
    (tmp_path / "dataset.json").write_text('{"format": "x"}')
    with pytest.raises(IoError, match="not an mmusv dataset index"):
        dataset_recordings(tmp_path)
    entry = Entry("a", "a.yaml", "a", "0" * 64, 1, "a/a.mcap", "complete", 1, 1, 1, 10)
    write_index(tmp_path / "dataset.json", [entry])
    with pytest.raises(IoError, match=r"recordings\[0\] \(a\) lists .*a\.mcap, which does not exist"):
        dataset_recordings(tmp_path)
    with pytest.raises(IoError, match="status outside"):
        write_index(tmp_path / "dataset.json", [Entry("a", "a.yaml", "a", None, None, None, "done", 0, 0, 0, 0)])
    (tmp_path / "plain").mkdir()
    with pytest.raises(IoError, match=r"plain is not a file but a folder without a dataset\.json"):
        convert(tmp_path / "plain", out_dir=tmp_path / "o")


@pytest.mark.parametrize(
    ("key", "value", "said"),
    [
        # followed out of the dataset's folder: its index holds paths relative to it only
        ("recording", "../outside/x.mcap", "recordings[0].recording = '../outside/x.mcap': must be a relative path"),
        ("recording", "/abs/x.mcap", "recordings[0].recording = '/abs/x.mcap': must be a relative path"),
        ("recording", 5, "recordings[0].recording = 5: must be a relative path"),  # read as the file '5'
        ("status", ["complete"], "recordings[0].status = ['complete']: must be a string, not list"),  # TypeError
        ("name", None, "recordings[0].name = None: must be a string, not NoneType"),
        # passed over without a word: the conversion and the studies read fewer recordings than listed
        ("status", "bogus", "recordings[0] (a).status = 'bogus': must be one of complete, failed, pending"),
        ("recording", None, "recordings[0] (a) is complete but names no recording"),
    ],
)
def test_an_index_entry_of_the_wrong_kind_is_named(tmp_path: Path, key: str, value: object, said: str) -> None:
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside/x.mcap").write_bytes(b"")
    (tmp_path / "ds/a").mkdir(parents=True)
    (tmp_path / "ds/a/a.mcap").write_bytes(b"")
    entry = Entry("a", "a.yaml", "a", "0" * 64, 1, "a/a.mcap", "complete", 1, 1, 1, 10)
    write_index(tmp_path / "ds/dataset.json", [entry])
    assert dataset_recordings(tmp_path / "ds") == [tmp_path / "ds/a/a.mcap"]
    doc = json.loads((tmp_path / "ds/dataset.json").read_text())
    doc["recordings"][0][key] = value
    (tmp_path / "ds/dataset.json").write_text(json.dumps(doc))
    with pytest.raises(IoError) as err:
        dataset_recordings(tmp_path / "ds")
    assert str(err.value).startswith(f"{tmp_path / 'ds/dataset.json'}: ") and said in str(err.value), str(err.value)


def test_a_killed_batch_leaves_an_index_of_what_is_done(tmp_path: Path) -> None:
    """The index is rewritten after every scenario, atomically: a driver killed between two leaves a valid one."""
    src = good_folder(tmp_path / "src")
    out = tmp_path / "out"
    seen: list[dict[str, int]] = []

    def watch(done: int, total: int) -> None:
        seen.append(read_index(out)["totals"])

    assert run_many(src, out_dir=out, progress=watch).ok
    assert [t["complete"] for t in seen] == [0, 1, 2, 3] and all(t["pending"] == 3 - t["complete"] for t in seen)
    assert not [p for p in out.iterdir() if p.name.endswith(".tmp")] and os.path.isfile(out / "dataset.json")


def test_detection_generate_records_through_the_batch_runner(tmp_path: Path) -> None:
    from mmusv.studies.detection.sources import generate_dataset

    spec = write(tmp_path / "tinyset.yaml", SPEC)
    ticks: list[tuple[str, int, int]] = []
    recs = generate_dataset(tmp_path / "d", spec=spec, progress=lambda *a: ticks.append(a))
    assert len(recs) == 3 and all(p.is_file() for p in recs) and ticks[-1] == ("recording", 18, 18)
    assert read_index(tmp_path / "d/recordings")["totals"]["complete"] == 3
    names = [p.parent.name for p in recs]
    before = stamps(tmp_path / "d/recordings", names)
    assert generate_dataset(tmp_path / "d", spec=spec) == recs  # a second call records nothing again
    assert stamps(tmp_path / "d/recordings", names) == before


def test_a_spec_no_candidate_meets_is_a_quota_shortfall_not_a_crash(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """No scenario met the spec: `mmusv dataset` exited 2 with "…/scenarios holds no *.yaml scenarios" (the batch
    runner's refusal of an empty folder), where the README promises exit 1 and the quota not met, as generate."""
    spec = Path(__file__).resolve().parents[2] / "scenarios/specs/impossible_port.yaml"
    out = tmp_path / "ds"
    for rerun in (False, True):
        assert main(["dataset", str(spec), "-o", str(out)]) == 1
        text = capsys.readouterr().out
        assert "quota not met: port_entry_close_2usv_huge: 0 of 5" in text, text
        assert ("kept (same spec)" in text) == rerun
        assert "nothing to convert" in text and "up to date" not in text
        doc = read_index(out / "dataset.json")
        assert doc["recordings"] == [] and doc["opv2v"]["status"] == "nothing to convert"
        assert doc["spec"]["name"] == "impossible_port"


def test_an_index_left_by_a_stop_during_the_conversion_does_not_call_it_complete(
    built: tuple[Path, Path, str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The index kept the earlier conversion's ``complete`` while ``opv2v/`` was being written again: a Ctrl-C then
    left ``"opv2v": {"status": "complete"}`` over a folder of a part of the files. It says ``converting`` until the
    conversion is done; a re-run finishes it into the same bytes."""
    from mmusv.export import conversion

    spec, done, _ = built
    out = tmp_path / "ds"
    shutil.copytree(done, out)
    shutil.rmtree(out / "opv2v")
    real = conversion.convert
    seen: list[str] = []

    def stopped(*args: object, **kwargs: object) -> object:
        seen.append(read_index(out)["opv2v"]["status"])
        raise KeyboardInterrupt

    monkeypatch.setattr(conversion, "convert", stopped)
    with pytest.raises(KeyboardInterrupt):
        build_dataset(spec, out_dir=out)
    assert seen == ["converting"] and read_index(out)["opv2v"]["status"] == "converting"
    monkeypatch.setattr(conversion, "convert", real)
    rep = build_dataset(spec, out_dir=out)
    assert rep.converted and tree(out) == tree(done)
