#!/usr/bin/env python3
"""Checks a change on cells nothing was tuned on: the Dallara cell with one extra obstacle near
the middle of its paths, written into a temporary folder (nothing is written to the repository).

  pillar  a 0.2 x 0.2 x 2.4 m column at (2.60, -1.20) m, 0.8 m outside the tool's arc from home
          to the patch at its middle (the tool passes (1.83, -1.05, 1.61) m there);
  beam    a 0.2 x 3.0 x 0.16 m beam at (1.60, -0.80, 2.95) m, above the upper arm and wrist
          between home and the patch.

Per cell and path (the three Dallara paths between keyframes): `leeway bounds --room on --json
--threads 1`, at the default (certified, grown) and with `--grow none`, then `leeway cf --self`
(30 windows x 10,000 samples, seed 1) on each bounds file. Prints one Markdown table: certified,
room (the mean kept share of each joint's one-joint free range [%]), the safety stage's time [s]
(one thread), the shrink steps of each segment, and the collisions found (obstacle + self).
Give another build's program with --leeway to compare two versions on the same machine.

Usage: python3 tools/obstacle_variants.py [--leeway build/leeway]
"""
import argparse
import json
import pathlib
import shutil
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
VARIANTS = {
    "pillar": '<geom name="pillar" type="box" pos="2.60 -1.20 1.20" size="0.10 0.10 1.20" '
              'contype="0" conaffinity="1"/>',
    "beam": '<geom name="beam" type="box" pos="1.60 -0.80 2.95" size="0.10 1.50 0.08" '
            'contype="0" conaffinity="1"/>',
}
PATHS = [("home", "patch"), ("patch", "mould"), ("mould", "home")]
ANCHOR = "<!-- Goals: the published"


def variant_cell(extra):
    text = (ROOT / "mjcf" / "workcells" / "dallara.xml").read_text()
    if ANCHOR not in text:
        sys.exit("obstacle_variants.py: mjcf/workcells/dallara.xml has no goals comment to insert at")
    return text.replace(ANCHOR, extra + "\n    " + ANCHOR, 1)


def run_json(cmd):
    out = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if out.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: exit {out.returncode}: {out.stderr.strip()}")
    return json.loads(out.stdout)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--leeway", default=str(ROOT / "build" / "leeway"))
    args = ap.parse_args()
    print("| cell | path | configuration | certified | room [%] | safety [s] | shrink steps | collisions / samples |")
    print("|---|---|---|---|---:|---:|---|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        # The cells include the robot as ../robots/...: the same layout as mjcf/.
        shutil.copytree(ROOT / "mjcf" / "robots", pathlib.Path(tmp) / "robots")
        (pathlib.Path(tmp) / "workcells").mkdir()
        for name, extra in VARIANTS.items():
            cell = pathlib.Path(tmp) / "workcells" / f"dallara_{name}.xml"
            cell.write_text(variant_cell(extra))
            for a, b in PATHS:
                for config, flags in (("default", []), ("--grow none", ["--grow", "none"])):
                    out = pathlib.Path(tmp) / f"{name}_{a}_{b}_{len(flags)}.json"
                    d = run_json([args.leeway, "bounds", str(cell), "--from", a, "--to", b, "--room", "on",
                                  "--json", "--threads", "1", "--out", str(out)] + flags)
                    k = run_json([args.leeway, "cf", str(cell), str(out), "--self", "--json", "--threads", "1"])
                    s = d["safety"]
                    shrinks = ", ".join(str(x["shrink_steps"]) for x in s["segments"])
                    hits = k["obstacle_collisions"] + k["self_collisions"]
                    print(f"| {name} | {a}-{b} | {config} | {'yes' if s['certified'] else 'no'} | "
                          f"{100 * d['room']['mean_share']:.1f} | {d['timing_ms']['safety'] / 1000:.2f} | "
                          f"{shrinks} | {hits} / {k['samples']:,} |", flush=True)


if __name__ == "__main__":
    main()
