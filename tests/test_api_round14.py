"""Round 14 of the API review: the public geometry helpers' refusals of input they cannot use (mmusv.annotate's
box helpers, mmusv.image_boxes, ...), each an InputError naming the argument and what is allowed."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from mmusv import frames, motion, wave_occlusion
from mmusv.annotate import Annotations, SilhouetteCache, annotate_agent, box_corners, footprint_in_range
from mmusv.classes import class_name
from mmusv.config import load_scenario
from mmusv.errors import ConfigError, InputError
from mmusv.image_boxes import clip_box, faces_in_image_box, in_image_box, pinhole_truncation, project_box
from mmusv.scene import Scene
from mmusv.simulation import Simulation
from tiny_scenario import lidar_scenario

K = (100.0, 100.0, 80.0, 60.0)
BOX = box_corners(np.eye(4), [2.0, 2.0, 2.0]) + np.array([0.0, 0.0, 10.0])  # in view, 10 m ahead of the camera

# ------------------------------------------------------------------------------------ true/false among numbers


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda: frames.translation([True, 2.0, 3.0]), "v must be .* of real numbers: it holds true/false"),
        (lambda: frames.transform_points(np.eye(4), [[1, 2, 3], [np.True_, 0, 0]]), "points must be .* true/false"),
        (lambda: frames.wrap_deg([np.array(True), 5.0]), "a must be angles in degrees .* true/false"),
        (lambda: box_corners(np.eye(4), [True, 2.0, 1.0]), "size must be .* it holds true/false"),
        (
            lambda: wave_occlusion.exposed_rays(np.array([True, True]), [True, -0.5]),
            r"z must be \(N,\) world heights .* it holds true/false",
        ),
        (
            lambda: wave_occlusion.exposed_rays(np.ones(2, dtype=bool), [1.0, 1.0], box=[True, 0], n_boxes=2),
            "box must be .* it holds true/false",
        ),
        (
            lambda: wave_occlusion.lidar_beam_rays(np.eye(3, dtype=np.float32), lidar_pose=np.eye(4), beams=[True, 0]),
            r"beams must be \(K,\) beam indices .* it holds true/false",
        ),
        (
            lambda: pinhole_truncation(BOX, intrinsics=(True, True, 80, 60), width=9, height=9),
            "intrinsics .* true/false",
        ),
    ],
)
def test_true_false_in_a_list_of_numbers_is_not_a_number(call: Callable[[], Any], words: str) -> None:
    """mmusv.arguments.reals (the check that frames, annotate and image_boxes use) refused an array of true/false but
    not a list mixing them with numbers, which numpy reads as numbers: ``translation([True, 2, 3])`` moved 1 m
    along x, a box of size ``[True, 2, 1]`` was 1 m long and intrinsics ``(True, True, 80, 60)`` a focal length
    of 1 px, without a word; mmusv.wave_occlusion's own check let the same lists through (a height ``[True, -0.5]``
    was 1 m above the still level, beam ``True`` beam 1). Each is an InputError naming the argument."""
    with pytest.raises(InputError, match=words):
        call()


def test_lists_of_numbers_still_read_as_numbers() -> None:
    """Lists of Python and numpy numbers, of arrays and of 0-d arrays are still the numbers they hold."""
    np.testing.assert_array_equal(frames.translation([np.float32(1.0), 2, np.int64(3)])[:3, 3], [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(frames.wrap_deg([np.array(370.0), 5]), [10.0, 5.0])
    rows = [np.array([1.0, 2.0, 3.0]), np.array([4, 5, 6])]
    np.testing.assert_array_equal(frames.transform_points(np.eye(4), rows), [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])


# ------------------------------------------------------------------------------------ a box's size


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda: box_corners(np.eye(4), [-4.0, 2.0, 1.0]), r"size must be .* finite metres >= 0 .* \[-4.0, 2.0, 1.0\]"),
        (lambda: box_corners(np.eye(4), [4.0, np.nan, 1.0]), r"size must be .* got \[4.0, nan, 1.0\]"),
        (lambda: box_corners(np.eye(4), [4.0, 2.0, np.inf]), r"size must be .* got \[4.0, 2.0, inf\]"),
        (lambda: footprint_in_range(np.eye(4), size=[-400.0, 2.0], range_m=10.0), r"size must be .* >= 0"),
        (
            lambda: footprint_in_range(np.eye(4), size=[np.nan, 2.0, 1.0], range_m=10.0),
            r"size must be .* got \[nan, 2.0, 1.0\]",
        ),
        (
            lambda: footprint_in_range(np.full((4, 4), np.nan), size=[4.0, 2.0], range_m=10.0),
            r"box must be a \(4, 4\) box -> ego LiDAR transform of finite numbers",
        ),
    ],
)
def test_a_box_of_negative_or_nan_size_is_refused(call: Callable[[], Any], words: str) -> None:
    """A negative extent is no box: ``box_corners`` gave corners in mirrored order (corner 0 at +x for a negative
    length, breaking the documented corner bits the image boxes' faces rely on) and ``footprint_in_range`` read a
    length of -400 m as a 400 m footprint; a NaN size gave NaN corners, and a NaN size or box 'not in range',
    without a word. Each is an InputError naming the argument (nothing in mmusv passes such a size: vessels' boxes
    are their meshes' extents)."""
    with pytest.raises(InputError, match=words):
        call()


def test_a_box_of_zero_size_still_has_corners() -> None:
    """A flat box (size 0 along an axis) is still a box: its corners, in order, and its footprint."""
    c = box_corners(np.eye(4), [2.0, 0.0, 0.0])
    np.testing.assert_array_equal(c[:, 0], [-1.0, 1.0] * 4)
    assert not c[:, 1:].any()
    assert footprint_in_range(np.eye(4), size=np.zeros(3), range_m=0.0)


# ------------------------------------------------------------------------------------ mmusv.image_boxes


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (
            lambda: pinhole_truncation(np.ones((8, 3), dtype=bool), intrinsics=K, width=160, height=120),
            r"corners_opt must be a box's \(8, 3\) corners in metres of real numbers: it holds true/false",
        ),
        (
            lambda: pinhole_truncation(BOX.astype(str), intrinsics=K, width=160, height=120),
            "corners_opt must be .* it holds text",
        ),
        (
            lambda: pinhole_truncation(BOX, intrinsics="1234", width=160, height=120),
            r"intrinsics must be \(fx, fy, cx, cy\) pixels of real numbers: it holds text",
        ),
        (
            lambda: pinhole_truncation(BOX, intrinsics=("100", "100", "80", "60"), width=160, height=120),
            "intrinsics must be .* it holds text",
        ),
        (lambda: clip_box("abcd", width=4, height=4), r"box must be a pixel box \[x0, y0, x1, y1\] .* it holds text"),
        (lambda: clip_box(["0", "0", "2", "2"], width=4, height=4), "box must be a pixel box .* it holds text"),
        (lambda: clip_box(np.ones(4, dtype=bool), width=4, height=4), "box must be .* it holds true/false"),
        (
            lambda: faces_in_image_box(None, intrinsics=K, lens=None, width=160, height=120),  # type: ignore[arg-type]
            r"faces_opt must be a list of convex \(n, 3\) polygons .* got None",
        ),
        (
            lambda: faces_in_image_box([None], intrinsics=K, lens=None, width=160, height=120),  # type: ignore[list-item]
            r"faces_opt\[0\] must be a convex \(n, 3\) polygon .* it holds None",
        ),
        (
            lambda: faces_in_image_box([np.ones((4, 2))], intrinsics=K, lens=None, width=160, height=120),
            r"faces_opt\[0\] must be .* got shape \(4, 2\)",
        ),
        (
            lambda: faces_in_image_box([np.full((4, 3), np.nan)], intrinsics=K, lens=None, width=160, height=120),
            r"faces_opt\[0\] must be a convex \(n, 3\) polygon \(finite metres\)",
        ),
        (lambda: project_box(BOX, intrinsics=K, lens="x"), "lens = 'x': must be None .* or the .camera, reach. of"),
        (
            lambda: in_image_box(BOX, intrinsics=K, lens=(None, 1.0), width=160, height=120),
            "lens = .* must be None",
        ),
    ],
)
def test_the_image_box_helpers_refuse_what_they_cannot_use(call: Callable[[], Any], words: str) -> None:
    """mmusv.image_boxes (the 2D boxes' geometry, which annotate and the KITTI export use) read a box's corners of
    true/false as ones and of text as the numbers written, intrinsics ``"1234"`` as ``(1, 2, 3, 4)`` (one digit
    per entry) and intrinsics or a pixel box of text as numbers, all without a word; ``clip_box`` of ``"abcd"``
    ended in numpy's bare ValueError, ``faces_in_image_box`` of None, ``[None]`` or ``(4, 2)`` faces in a bare
    TypeError or ValueError (a reshape), and of a NaN face in None ('not in the image'); a lens that is not
    ``camera_lens``'s ``(camera, reach)`` in a bare TypeError from inside. Each is an InputError naming the
    argument."""
    with pytest.raises(InputError, match=words):
        call()


def test_the_image_box_helpers_still_take_what_they_document() -> None:
    """Lists, numpy numbers and arrays of faces still work, with the same answers."""
    k32 = np.array(K, dtype=np.float32)
    assert pinhole_truncation(BOX.tolist(), intrinsics=k32, width=np.int64(160), height=np.uint16(120)) == 0.0
    r = 100.0 / 9.0  # the near face (z = 9 m) is the widest: 1 m at f = 100 px
    np.testing.assert_allclose(project_box(BOX, intrinsics=list(K)), [80.0 - r, 60.0 - r, 80.0 + r, 60.0 + r])
    clipped, area, carea = clip_box([-2, 0, 2, np.int32(2)], width=4, height=4)
    assert clipped.tolist() == [0.0, 0.0, 2.0, 2.0] and (area, carea) == (8.0, 4.0)
    assert faces_in_image_box([], intrinsics=K, lens=None, width=4, height=4) is None
    whole = faces_in_image_box(
        np.stack([BOX[[0, 1, 3, 2]], BOX[[4, 5, 7, 6]]]), intrinsics=K, lens=None, width=160, height=120
    )
    np.testing.assert_allclose(whole, project_box(BOX, intrinsics=K))


# ------------------------------------------------------------------------------------ annotate_agent


@pytest.fixture(scope="module")
def agent_call() -> Callable[..., Annotations]:
    """``annotate_agent`` of the first agent of a tiny scenario's frame 0, its arguments replaced by those given."""
    sim = Simulation(lidar_scenario("round14", frames=1))
    cap = sim.capture(0)
    agent = sim.agents[0]
    ac = cap.agents[agent.id]
    assert ac.lidar is not None
    base: dict[str, Any] = {
        "agent_id": agent.id,
        "agent_index": agent.index,
        "frame": cap.frame,
        "time_s": cap.time_s,
        "vessels": sim.vessels,
        "state": cap.world,
        "lidar_pose": ac.lidar_pose,
        "lidar_instances": ac.lidar.instance,
        "cameras": {},
        "silhouettes": SilhouetteCache(),
        "max_range_m": 200.0,
        "scene": sim.ws.scene,
    }
    return lambda **kw: annotate_agent(**{**base, **kw})


@pytest.mark.parametrize(
    ("kw", "words"),
    [
        ({"agent_index": -1}, r"agent_index = -1: must be a whole number in 0\.\.1"),
        ({"agent_index": 2}, r"agent_index = 2: must be a whole number in 0\.\.1"),
        ({"agent_index": True}, "agent_index = True: .* not true/false"),
        ({"agent_index": "0"}, "agent_index = '0': .* not str"),
        ({"max_range_m": float("nan")}, "max_range_m = nan: must be a number of metres >= 0"),
        ({"lidar_pose": np.eye(3)}, r"lidar_pose must be a \(4, 4\) LiDAR -> world transform .* got shape \(3, 3\)"),
        ({"lidar_pose": np.full((4, 4), np.nan)}, r"lidar_pose must be .*, finite, got"),
        ({"lidar_instances": np.array([1.5])}, r"lidar_instances must be the \(N,\) instance ids \(integers\)"),
        ({"frame": -1}, "frame = -1: must be a whole number >= 0"),
        ({"frame": "0"}, "frame = '0'"),
        ({"time_s": None}, "time_s = None: must be a finite number of seconds"),
        ({"agent_id": None}, r"agent_id = None: must be the agent's id \(a str\)"),
        ({"cameras": None}, "cameras = None: must be a dict name -> "),
        ({"vessels": None}, "vessels = None: must be the list of the world state's VesselInfo"),
        ({"silhouettes": None}, "silhouettes = None: must be a SilhouetteCache"),
    ],
)
def test_annotate_agent_refuses_what_it_cannot_use(
    agent_call: Callable[..., Annotations], kw: dict[str, Any], words: str
) -> None:
    """``annotate_agent`` took an ``agent_index`` that is no vessel's (-1, 2 of 2 vessels, ``"0"``) as 'no vessel is
    the agent' and gave the agent its own hull as a target (and -1 the last vessel's pose as the reference), read
    ``True`` as vessel 1, kept a frame of -1 or ``"0"``, a time of None and an agent id of None in its
    Annotations, took LiDAR instance ids of 1.5 as 1, and named a NaN ``max_range_m`` 'range_m'; a (3, 3)
    lidar_pose ended in numpy's bare matmul ValueError (a NaN one was blamed on 'box'), a list of instance ids, a
    ``cameras`` or ``vessels`` of None in a bare AttributeError or TypeError. Each is an InputError naming the
    argument."""
    with pytest.raises(InputError, match=words):
        agent_call(**kw)


def test_annotate_agent_still_takes_what_it_documents(agent_call: Callable[..., Annotations]) -> None:
    """numpy integers, a float32 time and a list of instance ids still give the same annotations."""
    ann = agent_call()
    assert ann.lidar_ids and ann.agent == "u"
    assert agent_call(agent_index=np.int64(0), frame=np.uint32(0), time_s=np.float32(0.0)) == ann
    target = ann.lidar_instance[0]
    assert agent_call(lidar_instances=[target, target, 0]).lidar_points == [2]


# ------------------------------------------------------------------------------------ mmusv.classes


@pytest.mark.parametrize(
    ("class_id", "words"),
    [
        (True, "class_id = True: must be a whole number, not true/false"),
        (10.0, r"class_id = 10.0: must be a whole number \(int or numpy integer\), not float"),
        ("10", "class_id = '10': .* not str"),
        (None, "class_id = None: .* not NoneType"),
    ],
)
def test_class_name_of_what_is_no_class_id_is_refused(class_id: Any, words: str) -> None:
    """``class_name`` named ``True`` 'water' (class 1) and ``10.0`` 'vessel', and ``"10"``, ``None`` or ``10.7``
    'unknown_10', 'unknown_None', 'unknown_10.7', names no class has, without a word. Each is an InputError."""
    with pytest.raises(InputError, match=words):
        class_name(class_id)


def test_class_name_still_names_class_ids() -> None:
    """Python and numpy integers (and 0-d integer arrays) are named as before; unknown ids stay 'unknown_<id>'."""
    assert class_name(10) == class_name(np.uint16(10)) == class_name(np.array(10, dtype=np.uint32)) == "vessel"
    assert class_name(300) == class_name(np.int64(300)) == "unknown_300"
    assert class_name(-1) == "unknown_-1"


# ------------------------------------------------------------------------------------ mmusv.scene


def _one_triangle() -> tuple[Scene, int]:
    scene = Scene()
    mesh = scene.add_mesh(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.array([[0, 1, 2]]))
    return scene, mesh


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (
            lambda s, m: s.add_instance(m, pose=np.eye(4).astype(str)),
            "pose must be an array of real numbers: it holds text",
        ),
        (lambda s, m: s.add_instance(m, pose=np.eye(4, dtype=bool)), "pose must be .* it holds true/false"),
        (lambda s, m: s.set_poses([s.add_instance(m)], np.eye(4).astype(str)), "poses must be .* it holds text"),
        (lambda s, m: s.set_materials(np.ones((2, 11)).astype(str)), "materials must be .* it holds text"),
        (lambda s, m: s.set_materials(np.ones((2, 11), dtype=bool)), "materials must be .* it holds true/false"),
        (lambda s, m: s.set_seabed(np.zeros((2, 2)).astype(str)), "seabed heights must be .* it holds text"),
        (lambda s, m: s.set_seabed(np.zeros((2, 2), dtype=bool)), "seabed heights must be .* it holds true/false"),
    ],
)
def test_scene_poses_materials_and_seabed_of_text_or_true_false_are_refused(
    call: Callable[[Scene, int], Any], words: str
) -> None:
    """Scene's poses, material table and seabed heights were read with numpy's float conversion: an identity pose
    written as text or as true/false placed the instance, a seabed of text or true/false was set and a material
    table of text loaded, without a word (a table of true/false was refused for its 'arc half-width' of 1). Each
    is an InputError naming the argument, through mmusv.arguments.reals (ray origins and directions
    already refused them)."""
    scene, mesh = _one_triangle()
    with pytest.raises(InputError, match=words):
        call(scene, mesh)


def test_scene_still_takes_lists_and_numpy_numbers() -> None:
    """Poses as lists or float32 arrays, and integer seabed heights, still work."""
    scene, mesh = _one_triangle()
    inst = scene.add_instance(mesh, pose=np.eye(4).tolist())
    scene.set_poses([inst], np.eye(4, dtype=np.float32)[None])
    scene.set_seabed(np.full((2, 2), -5, dtype=np.int32))
    np.testing.assert_array_equal(scene.instance_pose(inst), np.eye(4))


# ------------------------------------------------------------------------------------ mmusv.motion


@pytest.mark.parametrize("given", [lambda: lidar_scenario("motion", frames=2), lambda: None, lambda: "scenario.yaml"])
@pytest.mark.parametrize(
    "call", [motion.build_fleet, motion.scenario_poses, lambda s: motion.build_moored_fleet(s, [])]
)
def test_motion_takes_a_scenario_only(given: Callable[[], Any], call: Callable[[Any], Any]) -> None:
    """mmusv.motion's functions took a scenario's dict (as ``mmusv.run`` takes one), a path or None and ended in a
    bare AttributeError ('dict' object has no attribute 'vessels'). Each is a ConfigError saying how to get a
    Scenario."""
    with pytest.raises(
        ConfigError, match=r"scenario = .*: must be a mmusv.config.Scenario \(mmusv.config.load_scenario"
    ):
        call(given())


def test_motion_of_a_loaded_scenario_is_unchanged() -> None:
    sc = load_scenario(lidar_scenario("motion", frames=2))
    assert motion.scenario_poses(sc).shape == (2, len(sc.vessels), 6)
    assert motion.build_moored_fleet(sc, []) is None
