"""What the malformed-input round of batches and datasets (tests/malformed/test_round_studies_batch.py) broke or
placed late, found reviewing it; each test fails on that round's code:

- a scenario path through a linked folder and ``..`` (``link/../real/scen``) named a folder that is not there
  (``os.path.abspath`` collapses ``..`` by the letters), and a folder reached through a link was named by the
  link, not by the real path a Ray cluster's nodes mount;
- an editor's lock link (Emacs' ``.#a.yaml`` beside a file being edited) refused the whole batch;
- a ``dataset.json`` left empty (or of NUL bytes) by a machine's crash was refused as "not an mmusv dataset index";
- ``mmusv dataset`` refused a ``.yml`` in ``DIR/scenarios`` only once the whole spec had been generated;
- a scenario failed for a file where its part goes had its earlier recording removed and a parts manifest written
  first.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from mmusv.batch import run_many
from mmusv.batch.plan import scenario_files
from mmusv.errors import ConfigError, IoError
from test_round_studies_batch import TINY_SPEC, _scenario_folder, _write
from tiny_scenario import lidar_scenario


def _linked(tmp_path: Path) -> tuple[Path, Path]:
    """``real/scen/a.yaml`` and ``work/link -> real``; returns (the real folder, the link)."""
    scen = tmp_path / "real" / "scen"
    scen.mkdir(parents=True)
    _write(scen / "a.yaml", lidar_scenario("a", frames=1))
    (tmp_path / "work").mkdir()
    link = tmp_path / "work" / "link"
    link.symlink_to(tmp_path / "real")
    return scen, link


def test_a_scenario_folder_through_a_link_and_dotdot_is_found(tmp_path: Path) -> None:
    """``work/link/../real/scen`` is ``real/scen`` to the system (``link/..`` is ``link``'s target's parent); the
    batch made it ``work/real/scen`` and failed the scenario, 'scenario file ... does not exist'."""
    scen, link = _linked(tmp_path)
    via = link / ".." / "real" / "scen"
    assert via.is_dir() and not (tmp_path / "work" / "real").exists()
    assert scenario_files(via) == [scen.resolve() / "a.yaml"]
    assert scenario_files([via / "a.yaml"]) == [scen.resolve() / "a.yaml"]
    rep = run_many(via, out_dir=tmp_path / "out")
    assert rep.summary() == "1 done, 0 failed, 0 skipped, 0 retried", rep.outcomes[0].error


def test_a_scenario_folder_through_a_link_is_named_by_its_real_path(tmp_path: Path) -> None:
    """The tasks name the scenario files by the folder's real path (as before the round), the one every node of a
    Ray cluster mounts; a link on the driver's machine alone (``~/data -> /mnt/shared``) is not on the workers. A
    file that is itself a link keeps its own name."""
    scen, link = _linked(tmp_path)
    (scen / "c.yaml").symlink_to("a.yaml")
    assert scenario_files(link / "scen") == [scen.resolve() / "a.yaml", scen.resolve() / "c.yaml"]


def test_an_editors_lock_link_does_not_stop_the_batch(tmp_path: Path) -> None:
    """Emacs keeps ``.#a.yaml`` (a link to ``user@host.pid:boot``, broken) beside ``a.yaml`` while it is edited:
    such an entry was skipped as it is not a file; the round refused the whole folder for it."""
    src = _scenario_folder(tmp_path)
    (src / ".#a.yaml").symlink_to("me@host.1234:1700000000")
    assert [f.name for f in scenario_files(src)] == ["a.yaml"]
    (src / "b.yaml").symlink_to(tmp_path / "gone.yaml")  # a visible broken link is still refused
    with pytest.raises(ConfigError, match=r"b\.yaml: a broken symbolic link"):
        scenario_files(src)


@pytest.mark.parametrize("text", ["", "\n", "\0" * 5000, '{\n  "for'], ids=["empty", "newline", "nul", "cut"])
def test_an_index_left_empty_by_a_crash_is_replaced(tmp_path: Path, text: str) -> None:
    """An index is renamed into place without a sync, so a machine that crashes can leave ``dataset.json`` empty
    (or of NUL bytes): the re-run that is to finish the batch refused it as 'not an mmusv dataset index' (another
    tool's), though it holds nothing to lose."""
    from mmusv.batch.index import check_replaceable

    src = _scenario_folder(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "dataset.json").write_text(text, encoding="utf-8")
    check_replaceable(out / "dataset.json", writer="the batch")
    if text == "":
        assert run_many(src, out_dir=out).ok
        assert json.loads((out / "dataset.json").read_text(encoding="utf-8"))["totals"]["complete"] == 1


def test_mmusv_dataset_refuses_a_yml_before_generating(tmp_path: Path) -> None:
    """A ``.yml`` in ``DIR/scenarios`` (generate checks only ``*.yaml``) was refused once every scenario of the spec
    had been generated; moved away, the next run generated them all again (no index yet)."""
    from mmusv.batch.dataset import build_dataset

    spec = _write(tmp_path / "tiny.yaml", TINY_SPEC)
    out = tmp_path / "ds"
    (out / "scenarios").mkdir(parents=True)
    _write(out / "scenarios" / "extra.yml", lidar_scenario("extra", frames=1))
    with pytest.raises(IoError, match=r"holds scenario files the spec's generation did not write \(extra\.yml;"):
        build_dataset(spec, out_dir=out)
    assert sorted(p.name for p in (out / "scenarios").iterdir()) == ["extra.yml"]
    assert sorted(p.name for p in out.iterdir()) == ["scenarios"]


def test_a_blocked_part_leaves_the_earlier_recording_as_it_was(tmp_path: Path) -> None:
    """``--split-frames`` with a file where ``OUT/a/parts`` goes fails the scenario, naming the file; the check ran
    after the folder was readied, which removed the earlier whole recording and wrote ``a.parts.json`` for parts
    never to be recorded."""
    src = _scenario_folder(tmp_path, frames=2)
    out = tmp_path / "out"
    assert run_many(src, out_dir=out).ok
    before = (out / "a" / "a.mcap").read_bytes()
    (out / "a" / "parts").write_text("not a folder\n", encoding="utf-8")
    rep = run_many(src, out_dir=out, split_frames=1, overwrite=True)
    assert rep.summary() == "0 done, 1 failed, 0 skipped, 0 retried"
    assert "the folder of its part" in (rep.outcomes[0].error or "")
    assert (out / "a" / "a.mcap").read_bytes() == before
    assert (out / "a" / "manifest.json").is_file() and not (out / "a" / "a.parts.json").exists()
