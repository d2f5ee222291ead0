"""Vessels alone in the world: one single-instance scene per vessel asset, to cast rays against a vessel with
nothing else in the way (:class:`SilhouetteCache`). The annotations' occlusion and wave-occlusion shares
(:mod:`mmusv.annotate`, :mod:`mmusv.wave_occlusion`) count a vessel's silhouette so.

Frames: world x east, y north, z up, metres; a pose is the ``(4, 4)`` vessel body → world transform.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from mmusv.scene import Scene
from mmusv.world.vessels import VesselAsset, get_asset

__all__ = ["SilhouetteCache"]


class SilhouetteCache:
    """One single-instance scene per vessel asset, to render a vessel with nothing else in the way. ``assets``: the
    assets by name, as a :class:`~mmusv.simulation.Simulation` holds them (``sim.assets``), else those of the
    library now (a scenario read since may hold another asset under the same name)."""

    def __init__(self, assets: Mapping[str, VesselAsset] | None = None) -> None:
        self._scenes: dict[str, tuple[VesselAsset, Scene, int]] = {}
        self.assets = assets

    def hits(self, asset: str, *, pose: np.ndarray, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """``(N,)`` bool: which rays (``origins``, ``directions`` ``(N, 3)`` world, metres) hit the vessel ``asset``
        at ``pose`` (``(4, 4)`` body → world), alone in the world."""
        hit: np.ndarray = np.isfinite(self.distances(asset, pose=pose, origins=origins, directions=directions))
        return hit

    def distances(self, asset: str, *, pose: np.ndarray, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """``(N,)`` float32 distance (metres along each normalised direction) at which each ray meets the vessel
        ``asset`` at ``pose`` (body → world), alone in the world; ``inf`` where it misses."""
        a = self.assets[asset] if self.assets is not None and asset in self.assets else get_asset(asset)
        if asset not in self._scenes or self._scenes[asset][0] is not a:
            s = Scene()
            mid = s.add_mesh(a.mesh.vertices, a.mesh.faces, classes=a.mesh.classes, name=asset)
            self._scenes[asset] = (a, s, s.add_instance(mid))
        _, scene, inst = self._scenes[asset]
        scene.set_poses([inst], pose[None])
        if origins.shape[0] == 0:
            return np.zeros(0, dtype=np.float32)
        return scene.cast_rays(origins, directions).distance

    def distances_boxes(
        self,
        assets: list[str],
        *,
        poses: list[np.ndarray],
        origins: np.ndarray,
        directions: np.ndarray,
        starts: np.ndarray,
    ) -> np.ndarray:
        """:meth:`distances` of many vessels' rays at once: ``(N,)`` float32, rows ``starts[b]:starts[b + 1]`` of
        ``origins`` and ``directions`` (``(N, 3)``, world) cast against vessel ``assets[b]`` at ``poses[b]`` (body
        → world) alone; ``starts`` ``(B + 1,)`` row offsets from 0 to ``N``."""
        parts = [
            self.distances(
                a, pose=p, origins=origins[starts[b] : starts[b + 1]], directions=directions[starts[b] : starts[b + 1]]
            )
            for b, (a, p) in enumerate(zip(assets, poses, strict=True))
        ]
        return np.concatenate(parts) if parts else np.zeros(0, dtype=np.float32)
