#!/usr/bin/env python3
"""Scale benchmark: leeway on inputs far larger than the thesis's.

  1. `leeway bounds CELL --path P` on a joint-linear path file of N waypoints (default 1,000) at
     default settings (leeway preset, certified safety stage, all hardware threads); target <= 30 s;
     the result scored once by `leeway cf --self` (obstacle and self-collisions counted apart).
     The path runs between two keyframes of a bundled cell (--path-case CELL:FROM:TO; default: two
     thesis cells and two of the cells built for judging). The table gives the certified j1-j3
     width beside the time: a faster safety stage must not be a narrower one.
  2. `leeway check` on a cell with 20,000 extra obstacles (4 x 4 x 20 cm boxes at seeded random
     places over 8 x 8 m, overlaps included); target <= 5 s.

With --compare-runs, each path is also bounded once with `safety.runs` = false (every segment of
the dense path proven on its own, as before run boxes; docs/algorithm.md, "Run boxes"), and a
second table compares the two: wall and CPU time, leaves, and each joint's mean interval width.
With --compare-grow, each path is also bounded once with `--grow none` (the certified bounds
without growth by blocks; docs/algorithm.md, "Growing beyond the guide", step 8), and a table
compares the two: wall and CPU time, the growth's leaves, and the room (the mean kept share of each
joint's one-joint free range, leeway's room measure).

Every input is generated into a temporary folder (nothing is written to the repository); each case
runs --repeats times and the table gives the median wall time [s], the CPU time [s] and what the
run reported. Usage: python3 tools/scale_bench.py [--build build] [--repeats 3] [--waypoints 1000]
[--obstacles 20000] [--only bounds|check] [--path-case CELL:FROM:TO ...] [--compare-runs]
[--compare-grow]
"""
import argparse
import json
import os
import pathlib
import random
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from machine_info import cpu_of_children, machine  # noqa: E402
from make_safety_results import widths  # noqa: E402


def timed(cmd, ok=(0,)):
    c0, t0 = cpu_of_children(), time.monotonic()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall, cpu = time.monotonic() - t0, cpu_of_children() - c0
    if r.returncode not in ok:
        sys.exit(f"scale_bench: {' '.join(map(str, cmd))} exited {r.returncode}: {r.stderr.strip()[-400:]}")
    return wall, cpu, r.stdout


def ends(cell, a, b):
    """The joint names and the joint values of keyframes a and b, read by leeway itself."""
    r = subprocess.run([LEEWAY, "bounds", str(cell), "--from", a, "--to", b, "--safety", "none", "--json"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"scale_bench: leeway bounds {cell} --from {a} --to {b}: {r.stderr.strip()}")
    d = json.loads(r.stdout)
    return d["joints"], d["waypoints"][0]["q"], d["waypoints"][-1]["q"]


def path_file(folder, cell, joints, a, b, n):
    """A leeway-path-1 file: n waypoints evenly spaced on the joint-linear path from a to b."""
    waypoints = [{"q": [x + (y - x) * k / (n - 1) for x, y in zip(a, b)]} for k in range(n)]
    doc = {"format": "leeway-path-1", "cell": str(cell), "joints": joints, "units": {"q": "rad or m"},
           "waypoints": waypoints}
    p = folder / f"path_{n}.json"
    p.write_text(json.dumps(doc))
    return p


def crowded_cell(folder, base, count, seed):
    """The base cell with `count` extra 4 x 4 x 20 cm obstacle boxes over 8 x 8 m (seeded)."""
    text = base.read_text()
    rng = random.Random(seed)
    boxes = "".join(
        f'<geom name="crowd{k}" type="box" pos="{rng.uniform(-4, 4):.3f} {rng.uniform(-4, 4):.3f} 0.1" '
        f'size="0.02 0.02 0.1"/>\n' for k in range(count))
    at = text.rindex("</worldbody>")
    # Beside a copy of mjcf/, so that the cell's includes (../robots/...) resolve as in the repository.
    shutil.copytree(base.parent.parent, folder / "mjcf")
    p = folder / "mjcf" / "workcells" / f"crowded_{count}.xml"
    p.write_text(text[:at] + boxes + text[at:])
    return p


# Two thesis cells and two of the cells built for judging (docs/workcells.md).
DEFAULT_CASES = ["dallara:home:patch", "baltico:home:patch", "shelf_bay:pick:place", "rail_hall:home:patch"]


def main():
    global LEEWAY
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--waypoints", type=int, default=1000)
    ap.add_argument("--obstacles", type=int, default=20000)
    ap.add_argument("--only", choices=["bounds", "check"], help="run one of the two cases")
    ap.add_argument("--compare-runs", action="store_true",
                    help="also bound each path once with safety.runs = false and compare (a second table)")
    ap.add_argument("--compare-grow", action="store_true",
                    help="also bound each path once with --grow none and compare the room (a third table)")
    ap.add_argument("--out", help="also write the table as a docs section here (docs/data/perf/scale.md, "
                                  "which tools/make_results.py includes in docs/results.md)")
    ap.add_argument("--path-case", action="append", metavar="CELL:FROM:TO",
                    help="bundled cell and keyframes of a bounded path (repeatable; default: "
                         + ", ".join(DEFAULT_CASES) + ")")
    args = ap.parse_args()
    LEEWAY = str((ROOT / args.build / "leeway").resolve())
    rows = []
    compared = []  # (case, with runs: (wall, cpu, bounds json), without: (wall, cpu, bounds json))
    grown = []  # (case, default: (wall, cpu, bounds json), --grow none: (wall, cpu, bounds json))
    with tempfile.TemporaryDirectory() as tmp:
        folder = pathlib.Path(tmp)
        cases = args.path_case or DEFAULT_CASES
        off = folder / "runs_off.json"  # --compare-runs: the parameters without run boxes
        off.write_text(json.dumps({"safety": {"runs": False}}))
        paths = [] if args.only == "check" else [tuple(c.split(":")) for c in cases]
        for name, a, b in paths:
            cell = ROOT / "mjcf" / "workcells" / f"{name}.xml"
            joints, qa, qb = ends(cell, a, b)
            p = path_file(folder, cell, joints, qa, qb, args.waypoints)
            out = folder / "bounds.json"
            runs = [timed([LEEWAY, "bounds", str(cell), "--path", str(p), "--out", str(out)])
                    for _ in range(args.repeats)]
            d = json.loads(out.read_text())
            s = d["safety"]
            # The bisected joints' widths (j1-j3, whatever joints come before them, such as a rail).
            width, guide = widths(d)[0], widths(d, "guide_")[0]
            # Scored once, obstacles and self-collision apart (leeway cf --self: 30 x 10,000 samples).
            cf = json.loads(timed([LEEWAY, "cf", str(cell), str(out), "--self", "--json"])[2])
            room = d.get("room", {}).get("mean_share")
            note = (f"{len(d['waypoints'])} waypoints, {'certified' if s['certified'] else 'NOT certified'}, "
                    f"{s['leaves']} leaves ({s['grow']['leaves'] if s.get('grow') else 0} growing); "
                    + (f"room {100 * room:.1f} %; " if room is not None else "") +
                    f"mean j1-j3 width {width:.3f} rad, {100 * width / guide:.1f} % of "
                    f"the guide's; cf --self: {cf['obstacle_collisions']} obstacle and {cf['self_collisions']} "
                    f"self-collisions in {cf['samples']} samples")
            rows.append((f"bounds {name} {a}-{b} --path ({args.waypoints} waypoints)", runs, 30.0, note))
            # The same path once more with run boxes off, or growth off: (case, the default's medians
            # and bounds, the other run's wall, CPU and bounds).
            median = (statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs), d)
            for wanted, extra, table in ((args.compare_runs, ["--params", str(off)], compared),
                                         (args.compare_grow, ["--grow", "none"], grown)):
                if wanted:
                    out_other = folder / "bounds_other.json"
                    wall, cpu, _ = timed([LEEWAY, "bounds", str(cell), "--path", str(p), *extra,
                                          "--out", str(out_other)])
                    table.append((f"{name} {a}-{b}", median, (wall, cpu, json.loads(out_other.read_text()))))
        if args.only != "bounds":
            cell = crowded_cell(folder, ROOT / "mjcf" / "workcells" / "shelf_bay.xml", args.obstacles, 1)
            # Exit 1: check's findings (the random boxes overlap each other and the robot's reach).
            runs = [timed([LEEWAY, "check", str(cell), "--json"], ok=(0, 1)) for _ in range(args.repeats)]
            report = json.loads(runs[-1][2])
            rows.append((f"check shelf_bay + {args.obstacles} obstacles", runs, 5.0,
                         f"{report.get('overlap_count', len(report.get('overlaps', [])))} overlapping pairs "
                         f"counted, {len(report.get('overlaps', []))} listed"))
    lines = [f"Machine: {machine()}; load average {os.getloadavg()[0]:.2f} at the end; {args.repeats} runs "
             f"per case, median wall time [s].", "",
             "| case | wall median [s] | CPU median [s] | target [s] | met | reported |",
             "|---|---:|---:|---:|---|---|"]
    for name, runs, target, note in rows:
        wall = statistics.median(r[0] for r in runs)
        cpu = statistics.median(r[1] for r in runs)
        lines.append(f"| {name} | {wall:.2f} | {cpu:.2f} | {target:g} | {'yes' if wall <= target else 'NO'} | {note} |")
    if compared:
        lines += ["", "Run boxes against every segment proven on its own (`safety.runs` = false, one run each; "
                  "the times with run boxes are the medians above). *width* = each joint's mean interval "
                  "width over the waypoints with run boxes, as a share of its width without them [%].", "",
                  "| path | wall [s]: runs / without | CPU [s]: runs / without | leaves: runs / without | "
                  "segments proven by run boxes | width per joint [%] |",
                  "|---|---:|---:|---:|---:|---|"]
        def mean_width(doc, i):
            return statistics.mean(w["upper"][i] - w["lower"][i] for w in doc["waypoints"])

        for case, (wall, cpu, d), (wall_off, cpu_off, d_off) in compared:
            shares = []
            for i, name in enumerate(d["joints"]):
                base = mean_width(d_off, i)
                shares.append(f"{name} {100 * mean_width(d, i) / base:.1f}" if base > 0 else f"{name} -")
            shares = ", ".join(shares)
            s, s_off = d["safety"], d_off["safety"]
            lines.append(f"| {case} | {wall:.2f} / {wall_off:.2f} | {cpu:.2f} / {cpu_off:.2f} | "
                         f"{s['leaves']} / {s_off['leaves']} | {s['runs']['segments']} of {len(s['segments'])} | "
                         f"{shares} |")
    if grown:
        lines += ["", "Growth by blocks against none (`--grow none`, one run each; the default's times are the "
                  "medians above). *room* = the mean over the joints of each joint's kept share of its one-joint "
                  "free range, measured at 50 evenly spaced waypoints [%]; per joint: default / none [%].", "",
                  "| path | wall [s]: default / none | CPU [s]: default / none | leaves: default / none "
                  "(growing) | room [%]: default / none | per joint [%] |",
                  "|---|---:|---:|---:|---:|---|"]
        for case, (wall, cpu, d), (wall_none, cpu_none, d_none) in grown:
            s, s_none = d["safety"], d_none["safety"]
            share, share_none = d["room"]["joint_share"], d_none["room"]["joint_share"]
            joints = ", ".join(f"{j} {100 * share[j]:.1f} / {100 * share_none[j]:.1f}" for j in d["joints"])
            lines.append(f"| {case} | {wall:.2f} / {wall_none:.2f} | {cpu:.2f} / {cpu_none:.2f} | "
                         f"{s['leaves']} / {s_none['leaves']} ({s['grow']['leaves']}) | "
                         f"{100 * d['room']['mean_share']:.1f} / {100 * d_none['room']['mean_share']:.1f} | "
                         f"{joints} |")
    print("\n".join(lines))
    if args.out:
        section = ["## Scale (issue 14)", "",
                   f"`python3 tools/scale_bench.py {' '.join(sys.argv[1:])}`: a joint-linear path file of "
                   f"{args.waypoints} waypoints bounded at default settings (leeway preset, certified safety "
                   "stage, all hardware threads), and `leeway check` on shelf_bay with "
                   f"{args.obstacles} extra 4 x 4 x 20 cm obstacles (seeded random places over 8 x 8 m).", ""]
        pathlib.Path(args.out).write_text("\n".join(section + lines) + "\n\n")

if __name__ == "__main__":
    main()
