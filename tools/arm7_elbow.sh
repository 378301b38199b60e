#!/usr/bin/env bash
# The widths of the 7-joint test arm's intervals with the thesis's rule (a1-a3 bisected, the elbow
# a4 fixed) and with the elbow bisected (`--bisect a1,a2,a4`, and a1-a4), before the safety stage
# and certified: the numbers of docs/robots.md ("Arms other than the six-axis industrial arm").
# The cell is built as tests/urdf_import_test.cpp (SevenJointArmEndToEnd) builds it: arm7.urdf
# imported, a table in front of the arm and a post behind it, the path home -> lean in 3 waypoints.
# Prints one Markdown table row per run and waypoint: widths upper - lower [rad] per joint.
# Usage: tools/arm7_elbow.sh [path/to/leeway]   (default: build/leeway)
set -euo pipefail
cd "$(dirname "$0")/.."
leeway=$(realpath "${1:-build/leeway}")
urdf=$(realpath tests/data/urdf/arm7.urdf)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/robots" "$work/cells"
"$leeway" import-urdf "$urdf" --out "$work/robots/arm7.xml" >/dev/null
"$leeway" new-cell --robot "$work/robots/arm7.xml" --out "$work/cells/arm7.xml" >/dev/null
cell="$work/cells/arm7.xml"
python3 - "$cell" <<'EOF'
import sys
path = sys.argv[1]
s = open(path).read()
s = s.replace("  </worldbody>",
              '    <geom name="table" type="box" pos="0.8 0 0.25" size="0.3 0.4 0.25" contype="0" conaffinity="1"/>\n'
              '    <geom name="post" type="box" pos="-0.6 0.4 0.6" size="0.1 0.1 0.6" contype="0" conaffinity="1"/>\n'
              "  </worldbody>", 1)
s = s.replace("  </keyframe>", '    <key name="lean" qpos="0 0.6 0 1.0 0 1.0 0"/>\n  </keyframe>', 1)
open(path, "w").write(s)
EOF
echo "| bisected | safety | waypoint | a1 | a2 | a3 | a4 | a5 | a6 | a7 | checks | CF |"
echo "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for bisect in "" a1,a2,a4 a1,a2,a3,a4; do
  for safety in none certified; do
    args=(bounds "$cell" --from home --to lean --waypoints 3 --threads 1 --safety "$safety"
          --out "$work/b.json")
    [ -n "$bisect" ] && args+=(--bisect "$bisect")
    "$leeway" "${args[@]}" >/dev/null
    cf=$("$leeway" cf "$cell" "$work/b.json" --samples 2000 --threads 1 --json |
         python3 -c 'import json, sys; print("%.2f %%" % (100 * json.load(sys.stdin)["cf"]))')
    python3 - "$work/b.json" "${bisect:-a1,a2,a3 (default)}" "$safety" "$cf" <<'EOF'
import json, sys
b = json.load(open(sys.argv[1]))
for i, w in enumerate(b["waypoints"]):
    widths = " | ".join("%.3f" % (u - l) for l, u in zip(w["lower"], w["upper"]))
    print(f"| {sys.argv[2]} | {sys.argv[3]} | {i} | {widths} | {b['collision_checks']} | {sys.argv[4]} |")
EOF
  done
done
