"""The glTF document's graph, for :mod:`mmusv.world.gltf_checks`: the indices its entries give into its lists (a
scene's nodes, a node's mesh and children, a primitive's material and accessors, a texture's image) and the refusal
of one that is not in its list; its nodes' transforms and trees (one parent at most, no cycle); which meshes its
scene draws, and why a file whose scene draws no triangle holds none. Each refusal is one
:class:`~mmusv.world.asset_spec.AssetSpecError` at the asset entry naming the file and the glTF entry.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from typing import TypeGuard

from mmusv.world.asset_spec import AssetSpecError

__all__ = [
    "MODES",
    "TEXTURE_SLOTS",
    "finite_number",
    "node_checks",
    "primitives",
    "reference_checks",
    "surface_checks",
]


def finite_number(value: object) -> TypeGuard[float]:
    """Whether a JSON value is a finite number (``true`` and ``false`` are not)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _numbers(value: object, n: int) -> TypeGuard[list[float]]:
    """Whether a JSON value is a list of ``n`` finite numbers."""
    return isinstance(value, list) and len(value) == n and all(finite_number(v) for v in value)


def primitives(data: dict[str, object]) -> Iterator[tuple[int, int, dict[str, object]]]:
    """``(i, j, primitive)`` of every ``meshes[i].primitives[j]`` of a glTF JSON that is an object, in file order
    (entries of other kinds are skipped: trimesh's loader reports them)."""
    meshes = data.get("meshes")
    for i, m in enumerate(meshes if isinstance(meshes, list) else []):
        prims = m.get("primitives") if isinstance(m, dict) else None
        for j, p in enumerate(prims if isinstance(prims, list) else []):
            if isinstance(p, dict):
                yield i, j, p


TEXTURE_SLOTS = (
    ("pbrMetallicRoughness", "baseColorTexture"),
    ("pbrMetallicRoughness", "metallicRoughnessTexture"),
    (None, "emissiveTexture"),
)
"""The texture slots of a material mmusv reads (by their mean): (the object holding it, its name)."""


def _material_textures(material: object) -> Iterator[tuple[str, object]]:
    """``(where, texture info)`` of each of :data:`TEXTURE_SLOTS` a glTF material gives (``pbrMetallicRoughness.
    baseColorTexture``, ...)."""
    if not isinstance(material, dict):
        return
    for holder, name in TEXTURE_SLOTS:
        obj = material.get(holder) if holder else material
        if isinstance(obj, dict) and name in obj:
            yield (f"{holder}.{name}" if holder else name), obj[name]


MODES = {0: "POINTS", 1: "LINES", 2: "LINE_LOOP", 3: "LINE_STRIP", 4: "TRIANGLES", 5: "TRIANGLE_STRIP"}
MODES[6] = "TRIANGLE_FAN"


def _references(data: dict[str, object]) -> Iterator[tuple[str, object, str]]:
    """Every index the glTF's JSON gives into one of its lists: ``(where it is, the index, the list's name)``."""

    def items(name: str) -> list[object]:
        v = data.get(name)
        return v if isinstance(v, list) else []

    if "scene" in data:
        yield "scene", data["scene"], "scenes"
    for i, sc in enumerate(items("scenes")):
        for j, n in enumerate(
            sc.get("nodes", []) if isinstance(sc, dict) and isinstance(sc.get("nodes"), list) else []
        ):
            yield f"scenes[{i}].nodes[{j}]", n, "nodes"
    for i, nd in enumerate(items("nodes")):
        if not isinstance(nd, dict):
            continue
        if "mesh" in nd:
            yield f"nodes[{i}].mesh", nd["mesh"], "meshes"
        kids = nd.get("children")
        for j, n in enumerate(kids if isinstance(kids, list) else []):
            yield f"nodes[{i}].children[{j}]", n, "nodes"
    for i, me in enumerate(items("meshes")):
        prims = me.get("primitives") if isinstance(me, dict) else None
        for j, pr in enumerate(prims if isinstance(prims, list) else []):
            if not isinstance(pr, dict):
                continue
            at = f"meshes[{i}].primitives[{j}]"
            if "material" in pr:
                yield f"{at}.material", pr["material"], "materials"
            if "indices" in pr:
                yield f"{at}.indices", pr["indices"], "accessors"
            attrs = pr.get("attributes")
            for name, a in attrs.items() if isinstance(attrs, dict) else []:
                yield f"{at}.attributes.{name}", a, "accessors"
    for i, ac in enumerate(items("accessors")):
        if isinstance(ac, dict) and "bufferView" in ac:
            yield f"accessors[{i}].bufferView", ac["bufferView"], "bufferViews"
    for i, bv in enumerate(items("bufferViews")):
        if isinstance(bv, dict) and "buffer" in bv:
            yield f"bufferViews[{i}].buffer", bv["buffer"], "buffers"
    for i, tx in enumerate(items("textures")):
        if isinstance(tx, dict) and "source" in tx:
            yield f"textures[{i}].source", tx["source"], "images"
    for i, mat in enumerate(items("materials")):
        for at, info in _material_textures(mat):
            if isinstance(info, dict) and "index" in info:
                yield f"materials[{i}].{at}.index", info["index"], "textures"


def reference_checks(shown: str, data: dict[str, object], where: str) -> None:
    """Refuses an index into one of the glTF's lists that is not in it (``scene: 5`` with one scene, a primitive's
    ``material: 7`` with one material): trimesh failed on them with a bare ``IndexError: list index out of range``."""
    for at, index, kind in _references(data):
        items = data.get(kind)
        n = len(items) if isinstance(items, list) else 0
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < n:
            have = f"indices 0..{n - 1}" if n else "none"
            raise AssetSpecError(where, f"{shown}: {at} is {index!r}, but the file has {n} {kind} ({have})")


def node_checks(shown: str, data: dict[str, object], where: str) -> None:
    """Refuses node transforms and hierarchies glTF 2.0 does not allow, which trimesh read some way without a word:
    a ``matrix`` given with ``translation``/``rotation``/``scale`` (both were applied), a ``matrix`` that is not 16
    finite numbers of an affine transform (its last row (0, 0, 0, 1)), a ``rotation`` that is not a unit quaternion
    (a zero one was read as no rotation), ``translation``/``scale`` not three finite numbers, and a node that is a
    child of two nodes or of its own subtree (the nodes form disjoint strict trees)."""
    nodes = data.get("nodes")
    items = nodes if isinstance(nodes, list) else []
    parent: dict[int, int] = {}
    for i, node in enumerate(items):
        if not isinstance(node, dict):
            raise AssetSpecError(where, f"{shown}: nodes[{i}] is {node!r:.60}, not an object")
        at = f"{shown}: nodes[{i}]"
        trs = [k for k in ("translation", "rotation", "scale") if k in node]
        if "matrix" in node:
            m = node["matrix"]
            if trs:
                raise AssetSpecError(
                    where, f"{at} has both a matrix and {', '.join(trs)}; glTF 2.0 allows one or the other"
                )
            if not _numbers(m, 16):
                raise AssetSpecError(where, f"{at}.matrix is {m!r:.80}; glTF 2.0 asks for 16 finite numbers")
            if [m[3], m[7], m[11], m[15]] != [0, 0, 0, 1]:
                raise AssetSpecError(
                    where,
                    f"{at}.matrix's last row is {[m[3], m[7], m[11], m[15]]} (column-major: elements 3, 7, 11, 15), "
                    "not [0, 0, 0, 1]; glTF 2.0 node matrices are affine (translation, rotation, scale)",
                )
        for key, n in (("translation", 3), ("rotation", 4), ("scale", 3)):
            if key in node and not _numbers(node[key], n):
                raise AssetSpecError(where, f"{at}.{key} is {node[key]!r:.80}; glTF 2.0 asks for {n} finite numbers")
        if "rotation" in node:
            norm = math.sqrt(sum(float(v) ** 2 for v in node["rotation"]))
            if abs(norm - 1.0) > 1e-3:
                raise AssetSpecError(
                    where,
                    f"{at}.rotation is {node['rotation']!r}, of length {norm:.6g}; glTF 2.0 rotations are unit "
                    "quaternions [x, y, z, w] (no rotation: [0, 0, 0, 1])",
                )
        kids = node.get("children", [])
        for c in kids if isinstance(kids, list) else []:
            if not isinstance(c, int) or isinstance(c, bool):
                continue  # reference_checks refused it
            if c in parent or c == i:
                other = "itself" if c == i else f"nodes[{parent[c]}] too"
                raise AssetSpecError(
                    where,
                    f"{at} names nodes[{c}] as a child, which is a child of {other}; glTF 2.0 nodes form disjoint "
                    "trees (a node has one parent at most)",
                )
            parent[c] = i
    for i in range(len(items)):  # a node among its own ancestors
        seen, k = {i}, i
        while k in parent:
            k = parent[k]
            if k in seen:
                raise AssetSpecError(
                    where, f"{shown}: nodes[{i}] is its own ancestor (a cycle of children); glTF 2.0 nodes form trees"
                )
            seen.add(k)


def _drawn_meshes(data: dict[str, object]) -> tuple[int, set[int]] | None:
    """The scene trimesh draws (``scene``, else the first of ``scenes``, as glTF 2.0 leaves the choice to the reader)
    and the meshes its nodes place, through their children; ``None`` where the file has no scene."""
    scenes = data.get("scenes")
    if not isinstance(scenes, list) or not scenes:
        return None
    k = data.get("scene", 0)
    scene = scenes[k] if isinstance(k, int) and not isinstance(k, bool) and 0 <= k < len(scenes) else None
    nodes = data.get("nodes")
    items = nodes if isinstance(nodes, list) else []
    roots = scene.get("nodes") if isinstance(scene, dict) else None
    todo, seen, placed = list(roots if isinstance(roots, list) else []), set(), set()
    while todo:
        n = todo.pop()
        if isinstance(n, bool) or not isinstance(n, int) or n in seen or not 0 <= n < len(items):
            continue
        seen.add(n)
        node = items[n]
        if not isinstance(node, dict):
            continue
        mesh = node.get("mesh")
        if isinstance(mesh, int) and not isinstance(mesh, bool):
            placed.add(mesh)
        kids = node.get("children")
        todo.extend(kids if isinstance(kids, list) else [])
    return (k if isinstance(k, int) else 0), placed


def surface_checks(shown: str, data: dict[str, object], where: str) -> None:
    """Says why a file with primitives gives no triangle, where trimesh's reading said only that it "holds no
    triangles": no scene places its meshes (a glTF draws only what its scene's nodes place), or what its scene places
    is points and lines (no surface); and warns (:class:`~mmusv.scenario_checks.MmusvWarning`) of points and lines
    left out beside triangles, which were dropped without a word."""
    prims = list(primitives(data))
    if not prims:
        return  # no primitive at all: "holds no triangles" says it
    drawn = _drawn_meshes(data)
    modes = [] if drawn is None else [(i, j, p.get("mode", 4)) for i, j, p in prims if i in drawn[1]]
    if drawn is None or not modes:
        meshes = data.get("meshes")
        n = len(meshes) if isinstance(meshes, list) else 0
        what = (
            "has no scene (no scenes list)"
            if drawn is None
            else f"draws scenes[{drawn[0]}], whose nodes place no primitive of its {n} meshes"
        )
        raise AssetSpecError(
            where,
            f"{shown} {what}: a glTF draws only the meshes its scene's nodes place, so it holds no triangles to "
            "read; export it with its meshes placed in a scene (a node naming each mesh, in scenes[].nodes)",
        )
    loose = [(i, j, m) for i, j, m in modes if m in (0, 1, 2, 3)]
    listed = ", ".join(f"meshes[{i}].primitives[{j}] {MODES[m]}" for i, j, m in loose[:3])
    listed += ", ..." if len(loose) > 3 else ""
    if len(loose) == len(modes):
        raise AssetSpecError(
            where,
            f"{shown} holds no triangles: the primitives its scene places are points or lines ({listed}), which have "
            "no surface for the sensors to see; a vessel needs triangles (mode 4 TRIANGLES or 5 TRIANGLE_STRIP)",
        )
    if loose:
        from mmusv.scenario_checks import MmusvWarning  # here: scenario_checks imports the config, which imports us

        warnings.warn(
            f"{where}: {shown}: {len(loose)} primitive(s) of points or lines left out ({listed}): only triangles are "
            "surfaces the sensors see",
            MmusvWarning,
            stacklevel=4,
        )
