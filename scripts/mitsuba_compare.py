"""mmusv's camera radiance against Mitsuba 3, at a larger size than the tests: side-by-side pictures and a table.

For each scene of ``tests/reference/mitsuba_scenes.py`` (the same scenes, cameras, materials and light transport
as ``tests/reference/test_mitsuba.py``), writes ``docs/realism/mitsuba_<scene>.png``: mmusv | Mitsuba | the
per-pixel relative error, both pictures exposed alike (mmusv's metered exposure) and tone-mapped with mmusv's
curve; then ``docs/realism/mitsuba.md``: each scene's mean relative error (silhouettes excluded), per object
and per channel, Mitsuba's own noise at the tests' settings, and the timings.

Usage: ``python3 scripts/mitsuba_compare.py [--width 192 --height 128 --spp 1024 --out docs/realism]``
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import numpy.typing as npt

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "reference"))

import mitsuba_scenes as ms  # noqa: E402

#: The tests' settings (``tests/reference/test_mitsuba.py``), for the noise column.
TEST_SIZE, TEST_SPP = (96, 64), 256
#: One scene's outcome: the comparison, its seconds, Mitsuba's noise at the tests' settings, Mitsuba's full
#: path tracing, and mmusv's error at ``high`` quality.
Result = tuple[ms.Comparison, float, float, npt.NDArray[np.float32], float]
#: Top of the error heat map's scale.
ERROR_SCALE = 0.10


def tone(radiance: npt.NDArray[np.float32], exposure: float) -> npt.NDArray[np.uint8]:
    """mmusv's image formation (``shade/tonemap.rs``): exposure, Narkowicz's ACES fit, sRGB, 8 bits."""
    x = np.maximum(radiance.astype(np.float64) * exposure, 0.0)
    y = np.clip(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    s = np.where(y <= 0.0031308, 12.92 * y, 1.055 * np.power(y, 1.0 / 2.4) - 0.055)
    return np.asarray(np.clip(s * 255.0 + 0.5, 0, 255), dtype=np.uint8)


def picture(c: ms.Comparison, path: Path) -> None:
    """mmusv | Mitsuba | relative error (excluded pixels grey) side by side."""
    k = c.mmusv.exposure
    heat = np.ma.masked_array(c.error, mask=~c.keep)
    h, w = c.error.shape
    scale = 1.6 / 100.0
    fig, axes = plt.subplots(1, 3, figsize=(3 * w * scale + 1.0, h * scale + 0.7), dpi=100)
    for ax, img, label in [
        (axes[0], tone(c.mmusv.radiance, k), "mmusv"),
        (axes[1], tone(c.mitsuba.radiance, k), "Mitsuba 3 (reference)"),
    ]:
        ax.imshow(img, interpolation="nearest")
        ax.set_title(label, fontsize=8)
    cmap = plt.get_cmap("inferno").copy()
    cmap.set_bad((0.55, 0.55, 0.55))
    im = axes[2].imshow(heat, cmap=cmap, vmin=0.0, vmax=ERROR_SCALE, interpolation="nearest")
    axes[2].set_title(f"relative error, mean {100 * c.mean_error:.2f} %", fontsize=8)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    bar = fig.colorbar(im, ax=axes[2], fraction=0.046, pad=0.02)
    bar.ax.tick_params(labelsize=7)
    bar.set_ticks([0.0, 0.025, 0.05, 0.075, 0.1], labels=["0", "2.5 %", "5 %", "7.5 %", "≥ 10 %"])
    fig.suptitle(f"{c.scene.name}: {c.scene.title}", fontsize=9)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)


def breakdown(
    c: ms.Comparison, full: npt.NDArray[np.float32]
) -> list[tuple[str, int, float, npt.NDArray[np.float64], float]]:
    """Per object (and the sky): kept pixels, mean relative error, mean mmusv / Mitsuba per channel − 1, and the
    mean relative error against full path tracing ``full``."""
    rows = []
    parts = [(o.name, i) for i, o in enumerate(c.scene.objects)] + [("sky", -1)]
    for name, i in parts:
        m = (c.mmusv.instance == i) & c.keep
        if not m.any():
            continue
        bias = c.mmusv.radiance[m].astype(np.float64).mean(0) / c.mitsuba.radiance[m].astype(np.float64).mean(0) - 1
        beyond = float(ms.relative_error(c.mmusv.radiance, full)[m].mean())
        rows.append((name, int(m.sum()), float(c.error[m].mean()), bias, beyond))
    return rows


def noise_floor(scene: ms.RefScene, workdir: Path) -> float:
    """Mitsuba's own noise at the tests' settings: the mean relative difference of two renders with different
    seeds over the tests' kept pixels, divided by √2 (what one render contributes)."""
    w, h = TEST_SIZE
    a = ms.render_mmusv(scene, w, h)
    b1 = ms.render_mitsuba(scene, a.instance, w, h, spp=TEST_SPP, seed=0, workdir=workdir)
    b2 = ms.render_mitsuba(scene, a.instance, w, h, spp=TEST_SPP, seed=1, workdir=workdir)
    keep = ~ms.excluded(a)
    return float(ms.relative_error(b1.radiance, b2.radiance)[keep].mean() / np.sqrt(2.0))


def layer_table(scene: ms.RefScene, spp: int) -> str:
    """The Mitsuba layers of ``scene`` as a Markdown list."""
    lines = []
    for lay in ms.layers(scene, spp):
        objs = ", ".join(scene.objects[i].name for i in lay.objects)
        lights = " + ".join(x for x, on in (("sun", lay.sun), ("sky", lay.sky)) if on)
        pix = ", ".join("sky" if i < 0 else scene.objects[i].name for i in lay.pixels)
        water = f", water as `{lay.water}`" if any(scene.objects[i].is_water for i in lay.objects) else ""
        lines.append(
            f"  - `{lay.name}`: {objs} under {lights}, `max_depth` {lay.max_depth}, {lay.spp} spp{water}; "
            f"used on: {pix}"
        )
    return "\n".join(lines)


def machine() -> str:
    """A line describing this machine."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} cores ({cpu}), shared with other jobs; Python {platform.python_version()}"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    p.add_argument("--width", type=int, default=192, help="image width in pixels (default %(default)s)")
    p.add_argument("--height", type=int, default=128, help="image height in pixels (default %(default)s)")
    p.add_argument("--spp", type=int, default=1024, help="Mitsuba samples per pixel of the environment layers")
    p.add_argument("--out", type=Path, default=ROOT / "docs" / "realism", help="output folder (default docs/realism)")
    p.add_argument("--scenes", nargs="*", default=None, help="scene names (default: all)")
    args = p.parse_args(argv)
    import mitsuba as mi

    all_scenes = ms.scenes()
    names = args.scenes or list(all_scenes)
    args.out.mkdir(parents=True, exist_ok=True)
    results: list[Result] = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            scene = all_scenes[name]
            t0 = time.perf_counter()
            c = ms.compare(scene, args.width, args.height, spp=args.spp, workdir=Path(tmp))
            seconds = time.perf_counter() - t0
            noise = noise_floor(scene, Path(tmp))
            full = ms.render_path_traced(
                scene, args.width, args.height, spp=max(16, args.spp // 4), seed=0, workdir=Path(tmp)
            )
            high = ms.render_mmusv(scene, args.width, args.height, quality="high")
            high_error = float(ms.relative_error(high.radiance, c.mitsuba.radiance)[c.keep].mean())
            picture(c, args.out / f"mitsuba_{name}.png")
            results.append((c, seconds, noise, full, high_error))
            print(f"{name}: mean relative error {100 * c.mean_error:.2f} % ({seconds:.0f} s)", flush=True)
    write_table(args, results, str(mi.__version__))
    return 0


def write_table(args: Any, results: list[Result], mi_version: str) -> None:
    """``mitsuba.md``: method, the table, the breakdown per object."""
    w, h = args.width, args.height
    out: list[str] = [
        "# mmusv against Mitsuba 3",
        "",
        "Issue #28, part 4: the cameras' linear radiance (cd/m², before exposure and tone mapping) against Mitsuba "
        f"{mi_version} (`scalar_rgb`), on the scenes of `tests/reference/mitsuba_scenes.py`. The CI test "
        f"`tests/reference/test_mitsuba.py` renders the same scenes at {TEST_SIZE[0]}×{TEST_SIZE[1]} with "
        f"{TEST_SPP} spp and requires each scene's mean relative error to be at most 3 %, and in `water` and "
        "`grazing` that of the water below the objects (their reflections) to be at most 8 %. Generated by "
        f"`python3 scripts/mitsuba_compare.py --width {w} --height {h} --spp {args.spp}`.",
        "",
        "## Method",
        "",
        "- **Same input.** The same triangles (float32, flat face normals; spheres are 64×32 UV meshes given to "
        "Mitsuba as PLY files), the same pinhole camera (Mitsuba's `perspective` with `fov_axis = x` sends its "
        "ray through each pixel centre along mmusv's ray of that pixel, checked by a test), the same sun "
        "(`directional`, irradiance `env.sun_irradiance`, lux, linear sRGB) and the same sky (`env.sky_radiance`"
        f" as a {ms.ENVMAP_SIZE[0]}×{ms.ENVMAP_SIZE[1]} lat-long `envmap`, no sun disc; the ground below the "
        "horizon; checked by a test that cameras looking at the sky see the same radiance in both to 1 %).",
        "- **Same materials.** Lambert `(1 − metallic)·base/π` = `diffuse`; GGX/Smith specular (α = roughness²) "
        "= `roughconductor` with `ggx` (dielectric: `eta` 1.5, `k` 0, the exact Fresnel whose normal incidence "
        "value is mmusv's F0 = 0.04; metal: Mitsuba's `Al` `eta`/`k`, mmusv getting their normal incidence "
        "reflectance as base colour); their sum as a `blendbsdf` of weight 0.5 of both with doubled "
        "reflectances. Water = the body of a smooth `plastic` (`int_ior` 1.33, `ext_ior` 1, water albedo, "
        "`nonlinear` false) plus its rough interface, the sun's glint and the glossy reflections alike: "
        "`roughconductor` (`beckmann`, `eta` 1.33, `k` 0, α = the Cox–Munk slope). "
        "mmusv's Schlick Fresnel is compared against the exact one.",
        "- **Same light transport.** mmusv lights surfaces directly: the sun with a shadow ray, the sky and "
        "ground as image-based light without occlusion, water adding its reflections traced in directions drawn "
        "from the roughness lobe at each point and spread over the rest of it in screen space "
        "(`sensors/camera/glossy.rs`), weighted by the rough surface's "
        "directional reflectance (`sensors/shade/rough_water.rs`). Mitsuba path-traces that rough reflection; "
        "it renders the rest as layers composited by mmusv's instance image. Mitsuba's rough BSDFs reflect "
        "once, so mmusv's water is rendered with its single scattering alone (`water_multiple_scattering=False`;"
        " the light reflected between the wave facets, `sensors/shade/sea_ms.rs`, is checked on its own):",
        "",
        "\n\n".join(f"  {r[0].scene.name}:\n\n{layer_table(r[0].scene, args.spp)}" for r in results),
        "",
        "  The water scenes set `ground_albedo` 0: an object seen in the mirror has the water below its horizon, "
        "black at that path depth in Mitsuba, so mmusv's ground is black too.",
        "- **Same pixels.** mmusv is rendered at 4×4 times the resolution at its default `standard` quality (one "
        "traced water reflection per 2×2 block of water pixels, 4×4 where the water's glossy lobe spans many such "
        "blocks; the table also gives `high`, every pixel's) and "
        "box-averaged (mean over each pixel's area, as Mitsuba's box filter). **Excluded:** silhouette pixels "
        "(an instance change inside the pixel or with a 4-neighbour), dilated by one pixel: grey in the "
        "pictures' error maps. Edges seen in the "
        "water's reflection are kept.",
        "- **Error.** Per pixel `Σ_c |mmusv_c − Mitsuba_c| / Σ_c Mitsuba_c` over the RGB channels; the mean over "
        "the kept pixels. Mitsuba's own Monte Carlo noise adds to it: the noise column is the mean relative "
        "difference of two Mitsuba renders with different seeds at the tests' settings, over √2.",
        f"- **Machine.** {machine()}. Sampler `multijitter`; the environment layers get the spp below, the "
        "sun's layers a quarter.",
        "",
        "## Results",
        "",
        f"| scene | resolution | spp | pixels kept | mean relative error | the same, mmusv at `high` quality | "
        f"Mitsuba noise at {TEST_SIZE[0]}×{TEST_SIZE[1]}, {TEST_SPP} spp | mmusv s | Mitsuba s | "
        "against full path tracing (information) | picture |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c, _seconds, noise, full, high_error in results:
        beyond = float(ms.relative_error(c.mmusv.radiance, full)[c.keep].mean())
        out.append(
            f"| {c.scene.name} | {w}×{h} | {args.spp} | {100 * c.keep.mean():.1f} % | "
            f"**{100 * c.mean_error:.2f} %** | {100 * high_error:.2f} % | {100 * noise:.2f} % | "
            f"{c.mmusv.seconds:.1f} | "
            f"{sum(c.mitsuba.seconds.values()):.1f} | {100 * beyond:.2f} % | [png](mitsuba_{c.scene.name}.png) |"
        )
    out += [
        "",
        "The column *against full path tracing* is not the test: it compares the same mmusv image with Mitsuba's "
        f"full path tracing of the same scene (every object together under sun and sky, paths up to 8 segments, "
        f"{max(16, args.spp // 4)} spp, the water a smooth `plastic` without the glint): the sky hidden by the "
        "other objects, light passed between surfaces and the sky's light reflected by the water onto the "
        "objects, which mmusv's direct-light model leaves out by design (its uniform ground below the horizon "
        "stands in for them; the water scenes set it black, see above). The per-object table below gives its "
        "share per object.",
    ]
    out += [
        "",
        "## Per object",
        "",
        "Mean relative error, the bias of the mean radiance (mmusv / Mitsuba − 1) per channel, and the mean "
        "relative error against full path tracing (information).",
        "",
    ]
    for c, _seconds, _noise, full, _high in results:
        out += [
            f"### {c.scene.name}: {c.scene.title}",
            "",
            f"{c.scene.notes}.",
            "",
            f"![{c.scene.name}](mitsuba_{c.scene.name}.png)",
            "",
            "| part | pixels | mean relative error | bias R | bias G | bias B | against full path tracing |",
            "|---|---|---|---|---|---|---|",
        ]
        for name, n, err, bias, beyond in breakdown(c, full):
            out.append(
                f"| {name} | {n} | {100 * err:.2f} % | {100 * bias[0]:+.2f} % | {100 * bias[1]:+.2f} % | "
                f"{100 * bias[2]:+.2f} % | {100 * beyond:.2f} % |"
            )
        out.append("")
    (args.out / "mitsuba.md").write_text("\n".join(out))


if __name__ == "__main__":
    raise SystemExit(main())
