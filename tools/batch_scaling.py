#!/usr/bin/env python3
"""The scaling of `leeway batch` from 1 to 2 MPI ranks, for docs/batch.md.

Runs the suite (default suites/thesis.json) alternately on one process and under
`mpirun -np 2`, both with one thread per scenario, REPEATS times each; prints the wall times
and CPU times (median), their ratio, the cores the run kept busy, the load averages before and after each run (the machine may be shared),
the per-scenario times of the single-process runs and the makespan those times project for 1 to 8
ranks under leeway's dynamic assignment (each scenario, in suite order, to the first free rank).
Writes docs/data/batch_scaling.json. Standard library only.

  tools/batch_scaling.py [--build build] [--suite suites/thesis.json] [--repeats 3]
"""
import argparse
import heapq
import json
import os
import pathlib
import shutil
import statistics
import subprocess
import tempfile
import time

from machine_info import cpu_of_children, machine

ROOT = pathlib.Path(__file__).resolve().parent.parent


def run(cmd):
    load_before = os.getloadavg()
    cpu0 = cpu_of_children()
    t0 = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - t0
    if p.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stdout}{p.stderr}")
    return wall, cpu_of_children() - cpu0, load_before, os.getloadavg()


def makespan(times, ranks):
    """Dynamic assignment in suite order: each scenario goes to the rank that frees up first."""
    free = [0.0] * ranks
    for t in times:
        heapq.heapreplace(free, free[0] + t)
    return max(free)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=str(ROOT / "build"))
    ap.add_argument("--suite", default=str(ROOT / "suites" / "thesis.json"))
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    leeway = str(pathlib.Path(a.build) / "leeway")
    mpirun = shutil.which("mpirun")
    if not mpirun:
        raise SystemExit("no mpirun: install openmpi-bin (scripts/setup.sh)")
    mpi = [mpirun, "--oversubscribe", "-np", "2"] + (["--allow-run-as-root"] if os.getuid() == 0 else [])
    rows = {"1 process": [], "2 ranks": []}
    per_scenario = []
    with tempfile.TemporaryDirectory() as tmp:
        out = str(pathlib.Path(tmp) / "r.json")
        for r in range(a.repeats):
            for label, prefix in (("1 process", []), ("2 ranks", mpi)):
                wall, cpu, before, after = run(prefix + [leeway, "batch", a.suite, "--threads", "1", "--out", out])
                rows[label].append({"wall_s": wall, "cpu_s": cpu, "load_before": before, "load_after": after})
                if label == "1 process":
                    res = json.load(open(out))
                    per_scenario.append([s["timing"]["seconds"] for s in res["scenarios"]])
                print(f"run {r + 1} {label}: {wall:.2f} s wall, {cpu:.2f} s CPU (load averages {before[0]:.2f} {before[1]:.2f} "
                      f"{before[2]:.2f} before, {after[0]:.2f} {after[1]:.2f} {after[2]:.2f} after)", flush=True)
    one = statistics.median(x["wall_s"] for x in rows["1 process"])
    two = statistics.median(x["wall_s"] for x in rows["2 ranks"])
    times = [statistics.median(col) for col in zip(*per_scenario)]
    projected = {p: makespan(times, p) for p in range(1, 9)}
    print(f"median wall time: 1 process {one:.2f} s, 2 ranks {two:.2f} s, ratio {two / one:.3f} (target <= 0.6)")
    for label, rs in rows.items():
        cpu = statistics.median(x["cpu_s"] for x in rs)
        wall = statistics.median(x["wall_s"] for x in rs)
        print(f"{label}: median CPU time {cpu:.2f} s, {cpu / wall:.2f} cores busy on average")
    print("per-scenario times [s]: " + ", ".join(f"{t:.2f}" for t in times))
    print("projected makespan [s] (ratio to 1 rank): " +
          ", ".join(f"{p} ranks {m:.2f} ({m / projected[1]:.2f})" for p, m in projected.items()))
    def shown(v):
        try:
            return str(pathlib.Path(v).resolve().relative_to(ROOT))
        except (ValueError, TypeError):
            return str(v)

    data = {"command": "tools/batch_scaling.py " + " ".join(f"--{k} {shown(v)}" for k, v in vars(a).items()),
            "machine": machine(), "cores": os.cpu_count(), "runs": rows, "median_wall_s": {"1": one, "2": two},
            "ratio": two / one, "scenario_seconds": times,
            "projected_makespan_s": {str(p): m for p, m in projected.items()}}
    (ROOT / "docs" / "data").mkdir(exist_ok=True)
    (ROOT / "docs" / "data" / "batch_scaling.json").write_text(json.dumps(data, indent=2) + "\n")
    print("wrote docs/data/batch_scaling.json")


if __name__ == "__main__":
    main()
