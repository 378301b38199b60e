#!/usr/bin/env python3
"""Regenerates docs/results.md: the nine thesis sweeps (tables 4.1-4.9) on leeway's rebuilt cells,
beside the thesis's published figures (docs/data/thesis_tables.csv). Standard library only.

Usage: tools/make_results.py [--leeway build/leeway] [--samples 10000] [--out docs/results.md]
                             [--render-only]
The sweeps' CSV files are kept in docs/data/results/ (with the machine line); --render-only
rebuilds docs/results.md from them without running anything.
Runs `leeway sweep` for every (cell, path) in two configurations: the thesis's parameters
(section 4.1, with each cell's own reach radius and the DLR obstacle-box option) and the same with
volume.trail_margin = 0.1 m. Takes several minutes on 2 cores.
"""
import argparse
import csv
import datetime
import json
import os
import pathlib
import platform
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
PATHS = [("dallara", "home", "patch", "4.1"), ("dallara", "patch", "mould", "4.2"), ("dallara", "mould", "home", "4.3"),
         ("baltico", "home", "patch", "4.4"), ("baltico", "patch", "mould", "4.5"), ("baltico", "mould", "home", "4.6"),
         ("dlr", "home", "patch", "4.7"), ("dlr", "patch", "mould", "4.8"), ("dlr", "mould", "home", "4.9")]
CONFIGS = [("thesis", {}), ("margin", {"volume": {"trail_margin": 0.1}})]


def thesis_rows():
    rows = {}
    with open(ROOT / "docs" / "data" / "thesis_tables.csv") as f:
        lines = [line for line in f if not line.startswith("#")]
    for r in csv.DictReader(lines):
        rows[(r["cell"], r["path"], int(r["max_cells"]))] = r
    return rows


DATA = ROOT / "docs" / "data" / "results"


def read_csv(path):
    with open(path) as f:
        return {int(r["max_cells"]): r for r in csv.DictReader(f)}


def sweep(leeway, cell, src, dst, name, params, samples, tmp):
    pfile = pathlib.Path(tmp) / "params.json"
    pfile.write_text(json.dumps(params))
    out = DATA / f"{cell}-{src}-{dst}-{name}.csv"
    cmd = [leeway, "sweep", str(ROOT / "mjcf" / "workcells" / f"{cell}.xml"), "--from", src, "--to", dst,
           "--samples", str(samples), "--csv", str(out), "--params", str(pfile)]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return read_csv(out)


def machine():
    model = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip() or "unknown"
    return f"{model}, {os.cpu_count()} logical cores, {platform.system()} {platform.release()}; leeway commit {commit}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--leeway", default=str(ROOT / "build" / "leeway"))
    ap.add_argument("--samples", type=int, default=10000)
    ap.add_argument("--out", default=str(ROOT / "docs" / "results.md"))
    ap.add_argument("--render-only", action="store_true")
    args = ap.parse_args()
    thesis = thesis_rows()
    results = {}
    DATA.mkdir(parents=True, exist_ok=True)
    if args.render_only:
        run_info = json.loads((DATA / "run.json").read_text())
        for cell, src, dst, table in PATHS:
            for name, _ in CONFIGS:
                results[(cell, src, dst, name)] = read_csv(DATA / f"{cell}-{src}-{dst}-{name}.csv")
    else:
        run_info = {"date": datetime.date.today().isoformat(), "machine": machine(), "samples": args.samples,
                    "load_before": round(os.getloadavg()[0], 2)}
        with tempfile.TemporaryDirectory() as tmp:
            for cell, src, dst, table in PATHS:
                for name, params in CONFIGS:
                    print(f"{cell} {src}-{dst} {name}", file=sys.stderr, flush=True)
                    results[(cell, src, dst, name)] = sweep(args.leeway, cell, src, dst, name, params,
                                                            args.samples, tmp)
        # Stage benchmark on the Dallara paths (one thread, medians of 5 runs).
        bench = str(pathlib.Path(args.leeway).parent / "leeway-bench-stages")
        for src, dst in (("home", "patch"), ("patch", "mould"), ("mould", "home")):
            print(f"bench dallara {src}-{dst}", file=sys.stderr, flush=True)
            out = subprocess.run([bench, "--cell", "dallara", "--from", src, "--to", dst, "--repeats", "5",
                                  "--cells", "100,1000,5000,10000,20000,25000,50000,100000"],
                                 check=True, capture_output=True, text=True).stdout
            (DATA / f"bench-dallara-{src}-{dst}.md").write_text(out)
        run_info["load_after"] = round(os.getloadavg()[0], 2)
        (DATA / "run.json").write_text(json.dumps(run_info, indent=2) + "\n")

    o = []
    o.append("# Results: the thesis's sweeps on leeway's cells\n")
    o.append("Generated by `tools/make_results.py` (do not edit by hand) on "
             f"{run_info['date']}: {run_info['machine']}. Every row is one `leeway sweep` run: "
             f"volume, bounds at both waypoints with 2 threads, then the Confidence Factor with 30 windows x "
             f"{run_info['samples']} samples (seed 1). The raw CSV files are in `docs/data/results/`. "
             f"The machine is shared: its 1-minute load average was {run_info.get('load_before', '?')} when "
             f"the run started and {run_info.get('load_after', '?')} when it ended, so times are indicative; "
             "compare within a table, and against the thesis as ratios. Times in milliseconds, CF in percent; the thesis ran on an "
             "Intel i5-8250U (section 4.1). Two configurations: **thesis** = section 4.1's parameters (each "
             "cell's reach radius; DLR adds the obstacles' boxes to the volume), **margin** = the same with "
             "`volume.trail_margin` = 0.1 m (docs/algorithm.md). *collapsed* counts the bisected intervals "
             "(j1-j3 at 2 waypoints) that shrank to the nominal value and were widened by the guard; *width* is "
             "the mean width of the j1-j3 intervals in radians.\n")
    o.append("Our cells are rebuilt from the thesis's text (docs/workcells.md), not its CAD models, and our "
             "height-map covers the reach circle's bounding square, so the box count at a given MAX_cells "
             "differs from the thesis's; compare rows by box count as well as by MAX_cells.\n")
    # Headline: the thesis's abstract, Dallara home-patch, MAX_cells 25000.
    t = thesis[("dallara", "home-patch", 25000)]
    o.append("## Headline: Dallara home-patch at MAX_cells 25,000 (the thesis's abstract)\n")
    o.append("| | boxes | time [ms] | CF [%] | collapsed | width [rad] |")
    o.append("|---|---:|---:|---:|---:|---:|")
    o.append(f"| thesis (i5-8250U) | {t['boxes']} | {t['time_ms']} | {t['cf_percent']} | - | - |")
    for name, _ in CONFIGS:
        r = results[("dallara", "home", "patch", name)][25000]
        o.append(f"| leeway, {name} | {r['boxes']} | {float(r['time_ms']):.0f} | {100 * float(r['cf']):.4f} | "
                 f"{r['collapsed']}/6 | {float(r['mean_width']):.3f} |")
    o.append("")
    for cell, src, dst, table in PATHS:
        o.append(f"## {cell.capitalize() if cell != 'dlr' else 'DLR'} {src}-{dst} (thesis table {table})\n")
        o.append("| Max CBox | thesis CBox | thesis ms | thesis CF | CBox | ms | CF | 95 % CI | worst window | "
                 "collapsed | width | margin: CBox | ms | CF | worst window | collapsed | width |")
        o.append("|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for mc, r in sorted(results[(cell, src, dst, "thesis")].items()):
            th = thesis.get((cell, f"{src}-{dst}", mc), {})
            m = results[(cell, src, dst, "margin")][mc]
            o.append(f"| {mc} | {th.get('boxes', '-')} | {th.get('time_ms', '-')} | {th.get('cf_percent', '-')} | "
                     f"{r['boxes']} | {float(r['time_ms']):.0f} | {100 * float(r['cf']):.3f} | "
                     f"{100 * float(r['ci_low']):.3f} .. {100 * float(r['ci_high']):.3f} | "
                     f"{100 * float(r['worst_window_cf']):.1f} | {r['collapsed']} | {float(r['mean_width']):.3f} | "
                     f"{m['boxes']} | {float(m['time_ms']):.0f} | {100 * float(m['cf']):.3f} | "
                     f"{100 * float(m['worst_window_cf']):.1f} | {m['collapsed']} | {float(m['mean_width']):.3f} |")
        o.append("")
    o.append("## Where the time goes (benchmark)\n")
    o.append("`build/leeway-bench-stages --cell dallara --from A --to B --repeats 5` (one thread, medians; "
             "*us/check* = bounds time per collision check; *kinematics* = the robot's forward kinematics "
             "on the small model; *mj_collision* = the rest of a check: copying the robot's poses and "
             "MuJoCo's collision pass over the pool):\n")
    for src, dst in (("home", "patch"), ("patch", "mould"), ("mould", "home")):
        f = DATA / f"bench-dallara-{src}-{dst}.md"
        if f.exists():
            o.append(f.read_text())
    analysis = ROOT / "docs" / "results-analysis.md"
    if analysis.exists():
        o.append(analysis.read_text())
    pathlib.Path(args.out).write_text("\n".join(o) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
