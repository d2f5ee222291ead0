"""Sequence splits (deterministic, order-independent, no empty split when avoidable) and the ASCII PCD format."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mmusv.errors import ConfigError
from mmusv.export.pcd import pcd_bytes, read_pcd, write_pcd
from mmusv.export.splits import assign_splits, parse_ratios, split_counts


def test_split_counts() -> None:
    r = parse_ratios((0.7, 0.15, 0.15))
    assert split_counts(1, r) == [1, 0, 0]
    assert split_counts(3, r) == [1, 1, 1]
    assert split_counts(10, r) == [7, 2, 1] or split_counts(10, r) == [7, 1, 2]
    assert sum(split_counts(10, r)) == 10
    assert split_counts(20, r) == [14, 3, 3]
    assert split_counts(5, parse_ratios("1,0,0")) == [5, 0, 0]
    # three fractions in a numpy array: "expected three fractions", though it held three
    import numpy as np

    assert parse_ratios(np.array([0.7, 0.15, 0.15])) == r
    for n in range(0, 40):
        c = split_counts(n, r)
        assert sum(c) == n and min(c) >= 0
        if n >= 3:
            assert min(c) >= 1


def test_assign_splits_deterministic_and_order_independent() -> None:
    keys = [f"scenario_{i:02d}" for i in range(20)]
    a = assign_splits(keys, ratios=parse_ratios((0.7, 0.15, 0.15)), seed=0)
    b = assign_splits(list(reversed(keys)), ratios=parse_ratios((0.7, 0.15, 0.15)), seed=0)
    assert a == b
    assert sorted(a.values()).count("train") == 14
    c = assign_splits(keys, ratios=parse_ratios((0.7, 0.15, 0.15)), seed=1)
    assert c != a
    with pytest.raises(ConfigError):
        assign_splits(["x", "x"], ratios=(1.0, 0.0, 0.0), seed=0)
    # random.Random(-1) shuffles as random.Random(1): a negative seed is refused, not a copy of another
    with pytest.raises(ConfigError, match=r"seed = -1: the split's seed must be a whole number >= 0"):
        assign_splits(keys, ratios=parse_ratios((0.7, 0.15, 0.15)), seed=-1)


@pytest.mark.parametrize(
    ("ratios", "said"),
    [
        ((0.5, 0.5), "expected three fractions"),  # zip()'s ValueError
        ((0.7, 0.7, 0.7), "add up to"),  # 7 train, 3 validate, 0 test of 10, without a word
        ((-1.0, 1.0, 1.0), "non-negative"),  # a negative count of recordings for train, without a word
        ((0.5, float("nan"), 0.5), r"^ratios\[1\] = nan: must be a number"),
    ],
)
def test_assign_splits_checks_its_ratios(ratios: tuple[float, ...], said: str) -> None:
    """assign_splits (and the detection study's split_sequences and resolve_dataset, which call it from Python)
    took the ratios unchecked, where the command line parsed them first."""
    from mmusv.studies.detection.data import split_sequences

    keys = [f"s{i}" for i in range(10)]
    with pytest.raises(ConfigError, match=said):
        assign_splits(keys, ratios=ratios, seed=0)
    with pytest.raises(ConfigError, match=said):
        split_sequences(keys, split="train", ratios=ratios, seed=0)


def test_assign_splits_takes_weights_and_a_text_as_parse_ratios_does() -> None:
    keys = [f"s{i}" for i in range(10)]
    want = assign_splits(keys, ratios=parse_ratios((0.7, 0.2, 0.1)), seed=3)
    assert assign_splits(keys, ratios=(7, 2, 1), seed=3) == want  # 70, 20 and 10 recordings asked of 10: 7, 3, 0
    assert assign_splits(keys, ratios="0.7,0.2,0.1", seed=3) == want  # a TypeError of math.floor
    assert assign_splits(keys, ratios=(0.7, 0.2, 0.1), seed=3) == want


@pytest.mark.parametrize("bad", ["0.7,0.3", "a,b,c", "-1,1,1", "0,0,0", (0.5, float("nan"), 0.5)])
def test_parse_ratios_rejects(bad: object) -> None:
    with pytest.raises(ConfigError):
        parse_ratios(bad)  # type: ignore[arg-type]


def test_pcd_open3d_reads_points_and_intensity(tmp_path: Path) -> None:
    o3d = pytest.importorskip("open3d")
    rng = np.random.default_rng(0)
    xyz = rng.normal(size=(500, 3)) * 80
    inten = rng.uniform(size=500)
    inten[:3] = [0.0, 1.0, 1.7]  # out-of-range values are clipped
    p = tmp_path / "a.pcd"
    write_pcd(p, xyz=xyz, intensity=inten)
    text = p.read_text()
    assert "FIELDS x y z rgb\n" in text and "DATA ascii\n" in text
    pc = o3d.io.read_point_cloud(str(p))
    pts, cols = np.asarray(pc.points), np.asarray(pc.colors)
    np.testing.assert_allclose(pts, xyz, atol=6e-5)
    np.testing.assert_allclose(cols[:, 0], np.clip(inten, 0, 1), atol=0.5 / 255 + 1e-9)
    assert np.all(cols[:, 1:] == 0)
    back_xyz, back_i = read_pcd(p)
    np.testing.assert_allclose(back_xyz, xyz, atol=6e-5)
    np.testing.assert_allclose(back_i, cols[:, 0], atol=1e-12)


def test_pcd_deterministic_and_empty() -> None:
    xyz = np.array([[-1e-9, 0.0, 1.0]])
    assert pcd_bytes(xyz, [0.5]) == pcd_bytes(xyz.copy(), [0.5])
    assert b"\n0.0000 0.0000 1.0000 8388608\n" in pcd_bytes(xyz, [0.5])
    assert b"POINTS 0\n" in pcd_bytes(np.zeros((0, 3)), np.zeros(0))


def test_read_pcd_refuses_a_file_cut_short(tmp_path: Path) -> None:
    """A cloud cut after some rows read as fewer points without a word (a study then scored a damaged frame), and
    one cut inside its header as none with only numpy's warning; both name the file now. Whole files, the empty
    one included, read back."""
    rng = np.random.default_rng(1)
    p = tmp_path / "000001.pcd"
    write_pcd(p, xyz=rng.normal(size=(40, 3)), intensity=rng.uniform(size=40))
    data = p.read_bytes()
    assert read_pcd(p)[0].shape == (40, 3)
    empty = tmp_path / "000002.pcd"
    write_pcd(empty, xyz=np.zeros((0, 3)), intensity=np.zeros(0))
    assert read_pcd(empty)[0].shape == (0, 3) and read_pcd(empty)[1].shape == (0,)
    header = data.index(b"DATA ascii\n") + len(b"DATA ascii\n")
    cut_rows = data[: header + data[header:].index(b"\n", 200) + 1]  # whole rows, fewer than 40
    for cut, why in ((cut_rows, r"POINTS 40, and it holds \d+ \(a file cut short"), (data[:100], "not an ASCII")):
        p.write_bytes(cut)
        with pytest.raises(ValueError, match=why) as exc:
            read_pcd(p)
        assert str(p) in str(exc.value)
    p.write_bytes(data[:-9])  # inside the last row: a row of too few numbers
    with pytest.raises(ValueError):
        read_pcd(p)


@pytest.mark.parametrize(("bad", "total"), [("0.7,0.2,0.2", "1.1"), ((0.5, 0.25, 0.1), "0.85"), ("7.5,2,1", "10.5")])
def test_fractions_that_do_not_add_up_to_one_are_refused_not_rescaled(bad: object, total: str) -> None:
    # 0.7,0.2,0.2 (a typo for 0.7,0.15,0.15) was rescaled to 0.64/0.18/0.18 without a word (docs review).
    with pytest.raises(ConfigError, match=rf"the fractions add up to {total}; they must add up to 1"):
        parse_ratios(bad)  # type: ignore[arg-type]


def test_whole_number_weights_and_fractions_of_one_are_taken() -> None:
    assert parse_ratios("7,2,1") == pytest.approx((0.7, 0.2, 0.1))
    assert parse_ratios((1, 1, 1)) == pytest.approx((1 / 3,) * 3)
    assert parse_ratios("0.1,0.2,0.7") == pytest.approx((0.1, 0.2, 0.7))  # float sum 1 within rounding
    assert sum(parse_ratios("0.78,0,0.22")) == pytest.approx(1.0)


def test_a_frame_range_that_ends_before_it_starts_says_so() -> None:
    # Was "frames stop = 1: must be a whole number >= 3", which did not say why 3.
    from mmusv.export.convert_checks import frame_selection

    with pytest.raises(ConfigError, match=r"STOP \(1\) must be greater than START \(2\); STOP is excluded, so 2:3"):
        frame_selection("2:1")
    with pytest.raises(ConfigError, match=r"STOP \(2\) must be greater than START \(2\)"):
        frame_selection((2, 2))
    assert frame_selection("2:3") == (2, 3) and frame_selection("4:") == (4, None)
