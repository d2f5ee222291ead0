# ruff: noqa: E501  (the cases are one Python statement each, kept on one line to be read and re-run)
"""Fuzz the native boundary for crashes: every function and method of ``mmusv._core`` (and the thin Python wrappers
that feed it) called with adversarial values, one argument at a time, each case in a worker subprocess under a
memory limit and a per-case timeout, so that an abort, a segfault, a stack overflow, a hang or a huge allocation is
recorded instead of killing the harness.

    PYTHONPATH=python python3 scripts/fuzz_native.py [-o report.jsonl] [--timeout 20] [--mem-gib 4] [--only SUBSTR]
        [--random N --seed S]

Outcomes: ``ok``, ``MmusvError:<class>``, ``other:<type>`` (an exception outside mmusv.errors: judge its message),
``crash:<signal or rc>``, ``timeout``, ``memory`` (MemoryError or an allocation failure under the limit), ``rss``
(the case returned but grew the worker past ``--rss-gib``). The worker reports each case before running it; after a
crash or timeout it is restarted at the next case. ``--random N`` adds N cases mutating two or three arguments at
once (drawn with a fixed seed). Exit status 1 when any case crashed, hung or ran out of memory.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import select
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from typing import Any

# --- adversarial values ---------------------------------------------------------------------------------------------

FLOATS = ["float('nan')", "float('inf')", "-float('inf')", "-0.0", "0.0", "1e308", "-1e308", "5e-324", "-1.0",
          "1e30", "2.0**64", "'1.0'", "None", "True"]  # fmt: skip
INTS = ["0", "-1", "2**31", "2**32", "2**63", "2**64", "-2**63", "10**7", "10**9", "10**12", "1.5", "None",
        "np.int64(-1)", "np.uint64(2**63)"]  # fmt: skip
STRS = ["''", "'x'", "'\\x00'", "'é' * 10000", "None", "1", "b'x'"]
BOOLS = ["None", "2", "'yes'", "float('nan')"]
SEQS = ["[]", "[float('nan')] * 3", "[float('inf')] * 3", "[1e308] * 3", "[0.0] * 3", "[1.0] * 1000",
        "None", "'abc'", "[[1.0]]", "[1, 2]"]  # fmt: skip
OBJS = ["None", "1", "object()"]


def array_mutations(base: str) -> list[str]:
    """Variants of an array expression: dtype, ndim, order, emptiness, special values."""
    if base == "None":  # an optional array left out: what may be given instead
        return [
            "np.zeros((0, 0), np.float32)",
            "np.zeros((), np.float32)",
            "np.zeros((2, 3), np.float32)",
            "np.zeros((2, 9))",
            "np.full((2, 9), np.nan, np.float32)",
            "np.full((2, 9), np.inf, np.float32)",
            "np.zeros((2, 100), np.float32)",
            "np.zeros((0, 9), np.float32)",
            "[]",
            "1",
        ]
    b = f"({base})"
    return [
        f"np.asfortranarray({b})",
        f"np.repeat({b}, 2, axis=0)[::2]",
        f"{b}[::-1]",
        f"{b}[:0]",
        f"{b}[..., :0]",
        f"{b}.reshape(-1)",
        f"{b}[None]",
        f"{b}.astype(np.float64)",
        f"{b}.astype(np.float32)",
        f"{b}.astype(np.int32)",
        f"{b}.astype(np.uint8)",
        f"{b}.astype(np.complex128)",
        f"{b}.astype(object)",
        f"np.full_like({b}, np.nan) if {b}.dtype.kind == 'f' else np.full_like({b}, -1)",
        f"np.full_like({b}, np.inf) if {b}.dtype.kind == 'f' else np.full_like({b}, np.iinfo({b}.dtype).max)",
        f"np.full_like({b}, 1e30) if {b}.dtype.kind == 'f' else np.full_like({b}, np.iinfo({b}.dtype).min)",
        f"np.zeros_like({b})",
        f"np.repeat({b}, 1000, axis=0)",
        f"{b}.tolist()",
        "None",
        "np.zeros(())",
        "np.zeros((0, 0))",
    ]


def mutations(kind: str, base: str) -> list[str]:
    if kind == "f":
        return FLOATS
    if kind == "i":
        return INTS
    if kind == "s":
        return STRS
    if kind == "b":
        return BOOLS
    if kind == "q":
        return SEQS
    if kind == "o":
        return OBJS
    if kind == "a":
        return array_mutations(base)
    if kind == "fixed":
        return []
    raise ValueError(kind)


# --- targets: (callee, [(name or None for positional, base expression, kind)]) ---------------------------------------

ENV_KW = [("sun_direction", "[0.3, 0.2, 0.93]", "q"), ("turbidity", "3.0", "f"), ("cloud_cover", "0.0", "f"),
          ("ground_albedo", "0.1", "f"), ("fog_extinction_per_m", "0.0", "f"), ("rain_mm_per_h", "0.0", "f"),
          ("wave_height_m", "0.5", "f"), ("wind_speed_m_s", "3.0", "f"), ("water_albedo", "[0.004, 0.018, 0.03]", "q"),
          ("exposure_ev100", "None", "f"), ("shadows", "True", "b"), ("water_multiple_scattering", "True", "b")]  # fmt: skip
LIDAR_KW = [("elevations", "[-0.2, 0.0, 0.2]", "q"), ("azimuth_steps", "16", "i"), ("range_min", "0.5", "f"),
            ("range_max", "100.0", "f"), ("range_noise_std", "0.01", "f"), ("dropout", "0.0", "f"),
            ("water_probability", "0.1", "f"), ("water_probability_per_wave_m", "0.1", "f"),
            ("water_range_m", "20.0", "f"), ("water_range_per_wave_m", "5.0", "f"),
            ("beam_divergence", "0.003", "f")]  # fmt: skip
RADAR_KW = [("range_min_m", "5.0", "f"), ("range_max_m", "500.0", "f"), ("range_resolution_m", "5.0", "f"),
            ("azimuth_bins", "64", "i"), ("beamwidth_az_rad", "0.03", "f"), ("elevation_fan_rad", "(-0.2, 0.2)", "q"),
            ("rays_az", "64", "i"), ("rays_el", "4", "i"), ("target_rays", "16", "i"), ("horizon_fraction", "0.5", "f"),
            ("horizon_band_rad", "0.05", "f"), ("detection_threshold", "1e-3", "f"), ("range_noise_std_m", "0.5", "f"),
            ("sea_sigma0_at_1m", "1e-4", "f"), ("critical_range_per_m", "100.0", "f"), ("sea_max_range_m", "300.0", "f"),
            ("rain_eta_at_1mm_h", "1e-6", "f"), ("frequency_ghz", "9.4", "f"), ("polarisation", "'HH'", "s")]  # fmt: skip
CAM_KW = [("width", "8", "i"), ("height", "6", "i"), ("rgb", "True", "b"), ("hfov", "1.2", "f"),
          ("range_max", "500.0", "f"), ("quality", "'standard'", "s"), ("distortion", "None", "q"),
          ("noise", "None", "q"), ("exposure", "None", "q")]  # fmt: skip
ORTHO_KW = [("width", "8", "i"), ("height", "6", "i"), ("rgb", "True", "b"), ("metres_per_pixel", "1.0", "f")]
FLEET_KW = [("routes", "[np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 50.0]])]", "q"), ("end_behaviours", "['loop']", "q"),
            ("speeds", "np.ones(1)", "a"), ("start_offsets", "np.zeros(1)", "a"), ("z_base", "np.zeros(1)", "a"),
            ("dims", "np.array([[10.0, 3.0, 2.0]])", "a"), ("amplitudes", "np.array([[0.1, 0.05, 0.05]])", "a"),
            ("seed", "0", "i"), ("wave", "'W1'", "s")]  # fmt: skip
FLEET_PHYS_KW = [*FLEET_KW, ("sea", "WF", "o"), ("hulls", "np.array([[10.0, 3.0, 0.8, 0.5, 1.0]])", "a")]
WF_KW = [("hs_m", "1.0", "f"), ("tp_s", "6.0", "f"), ("gamma", "3.3", "f"), ("direction_rad", "0.3", "f"),
         ("spread_s", "10.0", "f"), ("seed", "1", "i")]  # fmt: skip
SURF_KW = [(None, "1.0", "f"), ("tp_s", "6.0", "f"), ("gamma", "3.3", "f"), ("direction_rad", "0.0", "f"),
           ("spread_s", "10.0", "f"), ("scenario_seed", "0", "i"), ("time_s", "0.0", "f"),
           ("foci", "np.zeros((1, 2), np.float32)", "a"), ("level", "0.0", "f"), ("tile_m", "32.0", "f"),
           ("near_m", "40.0", "f"), ("radius_m", "64.0", "f"), ("taper_m", "20.0", "f"), ("detail", "False", "b"),
           ("slopes", "True", "b"), ("fine_m", "0.0", "f")]  # fmt: skip
HULL = ("hull", "[10.0, 3.0, 0.8, 0.5, 1.0]", "q")
ORIG = "np.array([[-5.0, 0.1, 0.2], [-5.0, 0.5, 3.0], [0.0, -6.0, 0.0]], np.float32)"
DIRS = "np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], np.float32)"
VERTS = "np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)"
FACES = "np.array([[0, 1, 2], [0, 1, 3]], np.int64)"
POSE = "P.copy()"
SCENE_ARG = ("scene", "S", "o")
REC_COMMON = [("log_time_ns", "1", "i")]

TARGETS: list[tuple[str, list[tuple[str | None, str, str]]]] = [
    # --- scene ---
    (
        "S.add_mesh",
        [
            (None, VERTS, "a"),
            (None, FACES, "a"),
            (None, "np.array([1], np.uint16)", "a"),
            (None, "'m'", "s"),
            ("materials", "None", "a"),
        ],
    ),
    (
        "S.add_mesh",
        [
            (None, VERTS, "fixed"),
            (None, FACES, "fixed"),
            (None, "np.array([1], np.uint16)", "fixed"),
            (None, "'m'", "fixed"),
            ("materials", "np.array([0, 1], np.uint16)", "a"),
        ],
    ),
    ("S.set_materials", [(None, "np.ones((2, 11), np.float32)", "a")]),
    ("S.set_lights", [(None, "np.array([0], np.uint32)", "a"), (None, "True", "b")]),
    (
        "S.set_seabed",
        [(None, "np.zeros((3, 4), np.float32)", "a"), ("x0", "0.0", "f"), ("y0", "0.0", "f"), ("spacing", "1.0", "f")],
    ),
    ("S.add_instance", [(None, "0", "i"), (None, POSE, "a"), ("class_override", "None", "i")]),
    ("S.set_sea", [(None, "1", "i"), (None, "np.array([0], np.uint32)", "a")]),
    ("SW.set_wave_surface", SURF_KW),
    ("SW.prefetch_wave_surface", SURF_KW),
    ("SWW.wave_heights", [(None, "np.zeros((3, 2), np.float32)", "a")]),
    ("S.set_poses", [(None, "np.array([0], np.uint32)", "a"), (None, "P[None].copy()", "a")]),
    ("S.cast_rays", [(None, ORIG, "a"), (None, DIRS, "a"), (None, "100.0", "f")]),
    ("S0.cast_rays", [(None, ORIG, "a"), (None, DIRS, "a"), (None, "100.0", "f")]),
    ("S.export", [(None, "TMP + '/x.ply'", "s")]),
    ("S.instance_aabb", [(None, "0", "i")]),
    ("S.instance_pose", [(None, "0", "i")]),
    # --- sensors ---
    ("_core.pinhole_intrinsics", [("width", "8", "i"), ("height", "6", "i"), ("hfov", "1.2", "f")]),
    ("_core._pinhole_directions", [("width", "8", "i"), ("height", "6", "i"), ("hfov", "1.2", "f")]),
    ("_core._lidar_directions", [("elevations", "[-0.1, 0.1]", "q"), ("azimuth_steps", "8", "i")]),
    ("_core._lidar_directions", [("elevations", "np.array([-0.1, 0.1])", "a"), ("azimuth_steps", "8", "fixed")]),
    ("_core.uniform_elevations", [("channels", "16", "i"), ("lower", "-0.2", "f"), ("upper", "0.2", "f")]),
    ("_core.lidar_trace_order", [("channels", "16", "i"), ("azimuth_steps", "32", "i"), ("block", "8", "i")]),
    ("_core.SensorEnv", ENV_KW),
    ("E.sky_radiance", [(None, "np.array([[0, 0, 1], [1, 0, 0]], np.float32)", "a"), ("sun_disc", "True", "b")]),
    ("_core.Lidar", LIDAR_KW),
    ("LID.scan", [SCENE_ARG, ("pose", POSE, "a"), ("env", "E", "o"), ("seed", "1", "i"), ("wakes", "None", "a")]),
    (
        "LID.scan",
        [
            ("scene", "SW", "fixed"),
            ("pose", "PZ", "fixed"),
            ("env", "E", "fixed"),
            ("seed", "1", "fixed"),
            ("wakes", "WAKES", "a"),
        ],
    ),
    ("_core.Camera", CAM_KW),
    ("_core.Camera", [*CAM_KW[:6], ("distortion", "[0.1, 0.01, 0.0, 0.0, 0.0]", "q")]),
    ("_core.Camera", [*CAM_KW[:6], ("noise", "(0.01, 0.001)", "q")]),
    ("_core.Camera", [*CAM_KW[:6], ("exposure", "(None, 0.0, 6400.0)", "q")]),
    ("_core.Camera", [*CAM_KW[:6], ("exposure", "(10.0, 0.0, 6400.0)", "q")]),
    ("_core.Camera", ORTHO_KW),
    ("CAM.distort", [(None, "np.array([[0.1, 0.2], [0.0, 0.0]])", "a")]),
    ("CAM.world_rays", [(None, POSE, "a")]),
    ("CAM.pixel_rays", [(None, POSE, "a"), (None, "np.array([0, 5, 47], np.int64)", "a")]),
    (
        "CAM.render",
        [
            SCENE_ARG,
            ("pose", POSE, "a"),
            ("env", "E", "o"),
            ("seed", "1", "i"),
            ("wakes", "None", "a"),
            ("radiance", "False", "b"),
        ],
    ),
    (
        "CAM.render",
        [
            ("scene", "SW", "fixed"),
            ("pose", "PZ", "fixed"),
            ("env", "E", "fixed"),
            ("seed", "1", "fixed"),
            ("wakes", "WAKES", "a"),
        ],
    ),
    ("ORTHO.render", [SCENE_ARG, ("pose", "PZ", "a"), ("env", "E", "o"), ("seed", "1", "i")]),
    ("_core.Radar", RADAR_KW),
    ("RAD.sweep", [SCENE_ARG, ("pose", POSE, "a"), ("env", "E", "o"), ("seed", "1", "i")]),
    (
        "RAD.ppi_image",
        [
            ("range", "np.array([10.0, 100.0], np.float32)", "a"),
            ("azimuth", "np.array([0.0, 1.0], np.float32)", "a"),
            ("intensity", "np.array([1.0, 2.0], np.float32)", "a"),
            ("size_px", "64", "i"),
            ("metres_per_pixel", "2.0", "f"),
            ("orientation", "'north_up'", "s"),
            ("sensor_yaw", "0.3", "f"),
        ],
    ),
    (
        "_core.capture_frame",
        [
            SCENE_ARG,
            ("env", "E", "o"),
            ("tasks", "[(LID, P, 1), (CAM, P, 2), (RAD, P, 3)]", "q"),
            ("wakes", "None", "a"),
        ],
    ),
    (
        "_core.capture_frame",
        [SCENE_ARG, ("env", "E", "fixed"), ("tasks", "[(RAD, P, 3, (64, 2.0, 'head_up', 0.0))]", "fixed")],
    ),
    (
        "_core.surface_tiles",
        [(None, "np.zeros((2, 2), np.float32)", "a"), ("radius_m", "320.0", "f"), ("tile_m", "32.0", "f")],
    ),
    (
        "_core.demo_scene",
        [("seed", "1", "i"), ("extent", "200.0", "f"), ("terrain_cells", "8", "i"), ("vessels", "2", "i")],
    ),
    # --- kinematics ---
    ("_core.Fleet", FLEET_KW),
    ("_core.Fleet", FLEET_PHYS_KW),
    ("FL.poses_at", [(None, "1.0", "f")]),
    ("FL.velocities_at", [(None, "1.0", "f")]),
    ("FL.wake_pieces", [(None, "30.0", "f"), (None, "np.ones(1)", "a")]),
    ("FL.poses_at_times", [(None, "np.linspace(0, 10, 5)", "a")]),
    ("PFLEET.poses_at", [(None, "1.0", "f")]),
    ("PFLEET.poses_at_times", [(None, "np.linspace(0, 10, 5)", "a")]),
    ("PFLEET.wake_pieces", [(None, "30.0", "f"), (None, "np.ones(1)", "a")]),
    ("_core.wave_height", [(None, "'W1'", "s")]),
    ("_core.wave_height", [(None, "1.0", "f")]),
    # --- ocean ---
    ("_core.WaveField", WF_KW),
    ("WF.elevation", [(None, "np.zeros(3)", "a"), (None, "np.ones(3)", "a"), (None, "1.0", "f")]),
    ("WF.slope", [(None, "np.zeros(3)", "a"), (None, "np.ones(3)", "a"), (None, "1.0", "f")]),
    ("WF.orbital_velocity", [(None, "np.zeros((3, 3))", "a"), (None, "1.0", "f")]),
    (
        "WF.elevation_grid",
        [
            ("x0", "0.0", "f"),
            ("y0", "0.0", "f"),
            ("dx", "1.0", "f"),
            ("nx", "4", "i"),
            ("ny", "3", "i"),
            ("t", "0.0", "f"),
        ],
    ),
    (
        "WF.hull_response",
        [
            HULL,
            ("positions", "np.zeros((3, 2))", "a"),
            ("yaw", "np.zeros(3)", "a"),
            ("velocities", "np.ones((3, 2))", "a"),
            ("times", "np.arange(3.0)", "a"),
        ],
    ),
    ("_core.sea_seed", [(None, "7", "i")]),
    ("_core.fully_developed", [(None, "1.0", "f")]),
    ("_core.dnv_gamma", [(None, "1.0", "f"), (None, "6.0", "f")]),
    (
        "_core.hull_rao",
        [
            HULL,
            ("omega", "np.array([0.5, 1.0])", "a"),
            ("beta", "np.array([0.0, 3.0])", "a"),
            ("omega_e", "np.array([0.5, 1.2])", "a"),
        ],
    ),
    (
        "_core.response_variance",
        [
            HULL,
            ("hs_m", "1.0", "f"),
            ("tp_s", "6.0", "f"),
            ("gamma", "3.3", "f"),
            ("direction_rad", "0.0", "f"),
            ("spread_s", "10.0", "f"),
            ("yaw", "0.0", "f"),
            ("speed_mps", "2.0", "f"),
        ],
    ),
    # --- record ---
    ("_core.Recorder", [(None, "TMP + '/r.mcap'", "s"), ("overwrite", "True", "b")]),
    (
        "REC.point_cloud",
        [
            (None, "'/pc'", "s"),
            *REC_COMMON,
            ("frame_id", "'f'", "s"),
            ("names", "['x', 'y']", "q"),
            ("columns", "[np.zeros(3, np.float32), np.ones(3, np.float32)]", "q"),
            ("pose", "None", "q"),
        ],
    ),
    (
        "REC.point_cloud",
        [
            (None, "'/pc'", "fixed"),
            ("log_time_ns", "1", "fixed"),
            ("frame_id", "'f'", "fixed"),
            ("names", "['x']", "fixed"),
            ("columns", "[np.zeros(3, np.float32)]", "fixed"),
            ("pose", "(0, 0, 0, 0, 0, 0, 1)", "q"),
        ],
    ),
    (
        "REC.point_cloud",
        [
            (None, "'/pc'", "fixed"),
            ("log_time_ns", "1", "fixed"),
            ("frame_id", "'f'", "fixed"),
            ("names", "['x']", "fixed"),
            ("columns", "[C0]", "fixed"),
        ],
    ),
    (
        "REC.raw_image",
        [(None, "'/im'", "s"), *REC_COMMON, ("frame_id", "'f'", "s"), ("image", "np.zeros((4, 5, 3), np.uint8)", "a")],
    ),
    (
        "REC.png_image",
        [(None, "'/im'", "s"), *REC_COMMON, ("frame_id", "'f'", "s"), ("image", "np.zeros((4, 5), np.uint16)", "a")],
    ),
    (
        "REC.images",
        [
            *REC_COMMON,
            ("topics", "['/a', '/b']", "q"),
            ("frame_ids", "['f', 'g']", "q"),
            ("images", "[np.zeros((4, 5), np.uint8), np.zeros((2, 2), np.float32)]", "q"),
            ("formats", "['png', 'raw']", "q"),
        ],
    ),
    (
        "REC.frame_transforms",
        [
            (None, "'/tf'", "s"),
            *REC_COMMON,
            ("parents", "['w']", "q"),
            ("children", "['c']", "q"),
            ("translations", "np.zeros((1, 3))", "a"),
            ("rotations", "np.array([[0.0, 0.0, 0.0, 1.0]])", "a"),
        ],
    ),
    (
        "REC.boxes",
        [
            (None, "'/b'", "s"),
            *REC_COMMON,
            ("frame_id", "'w'", "s"),
            ("entity_id", "'e'", "s"),
            ("ids", "['a']", "q"),
            ("centers", "np.zeros((1, 3))", "a"),
            ("quaternions", "np.array([[0.0, 0.0, 0.0, 1.0]])", "a"),
            ("sizes", "np.ones((1, 3))", "a"),
            ("colors", "np.ones((1, 4), np.float32)", "a"),
            ("labels", "['x']", "q"),
        ],
    ),
    (
        "REC.world_state",
        [
            (None, "'/ws'", "s"),
            *REC_COMMON,
            ("frame", "0", "i"),
            ("time_s", "0.0", "f"),
            ("ids", "['a']", "q"),
            ("assets", "['b']", "q"),
            ("roles", "['usv']", "q"),
            ("classes", "np.array([1], np.uint32)", "a"),
            ("instance_ids", "np.array([2], np.uint32)", "a"),
            ("poses", "np.zeros((1, 6))", "a"),
            ("velocities", "np.zeros((1, 3))", "a"),
            ("box_centers", "np.zeros((1, 3))", "a"),
            ("box_sizes", "np.ones((1, 3))", "a"),
        ],
    ),
    (
        "REC.annotations",
        [
            (None, "'/an'", "s"),
            *REC_COMMON,
            ("frame", "0", "i"),
            ("time_s", "0.0", "f"),
            ("agent_id", "'a'", "s"),
            ("lidar_ids", "['v']", "q"),
            ("lidar_ints", "np.ones((1, 3), np.uint32)", "a"),
            ("lidar_values", "np.zeros((1, 13))", "a"),
            ("bev_ids", "['v']", "q"),
            ("bev_values", "np.zeros((1, 5))", "a"),
            ("camera_ids", "['v']", "q"),
            ("camera_names", "['c']", "q"),
            ("camera_ints", "np.ones((1, 2), np.uint32)", "a"),
            ("camera_values", "np.zeros((1, 7))", "a"),
        ],
    ),
    ("REC.metadata", [(None, "'m'", "s"), (None, "{'a': 'b'}", "o")]),
    (
        "REC.attachment",
        [(None, "'a'", "s"), ("media_type", "'text/plain'", "s"), ("data", "b'xyz'", "o"), ("log_time_ns", "0", "i")],
    ),
    # --- Python wrappers ---
    ("PS.add_mesh", [(None, VERTS, "a"), (None, FACES, "a"), ("classes", "[1]", "q"), ("name", "'m'", "s")]),
    ("PS.cast_rays", [(None, ORIG, "a"), (None, DIRS, "a"), ("max_range", "100.0", "f")]),
    ("PS.add_instance", [(None, "0", "i"), ("pose", POSE, "a"), ("class_override", "None", "i")]),
    ("PS.set_poses", [(None, "[0]", "q"), (None, "P[None].copy()", "a")]),
    ("PS.wave_heights", [(None, "np.zeros((3, 2), np.float32)", "a")]),
    ("PS.instance_aabb", [(None, "0", "i")]),
    ("mmusv.sea_surface.surface_tiles", [(None, "np.zeros((2, 2))", "a"), ("radius_m", "320.0", "f")]),
    (
        "mmusv.scene.demo_scene",
        [("seed", "1", "i"), ("extent", "200.0", "f"), ("terrain_cells", "8", "i"), ("vessels", "2", "i")],
    ),
    ("mmusv.sensors.radar.ppi_image", [(None, "RR", "o"), ("size_px", "64", "i"), ("metres_per_pixel", "2.0", "f")]),
    ("mmusv.sensors.env.wake_rows", [(None, "WAKES", "a")]),
    ("mmusv.sensors.env.turbidity_from_visibility", [(None, "1000.0", "f")]),
    ("mmusv.sensors.env.wind_from_wave_height", [(None, "1.0", "f")]),
    (
        "mmusv.sensors.mounts.inside_mesh",
        [
            (None, "VERTS4.astype(np.float64)", "a"),
            (None, "FACES4", "a"),
            ("point", "np.array([0.1, 0.1, 0.1])", "a"),
            ("rays", "9", "i"),
        ],
    ),
    (
        "mmusv.wave_occlusion.exposed_hidden",
        [
            (None, "PS", "o"),
            ("origins", ORIG, "a"),
            ("directions", DIRS, "a"),
            ("vessel_t", "np.array([4.0, np.inf, 5.0], np.float32)", "a"),
            ("max_range_m", "100.0", "f"),
        ],
    ),
    ("mmusv.wave_occlusion.pattern_angles", [(None, "LID.pattern()", "a")]),
    (
        "mmusv.wave_occlusion.lidar_beam_rays",
        [(None, "LID.pattern()", "a"), ("lidar_pose", POSE, "a"), ("beams", "np.array([0, 1, 2])", "a")],
    ),
    (
        "mmusv.wave_occlusion.lidar_box_beams",
        [
            (None, "mmusv.wave_occlusion.pattern_angles(LID.pattern())", "o"),
            ("lidar_pose", POSE, "a"),
            ("corners_world", "BOX8", "a"),
        ],
    ),
    ("SIM.capture", [(None, "0", "i")]),
    ("SIM.set_frame", [(None, "0", "i"), ("sea_radius_m", "64.0", "f")]),
    ("SIM.world_state", [(None, "0", "i")]),
    ("SIM.time_of", [(None, "0", "i")]),
]

# Hand-written cases beyond one-argument mutations: degenerate geometry, huge sizes, empty scenes, stateful misuse.
EXTRA = [
    # degenerate geometry
    "S0.add_instance(S0.add_mesh(np.zeros((3, 3), np.float32), np.array([[0, 1, 2]]), np.array([1], np.uint16), 'p'), P); S0.cast_rays(ORIGZ, DIRSZ, 100.0); S0.world_mesh(); S0.instance_aabb(0)",
    "S0.add_instance(S0.add_mesh(np.array([[0,0,0],[1,0,0],[2,0,0]], np.float32), np.array([[0, 1, 2]]), np.array([1], np.uint16), 'l'), P); S0.cast_rays(ORIGZ, DIRSZ, 100.0)",
    "S0.add_instance(S0.add_mesh(np.zeros((1, 3), np.float32), np.array([[0, 0, 0]] * 100), np.array([1], np.uint16), 'd'), P); S0.cast_rays(ORIGZ, DIRSZ, 100.0); CAM.render(S0, pose=PZ, env=E, seed=1); LID.scan(S0, pose=PZ, env=E, seed=1); RAD.sweep(S0, pose=PZ, env=E, seed=1)",
    "S0.add_instance(S0.add_mesh(np.full((3, 3), 3e38, np.float32), np.array([[0, 1, 2]]), np.array([1], np.uint16), 'big'), P); S0.cast_rays(ORIGZ, DIRSZ, 100.0)",
    "S0.add_instance(S0.add_mesh(np.array([[0,0,0],[1e-30,0,0],[0,1e-30,0]], np.float32), np.array([[0, 1, 2]]), np.array([1], np.uint16), 'tiny'), P); S0.cast_rays(ORIGZ, DIRSZ, 100.0)",
    "S0.add_mesh(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int64), np.array([1], np.uint16), 'empty')",
    "S0.add_mesh(VERTS4, np.array([[0, 1, 4]]), np.array([1], np.uint16), 'oob')",
    "S0.add_mesh(VERTS4, np.array([[0, 1, 2**40]]), np.array([1], np.uint16), 'oob')",
    "S0.add_mesh(VERTS4, np.array([[0, 1, -1]]), np.array([1], np.uint16), 'neg')",
    "S0.add_mesh(VERTS4, np.array([[0, 1, 2]]), np.array([1, 2, 3], np.uint16), 'classes')",
    "m = S0.add_mesh(VERTS4, FACES4, np.array([1], np.uint16), 'x'); [S0.add_instance(m, P) for _ in range(3)]; S0.set_poses(np.array([0, 0, 0], np.uint32), np.stack([P] * 3)); S0.cast_rays(ORIGZ, DIRSZ, 100.0)",
    "S0.add_instance(S0.add_mesh(VERTS4, FACES4, np.array([1], np.uint16), 'x'), np.diag([1e30, 1e30, 1e30, 1.0]))",
    "S0.add_instance(S0.add_mesh(VERTS4, FACES4, np.array([1], np.uint16), 'x'), np.diag([0.0, 0.0, 0.0, 1.0]))",
    "S0.add_instance(S0.add_mesh(VERTS4, FACES4, np.array([1], np.uint16), 'x'), np.diag([-1.0, 1.0, 1.0, 1.0]))",
    # empty scenes
    "S0.world_mesh()",
    "S0.export(TMP + '/e.ply')",
    "S0.export(TMP + '/e.obj')",
    "S0.export(TMP + '/e.stl')",
    "S0.export('/nonexistent/dir/e.ply')",
    "S0.instance_aabb(0)",
    "S0.instance_pose(0)",
    "S0.instance_meshes()",
    "S0.set_poses(np.zeros(0, np.uint32), np.zeros((0, 4, 4)))",
    "S0.set_lights(np.zeros(0, np.uint32), True)",
    "S0.set_sea(0, np.zeros(0, np.uint32))",
    "S0.wave_heights(np.zeros((2, 2), np.float32))",
    "S0.set_wave_surface(1.0); S0.wave_heights(np.zeros((2, 2), np.float32))",
    "S0.set_wave_surface(1.0, foci=np.zeros((0, 2), np.float32)); S0.wave_heights(np.zeros((2, 2), np.float32))",
    "CAM.render(S0, pose=P, env=E, seed=1)",
    "LID.scan(S0, pose=P, env=E, seed=1)",
    "RAD.sweep(S0, pose=P, env=E, seed=1)",
    "_core.capture_frame(S0, env=E, tasks=[])",
    "_core.capture_frame(S0, env=E, tasks=[(LID, P, 1)] * 64)",
    "_core.capture_frame(S, env=E, tasks=[(LID, P)])",
    "_core.capture_frame(S, env=E, tasks=[(RAD, P, 1, (10**6, 1.0, 'head_up', 0.0))])",
    "_core.capture_frame(S, env=E, tasks=[(RAD, P, 1, (64, 0.0, 'head_up', 0.0))])",
    "_core.capture_frame(S, env=E, tasks=[(RAD, P, 1, (64, 1.0, 'sideways', 0.0))])",
    "_core.capture_frame(S, env=E, tasks=[(RAD, P, 1, (64, 1.0, 'north_up', float('nan')))])",
    "_core.capture_frame(S, env=E, tasks=[(E, P, 1)])",
    "_core.capture_frame(S, env=E, tasks=[(LID, P, -1)])",
    "_core.capture_frame(S, env=E, tasks=[(CAM, np.full((4, 4), np.nan), 1)])",
    # huge requests
    "_core.Camera(width=10**6, height=10**6, rgb=True, hfov=1.0)",
    "_core.Camera(width=2**31, height=2**31, rgb=False, hfov=1.0)",
    "_core.Camera(width=10**5, height=10**5, rgb=False, metres_per_pixel=1.0)",
    "_core._pinhole_directions(width=10**6, height=10**6, hfov=1.0)",
    "_core._lidar_directions(elevations=[0.0] * 10**4, azimuth_steps=10**6)",
    "_core._lidar_directions(elevations=[0.0], azimuth_steps=10**9)",
    "_core.uniform_elevations(channels=10**7, lower=-0.1, upper=0.1)",
    "_core.uniform_elevations(channels=10**9, lower=-0.1, upper=0.1)",
    "_core.lidar_trace_order(channels=10**7, azimuth_steps=10**7)",
    "_core.lidar_trace_order(channels=1, azimuth_steps=1, block=2**63)",
    "_core.lidar_trace_order(channels=16, azimuth_steps=16, block=0)",
    "_core.Lidar(**{**LIDAR, 'elevations': [0.0] * 10**7})",
    "_core.Lidar(**{**LIDAR, 'azimuth_steps': 10**9})",
    "_core.Lidar(**{**LIDAR, 'elevations': [0.0] * 10**4, 'azimuth_steps': 10**6})",
    "_core.Radar(**{**RADAR, 'rays_az': 10**6, 'rays_el': 10**6})",
    "_core.Radar(**{**RADAR, 'azimuth_bins': 10**9})",
    "_core.Radar(**{**RADAR, 'range_resolution_m': 1e-9})",
    "_core.Radar(**{**RADAR, 'range_max_m': 1e12})",
    "_core.Radar(**{**RADAR, 'range_resolution_m': 5e-324, 'range_max_m': 1e308})",
    "RAD.ppi_image(range=np.zeros(1, np.float32), azimuth=np.zeros(1, np.float32), intensity=np.zeros(1, np.float32), size_px=10**6, metres_per_pixel=1.0, orientation='head_up', sensor_yaw=0.0)",
    "RAD.ppi_image(range=np.zeros(2, np.float32), azimuth=np.zeros(1, np.float32), intensity=np.zeros(3, np.float32), size_px=8, metres_per_pixel=1.0, orientation='head_up', sensor_yaw=0.0)",
    "WF.elevation_grid(x0=0.0, y0=0.0, dx=1.0, nx=10**6, ny=10**6, t=0.0)",
    "WF.elevation_grid(x0=0.0, y0=0.0, dx=1.0, nx=2**32, ny=1, t=0.0)",
    "WF.elevation(np.zeros(3), np.zeros(4), 0.0)",
    "WF.slope(np.zeros(3), np.zeros(4), 0.0)",
    "WF.hull_response(hull=[10.0, 3.0, 0.8, 0.5, 1.0], positions=np.zeros((3, 2)), yaw=np.zeros(2), velocities=np.zeros((1, 2)), times=np.zeros(5))",
    "_core.hull_rao(hull=[10.0, 3.0, 0.8, 0.5, 1.0], omega=np.zeros(3), beta=np.zeros(2), omega_e=np.zeros(1))",
    "_core.demo_scene(terrain_cells=4096, vessels=4096, extent=1e308)",
    "_core.demo_scene(terrain_cells=2**40)",
    "_core.SensorEnv(**{**ENV, 'sun_direction': [0.0, 0.0, 0.0]})",
    "_core.SensorEnv(**{**ENV, 'sun_direction': [1e-300, 0.0, 1e-300]})",
    "_core.SensorEnv(**{**ENV, 'sun_direction': [1e308, 1e308, 1e308]})",
    "_core.SensorEnv(**{**ENV, 'sun_direction': [0.0, 0.0, -1.0]})",
    "_core.Fleet(**{**FLEET, 'routes': [np.zeros((2, 2))]})",
    "_core.Fleet(**{**FLEET, 'routes': [np.zeros((1, 2))]})",
    "_core.Fleet(**{**FLEET, 'routes': [np.zeros((0, 2))]})",
    "_core.Fleet(**{**FLEET, 'routes': [np.zeros((10**6, 2))]}).poses_at(1.0)",
    "_core.Fleet(**{**FLEET, 'routes': [np.array([[0.0, 0.0], [1e-300, 0.0], [2e-300, 0.0]])]}).poses_at(1.0)",
    "_core.Fleet(**{**FLEET, 'routes': [np.array([[0.0, 0.0], [1e308, 0.0], [-1e308, 0.0]])]}).poses_at(1.0)",
    "_core.Fleet(**{**FLEET, 'routes': [np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]])]}).poses_at(1.0)",
    "_core.Fleet(**{**FLEET, 'routes': [np.array([[0.0, 0.0], [10.0, 0.0]])], 'end_behaviours': ['ping_pong'], 'speeds': np.array([1e300])}).poses_at(1e300)",
    "_core.Fleet(**{**FLEET, 'routes': [np.array([[0.0, 0.0], [10.0, 0.0]])], 'end_behaviours': ['loop'], 'speeds': np.array([1e-300])}).wake_pieces(1e300, np.ones(1))",
    "_core.Fleet(**{**FLEET, 'routes': [np.array([[0.0, 0.0], [10.0, 0.0]])], 'end_behaviours': ['loop']}).wake_pieces(1e15, np.full(1, 1e-300))",
    "_core.Fleet(**{**FLEET, 'routes': [np.array([[0.0, 0.0], [10.0, 0.0]])], 'end_behaviours': ['loop'], 'start_offsets': np.array([1e300])}).poses_at(0.0)",
    "_core.Fleet(**{**FLEET, 'routes': [], 'end_behaviours': [], 'speeds': np.zeros(0), 'start_offsets': np.zeros(0), 'z_base': np.zeros(0), 'dims': np.zeros((0, 3)), 'amplitudes': np.zeros((0, 3))}).poses_at_times(np.zeros(3))",
    "_core.Fleet(**{**FLEET, 'routes': [ROUTE] * 2})",
    "FL.poses_at_times(np.zeros(10**8))",
    "FL.poses_at_times(np.zeros((2, 2)))",
    "_core.WaveField(hs_m=1.0, tp_s=6.0, gamma=3.3, direction_rad=0.0, spread_s=1e308, seed=1).elevation(np.zeros(1), np.zeros(1), 0.0)",
    "_core.WaveField(hs_m=1.0, tp_s=6.0, gamma=1e308, direction_rad=0.0, spread_s=10.0, seed=1)",
    "_core.WaveField(hs_m=1e-300, tp_s=6.0, gamma=3.3, direction_rad=0.0, spread_s=10.0, seed=1)",
    "_core.WaveField(hs_m=1.0, tp_s=6.0, gamma=3.3, direction_rad=1e300, spread_s=10.0, seed=1).elevation(np.zeros(1), np.zeros(1), 0.0)",
    "WF.elevation(np.full(1, 1e300), np.zeros(1), 1e300)",
    "SW.set_wave_surface(1.0, foci=np.array([[1e30, 1e30]], np.float32))",
    "SW.set_wave_surface(1.0, foci=np.array([[3e38, -3e38]], np.float32), radius_m=1e6)",
    "SW.set_wave_surface(1.0, foci=np.zeros((10**5, 2), np.float32))",
    "SW.set_wave_surface(1.0, foci=np.random.default_rng(0).uniform(-1e6, 1e6, (2000, 2)).astype(np.float32))",
    "SW.set_wave_surface(1.0, tile_m=1e-3, radius_m=1.0)",
    "SW.set_wave_surface(1.0, tile_m=1e-30, radius_m=1e-30, near_m=1e-30, taper_m=0.0)",
    "SW.set_wave_surface(1.0, time_s=1e300)",
    "SW.set_wave_surface(1.0, level=1e30)",
    "SW.set_wave_surface(1.0, level=3e38); SW.cast_rays(ORIGZ, DIRSZ, 100.0)",
    "_core.surface_tiles(np.zeros((1, 2), np.float32), radius_m=1e30, tile_m=1e-30)",
    "_core.surface_tiles(np.array([[np.nan, 0.0]], np.float32), radius_m=10.0, tile_m=1.0)",
    "S.cast_rays(np.zeros((10**7, 3), np.float32), np.tile(np.array([1, 0, 0], np.float32), (10**7, 1)), 1e30)",
    "S.cast_rays(np.zeros((3, 3), np.float32), np.zeros((3, 3), np.float32), 100.0)",
    "S.cast_rays(np.full((3, 3), 3e38, np.float32), np.full((3, 3), -3e38, np.float32), 3e38)",
    "S.cast_rays(np.zeros((3, 3), np.float32), np.full((3, 3), 1e-45, np.float32), 100.0)",
    "S.cast_rays(np.zeros((2, 3), np.float32), np.zeros((3, 3), np.float32), 100.0)",
    "S.set_materials(np.ones((70000, 11), np.float32))",
    "S.set_materials(np.ones((0, 11), np.float32)); CAM.render(S, pose=PZ, env=E, seed=1)",
    "S.set_seabed(np.zeros((100000, 100000), np.float32)[:1, :1])",
    "S.set_seabed(np.zeros((1, 1), np.float32), spacing=5e-324); CAM.render(S, pose=PZ, env=E, seed=1)",
    "S.set_seabed(np.zeros((2, 2), np.float32), x0=1e308, y0=-1e308, spacing=1e308); CAM.render(S, pose=PZ, env=E, seed=1)",
    "S.set_seabed(np.zeros((0, 0), np.float32))",
    "S.set_seabed(None)",
    "S.set_sea(0, np.array([0], np.uint32)); CAM.render(S, pose=PZ, env=E, seed=1)",
    "S.set_sea(0, np.array([2**32 - 1], np.uint32))",
    "S.set_lights(np.array([2**32 - 1], np.uint32), True)",
    "S.set_poses(np.array([2**32 - 1], np.uint32), P[None].copy())",
    "S.set_poses(np.array([0], np.uint32), np.stack([P, P]))",
    "S.set_poses(np.array([0, 0], np.uint32), np.stack([P]))",
    "S.add_instance(2**32 - 1, P)",
    "S.add_instance(0, P, 65536)",
    "S.add_instance(0, P, -1)",
    "S.export(TMP)",
    "S.export(TMP + '/' + 'x' * 5000 + '.ply')",
    "S.export(TMP + '/a\\x00b.ply')",
    "CAM.pixel_rays(P, np.array([-1], np.int64))",
    "CAM.pixel_rays(P, np.array([48], np.int64))",
    "CAM.pixel_rays(P, np.array([2**62], np.int64))",
    "CAM.pixel_rays(P, np.zeros(10**7, np.int64))",
    "CAM.render(S, pose=PZ, env=E, seed=1, wakes=np.full((10**5, 9), 1.0, np.float32))",
    "CAM.render(S, pose=PZ, env=E, seed=1, wakes=np.array([[0, 0, 0, 5, 1e30, 1e30, 1e30, 1e30, 1e30]], np.float32))",
    "CAM.render(SW, pose=PZ, env=E, seed=1, wakes=np.array([[0, 0, 0, 5, 10, 3, 1e30, 1e30, 1e30]], np.float32))",
    "CAM.render(SW, pose=PZ, env=E, seed=1, wakes=np.array([[0, 0, 0, 5, 1e-30, 1e-30, 0, 0, 1e-30]], np.float32))",
    "CAM.render(SW, pose=PZ, env=E, seed=1, wakes=np.array([[0, 0, 0, 5, 10, 3, 5, 1e30, 1e30]] * 40, np.float32))",
    "LID.scan(SW, pose=PZ, env=E, seed=1, wakes=np.array([[0, 0, 0, 5, 1e30, 1e30, 1e30, 1e30, 1e30]], np.float32))",
    "_core.Camera(width=8, height=6, rgb=True, hfov=3.14159)",
    "_core.Camera(width=8, height=6, rgb=True, hfov=1e-30)",
    "_core.Camera(width=8, height=6, rgb=True, hfov=1.0, distortion=[1e30, 1e30, 1e30, 1e30, 1e30])",
    "_core.Camera(width=8, height=6, rgb=True, hfov=1.0, distortion=[-10.0, 0.0, 0.0, 0.0, 0.0]).render(S, pose=PZ, env=E, seed=1)",
    "_core.Camera(width=8, height=6, rgb=True, hfov=1.0, distortion=[0.0] * 4)",
    "_core.Camera(width=8, height=6, rgb=True, hfov=1.0, metres_per_pixel=1.0)",
    "_core.Camera(width=8, height=6, rgb=True)",
    "_core.Camera(width=8, height=6, rgb=True, hfov=1.0, noise=(1e30, 1e30)).render(S, pose=PZ, env=E, seed=1)",
    "_core.Camera(width=8, height=6, rgb=True, hfov=1.0, exposure=(1e30, 1e30, 1e30))",
    "_core.Camera(width=8, height=6, rgb=True, hfov=1.0, range_max=5e-324).render(S, pose=PZ, env=E, seed=1)",
    "_core.Camera(width=1, height=1, rgb=True, hfov=1.0, quality='high').render(S, pose=PZ, env=E, seed=1)",
    "_core.Camera(width=8, height=6, rgb=True, metres_per_pixel=1e30).render(S, pose=PZ, env=E, seed=1)",
    "_core.Camera(width=8, height=6, rgb=True, metres_per_pixel=1e-30).render(S, pose=PZ, env=E, seed=1)",
    "CAM.distort(np.full((2, 2), 1e300))",
    "_core.Camera(width=8, height=6, rgb=True, hfov=1.0, distortion=[0.1, 0.01, 0.0, 0.0, 0.0]).distort(np.full((2, 2), 1e300))",
    "CAM.world_rays(np.diag([1e300, 1e300, 1e300, 1.0]))",
    "CAM.world_rays(np.array([[1, 0, 0, 1e300], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]))",
    "CAM.render(S, pose=np.array([[1, 0, 0, 1e30], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]), env=E, seed=1)",
    "LID.scan(S, pose=np.array([[1, 0, 0, 3e38], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]), env=E, seed=1)",
    "RAD.sweep(S, pose=np.array([[1, 0, 0, 3e38], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]), env=E, seed=1)",
    "RAD.sweep(SW, pose=PZ, env=_core.SensorEnv(**{**ENV, 'rain_mm_per_h': 1e6, 'wave_height_m': 1e6}), seed=1)",
    "LID.scan(SW, pose=PZ, env=_core.SensorEnv(**{**ENV, 'fog_extinction_per_m': 1e30, 'rain_mm_per_h': 1e30}), seed=1)",
    "CAM.render(SW, pose=PZ, env=_core.SensorEnv(**{**ENV, 'fog_extinction_per_m': 1e30, 'rain_mm_per_h': 1e30, 'turbidity': 1e30}), seed=1)",
    "E.sky_radiance(np.zeros((3, 3), np.float32))",
    "E.sky_radiance(np.full((3, 3), np.nan, np.float32))",
    "E.sky_radiance(np.zeros((10**7, 3), np.float32))",
    "_core.sea_seed(-1)",
    "_core.sea_seed(2**64)",
    "_core.dnv_gamma(1.0, 0.0)",
    "_core.dnv_gamma(1e308, 1e-308)",
    "_core.fully_developed(1e308)",
    "_core.wave_height('W' * 10**6)",
    "_core.response_variance(hull=[1e-300, 1e-300, 1e-300, 1e-300, 1e-300], hs_m=1.0, tp_s=6.0, gamma=3.3, direction_rad=0.0, spread_s=10.0, yaw=0.0, speed_mps=0.0)",
    "_core.response_variance(hull=[1e300, 1e300, 1e300, 1.0, 1e300], hs_m=1.0, tp_s=6.0, gamma=3.3, direction_rad=0.0, spread_s=10.0, yaw=0.0, speed_mps=1e300)",
    "_core.hull_rao(hull=[10.0, 3.0, 0.8, 0.5, 1.0], omega=np.zeros(10**7), beta=np.zeros(10**7), omega_e=np.zeros(10**7))",
    # recorder misuse
    "REC.finish(); REC.finish()",
    "REC.abandon(); REC.raw_image('/a', log_time_ns=1, frame_id='f', image=np.zeros((2, 2), np.uint8))",
    "REC.raw_image('/a', log_time_ns=1, frame_id='f', image=np.zeros((2, 2), np.uint8)); REC.png_image('/a', log_time_ns=1, frame_id='f', image=np.zeros((2, 2), np.uint8))",
    "REC.png_image('/a', log_time_ns=1, frame_id='f', image=np.zeros((10**5, 10**5), np.uint8)[:, :0])",
    "REC.png_image('/a', log_time_ns=1, frame_id='f', image=np.zeros((0, 5), np.uint8))",
    "REC.png_image('/a', log_time_ns=1, frame_id='f', image=np.zeros((1, 2**31), np.uint8)[:, :1].copy())",
    "REC.png_image('/a', log_time_ns=1, frame_id='f', image=np.broadcast_to(np.zeros(1, np.uint8), (40000, 40000)))",
    "REC.raw_image('/a', log_time_ns=1, frame_id='f', image=np.zeros((2, 2, 4), np.uint8))",
    "REC.raw_image('/a', log_time_ns=1, frame_id='f', image=np.zeros((2, 2, 3), np.float32))",
    "REC.point_cloud('/p', log_time_ns=1, frame_id='f', names=['x', 'y'], columns=[np.zeros(3, np.float32)])",
    "REC.point_cloud('/p', log_time_ns=1, frame_id='f', names=['x', 'y'], columns=[np.zeros(3, np.float32), np.zeros(4, np.float32)])",
    "REC.point_cloud('/p', log_time_ns=1, frame_id='f', names=['x'] * 1000, columns=[np.zeros(3, np.float32)] * 1000)",
    "REC.point_cloud('/p', log_time_ns=1, frame_id='f', names=[], columns=[])",
    "REC.point_cloud('/p', log_time_ns=1, frame_id='f', names=['x'], columns=[np.zeros(3, np.int64)])",
    "REC.point_cloud('/p', log_time_ns=1, frame_id='f', names=['x'], columns=[np.zeros((3, 1), np.float32)])",
    "REC.point_cloud('/p', log_time_ns=1, frame_id='f', names=['x'], columns=[np.zeros(3, np.float32)], pose=(0, 0, 0, 0, 0, 0, 0))",
    "REC.point_cloud('/p', log_time_ns=1, frame_id='f', names=['x'], columns=[np.zeros(3, np.float32)], pose=(0, 0, 0))",
    "REC.images(log_time_ns=1, topics=['/a'], frame_ids=[], images=[], formats=[])",
    "REC.images(log_time_ns=1, topics=['/a'], frame_ids=['f'], images=[np.zeros((2, 2), np.uint8)], formats=['jpeg'])",
    "REC.images(log_time_ns=1, topics=['/a'] * 200, frame_ids=['f'] * 200, images=[np.zeros((64, 64), np.uint8)] * 200, formats=['png'] * 200)",
    "REC.images(log_time_ns=1, topics=['/a'], frame_ids=['f'], images=[np.zeros((2, 2), np.float32)], formats=['png'])",
    "REC.boxes('/b', log_time_ns=1, frame_id='w', entity_id='e', ids=['a', 'a'], centers=np.zeros((2, 3)), quaternions=np.tile([0.0, 0, 0, 1], (2, 1)), sizes=np.ones((2, 3)), colors=np.ones((2, 4), np.float32), labels=['', ''])",
    "REC.boxes('/b', log_time_ns=1, frame_id='w', entity_id='e', ids=['a'], centers=np.zeros((2, 3)), quaternions=np.tile([0.0, 0, 0, 1], (3, 1)), sizes=np.ones((0, 3)), colors=np.ones((2, 4), np.float32), labels=[])",
    "REC.frame_transforms('/tf', log_time_ns=1, parents=['w', 'x'], children=['c'], translations=np.zeros((3, 3)), rotations=np.zeros((0, 4)))",
    "REC.world_state('/ws', log_time_ns=1, frame=0, time_s=0.0, ids=['a', 'b'], assets=['x'], roles=[], classes=np.zeros(3, np.uint32), instance_ids=np.zeros(0, np.uint32), poses=np.zeros((1, 6)), velocities=np.zeros((2, 3)), box_centers=np.zeros((1, 3)), box_sizes=np.zeros((1, 3)))",
    "REC.annotations('/an', log_time_ns=1, frame=0, time_s=0.0, agent_id='a', lidar_ids=['v', 'w'], lidar_ints=np.ones((1, 3), np.uint32), lidar_values=np.zeros((3, 13)), bev_ids=[], bev_values=np.zeros((1, 5)), camera_ids=['v'], camera_names=[], camera_ints=np.ones((2, 2), np.uint32), camera_values=np.zeros((0, 7)))",
    "REC.metadata('m', {'a': 1})",
    "REC.metadata('m', {1: 'a'})",
    "REC.metadata('m', {'a': 'b' * 10**7})",
    "REC.attachment('a', media_type='x', data=b'x' * 10**8)",
    "REC.attachment('a', media_type='x', data=bytearray(3))",
    "REC.raw_image('/a', log_time_ns=2**63, frame_id='f', image=np.zeros((2, 2), np.uint8)); REC.raw_image('/a', log_time_ns=0, frame_id='f', image=np.zeros((2, 2), np.uint8)); REC.finish()",
    "REC.__exit__(ValueError, ValueError('x'), None)",
    "REC.__exit__(1, 2, 3)",
    "_core.Recorder(TMP + '/no/such/dir/x.mcap')",
    "_core.Recorder(TMP)",
    "_core.Recorder('')",
    "_core.Recorder(TMP + '/a\\x00.mcap')",
    "_core.Recorder(TMP + '/' + 'x' * 5000)",
    "r = _core.Recorder(TMP + '/same.mcap'); r2 = _core.Recorder(TMP + '/same.mcap', overwrite=True); r.finish(); r2.finish()",
    # Python wrappers with degenerate values
    "PS.add_mesh(np.zeros((3, 3)), [[0, 1, 2]], classes=[1], name='p')",
    "PS.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2.5]], classes=[1], name='p')",
    "PS.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2**70]], classes=[1], name='p')",
    "PS.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], classes=[70000], name='p')",
    "PS.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], classes=[-1], name='p')",
    "PS.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], classes=[1], name='p', materials=[70000])",
    "PS.set_materials(np.full((2, 11), np.nan))",
    "PS.set_lights([2**40], on=True)",
    "PS.set_sea(2**40)",
    "PS.set_wave_surface(None)",
    "mmusv.sensors.radar.ppi_image(RR, size_px=10**6, metres_per_pixel=1.0)",
    "mmusv.sensors.radar.ppi_image(RR, size_px=64, metres_per_pixel=float('nan'))",
    "mmusv.sensors.radar.ppi_colormap(np.full((4, 4), np.nan), vmin_db=float('nan'), vmax_db=float('nan'))",
    "mmusv.sensors.radar.ppi_colormap(np.zeros((4, 4)), vmin_db=1.0, vmax_db=1.0)",
    "mmusv.sensors.radar.ppi_colormap(np.zeros((0, 0)))",
    "mmusv.sensors.radar.ppi_colormap(np.zeros((2, 2, 2, 2)))",
    "mmusv.sensors.radar.ppi_colormap(np.zeros((4, 4)), vmin_db=float('inf'), vmax_db=float('inf'))",
    "mmusv.sensors.mounts.inside_mesh(np.zeros((3, 3)), np.array([[0, 1, 2]]), point=np.zeros(3), rays=10**9)",
    "mmusv.sensors.mounts.inside_mesh(np.zeros((3, 3)), np.array([[0, 1, 2]]), point=np.zeros(3), rays=0)",
    "mmusv.sensors.mounts.inside_mesh(np.zeros((3, 3)), np.array([[0, 1, 2]]), point=np.full(3, np.nan))",
    "mmusv.sensors.mounts.rpy_matrix((np.nan, 0, 0), (np.inf, 0, 0))",
    "mmusv.sensors.env.turbidity_from_visibility(0.0)",
    "mmusv.sensors.env.turbidity_from_visibility(-1.0)",
    "mmusv.wave_occlusion.exposed_hidden(PS, origins=np.zeros((10**7, 3), np.float32), directions=np.tile(np.array([1, 0, 0], np.float32), (10**7, 1)), vessel_t=np.full(10**7, np.inf, np.float32))",
    "mmusv.wave_occlusion.exposed_hidden(PS, origins=np.zeros((3, 3)), directions=np.zeros((3, 3)), vessel_t=np.zeros(3))",
    "mmusv.wave_occlusion.exposed_hidden(PS, origins=np.zeros((3, 3)), directions=np.ones((3, 3)), vessel_t=np.zeros(3), scene_instance=np.array([2**40, -5, 0]))",
    "mmusv.wave_occlusion.share(-1, 5)",
    "mmusv.wave_occlusion.share(0, 0)",
    "mmusv.wave_occlusion.share(2**70, 1)",
    "mmusv.wave_occlusion.pattern_angles(np.zeros((5, 3), np.float32))",
    "mmusv.wave_occlusion.lidar_box_beams(mmusv.wave_occlusion.pattern_angles(LID.pattern()), lidar_pose=P, corners_world=np.zeros((8, 3)))",
    "mmusv.wave_occlusion.lidar_box_beams(mmusv.wave_occlusion.pattern_angles(LID.pattern()), lidar_pose=P, corners_world=np.full((8, 3), np.nan))",
    "mmusv.wave_occlusion.lidar_box_rays(LID.pattern(), mmusv.wave_occlusion.pattern_angles(LID.pattern()[:3]), lidar_pose=P, corners_world=BOX8)",
    "SIM.capture(10**9)",
    "SIM.capture(-1)",
    "SIM.set_frame(0, sea_radius_m=1e30)",
    "SIM.set_frame(0, sea_radius_m=float('nan'))",
    "SIM.set_frame(0, sea_radius_m=0.0)",
    "SIM.set_frame(0, sea_radius_m=-1.0)",
    "SIM.set_sea_surface(object())",
    "SIM.capture(0, agents=['nobody'])",
    "SIM.capture(0, sensors=[])",
    "SIM.capture(0, agents=[])",
    "SIM.prefetch_frame(2**63)",
    "SIM.prefetch_frame(0); SIM.prefetch_frame(1); SIM.capture(0)",
    "mmusv.motion.scenario_poses(SIM.scenario, wave=float('nan'))",
    "mmusv.motion.scenario_poses(SIM.scenario, wave=1e308)",
    "mmusv.motion.scenario_poses(SIM.scenario, wave='W9')",
]


def build_cases() -> list[str]:
    cases: list[str] = []
    for callee, params in TARGETS:

        def call(i: int, value: str, params: list[tuple[str | None, str, str]] = params, callee: str = callee) -> str:
            parts = []
            for j, (name, base, _) in enumerate(params):
                v = value if j == i else base
                parts.append(v if name is None else f"{name}={v}")
            return f"{callee}({', '.join(parts)})"

        cases.append(call(-1, ""))
        for i, (_, base, kind) in enumerate(params):
            for v in mutations(kind, base):
                cases.append(call(i, v))
        # leaving an optional keyword argument out and passing an unknown one
        cases.append(f"{callee}(*[], **{{'no_such_argument': 1}})")
    return cases + EXTRA


def random_cases(n: int, seed: int) -> list[str]:
    """Cases mutating two or three arguments of one target at once, drawn with ``seed``."""
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        callee, params = rng.choice(TARGETS)
        mutable = [i for i, p in enumerate(params) if mutations(p[2], p[1])]
        if not mutable:
            continue
        k = min(len(mutable), rng.choice((2, 3)))
        chosen = rng.sample(mutable, k)
        parts = []
        for j, (name, base, kind) in enumerate(params):
            v = base
            if j in chosen:
                options = mutations(kind, base)
                v = options[rng.randrange(len(options))]
            parts.append(v if name is None else f"{name}={v}")
        out.append(f"{callee}({', '.join(parts)})")
    return out


# --- worker -----------------------------------------------------------------------------------------------------------

PRELUDE = r"""
import numpy as np, mmusv, mmusv.scene, mmusv.sensors.radar, mmusv.sensors.env, mmusv.sensors.mounts
import mmusv.wave_occlusion, mmusv.motion, mmusv.simulation
from mmusv import _core
from mmusv.errors import MmusvError
import tempfile
TMP = tempfile.mkdtemp(prefix='fuzz-native-')
_c, _s = np.cos(0.3), np.sin(0.3)
P = np.array([[_c, -_s, 0.0, 5.0], [_s, _c, 0.0, -2.0], [0.0, 0.0, 1.0, 1.0], [0.0, 0.0, 0.0, 1.0]])
PZ = np.eye(4); PZ[2, 3] = 3.0; PZ[0, 3] = -10.0
ORIGZ = np.array([[-5.0, 0.1, 0.2], [0.0, 0.0, 5.0]], np.float32)
DIRSZ = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]], np.float32)
VERTS4 = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float32)
FACES4 = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                   [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], np.int64)
BOX8 = VERTS4.astype(np.float64) * 2 + np.array([10.0, 0.0, 0.0])
ENV = dict(sun_direction=[0.3, 0.2, 0.93], turbidity=3.0, cloud_cover=0.0, ground_albedo=0.1, fog_extinction_per_m=0.0,
           rain_mm_per_h=0.0, wave_height_m=0.5, wind_speed_m_s=3.0, water_albedo=[0.004, 0.018, 0.03])
LIDAR = dict(elevations=[-0.2, 0.0, 0.2], azimuth_steps=16, range_min=0.5, range_max=100.0, range_noise_std=0.01,
             dropout=0.0, water_probability=0.1, water_probability_per_wave_m=0.1, water_range_m=20.0,
             water_range_per_wave_m=5.0, beam_divergence=0.003)
RADAR = dict(range_min_m=5.0, range_max_m=500.0, range_resolution_m=5.0, azimuth_bins=64, beamwidth_az_rad=0.03,
             elevation_fan_rad=(-0.2, 0.2), rays_az=64, rays_el=4, target_rays=16, horizon_fraction=0.5, horizon_band_rad=0.05,
             detection_threshold=1e-3, range_noise_std_m=0.5, sea_sigma0_at_1m=1e-4, critical_range_per_m=100.0,
             sea_max_range_m=300.0, rain_eta_at_1mm_h=1e-6, frequency_ghz=9.4, polarisation='HH')
ROUTE = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 50.0]])
FLEET = dict(routes=[ROUTE], end_behaviours=['loop'], speeds=np.ones(1), start_offsets=np.zeros(1), z_base=np.zeros(1),
             dims=np.array([[10.0, 3.0, 2.0]]), amplitudes=np.array([[0.1, 0.05, 0.05]]), seed=0, wave='W1')
WAKES = np.array([[0, 0, 0, 5, 10, 3, 40, 2, 20], [50, 0, 1, 5, 10, 3, 40, 2, 20]], np.float32)
C0 = np.zeros(3, np.float32)
E = _core.SensorEnv(**ENV)
WF = _core.WaveField(hs_m=1.0, tp_s=6.0, gamma=3.3, direction_rad=0.3, spread_s=10.0, seed=1)
LID = _core.Lidar(**LIDAR)
RAD = _core.Radar(**RADAR)
CAM = _core.Camera(width=8, height=6, rgb=True, hfov=1.2)
ORTHO = _core.Camera(width=8, height=6, rgb=True, metres_per_pixel=1.0)
FLEET_ = None
_SIM = None

def _box_scene():
    s = _core.Scene()
    s.add_instance(s.add_mesh(VERTS4 * 2, FACES4, np.array([3], np.uint16), 'box'), np.eye(4))
    return s

def _sea_scene():
    s = _box_scene()
    plane_v = np.array([[-500, -500, 0], [500, -500, 0], [500, 500, 0], [-500, 500, 0]], np.float32)
    sea = s.add_instance(s.add_mesh(plane_v, np.array([[0, 1, 2], [0, 2, 3]]), np.array([1], np.uint16), 'sea'), np.eye(4))
    s.set_sea(sea, np.array([0], np.uint32))
    return s

class _Lazy(dict):
    def __missing__(self, key):
        if key == 'S': v = _box_scene()
        elif key == 'S0': v = _core.Scene()
        elif key == 'SW': v = _sea_scene()
        elif key == 'SWW':
            v = _sea_scene(); v.set_wave_surface(1.0, foci=np.zeros((1, 2), np.float32), radius_m=64.0)
        elif key == 'PS':
            v = mmusv.scene.Scene(); v.add_instance(v.add_mesh(VERTS4 * 2, FACES4, classes=3, name='box'))
        elif key == 'FL': v = _core.Fleet(**FLEET)
        elif key == 'PFLEET': v = _core.Fleet(**FLEET, sea=WF, hulls=np.array([[10.0, 3.0, 0.8, 0.5, 1.0]]))
        elif key == 'REC': v = _core.Recorder(TMP + '/rec%d.mcap' % _N[0], overwrite=True)
        elif key == 'RR':
            v = mmusv.sensors.radar.RadarReturns.from_native(RAD.sweep(_box_scene(), pose=PZ, env=E, seed=1), pose=PZ, radar=RAD)
        elif key == 'SIM':
            global _SIM
            if _SIM is None:
                _SIM = mmusv.simulation.Simulation(mmusv.config.load_scenario(_TINY))
            v = _SIM
        else:
            raise KeyError(key)
        self[key] = v
        return v

_TINY = {
    'name': 'tiny', 'seed': 1, 'map': {'type': 'open_sea', 'seed': 1, 'params': {'extent_m': 1000}},
    'acquisition': {'frequency_hz': 5, 'frames': 3}, 'rigs': {'r': {'preset': 'lidar_only'}},
    'vessels': [
        {'id': 'usv_1', 'role': 'usv', 'asset': 'usv_wamv', 'rig': 'r', 'speed_mps': 2.0, 'route': [[0, 0], [100, 0]]},
        {'id': 't1', 'asset': 'fishing_boat_12m', 'speed_mps': 2.0, 'route': [[50, 50], [100, 50]]},
    ],
}
_N = [0]
"""

WORKER = r"""
import sys, os, resource, json, traceback
lim = int(sys.argv[1])
resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
exec(compile(PRELUDE, '<prelude>', 'exec'), globals())
import mmusv.config
out = os.fdopen(int(sys.argv[2]), 'w', buffering=1)
cases = json.loads(sys.stdin.readline())
for i, code in cases:
    out.write(json.dumps(['S', i]) + '\n')
    _N[0] = i
    ns = _Lazy(globals())
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    try:
        exec(compile(code, '<case>', 'exec'), ns)
        outcome, msg = 'ok', ''
    except MemoryError as e:
        outcome, msg = 'memory', repr(e)[:300]
    except MmusvError as e:
        outcome, msg = 'MmusvError:' + type(e).__name__, str(e)[:300]
    except BaseException as e:
        outcome, msg = 'other:' + type(e).__name__, str(e)[:300]
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    out.write(json.dumps(['R', i, outcome, msg, rss1 - rss0, rss1]) + '\n')
"""


def run(cases: list[str], *, timeout: float, mem: int, rss_kib: int, log: Any) -> list[dict[str, Any]]:
    results: list[dict[str, Any]] = []
    start = 0
    env = {**os.environ, "PYTHONFAULTHANDLER": "1"}
    src = f"PRELUDE = {PRELUDE!r}\n{WORKER}"
    while start < len(cases):
        r, w = os.pipe()
        errf = tempfile.TemporaryFile()  # noqa: SIM115  (the worker's stderr, closed when it has ended)
        proc = subprocess.Popen(
            [sys.executable, "-c", src, str(mem), str(w)],
            stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            stderr=errf,
            pass_fds=(w,),
            env=env,
            start_new_session=True,
        )
        os.close(w)
        assert proc.stdin is not None
        proc.stdin.write((json.dumps(list(enumerate(cases))[start:]) + "\n").encode())
        proc.stdin.flush()
        current: int | None = None
        buf = b""
        deadline = time.monotonic() + timeout + 60  # the prelude's imports
        ended = False
        while True:
            if b"\n" not in buf:
                left = deadline - time.monotonic()
                ready, _, _ = select.select([r], [], [], max(left, 0))
                if not ready:
                    # a hang (or a case that has not reported yet at its deadline)
                    i = current if current is not None else start
                    os.killpg(proc.pid, signal.SIGKILL)
                    proc.wait()
                    rec = {"case": i, "code": cases[i], "outcome": "timeout", "detail": f">{timeout}s"}
                    results.append(rec)
                    log(rec)
                    start = i + 1
                    break
                chunk = os.read(r, 1 << 16)
                if not chunk:
                    ended = True
                    break
                buf += chunk
                continue
            line, buf = buf.split(b"\n", 1)
            msg = json.loads(line)
            if msg[0] == "S":
                current = msg[1]
                deadline = time.monotonic() + timeout
            else:
                _, i, outcome, detail, grew, rss = msg
                if outcome in ("ok",) and grew > rss_kib:
                    outcome = "rss"
                    detail = f"grew {grew // 1024} MiB (peak {rss // 1024} MiB)"
                rec = {"case": i, "code": cases[i], "outcome": outcome, "detail": detail, "rss_grew_kib": grew}
                results.append(rec)
                log(rec)
                current = None
                start = i + 1
                deadline = time.monotonic() + timeout
                if i == len(cases) - 1:
                    break
        os.close(r)
        if ended:
            proc.wait()
            errf.seek(0)
            err = errf.read().decode(errors="replace")
            if current is None:
                raise SystemExit(f"worker died outside a case (rc {proc.returncode}):\n{err[-3000:]}")
            rc = proc.returncode
            what = f"signal {signal.Signals(-rc).name}" if rc < 0 else f"rc {rc}"
            outcome = "memory" if "memory allocation" in err or "MemoryError" in err else f"crash:{what}"
            rec = {"case": current, "code": cases[current], "outcome": outcome, "detail": err[-1500:]}
            results.append(rec)
            log(rec)
            start = current + 1
            errf.close()
        else:
            if proc.poll() is None:
                proc.stdin.close()
                try:
                    proc.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    os.killpg(proc.pid, signal.SIGKILL)
                    proc.wait()
            errf.close()
            if results and results[-1]["case"] == len(cases) - 1:
                break
    return results


def main() -> int:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument(
        "-o", "--out", default="/tmp/fuzz_native.jsonl", help="JSON lines, one per case (default %(default)s)"
    )
    ap.add_argument("--timeout", type=float, default=20.0, help="seconds per case (default %(default)s)")
    ap.add_argument(
        "--mem-gib", type=float, default=4.0, help="a worker's address-space limit, GiB (default %(default)s)"
    )
    ap.add_argument(
        "--rss-gib", type=float, default=1.0, help="a worker's resident-memory limit, GiB (default %(default)s)"
    )
    ap.add_argument("--only", default="", help="only the cases whose code holds this text")
    ap.add_argument("--random", type=int, default=0, help="this many random cases more, two or three arguments each")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random cases (default %(default)s)")
    ap.add_argument("--list", action="store_true", help="print the cases and stop")
    a = ap.parse_args()
    cases = build_cases() + random_cases(a.random, a.seed)
    if a.only:
        cases = [c for c in cases if a.only in c]
    if a.list:
        print("\n".join(cases))
        return 0
    print(f"{len(cases)} cases", file=sys.stderr)
    with open(a.out, "w", encoding="utf-8") as f:

        def log(rec: dict[str, Any]) -> None:
            f.write(json.dumps(rec) + "\n")
            f.flush()
            if rec["outcome"] not in ("ok",) and not rec["outcome"].startswith("MmusvError"):
                print(f"[{rec['outcome']}] {rec['code'][:200]}\n    {str(rec['detail'])[-300:]}", file=sys.stderr)

        results = run(cases, timeout=a.timeout, mem=int(a.mem_gib * 2**30), rss_kib=int(a.rss_gib * 2**20), log=log)
    counts = Counter(r["outcome"].split(":")[0] for r in results)
    print(json.dumps(dict(counts)), file=sys.stderr)
    bad = [r for r in results if r["outcome"].startswith(("crash", "timeout", "memory", "rss"))]
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
