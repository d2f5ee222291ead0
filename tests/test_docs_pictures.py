"""The picture pages read as a reader reads them: every embedded picture is an image file the page reaches and has
alt text, every commit a page quotes is one of this repository's, and every view a picture script is told to
render (``--only VIEW``) is one the script has.

``tests/test_docs.py`` already checks that links resolve and that script flags exist; these checks add what a
picture page needs beyond that. Each ``test_checker_catches_...`` test breaks a copy of a page on purpose and
shows the check failing on it.
"""

from __future__ import annotations

import re
import shlex
import subprocess
from functools import cache
from pathlib import Path

import pytest
from test_docs import DOCS, ROOT, SHELL_LANGS, Doc, _blocks, _docs, _doctored, _inline, _prose, _shell_lines

IMAGE = re.compile(r"!\[([^\]]*)\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
MAGIC = (b"\x89PNG\r\n\x1a\n", b"\xff\xd8\xff", b"GIF87a", b"GIF89a", b"<svg", b"<?xml")
HASH = re.compile(r"(?<![\w./#@-])([0-9a-f]{7,40})(?!\w)")
EXTERNAL_COMMITS = {"31ba160", "96812ed"}
"""Commits of other repositories the docs quote: OpenCOOD's and HEAL's, in docs/opencood.md."""


def _base(doc: Doc) -> Path:
    return (ROOT / doc.name).parent


def picture_problems(doc: Doc, base: Path | None = None) -> list[str]:
    """Each ``![alt](file)``: alt text given, the file there (from the page's folder, or ``base``) and an image,
    not a pointer."""
    base = _base(doc) if base is None else base
    out = []
    prose = _prose(doc.text)
    for m in IMAGE.finditer(prose):
        alt, target = m.group(1).strip(), m.group(2).split("#")[0]
        where = f"{doc.name}:{prose.count(chr(10), 0, m.start()) + 1}"
        if re.match(r"^[a-z][a-z0-9+.-]*:", target):
            continue
        if not alt:
            out.append(f"{where}: picture {target} has no alt text")
        path = base / target
        if not path.is_file():
            out.append(f"{where}: picture {target} does not exist (from the page's folder)")
        elif not path.read_bytes()[:16].lstrip().startswith(MAGIC):
            out.append(f"{where}: {target} is not an image (a Git LFS pointer, or text?)")
    return out


def _git(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True, check=False)


@cache
def _full_history() -> bool:
    try:
        r = _git("rev-parse", "--is-shallow-repository")
    except OSError:
        return False
    return r.returncode == 0 and r.stdout.strip() == "false"


def quoted_commits(doc: Doc) -> list[tuple[str, int]]:
    """Hex words of 7–40 digits with a letter and a digit in the page's prose and inline code (not its code
    blocks, not inside paths, URLs or anchors)."""
    prose = _prose(doc.text)
    found = []
    for m in HASH.finditer(prose):
        h = m.group(1)
        if re.search("[a-f]", h) and re.search("[0-9]", h) and h not in EXTERNAL_COMMITS:
            found.append((h, prose.count("\n", 0, m.start()) + 1))
    return found


def commit_problems(doc: Doc) -> list[str]:
    return [
        f"{doc.name}:{n}: commit {h} is not in this repository's history"
        for h, n in quoted_commits(doc)
        if _git("cat-file", "-e", f"{h}^{{commit}}").returncode != 0
    ]


def _commands(doc: Doc) -> list[tuple[str, int]]:
    lines: list[tuple[str, int]] = []
    for lang, body, first in _blocks(doc):
        if lang in SHELL_LANGS:
            lines += list(_shell_lines(body, first))
    return lines + list(_inline(doc))


def only_problems(doc: Doc) -> list[str]:
    """``scripts/X.py ... --only A B`` or ``--only A,B``: each view is a string the script names (a choice, or a
    key of its table of parts)."""
    out = []
    for line, n in _commands(doc):
        try:
            tokens = shlex.split(line, comments=True)
        except ValueError:
            continue
        script = next((t for t in tokens if re.fullmatch(r"scripts/[\w-]+\.py", t)), None)
        if script is None or "--only" not in tokens:
            continue
        if not (ROOT / script).is_file():
            continue  # test_docs.py reports the missing script
        text = (ROOT / script).read_text(encoding="utf-8")
        i = tokens.index("--only") + 1
        while i < len(tokens) and not tokens[i].startswith("-"):
            for view in filter(None, tokens[i].strip(",;").split(",")):
                if f'"{view}"' not in text:
                    out.append(f"{doc.name}:{n}: {script} has no view {view!r} for --only")
            i += 1
    return out


# ------------------------------------------------------------------------------------------------------- tests


def test_every_picture_is_an_image_with_alt_text() -> None:
    docs = _docs()
    assert sum(len(IMAGE.findall(_prose(d.text))) for d in docs) > 40  # the extraction finds the pages' pictures
    problems = [p for d in docs for p in picture_problems(d)]
    assert not problems, "\n".join(problems)


def test_every_quoted_commit_exists() -> None:
    if not _full_history():
        pytest.skip("needs the repository's full git history")
    docs = _docs()
    quoted = sum(len(quoted_commits(d)) for d in docs)
    assert quoted > 50
    problems = [p for d in docs for p in commit_problems(d)]
    if len(problems) > quoted // 2:  # a clone whose history was rewritten (squashed, filtered): not the docs' fault
        pytest.skip(f"{len(problems)} of {quoted} quoted commits are missing: not this repository's own history")
    assert not problems, "\n".join(problems)


def test_every_picture_script_view_exists() -> None:
    docs = _docs()
    assert sum(1 for d in docs for line, _ in _commands(d) if "--only" in line) >= 6
    problems = [p for d in docs for p in only_problems(d)]
    assert not problems, "\n".join(problems)


def test_the_pages_are_the_docs_walked() -> None:
    names = {str(p.relative_to(ROOT)) for p in DOCS}
    assert {"README.md", "docs/realism/README.md", "docs/sea/README.md", "docs/realism/mitsuba.md"} <= names


# ---------------------------------------------------------------------------------------- on a broken copy


def test_checker_catches_a_missing_or_unlabelled_picture(tmp_path: Path) -> None:
    doc = _doctored("docs/realism/README.md", "(tug_30m_after.png)", "(tug_30m_aftr.png)")
    assert any("tug_30m_aftr.png does not exist" in p for p in picture_problems(doc))
    doc = _doctored("docs/sea/README.md", "![LiDAR side view](craft_w3_lidar.png)", "![](craft_w3_lidar.png)")
    assert any("no alt text" in p for p in picture_problems(doc))
    # a path that resolves from the repository root but not from the page's folder
    doc = _doctored("docs/sea/README.md", "(lidar_wake.png)", "(docs/sea/lidar_wake.png)")
    assert any("docs/sea/lidar_wake.png does not exist" in p for p in picture_problems(doc))
    # a picture that is there but is not an image (what a checkout without Git LFS leaves)
    (tmp_path / "pointer.png").write_text("version https://git-lfs.github.com/spec/v1\n", encoding="utf-8")
    doc = Doc("page.md", "![a pointer](pointer.png) and ![a picture](lidar_wake.png)")
    assert picture_problems(doc, tmp_path)[0].endswith("pointer.png is not an image (a Git LFS pointer, or text?)")
    assert not picture_problems(Doc("page.md", "![a picture](lidar_wake.png)"), ROOT / "docs/sea")


def test_checker_catches_a_commit_that_does_not_exist() -> None:
    if not _full_history():
        pytest.skip("needs the repository's full git history")
    if _git("cat-file", "-e", "03a0d0c^{commit}").returncode != 0:
        pytest.skip("a clone without this repository's own history")
    doc = _doctored("docs/realism/README.md", "(03a0d0c)", "(03a0d0f)")
    assert [p for p in commit_problems(doc) if "03a0d0f" in p]
    assert not [p for p in commit_problems(Doc("x.md", "commit 66e5052, `crates/a1b2c3d4e/x.rs`")) if "66e5052" in p]


def test_checker_catches_a_picture_script_view_that_does_not_exist() -> None:
    doc = _doctored("docs/realism/README.md", "--only wake_bend", "--only wake_bends")
    assert [p for p in only_problems(doc) if "wake_bends" in p]
    doc = _doctored("docs/sea/README.md", "--only craft,wake", "--only craft,wakes")
    assert [p for p in only_problems(doc) if "'wakes'" in p]
