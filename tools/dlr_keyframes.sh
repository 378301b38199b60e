#!/usr/bin/env bash
# Derives the DLR cell's `patch` and `mould` keyframes with leeway's own inverse kinematics:
# tool0 at the thesis's published gripper position (section 4.2.3), tool pointing straight down,
# carriage policy rail_x = goal x (locked), elbow-up branch (seeded there); j6 has no effect on
# the position or the tool axis, so it keeps its seed, j6 = j1 as in the thesis poses. Prints one qpos line
# per keyframe (rail_x [m], j1..j6 [rad]) to paste into mjcf/workcells/dlr.xml.
# Usage: tools/dlr_keyframes.sh [path/to/leeway]   (default: build/leeway)
set -euo pipefail
cd "$(dirname "$0")/.."
leeway=${1:-build/leeway}
cell=mjcf/workcells/dlr.xml

derive() {  # name goal_x goal_y goal_z
  local seed="$2 1.570796 0.6 0.3 -3.141593 -0.6 1.570796"  # j6 = j1, as in the thesis poses
  local q
  q=$("$leeway" ik "$cell" --xyz "$2" "$3" "$4" --lock rail_x --seed-q "$seed" --json |
      sed -n '/"q": \[/,/\]/p' | tr -d ' \n' | sed 's/"q":\[//; s/\],\?$//; s/,/ /g')
  printf '<key name="%s" qpos="' "$1"
  for v in $q; do printf '%.6f ' "$v"; done | sed 's/ $//'
  printf '"/>\n'
}

derive patch -0.916442 2.115 0.800
derive mould -7.60193 1.70258 1.200
