#!/usr/bin/env bash
# Regenerates the pictures in docs/, from the repository root's build:
#   - docs/images/dallara-home-patch-volume.png: `leeway render` of the Dallara cell at the patch with
#     its volume and the ghosts of the robot at its bounds (the README's first picture);
#   - docs/images/dallara-home-patch-bounds.svg: `leeway plot` of the same bounds file;
#   - docs/images/dallara-home-patch-view.png: `leeway view` of the same bounds file, its page
#     opened in headless Chromium at t = 0.5 s (needs chromium);
#   - docs/images/dallara-patch-mould-simulate.png: a frame of `leeway simulate --video` on the
#     Dallara patch-mould path with a random push (needs ffmpeg);
#   - docs/images/sweep-CELL-PATH.svg: `leeway plot` of the nine recorded sweeps in
#     docs/data/results/ (both configurations) beside the thesis's tables 4.1-4.9;
# then docs/results.md from the recorded sweeps (tools/make_results.py --render-only), which embeds
# the sweep plots. The bounds file behind the first two is kept in docs/data/figures/. Deterministic
# except for the times recorded in that bounds file. Takes a few seconds.
# Usage: tools/make_figures.sh [path/to/leeway]   (default: build/leeway)
set -euo pipefail
cd "$(dirname "$0")/.."
leeway="${1:-build/leeway}"
mkdir -p docs/images docs/data/figures

cell=mjcf/workcells/dallara.xml
bounds=docs/data/figures/dallara-home-patch.json
"$leeway" bounds "$cell" --from home --to patch --out "$bounds" > /dev/null
"$leeway" render "$cell" --bounds "$bounds" --size 960x720 --out docs/images/dallara-home-patch-volume.png
"$leeway" plot "$bounds" --out docs/images/dallara-home-patch-bounds.svg
view_dir=$(mktemp -d)
"$leeway" view "$cell" --bounds "$bounds" --out "$view_dir/view.html" > /dev/null
chromium --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader --hide-scrollbars \
  --no-first-run --user-data-dir="$view_dir/profile" --window-size=1280,880 \
  --screenshot=docs/images/dallara-home-patch-view.png "file://$view_dir/view.html?t=0.5" 2> /dev/null
rm -rf "$view_dir"

# The closed loop (docs/simulate.md): the frame at t = 3 s of the video of a random push (seed 1).
sim_bounds=docs/data/figures/dallara-patch-mould.json
"$leeway" bounds "$cell" --from patch --to mould --out "$sim_bounds" > /dev/null
video_dir=$(mktemp -d)
trap 'rm -rf "$video_dir"' EXIT
"$leeway" simulate "$cell" --bounds "$sim_bounds" --human random --amplitude 100 --video "$video_dir/run.mp4" \
  --size 960x720 > /dev/null
ffmpeg -v error -y -ss 3 -i "$video_dir/run.mp4" -frames:v 1 docs/images/dallara-patch-mould-simulate.png

for case in dallara/home-patch dallara/patch-mould dallara/mould-home \
            baltico/home-patch baltico/patch-mould baltico/mould-home \
            dlr/home-patch dlr/patch-mould dlr/mould-home; do
  name="${case/\//-}"
  "$leeway" plot "docs/data/results/$name-thesis.csv" "docs/data/results/$name-margin.csv" --thesis "$case" \
    --out "docs/images/sweep-$name.svg"
done

python3 tools/make_results.py --render-only
