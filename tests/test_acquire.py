"""The main job end to end: `mmusv.run` / `mmusv run` into MCAP + Parquet, read back with the official readers."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import polars as pl
import pytest
import yaml
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
from mmusv.acquire import run
from mmusv.cli import main
from mmusv.recording import decode_image, decode_point_cloud

ROOT = Path(__file__).resolve().parents[1]


def small_scenario(frames: int = 3) -> dict[str, Any]:
    """The bundled port scenario shrunk for tests: 2 USVs, small images, short radar."""
    sc = yaml.safe_load((ROOT / "scenarios/port_entry.yaml").read_text())
    sc["acquisition"]["frames"] = frames
    sc["vessels"] = [v for v in sc["vessels"] if v["id"] != "usv_3"]
    sc["rigs"] = {
        "usv_standard": {
            "lidar": {"channels": 16, "points_per_second": 16 * 360 * 5},
            "radar": {"range_m": 1000, "azimuth_bins": 256, "rays_el": 8, "ppi_size_px": 64},
            "cameras": [
                {"name": "front", "resolution": [64, 48], "mount": {"point": "camera_front"}},
                {
                    "name": "rear",
                    "resolution": [64, 48],
                    "mount": {"point": "camera_rear"},
                    "outputs": ["rgb", "semantic"],
                },
            ],
            "top_view": {"resolution": [64, 64], "metres_per_pixel": 1.0},
        }
    }
    return sc


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    out = tmp_path_factory.mktemp("run")
    res = run(small_scenario(), out_dir=out)
    return out, res


def _messages(path: Path) -> list[tuple[str, int, Any, Any]]:
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [(c.topic, m.log_time, m, d) for _s, c, m, d in reader.iter_decoded_messages()]


def test_every_channel_decodes_and_frames_and_times_are_right(recorded: tuple[Path, Any]) -> None:
    _out, res = recorded
    assert res.status == "complete" and res.frames_written == 3
    msgs = _messages(res.recording)
    topics = {t for t, *_ in msgs}
    for agent in ("usv_1", "usv_2"):
        for suffix in (
            "lidar",
            "radar/returns",
            "radar/ppi",
            "camera/front/rgb",
            "camera/front/depth",
            "camera/front/semantic",
            "camera/front/instance",
            "camera/rear/rgb",
            "camera/rear/semantic",
            "top_view/rgb",
            "top_view/semantic",
            "boxes",
            "annotations",
        ):
            assert f"/{agent}/{suffix}" in topics
        assert f"/{agent}/camera/rear/depth" not in topics  # not among that camera's outputs
    assert {"/tf", "/world/state"} <= topics
    # One message per topic per frame, at t_k = k / f.
    per_topic: dict[str, list[int]] = {}
    for t, lt, _m, _d in msgs:
        per_topic.setdefault(t, []).append(lt)
    for t, times in per_topic.items():
        assert sorted(times) == [0, 200_000_000, 400_000_000], t
    states = [d for t, _lt, _m, d in msgs if t == "/world/state"]
    assert [s.frame for s in states] == [0, 1, 2]
    assert [len(s.vessels) for s in states] == [7 + 4] * 3  # 7 scenario vessels (usv_3 removed) + 4 moored ships


def test_recorded_sensors_match_a_direct_capture(recorded: tuple[Path, Any]) -> None:
    _out, res = recorded
    sim = mmusv.Simulation(small_scenario())
    cap = sim.capture(1)
    msgs = {t: d for t, lt, _m, d in _messages(res.recording) if lt == 200_000_000}
    pts = decode_point_cloud(msgs["/usv_1/lidar"])
    direct = cap.agents["usv_1"].lidar
    assert direct is not None
    np.testing.assert_array_equal(pts["x"], direct.xyz[:, 0])
    np.testing.assert_array_equal(pts["ring"], direct.ring)
    np.testing.assert_array_equal(pts["instance"], direct.instance)
    img = cap.agents["usv_1"].cameras["front"]
    np.testing.assert_array_equal(decode_image(msgs["/usv_1/camera/front/depth"]), img.depth)
    np.testing.assert_array_equal(decode_image(msgs["/usv_1/camera/front/semantic"]), img.semantic)
    assert img.rgb is not None
    np.testing.assert_array_equal(decode_image(msgs["/usv_1/camera/front/rgb"]), img.rgb)
    ann = msgs["/usv_1/annotations"]
    ids = [b.target_id for b in ann.boxes_lidar]
    assert "usv_1" not in ids, "the agent's own hull is never its target"
    assert all(b.range_m <= 200 for b in ann.boxes_lidar)  # the LiDAR's range
    assert {"ferry", "tug"} <= set(ids)  # both within 200 m of usv_1 in port_entry
    for b in ann.boxes_lidar:
        n = int(np.count_nonzero(pts["instance"] == b.instance_id))
        assert b.lidar_points == n


def test_tables_and_manifest(recorded: tuple[Path, Any]) -> None:
    out, _res = recorded
    ws = pl.read_parquet(out / "tables/world_state/*.parquet")
    assert ws.height == 3 * 11 and set(ws["frame"].unique()) == {0, 1, 2}
    b3 = pl.read_parquet(out / "tables/boxes_3d/*.parquet")
    assert (b3["agent"] != b3["target_id"]).all()
    man = json.loads((out / "manifest.json").read_text())
    assert man["status"] == "complete" and man["frames_written"] == 3 and man["agents"] == ["usv_1", "usv_2"]
    assert man["config_hash"] == mmusv.config.scenario_hash(mmusv.config.load_scenario(small_scenario()))


def test_same_scenario_and_seed_give_identical_bytes(recorded: tuple[Path, Any], tmp_path: Path) -> None:
    _out, res = recorded
    again = run(small_scenario(), out_dir=tmp_path)
    digest = lambda p: hashlib.sha256(Path(p).read_bytes()).hexdigest()  # noqa: E731
    assert digest(again.recording) == digest(res.recording)
    changed = small_scenario()
    changed["seed"] = 8
    other = run(changed, out_dir=tmp_path / "other")
    assert digest(other.recording) != digest(res.recording)


def test_existing_output_is_not_overwritten_unless_asked(recorded: tuple[Path, Any]) -> None:
    out, res = recorded
    before = res.recording.read_bytes()
    with pytest.raises(mmusv.IoError, match="overwrite"):
        run(small_scenario(), out_dir=out)
    assert res.recording.read_bytes() == before


def test_malformed_scenario_fails_before_anything_is_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = small_scenario()
    bad["rigs"]["usv_standard"]["lidar"]["channels"] = 0
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(bad))
    assert main(["run", str(path), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "rigs.usv_standard.lidar.channels" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_a_capture_that_fails_at_the_first_frame_writes_and_replaces_nothing(tmp_path: Path) -> None:
    """The first frame is captured before the recording is opened: a scenario the schema takes but the capture
    refuses (two USVs 200 km apart over a physical sea: too far for one sampled sea surface; the route checks,
    which would catch it earlier, are off) fails with a ConfigError naming the USVs, and an earlier complete run
    in the folder, with ``overwrite``, is left byte for byte as it was (recording, manifest, tables)."""
    sc = small_scenario(frames=2)
    first = run(sc, out_dir=tmp_path)
    before = {p.relative_to(tmp_path): p.read_bytes() for p in sorted(tmp_path.rglob("*")) if p.is_file()}
    far = small_scenario(frames=2)
    far["environment"]["wave"] = "W2"
    usvs = [v for v in far["vessels"] if v["role"] == "usv"]
    usvs[0]["route"] = [[-1e5, -1e5], [-99_900, -1e5]]
    usvs[1]["route"] = [[1e5, 1e5], [99_900, 1e5]]
    with pytest.raises(mmusv.ConfigError, match="USVs") as err:
        run(far, out_dir=tmp_path, overwrite=True, checks=False)
    assert usvs[0]["id"] in str(err.value)
    after = {p.relative_to(tmp_path): p.read_bytes() for p in sorted(tmp_path.rglob("*")) if p.is_file()}
    assert after == before and first.recording.name in {p.name for p in before}
    fresh = tmp_path / "fresh"
    with pytest.raises(mmusv.ConfigError):
        run(far, out_dir=fresh, checks=False)
    assert not fresh.exists()


def test_interrupted_run_leaves_a_readable_recording(tmp_path: Path) -> None:
    def stop(done: int, total: int) -> None:
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run(small_scenario(frames=5), out_dir=tmp_path, progress=stop)
    rec = tmp_path / "port_entry.mcap"
    msgs = _messages(rec)
    assert sorted({lt for _t, lt, _m, _d in msgs}) == [0, 200_000_000]
    with rec.open("rb") as f:
        meta = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    assert meta["run"]["status"] == "interrupted" and meta["run"]["frames_written"] == "2"
    assert json.loads((tmp_path / "manifest.json").read_text())["status"] == "interrupted"
    assert pl.read_parquet(tmp_path / "tables/world_state/*.parquet")["frame"].max() == 1


def test_info_and_preview_commands(
    recorded: tuple[Path, Any], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _out, res = recorded
    assert main(["info", str(res.recording)]) == 0
    text = capsys.readouterr().out
    assert "/usv_1/lidar" in text and "complete" in text and "3 frames" in text
    png = tmp_path / "p.png"
    assert main(["preview", str(res.recording), "--frame", "2", "--agent", "usv_2", "-o", str(png)]) == 0
    from PIL import Image

    with Image.open(png) as image:
        assert image.size[0] > 100
    assert main(["preview", str(res.recording), "--frame", "9"]) == 2


# ------------------------------------------------------------------ the overlapped pipeline (issue #12)


def _sequential(tmp_path: Path, frames: int, scenario: dict[str, Any] | None = None) -> bytes:
    """The recording written the plain way: capture, annotate, write, one frame after the other, one thread."""
    from mmusv.acquire import annotations_for
    from mmusv.recording.frames import FrameRecorder
    from mmusv.silhouettes import SilhouetteCache

    sim = mmusv.Simulation(scenario or small_scenario(frames))
    path = tmp_path / "sequential.mcap"
    rec = FrameRecorder(path, sim)
    silhouettes = SilhouetteCache()
    for k in range(frames):
        cap = sim.capture(k)
        rec.write_frame(cap, {a: ann.columns() for a, ann in annotations_for(sim, cap, silhouettes).items()})
    rec.finish(status="complete", frames=frames, requested=frames)
    return path.read_bytes()


def test_overlapped_run_writes_the_bytes_of_the_sequential_loop(recorded: tuple[Path, Any], tmp_path: Path) -> None:
    _out, res = recorded
    assert res.recording.read_bytes() == _sequential(tmp_path, 3)


def test_a_run_without_cameras_annotates_behind_the_capture_with_the_same_bytes(tmp_path: Path) -> None:
    """Without cameras each frame is annotated on the writer thread while the next is captured (the LiDAR's
    wave-occlusion shares over the physical sea included): the recording is the plain loop's, byte for byte, and the
    profile times the annotations on the writer's side."""
    sc = small_scenario(3)
    sc["rigs"]["usv_standard"] = {"preset": "lidar_only", "lidar": {"channels": 16, "points_per_second": 16 * 360 * 5}}
    res = run(sc, out_dir=tmp_path / "run", profile=True)
    assert res.recording.read_bytes() == _sequential(tmp_path, 3, sc)
    assert res.profile is not None
    stages = {r.stage for r in res.profile.rows()}
    assert "writer:annotate" in stages and "main:annotate" not in stages


def test_profiled_run_writes_the_same_bytes_and_times_every_stage(recorded: tuple[Path, Any], tmp_path: Path) -> None:
    out, res = recorded
    prof = run(small_scenario(), out_dir=tmp_path, profile=True)
    assert prof.recording.read_bytes() == res.recording.read_bytes()
    for table in ("world_state", "boxes_3d", "boxes_2d"):
        part = f"tables/{table}/part-00000.parquet"
        assert (tmp_path / part).read_bytes() == (out / part).read_bytes()
    assert res.profile is None and prof.profile is not None
    p = prof.profile
    stages = {r.stage: r for r in p.rows()}
    for sensor in ("lidar", "camera/front", "camera/rear", "top_view", "radar", "ppi"):
        assert stages[f"main:capture/{sensor}"].overlapping
    for stage in ("main:capture", "main:annotate", "main:wait", "main:python", "writer:write", "writer:tables"):
        assert not stages[stage].overlapping
    assert stages["writer:write/encode"].seconds > 0
    assert p.frames == 3 and p.wall_s > 0 and p.cpu_s > 0 and p.peak_rss_mb > 0
    # the main thread's stages and its rest add up to the wall time; the writer's and its idle time too
    for thread, rest in (("main", "python"), ("writer", "idle")):
        flat = [r.seconds for r in p.rows() if r.stage.startswith(thread + ":") and not r.overlapping]
        assert sum(flat) == pytest.approx(p.wall_s, rel=1e-9) or stages[f"{thread}:{rest}"].seconds == 0
    text = p.render()
    assert "main:capture/camera/front" in text and "frames/s" in text and "load average" in text


def test_interrupt_while_a_frame_is_being_written(
    recorded: tuple[Path, Any], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C lands while the writer thread is inside frame 1: frames 0 and 1 are complete in the file."""
    import threading

    from mmusv.recording.frames import FrameRecorder

    writing_1 = threading.Event()
    original = FrameRecorder.write_frame

    def slow_write(self: FrameRecorder, cap: Any, annotations: Any) -> None:
        if cap.frame == 1:
            writing_1.set()
            threading.Event().wait(0.5)  # still writing when the main thread is interrupted
        original(self, cap, annotations)

    monkeypatch.setattr(FrameRecorder, "write_frame", slow_write)

    def stop(done: int, total: int) -> None:
        if done == 2:
            assert writing_1.wait(10)
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run(small_scenario(frames=5), out_dir=tmp_path, progress=stop)
    rec = tmp_path / "port_entry.mcap"
    assert rec.exists() and not (tmp_path / "port_entry.mcap.partial").exists()
    msgs = _messages(rec)
    per_time: dict[int, set[str]] = {}
    for topic, lt, _m, _d in msgs:
        per_time.setdefault(lt, set()).add(topic)
    assert sorted(per_time) == [0, 200_000_000]
    every_topic = {t for t, *_ in _messages(recorded[1].recording)}
    assert per_time[0] == per_time[200_000_000] == every_topic  # both frames complete
    with rec.open("rb") as f:
        meta = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    assert meta["run"]["status"] == "interrupted" and meta["run"]["frames_written"] == "2"
    assert json.loads((tmp_path / "manifest.json").read_text())["frames_written"] == 2
    assert sorted(pl.read_parquet(tmp_path / "tables/world_state/*.parquet")["frame"].unique()) == [0, 1]


def test_a_failing_write_fails_the_run_and_keeps_the_frames_before_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from mmusv.recording.frames import FrameRecorder

    original = FrameRecorder.write_frame

    def failing(self: FrameRecorder, cap: Any, annotations: Any) -> None:
        if cap.frame == 2:
            raise mmusv.IoError("out.mcap: no space left on device")
        original(self, cap, annotations)

    monkeypatch.setattr(FrameRecorder, "write_frame", failing)
    with pytest.raises(mmusv.IoError, match="no space left"):
        run(small_scenario(frames=5), out_dir=tmp_path)
    rec = tmp_path / "port_entry.mcap"
    assert sorted({lt for _t, lt, _m, _d in _messages(rec)}) == [0, 200_000_000]
    with rec.open("rb") as f:
        meta = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    assert meta["run"]["status"] == "failed" and meta["run"]["frames_written"] == "2"
    assert "no space left" in meta["run"]["error"]
    man = json.loads((tmp_path / "manifest.json").read_text())
    assert man["status"] == "failed" and man["frames_written"] == 2
    assert sorted(pl.read_parquet(tmp_path / "tables/world_state/*.parquet")["frame"].unique()) == [0, 1]


def test_tf_holds_the_sensor_mounts_exactly(recorded: tuple[Path, Any]) -> None:
    """/tf agent → sensor is the mount itself (not body⁻¹ · pose): exact, and the same in every frame."""
    from mmusv.recording.frames import OPTICAL_IN_BODY, pose7

    _out, res = recorded
    sim = mmusv.Simulation(small_scenario())
    tfs = [d for t, _lt, _m, d in _messages(res.recording) if t == "/tf"]
    assert len(tfs) == 3
    for agent in sim.agents:
        assert agent.lidar_mount is not None and agent.radar_mount is not None
        want = {
            f"{agent.id}/lidar": pose7(agent.lidar_mount),
            f"{agent.id}/radar": pose7(agent.radar_mount),
            **{f"{agent.id}/camera/{n}": pose7(m @ OPTICAL_IN_BODY) for n, (_, _, m) in agent.cameras.items()},
        }
        for msg in tfs:
            got = {t.child_frame_id: t for t in msg.transforms if t.parent_frame_id == agent.id}
            assert set(got) == set(want)
            for child, (xyz, q) in want.items():
                t = got[child]
                assert [t.translation.x, t.translation.y, t.translation.z] == xyz.tolist(), child
                assert [t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w] == q.tolist(), child


def test_cli_profile_prints_the_table(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(small_scenario(frames=2)))
    assert main(["run", str(path), "-o", str(tmp_path / "out"), "--profile"]) == 0
    text = capsys.readouterr().out
    for row in ("main:capture", "main:capture/lidar", "main:capture/radar", "main:annotate", "writer:write/encode"):
        assert row in text
    assert "2 frames in" in text and "frames/s" in text and "CPU" in text
    assert main(["run", str(tmp_path), "-o", str(tmp_path / "o2"), "--profile"]) == 2  # a folder: one line
    assert "--profile times one scenario" in capsys.readouterr().err


def test_numpys_blas_runs_on_one_thread_while_recording(tmp_path: Path) -> None:
    # OpenBLAS spread the loop's skinny products over its threads (five times the CPU of one thread for an
    # (N, 3) by (3, 3) product) and its idle workers spun on the sensors' cores; the run holds it to one thread
    # and gives the user's setting back when it ends, finished or failed.
    from threadpoolctl import threadpool_info
    from tiny_scenario import lidar_scenario

    def blas_threads() -> list[int]:
        return [int(i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas"]

    before = blas_threads()
    seen: list[list[int]] = []
    run(lidar_scenario("blas", frames=2), out_dir=tmp_path / "a", progress=lambda *_: seen.append(blas_threads()))
    assert seen and all(t and all(n == 1 for n in t) for t in seen), seen
    assert blas_threads() == before

    def stop(*_: object) -> None:
        raise RuntimeError("stopped")

    with pytest.raises(RuntimeError):
        run(lidar_scenario("blas", frames=2), out_dir=tmp_path / "b", progress=stop)
    assert blas_threads() == before


def test_a_second_scenario_into_the_same_folder_is_refused(tmp_path: Path) -> None:
    """A review's: a second scenario run into a folder holding another's finished run replaced that run's
    manifest.json, scenario.yaml and tables without a word (the first recording was left without its tables). It
    is refused now, naming the other recording, with everything left as it was; ``overwrite=True`` replaces them."""
    from mmusv.errors import IoError
    from tiny_scenario import lidar_scenario

    out = tmp_path / "out"
    run(lidar_scenario("first", frames=2), out_dir=out)
    before = {p.relative_to(out): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}
    with pytest.raises(IoError, match=r"holds the run of another recording, first\.mcap .*overwrite"):
        run(lidar_scenario("second", frames=2), out_dir=out)
    assert {p.relative_to(out): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()} == before
    run(lidar_scenario("first", frames=2), out_dir=out, overwrite=True)  # its own run again: replaced as before
    run(lidar_scenario("second", frames=2), out_dir=out, overwrite=True)
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    assert manifest["recording"] == "second.mcap" and (out / "first.mcap").is_file()
    (out / "second.mcap").unlink()  # the other run's recording gone: nothing of it is lost by replacing the rest
    run(lidar_scenario("third", frames=2), out_dir=out)


def test_a_user_s_scenario_yaml_or_manifest_in_the_folder_is_never_replaced(tmp_path: Path) -> None:
    """A run replaced a scenario.yaml or manifest.json it did not write without a word, --overwrite or not: the
    user's notes, and the very scenario it ran (``mmusv run scenario.yaml -o .``). Refused before anything is
    written; a run's own files (beside its recording, or a scenario.yaml it dumped) are replaced as before."""
    from mmusv.errors import IoError
    from tiny_scenario import lidar_scenario

    hand = yaml.safe_dump(lidar_scenario("mine", frames=1), sort_keys=True)
    for overwrite in (False, True):
        out = tmp_path / f"same_{overwrite}"
        out.mkdir()
        (out / "scenario.yaml").write_text("# my notes: keep\n" + hand)
        with pytest.raises(IoError, match=r"scenario file .*scenario\.yaml is where a run into .* writes"):
            run(out / "scenario.yaml", out_dir=out, overwrite=overwrite)
        with pytest.raises(IoError, match=r"scenario\.yaml was not written by an mmusv run"):
            run(lidar_scenario("other", frames=1), out_dir=out, overwrite=overwrite)
        assert sorted(p.name for p in out.iterdir()) == ["scenario.yaml"]
        assert (out / "scenario.yaml").read_text().startswith("# my notes: keep\n")
    mine = tmp_path / "manifest"
    mine.mkdir()
    (mine / "manifest.json").write_text('{"a": 1}')
    with pytest.raises(IoError, match=r"manifest\.json was not written by an mmusv run"):
        run(lidar_scenario("other", frames=1), out_dir=mine)
    assert sorted(p.name for p in mine.iterdir()) == ["manifest.json"]
    out = tmp_path / "ours"  # a run's own scenario.yaml: again beside its recording, and alone (the rest moved)
    run(lidar_scenario("again", frames=1), out_dir=out)
    run(out / "scenario.yaml", out_dir=out, overwrite=True)
    for name in ("again.mcap", "manifest.json"):
        (out / name).unlink()
    run(lidar_scenario("again", frames=1), out_dir=out)


def test_overwrite_leaves_the_folder_a_fresh_run_would(tmp_path: Path) -> None:
    """An earlier run's table that this run writes no row of stayed as an empty folder, and the manifest listed it:
    the folder differed from a fresh run's."""
    from tiny_scenario import lidar_scenario

    fresh, again = tmp_path / "fresh", tmp_path / "again"
    run(lidar_scenario("same", frames=2), out_dir=fresh)
    run(lidar_scenario("same", frames=2), out_dir=again)
    stale = again / "tables" / "boxes_2d" / "part-00000.parquet"  # the camera table of an earlier run
    stale.parent.mkdir()
    stale.write_bytes(b"PAR1")
    run(lidar_scenario("same", frames=2), out_dir=again, overwrite=True)

    def files(root: Path) -> dict[str, bytes]:
        return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}

    assert sorted(p.name for p in (again / "tables").iterdir()) == sorted(p.name for p in (fresh / "tables").iterdir())
    assert files(again) == files(fresh)


def test_a_run_refused_over_an_interrupted_one_says_it_was_interrupted(tmp_path: Path) -> None:
    """``mmusv run`` again over a run stopped by Ctrl-C said only that the recording exists, as for a finished one."""
    from mmusv.errors import IoError
    from tiny_scenario import lidar_scenario

    def stop(done: int, total: int) -> None:
        if done == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run(lidar_scenario("stopped", frames=3), out_dir=tmp_path / "a", progress=stop)
    with pytest.raises(IoError, match=r"stopped\.mcap already exists \(its run was interrupted: 1 of 3 frames"):
        run(lidar_scenario("stopped", frames=3), out_dir=tmp_path / "a")
    run(lidar_scenario("done", frames=1), out_dir=tmp_path / "b")
    with pytest.raises(IoError, match=r"done\.mcap already exists; pass --overwrite"):
        run(lidar_scenario("done", frames=1), out_dir=tmp_path / "b")
