"""Times Bounds.sample(0.001) on a synthetic bounds file: 1,000 waypoints of 6 joints, 10 ms apart
(9.99 s, so 9,991 rows of t, s and per joint nominal, lower, upper). Prints the median of 20 runs.

    PYTHONPATH=build/python /usr/bin/python3 python/bench_sample.py
"""

import json
import math
import os
import statistics
import tempfile
import time

import leeway

WAYPOINTS, JOINTS, STEP, DT, RUNS = 1000, 6, 0.01, 0.001, 20


def synthetic_bounds():
    """A format-2 bounds file: smooth nominal values, intervals 0.1 .. 0.3 rad wide."""
    waypoints = []
    for i in range(WAYPOINTS):
        q = [0.5 * math.sin(0.01 * i + j) for j in range(JOINTS)]
        half = [0.05 + 0.05 * (1 + math.cos(0.02 * i + j)) for j in range(JOINTS)]
        waypoints.append({"t": round(i * STEP, 10), "s": i, "q": q,
                          "lower": [a - h for a, h in zip(q, half)],
                          "upper": [a + h for a, h in zip(q, half)]})
    return {"format": "leeway-bounds-2", "joints": [f"j{j + 1}" for j in range(JOINTS)],
            "timing": {"timed": True}, "waypoints": waypoints}


with tempfile.TemporaryDirectory() as folder:
    path = os.path.join(folder, "synthetic.json")
    with open(path, "w") as f:
        json.dump(synthetic_bounds(), f)
    bounds = leeway.read_bounds(path)

rows = len(bounds.sample(DT)["t"])
times = []
for _ in range(RUNS):
    start = time.perf_counter()
    bounds.sample(DT)
    times.append(time.perf_counter() - start)
print(f"Bounds.sample({DT}) on {WAYPOINTS} waypoints x {JOINTS} joints ({bounds.duration:.2f} s, "
      f"{rows} rows): median {1000 * statistics.median(times):.2f} ms of {RUNS} runs "
      f"(min {1000 * min(times):.2f} ms)")
