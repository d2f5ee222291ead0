"""The ``mmusv`` command's start (:mod:`mmusv._launch`) and the light ``import mmusv`` it needs: a Ctrl-C while
the command's modules load is ``mmusv: interrupted`` and exit status 130, not a traceback of the import; the
package's names load on first use and are the same objects as before."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import mmusv
import pytest

ROOT = Path(__file__).resolve().parents[1]

TINY = {
    "name": "tiny", "seed": 1, "acquisition": {"frequency_hz": 5, "frames": 6},
    "map": {"type": "open_sea", "seed": 0, "params": {"extent_m": 800, "islet_probability": 0.0, "n_buoys": 0}},
    "rigs": {"r": {"preset": "lidar_only"}},
    "vessels": [
        {"id": "usv", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2.0, "route": [[0, 0], [90, 0]]},
        {"id": "tug", "role": "target", "asset": "tug_32m", "speed_mps": 2.0, "route": [[40, 20], [140, 20]]},
    ],
}  # fmt: skip
"""Six frames of one USV and a tug on open sea: a recording made in a few seconds."""

# a signal sent to the process at the moment the named module starts loading (a Ctrl-C or a kill then)
_SIGNAL_AT = """\
import os, signal, sys
class At:
    def find_spec(self, name, path=None, target=None):
        if name == {module!r}:
            sys.meta_path.remove(self)
            os.kill(os.getpid(), signal.{signal})
sys.meta_path.insert(0, At())
"""

_STARTS = [
    "from mmusv._launch import main\nsys.exit(main())",  # what the console script does
    "import runpy\nrunpy.run_module('mmusv', run_name='__main__')",  # python -m mmusv
]


def _python(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=120)


def test_import_mmusv_loads_only_the_core_and_the_errors() -> None:
    out = _python(
        "import sys, mmusv\n"
        "heavy = sorted(m for m in ('mmusv.config', 'mmusv.acquire', 'polars', 'pydantic', 'scipy') "
        "if m in sys.modules)\n"
        "print(heavy)\n"
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_the_package_names_are_their_modules_objects() -> None:
    from mmusv import acquire, batch, config, scene, simulation

    assert mmusv.run is acquire.run and mmusv.RunResult is acquire.RunResult
    assert mmusv.run_many is batch.run_many and mmusv.BatchReport is batch.BatchReport
    assert mmusv.Scene is scene.Scene and mmusv.RayHits is scene.RayHits
    assert mmusv.Simulation is simulation.Simulation and mmusv.config is config
    assert mmusv.InputError is mmusv.errors.InputError
    assert set(mmusv.__all__) <= set(dir(mmusv))
    namespace: dict[str, object] = {}
    exec("from mmusv import *", namespace)
    assert set(mmusv.__all__) <= set(namespace)
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        _ = mmusv.not_a_name


@pytest.mark.parametrize("module", ["mmusv.export.common", "numpy", "mmusv.cli_run", "mmusv.generate.cli"])
@pytest.mark.parametrize("start", _STARTS)
def test_ctrl_c_while_the_command_loads_ends_it_after_the_load_in_one_line(module: str, start: str) -> None:
    # held to the end of the load (an interrupt inside an import was a traceback, or lost in a library's except),
    # then the command does not start: no version printed
    code = _SIGNAL_AT.format(module=module, signal="SIGINT") + "sys.argv = ['mmusv', 'version']\n" + start + "\n"
    out = _python(code)
    assert "Traceback" not in out.stderr, out.stderr
    assert out.stderr == "mmusv: interrupted\n"
    assert out.returncode == 130
    assert out.stdout == ""


@pytest.mark.parametrize("start", _STARTS)
def test_a_kill_while_the_command_loads_is_one_line_and_status_143(start: str) -> None:
    code = (
        _SIGNAL_AT.format(module="mmusv.export.common", signal="SIGTERM") + "sys.argv = ['mmusv', 'version']\n" + start
    )
    out = _python(code + "\n")
    assert out.stderr == "mmusv: terminated (SIGTERM)\n"
    assert out.returncode == 128 + signal.SIGTERM
    assert out.stdout == ""


def test_after_the_load_the_previous_handlers_are_back_and_the_command_runs() -> None:
    out = _python(
        "import signal, sys\nsys.argv = ['mmusv', 'version']\nfrom mmusv._launch import main\n"
        "code = main()\nprint(signal.getsignal(signal.SIGINT) is signal.default_int_handler, "
        "signal.getsignal(signal.SIGTERM) is signal.SIG_DFL, code)\n"
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[0].startswith("mmusv ")
    assert out.stdout.splitlines()[1] == "True True 0"


@pytest.mark.parametrize("delay_s", [0.15, 0.3, 0.6])
def test_a_real_ctrl_c_during_the_start_is_one_line(tmp_path: Path, delay_s: float) -> None:
    # the start takes about a second here; the signal lands in it, or in the command (the same words and status)
    proc = subprocess.Popen(
        [sys.executable, "-m", "mmusv", "run", str(ROOT / "scenarios" / "port_entry.yaml"), "-o", str(tmp_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(delay_s)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=120)
    assert "Traceback" not in stderr, stderr
    assert proc.returncode == 130, stderr
    assert stderr.strip().endswith("mmusv: interrupted"), stderr


@pytest.mark.parametrize(
    ("signal_name", "status", "line"), [("SIGINT", 130, "interrupted"), ("SIGTERM", 143, "terminated (SIGTERM)")]
)
@pytest.mark.parametrize("wrapper", ["RuntimeError", "ValueError"])
def test_a_stop_a_library_wraps_in_its_own_error_is_still_one_line(
    tmp_path: Path, signal_name: str, status: int, line: str, wrapper: str
) -> None:
    # A Ctrl-C that landed while pydantic built a scenario model (the command's own start, after the held load)
    # came out of the library as its own error: pydantic-core's SchemaError ("... KeyboardInterrupt:") or
    # Python's RuntimeError from __set_name__, a traceback and status 1 (3 in 280 starts under load). Any error
    # that ends a command after a stop is the stop.
    code = (
        "import os, signal, sys, time\n"
        f"sys.argv = ['mmusv', 'run', {str(ROOT / 'scenarios' / 'port_entry.yaml')!r}, '-o', {str(tmp_path)!r}]\n"
        "import mmusv.cli_run as cli_run\n"
        "def cut(*args, **kwargs):\n"
        "    try:\n"
        f"        os.kill(os.getpid(), signal.{signal_name})\n"
        "        time.sleep(5)\n"
        "    except KeyboardInterrupt as exc:\n"
        f"        raise {wrapper}('Error building a validator: KeyboardInterrupt') from exc\n"
        "cli_run._run_one = cut\n"
        "from mmusv._launch import main\nsys.exit(main())\n"
    )
    out = _python(code)
    assert "Traceback" not in out.stderr, out.stderr
    assert out.stderr == f"mmusv: {line}\n"
    assert out.returncode == status


_SWALLOWS = {
    # a library's ``except`` around the code the stop landed in
    "except": "        try:\n            stop()\n        except KeyboardInterrupt:\n            pass\n",
    # a finalizer (importlib's module-lock callback in the case found): Python reports it as "Exception ignored in"
    "finalizer": "        class Lock:\n            def __del__(self):\n                stop()\n        Lock()\n",
}


@pytest.mark.parametrize("swallow", sorted(_SWALLOWS))
def test_a_stop_a_library_swallows_still_ends_the_run_in_one_line(tmp_path: Path, swallow: str) -> None:
    # A Ctrl-C that landed in a lazy import during the first frames raised in importlib's module-lock callback,
    # which Python reports ("Exception ignored in ...", a traceback) and goes on: the run recorded all its frames
    # (1 of 200 starts of mmusv run under load). The stop is noted and raised again at the next frame.
    code = (
        "import os, signal, sys, time\n"
        f"sys.argv = ['mmusv', 'run', {str(ROOT / 'scenarios' / 'port_entry.yaml')!r}, '-o', {str(tmp_path)!r}, "
        "'--frames', '6']\n"
        "import mmusv.simulation as simulation\n"
        "original, calls = simulation.Simulation.capture, []\n"
        "def stop():\n"
        "    os.kill(os.getpid(), signal.SIGINT)\n"
        "    time.sleep(5)\n"
        "def capture(self, frame, **kwargs):\n"
        "    calls.append(frame)\n"
        "    if len(calls) == 2:\n"
        f"{_SWALLOWS[swallow]}"
        "    return original(self, frame, **kwargs)\n"
        "simulation.Simulation.capture = capture\n"
        "from mmusv._launch import main\ncode = main()\nprint(calls)\nsys.exit(code)\n"
    )
    out = _python(code)
    assert out.stderr == "mmusv: interrupted\n"
    assert out.returncode == 130
    assert out.stdout.splitlines()[-1] == "[0, 1]"  # no frame captured after the stop


def test_a_stop_a_library_swallows_still_ends_the_conversion(tmp_path: Path) -> None:
    # As for the recording (above): mmusv convert's frame loop raises a noted stop again.
    code = (
        "import os, signal, sys, time\n"
        "from mmusv.acquire import run\n"
        f"res = run({TINY!r}, out_dir={str(tmp_path / 'rec')!r})\n"
        f"sys.argv = ['mmusv', 'convert', str(res.recording), '--to', 'kitti', '-o', {str(tmp_path / 'kitti')!r}, "
        "'--no-progress']\n"
        "import mmusv.export.conversion as conversion\n"
        "class Stream(conversion.FrameStream):\n"
        "    def __iter__(self):\n"
        "        for k, frame in enumerate(super().__iter__()):\n"
        "            if k == 2:\n"
        "                try:\n"
        "                    os.kill(os.getpid(), signal.SIGINT)\n"
        "                    time.sleep(5)\n"
        "                except KeyboardInterrupt:\n"
        "                    pass  # swallowed\n"
        "            print('frame', k, flush=True)\n"
        "            yield frame\n"
        "conversion.FrameStream = Stream\n"
        "from mmusv._launch import main\nsys.exit(main())\n"
    )
    out = _python(code)
    assert out.stderr.endswith("mmusv: interrupted\n"), out.stderr
    assert out.returncode == 130
    assert [line for line in out.stdout.splitlines() if line.startswith("frame")] == ["frame 0", "frame 1", "frame 2"]


def test_the_parser_every_command_builds_loads_no_scenario_model_or_dataset_reader() -> None:
    # mmusv --help took 1.5-1.9 s here: the parser imported the detection dataset reader for one constant (0.7 s),
    # the generator's sampler and map builder (0.26 s), and the scenario models for a warning class
    out = _python(
        "import sys\nsys.argv = ['mmusv', 'version']\nfrom mmusv._launch import main\nassert main() == 0\n"
        "print(sorted(m for m in ('mmusv.config', 'mmusv.studies.detection.sources', 'mmusv.generate.runner', "
        "'mmusv.generate.families', 'polars', 'mmusv.export.conversion', 'mmusv.annotate', 'scipy') "
        "if m in sys.modules))\n"
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[-1] == "[]"


def test_the_export_package_names_are_its_modules_objects_whatever_was_loaded_first() -> None:
    # mmusv convert's parser loaded the conversion job with the package (annotations, geometry, scipy: 0.45 s of
    # mmusv --help's 0.9 s); lazily loaded, the function convert must not be shadowed by a submodule of that name
    out = _python(
        "import importlib, pkgutil, sys\n"
        "import mmusv.export as ex\n"
        "for info in pkgutil.iter_modules(ex.__path__):\n"
        "    importlib.import_module(f'mmusv.export.{info.name}')\n"
        "from mmusv.export import DEFAULT_EXTRAS, EXTRAS, TARGETS, ConvertReport, RecordingReport, convert, cli\n"
        "from mmusv.export import common, conversion, convert_report\n"
        "assert convert is conversion.convert and callable(convert), convert\n"
        "assert ConvertReport is convert_report.ConvertReport and RecordingReport is convert_report.RecordingReport\n"
        "assert (TARGETS, EXTRAS, DEFAULT_EXTRAS) == (common.TARGETS, common.EXTRAS, common.DEFAULT_EXTRAS)\n"
        "assert cli is sys.modules['mmusv.export.cli'] and set(ex.__all__) <= set(dir(ex))\n"
        "try:\n    ex.nothing\nexcept AttributeError as e:\n    print(e)\n"
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "module 'mmusv.export' has no attribute 'nothing'"


def test_the_generate_package_names_are_its_modules_objects() -> None:
    import importlib
    import pkgutil

    import mmusv.generate as gen
    from mmusv.studies import detection
    from mmusv.studies.detection import sources

    for info in pkgutil.iter_modules(gen.__path__):  # a submodule loaded does not shadow a name of the package
        if info.name not in ("cli",):
            importlib.import_module(f"mmusv.generate.{info.name}")
    from mmusv.generate import runner, spec

    assert gen.generate is runner.generate and callable(gen.generate)
    assert gen.load_spec is spec.load_spec and gen.GenerationSpec is spec.GenerationSpec
    assert set(gen.__all__) <= set(dir(gen)) | set(gen._LAZY)
    assert sources.BUNDLED_SPEC == detection.BUNDLED_SPEC == "scenarios/specs/coop_detection.yaml"
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        _ = gen.nothing


@pytest.mark.parametrize("where", ["dispatch", "load"])
def test_a_ctrl_c_inside_string_code_under_python_m_ends_with_130_not_by_the_signal(tmp_path: Path, where: str) -> None:
    # CPython marks a KeyboardInterrupt leaving exec(str) (every dataclass method as a module loads) as unhandled
    # even when caught, and under python -m ended the process by SIGINT after "mmusv: interrupted" (-2, not 130)
    kill = "exec('import os, signal\\nos.kill(os.getpid(), signal.SIGINT)\\nfor _ in range(10**6): pass', {})\n"
    if where == "dispatch":  # in the command, under the command line's handler
        body = f"import mmusv.cli as cli\ndef dispatch(args):\n    {kill}    return 0\ncli._dispatch = dispatch\n"
    else:  # after the load, before the command's handler: Python's own
        body = f"import mmusv.cli as cli\ndef run(argv=None):\n    {kill}    return 0\ncli.main = run\n"
    (tmp_path / "ctrl_c_in_exec.py").write_text(
        "import sys\n" + body + "sys.argv = ['mmusv', 'version']\nfrom mmusv._launch import main\nsys.exit(main())\n"
    )
    out = subprocess.run(
        [sys.executable, "-m", "ctrl_c_in_exec"], cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False
    )
    assert out.stderr == "mmusv: interrupted\n"
    assert out.returncode == 130
