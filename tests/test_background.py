"""The background writer (:mod:`mmusv.recording.background`): order, the bound on waiting items, failures, Ctrl-C."""

from __future__ import annotations

import _thread
import threading
import time

import pytest
from mmusv.recording.background import BackgroundWriter


def test_items_are_written_in_order_on_another_thread() -> None:
    seen: list[tuple[int, str]] = []
    w: BackgroundWriter[int] = BackgroundWriter(lambda i: seen.append((i, threading.current_thread().name)))
    for i in range(20):
        w.submit(i)
    w.close()
    w.raise_pending()
    assert [i for i, _ in seen] == list(range(20))
    assert {name for _, name in seen} == {"mmusv-writer"}
    assert w.done == 20 and w.error is None and not w.interrupted
    w.close()  # again: nothing to do
    with pytest.raises(RuntimeError, match="closed"):
        w.submit(21)


def test_at_most_depth_items_wait_while_one_is_written() -> None:
    gate, started = threading.Event(), threading.Event()
    written: list[int] = []

    def write(i: int) -> None:
        started.set()
        gate.wait(10)
        written.append(i)

    w: BackgroundWriter[int] = BackgroundWriter(write, depth=1)
    w.submit(0)
    assert started.wait(10)  # item 0 is being written
    w.submit(1)  # waits in the queue
    third = threading.Thread(target=w.submit, args=(2,))
    third.start()
    third.join(0.5)
    assert third.is_alive(), "a third item must wait while one is written and one waits"
    assert written == []
    gate.set()
    third.join(10)
    w.close()
    assert written == [0, 1, 2] and w.wait_seconds > 0.4


def test_a_failure_stops_the_writing_and_reaches_the_caller() -> None:
    written: list[int] = []

    def write(i: int) -> None:
        if i == 2:
            raise OSError("disk full")
        written.append(i)

    w: BackgroundWriter[int] = BackgroundWriter(write, depth=1)
    with pytest.raises(OSError, match="disk full"):  # raised by a later submit once the writer failed
        for i in range(50):
            w.submit(i)
            time.sleep(0.01)
    w.close()
    assert written == [0, 1] and w.done == 2  # nothing after the failure, nothing out of order
    assert isinstance(w.error, OSError)
    with pytest.raises(OSError, match="disk full"):
        w.raise_pending()


def test_ctrl_c_while_closing_still_writes_every_item_and_is_reported() -> None:
    written: list[int] = []

    def write(i: int) -> None:
        if i == 1:
            # Wait until the main thread is in close() (on a loaded machine a fixed sleep may not be enough), then
            # give it a moment to be waiting there.
            deadline = time.monotonic() + 30.0
            while not w._closed and time.monotonic() < deadline:
                time.sleep(0.01)
            time.sleep(0.1)
            _thread.interrupt_main()  # what Ctrl-C does
            time.sleep(0.3)
        written.append(i)

    w: BackgroundWriter[int] = BackgroundWriter(write, depth=1)
    w.submit(0)
    w.submit(1)
    w.submit(2)
    w.close()  # must not raise: the caller still has files to finish
    assert written == [0, 1, 2] and w.done == 3 and w.interrupted
    with pytest.raises(KeyboardInterrupt):
        w.raise_pending()


def test_depth_must_be_positive() -> None:
    with pytest.raises(ValueError, match="depth"):
        BackgroundWriter(lambda i: None, depth=0)
