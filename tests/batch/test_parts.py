"""Recordings split into frame ranges: `acquire.run(frame_range=...)` records the same frames as a whole run,
the parts manifest is read as one sequence by the reader and every consumer (info, preview frames, conversion,
the detection study), an interrupted part is re-run alone, a missing part shows as missing frames."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
from mmusv.batch import run_many
from mmusv.cli import main
from mmusv.errors import ConfigError, IoError
from mmusv.export import convert
from mmusv.recording.contents import summary
from mmusv.recording.folders import find_recordings
from mmusv.recording.info import read_info
from mmusv.recording.messages import frame_messages
from mmusv.recording.parts import read_parts_manifest
from mmusv.recording.stream import FrameStream
from mmusv.studies.detection.data import read_recording
from mmusv.studies.detection.sources import resolve_dataset

from .conftest import GOOD, good_folder, stamps, tree


def frames_of(path: Path) -> list[tuple[int, dict[str, bytes]]]:
    """Every frame of a recording (an .mcap or a parts manifest): index and the raw bytes of every message."""
    return [
        (f.index, {t: m.SerializeToString() for t, m in sorted(f.messages.items())})
        for f in FrameStream(read_info(path), lambda t: True)
    ]


@pytest.fixture(scope="module")
def split(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The three good scenarios recorded as parts of 25 frames (25 + 25 + 10) on the local pool."""
    base = tmp_path_factory.mktemp("split")
    report = run_many(good_folder(base / "src"), out_dir=base / "out", jobs=2, split_frames=25)
    assert report.ok and [o.parts for o in report.outcomes] == [3, 3, 3]
    return base / "out"


def whole(reference: tuple[Path, dict[str, str]], name: str) -> Path:
    return reference[0].parent / "out" / name / f"{name}.mcap"


def test_a_frame_range_records_the_frames_of_a_whole_run(
    reference: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    src, _ = reference
    res = mmusv.run(src / "b_sea.yaml", out_dir=tmp_path, frame_range=(10, 25))
    assert res.frames_written == 15 and res.status == "complete"
    part = frames_of(tmp_path / "b_sea.mcap")
    assert [k for k, _ in part] == list(range(10, 25))
    assert part == frames_of(whole(reference, "b_sea"))[10:25]
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["first_frame"] == 10 and manifest["frames_requested"] == 15
    assert read_info(tmp_path / "b_sea.mcap").run["first_frame"] == "10"
    for bad in ({"frame_range": (5, 5)}, {"frame_range": (0, 61)}, {"frame_range": (0, 4), "frames": 4}):
        with pytest.raises(ConfigError, match="frame"):
            mmusv.run(src / "b_sea.yaml", out_dir=tmp_path / "bad", **bad)  # type: ignore[arg-type]
    assert not (tmp_path / "bad").exists()


def test_parts_read_as_one_sequence(
    split: Path, reference: tuple[Path, dict[str, str]], capsys: pytest.CaptureFixture[str]
) -> None:
    for name in GOOD:
        manifest = split / name / f"{name}.parts.json"
        info = read_info(manifest)
        assert info.run["status"] == "complete" and info.run["frames_written"] == "60" and info.has_summary
        assert [p.parent.name for p in info.parts] == ["000000-000024", "000025-000049", "000050-000059"]
        assert frames_of(manifest) == frames_of(whole(reference, name))
        s, w = summary(manifest), summary(whole(reference, name))
        assert s["topics"] == w["topics"] and s["messages"] == w["messages"] and s["complete"] and s["parts"] == 3
        assert (s["start_ns"], s["end_ns"]) == (w["start_ns"], w["end_ns"])
        got = {t: m.SerializeToString() for t, m in frame_messages(manifest, 37).items()}
        assert got == {t: m.SerializeToString() for t, m in frame_messages(whole(reference, name), 37).items()}
    assert main(["info", str(split / "a_sea/a_sea.parts.json")]) == 0
    assert "status complete, 60 frames" in capsys.readouterr().out
    assert main(["preview", str(split / "a_sea/a_sea.parts.json"), "--frame", "30"]) == 0
    picture = split / "a_sea/a_sea_frame000030_u.png"  # named after the recording, from the part holding frame 30
    assert picture.stat().st_size > 0
    picture.unlink()
    # a folder search finds the manifests, not their parts
    assert find_recordings(split) == [split / n / f"{n}.parts.json" for n in GOOD]


def test_a_frame_range_of_parts_reads_only_the_parts_it_needs(
    split: Path, reference: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    manifest = split / "b_sea/b_sea.parts.json"
    full = frames_of(whole(reference, "b_sea"))
    for rng in ((20, 30), (30, 31), (49, None)):
        stream = FrameStream(read_info(manifest), lambda t: True, frames=rng)
        got = [(f.index, {t: m.SerializeToString() for t, m in sorted(f.messages.items())}) for f in stream]
        assert got == full[rng[0] : rng[1]] and stream.report() is None, rng
    # the first part is not even opened for frames of the second: its absence goes unnoticed
    moved = tmp_path / "b_sea"
    shutil.copytree(split / "b_sea", moved)
    shutil.rmtree(moved / "parts" / "000000-000024")
    stream = FrameStream(read_info(moved / "b_sea.parts.json"), lambda t: True, frames=(30, 33))
    assert [f.index for f in stream] == [30, 31, 32] and stream.report() is None
    rep = convert(moved / "b_sea.parts.json", out_dir=tmp_path / "conv", splits=None, frames=(30, 33))
    assert rep.frames == 3 and not rep.recordings[0].skipped


def test_conversion_and_the_study_read_parts_like_the_whole_recording(
    split: Path, reference: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    ref_out = reference[0].parent / "out"
    convert(split, out_dir=tmp_path / "parts", splits=None)  # the folder: its dataset.json's recordings
    convert(ref_out, out_dir=tmp_path / "whole", splits=None)
    a, b = tree(tmp_path / "parts"), tree(tmp_path / "whole")
    assert a.keys() == b.keys()
    differ = sorted(k for k in a if a[k] != b[k])
    # only the name of the source differs (x.parts.json for x.mcap)
    assert differ == [
        "a_sea/data_protocol.yaml",
        "b_sea/data_protocol.yaml",
        "c_sea/data_protocol.yaml",
        "conversion.yaml",
    ]
    for k in differ:
        text = (tmp_path / "parts" / k).read_text().replace(".parts.json", ".mcap")
        assert text == (tmp_path / "whole" / k).read_text()
    seq_parts = read_recording(split / "a_sea/a_sea.parts.json")
    seq_whole = read_recording(whole(reference, "a_sea"))
    assert seq_parts.name == seq_whole.name == "a_sea" and len(seq_parts.frames) == 60
    for fp, fw in zip(seq_parts.frames, seq_whole.frames, strict=True):
        assert fp.frame == fw.frame and np.array_equal(fp.agents[0].points, fw.agents[0].points)
        assert np.array_equal(fp.targets, fw.targets)
    ds = resolve_dataset([split], opv2v=None, split="all")
    assert ds.sources == {n: split / n / f"{n}.parts.json" for n in GOOD}


def test_an_interrupted_part_is_run_again_alone(split: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    shutil.copytree(split, out)
    before = tree(out)
    mid = out / "b_sea/parts/000025-000049"
    (mid / "manifest.json").unlink()  # as after a worker killed mid-part
    (mid / "b_sea.mcap").rename(mid / "b_sea.mcap.partial")
    keep = stamps(out, ["a_sea", "c_sea"])
    keep |= {k: v for k, v in stamps(out, ["b_sea"]).items() if "000025-000049" not in k}
    report = run_many(split.parent / "src", out_dir=out, split_frames=25)
    assert report.summary() == "1 done, 0 failed, 2 skipped, 0 retried"
    after = stamps(out, GOOD)
    assert {k: after[k] for k in keep} == keep and tree(out) == before


def test_a_missing_part_shows_as_missing_frames(split: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    shutil.copytree(split / "c_sea", out / "c_sea")
    shutil.rmtree(out / "c_sea/parts/000025-000049")
    manifest = out / "c_sea/c_sea.parts.json"
    info = read_info(manifest)
    assert info.run["status"] == "incomplete (2 of 3 parts complete)" and not info.has_summary
    assert [k for k, _ in frames_of(manifest)] == [*range(25), *range(50, 60)]
    rep = convert(manifest, out_dir=tmp_path / "conv", splits=None)
    (r,) = rep.recordings
    assert r.frames_converted == 35 and [s["frames"] for s in r.skipped] == [[25, 49]]
    with pytest.raises(ConfigError, match="part is not recorded"):
        frame_messages(manifest, 30)


def _manifest_doc(split: Path) -> dict[str, Any]:
    doc: dict[str, Any] = json.loads((split / "a_sea/a_sea.parts.json").read_text())
    return doc


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d["parts"][1].update(first_frame=26), "parts[1]"),
        (lambda d: d.update(frames=61), "cover frames 0..59"),
        (lambda d: d["parts"][0].update(recording="../x.mcap"), "parts[0].recording"),
        (lambda d: d.update(format="other"), "not a parts manifest"),
        (lambda d: d["parts"][2].pop("frames"), "'frames' is missing"),
        (lambda d: d.update(config_hash="0" * 64), "another configuration"),
    ],
)
def test_a_bad_parts_manifest_is_named(split: Path, tmp_path: Path, change: Any, message: str) -> None:
    shutil.copytree(split / "a_sea", tmp_path / "a_sea")
    doc = _manifest_doc(split)
    change(doc)
    path = tmp_path / "a_sea/a_sea.parts.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(IoError, match=r"a_sea\.parts\.json") as exc:
        read_info(path)
    assert message in str(exc.value)
    with pytest.raises(IoError):
        read_parts_manifest(tmp_path / "nothing.parts.json")


def test_switching_layouts(split: Path, reference: tuple[Path, dict[str, str]], tmp_path: Path) -> None:
    """A recording complete in one layout is skipped whatever the split asked for; an incomplete split
    recording run whole again leaves no parts behind."""
    src, ref = reference
    out = tmp_path / "out"
    shutil.copytree(split, out)
    assert run_many(src, out_dir=out).summary() == "0 done, 0 failed, 3 skipped, 0 retried"
    (out / "a_sea/parts/000050-000059/manifest.json").unlink()
    report = run_many(src, out_dir=out)
    assert report.summary() == "1 done, 0 failed, 2 skipped, 0 retried"
    assert sorted(p.name for p in (out / "a_sea").iterdir()) == [
        "a_sea.mcap",
        "manifest.json",
        "scenario.yaml",
        "tables",
    ]
    assert {k: v for k, v in tree(out).items() if k.startswith("a_sea/")} == {
        k: v for k, v in ref.items() if k.startswith("a_sea/")
    }
    # nor the parts' task files (`.mmusv/a_sea@000000-000049.task`, ... stayed beside `a_sea.task`)
    assert sorted(p.name for p in (out / ".mmusv").glob("a_sea*")) == ["a_sea.task"]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        # read as first_frame 0, 1 and 2 (int() of a float, true/false, a text): a wrong manifest taken, or a
        # message that showed another value than the file's
        (lambda d: d["parts"][0].update(first_frame=0.5), "parts[0].first_frame = 0.5: must be a whole number"),
        (lambda d: d["parts"][0].update(first_frame=True), "parts[0].first_frame = True: must be a whole number"),
        (lambda d: d["parts"][1].update(first_frame="2"), "parts[1].first_frame = '2': must be a whole number"),
        # "invalid field value (cannot convert float NaN to integer)": no field named
        (lambda d: d.update(frames=float("nan")), "frames = nan: must be a whole number"),
        (lambda d: d.update(parts={"a": 1}), "parts = {'a': 1}: must be a JSON list, not dict"),
        (lambda d: d.update(parts=[[0, 2]]), "parts[0] = [0, 2]: must be a JSON object"),
        # None and 5 were taken as the texts 'None' and '5'
        (lambda d: d.update(scenario=None), "scenario = None: must be a string, not NoneType"),
        (lambda d: d["parts"][0].update(recording=5), "parts[0].recording = 5: must be a string, not int"),
    ],
)
def test_a_parts_manifest_field_of_the_wrong_type_is_named(tmp_path: Path, change: Any, message: str) -> None:
    doc: dict[str, Any] = {
        "format": "mmusv.parts",
        "version": 1,
        "scenario": "s",
        "config_hash": "0" * 64,
        "frames": 3,
        "parts": [
            {"first_frame": 0, "frames": 2, "recording": "parts/000000-000001/s.mcap"},
            {"first_frame": 2, "frames": 1, "recording": "parts/000002-000002/s.mcap"},
        ],
    }
    path = tmp_path / "s.parts.json"
    path.write_text(json.dumps(doc))
    assert read_parts_manifest(path).frames == 3
    change(doc)
    path.write_text(json.dumps(doc))
    with pytest.raises(IoError) as exc:
        read_parts_manifest(path)
    assert str(exc.value).startswith(f"{path}: ") and message in str(exc.value), str(exc.value)
