"""Load the Dallara cell, bound the straight joint path from keyframe 'home' to 'patch', and print
whether the bounds are certified and how wide each joint's interval is at every waypoint [rad].

Run from the repository root after building:
    PYTHONPATH=build/python /usr/bin/python3 examples/python/01_load_and_bound.py
"""

import os

import leeway

HERE = os.path.dirname(os.path.abspath(__file__))
CELL = os.path.join(HERE, "..", "..", "mjcf", "workcells", "dallara.xml")

scene = leeway.Scene.load(CELL)
print(f"{scene.source}: {scene.dof} joints {scene.joint_names}")

# Five waypoints on the joint-linear path, the "leeway" preset (tuned parameters, certified safety).
# Any parameter can be changed by its dotted name, as in a parameter file; here the height-map's
# MAX_cells, set to the preset's own value (1725) to show the syntax.
bounds = leeway.bounds(scene, "home", "patch", waypoints=5, **{"height_map.max_cells": 1725})
print(f"certified: {bounds.certified}  (every box proven collision-free)")
print(f"nominal duration: {bounds.duration:.3f} s")

# Width of each joint's interval, upper - lower [rad], one row per waypoint.
widths = bounds.upper - bounds.lower
print("width [rad]  " + "".join(f"{name:>9}" for name in bounds.joint_names))
for i, (t, row) in enumerate(zip(bounds.times, widths)):
    print(f"wp {i} {t:5.2f} s " + "".join(f"{w:9.4f}" for w in row))

# The nominal path lies inside its own bounds.
assert (bounds.lower <= bounds.nominal).all() and (bounds.nominal <= bounds.upper).all()
