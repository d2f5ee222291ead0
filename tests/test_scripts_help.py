"""``--help`` of the helper scripts in ``scripts/`` and of ``python -m mmusv.learn.replay``, as a user reading
``docs/studies/detection.md`` meets them: each answers ``--help`` (``learn_pack.py`` ended in an ``IndexError``
traceback), its description is a whole paragraph (three stopped mid-sentence where their docstring's first line
ended: 'beside W1): the', 'before (the flat sea) and after', '(inference done') and every option and argument has
a line of help (the benches' own check: ``tests/test_benches_round.py``)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import mmusv
from help_pages import check_help_page

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted((ROOT / "scripts").glob("*.py"))
MODULES = ["mmusv.learn.replay"]


def _help_pages() -> dict[str, str]:
    """Each script's and module's ``--help`` text, from one interpreter (torch is imported once)."""
    runner = textwrap.dedent(
        """
        import contextlib, io, runpy, sys
        for target in sys.argv[1:]:
            sys.argv = [target, "--help"]
            buf = io.StringIO()
            code = 0
            with contextlib.redirect_stdout(buf):
                try:
                    if target.endswith(".py"):
                        runpy.run_path(target, run_name="__main__")
                    else:
                        runpy.run_module(target, run_name="__main__", alter_sys=True)
                except SystemExit as stop:
                    code = stop.code or 0
                except BaseException as e:
                    code = f"{type(e).__name__}: {e}"
            print("=====", target, code)
            print(buf.getvalue())
        """
    )
    env = dict(os.environ, COLUMNS="100")
    env["PYTHONPATH"] = os.pathsep.join(
        [str(Path(mmusv.__file__).resolve().parents[1]), env.get("PYTHONPATH", "")]
    ).rstrip(os.pathsep)
    proc = subprocess.run(
        [sys.executable, "-c", runner, *map(str, SCRIPTS), *MODULES],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    pages = {}
    for target, code, page in re.findall(r"===== (\S+) (.*?)\n(.*?)(?=\n===== |\Z)", proc.stdout, re.S):
        assert code == "0", f"{target} --help: {code}"
        pages[Path(target).name if target.endswith(".py") else target] = page
    assert len(pages) == len(SCRIPTS) + len(MODULES), proc.stdout
    return pages


def test_help_of_every_script_is_whole() -> None:
    for name, page in _help_pages().items():
        assert page.startswith("usage: "), f"{name}: {page[:300]!r}"
        check_help_page(name, page)
