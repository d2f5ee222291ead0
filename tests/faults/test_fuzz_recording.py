"""Property test: the bytes of a small recording mutated (bits flipped, bytes overwritten, deleted, inserted,
ranges duplicated, the file cut) and every reader run on the result. Each either raises an ``MmusvError`` naming
the file, or returns frames that are byte for byte those of the intact recording and reports the ones it lost —
never another exception, a wrong frame or a hang. 200 examples in CI; set MMUSV_FUZZ_EXAMPLES (e.g. 5000) for
the long run."""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from mmusv.errors import MmusvError

from .conftest import api_readers, check_against, cli_main

EXAMPLES = int(os.environ.get("MMUSV_FUZZ_EXAMPLES", "200"))
TIME_LIMIT_S = 30


class _Hang(Exception):
    pass


@contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    def alarm(signum: int, frame: Any) -> None:
        raise _Hang(f"a reader took more than {seconds} s")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


@st.composite
def mutations(draw: st.DrawFn, size: int) -> list[tuple[str, int, int, bytes]]:
    ops = []
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["flip", "flip", "overwrite", "delete", "insert", "duplicate", "cut"]))
        at = draw(st.integers(0, size - 1))
        n = draw(st.integers(1, 64))
        data = draw(st.binary(min_size=1, max_size=64)) if kind in ("overwrite", "insert") else b""
        ops.append((kind, at, n, data))
    return ops


def mutate(data: bytes, ops: list[tuple[str, int, int, bytes]]) -> bytes:
    b = bytearray(data)
    for kind, at, n, extra in ops:
        if not b:
            break
        at = min(at, len(b) - 1)
        if kind == "flip":
            b[at] ^= (n % 255) + 1
        elif kind == "overwrite":
            b[at : at + len(extra)] = extra
        elif kind == "delete":
            del b[at : at + n]
        elif kind == "insert":
            b[at:at] = extra
        elif kind == "duplicate":
            b[at:at] = b[max(0, at - n * 16) : at]
        elif kind == "cut":
            del b[at:]
    return bytes(b)


def test_mutated_recordings_give_a_clean_error_or_the_right_frames(
    chunky: tuple[Path, dict[int, dict[str, bytes]]], tmp_path_factory: Any
) -> None:
    src, reference = chunky
    data = src.read_bytes()
    folder = tmp_path_factory.mktemp("fuzz")
    path = folder / "tiny.mcap"

    @settings(
        max_examples=EXAMPLES,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
        derandomize=True,
    )
    @given(ops=mutations(len(data)))
    @example(ops=[("delete", 2179, 1, b"")])  # found by the long run: the first chunk's channels lost with it
    @example(ops=[("duplicate", 1142, 61, b""), ("cut", 3154, 1, b"")])  # metadata garbled but parseable
    def check(ops: list[tuple[str, int, int, bytes]]) -> None:
        path.write_bytes(mutate(data, ops))
        with time_limit(TIME_LIMIT_S):
            results = api_readers(path)
            for res in results.values():
                if isinstance(res, MmusvError):
                    assert path.name in str(res), res
            check_against(results, reference)
            code, _out, err = cli_main("info", str(path))
        # 2: not readable at all; 1: read, but not one frame (nothing to convert); 0: frames read, damage warned
        assert code in (0, 1, 2) and "Traceback" not in err
        if code == 2:
            assert err.startswith("mmusv: error: ") and err.count("\n") == 1, err

    check()
