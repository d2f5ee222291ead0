"""Procedural vessel meshes against independent expectations: closed-form volumes and corners of simple hulls
and parts (mmusv.world.vessel_shapes, built from specs validated by mmusv.world.asset_spec)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from mmusv.world.vessels import VesselAsset, load_asset_file
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

L, B, DRAFT, DEPTH = 10.0, 4.0, 1.0, 3.0
FREEBOARD = DEPTH - DRAFT
# every taper off: the hull is exactly the box [-L/2, L/2] x [-B/2, B/2] x [-DRAFT, FREEBOARD]
SQUARE = {
    "length": L,
    "beam": B,
    "draft": DRAFT,
    "depth": DEPTH,
    "bow": 0.0,
    "stern": 0.0,
    "rake": 0.0,
    "bottom": 1.0,
    "flare": 1.0,
}


def _asset(hull: dict[str, Any], parts: list[dict[str, Any]] | None = None) -> VesselAsset:
    return load_asset_file({"name": "shape_test", "hull": hull, "parts": parts or []})


def _volumes(a: VesselAsset) -> list[float]:
    """Signed volume (m³) of every connected piece of the mesh, in the order the pieces were built."""
    v, f = a.mesh.vertices, a.mesh.faces
    t = v[f]
    per_face = np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])) / 6.0
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]]])
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(len(v), len(v)))
    _, label = connected_components(graph, directed=False)
    piece = label[f[:, 0]]
    order = sorted(set(piece.tolist()), key=lambda p: int(np.argmax(piece == p)))
    return [float(per_face[piece == p].sum()) for p in order]


def test_square_hull_is_the_box_of_its_dimensions() -> None:
    a = _asset(SQUARE)
    np.testing.assert_allclose(a.bbox, [[-L / 2, -B / 2, -DRAFT], [L / 2, B / 2, FREEBOARD]], atol=1e-12)
    assert _volumes(a) == pytest.approx([L * B * DEPTH], rel=1e-12)
    corners = {(sx * L / 2, sy * B / 2, z) for sx in (-1, 1) for sy in (-1, 1) for z in (-DRAFT, FREEBOARD)}
    on_faces = np.isclose(np.abs(a.mesh.vertices[:, 0]), L / 2) | np.isclose(np.abs(a.mesh.vertices[:, 1]), B / 2)
    assert on_faces.all()  # every vertex on the box's sides
    assert corners <= {tuple(map(float, p)) for p in a.mesh.vertices}


def test_twin_square_hull_is_two_boxes() -> None:
    demi = 1.0
    a = _asset(dict(SQUARE, type="twin", demi_beam=demi))
    assert _volumes(a) == pytest.approx([L * demi * DEPTH] * 2, rel=1e-12)
    ys = np.unique(np.round(a.mesh.vertices[:, 1], 12))
    np.testing.assert_allclose(ys, [-B / 2, -B / 2 + demi, B / 2 - demi, B / 2], atol=1e-12)


def test_sheer_raises_the_deck_at_the_stem_only() -> None:
    sheer = 0.8
    a = _asset(dict(SQUARE, sheer=sheer))
    v = a.mesh.vertices
    assert v[:, 2].max() == pytest.approx(FREEBOARD + sheer)
    stem_top = v[np.isclose(v[:, 0], L / 2)][:, 2].max()
    aft_top = v[v[:, 0] <= 0.0][:, 2].max()
    assert stem_top == pytest.approx(FREEBOARD + sheer) and aft_top == pytest.approx(FREEBOARD)


def test_pointed_bow_follows_the_documented_taper() -> None:
    bow, power = 0.3, 2.0
    a = _asset(dict(SQUARE, bow=bow, bow_power=power))
    v = a.mesh.vertices
    deck = v[np.isclose(v[:, 2], FREEBOARD)]
    start = L / 2 - bow * L  # the taper starts here; half-width B/2 (1 - t^p) with t from 0 to 1 at the stem
    t = np.clip((deck[:, 0] - start) / (bow * L), 0.0, 1.0)
    np.testing.assert_allclose(np.abs(deck[:, 1]), B / 2 * (1.0 - t**power), atol=1e-12)
    assert np.abs(v[np.isclose(v[:, 0], L / 2)][:, 1]).max() == pytest.approx(0.0, abs=1e-12)  # a pointed stem


@pytest.mark.parametrize(
    ("part", "volume"),
    [
        ({"type": "box", "x": 1.0, "size": [2.0, 1.5], "height": 1.2}, 2.0 * 1.5 * 1.2),
        ({"type": "box", "x": 0.0, "size": [2.0, 2.0], "top": 4.0}, 2.0 * 2.0 * (4.0 - FREEBOARD)),
        # frustum of a square: h/3 (A + A t² + A t)
        (
            {"type": "box", "x": 0.0, "size": [2.0, 2.0], "height": 1.5, "taper": 0.5},
            1.5 / 3.0 * (4.0 + 4.0 * 0.25 + 4.0 * 0.5),
        ),
        # regular n-gon prism: n/2 r² sin(2π/n) h
        (
            {"type": "cylinder", "x": 0.0, "radius": 0.5, "height": 2.0, "segments": 12},
            6.0 * 0.25 * math.sin(2.0 * math.pi / 12.0) * 2.0,
        ),
        (
            {"type": "hcylinder", "x0": -2.0, "x1": 3.0, "z": 2.5, "radius": 0.3, "segments": 8},
            4.0 * 0.09 * math.sin(2.0 * math.pi / 8.0) * 5.0,
        ),
        # a triangle [x, z] profile 2 x 1.5 m, 0.2 m thick
        ({"type": "plate", "thickness": 0.2, "points": [[0.0, 2.0], [2.0, 2.0], [0.0, 3.5]]}, 0.5 * 2.0 * 1.5 * 0.2),
        (
            {"type": "strut", "from": [-1.0, 0.0, 2.5], "to": [2.0, 0.0, 6.5], "width": 0.2, "thickness": 0.1},
            5.0 * 0.02,
        ),
    ],
)
def test_part_volume_is_closed_form(part: dict[str, Any], volume: float) -> None:
    a = _asset(SQUARE, [part])
    hull, part_volume = _volumes(a)
    assert hull == pytest.approx(L * B * DEPTH, rel=1e-12)
    assert part_volume == pytest.approx(volume, rel=1e-9)


def test_box_stands_on_the_deck_at_its_corners() -> None:
    a = _asset(SQUARE, [{"type": "box", "x": 1.0, "y": -0.5, "size": [2.0, 1.0], "height": 1.2}])
    corners = {(x, y, z) for x in (0.0, 2.0) for y in (-1.0, 0.0) for z in (FREEBOARD, FREEBOARD + 1.2)}
    assert corners <= {tuple(float(c) for c in np.round(p, 12)) for p in a.mesh.vertices}


def test_row_places_count_boxes_with_gaps_and_cycled_heights() -> None:
    row = {"type": "row", "x0": -4.0, "x1": 4.0, "count": 3, "gap": 1.0, "width": 2.0, "heights": [1.0, 2.0]}
    a = _asset(SQUARE, [row])
    lx = (8.0 - 2 * 1.0) / 3  # 2 m each
    hull, *boxes = _volumes(a)
    assert hull == pytest.approx(L * B * DEPTH, rel=1e-12)
    assert boxes == pytest.approx([lx * 2.0 * 1.0, lx * 2.0 * 2.0, lx * 2.0 * 1.0], rel=1e-12)
    x = a.mesh.vertices[:, 0]
    for i in range(3):
        a0 = -4.0 + i * (lx + 1.0)
        assert np.isclose(x, a0).any() and np.isclose(x, a0 + lx).any()


def test_fit_narrows_a_part_to_stay_inside_the_deck() -> None:
    a = _asset(SQUARE, [{"type": "box", "x": 0.0, "size": [2.0, 10.0], "height": 1.0, "fit": 0.25}])
    part = a.mesh.vertices[a.mesh.vertices[:, 2] > FREEBOARD + 1e-9]
    assert np.abs(part[:, 1]).max() == pytest.approx(B / 2 - 0.25, abs=1e-12)
