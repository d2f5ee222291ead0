"""The pictures and counts of docs/sea (issue #29, the water every sensor sees): before (the flat sea) and after
(the displaced surface of the physical sea), same scenario, frame and seeds.

* a small craft 150 m ahead of a USV at W3, partly hidden by crests, in the camera and the LiDAR, with its
  wave-occlusion share (the annotations' ``wave_occlusion``);
* the LiDAR's water returns within 60 m at W0 and W3 (on wave faces after; on the flat plane before);
* the radar PPI at W0 and W3;
* the LiDAR's returns from a fast boat's wake passing a USV at W1 (after: the capture, whose LiDAR sees the
  wakes' foam; before: the same sweep without the wakes);
* a buoy ahead of a USV at W3, at rest (before) and riding the waves (after).

Usage: ``python scripts/sea_pictures.py [-o docs/sea] [--only craft,faces,radar,wake,buoys]``; prints the counts of
docs/sea/README.md.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from mmusv.acquire import annotations_for
from mmusv.silhouettes import SilhouetteCache
from mmusv.simulation import Simulation

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Sea:
    """A directional JONSWAP sea (:class:`mmusv.sea_surface.SeaState`)."""

    hs_m: float
    tp_s: float
    gamma: float = 3.3
    direction_rad: float = math.pi  # travelling towards the observer: crests across the line of sight
    spread_s: float = 15.0


SEAS = {"W0": Sea(0.5, 3.5), "W3": Sea(3.5, 9.4)}


def _scenario(wave: str) -> dict[str, Any]:
    camera = {
        "name": "view",
        "resolution": [640, 360],
        "hfov_deg": 12.0,
        "outputs": ["rgb", "instance"],
        "mount": {"xyz": [2.0, 0.0, 3.5], "rpy_deg": [0.0, 0.8, 0.0]},
    }
    # A long-range LiDAR (128 rings over 12°, 0.18° columns) so a 5 m craft at 150 m gets beams at all.
    lidar = {"channels": 128, "vertical_fov_deg": [-8.0, 4.0], "points_per_second": 128 * 2000 * 5.0, "range_m": 200.0}
    rig = {"cameras": [camera], "top_view": None, "lidar": lidar}
    return {
        "name": f"sea_{wave.lower()}",
        "seed": 29,
        "map": {"type": "open_sea", "seed": 1, "params": {"n_buoys": 0, "islet_probability": 0.0}},
        "environment": {"time_of_day": "15:00", "weather": "clear", "wave": wave},
        "acquisition": {"frequency_hz": 5, "frames": 40},
        "rigs": {"view": rig},
        "vessels": [
            {"id": "usv", "role": "usv", "asset": "usv_wamv", "rig": "view", "speed_mps": 0.5,
             "route": [[0.0, 0.0], [200.0, 0.0]]},
            {"id": "craft", "role": "target", "asset": "speedboat_5m", "speed_mps": 0.5,
             "route": [[150.0, -3.0], [150.0, 200.0]]},
        ],
    }  # fmt: skip


def _share(ann: Any, key: str, target: str) -> float:
    cols = ann.columns()[key]
    ids = list(cols["target_id"])
    return float(cols["wave_occlusion"][ids.index(target)]) if target in ids else float("nan")


def craft_views(out: Path, lines: list[str]) -> None:
    """The W3 craft at 150 m: camera and LiDAR, before and after, with the wave-occlusion shares."""
    from PIL import Image

    sim = Simulation(_scenario("W3"))
    sil = SilhouetteCache()
    sim.set_sea_surface(SEAS["W3"])
    # The frame where the crests hide closest to half of the craft (camera annotations).
    best, best_frame = 2.0, 0
    for f in range(sim.frames):
        cap = sim.capture(f, sensors=["cameras", "lidar"], radar=False)
        s = _share(annotations_for(sim, cap, sil)["usv"], "camera", "craft")
        print(f"frame {f}: camera wave occlusion {s:.2f}")
        if s == s and abs(s - 0.5) < abs(best - 0.5):
            best, best_frame = s, f
    rows = []
    for name, sea in (("before", None), ("after", SEAS["W3"])):
        sim.set_sea_surface(sea)
        cap = sim.capture(best_frame, radar=False)
        ann = annotations_for(sim, cap, sil)["usv"]
        ac = cap.agents["usv"]
        rgb = ac.cameras["view"].rgb
        assert rgb is not None
        Image.fromarray(np.asarray(rgb)).save(out / f"craft_w3_camera_{name}.png")
        cam, lid = _share(ann, "camera", "craft"), _share(ann, "lidar", "craft")
        lidar = ac.lidar
        assert lidar is not None and ac.lidar_pose is not None
        craft = sim.vessels[1].instance_id
        n_craft = int(np.count_nonzero(lidar.instance == craft))
        rows.append((name, cam, lid, n_craft, lidar, ac.lidar_pose))
        lines.append(f"| {name} | {best_frame} | {cam:.2f} | {lid:.2f} | {n_craft} |")
    _lidar_side(rows, out / "craft_w3_lidar.png", craft_x=150.0)


def _lidar_side(rows: list[Any], path: Path, *, craft_x: float) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(rows), 1, figsize=(9, 2.6 * len(rows)), sharex=True, sharey=True)
    for ax, (name, cam, lid, n_craft, lidar, pose) in zip(axes, rows, strict=True):
        p = lidar.xyz.astype(np.float64) @ pose[:3, :3].T + pose[:3, 3]
        sector = np.abs(np.arctan2(p[:, 1] - pose[1, 3], p[:, 0] - pose[0, 3])) < math.radians(4.0)
        cls = lidar.semantic_class
        for c, colour, label in ((1, "tab:blue", "water"), (10, "tab:red", "craft")):
            m = sector & (cls == c)
            ax.scatter(p[m, 0], p[m, 2], s=3, c=colour, label=label)
        ax.set_title(f"{name}: LiDAR returns within ±4° of the craft's bearing; craft points {n_craft}, "
                     f"wave occlusion LiDAR {lid:.2f}, camera {cam:.2f}", fontsize=9)  # fmt: skip
        ax.set_ylabel("world z (m)")
        ax.axvline(craft_x, color="grey", lw=0.5)
        ax.legend(loc="upper left", fontsize=8)
    axes[-1].set_xlabel("world x (m), the USV at 0 looking along +x")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def lidar_faces(out: Path, lines: list[str]) -> None:
    """Water returns within 60 m of the USV's LiDAR, W0 and W3, before and after: plan view coloured by height."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(10, 9))
    for j, wave in enumerate(("W0", "W3")):
        sim = Simulation(_scenario(wave))
        for i, (name, sea) in enumerate((("before", None), ("after", SEAS[wave]))):
            sim.set_sea_surface(sea)
            zs, n = [], 0
            for f in (0, 10, 20, 30):
                ac = sim.capture(f, sensors=["lidar"], radar=False).agents["usv"]
                assert ac.lidar is not None and ac.lidar_pose is not None
                p = ac.lidar.xyz.astype(np.float64) @ ac.lidar_pose[:3, :3].T + ac.lidar_pose[:3, 3]
                near = (ac.lidar.semantic_class == 1) & (
                    np.hypot(p[:, 0] - ac.lidar_pose[0, 3], p[:, 1] - ac.lidar_pose[1, 3]) < 60.0
                )
                zs.append(p[near, 2])
                n += int(near.sum())
                if f == 0:
                    ax = axes[i, j]
                    sc = ax.scatter(p[near, 0], p[near, 1], s=2, c=p[near, 2], cmap="viridis", vmin=-2, vmax=2)
                    ax.set_aspect("equal")
                    ax.set_title(f"{wave} {name}: {int(near.sum())} water returns (frame 0)", fontsize=9)
            z = np.concatenate(zs)
            lines.append(f"| {wave} | {name} | {n} | {z.std():.3f} | {z.std() / (SEAS[wave].hs_m / 4):.2f} |")
    fig.colorbar(sc, ax=axes, label="world z (m)", shrink=0.6)
    fig.savefig(out / "lidar_wave_faces.png", dpi=90)
    plt.close(fig)


def radar_ppi(out: Path, lines: list[str]) -> None:
    """The radar PPI at W0 and W3, before and after."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(9, 9))
    for j, wave in enumerate(("W0", "W3")):
        scenario = _scenario(wave)
        scenario["rigs"]["view"]["cameras"] = []
        sim = Simulation(scenario)
        for i, (name, sea) in enumerate((("before", None), ("after", SEAS[wave]))):
            sim.set_sea_surface(sea)
            ac = sim.capture(0, sensors=["radar"]).agents["usv"]
            assert ac.radar is not None and ac.radar_ppi is not None
            clutter = int(np.count_nonzero(ac.radar.instance_id < 0))
            r = ac.radar.range[ac.radar.instance_id < 0]
            far = float(np.percentile(r, 95)) if r.size else 0.0
            img = np.asarray(ac.radar_ppi, dtype=np.float64)
            if img.ndim == 3:
                img = img.mean(axis=2)
            c, half = img.shape[0] // 2, img.shape[0] // 16  # the inner sixteenth of the PPI's span
            crop = img[c - half : c + half, c - half : c + half]
            # Log scale: 60 dB below the brightest pixel up to it.
            shown = np.log10(1.0 + crop / max(float(crop.max()) * 1e-6, 1e-12))
            axes[i, j].imshow(shown, cmap="gray")
            span = sim.agents[0].rig.radar.range_m / 8 if sim.agents[0].rig.radar is not None else 0.0
            axes[i, j].set_title(f"{wave} {name}: {clutter} clutter returns (inner ±{span:.0f} m)", fontsize=9)
            axes[i, j].axis("off")
            lines.append(f"| {wave} | {name} | {clutter} | {far:.0f} |")
    fig.tight_layout()
    fig.savefig(out / "radar_ppi_w0_w3.png", dpi=90)
    plt.close(fig)


def lidar_wake(out: Path, lines: list[str]) -> None:
    """A patrol boat at 14 m/s passes 15 m beside a USV at W1: the USV's LiDAR returns in plan view, before (the
    same sweep without the wakes) and after (the capture, the wakes' foam seen), coloured by class."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mmusv.sensors.lidar import scan
    from mmusv.simulation import sensor_seed

    scenario = _scenario("W1")
    scenario["rigs"]["view"] = {"cameras": [], "top_view": None, "radar": None}  # the default 64-channel LiDAR
    scenario["acquisition"]["frames"] = 60
    scenario["vessels"] = [
        {"id": "usv", "role": "usv", "asset": "usv_wamv", "rig": "view", "speed_mps": 2.0,
         "route": [[0.0, 0.0], [400.0, 0.0]]},
        {"id": "patrol", "role": "target", "asset": "patrol_boat_35m", "speed_mps": 14.0,
         "route": [[-60.0, 15.0], [600.0, 15.0]]},
    ]  # fmt: skip
    sim = Simulation(scenario)
    frame = 46  # the patrol boat's bow about 60 m ahead of the USV: its track and arms reach past it
    cap = sim.capture(frame, sensors=["lidar"], radar=False)
    ac = cap.agents["usv"]
    assert ac.lidar is not None and ac.lidar_pose is not None
    agent = sim.agents[0]
    assert agent.lidar is not None
    seed = sensor_seed(sim.scenario.seed, frame=frame, agent=agent.index, sensor="lidar")
    without = scan(agent.lidar, sim.ws.scene, pose=ac.lidar_pose, env=sim.sensor_env, seed=seed)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.4), sharex=True, sharey=True)
    for ax, (name, pts) in zip(axes, (("before (no wakes)", without), ("after", ac.lidar)), strict=True):
        p = pts.xyz.astype(np.float64) @ ac.lidar_pose[:3, :3].T + ac.lidar_pose[:3, 3]
        water = pts.semantic_class == 1
        ax.scatter(p[water, 0], p[water, 1], s=1, c="tab:blue", label=f"water ({int(water.sum())})")
        ax.scatter(p[~water, 0], p[~water, 1], s=1, c="tab:red", label=f"vessels ({int((~water).sum())})")
        ax.set_aspect("equal")
        ax.set_xlim(-80, 170)
        ax.set_ylim(-70, 80)
        ax.set_title(f"{name}: {len(pts)} returns", fontsize=9)
        ax.legend(loc="lower left", fontsize=8, markerscale=6)
        lines.append(f"| {name} | {int(water.sum())} | {int((~water).sum())} |")
    axes[0].set_ylabel("world y (m)")
    for ax in axes:
        ax.set_xlabel("world x (m)")
    title = "LiDAR returns, W1: the USV at x ≈ 18 m heading +x at 2 m/s; a patrol boat at y = 15 m, 14 m/s"
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(out / "lidar_wake.png", dpi=90)
    plt.close(fig)


def buoys(out: Path, lines: list[str]) -> None:
    """A buoy 40 m ahead of a USV at W3 at two crests and two troughs: before (at rest at the still-water level,
    as every build before the buoys rode the waves) and after (riding the waves, :mod:`mmusv.world.buoys`), with
    the water's height at the buoy and the buoy's waterline."""
    from PIL import Image

    scenario = _scenario("W3")
    scenario["map"]["params"] = {"extent_m": 1000, "islet_probability": 0.0, "n_buoys": 4}
    camera = {"name": "view", "resolution": [320, 220], "hfov_deg": 40.0, "mount": {"point": "camera_front"}}
    scenario["rigs"]["view"] = {"cameras": [camera], "top_view": None, "lidar": None, "radar": None}
    scenario["acquisition"]["frames"] = 150  # 30 s: crests and troughs of the W3 sea (Tp 9.3 s) to choose from
    probe = Simulation({**scenario, "map": {"type": "open_sea", "seed": 2, "params": scenario["map"]["params"]}})
    bx, by = (float(v) for v in probe.world.priors.buoys[0])
    scenario["map"] = probe.scenario.map.model_dump()
    scenario["vessels"] = [
        {"id": "usv", "role": "usv", "asset": "usv_wamv", "rig": "view", "speed_mps": 0.5,
         "route": [[bx - 45.0, by], [bx - 35.0, by]]},
    ]  # fmt: skip
    # Two crests and two troughs at the buoy (the sea's elevation there, every frame).
    field = probe.scenario.environment.sea_spec().field(scenario_seed=scenario["seed"])
    times = np.arange(probe.frames) / probe.scenario.acquisition.frequency_hz
    eta = np.array([field.elevation(np.array([bx]), np.array([by]), float(t))[0] for t in times])

    def apart(candidates: np.ndarray) -> list[int]:  # the first two at least 10 frames (2 s) apart
        picked: list[int] = []
        for f in candidates:
            if all(abs(int(f) - g) >= 10 for g in picked):
                picked.append(int(f))
        return picked[:2]

    order = np.argsort(eta)
    frames = sorted(apart(order) + apart(order[::-1]))
    rows = []
    for name in ("before", "after"):
        sim = Simulation(scenario)
        if name == "before":
            sim._buoy_field = None  # the buoys at rest, as before they rode the waves
        tiles = []
        for frame in frames:
            cap = sim.capture(frame, radar=False)
            rgb = cap.agents["usv"].cameras["view"].rgb
            assert rgb is not None
            tiles.append(np.asarray(rgb))
            water = float(sim.ws.scene.wave_heights(np.array([[bx, by]]))[0])
            pose = sim.ws.scene.instance_pose(sim.ws.buoy_instances[0])
            tilt = float(np.degrees(np.arccos(np.clip(pose[2, 2], -1.0, 1.0))))
            lines.append(f"| {name} | {frame} | {water:+.2f} | {pose[2, 3]:+.2f} | {tilt:.1f} |")
        rows.append(np.concatenate(tiles, axis=1))
    Image.fromarray(np.concatenate(rows, axis=0)).save(out / "buoy_w3.png")
    # The tilt over many buoys and times, per sea state: the surface normal at the buoy's centre (the first model,
    # 2026-12-06) against the plane fitted over its waterplane (now) and the rms slope of the waves at least twice
    # the float's diameter long (the linear sea's sum of a^2 k^2 / 2 over them).
    from mmusv.world.buoys import buoy_matrices
    from mmusv.world.port import BUOY_FLOAT_RADIUS_M
    from mmusv.world.sea_state import sea_spec_for_preset

    xy = np.random.default_rng(1).uniform(-400.0, 400.0, size=(200, 2))
    lines += ["", "| sea state | tilt rms, normal at the centre (deg) | tilt rms, waterplane (deg) | max, waterplane "
              "(deg) | rms slope of the waves >= 2 diameters (deg) |", "|---|---|---|---|---|"]  # fmt: skip
    for wave in ("W0", "W1", "W2", "W3"):
        f = sea_spec_for_preset(wave).field(scenario_seed=7)
        a, _, k, _, _ = np.asarray(f.components()).T
        long = np.degrees(np.sqrt(np.sum((a**2 * k**2 / 2.0)[2.0 * np.pi / k >= 4.0 * BUOY_FLOAT_RADIUS_M])))
        point, plane = [], []
        for t in np.arange(0.0, 20.0, 0.4):
            s = f.slope(xy[:, 0].copy(), xy[:, 1].copy(), float(t))
            point.append(np.degrees(np.arctan(np.hypot(s[:, 0], s[:, 1]))))
            plane.append(np.degrees(np.arccos(np.clip(buoy_matrices(f, xy, float(t))[:, 2, 2], -1.0, 1.0))))
        pt, pl = np.concatenate(point), np.concatenate(plane)
        rms_pt, rms_pl = np.sqrt(np.mean(pt**2)), np.sqrt(np.mean(pl**2))
        lines.append(f"| {wave} | {rms_pt:.1f} | {rms_pl:.1f} | {pl.max():.1f} | {long:.1f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("-o", "--out", default=str(ROOT / "docs/sea"), help="output folder (default docs/sea)")
    ap.add_argument(
        "--only", default="craft,faces,radar,wake,buoys", help="comma-separated: craft, faces, radar, wake, buoys"
    )
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    parts = {
        "craft": (
            "| sea | frame | wave occlusion, camera | wave occlusion, LiDAR | LiDAR points on the craft |",
            craft_views,
        ),
        "faces": (
            "| sea state | sea | water returns within 60 m (4 sweeps) | world-z std (m) | std / (Hs/4) |",
            lidar_faces,
        ),
        "radar": ("| sea state | sea | clutter returns | 95th percentile clutter range (m) |", radar_ppi),
        "wake": ("| sweep | water returns | vessel returns |", lidar_wake),
        "buoys": ("| buoys | frame | water at the buoy (m) | the buoy's waterline (m) | its tilt (deg) |", buoys),
    }
    only = [p.strip() for p in args.only.split(",") if p.strip()]
    unknown = sorted(set(only) - set(parts))
    if unknown:
        ap.error(f"--only: unknown part(s) {', '.join(unknown)}; allowed: {', '.join(parts)}")
    lines: list[str] = []
    for name in only:
        header, make = parts[name]
        lines += ["", header, "|" + "---|" * header.count(" | ") + "---|"]
        make(out, lines)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
