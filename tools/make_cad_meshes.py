#!/usr/bin/env python3
"""Converts the public CAD meshes of mjcf/workcells/cad_cell.xml into the binary STL files of
mjcf/workcells/meshes/cad/ (standard library only). Sources, licence and changes:
mjcf/workcells/meshes/LICENSES.md.

The source is the NIST ARIAC repository (https://github.com/usnistgov/ARIAC, public domain in the
US, NIST's licence statement), read at a fixed commit from a clone or mirror of it:

  tools/make_cad_meshes.py --ariac-git /path/to/ARIAC/.git [--commit SHA] [--out DIR]

Each output part is one convex (or nearly convex) piece, because MuJoCo collides a mesh as its convex
hull: the assembly table's top and four legs are separate files in the source already; the
conveyor's 9 m middle section is split into its connected parts (two side rails, the belt, six legs;
the small brackets, bolts and sensor mounts on the rails, at most 0.12 m across, are left out) and
its legs are cut at the rails' underside (z 0.564 m) so that their hulls touch the rails' instead of
reaching into the channel; the parts bin and the disposal bin are kept whole (their hulls fill the
bins' openings and stands). Vertices are moved so that each model's parts share one frame: the
table's and bins' as in the source, the conveyor's centred on its middle section in x and y
(z unchanged: the floor), its length along y. Units: metres, as the source.
"""
import argparse
import pathlib
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import stl_mesh  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
COMMIT = "ffc825757dc05cc6e4dfbd5c2483e993aab35652"
MODELS = "ariac_gazebo/models"
RAIL_UNDERSIDE = 0.564  # [m] z of the conveyor rails' lowest vertex in the source


def source(git, commit, path):
    return subprocess.run(["git", "--git-dir", str(git), "show", f"{commit}:{MODELS}/{path}"],
                          check=True, capture_output=True).stdout


def conveyor_parts(tris):
    """The middle section's parts, named: rails (the two 116-triangle channels), the belt (124
    triangles) and the legs (12-triangle boxes), in order of x, then y."""
    lo_y, hi_y = -4.2, 5.0  # the middle section, y -4.071 .. 4.934 m in the source
    parts = [c for c in stl_mesh.components(tris)
             if lo_y < stl_mesh.bounds(c)[0][1] and stl_mesh.bounds(c)[1][1] < hi_y]
    by_kind = {116: [], 124: [], 12: []}
    for c in parts:
        if len(c) in by_kind:
            by_kind[len(c)].append(c)
    key = lambda c: (round(stl_mesh.bounds(c)[0][1], 3), round(stl_mesh.bounds(c)[0][0], 3))
    rails = sorted(by_kind[116], key=lambda c: stl_mesh.bounds(c)[0][0])
    legs = sorted(by_kind[12], key=key)
    assert len(rails) == 2 and len(by_kind[124]) == 1 and len(legs) == 6, "unexpected conveyor mesh"
    cut = lambda c: [tuple((p[0], p[1], min(p[2], RAIL_UNDERSIDE)) for p in t) for t in c]
    named = [("conveyor_rail_a", rails[0]), ("conveyor_rail_b", rails[1]), ("conveyor_belt", by_kind[124][0])]
    named += [(f"conveyor_leg_{i + 1}", cut(c)) for i, c in enumerate(legs)]
    lo, hi = stl_mesh.bounds([t for _, c in named for t in c])
    shift = (-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, 0.0)
    return [(n, stl_mesh.transform(c, shift=shift)) for n, c in named]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ariac-git", type=pathlib.Path, required=True, help="the ARIAC repository's git directory")
    ap.add_argument("--commit", default=COMMIT)
    ap.add_argument("--out", type=pathlib.Path, default=ROOT / "mjcf" / "workcells" / "meshes" / "cad")
    args = ap.parse_args()
    read = lambda p: stl_mesh.read_stl(source(args.ariac_git, args.commit, p))
    parts = [("table_top", read("assembly_table/meshes/table_top.stl"))]
    parts += [(f"table_leg_{i}", read(f"assembly_table/meshes/leg{i}.stl")) for i in range(1, 5)]
    parts += conveyor_parts(read("conveyor_belt/meshes/conveyor.stl"))
    parts += [("parts_bin", read("parts_bin/meshes/bin_exterior.stl")),
              ("disposal_bin", read("dropped_part_bin/meshes/disposal_bin.stl"))]
    args.out.mkdir(parents=True, exist_ok=True)
    for name, tris in parts:
        lo, hi = stl_mesh.bounds(tris)
        header = f"leeway cad_cell {name} from NIST ARIAC {args.commit[:10]}"
        (args.out / f"{name}.stl").write_bytes(stl_mesh.stl_bytes(tris, header))
        print(f"{name}: {len(tris)} triangles, x {lo[0]:.3f} .. {hi[0]:.3f}, y {lo[1]:.3f} .. {hi[1]:.3f}, "
              f"z {lo[2]:.3f} .. {hi[2]:.3f} m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
