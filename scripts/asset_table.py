"""Writes docs/assets.md: the vessel library's per-asset table (name, length, triangles, parts, floor met).

Usage: ``python3 scripts/asset_table.py [OUT]`` (default ``docs/assets.md`` next to this script's repository).
Every number is counted from the built meshes (:func:`mmusv.world.vessels.library`); the floors are those of
issue #28 (4,000 triangles under 15 m, 15,000 for 15-80 m, 40,000 from 80 m).
"""

from __future__ import annotations

import argparse
import statistics
import sys
from collections import Counter
from pathlib import Path

from mmusv.world.vessels import library

FLOORS = ((15.0, 4000, "under 15 m"), (80.0, 15000, "15-80 m"), (float("inf"), 40000, "80 m and over"))

USER_MESHES = """## Your own vessels: mesh files

An asset entry with `mesh:` (a file trimesh reads: `.glb`, `.gltf`, `.obj`, `.ply`, `.stl`, `.off`) builds a vessel
from your own model; `load_asset_file(..., register=True)` (or `load_asset_catalog` for a list) adds it to the
library, and a scenario's vessel names it as `asset:`. The entry's keys are those of
`mmusv.world.asset_spec.MeshAssetSpec`:

```python
from mmusv.world.vessels import load_asset_file

load_asset_file(
    {
        "name": "my_usv",
        "mesh": "models/my_usv.glb",  # relative to the YAML file's folder (a mapping: base_dir, else the cwd)
        "scale": 1.0,  # file units -> metres: 0.01 for a model in centimetres
        "draft": 0.4,  # metres below the waterline from the lowest point; or waterline_z (file units, default 0)
        "semantic_class": "usv",
        "mounts": {"lidar": {"xyz": [0.0, 0.0, 2.5]}},
    },
    register=True,
)
```

**From a scenario file.** `load_asset_file` registers an asset in one Python process only. A scenario run from the
command line (`mmusv run`, a batch, `mmusv dataset`, the editor) lists its asset files under `assets:`; each is a YAML
file holding one entry like the mapping above (or a list of them), its path relative to the scenario's folder, and
its `mesh:` relative to the asset file:

```yaml
# scenarios/with_my_usv.yaml
assets: [models/my_usv.yaml]   # name: my_usv, mesh: my_usv.glb, draft: 0.4, ...
vessels:
  - {id: usv_1, role: usv, asset: my_usv, speed_mps: 2, route: [[0, 0], [200, 0]]}
```

The files are read when the scenario is (an error names the scenario, `assets[i]` and the file), and read again in
the same process only when the asset file or its mesh changed. A name the library already holds (a built-in asset,
or another of the scenario's files') is refused, naming both. Each scenario sees the built-in assets (and those a
Python session registered) and its own asset files' assets only, none of another scenario's, wherever several are
read in one process (a batch, `mmusv run FOLDER`, in one process or its workers; the editor; a study; a Python
session): two scenarios may each name an asset of theirs `skiff`, and one that lists no asset file cannot use
another's. The scenario's config hash (`manifest.json`'s `config_hash`) covers the assets' meshes, so a batch re-run
records a scenario again when its mesh changed, rather than skipping it as complete. The `scenario.yaml` a run
writes beside its recording keeps the paths as written: copy the asset files along to run it again from there. The
editor (`mmusv editor`) reads a scenario's asset files from its folder (`--dir`), relative to it, as `mmusv run` of
the saved file does; it reads none outside that folder (Checks names the `assets[i]` to fix) but those of the
scenario named on its command line, which the page names by their full paths when that scenario lies outside
the folder (so a copy saved into the folder names the same files). Its vessel library and asset menus list the
built-in assets and the open scenario's own.

**Checking them: `mmusv assets FILE`.** `mmusv assets models/my_usv.yaml` lists an asset file's assets (its one
entry, or each of its list) and `mmusv assets with_my_usv.yaml` (the scenario above) those of the asset files the
scenario's `assets:` lists, read as `mmusv run` of it reads them (relative to its folder; the rest of the scenario
is not read). Several files may be given, scenarios and asset files mixed. The table has the library's columns
(length, beam, height and draft in metres, triangles, parts: 0 for a mesh file) and two more: `materials`, how many
materials its faces use (a file without colours or materials has its class's default look: 1), and `file`, the asset
file it comes from (and the scenario that lists it); it is printed instead of the built-in library's. `--materials`
adds a table per asset (the library's too, without FILE): each material by name with its faces, base colour (linear
RGB and the 8-bit sRGB it shows as), roughness, metallic, emitted radiance (cd/m²) and a navigation lamp's arc, so
you can see what was read of a glTF's PBR materials, an MTL or vertex colours (`class_default`: the class's
look). `--render DIR`
draws those assets' close-ups and their contact sheet, as for the library. A file that does not exist, one that is
neither a scenario nor an asset file, and an asset a run would refuse (a bad key, a missing mesh, a built-in asset's
name) are one `mmusv: error:` line naming the file and the key (exit status 2), before `--render`'s folder is made.
The files are read, not registered: nothing is added to the library.

**Axes.** `up_axis` and `forward_axis` (the file's up and bow directions, any of x, y, z, -x, -y, -z) turn the
file into the body frame: x forward (bow), y to port, z up, z = 0 the waterline. When an entry gives neither, the
file's format decides (`mmusv.world.asset_spec.FORMAT_AXES`): a `.gltf`/`.glb` file is read +Y up with its bow
towards +Z, as glTF 2.0 defines (section 3.4, "Coordinate System and Units"; Blender's glTF export writes it so),
and every other format z up, x forward (`mmusv.world.asset_spec.DEFAULT_AXES`: OBJ, PLY, STL and OFF have no
convention of their own). When an entry gives one axis, the other defaults to z (up) or x (forward) whatever the
format. A mesh that comes out wider or taller than long under a defaulted axis gets a warning (`MmusvWarning`)
naming the file and the keys to set; giving both axes silences it. Taller than long is what an OBJ or PLY exported
from Blender with its defaults (Y up) looks like read z up: a hull standing on end; the warning says to give
`up_axis: y` and the bow's direction. A dinghy whose mast stands higher than its hull is long warns too.

**Changed:** before, every file, glTF included, defaulted to z up, x forward. A `.gltf`/`.glb` written z-up (a
z-up mesh exported by trimesh, some CAD tools) whose entry gives neither axis now loads on its side: add
`up_axis: z` and `forward_axis: x` to its entry. Read as glTF, such a hull comes out wider than long (its length
becomes its beam), so the warning above names it and this fix. Entries that give either axis load exactly as
before.

**Units and node graphs.** A glTF scene's node transforms (nested, scaled, mirrored) are applied; glTF is in
metres, other files in whatever their author used: `scale` converts.

**Materials** come through per face, each texture by its mean over its texels (mmusv shades one material per
face); the conversions are `mmusv.world.mesh_materials`'s.

- *glTF/GLB*, as glTF 2.0 defines them: base colour = `baseColorFactor` (linear, as written: not rounded to 1/255) x
  `baseColorTexture` (sRGB, 8 or 16 bits, averaged in linear RGB); roughness and metallic = `roughnessFactor` and
  `metallicFactor` (default 1) x the green and blue channels of the `metallicRoughnessTexture`; emission =
  `emissiveFactor` (default 0) x `emissiveTexture` (sRGB) x
  `KHR_materials_emissive_strength`, 1 standing for `mmusv.world.mesh_files.GLTF_EMISSIVE_SCALE` cd/m². Not read:
  alpha (`alphaMode`, a base colour's alpha: every face is opaque), `doubleSided` (the ray caster hits both sides of
  every face anyway), normal and occlusion textures.

  Geometry compressed with Draco (`KHR_draco_mesh_compression`, as Blender's exporter and Sketchfab write it) is
  decoded with DracoPy, installed with mmusv (positions come back within Draco's quantisation: 14 bits over the
  mesh by default). A file that *requires* another extension (`extensionsRequired`) is refused, as glTF 2.0 asks
  of a reader that does not know it: mmusv reads `KHR_draco_mesh_compression`, `KHR_materials_emissive_strength`,
  `KHR_materials_pbrSpecularGlossiness` (trimesh converts it), `KHR_mesh_quantization` (integer positions read as
  their numbers; `normalized` positions are refused, trimesh would read them raw), `KHR_texture_transform`
  (textures are taken by their mean) and `EXT_texture_webp`; re-export a file that needs `EXT_meshopt_compression`
  or another without it. A sparse `POSITION` accessor is refused too (trimesh leaves its substitutions out).

  A primitive's vertex colours (`COLOR_0`: float, or unsigned byte/short normalized; RGB or RGBA, alpha not read)
  multiply its base colour, as glTF 2.0 defines them (section 3.9.2: "an additional linear multiplier to base
  color") and Blender's glTF importer and three.js's GLTFLoader apply them: taken as linear RGB as stored (not
  decoded from sRGB, unlike PLY colours), a face's colour is the mean of its three vertices', times the material's
  base colour, quantised to 64 levels per sRGB channel as vertex colours below. Each distinct result is one
  material `<file stem>:<material name>:#rrggbb`, the glTF material with that base colour (roughness, metallic and
  emission kept); a primitive with `COLOR_0` and no material gets the `vertex_colour:#rrggbb` materials below. A
  hard colour edge (a corner written once per face, as exporters split it) keeps each face's colour.
- *OBJ with MTL*: each face takes the material its `usemtl` names (`<file stem>:<newmtl name>`), from the files its
  `mtllib` lines name (relative to the `.obj`; textures relative to the `.mtl`, options such as `-s 1 1 1` skipped,
  as the [MTL spec](https://paulbourke.net/dataformats/mtl/) writes them, else by their file name beside the `.mtl`,
  as obj2gltf looks for an absolute path written on another machine), converted as Blender's OBJ importer
  (`source/blender/io/wavefront_obj/importer/obj_import_mtl.cc`) does:

  - `Kd` is the base colour, taken as linear RGB as stored: Blender sets it as the (scene-linear) Base Color and
    exports Base Color as `Kd`, so a model looks as it did in Blender; CesiumGS obj2gltf writes it as the linear
    `baseColorFactor` (three.js's MTLLoader decodes it from sRGB instead). A `map_Kd` texture takes its place, by
    its mean in linear RGB (sRGB-decoded), as Blender (texture linked to Base Color) and obj2gltf (factor 1) do.
    Neither: 0.8 grey, Blender's default Base Color.
  - roughness = `Pr` (the PBR extension) where given, else 1 - sqrt(clamp(`Ns`, 0, 1000) / 1000) (Blender's
    importer), 1 without `Ns` (obj2gltf's default `Ns` is 0).
  - metallic = `Pm` where given, else 0 (obj2gltf; Blender reads the mean of `Ka` as metallic for `illum 3` only,
    which mmusv does not follow: most files' `Ka` is an ambient colour, often white).
  - emission = `Ke` (a `map_Ke` texture's mean in its place), `Ke` 1 standing for `GLTF_EMISSIVE_SCALE` cd/m² as a
    glTF `emissiveFactor` of 1 does: Blender imports `Ke` as Emission Color at strength 1 and exports that as
    `emissiveFactor`.
  - not read: `d` and `Tr` (every face is opaque), `Ka`, `Ks`, `Ni`, `illum`, bump and normal maps.

  An OBJ without `mtllib` keeps the class's default look (its `usemtl` lines name nothing to read), as do faces
  before the first `usemtl`.
- *Vertex and face colours* (PLY `red`/`green`/`blue`, OBJ `v x y z r g b`, face colours of any format trimesh
  reads them from) are taken as sRGB (the default of Blender's PLY importer and exporter; three.js's PLYLoader
  decodes them so too). A face's colour is the mean of its three vertices' in linear RGB (the mean, over the face,
  of the colour a modelling tool interpolates across it), quantised to 64 levels per sRGB channel (steps of 1/63);
  each distinct colour is one material `vertex_colour:#rrggbb` (roughness 0.5, metallic 0, as the class default),
  shared by all files. A file with more than 256 distinct face colours
  (`mmusv.world.mesh_materials.MAX_COLOUR_MATERIALS`) is quantised coarser (32, 16, ... down to 2 levels) until it
  has no more (a glTF's `COLOR_0` materials counted with them; should they still be more at 2 levels, each glTF
  material its `COLOR_0` multiplies takes the mean of its faces' colours), with a `MmusvWarning` saying so. An
  OBJ's faces with an MTL material keep that material.
- STL, OFF and other files without colours, and glTF primitives with neither a material nor `COLOR_0`, get the
  class's default look.

**Bad files** are one `AssetSpecError` line naming the entry's `mesh` key, the file and what is wrong: missing, a
folder, empty, an extension trimesh does not read, a GLB shorter than its header says, a `.gltf` whose `.bin` or
texture file is missing or not an image, an OBJ whose `.mtl` (`mtllib`) or `map_Kd`/`map_Ke` texture is missing
(naming the entry and the path looked for) or not an image, a `usemtl` naming no material of its MTL files, an MTL
value out of range (`Kd` outside [0, 1], ...), a glTF material factor outside [0, 1] (`baseColorFactor`,
`metallicFactor`, `roughnessFactor`, `emissiveFactor`: trimesh would clamp it), a glTF index into one of the file's
lists that is not in it (`scene`, a node's `mesh`, a primitive's `material` or accessors, a material's texture,
...), JSON without `asset.version` or of another glTF major version than 2, an accessor `componentType` or `type`
glTF does not define, a `POSITION` that is not VEC3, `indices` that are not SCALAR unsigned integers, a
`TRIANGLE_FAN` primitive (mode 6, which trimesh would leave out), a node with both `matrix` and TRS, a non-affine
`matrix`, a `rotation` that is not a unit quaternion, a node with two parents or in a cycle, a buffer without
`uri` (but a GLB's first, which needs the GLB's binary chunk), a base colour, metallic-roughness or emissive
texture whose image cannot be read (trimesh would leave it out: the hull came out white), a `COLOR_0`
that glTF does not allow or that does not fit its
primitive (naming the primitive and accessor: another count than its `POSITION`, not VEC3/VEC4, not float or
normalized unsigned byte/short, a sparse accessor (trimesh does not apply its values), non-finite or outside
[0, 1]), non-finite coordinates, no triangles (for a glTF, why: no scene, a scene whose nodes place none of
its meshes, or only points and lines placed; points and lines beside triangles are left out with a warning naming
them), or trimesh's own reason for a file it cannot parse. A texture or
buffer URI is read as glTF means it: percent-decoded and relative to the `.gltf` (`../textures/` included).
"""


def floor(length: float) -> tuple[int, str]:
    """The triangle floor and size class of a vessel ``length`` metres long."""
    return next((f, label) for top, f, label in FLOORS if length < top)


def table() -> str:
    """The Markdown of docs/assets.md."""
    assets = library()
    rows = []
    by_class: dict[str, list[int]] = {label: [] for _, _, label in FLOORS}
    for a in sorted(assets, key=lambda a: a.length):
        f, label = floor(a.length)
        by_class[label].append(a.num_triangles)
        kinds = Counter(a.parts)
        listed = ", ".join(f"{k} ×{n}" if n > 1 else k for k, n in sorted(kinds.items()))
        met = "yes" if a.num_triangles >= f else "**no**"
        rows.append(
            f"| `{a.name}` | {a.category} | {a.length:.1f} | {a.num_triangles:,} | {f:,} | {met} | {a.num_parts} | "
            f"{listed} |"
        )
    summary = [
        f"| {label} | {len(v)} | {min(v):,} | {int(statistics.median(v)):,} | {max(v):,} |"
        for label, v in by_class.items()
        if v
    ]
    lines = [
        "# Vessel library",
        "",
        "The 37 built-in assets of `mmusv/world/vessel_catalog.yaml`, built from parts (hull loft: "
        "`mmusv.world.hull_form`; part families: `mmusv.world.parts_super`, `mmusv.world.parts_deck`) with a material "
        "on every face (`mmusv.world.materials`). Triangles are counted from the built meshes; the floors are issue "
        "#28's. `mmusv assets` prints the same counts; `mmusv assets --render DIR` draws a close-up of each and a "
        "contact sheet; `mmusv assets FILE` does the same for your own assets (below). Generated by "
        "`scripts/asset_table.py`; do not edit by hand.",
        "",
        "| size class | assets | min triangles | median | max |",
        "|---|---:|---:|---:|---:|",
        *summary,
        "",
        "| asset | category | length m | triangles | floor | floor met | parts | part kinds |",
        "|---|---|---:|---:|---:|---|---:|---|",
        *rows,
        "",
        USER_MESHES,
    ]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    default = Path(__file__).resolve().parent.parent / "docs" / "assets.md"
    ap.add_argument("out", nargs="?", type=Path, default=default, help="the Markdown file (default: docs/assets.md)")
    out = ap.parse_args(argv[1:]).out
    text = table()
    tmp = out.with_name(out.name + ".part")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(out)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
