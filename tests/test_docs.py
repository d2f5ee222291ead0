"""The documentation stays honest: README.md and docs/**/*.md against the code.

* every ``mmusv ...`` command (in a shell block or inline code) names subcommands and flags the CLI's parser has,
  with values its choices and types take, and every complete command in a shell block parses;
* every ``python scripts/X.py --flag`` (or ``benches/``, ``python -m mmusv...``) names flags that script defines;
* every relative link and picture, and every repository path in inline code, exists;
* every ``mmusv.a.b`` named in the text exists (resolved statically, without importing heavy modules);
* every ```python block compiles and the mmusv names it uses exist, with the keyword arguments it passes;
* the lists and defaults the docs spell out (export formats, topics, sea presets, assets, quality levels, flag
  defaults, the sea YAML examples) equal the code's.

Each checker returns a list of problems; the ``test_checker_catches_*`` tests feed it a doctored copy of a doc
line and require a problem, so that no check passes by checking nothing.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import importlib
import importlib.util
import inspect
import io
import itertools
import re
import shlex
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "python" / "mmusv"
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]

FENCE = re.compile(r"^```([\w-]*)[^\n]*\n(.*?)^```[ \t]*$", re.M | re.S)
SHELL_LANGS = {"bash", "sh", "shell", "console"}
PLACEHOLDER = re.compile(r"^[A-Z][A-Z0-9_]*([.:][A-Za-z0-9_]+)*$|^<[^>]+>$")
"""``DIR``, ``OUT``, ``N``, ``REC.mcap``, ``HOST:PORT``, ``<name>``: a value the reader fills in."""


@dataclass(frozen=True)
class Doc:
    name: str
    text: str


@dataclass(frozen=True)
class Command:
    where: str
    argv: tuple[str, ...]
    block: bool
    """From a shell block (a complete command line) rather than inline code in the text."""


def _docs() -> list[Doc]:
    return [Doc(str(p.relative_to(ROOT)), p.read_text(encoding="utf-8")) for p in DOCS]


def _line(text: str, pos: int) -> int:
    return text.count("\n", 0, pos) + 1


def _blocks(doc: Doc) -> Iterator[tuple[str, str, int]]:
    """(language, body, first line of the body) of each fenced block."""
    for m in FENCE.finditer(doc.text):
        yield m.group(1).lower(), m.group(2), _line(doc.text, m.start(2))


def _prose(text: str) -> str:
    """The text with fenced blocks blanked (newlines kept, so line numbers stay)."""
    return FENCE.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def _inline(doc: Doc) -> Iterator[tuple[str, int]]:
    """Every inline code span of the prose (a span may wrap a line) and its line."""
    prose = _prose(doc.text)
    for m in re.finditer(r"(?<!`)`([^`\n]+(?:\n[^`\n]+)?)`(?!`)", prose):
        yield m.group(1).replace("\n", " "), _line(prose, m.start())


# ---------------------------------------------------------------------------------------------------- commands


def _shell_lines(body: str, first: int) -> Iterator[tuple[str, int]]:
    """The logical lines of a shell block (``\\`` continuations joined) with their first line."""
    buf, start = "", first
    for i, raw in enumerate(body.splitlines()):
        if not buf:
            start = first + i
        if raw.rstrip().endswith("\\"):
            buf += raw.rstrip()[:-1] + " "
            continue
        yield buf + raw, start
        buf = ""
    if buf:
        yield buf, start


def _split_commands(tokens: list[str]) -> Iterator[list[str]]:
    """The simple commands of a token list (split at ``&&``, ``||``, ``;``, ``&``, ``|``), env assignments
    dropped."""
    cur: list[str] = []
    for t in [*tokens, ";"]:
        if t.endswith((";", "&")) and t not in {"&&", ";", "&"}:  # "a;" and "a&" end a command too
            cur.append(t.rstrip(";&"))
            t = ";"
        if t in {"&&", "||", ";", "&", "|"}:
            while cur and re.match(r"^[A-Za-z_]\w*=", cur[0]):
                cur.pop(0)
            if cur:
                yield cur
            cur = []
        else:
            cur.append(t)


def _expand(argv: list[str]) -> Iterator[tuple[str, ...]]:
    """Resolves the docs' shorthands: ``[--dir FOLDER]`` brackets dropped, ``...`` dropped, ``a|b`` (outside
    paths and flags) taken as alternatives, one command each."""
    toks: list[list[str]] = []
    for t in argv:
        t = t.strip("[]")
        if not t or t in {"...", "…"} or t.startswith("..."):
            continue
        alts = t.split("|") if "|" in t and "/" not in t and not t.startswith("-") else [t]
        toks.append(alts)
    for combo in itertools.product(*toks):
        yield tuple(combo)


def commands(doc: Doc, program: str = "mmusv") -> list[Command]:
    """Every invocation of ``program`` in ``doc``: shell blocks and inline code spans that start with it."""
    out: list[Command] = []
    for lang, body, first in _blocks(doc):
        if lang not in SHELL_LANGS:
            continue
        for line, n in _shell_lines(body, first):
            try:
                tokens = shlex.split(line, comments=True)
            except ValueError:
                continue
            for cmd in _split_commands(tokens):
                if cmd[0] == program:
                    out += [Command(f"{doc.name}:{n}", argv[1:], True) for argv in _expand(cmd)]
    for span, n in _inline(doc):
        words = span.split()
        if len(words) < 2 or words[0] != program or not re.match(r"^[a-z][a-z0-9|-]*$", words[1]):
            continue
        try:
            tokens = shlex.split(span, comments=True)
        except ValueError:
            tokens = words
        out += [Command(f"{doc.name}:{n}", argv[1:], False) for argv in _expand(tokens)]
    return out


@cache
def mmusv_parser() -> argparse.ArgumentParser:
    from mmusv.cli import _parser

    return _parser()


def _subparsers(p: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for a in p._actions:
        if isinstance(a, argparse._SubParsersAction):
            return dict(a.choices)
    return {}


def _options(p: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {s: a for a in p._actions for s in a.option_strings}


def _value_problem(action: argparse.Action, value: str) -> str | None:
    """Why ``value`` is not one the option takes (``None``: it is, or it is a placeholder)."""
    if PLACEHOLDER.match(value):
        return None
    if action.choices is not None and value not in action.choices:
        return f"{value!r} is not one of {list(action.choices)}"
    if action.type in (int, float):
        try:
            action.type(value)
        except ValueError:
            return f"{value!r} is not a{'n int' if action.type is int else ' float'}"
    return None


def check_command(cmd: Command, parser: argparse.ArgumentParser) -> list[str]:
    """The problems of one ``mmusv`` command: an unknown subcommand or flag, a value outside an option's choices
    or type, and for a complete command of a shell block, whatever the parser refuses."""
    where = f"{cmd.where}: mmusv {' '.join(cmd.argv)}"
    p, path, rest = parser, ["mmusv"], list(cmd.argv)
    while (subs := _subparsers(p)) and rest and not rest[0].startswith("-"):
        if rest[0] not in subs:
            if PLACEHOLDER.match(rest[0]):
                return []
            return [f"{where}: {' '.join(path)} has no subcommand {rest[0]!r} (it has {sorted(subs)})"]
        path.append(rest.pop(0))
        p = subs[path[-1]]
    if subs and not rest and cmd.block:
        return [f"{where}: {' '.join(path)} needs a subcommand"]
    problems: list[str] = []
    opts = _options(p)
    for i, t in enumerate(rest):
        if not t.startswith("-") or t == "-" or re.match(r"^-\d", t):
            continue
        flag, _, inline_value = t.partition("=")
        if flag not in opts:
            problems.append(f"{where}: {' '.join(path)} has no option {flag!r}")
            continue
        action = opts[flag]
        value = inline_value or (rest[i + 1] if i + 1 < len(rest) and action.nargs != 0 else None)
        if value is not None and not value.startswith("-") and (why := _value_problem(action, value)):
            problems.append(f"{where}: {flag} {why}")
    if cmd.block and not problems:
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err):
                parser.parse_args(list(cmd.argv))
        except SystemExit:
            problems.append(f"{where}: refused by the parser: {err.getvalue().strip().splitlines()[-1]}")
    return problems


# ----------------------------------------------------------------------------------------- scripts' own flags

SCRIPT_SOURCES: dict[str, tuple[str, ...]] = {
    # entries that hand their arguments on: the files whose parsers those are
    "scripts/learn_train.py": ("python/mmusv/learn/train.py", "python/mmusv/learn/infer.py"),
}


def script_commands(doc: Doc) -> list[tuple[str, str, list[str]]]:
    """(where, script path, flags) of every ``python scripts/X.py``, ``benches/X.py`` or ``python -m mmusv.x``
    command in ``doc`` (shell blocks and inline code)."""
    lines: list[tuple[str, int]] = []
    for lang, body, first in _blocks(doc):
        if lang in SHELL_LANGS:
            lines += list(_shell_lines(body, first))
    lines += list(_inline(doc))
    out = []
    for line, n in lines:
        try:
            tokens = shlex.split(line, comments=True)
        except ValueError:
            continue
        for cmd in _split_commands(tokens):
            if cmd and re.match(r"^(?:\S*/)?python3?$", cmd[0]):  # python3, venv/bin/python
                cmd = cmd[1:]
            if len(cmd) >= 2 and cmd[0] == "-m" and cmd[1].startswith("mmusv."):
                script = "python/" + cmd[1].replace(".", "/") + ".py"
            elif cmd and re.match(r"^(scripts|benches)/[\w-]+\.py$", cmd[0]):
                script = cmd[0]
            else:
                continue
            flags = [t.strip("[]").partition("=")[0] for t in cmd if t.strip("[]").startswith("--")]
            out.append((f"{doc.name}:{n}", script, flags))
    return out


def _defined_flags(script: str) -> set[str]:
    flags: set[str] = {"--help"}
    for rel in (script, *SCRIPT_SOURCES.get(script, ())):
        for m in re.finditer(r"add_argument\(\s*((?:\"[^\"]*\"\s*,\s*)+)", (ROOT / rel).read_text(encoding="utf-8")):
            flags.update(re.findall(r"\"(-[^\"]*)\"", m.group(1)))
    return flags


def check_script_command(where: str, script: str, flags: list[str]) -> list[str]:
    if not (ROOT / script).is_file():
        return [f"{where}: {script} does not exist"]
    known = _defined_flags(script)
    return [f"{where}: {script} has no option {f!r}" for f in flags if f not in known]


OTHER_TOOLS_FLAGS = {"--bench", "--release", "--example", "--clock", "--open", "--doc"}
"""Flags of cargo (``cargo bench --bench seacam``, ``cargo doc --open``, ``cargo test --doc``) and ROS 2
(``ros2 bag play --clock``) named in the text."""


@cache
def all_flags() -> frozenset[str]:
    """Every option of every mmusv subcommand, script and bench."""
    flags: set[str] = set(OTHER_TOOLS_FLAGS)

    def walk(p: argparse.ArgumentParser) -> None:
        flags.update(_options(p))
        for sub in _subparsers(p).values():
            walk(sub)

    walk(mmusv_parser())
    for f in [*ROOT.glob("scripts/*.py"), *ROOT.glob("benches/*.py"), *PKG.glob("learn/*.py")]:
        flags |= _defined_flags(str(f.relative_to(ROOT)))
    return frozenset(flags)


def check_bare_flags(doc: Doc) -> list[str]:
    """Every ``--flag`` in the doc's inline code is an option of some mmusv subcommand or script."""
    known = all_flags()
    out = []
    for span, n in _inline(doc):
        for m in re.finditer(r"(?<![\w-])--[a-z][a-z0-9-]*", span):
            if m.group(0) not in known:
                out.append(f"{doc.name}:{n}: no subcommand or script has {m.group(0)!r} (in `{span}`)")
    return out


# ---------------------------------------------------------------------------------------------- links, paths

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
REPO_ROOTS = ("crates/", "python/", "scripts/", "benches/", "tests/", "docs/", "scenarios/", ".ci/")
EXTERNAL_FILES = {"early_fusion_dataset.py", "intermediate_fusion_dataset.py", "late_fusion_dataset.py", "setup.py"}
"""OpenCOOD's files, named in docs/opencood.md (its ``setup.py``: in the ``git archive`` of its checkout)."""


def _braces(s: str) -> list[str]:
    m = re.search(r"\{([^{}]*)\}", s)
    if not m:
        return [s]
    return [x for alt in m.group(1).split(",") for x in _braces(s[: m.start()] + alt + s[m.end() :])]


@cache
def _source_files() -> tuple[str, ...]:
    found = [*ROOT.glob("crates/**/*.rs"), *ROOT.glob("benches/*.rs"), *ROOT.glob("python/**/*.py")]
    found += [*ROOT.glob("scripts/*.py"), *ROOT.glob("benches/*.py"), *ROOT.glob("tests/**/*.py")]
    return tuple("/" + str(p.relative_to(ROOT)) for p in found)


def check_paths(doc: Doc, base: Path) -> list[str]:
    """Relative links and pictures (from the doc's folder ``base``); repository paths in inline code (from the
    root; a Rust module ``x.rs`` may be ``x/mod.rs``); bare source files (``sea/surface.rs``, ``waves.py``) in
    inline code (some file ending so)."""
    problems = []
    prose = _prose(doc.text)
    for m in LINK.finditer(prose):
        target = m.group(1).split("#")[0]
        if not target or re.match(r"^[a-z][a-z0-9+.-]*:", target):
            continue
        if not (base / target).exists():
            problems.append(f"{doc.name}:{_line(prose, m.start())}: link to {target} that does not exist")
    for span, n in _inline(doc):
        for word in span.split():
            word = word.strip(",;()")
            if any(c in word for c in "<>*|…") or "..." in word:
                continue
            for path in _braces(word):
                while path.startswith("../"):
                    path = path[3:]
                if path.startswith(REPO_ROOTS):
                    if not (ROOT / path).exists() and not (ROOT / re.sub(r"\.rs$", "/mod.rs", path)).exists():
                        problems.append(f"{doc.name}:{n}: {path} does not exist")
                elif (
                    re.match(r"^[\w./-]+\.(rs|py)$", path)
                    and not path.startswith(("opencood/", "/"))
                    and path not in EXTERNAL_FILES
                    and not any(f.endswith("/" + path) for f in _source_files())
                ):
                    problems.append(f"{doc.name}:{n}: no source file {path}")
    return problems


# ------------------------------------------------------------------------------------------------ mmusv names

NOT_PYTHON = {"mmusv.WorldState", "mmusv.AgentAnnotations", "mmusv.parts", "mmusv.dataset", "mmusv.vehicles"}
"""Names spelled like modules that are not: the protobuf schemas, the ``format`` of the parts manifest and of
``dataset.json``, the OPV2V extras' YAML key."""


def _module_file(dotted: str) -> Path | None:
    parts = dotted.split(".")[1:]
    base = PKG.joinpath(*parts)
    for cand in (base.with_suffix(".py"), base / "__init__.py"):
        if cand.is_file():
            return cand
    return None


@cache
def _tree(path: Path) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"))


def _bound(body: list[ast.stmt], module: str) -> dict[str, ast.AST | str | None]:
    """Names a module or class body binds: a definition (its node), an import (the dotted name it stands for), an
    assignment (``None``); ``from x import *`` adds the names of x's ``__all__``."""
    names: dict[str, ast.AST | str | None] = {}
    for node in body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names[node.name] = node
        elif isinstance(node, ast.Assign):
            for t in node.targets:
                for n in ast.walk(t):
                    if isinstance(n, ast.Name):
                        names[n.id] = None
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names[node.target.id] = None
        elif isinstance(node, ast.Import):
            for a in node.names:
                names[(a.asname or a.name).split(".")[0]] = a.name if a.asname else a.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom):
            src = node.module or ""
            if node.level:
                src = ".".join(module.split(".")[: len(module.split(".")) - node.level + 1] + ([src] if src else []))
            for a in node.names:
                if a.name == "*":
                    f = _module_file(src) if src.startswith("mmusv") else None
                    if f is not None:
                        names.update(dict.fromkeys(_all_names(f), f"{src}.*"))
                else:
                    names[a.asname or a.name] = f"{src}.{a.name}"
        elif isinstance(node, (ast.If, ast.Try)):
            for sub in (node.body, getattr(node, "orelse", []), *[h.body for h in getattr(node, "handlers", [])]):
                names.update(_bound(sub, module))
    return names


def _all_names(path: Path) -> list[str]:
    for node in _tree(path).body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
            elts = getattr(node.value, "elts", [])
            return [e.value for e in elts if isinstance(e, ast.Constant) and isinstance(e.value, str)]
    return []


def resolve_name(dotted: str) -> bool:
    """Whether ``mmusv.a.b.c`` exists, read from the sources (the native ``mmusv._core`` imported)."""
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        module = ".".join(parts[:i])
        if module == "mmusv._core":
            return _has(importlib.import_module(module), parts[i:])
        f = _module_file(module)
        if f is None:
            continue
        rest = parts[i:]
        scope: dict[str, ast.AST | str | None] = _bound(_tree(f).body, module)
        for j, name in enumerate(rest):
            if name not in scope and _module_file(f"{module}.{name}") is not None and j == 0:
                return resolve_name(".".join([module, *rest]))
            if name not in scope:
                return False
            target = scope[name]
            if isinstance(target, str):
                if target.endswith(".*"):
                    target = f"{target[:-2]}.{name}"
                if target.startswith("mmusv") and target != dotted:
                    return resolve_name(".".join([target, *rest[j + 1 :]]))
                return True
            if isinstance(target, ast.ClassDef):
                scope = _bound(target.body, module)
                continue
            return j == len(rest) - 1
        return True
    return False


def _has(obj: Any, attrs: list[str]) -> bool:
    for a in attrs:
        if not hasattr(obj, a):
            return False
        obj = getattr(obj, a)
    return True


def prose_names(doc: Doc) -> list[tuple[str, int]]:
    """Every ``mmusv.x.y`` in the doc's prose and inline code (not a schema or file name)."""
    prose = _prose(doc.text)
    out = []
    for m in re.finditer(r"(?<![\w./-])mmusv(?:\.[A-Za-z_]\w*)+", prose):
        name = m.group(0)
        if name not in NOT_PYTHON and prose[m.end() : m.end() + 1] not in ("/", "-"):
            out.append((name, _line(prose, m.start())))
    return out


def check_names(doc: Doc) -> list[str]:
    return [f"{doc.name}:{n}: {name} does not exist" for name, n in prose_names(doc) if not resolve_name(name)]


# ------------------------------------------------------------------------------------------- python snippets


def _dotted(node: ast.AST) -> list[str] | None:
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        return [node.id, *reversed(parts)]
    return None


def _returns(func: Any) -> Any:
    """The class a callable returns, where its annotation names one of its module's classes (else ``None``)."""
    if inspect.isclass(func):
        return func
    try:
        ann = inspect.signature(func).return_annotation
    except (TypeError, ValueError):
        return None
    if isinstance(ann, str):
        ann = getattr(func, "__globals__", {}).get(ann.strip("'\""))
    return ann if inspect.isclass(ann) else None


def check_python(code: str, where: str) -> list[str]:
    """Compiles a snippet; resolves its mmusv imports, the attributes it reads off mmusv modules and off values
    of known classes (``x = mmusv.Simulation(...)``: ``x.capture`` must exist), and the keyword arguments of the
    mmusv callables it calls."""
    try:
        tree = ast.parse(code)
    except SyntaxError as exc:
        return [f"{where}: does not compile: {exc}"]
    problems: list[str] = []
    env: dict[str, Any] = {}  # name -> module, callable or class (a value of that class: ("instance", cls))

    def lookup(node: ast.AST) -> Any:
        if isinstance(node, ast.Call):
            f = lookup(node.func)
            return ("instance", _returns(f)) if f is not None and _returns(f) is not None else None
        parts = _dotted(node)
        if parts is None or parts[0] not in env:
            return None
        obj = env[parts[0]]
        for i, a in enumerate(parts[1:], 1):
            cls = obj[1] if isinstance(obj, tuple) else None
            holder = cls if cls is not None else obj
            if not hasattr(holder, a):
                annotations = getattr(cls, "__annotations__", {}) if cls is not None else {}
                fields = getattr(cls, "__dataclass_fields__", {}) if cls is not None else {}
                if a in annotations or a in fields or a in getattr(cls, "__slots__", ()):
                    return None
                problems.append(f"{where}: {'.'.join(parts[:i])} has no attribute {a!r}")
                return None
            obj = getattr(holder, a)
            if cls is not None:
                obj = ("method", obj)
        return obj[1] if isinstance(obj, tuple) and obj[0] == "method" else obj

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "mmusv":
                    env[(a.asname or a.name).split(".")[0]] = importlib.import_module(
                        a.name if a.asname else a.name.split(".")[0]
                    )
        elif isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "mmusv":
            mod = importlib.import_module(node.module or "")
            for a in node.names:
                if not hasattr(mod, a.name):
                    problems.append(f"{where}: {node.module} has no {a.name!r}")
                else:
                    env[a.asname or a.name] = getattr(mod, a.name)
    for stmt in tree.body:
        for node in ast.walk(stmt):
            if isinstance(node, ast.Call):
                f = lookup(node.func)
                if callable(f) and node.keywords:
                    try:
                        sig = inspect.signature(f)
                    except (TypeError, ValueError):
                        continue
                    params = sig.parameters
                    if not any(p.kind is p.VAR_KEYWORD for p in params.values()):
                        for kw in node.keywords:
                            if kw.arg is not None and kw.arg not in params:
                                problems.append(f"{where}: {ast.unparse(node.func)}() takes no argument {kw.arg!r}")
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Load):
                lookup(node)
        if isinstance(stmt, ast.Assign) and len(stmt.targets) == 1 and isinstance(stmt.targets[0], ast.Name):
            value = lookup(stmt.value)
            if value is not None:
                env[stmt.targets[0].id] = value
    return list(dict.fromkeys(problems))


def python_blocks(doc: Doc) -> list[tuple[str, str]]:
    return [(body, f"{doc.name}:{n}") for lang, body, n in _blocks(doc) if lang in {"python", "py"}]


# --------------------------------------------------------------------------------------------------- the tests


def test_every_mmusv_command_in_the_docs_is_one_the_cli_takes() -> None:
    parser = mmusv_parser()
    cmds = [c for d in _docs() for c in commands(d)]
    assert len(cmds) > 100 and sum(c.block for c in cmds) > 40  # the extraction found the docs' commands
    problems = [p for c in cmds for p in check_command(c, parser)]
    assert not problems, "\n".join(problems)


def test_every_script_command_in_the_docs_names_its_flags() -> None:
    found = [s for d in _docs() for s in script_commands(d)]
    assert len(found) > 10
    problems = [p for where, script, flags in found for p in check_script_command(where, script, flags)]
    assert not problems, "\n".join(problems)


def test_every_flag_named_in_the_text_exists() -> None:
    problems = [p for d in _docs() for p in check_bare_flags(d)]
    assert not problems, "\n".join(problems)


def test_links_pictures_and_repository_paths_exist() -> None:
    problems = [p for path, d in zip(DOCS, _docs(), strict=True) for p in check_paths(d, path.parent)]
    assert not problems, "\n".join(problems)


def test_every_mmusv_name_in_the_text_exists() -> None:
    docs = _docs()
    assert sum(len(prose_names(d)) for d in docs) > 50
    problems = [p for d in docs for p in check_names(d)]
    assert not problems, "\n".join(problems)


def test_python_snippets_compile_and_use_names_that_exist() -> None:
    blocks = [b for d in _docs() for b in python_blocks(d)]
    assert len(blocks) >= 3  # README (run and capture, the core) and docs/recording.md
    problems = [p for code, where in blocks for p in check_python(code, where)]
    assert not problems, "\n".join(problems)


def _doc(name: str) -> str:
    return (ROOT / name).read_text(encoding="utf-8")


def test_export_formats_are_the_codes() -> None:
    from mmusv.export.common import TARGETS

    table = _doc("docs/exports.md").split("| `--to` | for |", 1)[1].split("\n\n", 1)[0]
    rows = re.findall(r"^\| `(\w+)`(?: \(default\))? \|", table, re.M)
    assert tuple(rows) == TARGETS
    assert "| `opv2v` (default) |" in _doc("docs/exports.md")
    assert _options(_subparsers(mmusv_parser())["convert"])["--to"].default == "opv2v"


def test_recording_topics_are_the_codes() -> None:
    from mmusv.recording import topics
    from mmusv.sensors.config import _TOP_OUTPUTS

    line = re.search(r"Spelled in `mmusv.recording.topics`: (.*?)\n\n", _doc("docs/recording.md"), re.S)
    assert line is not None
    documented = set()
    for pattern in re.findall(r"`([^`]+)`", line.group(1)):
        m = re.match(r"^(.*)\{([a-z|_]+)\}$", pattern)
        documented |= {m.group(1) + k for k in m.group(2).split("|")} if m else {pattern}
    a, c = "{agent}", "{name}"
    expected = {topics.TF, topics.WORLD_STATE, topics.lidar(a), topics.radar_returns(a), topics.radar_ppi(a)}
    expected |= {
        topics.boxes(a),
        topics.agent_annotations(a),
        topics.camera_calibration(a, c),
        topics.camera_boxes(a, c),
    }
    expected |= {topics.camera(a, c, kind=k) for k in topics.CAMERA_KINDS} | {
        topics.top_view(a, k) for k in _TOP_OUTPUTS
    }
    assert documented == expected


def test_recording_tables_are_the_codes() -> None:
    from mmusv.acquire import TABLE_PART_FRAMES
    from mmusv.recording.tables import SCHEMAS

    text = _doc("docs/recording.md")
    m = re.search(r"`tables/\{([\w,]+)\}/part-NNNNN\.parquet`", text)
    assert m is not None and set(m.group(1).split(",")) == set(SCHEMAS)
    assert f"a part every {TABLE_PART_FRAMES} frames" in text


def test_sea_presets_table_is_the_cores() -> None:
    import mmusv._core as core

    rows = {}
    for m in re.finditer(r"^\| (W?\d) \| ([^|]+) \| ([\d.]+) \| ([\d.–]+) \| ([\d.]+) \|$", _doc("docs/sea.md"), re.M):
        rows[m.group(1)] = (float(m.group(3)), m.group(4), float(m.group(5)))
    presets = {name: (hs, tp, wind) for name, _, hs, tp, _gamma, wind in core.sea_presets()}
    assert set(rows) == set(presets)
    for name, (hs, tp, wind) in presets.items():
        doc_hs, doc_tp, doc_wind = rows[name]
        assert doc_hs == pytest.approx(hs, abs=5e-4), name
        assert doc_tp == ("–" if hs == 0 else f"{tp:.1f}"), name
        assert doc_wind == pytest.approx(round(wind, 1)), name


def test_sea_yaml_examples_are_valid_scenario_environments() -> None:
    from mmusv.config import EnvironmentConfig, SeaConfig

    blocks = [body for lang, body, _ in _blocks(Doc("docs/sea.md", _doc("docs/sea.md"))) if lang == "yaml"]
    assert len(blocks) >= 3
    for body in blocks:
        env = EnvironmentConfig.model_validate(yaml.safe_load(body)["environment"])
        assert env.motion == "physical"
        for key, default in re.findall(r"^\s+(\w+):.*\(default ([\d.]+)", body, re.M):
            assert float(SeaConfig.model_fields[key].default) == float(default), key
    assert EnvironmentConfig.model_fields["motion"].default == "physical"


def test_assets_table_is_the_catalogue() -> None:
    catalogue = yaml.load((PKG / "world/vessel_catalog.yaml").read_text(encoding="utf-8"), Loader=yaml.CSafeLoader)
    names = [v["name"] for v in catalogue["vessels"]]
    text = _doc("docs/assets.md")
    assert sorted(re.findall(r"^\| `(\w+)` \|", text, re.M)) == sorted(names)
    assert f"The {len(names)} built-in assets" in text
    assert f"Vessel library ({len(names)} assets" in _doc("README.md")


def test_quality_levels_and_rig_presets_are_the_codes() -> None:
    from typing import get_args

    from mmusv.sensors.config import RIG_PRESETS, CameraConfig, Quality

    readme = _doc("README.md")
    assert get_args(Quality) == ("draft", "standard", "high")
    assert CameraConfig.model_fields["quality"].default == "standard"
    assert "(`draft`: one sample per pixel" in readme and "`standard`, the default:" in readme
    assert "`high`: reflections for every pixel" in readme
    assert set(RIG_PRESETS) == {"full", "lidar_only"} and "{preset: lidar_only}" in readme


DEFAULTS: list[tuple[str, str, tuple[str, ...], str, Any]] = [
    # (doc, the words there, subcommand path, option, the parser's default those words state)
    (
        "docs/exports.md",
        "`--split train,validate,test` (default `0.7,0.15,0.15`)",
        ("convert",),
        "--split",
        "0.7,0.15,0.15",
    ),
    ("docs/exports.md", "`--seed` (default 0)", ("convert",), "--seed", 0),
    ("docs/exports.md", "`--min-box-px` (default 0)", ("convert",), "--min-box-px", 0),
    ("docs/exports.md", "`--max-occlusion` (default 1)", ("convert",), "--max-occlusion", 1),
    ("docs/exports.md", "`--min-contrast C` (default: none", ("convert",), "--min-contrast", None),
    ("docs/exports.md", "`--box visible` (the default)", ("convert",), "--box", "visible"),
    ("docs/opencood.md", "`mmusv convert --range`, 200 m", ("convert",), "--range", 200),
    ("README.md", "`http://127.0.0.1:8765/`", ("editor",), "--port", 8765),
    ("README.md", "`http://127.0.0.1:8765/`", ("editor",), "--host", "127.0.0.1"),
    ("README.md", "(`--jobs N`, the default)", ("run",), "--jobs", 1),
    ("README.md", "`--retries N` re-runs failed tasks", ("run",), "--retries", 0),
    ("docs/studies/detection.md", "within 200 m (`--range`)", ("study", "detection"), "--range", 200),
    ("docs/studies/detection.md", "(`--late-merge nms`, the default)", ("study", "detection"), "--late-merge", "nms"),
    ("docs/studies/detection.md", "any recordings (default split: all)", ("study", "detection"), "--split", None),
    ("docs/studies/detection.md", "--preset cpu -o out/learned      # train split", ("train",), "--split", "train"),
    ("docs/studies/detection.md", "(`--jobs`, default one per model", ("train",), "--jobs", "auto"),
    ("docs/sea.md", "(`mmusv study waves` uses it by default)", ("study", "waves"), "--motion", "paper"),
    (
        "docs/exports.md",
        "(by default `depth,semantic,radar,top_view`:",
        ("convert",),
        "--extras",
        "depth,semantic,radar,top_view",
    ),
]


@pytest.mark.parametrize(("doc", "words", "path", "option", "default"), DEFAULTS)
def test_documented_defaults_are_the_parsers(
    doc: str, words: str, path: tuple[str, ...], option: str, default: Any
) -> None:
    assert words in _doc(doc).replace("\n", " ")
    p = mmusv_parser()
    for name in path:
        p = _subparsers(p)[name]
    assert _options(p)[option].default == default


# ----------------------------------------------------------------------- each checker catches a wrong doc line


def _doctored(name: str, old: str, new: str) -> Doc:
    text = _doc(name)
    assert old in text, f"{old!r} is no longer in {name}: pick another line for this check"
    return Doc(name, text.replace(old, new, 1))


def test_checker_catches_a_bogus_flag_subcommand_or_value() -> None:
    parser = mmusv_parser()
    cases = [
        ("--frame 10", "--frame 10 --bogus-flag"),  # a flag no subcommand has, in a shell block
        ("mmusv info out/island", "mmusv infos out/island"),  # a subcommand that does not exist
        ("--motion physical", "--motion wild"),  # a value outside the choices
        ("--frame 5", "--frame five"),  # a value of the wrong type
    ]
    for old, new in cases:
        doc = _doctored("README.md", old, new)
        problems = [p for c in commands(doc) for p in check_command(c, parser)]
        assert problems, f"{new!r} was not caught"
    inline = _doctored(
        "docs/exports.md", "`mmusv convert REC [REC ...] --to FORMAT -o DIR`", "`mmusv convert REC --too X`"
    )
    assert [p for c in commands(inline) for p in check_command(c, parser)]
    # a complete command the parser refuses although every flag exists: a missing required value
    doc = _doctored("docs/studies/detection.md", "--split test -o out/rob\n", "--split test -o\n")
    assert [p for c in commands(doc) for p in check_command(c, parser)]


def test_checker_catches_a_bogus_script_flag() -> None:
    doc = _doctored(
        "docs/realism/README.md", "--label after --only dusk_series", "--label after --only-one dusk_series"
    )
    problems = [p for s in script_commands(doc) for p in check_script_command(*s)]
    assert problems and "--only-one" in problems[0]


def test_checker_catches_a_bogus_bare_flag() -> None:
    assert not check_bare_flags(Doc("x.md", "`--split-frames N` and `--cpus-per-task`"))
    doc = _doctored("README.md", "`--retries N` re-runs failed tasks", "`--retry N` re-runs failed tasks")
    assert check_bare_flags(doc)


def test_checker_catches_a_missing_link_picture_or_path() -> None:
    base = ROOT / "docs/realism"
    for old, new in [
        ("(mitsuba_spheres.png)", "(mitsuba_spherez.png)"),
        ("`tests/reference/mitsuba_scenes.py`", "`tests/reference/mitsuba_scene.py`"),
        ("(`sensors/camera/glossy.rs`)", "(`sensors/camera/glosy.rs`)"),
    ]:
        assert check_paths(_doctored("docs/realism/mitsuba.md", old, new), base), f"{new!r} was not caught"


def test_checker_catches_a_name_that_does_not_exist() -> None:
    doc = _doctored("docs/recording.md", "`mmusv.recording.guard.write_cause`", "`mmusv.recording.guard.write_causes`")
    assert check_names(doc)
    doc = _doctored("docs/recording.md", "`mmusv.recording.tables.read_table`", "`mmusv.recordings.tables.read_table`")
    assert check_names(doc)
    assert resolve_name("mmusv.Simulation.capture") and not resolve_name("mmusv.Simulation.capture_all")
    assert resolve_name("mmusv.MmusvError") and resolve_name("mmusv._core.sea_presets")


def test_checker_catches_a_wrong_python_snippet() -> None:
    (code, where), *_ = python_blocks(Doc("docs/recording.md", _doc("docs/recording.md")))
    assert not check_python(code, where)
    for old, new in [
        ("read_messages, summary", "read_message, summary"),  # an import that does not exist
        ('topics=["/world/state"]', 'topic=["/world/state"]'),  # a keyword the function does not take
        ("print(topic", "print(topic"),  # unchanged: must stay clean (control)
    ]:
        problems = check_python(code.replace(old, new), where)
        assert bool(problems) == (old != new), (new, problems)
    readme = python_blocks(Doc("README.md", _doc("README.md")))
    code, where = next(b for b in readme if "Simulation" in b[0])
    assert not check_python(code, where)
    assert check_python(code.replace("sim.prefetch_frame(8)", "sim.prefetch(8)"), where)  # a method of a value
    assert check_python(code.replace('out_dir="out/port"', 'output="out/port"'), where)
    assert check_python("import mmusv\nmmusv.Simulation(\n", where)  # does not compile


def test_checker_catches_a_wrong_sea_yaml_example() -> None:
    from mmusv.config import EnvironmentConfig

    with pytest.raises(ValueError, match="not both"):
        EnvironmentConfig.model_validate({"wave": "W2", "sea": {"state": 5}})


def test_the_asset_page_is_what_its_generator_writes() -> None:
    """``docs/assets.md`` says "Generated by scripts/asset_table.py; do not edit by hand": a paragraph added to the
    page alone (the Draco and required-extensions one was) would be lost the next time the page is regenerated."""
    spec = importlib.util.spec_from_file_location("asset_table", ROOT / "scripts" / "asset_table.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.table() == (ROOT / "docs" / "assets.md").read_text(encoding="utf-8")
