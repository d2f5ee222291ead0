"""Checking many bad calls at once: each must raise its mmusv error with words that name what is wrong."""

from __future__ import annotations

from collections.abc import Callable, Iterable


def unrefused(calls: Iterable[tuple[str, Callable[[], object], type[BaseException], str]]) -> list[str]:
    """The problems with ``(label, call, error class, words)`` bad calls: a call that was accepted, raised
    another exception, or raised the class without ``words`` in its message. Empty when every call is refused as
    it should be."""
    wrong = []
    for label, call, cls, words in calls:
        try:
            call()
        except cls as exc:
            if words not in str(exc):
                wrong.append(f"{label}: {type(exc).__name__}: {exc} (want {words!r})")
        except Exception as exc:
            wrong.append(f"{label}: {type(exc).__name__}: {exc}")
        else:
            wrong.append(f"{label}: accepted")
    return wrong
