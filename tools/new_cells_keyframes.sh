#!/usr/bin/env bash
# Derives the goal keyframes of the cells not used for tuning, mjcf/workcells/press_shop.xml
# (fixed base: `pick`, `place`), mjcf/workcells/shelf_bay.xml (fixed base: `pick`,
# `place`), mjcf/workcells/rail_hall.xml (linear axis: `patch`, `mould`) and mjcf/workcells/low_beam.xml
# (fixed base: `pick`; `place` is its mirror image, below), mjcf/workcells/round_pillars.xml and
# mjcf/workcells/cad_cell.xml (fixed base: `pick`, `place`; their boxed twins, written by
# tools/make_mesh_twins.py, copy the keyframes),
# with leeway's own inverse kinematics, as tools/dlr_keyframes.sh does for DLR: tool0 on the goal
# site, tool pointing straight down, elbow-up branch (seeded there, j4 = -pi); j6 has no effect on
# the position or the tool axis, so it keeps its seed, j6 = j1 as in the thesis poses. Fixed base:
# the seed's j1 is the goal's bearing atan2(y, x). Linear axis: carriage policy rail_x = goal x
# (locked), j1 = +-pi/2 towards the goal. Prints one <key> line per keyframe (joint values in the
# model's order: [rail_x [m],] j1..j6 [rad]) to paste into the cell files; `home` is chosen, not
# derived (press_shop: all zeros; rail_hall: rail_x = -3, j1 = pi/2, the rest zero).
# Usage: tools/new_cells_keyframes.sh [path/to/leeway]   (default: build/leeway)
set -euo pipefail
cd "$(dirname "$0")/.."
leeway=${1:-build/leeway}

site_xyz() {  # cell site -> "x y z" of the site's pos attribute
  sed -n "s/.*<site name=\"$2\" pos=\"\([^\"]*\)\".*/\1/p" "$1"
}

derive() {  # cell key site [--lock rail_x]
  local cell=$1 key=$2 site=$3 lock=${4:-}
  local x y z j1 seed q
  read -r x y z <<<"$(site_xyz "$cell" "$site")"
  if [ -n "$lock" ]; then
    j1=$(awk -v y="$y" 'BEGIN { printf "%.6f", (y >= 0 ? 1 : -1) * atan2(1, 0) }')
    seed="$x $j1 0.6 0.3 -3.141593 -0.6 $j1"
  else
    j1=$(awk -v x="$x" -v y="$y" 'BEGIN { printf "%.6f", atan2(y, x) }')
    seed="$j1 0.6 0.3 -3.141593 -0.6 $j1"
  fi
  q=$("$leeway" ik "$cell" --xyz "$x" "$y" "$z" ${lock:+--lock "$lock"} --seed-q "$seed" --json |
      sed -n '/"q": \[/,/\]/p' | tr -d ' \n' | sed 's/"q":\[//; s/\],\?$//; s/,/ /g')
  printf '<key name="%s" qpos="' "$key"
  for v in $q; do printf '%.6f ' "$v"; done | sed 's/ $//'
  printf '"/>\n'
}

echo "mjcf/workcells/press_shop.xml:"
derive mjcf/workcells/press_shop.xml pick pick
derive mjcf/workcells/press_shop.xml place place
echo "mjcf/workcells/shelf_bay.xml:"
derive mjcf/workcells/shelf_bay.xml pick pick
derive mjcf/workcells/shelf_bay.xml place place
echo "mjcf/workcells/rail_hall.xml:"
derive mjcf/workcells/rail_hall.xml patch patch rail_x
derive mjcf/workcells/rail_hall.xml mould mould rail_x
# low_beam's place site is the mirror image of its pick site in the x-z plane: its keyframe is
# pick's with j1 and j6 negated (the IK from this seed lands on the j4 = +pi branch there instead).
echo "mjcf/workcells/low_beam.xml:"
derive mjcf/workcells/low_beam.xml pick pick
echo "mjcf/workcells/round_pillars.xml:"
derive mjcf/workcells/round_pillars.xml pick pick
derive mjcf/workcells/round_pillars.xml place place
echo "mjcf/workcells/cad_cell.xml:"
derive mjcf/workcells/cad_cell.xml pick pick
derive mjcf/workcells/cad_cell.xml place place
