"""Damaged and missing inputs: every reader of a recording gives a clean one-line error naming the file, or
recovers every complete frame byte for byte and says which frames are missing and where the damage is."""

from __future__ import annotations

import random
from pathlib import Path

import pytest
from mcap_rechunk import rechunk
from mmusv.errors import IoError, MmusvError

from .conftest import api_readers, check_against, chunk_spans, cli_main, frames_of


def _bad_inputs(tmp: Path, good: Path) -> dict[str, Path]:
    tmp.mkdir(parents=True, exist_ok=True)
    (tmp / "empty.mcap").write_bytes(b"")
    (tmp / "text.mcap").write_text("not a recording\n", encoding="utf-8")
    data = bytearray(good.read_bytes())
    data[3] ^= 0x01  # wrong magic
    (tmp / "magic.mcap").write_bytes(bytes(data))
    (tmp / "folder.mcap").mkdir()
    return {
        "missing": tmp / "nonexistent.mcap",
        "directory": tmp / "folder.mcap",
        "empty": tmp / "empty.mcap",
        "not mcap": tmp / "text.mcap",
        "wrong magic": tmp / "magic.mcap",
    }


def test_missing_empty_and_foreign_files_are_one_line_errors(small: Path, tmp_path: Path) -> None:
    for what, path in _bad_inputs(tmp_path / "in", small / "tiny.mcap").items():
        for args in (
            ("info", str(path)),
            ("preview", str(path), "-o", str(tmp_path / "p.png")),
            ("convert", str(path), "-o", str(tmp_path / "c"), "--no-progress", "--no-split"),
            ("recover", str(path)),
        ):
            code, _out, err = cli_main(*args)
            assert code == 2, (what, args, err)
            assert err.startswith("mmusv: error: ") and err.count("\n") == 1 and path.name in err, (what, args, err)
        results = api_readers(path)
        for name, res in results.items():
            assert isinstance(res, MmusvError) and path.name in str(res), (what, name, res)
        from mmusv.studies.detection.data import read_recording

        with pytest.raises(MmusvError, match=path.name):
            read_recording(path)


def test_truncation_at_random_byte_offsets(chunky: tuple[Path, dict[int, dict[str, bytes]]], tmp_path: Path) -> None:
    src, reference = chunky
    data = src.read_bytes()
    rng = random.Random(30)
    offsets = [*sorted(rng.randrange(9, len(data)) for _ in range(6)), len(data) // 2]
    for i, cut in enumerate(offsets):
        path = tmp_path / f"cut{i}.mcap.partial"
        path.write_bytes(data[:cut])
        results = api_readers(path)
        check_against(results, reference)
        got = results["frames"]
        if isinstance(got, MmusvError):  # cut inside the metadata: nothing to read, said so
            assert isinstance(got, IoError) and path.name in str(got)
            continue
        frames, stream = got
        assert "the file is truncated" in (stream.truncated or ""), stream.truncated
        # every frame whose chunk ended before the cut is recovered
        whole = [s for s in chunk_spans(src) if s[1] <= cut]
        assert len(frames) >= len(whole) - 2, (cut, len(frames), len(whole))
        code, out, err = cli_main("info", str(path))
        assert code == (0 if frames else 1) and "Traceback" not in err, (cut, len(frames), err)  # 1: no frame reads
        assert "mmusv: warning:" in out and "truncated" in out
        if len(frames) < 12:
            assert f"{len(frames)} of 12 frames" in out and "missing" in out, out


def test_a_bit_flip_in_a_chunk_skips_that_chunk_and_keeps_the_frames_after_it(
    chunky: tuple[Path, dict[int, dict[str, bytes]]], tmp_path: Path
) -> None:
    src, reference = chunky
    spans = chunk_spans(src)
    data = bytearray(src.read_bytes())
    start, end = spans[len(spans) // 2]
    for at in (end - 40, end - 400):  # inside the compressed records of one chunk
        data[at] ^= 0x21
    bad = tmp_path / "tiny.mcap"
    bad.write_bytes(bytes(data))
    frames, stream = frames_of(bad)
    for k, msgs in frames.items():
        assert msgs == reference[k]
    lost = sorted(set(reference) - set(frames))
    assert lost and max(frames) == 11 and min(frames) == 0, lost  # frames on both sides of the damage are kept
    assert f"bytes {start}..{end}" in (stream.truncated or "") and "damaged chunk" in (stream.truncated or "")
    assert stream.missing() == lost
    code, out, err = cli_main("info", str(bad))
    assert code == 0 and "damaged" in out and f"{len(frames)} of 12" in out, out
    # conversion writes the intact frames only, identical to those of the intact recording
    assert cli_main("convert", str(src), "-o", str(tmp_path / "ref"), "--no-progress", "--no-split")[0] == 0
    code, out, err = cli_main("convert", str(bad), "-o", str(tmp_path / "got"), "--no-progress", "--no-split")
    assert code in (0, 1) and "Traceback" not in err
    got = {p.relative_to(tmp_path / "got"): p.read_bytes() for p in (tmp_path / "got").rglob("*.pcd")}
    ref = {p.relative_to(tmp_path / "ref"): p.read_bytes() for p in (tmp_path / "ref").rglob("*.pcd")}
    assert got and len(got) == len(frames) and all(ref[name] == b for name, b in got.items())


def test_damage_in_the_real_recorder_output(small: Path, tmp_path: Path) -> None:
    """The recorder's own layout (one large chunk, then indexes and the summary): a flipped byte in the chunk
    loses its frames and is reported; a flipped byte in the summary loses nothing."""
    data = bytearray((small / "tiny.mcap").read_bytes())
    ((start, end),) = chunk_spans(small / "tiny.mcap")
    in_chunk = bytearray(data)
    in_chunk[(start + end) // 2] ^= 0x08
    path = tmp_path / "chunk.mcap"
    path.write_bytes(bytes(in_chunk))
    res = api_readers(path)
    frames, stream = res["frames"]
    assert frames == {} and stream.missing() == list(range(12)) and "damaged chunk" in (stream.truncated or "")
    assert isinstance(res["frame_messages"], MmusvError)
    s = res["summary"]
    assert not s["complete"] and s["damage"] and s["frames"]["read"] == 0
    in_summary = bytearray(data)
    in_summary[len(data) - 60] ^= 0x08
    path = tmp_path / "summary.mcap"
    path.write_bytes(bytes(in_summary))
    reference, _ = frames_of(small / "tiny.mcap")
    res = api_readers(path)
    check_against(res, reference)
    assert sorted(res["frames"][0]) == list(range(12))


def test_the_batch_index_and_the_editor_open_damaged_files_cleanly(small: Path, tmp_path: Path) -> None:
    """A damaged ``dataset.json`` (the batch index that ``convert`` and the studies read) and a damaged scenario
    file opened in the editor: one error naming the file."""
    import warnings

    from mmusv.batch.index import dataset_recordings

    (tmp_path / "out").mkdir()
    (tmp_path / "out/dataset.json").write_bytes(b'{"format": "mmusv.dataset", "version": 1, "recordings": [\x00')
    with pytest.raises(IoError, match=r"dataset\.json"):
        dataset_recordings(tmp_path / "out")
    code, _out, err = cli_main("convert", str(tmp_path / "out"), "-o", str(tmp_path / "c"), "--no-progress")
    assert code == 2 and "dataset.json" in err and err.count("\n") == 1, err
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
        from fastapi.testclient import TestClient
    from mmusv.editor.app import create_app

    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "bad.yaml").write_bytes((small / "tiny.mcap").read_bytes()[:3000])  # binary garbage
    (folder / "cut.yaml").write_text((small / "scenario.yaml").read_text()[:200], encoding="utf-8")
    client = TestClient(create_app(folder))
    for name in ("bad.yaml", "cut.yaml"):
        r = client.get(f"/api/files/{name}")
        assert r.status_code in (200, 422) and "Traceback" not in r.text, r.text
        if r.status_code == 422:
            assert name in r.json()["error"]
        else:
            assert r.json()["valid"] is False


def _with_run_metadata(src: Path, dst: Path, **changes: str) -> Path:
    """``src`` copied record by record with ``changes`` made to its ``run`` metadata."""
    rechunk(src, dst, 4 * 1024 * 1024, run_changes=changes)
    return dst


@pytest.mark.parametrize("value", ["x", "-3", "1e3"])
def test_a_run_count_that_is_not_a_whole_number_is_named(small: Path, tmp_path: Path, value: str) -> None:
    """``frames_written = "x"`` in the run metadata was a ValueError traceback in the middle of a conversion (after
    its output folder was made); ``"-3"`` was taken."""
    from mmusv.recording.info import read_info

    bad = _with_run_metadata(small / "tiny.mcap", tmp_path / "tiny.mcap", frames_written=value)
    with pytest.raises(IoError) as err:
        read_info(bad)
    said = f"{bad}: damaged run metadata: frames_written = '{value}', must be a whole number of frames in 0..10,000,000"
    assert str(err.value) == said
    code, _out, cli_err = cli_main("convert", str(bad), "--to", "opv2v", "-o", str(tmp_path / "conv"), "--no-progress")
    assert code == 2 and cli_err == f"mmusv: error: {said}\n", cli_err
    assert not (tmp_path / "conv").exists()
    # info read it as another program's MCAP file "(no scenario/sensors metadata)", without saying what is damaged
    code, out, _err = cli_main("info", str(bad))
    text = " ".join(out.split())
    assert code == 0 and "its mmusv metadata cannot be read: its messages only" in text, text
    assert f"mmusv: warning: {said}" in text and "no scenario/sensors metadata" not in text, text
