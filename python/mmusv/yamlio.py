"""The one reader of every YAML input mmusv takes: scenarios, generation specs, rigs, asset catalogues.

:func:`read_yaml` turns a file into plain Python data, or raises :class:`mmusv.ConfigError` naming the file and
what is wrong, never a ``UnicodeDecodeError`` or a bare parser error:

* bytes are decoded as UTF-8 (a UTF-8 byte-order mark is accepted); UTF-16/32 files (as some Windows editors
  save them), Latin-1 text and binary files are refused with the byte offset of the first bad byte;
* duplicate keys in a mapping are refused, naming the key and both lines (the YAML spec forbids them, and
  PyYAML would silently keep the last one: two ``vessels:`` blocks would drop the first fleet);
* syntax errors name the line and column.

:func:`mapping_source` accepts a path, a dict or an already validated model, which is how ``load_scenario``
and ``load_spec`` take their input.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import Any

import yaml

from mmusv.errors import ConfigError

__all__ = ["MAX_YAML_BYTES", "MAX_YAML_VALUES", "decode_text", "mapping_source", "parse_yaml", "read_yaml"]

MAX_YAML_BYTES = 64 * 1024 * 1024
"""Largest YAML input read (64 MiB): larger files are refused before they are read."""

MAX_YAML_VALUES = 1_000_000
"""Most values (scalars, lists and mappings, each time an alias repeats them) a YAML document may expand to: a few
hundred bytes of nested aliases can stand for billions of values, which no scenario needs."""

_BOMS = {
    b"\xff\xfe\x00\x00": "UTF-32 (little-endian)",
    b"\x00\x00\xfe\xff": "UTF-32 (big-endian)",
    b"\xff\xfe": "UTF-16 (little-endian)",
    b"\xfe\xff": "UTF-16 (big-endian)",
}


class _UniqueKeyLoader(yaml.SafeLoader):
    """PyYAML's safe loader, refusing duplicate keys in any mapping."""


# The same on libyaml's C parser where PyYAML was built with it (its wheels are): the same documents, ten times
# faster (the built-in vessel catalogue, 74 kB, parses in 0.05 s instead of 0.58 s at every start), but only for
# mmusv's own files (`parse_yaml(trusted=True)`): it composes nested nodes by recursion on the C stack, and a
# hostile document nested 100,000 deep crashes the process, where the pure-Python parser refuses it ("nested too
# deeply"). A document it refuses is parsed again by the pure-Python parser, whose messages say more.
_CSafeLoader: Any = getattr(yaml, "CSafeLoader", None)
_FastUniqueKeyLoader: Any = (
    None
    if _CSafeLoader is None
    else type("_FastUniqueKeyLoader", (_CSafeLoader,), {"__doc__": _UniqueKeyLoader.__doc__})
)


def _construct_mapping(loader: Any, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
    # Only the keys written in this mapping must be unique: a merge key (`<<: *base`) brings in keys that the
    # mapping's own may override, as YAML's merge type says.
    explicit = [(k, v) for k, v in node.value if k.tag != "tag:yaml.org,2002:merge"]
    loader.flatten_mapping(node)
    seen: dict[Any, int] = {}
    for key_node, _ in explicit:
        key = loader.construct_object(key_node, deep=True)
        try:
            hash(key)
        except TypeError:
            raise yaml.constructor.ConstructorError(
                "while constructing a mapping", node.start_mark, "found an unhashable key", key_node.start_mark
            ) from None
        line = key_node.start_mark.line + 1
        if key in seen:
            raise _DuplicateKey(f"duplicate key {key!r} at line {line} (first at line {seen[key]})")
        seen[key] = line
    mapping: dict[Any, Any] = loader.construct_mapping(node, deep=deep)
    return mapping


class _DuplicateKey(Exception):
    pass


for _loader in (_UniqueKeyLoader, _FastUniqueKeyLoader):
    if _loader is not None:
        _loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def decode_text(raw: bytes, where: str) -> str:
    """The text of a YAML file's bytes ``raw`` (UTF-8, a leading byte-order mark dropped);
    :class:`~mmusv.errors.ConfigError` naming ``where`` for UTF-16/32 (by their byte-order marks), binary (a NUL
    byte) or other non-UTF-8 files, with the offset of the first bad byte."""
    for bom, name in _BOMS.items():
        if raw.startswith(bom):
            raise ConfigError(f"{where}: the file is encoded as {name}; save it as UTF-8")
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]
    nul = raw.find(b"\x00")
    if nul >= 0:
        raise ConfigError(f"{where}: not a text file (a NUL byte at offset {nul}); expected UTF-8 YAML")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        bad = raw[exc.start : exc.start + 1].hex()
        raise ConfigError(
            f"{where}: not UTF-8 text (byte 0x{bad} at offset {exc.start}); save the file as UTF-8"
        ) from None


def parse_yaml(text: str, where: str, *, trusted: bool = False) -> Any:
    """Parses YAML ``text`` (``where`` names it in errors), refusing duplicate keys. ``trusted``: one of mmusv's
    own files (the built-in catalogues), parsed by libyaml's C parser where PyYAML has it; every input a user
    gives goes through the pure-Python parser, which refuses any nesting depth without crashing."""
    try:
        if trusted and _FastUniqueKeyLoader is not None:
            try:
                return yaml.load(text, Loader=_FastUniqueKeyLoader)
            except yaml.YAMLError:
                pass  # refused: again below, for the pure-Python parser's message
        data = yaml.load(text, Loader=_UniqueKeyLoader)
        _check_expansion(data, where)
        return data
    except _DuplicateKey as exc:
        raise ConfigError(f"{where}: {exc}; each key may appear once") from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        problem = " ".join(str(exc.problem or exc.context or "unreadable").split())
        raise ConfigError(f"{where}: not valid YAML{at}: {problem}") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"{where}: not valid YAML: {' '.join(str(exc).split())}") from None
    except RecursionError:
        raise ConfigError(f"{where}: not valid YAML: nested too deeply") from None
    except ValueError as exc:  # an integer of more digits than Python converts (4300)
        what = "an integer of more than 4,300 digits" if "digits" in str(exc) else str(exc)
        raise ConfigError(f"{where}: not valid YAML: {what}; no value of a scenario needs one") from None


def _check_expansion(data: Any, where: str) -> None:
    """Refuses a document that expands to more than :data:`MAX_YAML_VALUES` values, counting a value as often as
    aliases repeat it (PyYAML shares one object per anchor, so the document is small in memory, but everything
    that reads it walks every repetition). Stops counting at the limit."""
    count, stack, seen, aliased = 0, [data], set(), False
    while stack:
        v = stack.pop()
        count += 1
        if count > MAX_YAML_VALUES:
            if aliased:
                raise ConfigError(
                    f"{where}: the document expands to more than {MAX_YAML_VALUES:,} values (aliases repeating "
                    "anchors within anchors); write the values out or use fewer repetitions"
                )
            raise ConfigError(
                f"{where}: the document holds more than {MAX_YAML_VALUES:,} values, more than a YAML file of mmusv "
                "may; split it (fewer vessels or waypoints per scenario)"
            )
        if isinstance(v, (dict, list)):
            if id(v) in seen:  # the same container met again: an alias repeats an anchor
                aliased = True
            seen.add(id(v))
        if isinstance(v, dict):
            stack.extend(v.keys())
            stack.extend(v.values())
        elif isinstance(v, list):
            stack.extend(v)


def read_yaml(path: str | os.PathLike[str], *, kind: str = "YAML") -> Any:
    """Reads and parses the YAML file ``path`` (``kind`` names it in errors: "scenario", "spec", ...)."""
    p = Path(os.fspath(path))
    try:
        p.stat()
    except OSError as exc:  # a name too long, a loop of links, a file below a file: said, not raised as OSError
        if exc.errno not in (errno.ENOENT, errno.ENOTDIR):
            raise ConfigError(f"{kind} file {str(p)!r} cannot be read: {exc.strerror or exc}") from None
    if p.is_dir():
        raise ConfigError(f"{kind} {str(p)!r} is a directory, not a file")
    if not p.is_file():
        if p.exists():  # a FIFO, a socket, a device: "does not exist" was wrong, and reading one may never end
            raise ConfigError(f"{kind} {str(p)!r} is not a regular file (a pipe, socket or device); give a YAML file")
        raise ConfigError(f"{kind} file {str(p)!r} does not exist")
    try:
        size = p.stat().st_size
        if size > MAX_YAML_BYTES:
            raise ConfigError(f"{p}: {size} bytes; a {kind} file may be at most {MAX_YAML_BYTES} bytes")
        raw = p.read_bytes()
    except OSError as exc:
        raise ConfigError(f"{kind} file {str(p)!r} cannot be read: {exc.strerror or exc}") from None
    return parse_yaml(decode_text(raw, str(p)), str(p))


def mapping_source(source: Any, *, kind: str, root_hint: str) -> tuple[dict[str, Any], str]:
    """``(data, where)`` for a path or a dict: the mapping to validate and how errors name it. ``root_hint``
    says what the mapping needs (``"at least `vessels:`"``)."""
    if isinstance(source, dict):
        data: Any = source
        where = kind
    elif isinstance(source, (str, os.PathLike)):
        data = read_yaml(source, kind=kind)
        where = str(Path(os.fspath(source)))
    else:
        raise ConfigError(f"a {kind} is a YAML path, a dict or a validated model, not {type(source).__name__}")
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: a {kind} must be a YAML mapping with {root_hint}")
    return data, where
