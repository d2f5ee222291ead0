"""A conversion whose writes fail (a full disk): the error names the file it could not write.

The ``OSError`` of a write to an open file names no file (only opening one does), so ``mmusv convert`` onto a full
disk said only ``mmusv: error: No space left on device``, and ``conversion.yaml``'s ``error`` the same."""

from __future__ import annotations

import errno
import os
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml
from mmusv.cli import main
from mmusv.export import convert

_REAL_WRITE_BYTES = Path.write_bytes


def _full_disk_for(suffix: str) -> Callable[[Path, bytes], int]:
    """``Path.write_bytes`` that fails as a full disk does for files ending in ``suffix``: the file is opened (and
    left empty), the write fails with an ``OSError`` naming no file."""

    def write_bytes(self: Path, data: bytes) -> int:
        if self.name.endswith(suffix):
            self.touch()
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return _REAL_WRITE_BYTES(self, data)

    return write_bytes


def test_full_disk_names_the_file(
    coop_rec: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o"
    monkeypatch.setattr(Path, "write_bytes", _full_disk_for(".png"))
    code = main(["convert", str(coop_rec), "--to", "coco", "--no-split", "-o", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    line = next(x for x in err.splitlines() if x.startswith("mmusv: error:"))
    assert line != f"mmusv: error: {os.strerror(errno.ENOSPC)}", err  # what it said
    png = out / "images" / "all" / "export_coop" / "usv_a" / "front" / "000000.png"
    assert line == f"mmusv: error: {png}: {os.strerror(errno.ENOSPC)}", err
    # the folder's report says the same
    monkeypatch.setattr(Path, "write_bytes", _REAL_WRITE_BYTES)
    report = yaml.safe_load((out / "conversion.yaml").read_text())
    assert report["status"] == "failed"
    assert str(png) in report["error"], report


def test_full_disk_names_the_file_and_keeps_a_previous_conversion(
    coop_rec: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "o"
    convert(coop_rec, to="kitti", out_dir=out, splits=None, extras=())
    before = sorted(p.relative_to(out) for p in out.rglob("*"))
    monkeypatch.setattr(Path, "write_bytes", _full_disk_for(".bin"))
    with pytest.raises(OSError, match="No space left on device") as caught:
        convert(coop_rec, to="kitti", out_dir=out, splits=None, extras=(), overwrite=True)
    assert Path(caught.value.filename).name == "000000.bin", caught.value  # in the staging folder beside out
    assert Path(caught.value.filename).parent.name == "velodyne", caught.value
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == before


def test_full_disk_in_a_bag_names_the_bag(
    coop_rec: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from rosbags.rosbag2 import Writer

    real = Writer.write

    def write(self: Writer, *args: object, **kwargs: object) -> None:
        if kwargs or len(args) != 3 or args[1] > 1_200_000_000:  # type: ignore[operator]  # frame 1 onwards
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(self, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(Writer, "write", write)
    out = tmp_path / "o"
    code = main(["convert", str(coop_rec), "--to", "ros2", "-o", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    bag = out / "export_coop" / "export_coop.mcap"
    assert f"mmusv: error: {bag}: {os.strerror(errno.ENOSPC)}" in err.splitlines(), err


def test_full_disk_before_the_report_leaves_no_folder(
    coop_rec: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The first write, the report's: it left a new folder holding an empty conversion.yaml, which the next
    conversion into it took for a previous conversion (--overwrite asked for), and named no file."""
    out = tmp_path / "o"
    monkeypatch.setattr(Path, "write_bytes", _full_disk_for("conversion.yaml"))
    code = main(["convert", str(coop_rec), "--to", "coco", "-o", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    assert f"mmusv: error: {out / 'conversion.yaml'}: {os.strerror(errno.ENOSPC)}" in err.splitlines(), err
    assert not out.exists()
