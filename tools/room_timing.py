#!/usr/bin/env python3
"""Times the safety stage of the certified mode (`--grow none`) against one or more other
configurations on the 15 sparse paths of tools/make_room_results.py, interleaved: for each repeat
and each path, every configuration runs once, one after the other, so that a slow minute of a
shared machine slows them alike. Prints, per configuration, the median share over the paths (the
room, deterministic), the safety stage's time [s] summed over the paths (each path's median over
the repeats) and its ratio to `--grow none`'s. Standard library only.

Usage: tools/room_timing.py [--leeway build/leeway] [--repeats 3] [--config NAME=ARGS ...]

Each --config is a name and the extra `leeway bounds` arguments, split at spaces, e.g.
`--config "gl2=--params gl2.json"`; without any, the default configuration is timed.
"""
import argparse
import json
import pathlib
import statistics
import subprocess

from make_room_results import PATHS, ROOT


def bounds(leeway, cell, src, dst, extra):
    cmd = [leeway, "bounds", f"mjcf/workcells/{cell}.xml", "--from", src, "--to", dst, "--room", "on",
           "--json", "--threads", "1"] + extra
    out = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: exit {out.returncode}: {out.stderr.strip()}")
    d = json.loads(out.stdout)
    return d["timing_ms"]["safety"], d["room"]["mean_share"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--leeway", default=str(ROOT / "build" / "leeway"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--config", action="append", default=[], metavar="NAME=ARGS")
    args = ap.parse_args()
    configs = [("--grow none", ["--grow", "none"])]
    for c in args.config or ["default="]:
        name, _, extra = c.partition("=")
        configs.append((name, extra.split()))
    times = {name: {p: [] for p in PATHS} for name, _ in configs}
    shares = {name: {} for name, _ in configs}
    for _ in range(args.repeats):
        for p in PATHS:
            for name, extra in configs:
                ms, share = bounds(args.leeway, *p, extra)
                times[name][p].append(ms)
                shares[name][p] = share
    total = {name: sum(statistics.median(v) for v in times[name].values()) / 1000 for name, _ in configs}
    base = total["--grow none"]
    print(f"Safety stage on the {len(PATHS)} sparse paths, one thread, {args.repeats} interleaved repeats "
          f"(per path the median; units: %, s)")
    print("| configuration | median share [%] | mean share [%] | safety stage [s] | ratio |")
    print("|---|---:|---:|---:|---:|")
    for name, _ in configs:
        s = list(shares[name].values())
        print(f"| {name} | {100 * statistics.median(s):.1f} | {100 * statistics.mean(s):.1f} | "
              f"{total[name]:.2f} | {total[name] / base:.2f} |")


if __name__ == "__main__":
    main()
