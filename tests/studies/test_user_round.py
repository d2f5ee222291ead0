"""A new user's round on the studies: ``mmusv study detection DIR/recordings`` on a ``mmusv dataset`` folder reads
the recordings its ``dataset.json`` lists, not whatever ``.mcap`` is left below (a scenario the spec no longer
makes, a recording the index marks failed). Failed before its fix."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.batch.dataset import build_dataset
from mmusv.errors import InputError
from mmusv.studies.detection.sources import resolve_dataset

SPEC: dict[str, Any] = {
    "name": "tiny",
    "seed": 5,
    "map": {"type": "open_sea", "seed": 2},
    "acquisition": {"frequency_hz": 5, "frames": 2},
    "rig": "usv_lidar",
    "rigs": {"usv_lidar": {"preset": "lidar_only", "lidar": {"channels": 16}}},
    "combinations": [{"family": "crossing", "difficulty": "easy", "cooperating": 1, "targets": ["small"], "quota": 2}],
}
NAMES = ["crossing_easy_2usv_small_000", "crossing_easy_2usv_small_001"]


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("ds")
    spec = root / "spec.yaml"
    spec.write_text(yaml.safe_dump(SPEC, sort_keys=False), encoding="utf-8")
    rep = build_dataset(spec, out_dir=root / "out")
    assert rep.ok and [o.file.stem for o in rep.batch.outcomes] == NAMES
    return root / "out"


def _stale(out: Path, name: str) -> None:
    """A recording left below DIR/recordings that the index does not list (as when the spec dropped its
    scenario: ``mmusv dataset`` keeps the recordings it no longer indexes)."""
    src = out / "recordings" / NAMES[0]
    dst = out / "recordings" / name
    shutil.copytree(src, dst)
    (dst / f"{NAMES[0]}.mcap").rename(dst / f"{name}.mcap")


def test_the_recordings_folder_of_a_dataset_is_read_through_its_index(dataset: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    shutil.copytree(dataset, out)
    _stale(out, "dropped_000")
    assert not (out / "recordings" / "dataset.json").exists()  # the index is DIR/dataset.json
    by_folder = resolve_dataset([out / "recordings"], opv2v=None, split="all")
    by_dataset = resolve_dataset([out], opv2v=None, split="all")
    assert sorted(by_folder.sources) == sorted(by_dataset.sources) == NAMES
    assert by_folder.sources == {n: out / "recordings" / n / f"{n}.mcap" for n in NAMES}
    # a recording the index marks failed is not read either, though its .mcap is there
    doc = json.loads((out / "dataset.json").read_text(encoding="utf-8"))
    doc["recordings"][1]["status"] = "failed"
    (out / "dataset.json").write_text(json.dumps(doc), encoding="utf-8")
    assert sorted(resolve_dataset([out / "recordings"], opv2v=None, split="all").sources) == NAMES[:1]
    for r in doc["recordings"]:
        r["status"] = "failed"
    (out / "dataset.json").write_text(json.dumps(doc), encoding="utf-8")
    with pytest.raises(InputError, match=r"dataset\.json lists no complete recording in this folder"):
        resolve_dataset([out / "recordings"], opv2v=None, split="all")


def test_a_folder_without_an_index_above_is_still_searched(dataset: Path, tmp_path: Path) -> None:
    """Recordings copied elsewhere (no dataset.json beside their folder) are found by searching, as before."""
    loose = tmp_path / "loose"
    shutil.copytree(dataset / "recordings", loose)
    assert sorted(resolve_dataset([loose], opv2v=None, split="all").sources) == NAMES
