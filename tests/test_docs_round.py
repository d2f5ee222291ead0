"""The docs walked as a new user walks them: the snippets run and print what their comments say, the set-up
commands are the ones CI runs, and the dependency table names what gets installed.

``tests/test_docs.py`` checks the docs statically (flags, names, paths); this file runs what is cheap to run:

* the README's low-level core snippet, with small inputs for the names it leaves to the reader;
* docs/recording.md's reading snippet on a small recording (its printed lines are those its comment names);
* the README's ``Simulation`` lines, whose comments give each array's shape and dtype;
* the README's two set-up commands against ``.ci/run``, ``scripts/test.sh`` and the Makefile;
* the README's *Dependencies and why* table against ``pyproject.toml`` and the packages ``scripts/test.sh`` installs.
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import numpy as np
import pytest
import yaml
from test_docs import ROOT, Doc, _blocks, _doc, _doctored, check_script_command, script_commands


def _readme_python(marker: str) -> str:
    blocks = [body for lang, body, _ in _blocks(Doc("README.md", _doc("README.md"))) if lang == "python"]
    found = [b for b in blocks if marker in b]
    assert len(found) == 1, f"no single README python block holds {marker!r}"
    return found[0]


# ------------------------------------------------------------------------------------------------- snippets


def test_low_level_core_snippet_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The README's *Using the low-level core* block, run as printed; the reader's own arrays (a triangle, one pose,
    one ray down onto it) are the only lines added."""
    code = _readme_python("mmusv.Scene()")
    given = {
        "vertices": np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        "faces": np.array([[0, 1, 2]]),
        "pose_matrices": np.eye(4)[None],
        "origins": np.array([[0.2, 0.2, 5.0]]),
        "directions": np.array([[0.0, 0.0, -1.0]]),
    }
    monkeypatch.chdir(tmp_path)
    scope: dict[str, object] = dict(given)
    exec(compile(code, "README.md", "exec"), scope)
    hits = scope["hits"]
    assert hits.distance.tolist() == [5.0]  # type: ignore[attr-defined]
    assert hits.semantic_class.tolist() == [10]  # type: ignore[attr-defined]  # classes=10
    assert (tmp_path / "frame.ply").stat().st_size > 0


def _world_state_only(name: str) -> dict[str, object]:
    """``port_entry`` without its USVs, two frames: a recording of the world state alone, written in a second."""
    cfg = yaml.safe_load((ROOT / "scenarios/port_entry.yaml").read_text(encoding="utf-8"))
    cfg["vessels"] = [v for v in cfg["vessels"] if v.get("role") != "usv"]
    cfg.pop("rigs", None)
    cfg["name"] = name
    cfg["acquisition"]["frames"] = 2
    return cfg


def test_recording_snippet_prints_what_it_says(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import mmusv
    from mmusv.scenario_checks import MmusvWarning

    with pytest.warns(MmusvWarning, match="no vessel has role: usv"):  # said, and the world state recorded
        mmusv.run(_world_state_only("run"), out_dir=tmp_path)  # writes run.mcap, the file the snippet opens
    code = next(
        body for lang, body, _ in _blocks(Doc("docs/recording.md", _doc("docs/recording.md"))) if lang == "python"
    )
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "docs/recording.md", "exec"), {})
    lines = out.getvalue().splitlines()
    # topic, log time (k / 5 Hz in ns), frame k, vessels: the scenario's five and the port's moored ships
    rows = [re.fullmatch(r"/world/state (\d+) (\d+) (\d+)", ln) for ln in lines[:2]]
    assert all(rows), lines[:2]
    assert [(int(m[1]), int(m[2])) for m in rows if m] == [(0, 0), (200_000_000, 1)]
    assert {int(m[3]) for m in rows if m} == {len(_world_state_only("run")["vessels"]) + 4}  # type: ignore[arg-type]
    # the last line: the summary with what the comment lists (topics, message counts, start/end, metadata, ...)
    for key in ("'topics'", "'messages'", "'start_ns'", "'end_ns'", "'metadata'", "'attachments'"):
        assert key in lines[2], key


SHAPE_COMMENT = re.compile(r"^(cap\.[^\s#]+)\s+#\s*\(([^)]*)\)\s+(\w+)", re.M)


def test_readme_simulation_lines_give_the_shapes_their_comments_say(monkeypatch: pytest.MonkeyPatch) -> None:
    """``sim = mmusv.Simulation(...)`` and the lines after it (not the recording runs before them): each
    ``cap....  # (H, W) dtype`` comment is the array's shape and dtype."""
    import mmusv

    code = _readme_python("mmusv.Simulation(")
    lines = code[code.index("sim = mmusv.Simulation(") :]
    checks = SHAPE_COMMENT.findall(lines)
    assert len(checks) == 3, checks
    monkeypatch.chdir(ROOT)  # the snippet names scenarios/port_entry.yaml
    scope: dict[str, object] = {"mmusv": mmusv}
    exec(compile(lines, "README.md", "exec"), scope)
    for expr, shape, dtype in checks:
        value = eval(expr, scope)
        dims = [d.strip() for d in shape.split(",")]
        assert len(value.shape) == len(dims), expr
        for got, want in zip(value.shape, dims, strict=True):
            assert want == "N" or got == int(want), (expr, value.shape, shape)
        assert value.dtype == np.dtype(dtype), (expr, value.dtype)


# ------------------------------------------------------------------------------------ set-up and dependencies


def _test_sh() -> str:
    return (ROOT / "scripts/test.sh").read_text(encoding="utf-8")


def test_readme_setup_commands_are_what_ci_runs() -> None:
    readme = _doc("README.md")
    section = readme.split("## Two commands", 1)[1].split("\n## ", 1)[0]
    shell = [body.strip() for lang, body, _ in _blocks(Doc("README.md", section)) if lang == "bash"]
    assert len(shell) == 2
    install, test = shell
    assert install.startswith("pip install . && ")
    make_install = re.search(r"^install:.*\n\t(.+)$", (ROOT / "Makefile").read_text(encoding="utf-8"), re.M)
    assert make_install is not None and make_install.group(1).strip() == "python3 -m pip install ."
    assert test == "bash scripts/test.sh"
    ci = [ln for ln in (ROOT / ".ci/run").read_text(encoding="utf-8").splitlines() if ln and not ln.startswith("#")]
    assert ci[-1] == test
    # the extras scripts/test.sh installs are the ones the README's sentence names
    extras = re.search(r'pip install [^\n]*-e "\.\[([\w,]+)\]"', _test_sh())
    assert extras is not None
    sentence = section.split("Install everything the tests need", 1)[1].split(":", 1)[0]
    for extra in extras.group(1).split(","):
        assert f"`{extra}`" in sentence, f"the README does not say scripts/test.sh installs the {extra!r} extra"


def _requirement_name(req: str) -> str:
    return re.split(r"[<>=!~\[; ]", req.strip(), maxsplit=1)[0].lower()


def installed_packages() -> set[str]:
    """Every package ``pyproject.toml`` asks for (dependencies and every extra) and every one ``scripts/test.sh``
    installs by name (``pip install --no-deps "X>=..."``)."""
    tomllib = pytest.importorskip("tomllib")  # Python 3.11+
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    reqs = [*project["dependencies"], *[r for extra in project["optional-dependencies"].values() for r in extra]]
    names = {_requirement_name(r) for r in reqs}
    for line in _test_sh().splitlines():
        if "pip install" in line and "--no-deps" in line:
            names |= {_requirement_name(r) for r in re.findall(r'"([A-Za-z][\w.-]*[<>=][^"]*)"', line)}
    return names


def dependency_table_problems(readme: str) -> list[str]:
    table = readme.split("## Dependencies and why", 1)[1].split("\n## ", 1)[0]
    named = {t.lower() for row in table.splitlines() if row.startswith("|") for t in re.findall(r"`([^`]+)`", row)}
    return [
        f"README.md, Dependencies and why: {p} is installed but not named" for p in sorted(installed_packages() - named)
    ]


def test_dependency_table_names_every_installed_package() -> None:
    assert {"numpy", "torch", "motmetrics", "trackeval", "ultralytics"} <= installed_packages()
    problems = dependency_table_problems(_doc("README.md"))
    assert not problems, "\n".join(problems)


def test_checker_catches_a_dependency_left_out_of_the_table() -> None:
    doc = _doctored(
        "README.md", "| `motmetrics`, `trackeval`, `tabulate` (tests) |", "| `trackeval`, `tabulate` (tests) |"
    )
    assert dependency_table_problems(doc.text) == [
        "README.md, Dependencies and why: motmetrics is installed but not named"
    ]


def test_checker_reads_a_script_run_by_a_venv_interpreter() -> None:
    """docs/opencood.md runs ``venv/bin/python scripts/opencood_check.py``: its flags are checked too."""
    found = script_commands(Doc("docs/opencood.md", _doc("docs/opencood.md")))
    assert any(script == "scripts/opencood_check.py" and "--patch" in flags for _, script, flags in found), found
    doc = _doctored("docs/opencood.md", "--export EXPORT --patch", "--export EXPORT --patches")
    problems = [p for s in script_commands(doc) for p in check_script_command(*s)]
    assert problems and "--patches" in problems[0]
