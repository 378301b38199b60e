#!/usr/bin/env python3
"""Measures the closed loop (`leeway simulate`: a simulated co-worker pushes the tool, the controller
keeps the robot inside the bounds) on the nine thesis paths and on the cells no parameter was tuned
on, and writes docs/data/simulate/results.json and docs/data/simulate/section.md (the "Closed loop"
section of docs/results.md). Standard library only.

Usage: tools/make_simulate_results.py [--leeway build/leeway] [--seeds 10] [--jobs 2]
                                      [--paths cell/from/to,...] [--render-only]
Per path, two bounds files: the default (`leeway bounds`: the leeway preset, certified) and
`--preset thesis` (section 4.1's method, no safety stage). On each, `leeway simulate --json` with
`--human random --seed S` for S = 1..--seeds and once with `--human push-toward nearest` (a
deterministic push: the seed changes nothing). Exit 0 = no contact and never left the bounds,
1 = a contact or left the bounds (both are results), 2/3 = an error (recorded). The simulations run
--jobs at a time.
"""
import argparse
import concurrent.futures
import datetime
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import threading
import time

from machine_info import machine

ROOT = pathlib.Path(__file__).resolve().parent.parent
DATA = ROOT / "docs" / "data" / "simulate"
SAFETY = ROOT / "docs" / "data" / "safety" / "results.json"
THESIS_PATHS = [("dallara", "home", "patch"), ("dallara", "patch", "mould"), ("dallara", "mould", "home"),
                ("baltico", "home", "patch"), ("baltico", "patch", "mould"), ("baltico", "mould", "home"),
                ("dlr", "home", "patch"), ("dlr", "patch", "mould"), ("dlr", "mould", "home")]
# Cells built for judging features on layouts nothing was tuned on (docs/workcells.md).
NEW_PATHS = [("press_shop", "home", "pick"), ("press_shop", "pick", "place"), ("press_shop", "place", "home"),
             ("rail_hall", "home", "patch"), ("rail_hall", "patch", "mould"), ("rail_hall", "mould", "home"),
             ("shelf_bay", "home", "pick"), ("shelf_bay", "pick", "place"), ("shelf_bay", "place", "home"),
             ("wide_elbow", "home", "pick"), ("wide_elbow", "pick", "place"), ("wide_elbow", "place", "home"),
             ("low_beam", "home", "pick"), ("low_beam", "pick", "place"), ("low_beam", "place", "home")]
BOUNDS = [("default", []), ("thesis", ["--preset", "thesis"])]
# The numbers kept from each run's report (the rest of it, e.g. the controller's settings, is the same
# for every run).
KEYS = ["contacts", "first_contact", "min_distance", "left_bounds", "max_excursion", "freedom_used",
        "max_deviation", "max_tracking_error", "simulated_time", "wall_time", "reached_end", "end_time",
        "nominal_duration", "limit_periods", "clamp_steps", "steps", "joints"]


def rel(path):
    """path relative to the repository when it is inside it (for reproducible command lines)."""
    try:
        return str(pathlib.Path(path).resolve().relative_to(ROOT))
    except ValueError:
        return str(path)


def make_bounds(leeway, cell, src, dst, extra, out):
    """Writes one bounds file; returns its summary, or {"error": ...}."""
    xml = ROOT / "mjcf" / "workcells" / f"{cell}.xml"
    args = ["bounds", rel(xml), "--from", src, "--to", dst] + extra + ["--out"]
    cmd = [leeway] + args + [str(out)]
    shown = " ".join([rel(leeway)] + args + [out.name])
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        return {"command": shown, "error": f"exit {r.returncode}: {(r.stderr or r.stdout).strip()}"}
    b = json.loads(out.read_text())
    return {
        "command": shown,
        "boxes": b.get("boxes"),
        "waypoints": len(b["waypoints"]),
        "planned": b.get("nominal_path", {}).get("planned", False),
        "certified": b.get("safety", {}).get("certified"),
        "ms_total": b.get("timing_ms", {}).get("total"),
        "note": next((line for line in r.stdout.splitlines() if "hits" in line), ""),
    }


def simulate(leeway, cell, bounds_file, human, seed):
    """One `leeway simulate --json` run; returns the kept numbers, or {"error": ...}."""
    xml = ROOT / "mjcf" / "workcells" / f"{cell}.xml"
    tail = ["--human"] + human.split() + (["--seed", str(seed)] if seed is not None else []) + ["--json"]
    cmd = [leeway, "simulate", rel(xml), "--bounds", str(bounds_file)] + tail
    shown = " ".join([rel(leeway), "simulate", rel(xml), "--bounds", bounds_file.name] + tail)
    run = {"human": human, "seed": seed, "command": shown}
    code, stdout, stderr, cpu = run_timed(cmd)
    run["exit"] = code
    if code not in (0, 1):
        run["error"] = f"exit {code}: {(stderr or stdout).strip()}"
        return run
    try:
        report = json.loads(stdout)
    except json.JSONDecodeError as e:
        run["error"] = f"exit {code}, no JSON on stdout ({e}): {stderr.strip()}"
        return run
    run.update({k: report.get(k) for k in KEYS})
    run["cpu_time"] = cpu
    return run


def run_timed(cmd, timeout=1800):
    """Runs cmd in the repository; returns (exit code, stdout, stderr, the process's user + system CPU
    time [s]). The CPU time comes from the process's own rusage (os.wait4), so it holds with several
    runs at a time, and it is less sensitive than the wall time to other load on the machine."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        p = subprocess.Popen(cmd, cwd=ROOT, stdout=out, stderr=err, text=True)
        timer = threading.Timer(timeout, p.kill)
        timer.start()
        try:
            _, status, usage = os.wait4(p.pid, 0)
        finally:
            timer.cancel()
        p.returncode = code = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return code, out.read(), err.read(), usage.ru_utime + usage.ru_stime


def ok(runs):
    return [r for r in runs if "error" not in r]


def had_contact(r):
    return r["contacts"] > 0 or r["first_contact"] is not None


def rtf(r):
    return r["simulated_time"] / r["wall_time"] if r["wall_time"] > 0 else float("inf")


def cpu_factor(r):
    """Simulated time over the process's CPU time (which includes loading the cell and the bounds)."""
    return r["simulated_time"] / r["cpu_time"] if r.get("cpu_time") else float("inf")


def contact_cell(runs, n):
    """'k' (runs with contact), with the errors said."""
    good = ok(runs)
    text = str(sum(1 for r in good if had_contact(r)))
    if len(good) != n:
        text += f" ({n - len(good)} errors)"
    return text


def first_contact(runs):
    """The geoms of the first run (seeds in order, then the push) that had a contact."""
    for r in ok(runs):
        if had_contact(r) and r["first_contact"]:
            c = r["first_contact"]
            which = f"seed {r['seed']}" if r["human"] == "random" else "push"
            return f"{c['geom1']} - {c['geom2']}{' (self)' if c.get('self') else ''}, {which}"
    return "-"


def min_distance(runs):
    good = ok(runs)
    if not good:
        return "-"
    measured = [r["min_distance"]["value"] for r in good if not r["min_distance"]["capped"]]
    if not measured:
        return f">= {good[0]['min_distance']['value']:.3f}"
    return f"{min(measured):.4f}"


def render(info, results):
    n = info["seeds"] + 1
    o = ["## Closed loop: a simulated co-worker pushing inside the bounds\n",
         f"Generated by `tools/make_simulate_results.py` on {info['date']}: {info['machine']}; "
         f"1-minute load average {info['load_before']} before, {info['load_after']} after (times are "
         f"indicative; {info['jobs']} simulations at a time). Per path, two bounds files: the default "
         "(`leeway bounds`, the leeway preset with certified safety) and `--preset thesis` (section 4.1's "
         "method, no safety stage); straight paths that hit an obstacle are planned around, as `leeway "
         f"bounds` does by itself. On each, `leeway simulate` {n} times: {info['seeds']} runs with "
         f"`--human random --seed 1..{info['seeds']}` (a smooth random force on the tool, 60 N standard "
         "deviation per component, corner frequency 0.5 Hz) and one with `--human push-toward nearest` "
         "(60 N toward the obstacle nearest the tool, ramped up over 0.5 s: the adversarial push; it is "
         "deterministic, so it runs once, not per seed), with the default MPC controller. A *contact* is "
         "a MuJoCo contact with dist < 0 between a robot geom and the cell, or between two robot geoms of "
         "a counted self pair; *left bounds* = the configuration was outside the box at its path "
         "parameter (up to the first contact). *min distance* = the smallest robot-cell or counted "
         "robot-robot distance over the runs [m] (0 at a contact; measured up to 0.5 m). *freedom used* = "
         "per joint, the largest share of the room between the nominal and the bound (on the side the "
         "joint moved to) the robot used, in [0, 1]: *mean* over the joints and the random runs, *max* "
         "the largest joint's over all runs. *real-time factor* = simulated time over wall time, the "
         "median over all runs of the path (both bounds files). Raw numbers and the command of every "
         "run: `docs/data/simulate/results.json`.\n",
         f"| path | default: runs with contact (of {n}) | min distance [m] | left bounds (runs) | "
         "mean freedom used | max freedom used | "
         f"thesis: runs with contact (of {n}) | first contact | real-time factor |",
         "|---|---:|---:|---:|---:|---:|---:|---|---:|"]
    groups = [("The nine thesis paths", THESIS_PATHS), ("Cells nothing was tuned on", NEW_PATHS)]
    for title, paths in groups:
        rows = [p for p in paths if "/".join(p) in results]
        if not rows:
            continue
        o.append(f"| **{title}** | | | | | | | | |")
        for cell, src, dst in rows:
            r = results["/".join((cell, src, dst))]
            d, t = r["default"], r["thesis"]
            planned = d.get("bounds", {}).get("planned")
            name = f"{cell} {src}-{dst}" + (f" (planned, {d['bounds']['waypoints']} waypoints)" if planned else "")
            cells = []
            if "error" in d.get("bounds", {}):
                cells += ["bounds failed", "-", "-", "-", "-"]
            else:
                good = ok(d["runs"])
                rnd = [x for x in good if x["human"] == "random"]
                mean_free = (statistics.mean(v for x in rnd for v in x["freedom_used"]) if rnd else float("nan"))
                max_free = max((v for x in good for v in x["freedom_used"]), default=float("nan"))
                cells += [contact_cell(d["runs"], n), min_distance(d["runs"]),
                          str(sum(1 for x in good if x["left_bounds"])), f"{mean_free:.2f}", f"{max_free:.2f}"]
            if "error" in t.get("bounds", {}):
                cells += ["bounds failed", "-"]
            else:
                cells += [contact_cell(t["runs"], n), first_contact(t["runs"])]
            factors = [rtf(x) for x in ok(d.get("runs", []) + t.get("runs", []))]
            cells.append(f"{statistics.median(factors):.0f}x" if factors else "-")
            o.append(f"| {name} | " + " | ".join(cells) + " |")
    o.append("")

    # Summary against the targets, computed from the rows above.
    keys = [k for k in ("/".join(p) for p in THESIS_PATHS + NEW_PATHS) if k in results]
    every = [x for k in keys for b in ("default", "thesis") for x in results[k][b].get("runs", [])]
    default_runs = [x for k in keys for x in ok(results[k]["default"].get("runs", []))]
    touched = [x for x in default_runs if had_contact(x)]
    left = sum(1 for x in default_runs if x["left_bounds"])
    touched_paths = sorted({k for k in keys for x in ok(results[k]["default"].get("runs", [])) if had_contact(x)})
    line = (f"- Default bounds: {len(touched)} of {len(default_runs)} runs had a contact (target: 0), "
            f"{sum(x['contacts'] for x in default_runs)} steps with contact in all; {left} runs left the bounds")
    if touched_paths:
        line += "; contacts on " + ", ".join(
            f"{k.replace('/', ' ')} ({first_contact(results[k]['default']['runs'])})" for k in touched_paths)
    outside = []
    for k in keys:
        runs = [x for x in ok(results[k]["default"].get("runs", [])) if x["left_bounds"]]
        if runs:
            worst = max(x["max_excursion"] for x in runs)
            outside.append(f"{k.replace('/', ' ')} ({len(runs)} run{'s' if len(runs) > 1 else ''}, max excursion "
                           + (f"{worst:.4f}" if worst >= 1e-4 else f"{worst:.1e}") + " rad or m)")
    if outside:
        line += "; left the bounds on " + ", ".join(outside)
    o.append(line + ".")
    safety = info.get("safety_cf", {})
    low = [k for k in keys if k in safety and safety[k] < 1.0]
    parts = []
    for k in low:
        t = results[k]["thesis"]
        if "error" in t.get("bounds", {}):
            parts.append(f"{k.replace('/', ' ')} (CF {100 * safety[k]:.4f} %): bounds failed")
            continue
        c = sum(1 for x in ok(t["runs"]) if had_contact(x))
        parts.append(f"{k.replace('/', ' ')} (CF {100 * safety[k]:.4f} %): "
                     + (f"contact in {c} of {len(ok(t['runs']))} runs" if c else "no contact"))
    found = sum(1 for k in low if any(had_contact(x) for x in ok(results[k]["thesis"].get("runs", []))))
    o.append(f"- Thesis-preset bounds: the simulation found a contact on {found} of the {len(low)} paths whose "
             "thesis CF (`docs/data/safety/results.json`) is < 100 %" + (": " + "; ".join(parts) if parts else "")
             + ".")
    full = [k for k in keys if k in safety and safety[k] >= 1.0
            and any(had_contact(x) for x in ok(results[k]["thesis"].get("runs", [])))]
    if full:
        o.append("- Thesis-preset bounds with CF 100 % that still got a contact in the simulation: "
                 + ", ".join(k.replace("/", " ") for k in full) + ".")
    factors = [rtf(x) for x in ok(every)]
    cpu = [cpu_factor(x) for x in ok(every) if x.get("cpu_time")]
    if factors:
        o.append(f"- Real-time factor over all {len(factors)} runs: median {statistics.median(factors):.0f}x, "
                 f"minimum {min(factors):.0f}x (target: >= 10x)"
                 + (f"; over the process's CPU time (user + system, including loading the cell and "
                    f"the bounds; less sensitive to other load) median {statistics.median(cpu):.0f}x, minimum "
                    f"{min(cpu):.0f}x" if cpu else "") + ".")
    errors = [x for x in every if "error" in x]
    failed = [k for k in keys for b in ("default", "thesis") if "error" in results[k][b].get("bounds", {})]
    if errors or failed:
        o.append(f"- Errors: {len(errors)} simulation runs"
                 + (", `leeway bounds` failed on " + ", ".join(f"{k.replace('/', ' ')} ({b})" for k, b in
                                                          ((k, b) for k in keys for b in ("default", "thesis")
                                                           if "error" in results[k][b].get("bounds", {})))
                    if failed else "") + " (see results.json).")
    o.append("")
    notes = [f"- {k.replace('/', ' ')}: {results[k]['default']['bounds']['note']}" for k in keys
             if results[k]["default"].get("bounds", {}).get("note")]
    if notes:
        o.append("Straight keyframe paths that hit an obstacle were planned around (`leeway bounds` says so):\n")
        o.extend(notes)
        o.append("")
    return "\n".join(o) + "\n"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--leeway", default=str(ROOT / "build" / "leeway"))
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--paths", default="", help="cell/from/to,... (default: all)")
    ap.add_argument("--render-only", action="store_true")
    args = ap.parse_args()
    if pathlib.Path(args.leeway).exists():
        args.leeway = str(pathlib.Path(args.leeway).resolve())
    DATA.mkdir(parents=True, exist_ok=True)
    if args.render_only:
        saved = json.loads((DATA / "results.json").read_text())
        info, results = saved["run"], saved["results"]
    else:
        paths = THESIS_PATHS + NEW_PATHS
        if args.paths:
            wanted = [tuple(p.split("/")) for p in args.paths.split(",") if p]
            paths = [p for p in wanted if p in paths] + [p for p in wanted if p not in paths]
        paths = [p for p in paths if (ROOT / "mjcf" / "workcells" / f"{p[0]}.xml").exists()]
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True).stdout.strip() or "unknown"
        safety = json.loads(SAFETY.read_text())["results"] if SAFETY.exists() else {}
        info = {"date": datetime.date.today().isoformat(), "machine": machine(), "commit": commit,
                "leeway": rel(args.leeway), "seeds": args.seeds, "jobs": args.jobs,
                "humans": ["random (per seed)", "push-toward nearest (once)"],
                "safety_cf": {k: v["thesis"]["cf"] for k, v in safety.items() if "thesis" in v},
                "load_before": round(os.getloadavg()[0], 2)}
        start = time.monotonic()
        results = {}
        with tempfile.TemporaryDirectory() as tmp:
            # The bounds files one after another (leeway bounds uses its own worker threads).
            jobs = []
            for cell, src, dst in paths:
                key = "/".join((cell, src, dst))
                results[key] = {}
                for name, extra in BOUNDS:
                    print(f"{key} bounds {name}", file=sys.stderr, flush=True)
                    out = pathlib.Path(tmp) / f"{cell}_{src}_{dst}_{name}.json"
                    b = make_bounds(args.leeway, cell, src, dst, extra, out)
                    results[key][name] = {"bounds": b, "runs": []}
                    if "error" in b:
                        print(f"  {b['error']}", file=sys.stderr, flush=True)
                        continue
                    for seed in range(1, args.seeds + 1):
                        jobs.append((key, name, cell, out, "random", seed))
                    jobs.append((key, name, cell, out, "push-toward nearest", None))
            # The simulations, --jobs at a time.
            with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
                futures = {pool.submit(simulate, args.leeway, cell, out, human, seed): (key, name)
                           for key, name, cell, out, human, seed in jobs}
                for i, f in enumerate(concurrent.futures.as_completed(futures), 1):
                    key, name = futures[f]
                    r = f.result()
                    results[key][name]["runs"].append(r)
                    state = r.get("error") or (f"{r['contacts']} contact steps" if had_contact(r) else "clean")
                    print(f"[{i}/{len(jobs)}] {key} {name} {r['human']} seed {r['seed']}: {state}",
                          file=sys.stderr, flush=True)
        # Runs in a fixed order: seeds ascending, then the push.
        for key in results:
            for name in results[key]:
                results[key][name]["runs"].sort(key=lambda r: (r["human"] != "random", r["seed"] or 0))
        info["load_after"] = round(os.getloadavg()[0], 2)
        info["duration_s"] = round(time.monotonic() - start, 1)
        (DATA / "results.json").write_text(json.dumps({"run": info, "results": results}, indent=2) + "\n")
    (DATA / "section.md").write_text(render(info, results))


if __name__ == "__main__":
    main()
