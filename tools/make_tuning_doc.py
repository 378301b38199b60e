#!/usr/bin/env python3
"""Runs the tuning studies of docs/tuning.md with leeway-tune and writes their numbers into it.

Usage: tools/make_tuning_doc.py [--tune build/leeway-tune] [--only compare,noise,run,noise-local]
                                [--render-only]
                                [--run-seconds 1080] [--threads 2]

Phases (each writes docs/data/tuning/; --only picks some, --render-only runs none):
  compare  the algorithm comparison: every candidate on 3 cases (one path of each cell), the same
           budget of evaluations, the same objective and seeds (about 25 minutes on 2 cores)
  noise    the noise study: the start and random points on all nine paths, bounds repeated, CF at
           three seeds and at the summary's size (about 5 minutes)
  run      the real tuning run on all nine thesis paths (--run-seconds of search, then the summary)
  noise-local  the noise study again, on points around the run's tuned parameters (about 3 minutes)
Then docs/tuning.md is rewritten between its <!-- begin NAME --> / <!-- end NAME --> markers; the
prose outside them is left as it is. Standard library only.
"""
import argparse
import csv
import datetime
import itertools
import json
import os
import pathlib
import re
import statistics
import subprocess
import sys

from machine_info import machine

ROOT = pathlib.Path(__file__).resolve().parent.parent
DATA = ROOT / "docs" / "data" / "tuning"
DOC = ROOT / "docs" / "tuning.md"
CELLS = ROOT / "mjcf" / "workcells"
NINE = [f"{c}:{a}:{b}" for c in ("dallara", "baltico", "dlr")
        for a, b in (("home", "patch"), ("patch", "mould"), ("mould", "home"))]
COMPARE_CASES = ["dallara:home:patch", "baltico:patch:mould", "dlr:mould:home"]
COMPARE_BUDGET = 100
# (name, --algorithm, --seed): local methods from the thesis's start, global ones, and two-stage ones.
CANDIDATES = [
    ("cobyla", "cobyla", 1), ("bobyqa", "bobyqa", 1), ("neldermead", "neldermead", 1),
    ("sbplx", "sbplx", 1), ("direct", "direct", 1),
    ("isres-s1", "isres", 1), ("isres-s2", "isres", 2),
    ("crs2-s1", "crs2", 1), ("crs2-s2", "crs2", 2),
    ("direct+cobyla", "direct+cobyla", 1),
    ("isres+cobyla-s1", "isres+cobyla", 1), ("isres+cobyla-s2", "isres+cobyla", 2),
    ("crs2+cobyla-s1", "crs2+cobyla", 1), ("crs2+cobyla-s2", "crs2+cobyla", 2),
]
RUN_ALGORITHM = "direct+cobyla"
NOISE_POINTS = 20
NOISE_REPEATS = 5


def case_args(labels):
    out = []
    for label in labels:
        cell, a, b = label.split(":")
        out += ["--case", f"{CELLS.relative_to(ROOT) / cell}.xml:{a}:{b}"]
    return out


def rel(path):
    return os.path.relpath(path, ROOT)


def run(cmd, log_name):
    print(" ".join(cmd), file=sys.stderr, flush=True)
    with open(DATA / log_name, "w") as err:
        subprocess.run(cmd, check=True, cwd=ROOT, stdout=err, stderr=subprocess.STDOUT)


def stamp(name, extra=None):
    info = {"date": datetime.date.today().isoformat(), "machine": machine(),
            "load": [round(x, 2) for x in os.getloadavg()]}
    info.update(extra or {})
    (DATA / f"{name}-info.json").write_text(json.dumps(info, indent=2) + "\n")


def phase_compare(tune, threads):
    (DATA / "compare").mkdir(parents=True, exist_ok=True)
    for name, algorithm, seed in CANDIDATES:
        base = DATA / "compare" / name
        run([tune] + case_args(COMPARE_CASES) +
            ["--budget-evals", str(COMPARE_BUDGET), "--algorithm", algorithm, "--seed", str(seed),
             "--threads", str(threads), "--no-summary", "--log", rel(f"{base}.csv"), "--report",
             rel(f"{base}.json"), "--out", rel(f"{base}-tuned.json")], f"compare/{name}.out")
    stamp("compare")


def phase_noise(tune, threads):
    run([tune] + case_args(NINE) +
        ["--noise-study", str(NOISE_POINTS), "--repeats", str(NOISE_REPEATS), "--seed", "3", "--threads",
         str(threads), "--log", rel(DATA / "noise.csv"), "--report", rel(DATA / "noise.json")], "noise.out")
    stamp("noise")


def phase_noise_local(tune, threads):
    run([tune] + case_args(NINE) +
        ["--noise-study", str(NOISE_POINTS), "--noise-center", rel(DATA / "tuned.json"), "--repeats",
         str(NOISE_REPEATS), "--seed", "4", "--threads", str(threads), "--log", rel(DATA / "noise-local.csv"),
         "--report", rel(DATA / "noise-local.json")], "noise-local.out")
    stamp("noise-local")


def phase_run(tune, threads, seconds):
    run([tune] + case_args(NINE) +
        ["--budget-seconds", str(seconds), "--algorithm", RUN_ALGORITHM, "--threads", str(threads),
         "--recheck", "5", "--log", rel(DATA / "run.csv"), "--report", rel(DATA / "run.json"),
         "--out", rel(DATA / "tuned.json")], "run.out")
    stamp("run")


# ---------------------------------------------------------------- analysis


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def ranks(v):
    order = sorted(range(len(v)), key=lambda i: v[i])
    r = [0.0] * len(v)
    i = 0
    while i < len(order):
        j = i
        while j + 1 < len(order) and v[order[j + 1]] == v[order[i]]:
            j += 1
        for k in range(i, j + 1):
            r[order[k]] = (i + j) / 2
        i = j + 1
    return r


def spearman(a, b):
    ra, rb = ranks(a), ranks(b)
    ma, mb = statistics.fmean(ra), statistics.fmean(rb)
    sab = sum((x - ma) * (y - mb) for x, y in zip(ra, rb))
    saa = sum((x - ma) ** 2 for x in ra)
    sbb = sum((y - mb) ** 2 for y in rb)
    return sab / (saa * sbb) ** 0.5 if saa > 0 and sbb > 0 else 1.0


def concordance(a, b):
    """Share of pairs ordered the same way by a and b."""
    same = total = 0
    for i, j in itertools.combinations(range(len(a)), 2):
        if a[i] == a[j] or b[i] == b[j]:
            continue
        total += 1
        same += (a[i] > a[j]) == (b[i] > b[j])
    return same / total if total else 1.0


def fmt(x, d=3):
    return f"{x:.{d}f}"


def render_compare():
    out = []
    budget_marks = (25, 50, 100)
    out.append(f"Cases: {', '.join(COMPARE_CASES)}; budget {COMPARE_BUDGET} evaluations each; the objective "
               "and every other setting as in the real run (defaults, `--threads 2`). Best J so far after 25, "
               "50 and 100 evaluations and after 30 s of search (higher is better; *start J* is the thesis's "
               "parameters, evaluation 1), the evaluation that found the best, the search's wall time, and "
               "the best point's MAX_cells and trail margin.\n")
    out.append("| algorithm | seed | start J | best J @25 | @50 | @100 | @30 s | found at | wall [s] | MAX_cells | "
               "trail_margin [m] |")
    out.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    summary = {}
    for name, algorithm, seed in CANDIDATES:
        path = DATA / "compare" / f"{name}.csv"
        rep = DATA / "compare" / f"{name}.json"
        if not path.exists() or not rep.exists():
            continue
        r = rows(path)
        report = json.loads(rep.read_text())
        best = [float(x["best"]) for x in r]
        marks = [best[min(m, len(best)) - 1] for m in budget_marks]
        marks.append(max(float(x["best"]) for x in r if float(x["elapsed_s"]) <= 30 or x is r[0]))
        s = report["search"]
        bx = s["best_x"]
        summary.setdefault(algorithm, []).append(marks[2])
        out.append(f"| {algorithm} | {seed} | {fmt(float(r[0]['objective']))} | "
                   + " | ".join(fmt(m) for m in marks)
                   + f" | {s['best_evaluation']} | {s['seconds']:.0f} | {round(10 ** bx[9])} | {bx[10]:.3f} |")
    out.append("")
    if summary:
        out.append("Mean best J at 100 evaluations over the seeds run: "
                   + "; ".join(f"{a} {fmt(statistics.fmean(v))}" for a, v in
                               sorted(summary.items(), key=lambda kv: -statistics.fmean(kv[1])))
                   + ".\n")
    return "\n".join(out)


def noise_objectives(r, lam, mu):
    """Per (point, case) row: objective variants."""
    walls = [float(r[k]) for k in r if k.startswith("wall_ms_")]
    cpus = [float(r[k]) for k in r if k.startswith("cpu_ms_")]
    s = float(r["shortfall"])

    def j(cf, ms):
        return 100 * cf - lam * ms / 1000 - mu * s
    return {
        "search": j(float(r["cf_seed_a"]), float(r["cost_ms"])),  # proxy + CRN, 30 x 1000
        "seed_b": j(float(r["cf_seed_b"]), float(r["cost_ms"])),
        "seed_c": j(float(r["cf_seed_c"]), float(r["cost_ms"])),
        "reference_cpu": j(float(r["cf_final"]), statistics.median(cpus)),
        "reference_wall": j(float(r["cf_final"]), statistics.median(walls)),
        "one_wall": j(float(r["cf_seed_b"]), walls[0]),  # one wall-time measurement, a fresh CF seed
    }


def solve(a, y):
    """Least squares by the normal equations (few columns) with Gauss-Jordan elimination."""
    n = len(a[0])
    m = [[sum(r[i] * r[j] for r in a) for j in range(n)] + [sum(r[i] * v for r, v in zip(a, y))]
         for i in range(n)]
    for i in range(n):
        p = max(range(i, n), key=lambda k: abs(m[k][i]))
        m[i], m[p] = m[p], m[i]
        for k in range(n):
            if k != i:
                f = m[k][i] / m[i][i]
                m[k] = [x - f * z for x, z in zip(m[k], m[i])]
    return [m[i][n] / m[i][i] for i in range(n)]


def proxy_forms(data):
    """Relative errors of two proxy forms fitted to relative error on the noise study's CPU times."""
    out = []
    y = [statistics.median([float(r[k]) for k in r if k.startswith("cpu_ms_")]) for r in data]
    for label, cols in (("a + b checks + c checks x boxes", lambda r: [1, r[0], r[0] * r[1]]),
                        ("a + b checks + c checks x boxes + d checks x near", lambda r: [1, r[0], r[0] * r[1],
                                                                                        r[0] * r[2]])):
        rows_ = [cols((float(r["checks"]), float(r["boxes"]), float(r["near"]))) for r in data]
        a = [[x / v for x in row] for row, v in zip(rows_, y)]
        coef = solve(a, [1.0] * len(y))
        rel = sorted(abs(sum(c * x for c, x in zip(coef, row)) - v) / v for row, v in zip(rows_, y))
        out.append((label, statistics.median(rel), rel[int(0.9 * (len(rel) - 1))], rel[-1]))
    return out


def noise_metrics(csv_path, json_path):
    data = rows(csv_path)
    report = json.loads(json_path.read_text())
    lam, mu = report["objective"]["lambda"], report["objective"]["mu"]
    points = sorted({int(r["point"]) for r in data})
    m = {"rows": len(data), "points": len(points), "report": report, "data": data}
    wall_cv, cpu_cv, err_cpu, err_wall, cost, cpu_med = [], [], [], [], [], []
    for r in data:
        w = [float(r[k]) for k in r if k.startswith("wall_ms_")]
        c = [float(r[k]) for k in r if k.startswith("cpu_ms_")]
        wall_cv.append((max(w) - min(w)) / statistics.median(w))
        cpu_cv.append((max(c) - min(c)) / statistics.median(c))
        err_cpu.append(abs(float(r["cost_ms"]) - statistics.median(c)) / statistics.median(c))
        err_wall.append(abs(float(r["cost_ms"]) - statistics.median(w)) / statistics.median(w))
        cost.append(float(r["cost_ms"]))
        cpu_med.append(statistics.median(c))
    m["wall_cv"], m["cpu_cv"], m["err_cpu"], m["err_wall"] = wall_cv, cpu_cv, err_cpu, err_wall
    m["proxy_spearman"] = spearman(cost, cpu_med)
    seeds = ("cf_seed_a", "cf_seed_b", "cf_seed_c")
    m["cf_sd"] = [statistics.pstdev([float(r[k]) for k in seeds]) for r in data]
    by_case = {}
    for r in data:
        by_case.setdefault(r["case"], {})[int(r["point"])] = r
    crn, indep = [], []
    for pts in by_case.values():
        for p, q in itertools.combinations(sorted(pts), 2):
            a, b = pts[p], pts[q]
            crn.append(statistics.pstdev([float(a[k]) - float(b[k]) for k in seeds]))
            indep.append(statistics.pstdev([float(a[k]) - float(b[t]) for k, t in zip(seeds, seeds[1:] + seeds[:1])]))
    m["crn"], m["indep"] = crn, indep
    variants = {}
    for r in data:
        for k, v in noise_objectives(r, lam, mu).items():
            variants.setdefault(k, {}).setdefault(int(r["point"]), []).append(v)
    agg = {k: [statistics.fmean(v[p]) for p in points] for k, v in variants.items()}
    m["agg"] = agg
    m["spread"] = max(agg["reference_cpu"]) - min(agg["reference_cpu"])
    return m


def q90(v):
    return sorted(v)[int(0.9 * (len(v) - 1))]


def render_noise():
    studies = []
    for name, label in (("noise", "random points"), ("noise-local", "around the tuned point")):
        if (DATA / f"{name}.csv").exists() and (DATA / f"{name}.json").exists():
            studies.append((label, noise_metrics(DATA / f"{name}.csv", DATA / f"{name}.json")))
    if not studies:
        return "(no noise study yet)\n"
    out = []
    first = studies[0][1]["report"]
    out.append(f"Two studies on all nine paths, {first['noise_study']['points']} parameter sets each: *random "
               "points* are the thesis's start and uniformly random feasible points of the whole box "
               "(`--noise-study 20 --seed 3`); *around the tuned point* are the run's result and random moves "
               "of every variable by up to 5 % of its range (`--noise-center docs/data/tuning/tuned.json "
               "--seed 4`), where the search makes its finest decisions. Per set and path: the bounding step "
               f"repeated {first['noise_study']['repeats']} times, the CF at three seeds with the search's "
               f"30 x {first['objective']['cf_samples']} samples, and once with 30 x "
               f"{first['noise_study']['final_samples']} at the summary's seed. Raw rows: "
               "`docs/data/tuning/noise.csv`, `noise-local.csv`.\n")
    head = "| quantity | " + " | ".join(f"{l}: median | 90th pct." for l, _ in studies) + " |"
    out.append(head)
    out.append("|---|" + "---:|---:|" * len(studies))

    def line(label, key, scale=100, digits=1, unit=" %"):
        cells = []
        for _, m in studies:
            v = m[key]
            cells += [f"{scale * statistics.median(v):.{digits}f}{unit}", f"{scale * q90(v):.{digits}f}{unit}"]
        out.append(f"| {label} | " + " | ".join(cells) + " |")
    line("wall time: (max - min) / median of the repeats", "wall_cv")
    line("CPU time: (max - min) / median of the repeats", "cpu_cv")
    line("proxy against the median CPU time: relative error", "err_cpu")
    line("proxy against the median wall time: relative error", "err_wall")
    line(f"CF (30 x {first['objective']['cf_samples']}): std. dev. over 3 seeds [points]", "cf_sd", 100, 3, "")
    line("CF difference of two sets, common random numbers: std. dev. [points]", "crn", 100, 3, "")
    line("CF difference of two sets, independent seeds: std. dev. [points]", "indep", 100, 3, "")
    out.append("")
    out.append("Spearman correlation of the proxy with the median CPU time: "
               + "; ".join(f"{l} {m['proxy_spearman']:.4f} ({m['rows']} rows)" for l, m in studies) + ".\n")
    out.append("Why the near pairs are in the proxy: both forms fitted (to relative error) on the random points' "
               "median CPU times; in-sample relative errors:\n")
    out.append("| proxy form | median | 90th percentile | worst |")
    out.append("|---|---:|---:|---:|")
    for label, med, p90, worst in proxy_forms(studies[0][1]["data"]):
        out.append(f"| {label} | {100 * med:.1f} % | {100 * p90:.1f} % | {100 * worst:.1f} % |")
    out.append("")
    out.append("Ranking of the parameter sets by J (mean over the nine paths) against the reference ranking "
               "(CF 30 x 10,000 at the unseen seed, median CPU time). Spearman correlation / share of pairs "
               "ordered as in the reference / rank given to the reference's best set:\n")
    out.append("| J computed with | " + " | ".join(l for l, _ in studies) + " |")
    out.append("|---|" + "---|" * len(studies))
    names = [("search", "the search's objective: proxy time, CF 30 x 1000 at the search's seed"),
             ("seed_b", "the same at a second CF seed"),
             ("seed_c", "the same at a third CF seed"),
             ("reference_wall", "the reference's CF with the median wall time"),
             ("one_wall", "one wall-time measurement, CF 30 x 1000 at a second seed")]
    for k, label in names:
        cells = []
        for _, m in studies:
            v, ref = m["agg"][k], m["agg"]["reference_cpu"]
            best_ref = max(range(len(ref)), key=lambda i: ref[i])
            order = sorted(range(len(v)), key=lambda i: -v[i])
            cells.append(f"{spearman(v, ref):.3f} / {100 * concordance(v, ref):.0f} % / "
                         f"{order.index(best_ref) + 1} of {len(v)}")
        out.append(f"| {label} | " + " | ".join(cells) + " |")
    out.append("")
    out.append("Range of the reference J over the sets: "
               + "; ".join(f"{l} {m['spread']:.3f} points" for l, m in studies) + ".\n")
    best = []
    for l, m in studies:
        ref = m["agg"]["reference_cpu"]
        i = max(range(len(ref)), key=lambda k: ref[k])
        best.append(f"{l}: set {i + 1} (reference J {ref[i]:.3f}; set 1 {ref[0]:.3f})")
    out.append("The reference's best set (set 1 is the thesis's start, or the tuned point): "
               + "; ".join(best) + ".\n")
    return "\n".join(out)


def render_run():
    path = DATA / "run.json"
    if not path.exists():
        return {"run": "(no tuning run yet)\n", "run-params": "", "run-summary": "", "run-command": "", "run-thesis": ""}
    rep = json.loads(path.read_text())
    info = json.loads((DATA / "run-info.json").read_text()) if (DATA / "run-info.json").exists() else {}
    s = rep["search"]
    parts = {}
    cmd = rep["command"]
    parts["run-command"] = (f"```sh\n{cmd}\n```\n\nRun on {info.get('date', '?')}, {info.get('machine', '?')} "
                            f"(1-minute load average when it ended: {info.get('load', ['?'])[0]}; the machine "
                            "is shared, so the wall times below are indicative).\n")
    tm = rep["time_model"]
    pc = rep.get("proxy_check", {})
    parts["run"] = (
        f"The search stopped on *{s['stop']}* after {s['evaluations']} evaluations in {s['seconds']:.0f} s "
        f"(calibration included in the total, not in the search budget). The best J was found at evaluation "
        f"{s['best_evaluation']}: {s['best_objective']:.4f}, against {s['start_objective']:.4f} for the thesis's "
        f"parameters at evaluation 1 (search objective: CF 30 x 1000, proxy time). The time proxy of this run: "
        f"{tm['ms_fixed']:.3g} ms + {tm['ms_per_check']:.3g} ms x checks + {tm['ms_per_check_box']:.3g} ms x "
        f"checks x boxes + {tm['ms_per_check_near']:.3g} ms x checks x near pairs (R^2 {tm['r2']:.4f}, median relative error {100 * tm['median_rel_error']:.1f} % on its "
        f"{len(tm['runs'])} calibration runs); over the search's {pc.get('runs', 0)} runs its Spearman "
        f"correlation with the measured CPU time was {pc.get('spearman_cpu', float('nan')):.4f} and its median "
        f"relative error {100 * pc.get('median_rel_error_cpu', float('nan')):.1f} %.\n")
    # Parameters.
    p = ["| variable | range | thesis | tuned |", "|---|---|---:|---:|"]
    for v, x in zip(rep["variables"], s["best_x"]):
        if v["name"] == "log10_max_cells":
            p.append(f"| max_cells | {round(10 ** v['lower'])} .. {round(10 ** v['upper'])} (log10 tuned) | "
                     f"{round(10 ** v['thesis'])} | {round(10 ** x)} |")
        else:
            p.append(f"| {v['name']} [{v['unit']}] | {v['lower']:g} .. {v['upper']:g} | {v['thesis']:g} | "
                     f"{x:.4g} |")
    parts["run-params"] = "\n".join(p) + "\n\nThe file, as `leeway bounds --params` reads it " \
        "(`docs/data/tuning/tuned.json`):\n\n```json\n" + json.dumps(rep["tuned_params"], indent=2) + "\n```\n"
    # Before / after.
    ss = rep.get("summary_settings", {})
    o = [f"CF with 30 x {ss.get('cf_samples', '?')} samples at seed {ss.get('cf_seed', '?')} (not the search's "
         f"seed); time = median of {ss.get('repeats', '?')} single-threaded runs of the method (volume and "
         "bounds at both waypoints), wall clock, with the proxy in brackets; *collapsed*: bisected intervals "
         "(j1-j3 at both waypoints) widened by the collapse guard; *width*: their mean width; *J*: the "
         "objective with this CF and the proxy time. *start@N* is the thesis's parameters at MAX_cells N.\n",
         "| path | parameters | MAX_cells | boxes | CF [%] | time [ms] | collapsed | width [rad] | J |",
         "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for c in rep.get("summary", []):
        for cfg in c["configs"]:
            o.append(f"| {c['case']} | {cfg['name']} | {cfg['max_cells']} | {cfg['boxes']} | "
                     f"{100 * cfg['cf']:.3f} | {cfg['wall_ms']:.1f} [{cfg['cost_ms']:.1f}] | "
                     f"{cfg['collapsed']}/{cfg['bisected']} | {cfg['mean_width']:.3f} | {cfg['score']:.3f} |")
    o.append("")
    totals = rep.get("summary_objective", {})
    if totals:
        # Means over the nine paths.
        o.append("| parameters | mean CF [%] | worst CF [%] | mean time [ms] | collapsed | mean width [rad] | "
                 "J (mean) |")
        o.append("|---|---:|---:|---:|---:|---:|---:|")
        names = [cfg["name"] for cfg in rep["summary"][0]["configs"]]
        for n in names:
            cfgs = [next(x for x in c["configs"] if x["name"] == n) for c in rep["summary"]]
            o.append(f"| {n} | {100 * statistics.fmean(x['cf'] for x in cfgs):.3f} | "
                     f"{100 * min(x['cf'] for x in cfgs):.3f} | "
                     f"{statistics.fmean(x['wall_ms'] for x in cfgs):.1f} | "
                     f"{sum(x['collapsed'] for x in cfgs)}/{sum(x['bisected'] for x in cfgs)} | "
                     f"{statistics.fmean(x['mean_width'] for x in cfgs):.3f} | {totals.get(n, float('nan')):.3f} |")
        o.append("")
    rc = rep.get("recheck")
    if rc:
        o.append(f"Ranking check (`--recheck {len(rc['points'])}`): the best evaluation of the search and the next "
                 "best ones each at least 0.02 below the previous, re-scored with the summary's CF and measured "
                 "times (medians of 3 runs) instead of the search's CF and the proxy:\n")
        o.append("| search J | J with wall time | J with CPU time |")
        o.append("|---:|---:|---:|")
        for pt in rc["points"]:
            o.append(f"| {pt['search_objective']:.4f} | {pt['wall_objective']:.4f} | {pt['cpu_objective']:.4f} |")
        o.append(f"\nSpearman correlation with the search's order: {rc['spearman_wall']:.3f} (wall), "
                 f"{rc['spearman_cpu']:.3f} (CPU).\n")
    parts["run-summary"] = "\n".join(o)
    parts["run-thesis"] = render_run_thesis(rep)
    return parts


def render_run_thesis(rep):
    """The tuned parameters beside the thesis's published rows of tables 4.1-4.9."""
    thesis = {}
    with open(ROOT / "docs" / "data" / "thesis_tables.csv") as f:
        for r in csv.DictReader(line for line in f if not line.startswith("#")):
            thesis.setdefault(f"{r['cell']}:{r['path'].replace('-', ':')}", []).append(r)
    o = ["The thesis's published rows (tables 4.1-4.9: its cells, its machine, an Intel i5-8250U) beside "
         "leeway with the tuned parameters (our cells, this machine; time = median wall time of 3 "
         "single-threaded runs, CF 30 x 10000 at the summary's seed). *thesis @25000* is the MAX_cells of "
         "the abstract's numbers (12148 boxes, 1.527 s: table 4.1's 25000 row), taken for every path "
         "(leeway's choice); *thesis, best CF* its row with the highest CF over the 20 MAX_cells "
         "(the fastest of equal ones). The ratio is the thesis's time at 25,000 cells over leeway's.\n",
         "| path | thesis @25000: boxes | time [ms] | CF [%] | thesis, best CF: MAX_cells | time [ms] | CF [%] | "
         "leeway tuned: boxes | time [ms] | CF [%] | time ratio |",
         "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    ratios = []
    for c in rep.get("summary", []):
        rows_ = thesis.get(c["case"])
        tuned = next((x for x in c["configs"] if x["name"] == "tuned"), None)
        if not rows_ or tuned is None:
            continue
        at = next(r for r in rows_ if r["max_cells"] == "25000")
        best = max(rows_, key=lambda r: (float(r["cf_percent"]), -float(r["time_ms"])))
        ratio = float(at["time_ms"]) / tuned["wall_ms"]
        ratios.append(ratio)
        o.append(f"| {c['case']} | {at['boxes']} | {at['time_ms']} | {float(at['cf_percent']):.3f} | "
                 f"{best['max_cells']} | {best['time_ms']} | {float(best['cf_percent']):.3f} | {tuned['boxes']} | "
                 f"{tuned['wall_ms']:.1f} | {100 * tuned['cf']:.3f} | {ratio:.0f} |")
    if ratios:
        o.append(f"\nMedian time ratio over the paths: {statistics.median(ratios):.0f}. The two columns differ "
                 "in hardware, cell models and implementation at once; no measurement separates them.\n")
    return "\n".join(o)


def render():
    text = DOC.read_text()
    blocks = {"compare": render_compare(), "noise": render_noise()}
    blocks.update(render_run())
    for name, body in blocks.items():
        pattern = re.compile(rf"(<!-- begin {name} -->\n).*?(<!-- end {name} -->)", re.S)
        if not pattern.search(text):
            print(f"warning: no block '{name}' in {DOC}", file=sys.stderr)
            continue
        text = pattern.sub(lambda m: m.group(1) + body.rstrip("\n") + "\n" + m.group(2), text)
    DOC.write_text(text)
    print(f"wrote {DOC}", file=sys.stderr)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tune", default="build/leeway-tune", help="the program, relative to the repository")
    ap.add_argument("--only", default="compare,noise,run,noise-local")
    ap.add_argument("--render-only", action="store_true")
    ap.add_argument("--run-seconds", type=int, default=1080)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    DATA.mkdir(parents=True, exist_ok=True)
    if not args.render_only:
        phases = args.only.split(",")
        if "compare" in phases:
            phase_compare(args.tune, args.threads)
        if "noise" in phases:
            phase_noise(args.tune, args.threads)
        if "run" in phases:
            phase_run(args.tune, args.threads, args.run_seconds)
        if "noise-local" in phases:
            phase_noise_local(args.tune, args.threads)
    render()


if __name__ == "__main__":
    main()
