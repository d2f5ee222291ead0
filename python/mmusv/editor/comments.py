"""The ``#`` comments of a scenario file, read with their anchors and written back into the editor's YAML.

The editor writes a scenario file from its document (:func:`mmusv.editor.document.scenario_yaml`), so the text a
person wrote around the values would be lost on every save. This module keeps it. Reading comments is a concern
apart from reading data (:mod:`mmusv.yamlio` stays the one loader of values): :func:`read_comments` composes the
text with PyYAML only for the positions of its keys and values, and finds each comment around them.

**Anchors.** Every comment is tied to a key path (:class:`Comment`): a top-level key (``("environment",)``), a key
inside a block (``("environment", "wave")``, ``("rigs", "usv_standard", "lidar")``), a list item (its index), or a
vessel, which is matched by its ``id`` (``("vessels", "ferry")``, wherever it moves in the list). A comment on a line
of its own belongs to the entry that starts on the next line holding one (``at="before"``); a comment after a value
belongs to the entry that ends on that line (``at="end"``); comments after the last value belong to the end of the
file (the empty path). The file's leading comment block (the lines starting with ``#`` at its very top, which the page
shows as the scenario's description) is not among them: :func:`~mmusv.editor.document.leading_comment` reads it.

**Writing back.** The editor's YAML has a line of its own only for each top-level key, each rig and each vessel (one
flow line, perhaps wrapped): that entry is a comment's *home* (the vessel or rig its path lies in, else its
top-level key). :func:`place_comments` writes a comment at the end of its home's line when it was at the end of that
entry's own line, and on a line of its own just above its home's line otherwise (a comment inside a vessel or block
written out in full moves above the one flow line that now holds it), in the order of the file, indented as that
line. A comment whose home is still there but whose own key is not (``environment.rain`` set back to its default)
stays with that home. A comment whose home is gone (a deleted vessel or rig, or one renamed by a client that did not
rename its comments' anchors with it, as the editor's page does) is kept, not dropped: it is
written at the end of the file under a line ``# [removed from the scenario: vessel ferry]`` and returned, so the
save can say so; later saves keep it there as one of the file's last comments.

**Blank lines.** A blank line that sets off an entry the editor writes on a line of its own (a top-level key, a rig,
a vessel, with the comments above it) is kept as an empty comment (``text == ""``) anchored before that entry, and
one before the comments at the end of the file likewise; blank lines inside a block the editor writes as one flow
line, inside a text (a ``|`` block) and after the file's last line are not (the flow line has no place for them).
So a file whose sections are set apart by blank lines keeps them. The same text and comments give the same bytes,
and saving a file written this way again gives it back byte for byte.
"""

from __future__ import annotations

import bisect
import json
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import yaml

__all__ = ["Comment", "comment_problem", "moved_note", "place_comments", "read_comments"]

Path = tuple[str | int, ...]
"""Keys (texts) and list indices from the top of the file; a vessel is its ``id`` after ``"vessels"``."""

_BREAK = re.compile("\r\n|[\r\n\x85\u2028\u2029]")
"""Line breaks as YAML (and PyYAML's line numbers) count them."""
_ESCAPE = re.compile("[^\x20-\x7e\xa0-\u2027\u202a-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
_NOT_IN_COMMENT = re.compile("[^\x09\x20-\x7e\xa0-\u2027\u202a-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
"""A character a one-line comment may not hold: line breaks, other control characters (tab is allowed)."""


@dataclass(frozen=True)
class Comment:
    """One comment: ``text`` as written from its ``#`` (trailing spaces dropped; ``""`` for a blank line), its anchor
    ``path`` (``()``: the end of the file) and where it stood, ``"before"`` the entry (on a line of its own) or at the
    ``"end"`` of it."""

    path: Path
    at: Literal["before", "end"]
    text: str

    def as_json(self) -> dict[str, Any]:
        return {"path": list(self.path), "at": self.at, "text": self.text}


def comment_problem(text: str) -> str | None:
    """Why ``text`` cannot be written as one comment line, or an empty one as a blank line (None when it can)."""
    if text == "":
        return None
    if not text.startswith("#"):
        return f"a comment starts with '#': {text[:40]!r}"
    bad = _NOT_IN_COMMENT.search(text)
    if bad is not None:
        return f"a comment is one line of text: U+{ord(bad.group()):04X} at position {bad.start()} is not allowed"
    return None


@dataclass(frozen=True)
class _Anchor:
    path: Path
    start: int  # the line it starts on (its key, or the item)
    column: int
    eol: int  # the line whose end belongs to it: the key's line for a block collection, else its value's last line


def _last_line(node: yaml.Node) -> int:
    end = node.end_mark
    return int(end.line - 1 if end.column == 0 and end.line > node.start_mark.line else end.line)


def _eol(entry_line: int, value: yaml.Node) -> int:
    if isinstance(value, (yaml.MappingNode, yaml.SequenceNode)) and not value.flow_style:
        return entry_line
    return _last_line(value)


def _vessel_id(item: yaml.Node) -> str | None:
    if isinstance(item, yaml.MappingNode):
        for k, v in item.value:
            if isinstance(k, yaml.ScalarNode) and k.value == "id" and isinstance(v, yaml.ScalarNode):
                return str(v.value)
    return None


def _compose(text: str) -> tuple[list[_Anchor], list[tuple[int, int]]]:
    """The anchors of ``text`` and the character spans of its scalars (where a ``#`` is text, not a comment)."""
    root = yaml.compose(text, Loader=yaml.SafeLoader)
    anchors: list[_Anchor] = []
    spans: list[tuple[int, int]] = []
    seen: set[int] = set()
    stack: list[tuple[yaml.Node, Path]] = [(root, ())] if root is not None else []
    while stack:
        node, path = stack.pop()
        if id(node) in seen:  # an alias: its node was walked where it was written
            continue
        seen.add(id(node))
        if isinstance(node, yaml.ScalarNode):
            spans.append((node.start_mark.index, node.end_mark.index))
        elif isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                if isinstance(k, yaml.ScalarNode):
                    spans.append((k.start_mark.index, k.end_mark.index))
                    seen.add(id(k))
                    p = (*path, str(k.value))
                    line = k.start_mark.line
                    aliased = v.start_mark.index < k.start_mark.index  # `key: *a`: the node is where `&a` is
                    anchors.append(_Anchor(p, line, k.start_mark.column, line if aliased else _eol(line, v)))
                    stack.append((v, p))
                else:  # a complex key: no path below it, but its scalars are still text
                    stack.append((k, (*path, "?")))
                    stack.append((v, (*path, "?")))
        elif isinstance(node, yaml.SequenceNode):
            for i, item in enumerate(node.value):
                if item.start_mark.index < node.start_mark.index:  # `- *a`: where it is written is not known
                    continue
                vid = _vessel_id(item) if path == ("vessels",) else None
                p = (*path, vid if vid is not None else i)
                line = item.start_mark.line
                anchors.append(_Anchor(p, line, item.start_mark.column, _eol(line, item)))
                stack.append((item, p))
    anchors.sort(key=lambda a: (a.start, a.column, len(a.path)))
    spans.sort()
    return anchors, spans


def _lines(text: str) -> list[tuple[int, str]]:
    """``(offset, line)`` of every line of ``text`` (YAML's line breaks)."""
    out, pos = [], 0
    for m in _BREAK.finditer(text):
        out.append((pos, text[pos : m.start()]))
        pos = m.end()
    if pos < len(text):
        out.append((pos, text[pos:]))
    return out


def _in_span(spans: list[tuple[int, int]], index: int) -> bool:
    """Whether ``index`` lies in one of ``spans`` (sorted, disjoint: scalars do not nest)."""
    i = bisect.bisect_right(spans, (index, len(spans) + 2**62)) - 1
    return i >= 0 and spans[i][0] <= index < spans[i][1]


def _comment_at(line: str, offset: int, spans: list[tuple[int, int]]) -> int | None:
    """Where the comment of ``line`` starts (its ``#``), or None."""
    j = line.find("#")
    while j >= 0:
        if (j == 0 or line[j - 1] in " \t") and not _in_span(spans, offset + j):
            return j
        j = line.find("#", j + 1)
    return None


def read_comments(text: str) -> list[Comment]:
    """The comments of the YAML ``text`` but its leading block, in the order of the file, with their anchors (see
    the module docstring); ``[]`` for a text PyYAML cannot compose. A leading byte-order mark is not text."""
    text = text.removeprefix("\ufeff")  # (else the file's first line, a comment, would be neither kind)
    lines = _lines(text)
    first = 0
    while first < len(lines) and lines[first][1].startswith("#"):  # the leading block (leading_comment's)
        first += 1
    if not any("#" in line or not line.strip() for _, line in lines[first:]):
        return []
    try:
        anchors, spans = _compose(text)
    except (yaml.YAMLError, RecursionError):
        return []
    starts = [a.start for a in anchors]
    starting: dict[int, list[_Anchor]] = {}
    ending: dict[int, list[_Anchor]] = {}
    for a in anchors:
        starting.setdefault(a.start, []).append(a)
        ending.setdefault(a.eol, []).append(a)
    found: list[tuple[int, int, str, bool]] = []  # (line, column, text, own line)
    content: list[int] = []  # lines holding something other than a comment
    for number, (offset, line) in enumerate(lines):
        j = _comment_at(line, offset, spans) if "#" in line else None
        head = line if j is None else line[:j]
        if head.strip():
            content.append(number)
        if j is not None and number >= first:
            found.append((number, j, line[j:].rstrip(), not head.strip()))
        elif not line.strip() and number >= first and not _in_span(spans, offset):  # a blank line (not in a text)
            found.append((number, 0, "", True))
    out: list[Comment] = []
    for number, _, body, own in found:
        anchor: _Anchor | None = None
        if not own:
            ends = ending.get(number)
            if ends:  # the shallowest entry ending on the line; of those, the last written
                depth = min(len(a.path) for a in ends)
                anchor = max((a for a in ends if len(a.path) == depth), key=lambda a: (a.start, a.column))
            else:  # the entry the line belongs to: the last one started on or before it
                i = bisect.bisect_right(starts, number) - 1
                anchor = anchors[i] if i >= 0 else None
            if anchor is not None:
                out.append(Comment(anchor.path, "end", body))
                continue
        k = bisect.bisect_right(content, number)
        nxt = content[k] if k < len(content) else None
        if nxt is not None and nxt in starting:
            anchor = min(starting[nxt], key=lambda a: (len(a.path), a.column))
        elif nxt is not None:  # a line that continues an entry (a wrapped flow value): that entry
            i = bisect.bisect_left(starts, nxt) - 1
            anchor = anchors[i] if i >= 0 else None
        path = anchor.path if anchor is not None else ()
        if body or _home(path) == path:  # a blank line only before an entry with a line of its own
            out.append(Comment(path, "before", body))
    while out and out[-1] == Comment((), "before", ""):  # blank lines after the file's last line
        out.pop()
    return out


def _home(path: Path) -> Path:
    """The entry of the editor's YAML whose line holds ``path`` (see the module docstring)."""
    if not path:
        return ()
    if path[0] in ("vessels", "rigs") and len(path) >= 2 and isinstance(path[1], str):
        return path[:2]
    return path[:1]


def _shown(value: str | int) -> str:
    text = str(value)
    return json.dumps(text) if _ESCAPE.search(text) or not text.strip() else text


def _what(home: Path) -> str:
    if len(home) == 2 and home[0] == "vessels":
        return f"vessel {_shown(home[1])}"
    if len(home) == 2 and home[0] == "rigs":
        return f"rig {_shown(home[1])}"
    return "key " + ".".join(_shown(p) for p in home)


def moved_note(moved: Sequence[Comment]) -> str | None:
    """What a save tells the person about ``moved`` (the comments :func:`place_comments` moved to the end of the
    file), e.g. ``"2 comments of the removed vessel ferry were moved to the end of the file"``; None if none."""
    if not moved:
        return None
    counts: dict[Path, int] = {}
    for c in moved:
        counts[_home(c.path)] = counts.get(_home(c.path), 0) + 1
    parts = [f"{n} comment{'s' if n > 1 else ''} of the removed {_what(h)}" for h, n in counts.items()]
    verb = "was" if len(moved) == 1 else "were"
    return f"{', '.join(parts)} {verb} moved to the end of the file"


def place_comments(body: str, comments: Iterable[Comment]) -> tuple[str, list[Comment]]:
    """``body`` (the editor's YAML of a scenario, without its leading comment) with ``comments`` written at their
    anchors, and the comments whose anchor is gone (written at the end of the file, see the module docstring)."""
    comments = list(comments)
    if not comments:
        return body, []
    anchors, _ = _compose(body)
    homes = {a.path: a for a in anchors if _home(a.path) == a.path}
    lines = body.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    above: dict[int, list[str]] = {}
    after: dict[int, list[str]] = {}
    trailing: list[str] = []
    moved: dict[Path, list[Comment]] = {}
    comments = [Comment(c.path, c.at, c.text.rstrip()) for c in comments]  # as they read back
    for c in comments:
        home = _home(c.path)
        if not c.text and c.at == "end":  # a blank line is a line of its own: at a line's end, nothing to write
            continue
        if not home:
            trailing.append(c.text)
        elif home not in homes:
            if c.text:  # (a removed entry's blank line goes with it)
                moved.setdefault(home, []).append(c)
        elif c.at == "end" and c.path == home:
            after.setdefault(homes[home].eol, []).append(c.text)
        else:
            above.setdefault(homes[home].start, []).append(c.text)
    out: list[str] = []
    for number, line in enumerate(lines):
        indent = line[: len(line) - len(line.lstrip(" "))]
        out.extend(indent + text if text else "" for text in above.get(number, []))
        out.append("  ".join([line, *after.get(number, [])]))
    while trailing and not trailing[-1] and not moved:  # a blank line after the file's last line is not layout
        trailing.pop()
    out.extend(trailing)
    for home, cs in moved.items():
        out.append(f"# [removed from the scenario: {_what(home)}]")
        out.extend(c.text for c in cs)
    return "\n".join(out) + "\n", [c for cs in moved.values() for c in cs]
