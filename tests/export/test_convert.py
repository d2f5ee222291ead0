"""The conversion job: bad input, overwrite, determinism, truncated recordings, splits and the command line."""

from __future__ import annotations

import argparse
import hashlib
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml
from mcap_rechunk import rechunk
from mmusv.errors import ConfigError, IoError, MmusvError
from mmusv.export import cli as export_cli
from mmusv.export import convert


def tree(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def parse(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="mmusv")
    export_cli.add_parser(p.add_subparsers(dest="command"))
    return p.parse_args(["convert", *argv])


# ---------------------------------------------------------------------------------------------- bad input


def test_missing_and_non_mcap_inputs(tmp_path: Path) -> None:
    with pytest.raises(IoError, match="does not exist"):
        convert(tmp_path / "nope.mcap", out_dir=tmp_path / "o")
    junk = tmp_path / "junk.mcap"
    junk.write_text("not an mcap\n")
    with pytest.raises(IoError, match="not an MCAP file"):
        convert(junk, out_dir=tmp_path / "o")
    with pytest.raises(IoError, match="not a file"):
        convert(tmp_path, out_dir=tmp_path / "o")
    assert not (tmp_path / "o").exists()  # nothing written on bad input


def test_bad_options(coop_rec: Path, tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="unknown target 'pascal'"):
        convert(coop_rec, to="pascal", out_dir=tmp_path / "o")
    with pytest.raises(ConfigError, match="unknown extra"):
        convert(coop_rec, out_dir=tmp_path / "o", extras=("depth", "lidar2"))
    with pytest.raises(ConfigError, match="eval_range_m"):
        convert(coop_rec, out_dir=tmp_path / "o", eval_range_m=-5)
    with pytest.raises(ConfigError, match="split"):
        convert(coop_rec, out_dir=tmp_path / "o", splits=(0.5, 0.5))
    with pytest.raises(ConfigError, match="same scenario configuration"):
        convert([coop_rec, coop_rec], out_dir=tmp_path / "o")
    # extras for a format that writes none: COCO exited 0 and wrote no depth (conversion.yaml listed it)
    for to in ("coco", "yolo", "mastr", "semantickitti", "mot", "ros2"):
        with pytest.raises(ConfigError, match=rf"extras = 'depth': only the OPV2V, .* not to = '{to}'"):
            convert(coop_rec, to=to, out_dir=tmp_path / "o", extras="depth")
    assert not (tmp_path / "o").exists()


def test_cli_errors_are_one_line(coop_rec: Path, tmp_path: Path) -> None:
    for argv, kind in (
        ([str(coop_rec), "--to", "pascal", "-o", str(tmp_path / "o")], ConfigError),
        ([str(tmp_path / "missing.mcap"), "-o", str(tmp_path / "o")], IoError),
        ([str(coop_rec), "-o", str(tmp_path / "o"), "--extras", "depth,nope"], ConfigError),
        ([str(coop_rec), "-o", str(tmp_path / "o"), "--split", "1,2"], ConfigError),
    ):
        with pytest.raises(kind) as exc:
            export_cli.run(parse([*argv, "--no-progress"]))
        assert isinstance(exc.value, MmusvError) and "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match=r"^-o/--output is empty"):  # it named the API's out_dir
        export_cli.run(parse([str(coop_rec), "-o", "", "--no-progress"]))


def test_cli_converts(coop_rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "o"
    assert export_cli.run(parse([str(coop_rec), "-o", str(out), "--no-split", "--range", "150", "--extras", ""])) == 0
    text = capsys.readouterr().out
    assert "export_coop.mcap -> export_coop: 3 frames" in text
    doc = yaml.safe_load((out / "conversion.yaml").read_text())
    assert doc["status"] == "complete" and doc["options"]["eval_range_m"] == 150.0 and doc["options"]["extras"] == []
    assert sorted(p.name for p in (out / "export_coop").iterdir()) == ["1000", "1002", "data_protocol.yaml"]


# ---------------------------------------------------------------------------------------------- overwrite, determinism


def test_existing_output_refused_without_overwrite(coop_rec: Path, tmp_path: Path) -> None:
    out = tmp_path / "o"
    convert(coop_rec, out_dir=out, splits=None, extras=())
    with pytest.raises(IoError, match="already exists"):
        convert(coop_rec, out_dir=out, splits=None, extras=())
    rep = convert(coop_rec, out_dir=out, splits=None, extras=(), overwrite=True)
    assert rep.frames == 3
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "precious.txt").write_text("keep me")
    with pytest.raises(IoError, match="refusing to delete"):
        convert(coop_rec, out_dir=foreign, overwrite=True)
    # without --overwrite it is not told to pass it (it said so, then refused when it was)
    with pytest.raises(IoError) as err:
        convert(coop_rec, out_dir=foreign)
    assert "holds no conversion.yaml of a previous conversion; choose another folder" in str(err.value)
    assert "overwrite" not in str(err.value)
    assert (foreign / "precious.txt").read_text() == "keep me"


def test_overwrite_never_deletes_the_recording_being_converted(coop_rec: Path, tmp_path: Path) -> None:
    # A recording copied into an earlier conversion's folder, converted into that folder with --overwrite: the
    # folder used to be emptied first, the input with it.
    out = tmp_path / "conv"
    convert(coop_rec, out_dir=out, splits=None, extras=())
    inside = out / "in.mcap"
    shutil.copyfile(coop_rec, inside)
    for target in (out, out / "deeper" / ".."):
        with pytest.raises(IoError, match="being converted"):
            convert(inside, out_dir=target, splits=None, extras=(), overwrite=True)
        assert inside.stat().st_size == coop_rec.stat().st_size


def test_overwrite_replaces_only_what_the_previous_conversion_wrote(coop_rec: Path, tmp_path: Path) -> None:
    # --overwrite deleted any folder with a conversion.yaml at its top: recordings below it, a user's notes
    out = tmp_path / "o"
    convert(coop_rec, out_dir=out, splits=None, extras=())
    doc = yaml.safe_load((out / "conversion.yaml").read_text())
    assert doc["contents"] == {
        "entries": ["export_coop", "opencood"],
        "files": sum(1 for p in out.rglob("*") if p.is_file()) - 1,
    }
    run = out / "runs" / "a"  # a recording's run folder (copied), its tables included
    run.mkdir(parents=True)
    shutil.copyfile(coop_rec, run / "a.mcap")
    (run / "manifest.json").write_text("{}")
    before = tree(out)
    with pytest.raises(IoError, match=r"holds .*a\.mcap, .*manifest\.json, which no conversion writes"):
        convert(coop_rec, out_dir=out, splits=None, extras=(), overwrite=True)
    assert tree(out) == before
    shutil.rmtree(out / "runs")
    for name in ("notes.txt", "export_coop/notes.txt"):  # a file at the top, a file inside the layout
        (out / name).write_text("mine")
        before = tree(out)
        with pytest.raises(IoError, match="refusing to delete what no conversion wrote"):
            convert(coop_rec, out_dir=out, splits=None, extras=(), overwrite=True)
        assert tree(out) == before
        (out / name).unlink()
    for name, data in (("b.parquet", b"PAR1"), ("c.mcap.partial", b""), ("d.parts.json", b"{}")):
        (out / "export_coop" / name).write_bytes(data)
        with pytest.raises(IoError, match="which no conversion writes"):
            convert(coop_rec, out_dir=out, splits=None, extras=(), overwrite=True)
        (out / "export_coop" / name).unlink()
    assert convert(coop_rec, out_dir=out, splits=None, extras=(), overwrite=True).frames == 3
    # a conversion that did not finish says nothing of its files: a recording below it is still refused
    (out / "conversion.yaml").write_text("status: interrupted\n")
    (out / "x.mcap").write_bytes(coop_rec.read_bytes()[:4096])
    with pytest.raises(IoError, match="which no conversion writes"):
        convert(coop_rec, out_dir=out, splits=None, extras=(), overwrite=True)
    (out / "x.mcap").unlink()
    assert convert(coop_rec, out_dir=out, splits=None, extras=(), overwrite=True).frames == 3


def test_a_killed_run_s_missing_frames_are_those_it_set_out_to_write(short_rec: Path, tmp_path: Path) -> None:
    # a run of 2 of the scenario's 3 frames, killed (no run metadata): its manifest says 2; the conversion
    # listed frames 0..2 of the scenario as skipped, one of them never asked for
    small = tmp_path / "export_short.mcap"
    rechunk(short_rec, small, 64 * 1024)
    data = small.read_bytes()
    cut = tmp_path / "export_short.mcap.partial"
    cut.write_bytes(data[: int(len(data) * 0.7)])  # inside frame 1
    rep = convert(cut, out_dir=tmp_path / "o", splits=None, extras=())
    assert rep.frames == 1
    skipped = rep.recordings[0].skipped
    assert [s["frames"] for s in skipped] == [[1, 1]], skipped
    assert "3 frames" not in skipped[0]["reason"]


@pytest.mark.parametrize("to", ["opv2v", "kitti"])
def test_deterministic(coop_rec: Path, tmp_path: Path, to: str) -> None:
    a = convert(coop_rec, to=to, out_dir=tmp_path / "a", splits=None)
    b = convert(coop_rec, to=to, out_dir=tmp_path / "b", splits=None)
    ta, tb = tree(tmp_path / "a"), tree(tmp_path / "b")
    assert ta == tb and len(ta) > 50
    assert a.bytes == b.bytes == sum((tmp_path / "a" / f).stat().st_size for f in ta)
    assert a.files == len(ta)


# ---------------------------------------------------------------------------------------------- truncated recordings


def test_run_cut_by_frames_converts_what_it_asked_for(short_rec: Path, tmp_path: Path) -> None:
    """A run limited to its first 2 of 3 configured frames (--frames 2) is complete: no frame counts as skipped
    (the note used to count the configured frames, not the frames the run set out to write)."""
    rep = convert(short_rec, out_dir=tmp_path / "o", splits=None, extras=())
    assert rep.frames == 2
    assert rep.skipped == []
    assert sorted(p.stem for p in (tmp_path / "o" / "export_short" / "1000").glob("*.pcd")) == ["000000", "000001"]
    assert "skipped" not in "\n".join(rep.lines())
    doc = yaml.safe_load((tmp_path / "o" / "conversion.yaml").read_text())
    assert doc["recordings"][0]["skipped"] == []


def test_a_frame_range_beyond_every_recording_is_refused_before_writing(
    coop_rec: Path, short_rec: Path, tmp_path: Path
) -> None:
    """``--frames 5:9`` of a 3-frame recording was a 'complete' conversion of nothing ("no complete frame"); it is a
    ConfigError naming what the recording holds, and no output folder is made."""
    with pytest.raises(ConfigError, match=r"frames = 5:9: none is in .*export_coop\.mcap, which holds frames 0\.\.2"):
        convert(coop_rec, out_dir=tmp_path / "o", to="kitti", frames="5:9")
    assert not (tmp_path / "o").exists()
    # beside a recording that holds some of the range, the other is noted and left out
    rep = convert([coop_rec, short_rec], out_dir=tmp_path / "two", to="kitti", frames="2:3", splits=None)
    notes = {r.folder: " ".join(r.notes) for r in rep.recordings}
    assert rep.frames == 1 and "which holds frames 0..1: nothing converted" in notes["export_short"], notes
    assert not (tmp_path / "two" / "export_short").exists()


def test_a_frame_range_past_an_interrupted_run_s_last_frame_is_refused_before_writing(tmp_path: Path) -> None:
    """The malformed-input review's: ``--frames 20:30`` of a run interrupted after 10 of its 50 frames wrote a
    conversion of nothing and exited 1, and ``--frames 150:160`` was refused as past "frames 0..49", frames the run
    never wrote. Both are refused before anything is written, naming the frames it holds and why."""
    from mmusv.acquire import run
    from tiny_scenario import lidar_scenario

    def stop(done: int, _total: int) -> None:
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run(lidar_scenario("stopped", frames=6), out_dir=tmp_path / "run", progress=stop)
    rec = tmp_path / "run" / "stopped.mcap"
    for frames in ("3:5", "8:9"):
        with pytest.raises(ConfigError) as err:
            convert(rec, out_dir=tmp_path / "o", to="semantickitti", frames=frames, splits=None)
        assert (
            f"frames = {frames}: none is in {rec}, which holds frames 0..1 (its run is interrupted: 2 of the 6 "
            "frames it set out to write)" in str(err.value)
        ), err.value
        assert not (tmp_path / "o").exists()
    rep = convert(rec, out_dir=tmp_path / "o", to="semantickitti", frames="1:5", splits=None)
    assert rep.frames == 1


def test_a_frame_range_reaching_past_the_recording_is_noted(coop_rec: Path, tmp_path: Path) -> None:
    """``--frames 1:10`` of a 3-frame recording converted frames 1 and 2 without a word about 3..9; the report says
    which indices of the range the recording does not hold (a range inside it, or open-ended, says nothing)."""
    rep = convert(coop_rec, out_dir=tmp_path / "o", to="kitti", frames="1:10", splits=None)
    (r,) = rep.recordings
    assert r.frames_converted == 2
    said = [n for n in r.notes if "reach past" in n]
    assert said == ["frames 1:10 reach past the recording, which holds frames 0..2: 3..9 not in it"], r.notes
    for frames in ("1:3", "1:"):
        rep = convert(coop_rec, out_dir=tmp_path / frames.replace(":", "_"), to="kitti", frames=frames, splits=None)
        assert not [n for n in rep.recordings[0].notes if "reach past" in n], rep.recordings[0].notes


def test_interrupted_run(tmp_path: Path, make_coop: Callable[..., dict[str, Any]]) -> None:
    from mmusv.acquire import recording_path, run

    def stop(done: int, total: int) -> None:
        if done == 2:
            raise KeyboardInterrupt

    cfg = make_coop(name="export_interrupted")
    with pytest.raises(KeyboardInterrupt):
        run(cfg, out_dir=tmp_path / "in", progress=stop)
    from mmusv.config import load_scenario

    rec = recording_path(tmp_path / "in", load_scenario(cfg))
    if not rec.exists():
        rec = rec.with_name(rec.name + ".partial")
    rep = convert(rec, out_dir=tmp_path / "o", splits=None, extras=())
    assert rep.frames == 2
    assert rep.skipped[0]["frames"] == [2, 2] and "interrupted" in rep.skipped[0]["reason"]


def test_truncated_partial_file(coop_rec: Path, tmp_path: Path) -> None:
    small = tmp_path / "export_coop.mcap"
    rechunk(coop_rec, small, 64 * 1024)
    full = convert(small, out_dir=tmp_path / "full", splits=None)
    ref = convert(coop_rec, out_dir=tmp_path / "ref", splits=None)
    assert tree(tmp_path / "full") == tree(tmp_path / "ref") and full.frames == ref.frames == 3
    data = small.read_bytes()
    cut = tmp_path / "export_coop.mcap.partial"
    cut.write_bytes(data[: int(len(data) * 0.55)])  # a killed writer: no summary, last chunk cut in the middle
    rep = convert(cut, out_dir=tmp_path / "cut", splits=None)
    assert 1 <= rep.frames < 3
    done = rep.recordings[0]
    skipped = {k for s in done.skipped for k in range(s["frames"][0], s["frames"][1] + 1)}
    assert skipped == set(range(rep.frames, 3))
    reasons = " ".join(s["reason"] for s in done.skipped)
    assert "the file is truncated" in reasons
    assert "incomplete: missing" in reasons or "not in the recording" in reasons
    # the converted frames are byte-identical to those of the complete recording
    t_cut, t_ref = tree(tmp_path / "cut"), tree(tmp_path / "ref")
    for name, digest in t_cut.items():
        if name.endswith((".pcd", ".png")) or (name.endswith(".yaml") and "/100" in name):
            assert t_ref[name] == digest, name
    stamps = {c: sorted(p.stem for p in (tmp_path / "cut" / "export_coop" / c).glob("*.pcd")) for c in ("1000", "1002")}
    assert stamps["1000"] == stamps["1002"] == [f"{k:06d}" for k in range(rep.frames)]


def test_cut_before_any_frame(coop_rec: Path, tmp_path: Path) -> None:
    from mcap.records import Chunk
    from mcap.stream_reader import StreamReader

    with coop_rec.open("rb") as f:  # the start of the first chunk: metadata read, no message complete
        chunk, end = next((r, f.tell()) for r in StreamReader(f, emit_chunks=True).records if isinstance(r, Chunk))
    start = end - (9 + 8 + 8 + 8 + 4 + 4 + len(chunk.compression) + 8 + len(chunk.data))
    cut = tmp_path / "x.mcap.partial"
    cut.write_bytes(coop_rec.read_bytes()[: start + 60])
    # a new folder is left as it was: it was a conversion.yaml saying "complete" over no frame (exit status 1)
    with pytest.raises(IoError, match=r"nothing converted: no complete frame in .*x\.mcap\.partial; nothing written"):
        convert(cut, out_dir=tmp_path / "o", splits=None)
    assert not (tmp_path / "o").exists()
    (tmp_path / "empty").mkdir()
    with pytest.raises(IoError, match="nothing written"):
        export_cli.run(parse([str(cut), "-o", str(tmp_path / "empty"), "--no-progress"]))
    assert list((tmp_path / "empty").iterdir()) == []
    # over a good conversion, --overwrite that converts nothing keeps it (it used to replace it with an empty one)
    good = convert(coop_rec, out_dir=tmp_path / "good", splits=None)
    before = tree(tmp_path / "good")
    with pytest.raises(IoError, match=r"nothing converted: no complete frame in .*x\.mcap\.partial; .*good keeps"):
        convert(cut, out_dir=tmp_path / "good", splits=None, overwrite=True)
    assert good.frames == 3 and tree(tmp_path / "good") == before
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []  # no staging folder left


# ---------------------------------------------------------------------------------------------- splits


def test_splits_by_sequence(many_recs: list[Path], tmp_path: Path) -> None:
    rep = convert(many_recs, out_dir=tmp_path / "a", splits=(0.6, 0.2, 0.2), seed=3, extras=())
    where = {r.folder: r.split or "" for r in rep.recordings}
    assert sorted(where.values()) == ["test", "train", "train", "train", "validate"]
    for name, split in where.items():
        assert (tmp_path / "a" / split / name / "1000").is_dir()
        assert [s for s in ("train", "validate", "test") if (tmp_path / "a" / s / name).exists()] == [split]
    again = convert(list(reversed(many_recs)), out_dir=tmp_path / "b", splits=(0.6, 0.2, 0.2), seed=3, extras=())
    assert {r.folder: r.split or "" for r in again.recordings} == where
    assert tree(tmp_path / "a") == tree(tmp_path / "b")
    other = convert(many_recs, out_dir=tmp_path / "c", splits="0.6,0.2,0.2", seed=4, extras=())
    assert sorted(r.split or "" for r in other.recordings) == sorted(where.values())
    doc = yaml.safe_load((tmp_path / "a" / "conversion.yaml").read_text())
    assert {r["folder"]: r["split"] for r in doc["recordings"]} == where
    assert doc["options"]["seed"] == 3


def test_two_conversions_into_one_folder_at_once(coop_rec: Path, tmp_path: Path) -> None:
    """Two conversions into the same folder at once (threads here; processes alike): the second is refused, naming
    the folder, and the folder holds the first's conversion whole. Before, both wrote into one staging folder:
    one came back 'complete' with files missing, the other with a bare FileNotFoundError (found by the
    concurrency round)."""
    import threading

    convert(coop_rec, to="kitti", out_dir=tmp_path / "ref")
    out = tmp_path / "out"
    convert(coop_rec, to="kitti", out_dir=out)  # a previous conversion, replaced by both below
    results: list[object] = []
    start = threading.Barrier(2)

    def again() -> None:
        start.wait()
        try:
            results.append(convert(coop_rec, to="kitti", out_dir=out, overwrite=True))
        except IoError as exc:
            results.append(exc)

    threads = [threading.Thread(target=again) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    refused = [r for r in results if isinstance(r, IoError)]
    assert len(results) == 2 and len(refused) <= 1, results
    for r in refused:
        assert "is being written by another mmusv convert" in str(r), r
    assert tree(out) == tree(tmp_path / "ref")


def test_frames_lost_to_damage_in_a_complete_run_are_said_lost_not_absent(coop_rec: Path, tmp_path: Path) -> None:
    """A damaged chunk of a finished run: its frames were said "not in the recording (run complete: 3 of 3 frames
    written)", which the run says they are."""
    small = tmp_path / "export_coop.mcap"
    rechunk(coop_rec, small, 64 * 1024)
    data = bytearray(small.read_bytes())
    at = len(data) // 2
    data[at : at + 64] = bytes(b ^ 0xFF for b in data[at : at + 64])
    small.write_bytes(bytes(data))
    rep = convert(small, out_dir=tmp_path / "o", splits=None, extras=())
    skipped = rep.recordings[0].skipped
    assert 0 < rep.frames < 3 and skipped, skipped
    lost = [s for s in skipped if s["reason"].startswith("lost from the recording (run complete: 3 of 3 frames")]
    assert lost and not [s for s in skipped if "not in the recording" in s["reason"]], skipped


def test_splits_that_get_no_recording_are_said(coop_rec: Path, tmp_path: Path) -> None:
    """One recording split 0.7/0.15/0.15 goes to train alone (a split takes whole recordings): nothing said so, and
    YOLO's data.yaml then validates on the training images."""
    rep = convert(coop_rec, to="yolo", out_dir=tmp_path / "y", box="projected")
    lines = rep.lines()
    assert lines[0].endswith("-> train/export_coop: 3 frames"), lines
    assert (
        "note: validate and test hold no recording (a split takes whole recordings, and 1 recording was given); "
        "data.yaml's val is the train images"
    ) in lines, lines
    unsplit = convert(coop_rec, to="yolo", out_dir=tmp_path / "n", box="projected", splits=None)
    assert not any("hold no recording" in line for line in unsplit.lines())


# ---------------------------------------------------------------------------------------------- a frame twice


def _frame_twice(src: Path, dst: Path, *, frame: int) -> Path:
    """``dst``: ``src`` with every message of its ``frame``-th frame (by log time) written again after the last frame,
    as a recording that holds a frame twice (a run resumed over frames it had written) has it."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer
    from mcap_rechunk import write_records

    with src.open("rb") as f:
        reader = make_reader(f)
        meta = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
        msgs = list(reader.iter_messages())
    again = sorted({m.log_time for _, _, m in msgs})[frame]
    dst.mkdir(parents=True)
    out = dst / src.name
    with out.open("wb") as g:
        w = Writer(g, compression=CompressionType.NONE)
        write_records(w, meta, msgs + [t for t in msgs if t[2].log_time == again])
        w.finish()  # type: ignore[no-untyped-call]
    return out


@pytest.mark.parametrize("to", ["coco", "semantickitti", "ros2"])
def test_a_frame_recorded_twice_is_converted_once(coop_rec: Path, tmp_path: Path, to: str) -> None:
    """A recording holding frame 1 twice converts to what the recording with it once does, file for file: its first
    copy, once (COCO listed the image twice, with its annotations, SemanticKITTI added a fourth scan, the bag held
    every message of the frame twice), and ``conversion.yaml`` counts 3 frames converted, not 4."""
    twice = _frame_twice(coop_rec, tmp_path / "twice", frame=1)
    once = convert(coop_rec, to=to, out_dir=tmp_path / "once", splits=None)
    got = convert(twice, to=to, out_dir=tmp_path / "got", splits=None)
    a, b = tree(tmp_path / "once"), tree(tmp_path / "got")
    assert a.pop("conversion.yaml") and b.pop("conversion.yaml")
    if to == "ros2":  # the bag's own metadata name its file's size and chunk layout alike
        a = {k: v for k, v in a.items() if not k.endswith("metadata.yaml")}
        b = {k: v for k, v in b.items() if not k.endswith("metadata.yaml")}
    assert a == b
    assert once.frames == 3 and got.frames == 3
    assert any("frames [1] appear more than once" in n for r in got.recordings for n in r.notes)
    doc = yaml.safe_load((tmp_path / "got" / "conversion.yaml").read_text())
    assert doc["frames_converted"] == 3 and doc["recordings"][0]["skipped"] == []
