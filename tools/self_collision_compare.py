#!/usr/bin/env python3
"""Compares two leeway builds on the 15 sparse paths (the nine thesis paths and the six on the cells
built for judging): the safety stage's time and leaves, the certified/guide j1-j3 width ratio, and
`leeway cf --self` of each build's certified bounds scored by the NEW build (obstacle collisions and
self-collisions counted apart). Written for the self-collision work: the base build certifies
against the obstacles only, the new one against the robot itself too.

Usage: tools/self_collision_compare.py --base BASE/leeway --new build/leeway [--base-root BASE]
                                       [--samples 10000] [--repeats 1] [--out FILE.md]
The base build reads its own cells (--base-root, its checkout); both runs are made one after the
other per path, so they share the machine's state. Times are the bounds file's timing_ms.safety [ms],
median of --repeats runs. Standard library only.
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from machine_info import machine  # noqa: E402
from make_safety_results import NEW_PATHS, THESIS_PATHS, widths  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent


def bounds(leeway, root, cell, src, dst, out, repeats):
    xml = str(pathlib.Path(root) / "mjcf" / "workcells" / f"{cell}.xml")
    times = []
    for _ in range(repeats):
        r = subprocess.run([leeway, "bounds", xml, "--from", src, "--to", dst, "--out", out],
                           capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f"{leeway} bounds {cell} {src}-{dst} failed ({r.returncode}): {r.stderr.strip()}")
        data = json.loads(pathlib.Path(out).read_text())
        times.append(data["timing_ms"]["safety"])
    return data, statistics.median(times)


def cf_self(leeway, cell, path, samples):
    xml = str(ROOT / "mjcf" / "workcells" / f"{cell}.xml")
    r = subprocess.run([leeway, "cf", xml, path, "--self", "--json", "--samples", str(samples)],
                       capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"{leeway} cf {cell} {path} failed ({r.returncode}): {r.stderr.strip()}")
    return json.loads(r.stdout)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", required=True)
    ap.add_argument("--base-root", default=None)
    ap.add_argument("--new", default=str(ROOT / "build" / "leeway"))
    ap.add_argument("--samples", type=int, default=10000)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    base_root = a.base_root or str(pathlib.Path(a.base).resolve().parent.parent)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for cell, src, dst in THESIS_PATHS + NEW_PATHS:
            bf, nf = f"{tmp}/base.json", f"{tmp}/new.json"
            b, bt = bounds(a.base, base_root, cell, src, dst, bf, a.repeats)
            n, nt = bounds(a.new, ROOT, cell, src, dst, nf, a.repeats)
            cb, cn = cf_self(a.new, cell, bf, a.samples), cf_self(a.new, cell, nf, a.samples)
            ratio = lambda d: widths(d)[0] / widths(d, "guide_")[0]
            rows.append({"path": f"{cell} {src}-{dst}", "base_ms": bt, "new_ms": nt,
                         "base_leaves": b["safety"]["leaves"], "new_leaves": n["safety"]["leaves"],
                         "base_ratio": ratio(b), "new_ratio": ratio(n),
                         "base_width": widths(b)[0], "new_width": widths(n)[0],
                         "base_certified": b["safety"]["certified"], "new_certified": n["safety"]["certified"],
                         "base_obstacle": cb["obstacle_collisions"], "base_self": cb["self_collisions"],
                         "new_obstacle": cn["obstacle_collisions"], "new_self": cn["self_collisions"],
                         "samples": cn["samples"]})
            r = rows[-1]
            print(f"{r['path']}: base {bt:.0f} ms ratio {r['base_ratio']:.4f} self {r['base_self']}; "
                  f"new {nt:.0f} ms ratio {r['new_ratio']:.4f} obstacle {r['new_obstacle']} self {r['new_self']}",
                  flush=True)
    head = ["## Self-collision: certified against the robot itself", "",
            f"`tools/self_collision_compare.py --base BASE/build/leeway --samples {a.samples} --repeats "
            f"{a.repeats} --out docs/data/safety/self_collision.md`, BASE a build of the commit before "
            "self-collision was certified. Machine: " + machine() + f"; load average {os.getloadavg()[0]:.2f} "
            "at the end. Both builds run one after the other on each path; the safety stage's time is the "
            "median of the repeats [ms]; `cf --self` (30 windows, seed 1) of both builds' certified bounds is "
            "scored by the new build, obstacle collisions and self-collisions apart.", ""]
    lines = ["| path | safety stage [ms] base -> new | leaves base -> new | certified/guide j1-j3 width "
             "base -> new | certified j1-j3 width [rad] base -> new | cf --self of base bounds: obstacle, self | "
             "of new bounds: obstacle, self | certified |",
             "|---|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| {r['path']} | {r['base_ms']:.0f} -> {r['new_ms']:.0f} | {r['base_leaves']:,} -> "
                     f"{r['new_leaves']:,} | {r['base_ratio']:.4f} -> {r['new_ratio']:.4f} | "
                     f"{r['base_width']:.3f} -> {r['new_width']:.3f} | {r['base_obstacle']}, "
                     f"{r['base_self']} | {r['new_obstacle']}, {r['new_self']} | {r['new_certified']} |")
    tb, tn = sum(r["base_ms"] for r in rows), sum(r["new_ms"] for r in rows)
    mb = statistics.mean(r["base_ratio"] for r in rows)
    mn = statistics.mean(r["new_ratio"] for r in rows)
    lines.append(f"| **total / mean** | **{tb:.0f} -> {tn:.0f}** ({tn / tb:.2f}x) | "
                 f"{sum(r['base_leaves'] for r in rows):,} -> {sum(r['new_leaves'] for r in rows):,} | "
                 f"**{mb:.4f} -> {mn:.4f}** ({100 * (mn / mb - 1):+.1f} %) | "
                 f"{statistics.mean(r['base_width'] for r in rows):.3f} -> "
                 f"{statistics.mean(r['new_width'] for r in rows):.3f} | "
                 f"{sum(r['base_obstacle'] for r in rows)}, {sum(r['base_self'] for r in rows)} | "
                 f"{sum(r['new_obstacle'] for r in rows)}, {sum(r['new_self'] for r in rows)} | |")
    lines.append("")
    lines.append(f"Samples per path: {rows[0]['samples']:,} (30 windows, seed 1). Command: "
                 f"`tools/self_collision_compare.py --base BASE/build/leeway --samples {a.samples} --repeats {a.repeats}`.")
    text = "\n".join(head + lines) + "\n"
    print(text)
    if a.out:
        pathlib.Path(a.out).write_text(text)


if __name__ == "__main__":
    main()
