"""The one reader of every YAML input mmusv takes: scenarios, generation specs, rigs, asset catalogues.

:func:`read_yaml` turns a file into plain Python data, or raises :class:`mmusv.ConfigError` naming the file and
what is wrong, never a ``UnicodeDecodeError`` or a bare parser error:

* bytes are decoded as UTF-8 (a UTF-8 byte-order mark is accepted); UTF-16/32 files (as some Windows editors
  save them), Latin-1 text and binary files are refused with the byte offset of the first bad byte;
* duplicate keys in a mapping are refused, naming the key and both lines (the YAML spec forbids them, and
  PyYAML would silently keep the last one: two ``vessels:`` blocks would drop the first fleet);
* syntax errors name the line and column;
* the numbers only YAML 1.1 has are refused, naming the field, its line and column, the text as written, what YAML
  1.1 reads it as and what to write instead: an unquoted ``seed: 017`` is octal (15), ``frames: 1:0`` and
  ``time_of_day: 13:00`` base 60 (60, 780), ``0b11`` binary (3) and ``0x1F`` hexadecimal (31), which YAML 1.2
  and most other readers take otherwise (as text, or 17), and which nobody writing a seed or a frame count means.
  Integers are written in decimal (``17``, ``-60``, ``1_000``), floats as decimals (``0.5``, ``-1.5``,
  ``1.0e+3``, ``.inf``); a time, a version or any text that looks like one of these numbers goes in quotes;
* so are the booleans only YAML 1.1 has: an unquoted ``name: off`` or ``weather: no`` is read as false (YAML 1.2
  and most other readers take it as text), which a scenario's text fields then refused as "not a valid string"
  without saying why; booleans are written ``true`` and ``false``.

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
    """PyYAML's safe loader, refusing duplicate keys in any mapping and the numbers only YAML 1.1 has, and bounding
    what merge keys copy (:func:`_flatten_mapping`)."""

    def flatten_mapping(self, node: yaml.MappingNode) -> None:
        _flatten_mapping(self, node)


# The same on libyaml's C parser where PyYAML was built with it (its wheels are): the same documents, ten times
# faster (the built-in vessel catalogue, 74 kB, parses in 0.05 s instead of 0.58 s at every start), but only for
# mmusv's own files (`parse_yaml(trusted=True)`): it composes nested nodes by recursion on the C stack, and a
# hostile document nested 100,000 deep crashes the process, where the pure-Python parser refuses it ("nested too
# deeply"). A document it refuses is parsed again by the pure-Python parser, whose messages say more.
_CSafeLoader: Any = getattr(yaml, "CSafeLoader", None)
_FastUniqueKeyLoader: Any = (
    None
    if _CSafeLoader is None
    else type(
        "_FastUniqueKeyLoader",
        (_CSafeLoader,),
        {"__doc__": _UniqueKeyLoader.__doc__, "flatten_mapping": _UniqueKeyLoader.flatten_mapping},
    )
)


def _construct_mapping(loader: Any, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
    if not isinstance(node, yaml.MappingNode):  # `!!map [1, 2]`: its items were unpacked as pairs (a TypeError)
        raise yaml.constructor.ConstructorError(
            None, None, f"expected a mapping node, but found {node.id} (tagged !!map)", node.start_mark
        )
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


def _flatten_mapping(loader: Any, node: yaml.MappingNode) -> None:
    """PyYAML's ``flatten_mapping`` (the entries of merge keys, ``<<: *base`` or ``<<: [*a, *b]``, copied into the
    mapping, the first listed winning), counting the entries copied in the whole document: each mapping that merges
    another holds a copy of its entries, so a few hundred bytes of merges of merges (``<<: [*a, *a, *a, *a]`` ten
    deep) copied millions of entries (a minute and gigabytes, 4 times more for each level), though the mapping they
    make has a few keys. Past :data:`MAX_YAML_VALUES` entries :class:`_MergeBomb` stops it, before copying them."""
    merge: list[tuple[yaml.Node, yaml.Node]] = []
    index = 0
    while index < len(node.value):
        key_node, value_node = node.value[index]
        if key_node.tag == "tag:yaml.org,2002:merge":
            del node.value[index]
            if isinstance(value_node, yaml.MappingNode):
                subnodes = [value_node]
            elif isinstance(value_node, yaml.SequenceNode):
                subnodes = list(value_node.value)
            else:
                raise yaml.constructor.ConstructorError(
                    "while constructing a mapping",
                    node.start_mark,
                    f"expected a mapping or list of mappings for merging, but found {value_node.id}",
                    value_node.start_mark,
                )
            for subnode in subnodes:
                if not isinstance(subnode, yaml.MappingNode):
                    raise yaml.constructor.ConstructorError(
                        "while constructing a mapping",
                        node.start_mark,
                        f"expected a mapping for merging, but found {subnode.id}",
                        subnode.start_mark,
                    )
                _flatten_mapping(loader, subnode)
            for subnode in reversed(subnodes):
                copied = getattr(loader, "_mmusv_merged", 0) + len(subnode.value)
                if copied > MAX_YAML_VALUES:
                    raise _MergeBomb(node.start_mark)
                loader._mmusv_merged = copied
                merge.extend(subnode.value)
        elif key_node.tag == "tag:yaml.org,2002:value":
            key_node.tag = "tag:yaml.org,2002:str"
            index += 1
        else:
            index += 1
    if merge:
        node.value = merge + node.value


class _MergeBomb(Exception):
    """The merge keys of a document copy more than :data:`MAX_YAML_VALUES` entries (:func:`_flatten_mapping`)."""

    def __init__(self, mark: yaml.Mark) -> None:
        super().__init__(mark)
        self.mark = mark


class _DuplicateKey(Exception):
    pass


class _Yaml11Number(Exception):
    """A number written in a form only YAML 1.1 reads as a number (:func:`_yaml11_kind`), or a boolean only YAML
    1.1 reads as one (``yes``, ``no``, ``on``, ``off``: kind ``"boolean"``); ``path`` is filled in by :func:`_load`
    once the node is found in the document."""

    def __init__(self, node: yaml.ScalarNode, kind: str, value: int | float) -> None:
        super().__init__(node.value)
        self.node, self.kind, self.value = node, kind, value
        self.path: tuple[str, str | None, bool] = ("", None, False)


def _yaml11_kind(text: str, *, integer: bool) -> str | None:
    """What YAML-1.1-only number the plain scalar ``text`` (resolved as an integer when ``integer``, else as a
    float) is written as: ``"base-60"`` (``1:20``, ``13:00``, ``1:20.5``), ``"octal"`` (``017``), ``"binary"``
    (``0b11``) or ``"hexadecimal"`` (``0x1F``); None for a decimal number."""
    body = text.replace("_", "").lstrip("+-")
    if ":" in body:
        return "base-60"
    if not integer:
        return None
    low = body.lower()
    if low.startswith("0b"):
        return "binary"
    if low.startswith("0x"):
        return "hexadecimal"
    if len(body) > 1 and body.startswith("0"):
        return "octal"
    return None


def _construct_int(loader: Any, node: yaml.ScalarNode) -> int:
    value: int = yaml.constructor.SafeConstructor.construct_yaml_int(loader, node)
    kind = _yaml11_kind(str(node.value), integer=True)
    if kind is not None:
        raise _Yaml11Number(node, kind, value)
    return value


def _construct_float(loader: Any, node: yaml.ScalarNode) -> float:
    value: float = yaml.constructor.SafeConstructor.construct_yaml_float(loader, node)
    kind = _yaml11_kind(str(node.value), integer=False)
    if kind is not None:
        raise _Yaml11Number(node, kind, value)
    return value


def _construct_bool(loader: Any, node: yaml.ScalarNode) -> bool:
    value: bool = yaml.constructor.SafeConstructor.construct_yaml_bool(loader, node)
    if str(node.value).lower() not in ("true", "false"):  # yes, no, on, off: booleans in YAML 1.1 only
        raise _Yaml11Number(node, "boolean", value)
    return value


for _loader in (_UniqueKeyLoader, _FastUniqueKeyLoader):
    if _loader is not None:
        _loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)
        _loader.add_constructor("tag:yaml.org,2002:int", _construct_int)
        _loader.add_constructor("tag:yaml.org,2002:float", _construct_float)
        _loader.add_constructor("tag:yaml.org,2002:bool", _construct_bool)


def _load(text: str, loader_class: Any) -> Any:
    """``yaml.load(text, Loader=loader_class)``, keeping the document's nodes so that a refused number can be named
    by the field it is written in."""
    loader = loader_class(text)
    try:
        root = loader.get_single_node()
        if root is None:
            return None
        try:
            return loader.construct_document(root)
        except _Yaml11Number as exc:
            exc.path = _node_path(root, exc.node)
            raise
    finally:
        loader.dispose()


def _node_path(root: yaml.Node, target: yaml.Node) -> tuple[str, str | None, bool]:
    """``(path, last key, is a key)`` of ``target`` in the document ``root``: ``("vessels[0].route[1][0]",
    "route", False)``, ``("environment.time_of_day[0]", "time_of_day", False)``; a mapping key is named by the path
    of its mapping (``("rigs", "rigs", True)``); ``("", None, False)`` for the root or a node not found. Depth first
    in document order, each node once (an anchor is found where it is written, however often aliases repeat it)."""
    stack: list[tuple[yaml.Node, str, str | None]] = [(root, "", None)]
    seen: set[int] = set()
    while stack:
        node, path, key = stack.pop()
        if node is target:
            return path, key, False
        if id(node) in seen:
            continue
        seen.add(id(node))
        children: list[tuple[yaml.Node, str, str | None]] = []
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                name = str(k.value) if isinstance(k, yaml.ScalarNode) else "?"
                if k is target:
                    return path, key, True
                children.append((v, f"{path}.{name}" if path else name, name))
        elif isinstance(node, yaml.SequenceNode):
            children = [(v, f"{path}[{i}]", key) for i, v in enumerate(node.value)]
        stack.extend(reversed(children))
    return "", None, False


def _yaml11_message(exc: _Yaml11Number) -> str:
    """The explanation of a refused YAML-1.1-only number (:class:`_Yaml11Number`)."""
    mark = exc.node.start_mark
    text = str(exc.node.value)
    path, key, is_key = exc.path
    if is_key:
        what = f"the key {text} of {path}" if path else f"the key {text}"
    else:
        what = f"{path} = {text}" if path else text
    at = f"{what} at line {mark.line + 1}, column {mark.column + 1}"
    if exc.kind == "boolean":
        return (
            f"{at} is a boolean in YAML 1.1, which reads it as {str(exc.value).lower()}; write true or false or, if "
            f'it is text, put it in quotes ("{text}")'
        )
    if key == "time_of_day":
        example = f'"{text}"' if exc.kind == "base-60" else '"16:30"'
        return (
            f'{at}: use 24-hour "HH:MM" in quotes, e.g. {example} (unquoted, YAML reads it as the number {exc.value})'
        )
    if exc.kind == "octal":
        sign = "-" if text.startswith("-") else ""
        digits = text.replace("_", "").lstrip("+-").lstrip("0") or "0"
        instead = f"without the leading zero ({sign}{digits})"
    else:
        instead = f"in decimal ({exc.value})"
    article = "an" if exc.kind == "octal" else "a"
    return (
        f"{at} is {article} {exc.kind} number in YAML 1.1, which reads it as {exc.value}; write the number {instead} "
        f'or, if it is text, put it in quotes ("{text}")'
    )


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
                return _load(text, _FastUniqueKeyLoader)
            except yaml.YAMLError:
                pass  # refused: again below, for the pure-Python parser's message
        data = _load(text, _UniqueKeyLoader)
        _check_expansion(data, where)
        return data
    except _MergeBomb as exc:
        raise ConfigError(
            f"{where}: the merge keys (<<) at line {exc.mark.line + 1} copy more than {MAX_YAML_VALUES:,} entries "
            "(merges of mappings that merge others, repeated); write the values out or merge fewer times"
        ) from None
    except _DuplicateKey as exc:
        raise ConfigError(f"{where}: {exc}; each key may appear once") from None
    except _Yaml11Number as exc:
        raise ConfigError(f"{where}: {_yaml11_message(exc)}") from None
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
