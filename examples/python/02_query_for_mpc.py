"""A toy joint-space controller kept inside the bounds: it follows the nominal path at 100 Hz while
a simulated person pushes the arm, and clamps every command into the box the bounds give at that
moment (Bounds.at_t). A real MPC would put lower/upper into its state constraints instead.

Run from the repository root after building:
    PYTHONPATH=build/python /usr/bin/python3 examples/python/02_query_for_mpc.py [bounds.json]
With a bounds file (leeway bounds --out) it reads that; without, it computes Dallara home -> patch.
"""

import os
import sys

import numpy as np

import leeway

HERE = os.path.dirname(os.path.abspath(__file__))
CELL = os.path.join(HERE, "..", "..", "mjcf", "workcells", "dallara.xml")

if len(sys.argv) > 1:
    bounds = leeway.read_bounds(sys.argv[1])  # a format-2 file carries its own times
else:
    scene = leeway.Scene.load(CELL)
    bounds = leeway.bounds(scene, "home", "patch", waypoints=5)

DT = 0.01  # control period [s]: 100 Hz
rng = np.random.default_rng(7)  # seeded: the same pushes every run
n = bounds.dof
steps = int(np.ceil(bounds.duration / DT)) + 1

# The push: during the middle third of the motion a person leans on the arm with a force that
# drifts in a random direction; as joint offsets it grows up to ~0.3 rad and decays afterwards.
push_start, push_end = bounds.duration / 3, 2 * bounds.duration / 3
direction = rng.normal(size=n)
direction /= np.linalg.norm(direction)

q = bounds.nominal[0].copy()  # the robot's state [rad]
offset = np.zeros(n)          # the disturbance's offset from the nominal [rad]
clamps = 0                    # joint commands the box changed
steps_clamped = 0             # control steps with at least one clamp
for k in range(steps):
    t = min(k * DT, bounds.duration)
    box = bounds.at_t(t)  # lower/upper/nominal at nominal time t (the robot keeps to the timing)
    if push_start <= t <= push_end:
        direction += 0.3 * rng.normal(size=n)
        direction /= np.linalg.norm(direction)
        offset += 0.02 * direction
    else:
        offset *= 0.9
    command = box.nominal + offset
    safe = np.clip(command, box.lower, box.upper)  # the only safety logic: stay in the box
    changed = np.count_nonzero(safe != command)
    clamps += changed
    steps_clamped += changed > 0
    q = safe  # an ideal joint servo reaches the command within the period
    assert bounds.contains(box.s, q), f"left the bounds at t = {t:.2f} s"

print(f"{steps} control steps at {1 / DT:.0f} Hz over {bounds.duration:.3f} s, "
      f"push from {push_start:.2f} to {push_end:.2f} s")
print(f"clamped {clamps} joint commands in {steps_clamped} steps; the state stayed inside the bounds")
print("final q [rad]: " + " ".join(f"{v:+.4f}" for v in q))
