#!/usr/bin/env python3
"""Imports two public robots with STL collision meshes (a UR5e from ROS-Industrial's
universal_robot, a KUKA LBR iiwa 14 from IFL-CAMP's iiwa_stack) with `leeway import-urdf
--link-geometry mesh` and `box`, puts each into a cell with `leeway new-cell`, adds keyframes at
ordinary poses and runs `leeway check` on it. Prints, per robot and mode, the self-collision pairs
the import excluded and which keyframes `check` passes (docs/robots.md, "Mesh geoms and boxes on
two public robots").

The repositories are not part of leeway: check them out yourself and pass the folder holding them,
e.g. `git clone https://github.com/ros-industrial/universal_robot` and
`git clone https://github.com/IFL-CAMP/iiwa_stack` into DIR, then

    tools/import_public_robots.py --repos DIR [--leeway build/leeway] [--work /tmp/leeway-public-robots]

Without ROS, the xacro files are expanded by a small expander below (properties, macros with
default and block parameters, includes, $(find) and $(arg), xacro:if/unless, xacro.load_yaml and
Python expressions in ${...}): enough for these two descriptions, not a replacement for xacro.
Everything is written under --work (default: a folder in the system's temporary folder). Units:
radians.
"""

import argparse
import copy
import json
import math
import os
import re
import shlex
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import yaml

# ---- a small xacro expander ----


class Scope(dict):
    def __init__(self, parent=None):
        super().__init__()
        self.parent = parent

    def find(self, name):
        s = self
        while s is not None:
            if name in s:
                return s[name]
            s = s.parent
        raise KeyError(name)

    def flat(self):
        chain, s = [], self
        while s is not None:
            chain.append(s)
            s = s.parent
        out = {}
        for s in reversed(chain):
            out.update(s)
        return out


class _YamlLoader(yaml.SafeLoader):
    """xacro.load_yaml's tags: !degrees X is X degrees in radians, !radians X is X."""


_YamlLoader.add_constructor("!degrees", lambda l, n: math.radians(float(l.construct_scalar(n))))
_YamlLoader.add_constructor("!radians", lambda l, n: float(l.construct_scalar(n)))


class _Xacro:
    @staticmethod
    def load_yaml(path):
        with open(path) as f:
            return yaml.load(f, Loader=_YamlLoader)


def _number(text):
    if not isinstance(text, str):
        return text
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


class Expander:
    def __init__(self, packages, args=None):
        self.packages = packages  # name -> folder
        self.args = dict(args or {})
        self.macros = {}

    def subst(self, text):
        text = re.sub(r"\$\(find ([^)\s]+)\)", lambda m: self.packages[m.group(1)], text)
        return re.sub(r"\$\(arg ([^)\s]+)\)", lambda m: str(self.args[m.group(1)]), text)

    def ev(self, text, scope):
        text = self.subst(text)
        env = {k: getattr(math, k) for k in dir(math) if not k.startswith("_")}
        env.update(xacro=_Xacro, true=True, false=False, True_=True)
        env.update({k: _number(v) for k, v in scope.flat().items() if not k.startswith("*")})
        whole = re.fullmatch(r"\$\{(.*)\}", text.strip(), re.S)
        if whole and "${" not in whole.group(1):
            return eval(whole.group(1), env)
        return re.sub(r"\$\{([^}]*)\}", lambda m: self._str(eval(m.group(1), env)), text)

    @staticmethod
    def _str(v):
        return repr(v) if isinstance(v, float) else str(v)

    @staticmethod
    def tag(e):
        if isinstance(e.tag, str) and e.tag.startswith("{") and "xacro" in e.tag:
            return "xacro:" + e.tag.split("}", 1)[1]
        return e.tag

    def expand_file(self, path):
        root = ET.parse(path).getroot()
        out = ET.Element("robot", {k: v for k, v in root.attrib.items() if not k.startswith("{")})
        self.process(root, Scope(), out)
        return out

    def truth(self, value, scope):
        v = self.ev(value, scope)
        return v not in (False, 0, "false", "False", "0", "")

    def process(self, elem, scope, out):
        children = [c for c in elem if isinstance(c.tag, str)]
        for child in children:
            t = self.tag(child)
            if t == "xacro:include":
                root = ET.parse(self.subst(child.get("filename"))).getroot()
                self.process(root, scope, out)
            elif t == "xacro:property":
                target = scope.parent if child.get("scope") == "parent" and scope.parent is not None else scope
                if child.get("value") is not None:
                    target[child.get("name")] = self.ev(child.get("value"), scope)
                else:
                    target["*" + child.get("name")] = child
            elif t == "xacro:arg":
                self.args.setdefault(child.get("name"), self.subst(child.get("default", "")))
            elif t == "xacro:macro":
                self.macros[child.get("name")] = child
            elif t in ("xacro:if", "xacro:unless"):
                if self.truth(child.get("value"), scope) == (t == "xacro:if"):
                    self.process(child, scope, out)
            elif t == "xacro:insert_block":
                block = scope.find("*" + child.get("name"))
                holder = ET.Element("holder")
                holder.append(copy.deepcopy(block))
                self.process(holder, scope, out)
            elif t.startswith("xacro:"):
                self.call(self.macros[t[len("xacro:"):]], child, scope, out)
            else:
                new = ET.SubElement(out, t, {k: self._str(self.ev(v, scope)) for k, v in child.attrib.items()})
                if child.text and child.text.strip():
                    new.text = self._str(self.ev(child.text, scope))
                self.process(child, scope, new)

    def call(self, macro, call, scope, out):
        inner = Scope(scope)
        blocks = [c for c in call if isinstance(c.tag, str)]
        for spec in shlex.split(macro.get("params", "")):
            if spec.startswith("*"):
                inner[spec] = blocks.pop(0)
                continue
            name, default = spec, None
            for sep in (":=", "^|"):
                if sep in spec:
                    name, default = spec.split(sep, 1)
            if call.get(name) is not None:
                inner[name] = self.ev(call.get(name), scope)
            elif default is not None:
                inner[name] = self.ev(default, scope)
            else:
                inner[name] = scope.find(name)
        self.process(macro, inner, out)


def expand(path, packages, args=None):
    robot = Expander(packages, args).expand_file(path)
    ET.indent(robot)
    return ET.tostring(robot, encoding="unicode") + "\n"


# ---- the robots and the poses ----

ROBOTS = [
    {
        "name": "ur5e",
        "repo": "universal_robot",
        "xacro": "ur_description/urdf/ur5e.xacro",
        "packages": {"ur_description": "ur_description"},
        "tool": "tool0",
        # shoulder_pan, shoulder_lift, elbow, wrist_1, wrist_2, wrist_3 [rad]
        "poses": {
            "lift_m1_2": [0, -1.2, 0, 0, 0, 0],
            "lift_m1_2_elbow_1": [0, -1.2, 1.0, 0, 0, 0],
            "lift_m0_6_elbow_1_5": [0, -0.6, 1.5, -1.0, 0, 0],
            "lift_m1_9": [0, -1.9, 0, 0, 0, 0],
            "fold_elbow_3_1": [0, -1.2, 3.1, 0, 0, 0],  # folded: the links really collide
        },
        # The path `leeway bounds` runs in both modes (room, safety time): both ends pass in mesh mode.
        "path": ("home", "lift_m1_2_elbow_1"),
    },
    {
        "name": "iiwa14",
        "repo": "iiwa_stack",
        "xacro": "iiwa_description/urdf/iiwa14.urdf.xacro",
        "packages": {"iiwa_description": "iiwa_description"},
        "tool": "iiwa_link_ee",
        # a1 .. a7 [rad]
        "poses": {
            "a6_p0_5": [0, 0, 0, 0, 0, 0.5, 0],
            "a6_m0_5": [0, 0, 0, 0, 0, -0.5, 0],
            "a2_0_5_a4_m1_a6_0_5": [0, 0.5, 0, -1.0, 0, 0.5, 0],
            "a6_p0_3": [0, 0, 0, 0, 0, 0.3, 0],
            "fold_a4_m2_a6_m2": [0, 0, 0, -2.0, 0, -2.0, 0],  # folded wrist: link_5 and link_7 meet
        },
        "path": ("home", "a6_p0_3"),  # both ends pass in both modes
    },
]


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr


def add_keyframes(cell, poses):
    with open(cell) as f:
        text = f.read()
    keys = "".join(
        '    <key name="%s" qpos="%s"/>\n' % (name, " ".join(repr(float(v)) for v in q)) for name, q in poses.items()
    )
    text = text.replace("  </keyframe>", keys + "  </keyframe>", 1)
    with open(cell, "w") as f:
        f.write(text)


def measure(robot, repos, leeway, work):
    root = os.path.join(repos, robot["repo"])
    packages = {k: os.path.join(root, v) for k, v in robot["packages"].items()}
    urdf = os.path.join(work, robot["name"] + ".urdf")
    with open(urdf, "w") as f:
        f.write(expand(os.path.join(root, robot["xacro"]), packages))
    results = {}
    for mode in ("mesh", "box"):
        d = os.path.join(work, robot["name"] + "_" + mode)
        os.makedirs(os.path.join(d, "robots"), exist_ok=True)
        os.makedirs(os.path.join(d, "cells"), exist_ok=True)
        frag = os.path.join(d, "robots", robot["name"] + ".xml")
        cell = os.path.join(d, "cells", robot["name"] + "_cell.xml")
        cmd = [leeway, "import-urdf", urdf, "--out", frag, "--tool", robot["tool"], "--link-geometry", mode,
               "--package-path", root]
        code, out = run(cmd)
        if code != 0:
            sys.exit("import failed:\n" + " ".join(cmd) + "\n" + out)
        excluded = re.findall(r"^excluded: '([^']+)' and '([^']+)'", out, re.M)
        code, out2 = run([leeway, "new-cell", "--robot", frag, "--out", cell])
        if code != 0:
            sys.exit("new-cell failed:\n" + out2)
        add_keyframes(cell, robot["poses"])
        code, report = run([leeway, "check", cell])
        poses = {}
        for name in robot["poses"]:
            failing = [line for line in report.splitlines() if line.startswith("problem: keyframe '%s'" % name)]
            poses[name] = "fails" if failing else "passes"
        results[mode] = {"import": " ".join(cmd), "excluded": excluded, "check_exit": code, "poses": poses,
                         "check_output": report.strip().splitlines(), "bounds": bounds(leeway, cell, robot["path"], d)}
    return results


def bounds(leeway, cell, path, folder):
    """`leeway bounds` (the default, certified mode, one thread) along the robot's path: segments
    proven, the mean kept share [%] and the safety stage's time [s], or the exit and the last line."""
    out = os.path.join(folder, "bounds.json")
    code, text = run([leeway, "bounds", cell, "--from", path[0], "--to", path[1], "--out", out, "--threads", "1"])
    if code != 0:
        return {"path": "-".join(path), "exit": code, "why": text.strip().splitlines()[-1]}
    with open(out) as f:
        b = json.load(f)
    segments = b["safety"].get("segments", [])
    return {"path": "-".join(path), "exit": 0, "proven": "%d/%d" % (sum(s["passed"] for s in segments), len(segments)),
            "mean_share": 100 * b["room"]["mean_share"], "safety_s": b["timing_ms"]["safety"] / 1000}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repos", required=True, help="folder holding universal_robot/ and iiwa_stack/")
    ap.add_argument("--leeway", default="build/leeway")
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "leeway-public-robots"))
    ap.add_argument("--json", action="store_true", help="print the results as JSON")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    all_results = {r["name"]: measure(r, a.repos, os.path.abspath(a.leeway), a.work) for r in ROBOTS}
    if a.json:
        print(json.dumps(all_results, indent=1))
        return
    for name, modes in all_results.items():
        for mode, r in modes.items():
            print("%s --link-geometry %s: %d pair(s) excluded" % (name, mode, len(r["excluded"])))
            for g1, g2 in r["excluded"]:
                print("  excluded: %s and %s" % (g1, g2))
            print("  leeway check exit %d; keyframes: %s" % (
                r["check_exit"], ", ".join("%s %s" % (k, v) for k, v in r["poses"].items())))
            for line in r["check_output"]:
                print("    | " + line)
            b = r["bounds"]
            if b["exit"] == 0:
                print("  bounds %s: %s segments proven, mean kept share %.1f %%, safety stage %.2f s (1 thread)" % (
                    b["path"], b["proven"], b["mean_share"], b["safety_s"]))
            else:
                print("  bounds %s: exit %d: %s" % (b["path"], b["exit"], b["why"]))


if __name__ == "__main__":
    main()
