"""Tests of the Python module `leeway` (python/leeway_module.cpp).

Expected values are worked out by hand from small bounds files written here (linear interpolation
in the path parameter s, docs/cli.md "Contract for a controller"), not taken from the module's own
output. Run by ctest (python/CMakeLists.txt) with PYTHONPATH at the built module and LEEWAY_MJCF_DIR
at the repository's mjcf folder.
"""

import json
import math
import os
import threading
import time

import numpy as np
import pytest

import leeway

MJCF_DIR = os.environ.get(
    "LEEWAY_MJCF_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "mjcf"))
DALLARA = os.path.join(MJCF_DIR, "workcells", "dallara.xml")

# Two joints, three waypoints at t = 0, 2, 3 s.
TWO_JOINTS = {
    "format": "leeway-bounds-2",
    "joints": ["a", "b"],
    "timing": {"timed": True},
    "waypoints": [
        {"t": 0, "s": 0, "q": [0, 1], "lower": [-1, 0], "upper": [1, 2]},
        {"t": 2, "s": 1, "q": [1, 1], "lower": [0, 0.5], "upper": [2, 1.5]},
        {"t": 3, "s": 2, "q": [1, 0], "lower": [1, -1], "upper": [1, 0.5]},
    ],
}

# A one-link arm: hinge j1 about z at (0, 0, 0.5), a 1 m link along +x, nominal speed 1.5 rad/s;
# BLOCK_POS puts the obstacle (a 0.2 m cube at z = 0.5 m).
ONE_LINK = """<mujoco model="one-link">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <body name="base">
      <geom name="base_box" type="box" size="0.1 0.1 0.25" pos="0 0 0.25"/>
      <body name="link" pos="0 0 0.5">
        <joint name="j1" type="hinge" axis="0 0 1" range="-3 3" user="1.5"/>
        <geom name="link_box" type="box" size="0.5 0.05 0.05" pos="0.5 0 0"/>
        <site name="tool0" pos="1 0 0"/>
      </body>
    </body>
    <geom name="block" type="box" pos="BLOCK_POS" size="0.1 0.1 0.1" contype="0" conaffinity="1"/>
  </worldbody>
  <keyframe>
    <key name="a" qpos="0"/>
    <key name="b" qpos="0.5"/>
    <key name="up" qpos="1.5708"/>
  </keyframe>
</mujoco>
"""

# The one-link arm's bounds from q = 0 to 0.5 rad in 0.5 s.
ONE_JOINT = {
    "format": "leeway-bounds-2",
    "joints": ["j1"],
    "timing": {"timed": True},
    "waypoints": [
        {"t": 0, "s": 0, "q": [0], "lower": [-0.1], "upper": [0.1]},
        {"t": 0.5, "s": 1, "q": [0.5], "lower": [0.4], "upper": [0.6]},
    ],
}


def write_json(path, obj):
    path.write_text(json.dumps(obj))
    return str(path)


def one_link_cell(tmp_path, block_pos="-0.6 -0.6 0.5"):
    path = tmp_path / "one_link.xml"
    path.write_text(ONE_LINK.replace("BLOCK_POS", block_pos))
    return leeway.Scene.load(str(path))


@pytest.fixture(scope="module")
def two_joints(tmp_path_factory):
    return leeway.read_bounds(write_json(tmp_path_factory.mktemp("b") / "two.json", TWO_JOINTS))


@pytest.fixture(scope="module")
def dallara():
    return leeway.Scene.load(DALLARA)


@pytest.fixture(scope="module")
def dallara_bounds(dallara):
    return leeway.bounds(dallara, "home", "patch", waypoints=3, **{"height_map.max_cells": 300})


# --- a bounds file read without its cell ---------------------------------------------------------

def test_read_without_scene_gives_the_files_arrays(two_joints):
    b = two_joints
    assert b.joint_names == ["a", "b"]
    assert b.nominal.shape == (3, 2) and b.nominal.dtype == np.float64
    np.testing.assert_array_equal(b.nominal, [[0, 1], [1, 1], [1, 0]])
    np.testing.assert_array_equal(b.lower, [[-1, 0], [0, 0.5], [1, -1]])
    np.testing.assert_array_equal(b.upper, [[1, 2], [2, 1.5], [1, 0.5]])
    np.testing.assert_array_equal(b.times, [0, 2, 3])
    assert b.duration == 3
    assert b.certified is None  # the file has no certified_region
    assert len(b) == 3 and b.dof == 2


def test_at_s_interpolates_linearly_in_s(two_joints):
    # s = 0.25: a quarter of the way from waypoint 0 to 1; that segment lasts 2 s, so t = 0.5 s.
    st = two_joints.at_s(0.25)
    assert st.s == 0.25 and st.t == pytest.approx(0.5)
    np.testing.assert_allclose(st.nominal, [0.25, 1.0])
    np.testing.assert_allclose(st.lower, [-0.75, 0.125])
    np.testing.assert_allclose(st.upper, [1.25, 1.875])


def test_at_t_goes_through_the_times(two_joints):
    # t = 2.5 s is half of the second segment (2 .. 3 s): s = 1.5.
    st = two_joints.at_t(2.5)
    assert st.s == pytest.approx(1.5)
    np.testing.assert_allclose(st.nominal, [1.0, 0.5])
    np.testing.assert_allclose(st.lower, [0.5, -0.25])
    np.testing.assert_allclose(st.upper, [1.5, 1.0])
    # t = 1 s is half of the first segment (0 .. 2 s): s = 0.5.
    st = two_joints.at_t(1.0)
    assert st.s == pytest.approx(0.5)
    np.testing.assert_allclose(st.nominal, [0.5, 1.0])
    np.testing.assert_allclose(st.lower, [-0.5, 0.25])
    np.testing.assert_allclose(st.upper, [1.5, 1.75])


def test_out_of_range_is_clamped_to_the_ends(two_joints):
    np.testing.assert_array_equal(two_joints.at_s(-3).lower, [-1, 0])
    np.testing.assert_array_equal(two_joints.at_t(99).upper, [1, 0.5])
    assert two_joints.at_t(99).s == 2


def test_contains(two_joints):
    assert two_joints.contains(0.25, [1.25, 1.0])
    assert not two_joints.contains(0.25, [1.26, 1.0])
    assert not two_joints.contains(0.25, [0.0, 0.1])  # joint b below 0.125
    with pytest.raises(ValueError):
        two_joints.contains(0.25, [0.0])


def test_sample_covers_zero_to_duration_inclusive(two_joints):
    # dt 0.4 s over 3 s: t = 0, 0.4, ..., 2.8, then the end 3.0: 9 rows.
    r = two_joints.sample(0.4)
    assert set(r) == {"t", "s", "nominal", "lower", "upper"}
    assert r["t"].shape == (9,) and r["s"].shape == (9,)
    assert r["nominal"].shape == (9, 2) and r["lower"].shape == (9, 2) and r["upper"].shape == (9, 2)
    np.testing.assert_allclose(r["t"], [0, 0.4, 0.8, 1.2, 1.6, 2.0, 2.4, 2.8, 3.0])
    assert r["t"][-1] == 3.0 and r["s"][-1] == 2.0
    np.testing.assert_array_equal(r["nominal"][-1], [1, 0])
    # t = 0.4 s is a fifth of the first segment: s = 0.2.
    assert r["s"][1] == pytest.approx(0.2)
    np.testing.assert_allclose(r["nominal"][1], [0.2, 1.0])
    np.testing.assert_allclose(r["lower"][1], [-0.8, 0.1])
    np.testing.assert_allclose(r["upper"][1], [1.2, 1.9])
    # t = 2.4 s: s = 1.4.
    np.testing.assert_allclose(r["upper"][6], [1.6, 1.1])


def test_sample_does_not_repeat_the_end(two_joints):
    # 3 s is a multiple of 1 s: t = 0, 1, 2, 3 and no second row at 3.
    np.testing.assert_array_equal(two_joints.sample(1.0)["t"], [0, 1, 2, 3])


@pytest.mark.parametrize("bad", [0.0, -0.1, float("nan"), float("inf")])
def test_sample_refuses_a_bad_step(two_joints, bad):
    with pytest.raises(ValueError, match="dt"):
        two_joints.sample(bad)


def test_nan_is_refused(two_joints):
    with pytest.raises(ValueError):
        two_joints.at_t(float("nan"))
    with pytest.raises(ValueError):
        two_joints.at_s(math.nan)


def test_missing_file_names_the_path(tmp_path):
    missing = str(tmp_path / "no_such_bounds.json")
    with pytest.raises(ValueError, match="no_such_bounds.json"):
        leeway.read_bounds(missing)
    with pytest.raises(ValueError, match="no_such_cell.xml"):
        leeway.Scene.load(str(tmp_path / "no_such_cell.xml"))


def test_bad_file_is_value_error(tmp_path):
    bad = dict(TWO_JOINTS)
    bad["waypoints"] = [dict(w) for w in TWO_JOINTS["waypoints"]]
    bad["waypoints"][1]["lower"] = [1.5, 0.5]  # above the nominal 1
    with pytest.raises(ValueError):
        leeway.read_bounds(write_json(tmp_path / "bad.json", bad))


def test_save_of_a_read_file_round_trips(two_joints, tmp_path):
    out = str(tmp_path / "again.json")
    two_joints.save(out)
    again = leeway.read_bounds(out)
    for name in ("nominal", "lower", "upper", "times"):
        np.testing.assert_array_equal(getattr(again, name), getattr(two_joints, name))


# --- a bounds file with its cell ------------------------------------------------------------------

def test_read_with_scene_and_confidence_factor(tmp_path):
    scene = one_link_cell(tmp_path)
    assert scene.joint_names == ["j1"] and scene.dof == 1
    b = leeway.read_bounds(write_json(tmp_path / "one.json", ONE_JOINT), scene)
    # Half-way in time (0.25 s of 0.5 s): q 0.25, bounds 0.15 .. 0.35 rad.
    st = b.at_t(0.25)
    np.testing.assert_allclose([st.nominal[0], st.lower[0], st.upper[0]], [0.25, 0.15, 0.35])
    # The block is at -135 degrees, far from the bounds' -0.1 .. 0.6 rad: nothing collides.
    r = leeway.confidence_factor(scene, b, samples=50, windows=4, threads=2)
    assert r["samples"] == 200 and r["collisions"] == 0 and r["cf"] == 1.0
    assert r["duration"] == pytest.approx(0.5)


def test_confidence_factor_counts_collisions(tmp_path):
    # The block on the link's path at +0.3 rad (x 0.67, y 0.2): some samples hit it.
    scene = one_link_cell(tmp_path, "0.67 0.2 0.5")
    b = leeway.read_bounds(write_json(tmp_path / "one.json", ONE_JOINT))
    r = leeway.confidence_factor(scene, b, samples=100, windows=2, seed=3)
    assert 0 < r["collisions"] < 200 and r["cf"] < 1.0
    assert r["obstacle_collisions"] == r["collisions"]


def test_read_with_another_cell_is_refused(tmp_path):
    scene = one_link_cell(tmp_path)
    with pytest.raises(ValueError):
        leeway.read_bounds(write_json(tmp_path / "two.json", TWO_JOINTS), scene)
    b = leeway.read_bounds(write_json(tmp_path / "two.json", TWO_JOINTS))
    with pytest.raises(ValueError, match="joints"):
        leeway.confidence_factor(scene, b, samples=1, windows=1)


def test_a_colliding_straight_path_raises_collision_error(tmp_path):
    # The block at +45 degrees, 0.6 m out, lies on the way from 0 to 90 degrees.
    scene = one_link_cell(tmp_path, "0.42 0.42 0.5")
    with pytest.raises(leeway.CollisionError, match="block") as e:
        leeway.bounds(scene, "a", "up")
    assert isinstance(e.value, RuntimeError)


def test_one_link_bounds_contain_the_nominal(tmp_path):
    scene = one_link_cell(tmp_path)
    # A numpy integer is a number like any other.
    b = leeway.bounds(scene, "a", "b", waypoints=3, threads=1, **{"height_map.max_cells": np.int64(100)})
    # The straight path 0 .. 0.5 rad in three waypoints; at 1.5 rad/s each half lasts 1/6 s.
    np.testing.assert_allclose(b.nominal[:, 0], [0, 0.25, 0.5])
    np.testing.assert_allclose(b.times, [0, 1 / 6, 1 / 3])
    assert np.all(b.lower <= b.nominal) and np.all(b.nominal <= b.upper)


# --- Dallara --------------------------------------------------------------------------------------

def test_scene_properties(dallara):
    assert dallara.dof == 6 and len(dallara.joint_names) == 6
    assert dallara.source.endswith("dallara.xml")
    np.testing.assert_array_equal(dallara.keyframes["home"], np.zeros(6))


def test_check_returns_the_report(dallara):
    r = leeway.check(dallara)
    assert r["ok"] is True and r["problems"] == []


def test_dallara_bounds(dallara, dallara_bounds):
    b = dallara_bounds
    assert b.lower.shape == (3, 6) and b.upper.shape == (3, 6) and b.nominal.shape == (3, 6)
    assert b.times.shape == (3,) and b.times[0] == 0 and b.duration > 0
    assert b.joint_names == dallara.joint_names
    assert np.all(b.lower <= b.nominal) and np.all(b.nominal <= b.upper)
    assert np.all(b.upper - b.lower > 0)
    home, patch = dallara.keyframes["home"], dallara.keyframes["patch"]
    np.testing.assert_allclose(b.nominal[0], home, atol=1e-12)
    np.testing.assert_allclose(b.nominal[-1], patch, atol=1e-12)
    np.testing.assert_allclose(b.nominal[1], (home + patch) / 2, atol=1e-12)  # joint-linear
    assert b.certified is True
    r = b.sample(0.01)
    assert r["t"][0] == 0 and r["t"][-1] == b.duration and r["nominal"].shape[1] == 6


def test_dallara_save_and_read_round_trip(dallara, dallara_bounds, tmp_path):
    out = str(tmp_path / "dallara.json")
    dallara_bounds.save(out)
    with open(out) as f:
        assert json.load(f)["format"] == "leeway-bounds-2"
    for again in (leeway.read_bounds(out, dallara), leeway.read_bounds(out)):
        for name in ("nominal", "lower", "upper", "times"):
            np.testing.assert_array_equal(getattr(again, name), getattr(dallara_bounds, name))
        assert again.certified is True


def test_certified_bounds_have_no_collisions(dallara, dallara_bounds):
    r = leeway.confidence_factor(dallara, dallara_bounds, samples=300, windows=5, seed=7)
    assert r["samples"] == 1500 and r["collisions"] == 0 and r["cf"] == 1.0
    assert set(r) >= {"cf", "ci95", "samples", "collisions", "obstacle_collisions",
                      "self_collisions", "duration"}


def test_unknown_parameter_is_named(dallara):
    with pytest.raises(ValueError, match="height_map.max_cellz"):
        leeway.bounds(dallara, "home", "patch", **{"height_map.max_cellz": 300})
    with pytest.raises(ValueError, match="nosuchsection"):
        leeway.bounds(dallara, "home", "patch", nosuchsection=1)
    with pytest.raises(ValueError, match="height_map.max_cells"):
        leeway.bounds(dallara, "home", "patch", **{"height_map.max_cells": [300]})


def test_bad_arguments_are_value_errors(dallara):
    with pytest.raises(ValueError, match="keyframe|nokey"):
        leeway.bounds(dallara, "home", "nokey")
    with pytest.raises(ValueError, match="waypoints"):
        leeway.bounds(dallara, "home", "patch", waypoints=1)
    with pytest.raises(ValueError, match="safety"):
        leeway.bounds(dallara, "home", "patch", safety="maybe")
    with pytest.raises(ValueError, match="preset"):
        leeway.bounds(dallara, "home", "patch", preset="nope")


def test_bounds_releases_the_gil(dallara):
    count = 0
    stop = threading.Event()

    def counter():
        nonlocal count
        while not stop.is_set():
            count += 1
            time.sleep(0.001)

    worker = threading.Thread(target=counter)
    worker.start()
    try:
        before = count
        t0 = time.monotonic()
        leeway.bounds(dallara, "home", "patch", waypoints=3, threads=1,
                      **{"height_map.max_cells": 300})
        elapsed = time.monotonic() - t0
        during = count - before
    finally:
        stop.set()
        worker.join()
    # The counter ticks about once a millisecond when it gets the GIL; held for the whole call it
    # would tick only at the switches before and after.
    assert elapsed > 0.05, "the call was too short to tell"
    assert during >= 10, f"the counter advanced {during} times in {elapsed:.3f} s"


def test_two_threads_share_a_scene(tmp_path):
    # Scene and Bounds are immutable: two Python threads computing on one Scene at once get what
    # one thread gets alone.
    scene = one_link_cell(tmp_path)
    alone = leeway.bounds(scene, "a", "b", waypoints=4, threads=1, **{"height_map.max_cells": 100})
    results = [None, None]

    def run(k):
        results[k] = leeway.bounds(scene, "a", "b", waypoints=4, threads=1,
                                   **{"height_map.max_cells": 100})

    workers = [threading.Thread(target=run, args=(k,)) for k in range(2)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    for r in results:
        np.testing.assert_array_equal(r.lower, alone.lower)
        np.testing.assert_array_equal(r.upper, alone.upper)
