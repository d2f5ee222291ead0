"""The tensor cache: a split of the detection dataset packed into one ``.npz`` file that trains with numpy and
torch alone (on a machine without mmusv's native extension).

:func:`build_cache` reads the sequences through the detection study's own dataset code
(:func:`mmusv.studies.detection.sources.resolve_dataset`: recordings or an OPV2V export, split by sequence) and
takes, for every frame and every instrumented USV as the ego, its ground truth from
:func:`mmusv.studies.detection.data.gt_in_ego` (the study's one target rule). :class:`Cache` reads it back.

Layout (all arrays of one ``np.savez_compressed`` file):

- ``xyz_cm`` ``(N, 3)`` int16: every cloud's points, LiDAR frame, centimetres (±327 m; points beyond are dropped);
  ``intensity`` ``(N,)`` uint8 (intensity · 255); ``cloud_offsets`` ``(C + 1,)`` int64;
- ``cloud_lidar`` ``(C, 4, 4)`` float64 LiDAR → world; ``cloud_frame`` ``(C,)`` int64 frame slot;
  ``cloud_agent`` ``(C,)`` the USV (or OPV2V CAV) id;
- ``frame_seq`` ``(F,)`` int64 sequence slot, ``frame_index`` ``(F,)`` acquisition index, ``sequences`` ``(S,)``;
- ``sample_cloud`` ``(K,)`` int64 the ego's cloud of each sample; ``gt`` ``(G, 7)`` float32 ego-frame boxes
  ``x, y, z, l, w, h, yaw``; ``gt_offsets`` ``(K + 1,)`` int64;
- ``meta`` a JSON string: the split, ratios, seed, sources and their ``fingerprints``
  (:func:`dataset_fingerprints`; caches written before they were added lack them).

:meth:`Cache.identity` is what the cache was built from (the sequences, each with its fingerprint, the range and
the frame stride): ``mmusv train`` reuses ``OUT/cache_<split>.npz`` only for the same data, and a checkpoint records
it, so a run is resumed, and a model evaluated, knowing which sequences it was trained on.
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mmusv.held_signals import raise_noted_stop
from mmusv.learn._errors import input_error
from mmusv.text import given

__all__ = ["Cache", "Sample", "build_cache", "cache_identity", "dataset_fingerprints", "same_data"]

Sample = tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]], np.ndarray]
"""``(ego points (N, 4) float32, [(neighbour points (N_i, 4) float32 own frame, rel (4, 4) neighbour → ego)],
ground truth (G, 7) float64)``."""

_LIMIT_CM = 32767
_IDENTITY = ("sources", "fingerprints", "range_m", "frame_stride")


def dataset_fingerprints(ds: Any) -> dict[str, str]:
    """``{sequence name: fingerprint}`` of a detection dataset (:class:`mmusv.studies.detection.sources.Dataset`),
    without reading its frames: a recording's config hash and frame count (what it says of itself); an OPV2V
    scenario folder's first frame's YAML (the poses and boxes) and its frame count. A sequence whose fingerprint
    cannot be read is left out. Two sequences with the same name and fingerprint hold the same data (the names
    alone repeat across datasets: every generated spec has its ``island_crossing_000``)."""
    import hashlib

    out: dict[str, str] = {}
    for name, path in sorted(ds.sources.items()):
        try:
            if ds.kind == "recording":
                from mmusv.studies.detection.data import recording_summary

                s = recording_summary(path)
                out[name] = f"recording:{s.config_hash}:{s.frames_configured}"
            else:
                cavs = sorted(c for c in Path(path).iterdir() if c.is_dir())
                yamls = sorted(f for f in cavs[0].glob("*.yaml") if not f.stem.endswith("_additional"))
                digest = hashlib.sha256(yamls[0].read_bytes()).hexdigest()[:32]
                out[name] = f"opv2v:{digest}:{len(yamls)}"
        except Exception:  # a fingerprint is a check's input: reading the sequence reports a bad file
            continue
    return out


def _identity_of(meta: dict[str, Any]) -> dict[str, Any]:
    keys = (*_IDENTITY, "split", "ratios", "seed")
    return {k: meta[k] for k in keys if k in meta}


def cache_identity(path: str | Path) -> dict[str, Any] | None:
    """:meth:`Cache.identity` of the cache file ``path`` read from its ``meta`` alone (not its arrays); ``None``
    where it cannot be read (:class:`Cache` says why when it is loaded)."""
    try:
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
    except (OSError, ValueError, EOFError, TypeError, KeyError, zipfile.BadZipFile):
        return None
    return _identity_of(meta) if isinstance(meta, dict) else None


def same_data(a: dict[str, Any] | None, b: dict[str, Any] | None) -> bool:
    """Whether two :meth:`Cache.identity` values name the same data: the same sequences, range and stride, and,
    where both give fingerprints, the same fingerprints (``None``: unknown, taken as the same)."""
    if not isinstance(a, dict) or not isinstance(b, dict):
        return True
    if any(a[k] != b[k] for k in _IDENTITY if k != "fingerprints" and k in a and k in b):
        return False
    fa, fb = a.get("fingerprints"), b.get("fingerprints")
    if isinstance(fa, dict) and isinstance(fb, dict):  # a sequence whose fingerprint could not be read is not compared
        return all(fa[n] == fb[n] for n in fa.keys() & fb.keys())
    return True


def build_cache(
    inputs: Sequence[str | Path],
    out: str | Path,
    *,
    opv2v: str | None = None,
    split: str = "train",
    ratios: Sequence[float] = (0.7, 0.15, 0.15),
    seed: int = 0,
    range_m: float = 200.0,
    frame_stride: int = 1,
) -> Path:
    """Packs ``split`` of the dataset (recordings ``inputs`` or the OPV2V folder ``opv2v``) into ``out``
    (module docstring), every ``frame_stride``-th frame of each sequence; returns ``out``. Written to a
    temporary name and renamed, so a killed build leaves no file that looks complete."""
    from mmusv.studies.detection.data import gt_in_ego
    from mmusv.studies.detection.sources import resolve_dataset

    ds = resolve_dataset(list(inputs), opv2v=opv2v, split=split, ratios=tuple(ratios), seed=seed)
    fingerprints = dataset_fingerprints(ds)
    xyz: list[np.ndarray] = []
    inten: list[np.ndarray] = []
    counts: list[int] = []
    lidar: list[np.ndarray] = []
    cloud_frame: list[int] = []
    cloud_agent: list[str] = []
    frame_seq: list[int] = []
    frame_index: list[int] = []
    names: list[str] = []
    sample_cloud: list[int] = []
    gts: list[np.ndarray] = []
    for s, seq in enumerate(ds.sequences()):  # each loaded when reached: minutes for a large dataset
        raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
        if seq.frames and not seq.agent_ids:  # it left no sample, and the cache was built (or "no frame to cache")
            raise input_error(
                f"sequence {seq.name}: no LiDAR: none of its instrumented USVs carries one (a rig with lidar: null), "
                "and the models learn from LiDAR clouds; leave it out of the training data"
            )
        names.append(seq.name)
        for fr in seq.frames[:: max(1, frame_stride)]:
            f = len(frame_seq)
            frame_seq.append(s)
            frame_index.append(fr.frame)
            for a in fr.agents:
                c = len(counts)
                pts = np.asarray(a.points, dtype=np.float64)
                q = np.round(pts[:, :3] * 100.0)
                ok = (np.abs(q) <= _LIMIT_CM).all(axis=1)
                xyz.append(q[ok].astype(np.int16))
                inten.append(np.round(np.clip(pts[ok, 3], 0.0, 1.0) * 255).astype(np.uint8))
                counts.append(int(ok.sum()))
                lidar.append(a.lidar)
                cloud_frame.append(f)
                cloud_agent.append(a.id)
                sample_cloud.append(c)
                gts.append(gt_in_ego(fr, a, range_m=range_m).astype(np.float32))
    if not counts:
        raise input_error(f"split {split!r} of {list(inputs) or opv2v}: no frame to cache")
    out_p = Path(out)
    out_p.parent.mkdir(parents=True, exist_ok=True)
    tmp = out_p.with_name(f".{out_p.name}.partial.npz")
    meta = {
        "frame_stride": frame_stride,
        "split": split,
        "ratios": list(ratios),
        "seed": seed,
        "range_m": range_m,
        "sources": sorted(ds.sources),
        "fingerprints": fingerprints,
    }
    np.savez_compressed(
        tmp,
        xyz_cm=np.concatenate(xyz),
        intensity=np.concatenate(inten),
        cloud_offsets=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
        cloud_lidar=np.stack(lidar),
        cloud_frame=np.array(cloud_frame, dtype=np.int64),
        cloud_agent=np.array(cloud_agent),
        frame_seq=np.array(frame_seq, dtype=np.int64),
        frame_index=np.array(frame_index, dtype=np.int64),
        sequences=np.array(names),
        sample_cloud=np.array(sample_cloud, dtype=np.int64),
        gt=np.concatenate(gts) if gts else np.zeros((0, 7), np.float32),
        gt_offsets=np.concatenate([[0], np.cumsum([len(g) for g in gts])]).astype(np.int64),
        meta=np.array(json.dumps(meta)),
    )
    tmp.replace(out_p)
    return out_p


def _check_arrays(path: Path, a: dict[str, np.ndarray], given_as: str) -> None:
    """Refuses a cache whose arrays do not fit together or hold values that are not finite, naming the array: a NaN
    ground-truth box was a ``ValueError`` traceback in training (``cannot convert float NaN to integer``), and offsets
    past the points an ``IndexError`` at some sample."""

    def bad(what: str) -> Exception:
        return input_error(f"{given(given_as, path)}: {what} (a damaged or edited cache: build it again)")

    n_clouds, n_frames = len(a["cloud_lidar"]), len(a["frame_seq"])
    shapes = {
        "xyz_cm": (a["xyz_cm"].ndim == 2 and a["xyz_cm"].shape[1] == 3, "(N, 3)"),
        "gt": (a["gt"].ndim == 2 and a["gt"].shape[1] == 7, "(G, 7) x, y, z, l, w, h, yaw"),
        "cloud_lidar": (a["cloud_lidar"].ndim == 3 and a["cloud_lidar"].shape[1:] == (4, 4), "(C, 4, 4)"),
        "cloud_offsets": (a["cloud_offsets"].shape == (n_clouds + 1,), f"({n_clouds + 1},), one more than the clouds"),
        "cloud_frame": (a["cloud_frame"].shape == (n_clouds,), f"({n_clouds},), one per cloud"),
        "intensity": (a["intensity"].shape == (len(a["xyz_cm"]),), f"({len(a['xyz_cm'])},), one per point"),
        "gt_offsets": (a["gt_offsets"].shape == (len(a["sample_cloud"]) + 1,), "one more than the samples"),
    }
    for name, (ok, want) in shapes.items():
        if not ok:
            raise bad(f"{name}: shape {a[name].shape}, expected {want}")
    for name, total in (("cloud_offsets", len(a["xyz_cm"])), ("gt_offsets", len(a["gt"]))):
        o = a[name]
        if o[0] != 0 or o[-1] != total or (np.diff(o) < 0).any():
            raise bad(f"{name}: not a rising run from 0 to {total}")
    for name, top in (("sample_cloud", n_clouds), ("cloud_frame", n_frames), ("frame_seq", len(a["sequences"]))):
        if len(a[name]) and (a[name].min() < 0 or a[name].max() >= top):
            raise bad(f"{name}: indices outside 0..{top - 1}")
    for name in ("gt", "cloud_lidar"):
        finite = np.isfinite(a[name]).reshape(len(a[name]), -1).all(axis=1)
        if not finite.all():
            rows = np.flatnonzero(~finite)
            raise bad(
                f"{name}: {len(rows)} row(s) with values that are not finite (NaN or inf), the first row {rows[0]}"
            )


class Cache:
    """A tensor cache read back (module docstring): :meth:`sample` gives one ego's inputs and ground truth."""

    KEYS = (
        "xyz_cm",
        "intensity",
        "cloud_offsets",
        "cloud_lidar",
        "cloud_frame",
        "frame_seq",
        "frame_index",
        "sequences",
        "sample_cloud",
        "gt",
        "gt_offsets",
        "meta",
    )

    def __init__(self, path: str | Path, *, name: str = "path") -> None:
        """Reads the cache at ``path``; ``name`` is the argument that gave it, for the messages (``path``; ``cache``
        where :func:`mmusv.learn.train.train` reads it; a flag on the command line: :func:`mmusv.text.given`)."""
        p = Path(path)
        try:
            # numpy leaves the file it opened open when it is not a zip: the file is ours to close
            with open(p, "rb") as fh, np.load(fh, allow_pickle=False) as z:
                missing = [k for k in self.KEYS if k not in z.files]
                if missing:
                    raise input_error(f"{given(name, p)}: not an mmusv.learn cache (missing {missing})")
                self.arrays: dict[str, np.ndarray] = {k: z[k] for k in self.KEYS}
                if "cloud_agent" in z.files:  # caches written before it was added lack it
                    self.arrays["cloud_agent"] = z["cloud_agent"]
        except (OSError, ValueError, EOFError, TypeError, zipfile.BadZipFile) as exc:  # a cut copy; a .npy (TypeError)
            raise input_error(f"{given(name, p)}: not a readable .npz cache ({type(exc).__name__}: {exc})") from None
        self.path = p
        try:
            self.meta: dict[str, Any] = json.loads(str(self.arrays["meta"]))
        except ValueError:
            raise input_error(f"{given(name, p)}: meta: not JSON (not an mmusv.learn cache)") from None
        a = self.arrays
        _check_arrays(p, a, name)
        self.frame_clouds: list[np.ndarray] = [np.zeros(0, np.int64)] * len(a["frame_seq"])
        order = np.argsort(a["cloud_frame"], kind="stable")
        bounds = np.searchsorted(a["cloud_frame"][order], np.arange(len(a["frame_seq"]) + 1))
        self.frame_clouds = [order[bounds[f] : bounds[f + 1]] for f in range(len(a["frame_seq"]))]

    def __len__(self) -> int:
        return len(self.arrays["sample_cloud"])

    def identity(self) -> dict[str, Any]:
        """What the cache was built from (module docstring): ``sources``, ``fingerprints`` (when recorded),
        ``range_m``, ``frame_stride``, and the ``split``, ``ratios`` and ``seed`` that chose the sequences."""
        return _identity_of(self.meta)

    def cloud(self, c: int) -> np.ndarray:
        """``(N, 4)`` float32 points of cloud ``c`` (LiDAR frame, metres; intensity in [0, 1])."""
        a = self.arrays
        lo, hi = a["cloud_offsets"][c], a["cloud_offsets"][c + 1]
        out = np.empty((hi - lo, 4), dtype=np.float32)
        out[:, :3] = a["xyz_cm"][lo:hi].astype(np.float32) / 100.0
        out[:, 3] = a["intensity"][lo:hi].astype(np.float32) / 255.0
        return out

    def key(self, c: int) -> tuple[str, int, str]:
        """``(sequence, acquisition index, agent id)`` of cloud ``c``: the detection study's key of an ego."""
        a = self.arrays
        f = int(a["cloud_frame"][c])
        agent = str(a["cloud_agent"][c]) if "cloud_agent" in a else str(c)
        return str(a["sequences"][a["frame_seq"][f]]), int(a["frame_index"][f]), agent

    def frame_position(self, k: int) -> int:
        """The position of sample ``k``'s frame within its sequence (0 for the first frame)."""
        a = self.arrays
        f = int(a["cloud_frame"][a["sample_cloud"][k]])
        first = int(np.searchsorted(a["frame_seq"], a["frame_seq"][f]))
        return f - first

    def sample(self, k: int) -> Sample:
        """Sample ``k``: the ego's cloud, every neighbour's cloud with its pose in the ego frame, the ground truth."""
        a = self.arrays
        c = int(a["sample_cloud"][k])
        f = int(a["cloud_frame"][c])
        inv = np.linalg.inv(a["cloud_lidar"][c])
        nbs = [(self.cloud(int(o)), inv @ a["cloud_lidar"][o]) for o in self.frame_clouds[f] if int(o) != c]
        gt = a["gt"][a["gt_offsets"][k] : a["gt_offsets"][k + 1]].astype(np.float64)
        return self.cloud(c), nbs, gt
