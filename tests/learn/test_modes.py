"""mmusv.learn.modes: the one table of the models the study's fusion modes run, readable without PyTorch or the
native extension."""

from __future__ import annotations

import itertools
import subprocess
import sys
from pathlib import Path

import pytest
from mmusv.learn.modes import MODELS, STUDY_NEEDS, fusion_modes, models_for
from mmusv.studies.detection.fusion import MODES as STUDY_MODES

ROOT = Path(__file__).resolve().parents[2]


def test_every_study_mode_runs_one_of_the_models() -> None:
    assert tuple(STUDY_NEEDS) == STUDY_MODES
    assert set(STUDY_NEEDS.values()) == set(MODELS)


@pytest.mark.parametrize("n", range(len(MODELS) + 1))
def test_fusion_modes_are_the_modes_whose_model_is_there(n: int) -> None:
    for models in itertools.combinations(MODELS, n):
        # brute force over the study's modes: late fusion merges single-agent boxes, so it needs single
        expected = tuple(
            m
            for m in ("none", "late", "early", "intermediate")
            if {"none": "single", "late": "single"}.get(m, m) in models
        )
        assert fusion_modes(models) == expected
        assert fusion_modes(reversed(models)) == expected


def test_models_for_names_each_needed_model_once_in_training_order() -> None:
    assert models_for(["late", "none"]) == ("single",)
    assert models_for(["intermediate", "none", "late"]) == ("single", "intermediate")
    assert models_for(STUDY_MODES) == MODELS
    assert models_for([]) == ()
    assert models_for(["bogus"]) == ()


_BLOCK = (
    "import sys\n"
    "class Block:\n"
    "    def find_spec(self, name, path=None, target=None):\n"
    "        if name.split('.')[0] in {BLOCKED} or name == 'mmusv._core':\n"
    "            raise ImportError('blocked: ' + name)\n"
    "sys.meta_path.insert(0, Block())\n"
)


def _run_blocked(blocked: set[str], code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", _BLOCK.replace("{BLOCKED}", repr(blocked)) + code],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )


def test_the_table_imports_without_torch_or_the_native_extension() -> None:
    # as scripts/learn_train.py loads it: mmusv a bare package over its source folder (no mmusv/__init__.py)
    out = _run_blocked(
        {"torch", "polars"},
        "import types\n"
        "bare = types.ModuleType('mmusv'); bare.__path__ = ['python/mmusv']; sys.modules['mmusv'] = bare\n"
        "from mmusv.learn.modes import STUDY_NEEDS, fusion_modes\n"
        "print(STUDY_NEEDS['late'], fusion_modes(['early']))\n",
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "single ('early',)"


def test_the_training_script_runs_without_the_native_extension_or_polars() -> None:
    # its promise: a machine with torch and numpy, without mmusv installed
    out = _run_blocked(
        {"polars"},
        "import runpy\nsys.argv = ['scripts/learn_train.py', '--help']\n"
        "runpy.run_path('scripts/learn_train.py', run_name='__main__')\n",
    )
    assert out.returncode == 0, out.stderr
    assert "--cache" in out.stdout
