"""Review round 5: what the latest commits got wrong, each test failing on the code before its fix."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mmusv.export.pcd import read_pcd, write_pcd


def _cloud(tmp_path: Path) -> tuple[Path, bytes]:
    p = tmp_path / "000001.pcd"
    write_pcd(p, xyz=np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.5]]), intensity=[0.5, 1.0, 0.2])
    return p, p.read_bytes()


def test_read_pcd_refuses_a_file_cut_inside_its_last_row(tmp_path: Path) -> None:
    """85fba3b counts the rows against POINTS, but a file cut inside its last row holds as many rows as POINTS: cut
    inside the last number it read back without a word (``... 9.5000 3`` gave the last point intensity 0 instead
    of 0.2), cut before it numpy's "number of columns changed" came without the file's name. A row that does not
    end in a newline is a row cut short: refused, naming the file."""
    p, data = _cloud(tmp_path)
    last = data.rindex(b"\n", 0, len(data) - 1) + 1  # where the last row starts
    for cut in range(last + 1, len(data) - 1):
        p.write_bytes(data[:cut])
        with pytest.raises(ValueError, match="cut short") as exc:
            read_pcd(p)
        assert str(p) in str(exc.value), data[:cut]
    p.write_bytes(data)
    assert read_pcd(p)[1].tolist() == pytest.approx([128 / 255, 1.0, 51 / 255])


def test_read_pcd_reads_a_points_line_spaced_otherwise(tmp_path: Path) -> None:
    """85fba3b's ``^POINTS (\\d+)$`` took a header line ``POINTS 3 `` (a blank after the count) or ``POINTS\\t3``
    for no POINTS at all, refusing a cloud read whole before it, and by Open3D and PCL."""
    p, data = _cloud(tmp_path)
    want = read_pcd(p)
    for line in (b"POINTS 3 \n", b"POINTS\t3\n", b"POINTS  3\t\n"):
        p.write_bytes(data.replace(b"POINTS 3\n", line))
        got = read_pcd(p)
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
    p.write_bytes(data.replace(b"POINTS 3\n", b"POINTS 2 \n"))
    with pytest.raises(ValueError, match="POINTS 2, and it holds 3"):
        read_pcd(p)
