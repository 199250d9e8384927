#!/usr/bin/env bash
# calibration.sh: the unseen fill's level from a render (`calibration`; README "The fill's
# level from a render"), every figure from `hbil bench`.
#
#   bench/calibration.sh NAME=SHOT_DIR=CALIBRATION ... [BUILD_DIR via BUILD=build]
#
# For each scene NAME: SHOT_DIR/frame_####.exr holds its frames and its 8-bounce reference
# (Combined, DiffCol, DiffInd: rendered as samples/README.md says), CALIBRATION a render of
# some of its frames with global illumination at low samples (a file, or a frame pattern),
# e.g. frame 1 at 1 spp with another seed than the reference:
#   blender -b --factory-startup --python samples/blender/SCENE.py -- --out DIR \
#     --mode main --samples 1 --seed 7 --frames 1-1
# One bench per scene, four configurations, alternating in RUNS timed runs (default 3): the
# default preset and presets/interior.json, each without and with `calibration`. Prints one
# table row per configuration: composite and indirect RMSE / mean error / PSNR over the
# non-background pixels of all frames, and s/frame (the calibration's solve included; the
# calibration render's own time is not).
#   OUT=/tmp/cal bench/calibration.sh ...   keep each bench's folder there
set -euo pipefail
cd "$(dirname "$0")/.."
hbil="${BUILD:-build}/hbil"
runs=${RUNS:-3}
if [ -n "${OUT:-}" ]; then
  out=$OUT
  mkdir -p "$out"
else
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi
[ $# -gt 0 ] || { echo "usage: bench/calibration.sh NAME=SHOT_DIR=CALIBRATION ..." >&2; exit 2; }
echo "(machine: $(nproc) cores, load at start $(cut -d' ' -f1-3 /proc/loadavg))"
echo
echo "| scene | preset | calibration | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
echo "|---|---|---|---|---|---|"
for arg in "$@"; do
  IFS='=' read -r name dir cal <<< "$arg"
  [ -n "$cal" ] && [ -f "$dir/frame_0001.exr" ] ||
    { echo "calibration.sh: expected NAME=SHOT_DIR=CALIBRATION, got $arg" >&2; exit 2; }
  in="$dir/frame_####.exr"
  mkdir -p "$out/$name.presets"
  echo "{\"calibration\": \"$cal\"}" > "$out/$name.presets/calibrated.json"
  echo "{\"unseen_carry\": true, \"calibration\": \"$cal\"}" > "$out/$name.presets/interior_calibrated.json"
  "$hbil" bench "$in" -o "$out/$name" -q --runs "$runs" \
    --ref "indirect=$in:DiffCol*DiffInd" --ref "composite=$in:Combined" \
    --preset presets/default.json --preset presets/interior.json \
    --preset "$out/$name.presets/calibrated.json" \
    --preset "$out/$name.presets/interior_calibrated.json" > /dev/null
  python3 bench/tables.py "$out/$name" --prefix "$name" \
    --label "default=default | none" --label "interior=interior | none" \
    --label "calibrated=default | $(basename "$cal")" \
    --label "interior_calibrated=interior | $(basename "$cal")" \
    indirect:rmp composite:rmp s
done
echo
echo "(load at end $(cut -d' ' -f1-3 /proc/loadavg))"
