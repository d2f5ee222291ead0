"""Turning a generated map and a scenario's vessels into a ray-castable :class:`mmusv.Scene`.

Static map meshes become one instance each at the identity pose (instance ids ``0..S-1`` in the key order of
``MapWorld.static_meshes``), except the buoys: one buoy mesh instanced once per buoy at its position (each buoy
its own instance id, in ``MapPriors.buoys`` order, where the ``"buoys"`` key falls; over a physical sea they ride
the waves, :mod:`mmusv.world.buoys`); every vessel asset is added once as a mesh and instanced per vessel, so moving
vessels only rebuilds the scene's top level. Moored ships of a port map are static instances of their assets.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mmusv.classes import SemanticClass
from mmusv.frames import pose_matrices  # re-exported: the pose convention lives in mmusv.frames
from mmusv.scene import Scene
from mmusv.world.buoys import buoy_matrices
from mmusv.world.maps import MapWorld
from mmusv.world.materials import material_table
from mmusv.world.port import buoy_mesh
from mmusv.world.primitives import TriMesh
from mmusv.world.vessels import get_asset

__all__ = ["WorldScene", "build_static_scene", "build_world_scene", "pose_matrices"]


@dataclass
class WorldScene:
    """A scene plus the bookkeeping that maps scenario objects to instance ids.

    Attributes:
        scene: the ray-castable scene.
        static_instances: map mesh name -> instance id.
        vessel_instances: ``(V,)`` int64 instance id of scenario vessel ``i``.
        moored_instances: instance ids of moored ships (port maps), in ``MapWorld.moored`` order.
        buoy_instances: instance ids of the map's buoys, in ``MapPriors.buoys`` order (their rest positions).
        asset_meshes: asset name -> mesh id.
    """

    scene: Scene
    static_instances: dict[str, int]
    vessel_instances: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    moored_instances: list[int] = field(default_factory=list)
    buoy_instances: list[int] = field(default_factory=list)
    asset_meshes: dict[str, int] = field(default_factory=dict)


def _add(scene: Scene, mesh: TriMesh, name: str) -> int:
    """Adds ``mesh`` with its materials; the scene's material table is (re)set first when the mesh names a
    material it does not have yet (user assets register theirs when they load)."""
    mats = mesh.materials
    if mats.size and int(mats.max()) >= scene.num_materials:
        scene.set_materials(material_table())
    return scene.add_mesh(mesh.vertices, mesh.faces, classes=mesh.classes, name=name, materials=mats)


def build_static_scene(world: MapWorld, *, include_water: bool = True, include_moored: bool = True) -> WorldScene:
    """A scene holding the map's static meshes (and its moored ships), no scenario vessels.

    ``include_water=False`` leaves the water plane out (useful for line-of-sight checks above the surface).
    """
    scene = Scene()
    scene.set_materials(material_table())
    static: dict[str, int] = {}
    buoys: list[int] = []
    for name, mesh in world.static_meshes.items():
        if name == "water" and not include_water:
            continue
        if mesh.num_triangles == 0:
            continue
        if name == "buoys":
            # One mesh, one instance a buoy (its own instance id), at rest at its position.
            buoy = _add(scene, buoy_mesh(0.0, 0.0), "buoy")
            rest = buoy_matrices(None, world.priors.buoys, 0.0)
            buoys += [scene.add_instance(buoy, pose=m) for m in rest]
            continue
        static[name] = scene.add_instance(_add(scene, mesh, name))
    hf = world.heightfield
    # The bottom the cameras see through shallow water (the terrain's heights, below the sea surface there).
    scene.set_seabed(hf.z, x0=hf.x0, y0=hf.y0, spacing=hf.spacing)
    out = WorldScene(scene=scene, static_instances=static, buoy_instances=buoys)
    if include_moored:
        for asset_name, (x, y, yaw) in world.moored:
            mid = _mesh_for(out, asset_name)
            pose = pose_matrices(np.array([x, y, 0.0, 0.0, 0.0, yaw]))
            out.moored_instances.append(scene.add_instance(mid, pose=pose))
    return out


def _mesh_for(ws: WorldScene, asset_name: str) -> int:
    if asset_name not in ws.asset_meshes:
        asset = get_asset(asset_name)
        ws.asset_meshes[asset_name] = _add(ws.scene, asset.mesh, asset_name)
    return ws.asset_meshes[asset_name]


def build_world_scene(
    world: MapWorld,
    vessels: list[tuple[str, str]],
    initial_poses: np.ndarray,
    *,
    moored_move: bool = False,
    buoys_move: bool = False,
) -> WorldScene:
    """The full scene: static map, moored ships, and one instance per scenario vessel.

    Args:
        world: the generated map.
        vessels: ``(asset_name, role)`` per scenario vessel, role ``"usv"`` or ``"target"``; a USV's faces are
            labelled :data:`SemanticClass.USV` whatever the asset says.
        initial_poses: ``(V, 6)`` float64 poses η ``[x, y, z, roll, pitch, yaw]`` (world frame, metres, radians)
            of the vessels at the first frame.
        moored_move: the moored ships move too (over a physical sea they heave, roll and pitch at their berths):
            the sea's shortcuts count them among the moving instances, not in the static height bound.
        buoys_move: the buoys ride the waves (a physical sea, :mod:`mmusv.world.buoys`): moving instances too.
    """
    ws = build_static_scene(world)
    mats = pose_matrices(np.asarray(initial_poses, dtype=np.float64).reshape(-1, 6))
    ids = []
    for (asset_name, role), m in zip(vessels, mats, strict=True):
        override = int(SemanticClass.USV) if role == "usv" else None
        ids.append(ws.scene.add_instance(_mesh_for(ws, asset_name), pose=m, class_override=override))
    ws.vessel_instances = np.asarray(ids, dtype=np.int64)
    if "water" in ws.static_instances:
        # Exact shortcuts for rays that can only meet the sea or the sky (vessels are the instances that move).
        moving = ws.vessel_instances
        if moored_move and ws.moored_instances:
            moving = np.concatenate([moving, np.asarray(ws.moored_instances, dtype=np.int64)])
        if buoys_move and ws.buoy_instances:
            moving = np.concatenate([moving, np.asarray(ws.buoy_instances, dtype=np.int64)])
        ws.scene.set_sea(ws.static_instances["water"], moving=moving)
    return ws
