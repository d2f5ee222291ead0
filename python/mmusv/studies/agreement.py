"""Annotation-vs-rendering agreement (Table II of the paper): do the 3D box labels sit on the rendered vessels?

For every USV's top-view camera and every frame, each other vessel's 3D box (its world-state pose and asset box)
is projected into the top-view image: the convex hull of the 8 projected corners (shapely). The vessel mask is
the top-view semantic image's vessel/USV pixels; its connected component overlapping the hull the most is the
rendered vessel. A sample is valid when the hull lies inside the image and such a component exists and belongs
to this vessel alone (per the instance image). Per sample:

* ``centre error`` (px): distance between the projected box centre and the centre of the component's extent
  measured along the box's own axes (mid-point of the farthest mask pixels forward/aft and port/starboard) —
  the quantity a box fitted to the mask would have;
* ``forward offset`` and ``port offset`` (px, signed): that extent centre's offset from the projected box centre
  along the box's forward (bow) and port axes, the two components of the centre error. A pointed bow, whose tip
  narrows below a pixel, loses its tip's pixels to the pixel-centre sampling of the semantic image while a transom
  keeps its last row: on the bundled scenarios the forward offset is negative (aft) while the port offset is not
  biased (``docs/studies/agreement.md``);
* ``centroid error`` (px): distance between the projected box centre and the centroid of the component's pixels
  inside the hull, M_local ∩ H_proj (what the paper reports; it also measures how asymmetric a hull is about its
  box centre);
* ``containment``: share of component pixel centres inside the hull (on its edge counts as inside);
* ``hull occupancy``: component pixels inside the hull / hull area, |M_local ∩ H_proj| / |H_proj| (the paper's).

Per map the study reports the number of valid samples, the medians of both errors, mean containment and mean
occupancy (a map without valid samples has no row; the tables keep their columns).

Every vessel other than the observing USV is sampled, the other USVs included, where the paper samples "each
visible target vessel" (``docs/studies/agreement.md`` gives the table over the targets alone).
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from dataclasses import dataclass
from numbers import Integral
from pathlib import Path

import numpy as np
import polars as pl
import shapely
from scipy import ndimage

from mmusv.boxes3d import box_corners
from mmusv.bundled import resolve_scenario
from mmusv.config import Scenario, load_scenario
from mmusv.errors import ConfigError, located
from mmusv.forking import check_polars
from mmusv.frames import translation
from mmusv.held_signals import raise_noted_stop
from mmusv.jsonio import write_files_atomic
from mmusv.sensors.config import RigConfig
from mmusv.simulation import Simulation

__all__ = [
    "BUNDLED_SCENARIOS",
    "FILES",
    "AgreementStudy",
    "check_counts",
    "load_scenarios",
    "run_agreement_study",
    "sample_agreement",
]

BUNDLED_SCENARIOS = ("scenarios/island_occlusion.yaml", "scenarios/open_sea_convoy.yaml", "scenarios/port_entry.yaml")
FILES = ("agreement_samples.parquet", "agreement_summary.csv")
"""The files :meth:`AgreementStudy.write` writes (the samples, the summary)."""
_VESSEL_CLASSES = (10, 11)


def sample_agreement(
    *,
    semantic: np.ndarray,
    instance: np.ndarray,
    camera_pose: np.ndarray,
    metres_per_pixel: float,
    box_matrix: np.ndarray,
    box_size: np.ndarray,
    instance_id: int,
) -> dict[str, float] | None:
    """One vessel in one top-view image; ``None`` when the sample is not valid (see the module docstring).

    ``camera_pose``: ``(4, 4)`` top-view camera body → world (x = viewing direction); ``box_matrix``: ``(4, 4)``
    box → world (centred); ``box_size``: full length, beam, height (m).
    """
    h, w = semantic.shape
    inv = np.linalg.inv(camera_pose)
    corners = box_corners(box_matrix, box_size) @ inv[:3, :3].T + inv[:3, 3]
    # Continuous pixel coordinates (pixel centres at +0.5): u = W/2 − y/m, v = H/2 − z/m.
    uv = np.stack([w / 2.0 - corners[:, 1] / metres_per_pixel, h / 2.0 - corners[:, 2] / metres_per_pixel], axis=1)
    if uv.min() < 0 or uv[:, 0].max() > w or uv[:, 1].max() > h:
        return None
    hull = shapely.convex_hull(shapely.multipoints(uv))
    if hull.area <= 0:
        return None
    labels, _ = ndimage.label(np.isin(semantic, _VESSEL_CLASSES))
    u0, v0 = int(np.floor(uv[:, 0].min())), int(np.floor(uv[:, 1].min()))
    u1, v1 = int(np.ceil(uv[:, 0].max())), int(np.ceil(uv[:, 1].max()))
    vv, uu = np.mgrid[v0:v1, u0:u1]
    inside = shapely.contains_xy(hull, uu + 0.5, vv + 0.5)
    cand = labels[v0:v1, u0:u1][inside]
    cand = cand[cand > 0]
    if cand.size == 0:
        return None
    comp = int(np.bincount(cand).argmax())
    rows, cols = np.nonzero(labels == comp)
    owners = instance[rows, cols]
    if np.count_nonzero(owners == instance_id) < owners.size:
        return None  # merged with another vessel, or not this vessel at all
    px = np.stack([cols + 0.5, rows + 0.5], axis=1)
    in_hull = shapely.contains_xy(hull, px[:, 0], px[:, 1]) | shapely.intersects_xy(hull.boundary, px[:, 0], px[:, 1])
    contained = float(np.mean(in_hull))
    centre_body = inv[:3, :3] @ box_matrix[:3, 3] + inv[:3, 3]
    centre_uv = np.array([w / 2.0 - centre_body[1] / metres_per_pixel, h / 2.0 - centre_body[2] / metres_per_pixel])
    # The box's forward and port axes in the image plane.
    axes_body = inv[:3, :3] @ box_matrix[:3, :2]
    axes_uv = np.stack([-axes_body[1], -axes_body[2]], axis=0)  # columns: forward, port (in pixel units per metre·m)
    extent_centre = centre_uv.copy()
    offsets = [0.0, 0.0]
    for k in range(2):
        a = axes_uv[:, k]
        n = np.linalg.norm(a)
        if n < 1e-9:
            continue
        a = a / n
        proj = (px - centre_uv) @ a
        offsets[k] = float((proj.min() + proj.max()) / 2.0)
        extent_centre += a * offsets[k]
    return {
        "centre_error_px": float(np.linalg.norm(extent_centre - centre_uv)),
        "forward_offset_px": offsets[0],
        "port_offset_px": offsets[1],
        # M_local ∩ H_proj, as the paper (the whole component's centroid moved with the pixels outside the hull).
        "centroid_error_px": float(np.linalg.norm(px[in_hull].mean(axis=0) - centre_uv)),
        "containment": contained,
        "hull_occupancy": float(np.count_nonzero(in_hull) / hull.area),
        "pixels": float(px.shape[0]),
    }


@dataclass(frozen=True)
class AgreementStudy:
    """The per-sample table and the per-map summary."""

    samples: pl.DataFrame
    summary: pl.DataFrame

    def write(self, out_dir: Path) -> dict[str, Path]:
        """Writes ``agreement_samples.parquet`` and ``agreement_summary.csv`` under ``out_dir`` (created) with
        :func:`mmusv.jsonio.write_files_atomic`; returns their paths."""
        paths = {key: out_dir / name for key, name in zip(("samples", "summary"), FILES, strict=True)}
        samples = io.BytesIO()
        self.samples.write_parquet(samples)
        write_files_atomic(
            {paths["samples"]: samples.getvalue(), paths["summary"]: self.summary.write_csv().encode("utf-8")}
        )
        return paths


def check_counts(frames: int | None, stride: int = 1) -> None:
    """Raises :class:`~mmusv.errors.ConfigError` for ``frames`` (``None``: all) or ``stride`` below 1, which
    evaluated nothing and wrote an empty table: :func:`run_agreement_study`'s check, for a caller to make before
    it prepares anything."""
    if frames is not None and (isinstance(frames, bool) or not isinstance(frames, Integral) or frames < 1):
        raise ConfigError(f"frames (--frames) = {frames!r}: must be a whole number >= 1 (or left out for all frames)")
    if isinstance(stride, bool) or not isinstance(stride, Integral) or stride < 1:
        raise ConfigError(f"stride = {stride!r}: must be a whole number >= 1")


def load_scenarios(scenarios: Sequence[str | Path | Scenario]) -> list[Scenario]:
    """The scenarios (paths, names of bundled ones, or loaded ones), each loaded and checked: at least one USV
    whose rig has a top-view camera (:class:`~mmusv.errors.ConfigError` naming the scenario otherwise; such a
    scenario was an empty table and exit status 0). :func:`run_agreement_study`'s check, for a caller to make
    before it prepares anything (a missing second scenario was named only after the first had run)."""
    out = []
    seen: dict[str, str] = {}
    for path in scenarios:
        sc = path if isinstance(path, Scenario) else load_scenario(resolve_scenario(path))
        where = f"scenario {sc.name!r}" if isinstance(path, Scenario) else str(path)
        usvs = [v for v in sc.vessels if v.role == "usv"]
        if not any((sc.rigs[v.rig] if v.rig is not None else RigConfig()).top_view is not None for v in usvs):
            why = "no vessel with role: usv" if not usvs else "no USV whose rig has a top_view (rigs.NAME.top_view)"
            raise located(ConfigError(f"the agreement study needs a USV's top-view camera; it has {why}"), where)
        if sc.name in seen:  # its samples were counted twice in the table, under one name in the samples' file
            raise ConfigError(
                f"{where}: the scenario name {sc.name!r} is taken by an earlier scenario of the study "
                f"({seen[sc.name]}): the samples name their scenario, so two of one name cannot be told apart (and "
                "one given twice counts twice); give each scenario once, under a name of its own (its name: field)"
            )
        seen[sc.name] = where
        out.append(sc)
    return out


_SAMPLE_SCHEMA = {
    "map": pl.String,
    "scenario": pl.String,
    "frame": pl.Int64,
    "agent": pl.String,
    "target": pl.String,
    "centre_error_px": pl.Float64,
    "forward_offset_px": pl.Float64,
    "port_offset_px": pl.Float64,
    "centroid_error_px": pl.Float64,
    "containment": pl.Float64,
    "hull_occupancy": pl.Float64,
    "pixels": pl.Float64,
}


def run_agreement_study(
    scenarios: Sequence[str | Path | Scenario] = BUNDLED_SCENARIOS, *, frames: int | None = None, stride: int = 1
) -> AgreementStudy:
    """Runs the top-view cameras of every USV over ``frames`` frames (default: the scenario's) of each scenario
    and evaluates every other vessel (see the module docstring); every ``stride``-th frame. ``frames`` and
    ``stride`` below 1 raise :class:`~mmusv.errors.ConfigError` (before any scenario is loaded): they evaluated
    nothing and wrote an empty table; every scenario is loaded and checked (:func:`load_scenarios`) before the
    first is run. The scenarios run, and their samples come, in name order, whatever the order given: the same
    scenarios give the same bytes."""
    check_polars("mmusv study agreement")
    check_counts(frames, stride)
    rows: list[dict[str, object]] = []
    # In name order (the names are unique, load_scenarios checks): the samples were in the order the scenarios were
    # given and the per-map means summed them so, so `A B` and `B A` wrote other bytes (the means' last digits too).
    for sc in sorted(load_scenarios(scenarios), key=lambda s: s.name):
        sim = Simulation(sc)
        n = sc.acquisition.frames if frames is None else min(frames, sc.acquisition.frames)
        for k in range(0, n, stride):
            raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
            cap = sim.capture(k, sensors=["top_view"])
            state = cap.world
            for agent in sim.agents:
                ac = cap.agents[agent.id]
                tv = agent.rig.top_view
                if ac.top_view is None or ac.top_view_pose is None or tv is None:
                    continue
                for vi, info in enumerate(sim.vessels):
                    if vi == agent.index:
                        continue
                    box = state.matrices[vi] @ translation(info.box_center_body)
                    r = sample_agreement(
                        semantic=ac.top_view.semantic,
                        instance=ac.top_view.instance,
                        camera_pose=ac.top_view_pose,
                        metres_per_pixel=tv.metres_per_pixel,
                        box_matrix=box,
                        box_size=info.box_size,
                        instance_id=info.instance_id,
                    )
                    if r is not None:
                        rows.append(
                            {
                                "map": sc.map.type,
                                "scenario": sc.name,
                                "frame": k,
                                "agent": agent.id,
                                "target": info.id,
                                **r,
                            }
                        )
    # The same columns with or without samples (an empty table had two columns, its CSV a two-column header).
    samples = pl.DataFrame(rows, schema=_SAMPLE_SCHEMA)
    summary = (
        samples.group_by("map", maintain_order=True)
        .agg(
            pl.len().alias("valid_samples"),
            pl.col("centre_error_px").median().alias("median_centre_error_px"),
            pl.col("centroid_error_px").median().alias("median_centroid_error_px"),
            pl.col("containment").mean().alias("mean_containment"),
            pl.col("hull_occupancy").mean().alias("mean_hull_occupancy"),
        )
        .sort("map")
    )
    return AgreementStudy(samples, summary)
