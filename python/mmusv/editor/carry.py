"""What a scenario document may hold on its way between the page and a file: what JSON can carry back to the
page (:func:`unjsonable`: no non-finite numbers, no unpaired UTF-16 surrogates), what a YAML file can hold
(:data:`NOT_YAML`) and how many values a file holds as :mod:`mmusv.yamlio` counts them (:func:`value_count`).
"""

from __future__ import annotations

import math
import re
from typing import Any

__all__ = ["NOT_YAML", "unjsonable", "value_count"]

NOT_YAML = re.compile("[^\x09\x0a\x0d\x20-\x7e\x85\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
"""A character a YAML file may not hold anywhere, comments included (control characters but tab and line breaks,
unpaired surrogates, U+FFFE/U+FFFF): a file with one does not load again."""
_SURROGATE = re.compile("[\ud800-\udfff]")


def _path(parts: list[str | int]) -> str:
    """``vessels[0].route`` from the keys and indices ``parts``."""
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def unjsonable(value: Any, root: str) -> str | None:
    """Where ``value`` (plain JSON-like data) holds what JSON cannot carry back to the page, and what it is:
    a number that is not finite (``.nan``, ``.inf`` in YAML, ``NaN`` in lenient JSON) or a text with an unpaired
    UTF-16 surrogate (``"\\ud800"``); None when there is nothing."""
    stack: list[tuple[Any, list[str | int]]] = [(value, [root] if root else [])]
    while stack:
        v, parts = stack.pop()
        if isinstance(v, float) and not math.isfinite(v):
            return f"{_path(parts) or 'the value'} = {v}: not a finite number"
        if isinstance(v, str) and _SURROGATE.search(v) is not None:
            return f"{_path(parts) or 'the value'} = {v!r}: an unpaired UTF-16 surrogate is not text"
        if isinstance(v, dict):
            for k, item in v.items():
                if isinstance(k, str) and _SURROGATE.search(k) is not None:
                    return (
                        f"{_path(parts) or 'the mapping'} has the key {k!r}: an unpaired UTF-16 surrogate is not text"
                    )
                stack.append((item, [*parts, str(k)]))
        elif isinstance(v, list):
            stack.extend((item, [*parts, i]) for i, item in enumerate(v))
    return None


def value_count(document: Any, limit: int) -> int:
    """How many values (mappings, lists, keys and scalars) ``document`` holds, as :mod:`mmusv.yamlio` counts them
    when the file is read again; stops counting above ``limit``."""
    count, stack = 0, [document]
    while stack and count <= limit:
        v = stack.pop()
        count += 1
        if isinstance(v, dict):
            stack.extend(v.keys())
            stack.extend(v.values())
        elif isinstance(v, list):
            stack.extend(v)
    return count
