#!/usr/bin/env bash
# calibration.sh: the unseen fill's level from a render (`calibration`; README "The fill's
# level from a render"), every figure from `hbil bench`.
#
#   bench/calibration.sh NAME=SHOT_DIR=CALIBRATION[=REF_DIR] ... [BUILD_DIR via BUILD=build]
#
# For each scene NAME: SHOT_DIR/frame_####.exr holds its frames, REF_DIR/frame_####.exr
# (default SHOT_DIR) its 8-bounce reference (Combined, DiffCol, DiffInd: rendered as
# samples/README.md says), CALIBRATION a render of some of its frames with global
# illumination at low samples (a file, or a frame pattern), e.g. frame 1 at 1 spp with
# another seed than the reference:
#   blender -b --factory-startup --python samples/blender/SCENE.py -- --out DIR \
#     --mode main --samples 1 --seed 7 --frames 1-1
# One bench per scene, four configurations, alternating in RUNS timed runs (default 3): the
# default preset and presets/interior.json, each without and with `calibration`. Prints one
# table row per configuration: composite and indirect RMSE / mean error / PSNR over the
# non-background pixels of all frames, and s/frame (the calibration's solve included; the
# calibration render's own time is not).
#   OUT=/tmp/cal bench/calibration.sh ...   keep each bench's folder there
#   TILES=1 bench/calibration.sh ...   each calibrated configuration also with one factor per
#       calibration frame (`calibration_tiles` 0) beside the default tiles
#   EMISSION=1 RUNS=1 bench/calibration.sh ...   instead, the Emit pass gathered as light or
#       not (`emission`; README "Emitting surfaces"): the default preset with `emission`
#       "gathered" and with its default "auto", and presets/interior.json with `calibration`,
#       each way; one row per scene: composite PSNR, indirect relative RMSE and indirect
#       energy (sum of indirect over the sum of DiffCol x DiffInd), gathered -> auto
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
[ $# -gt 0 ] ||
  { echo "usage: bench/calibration.sh NAME=SHOT_DIR=CALIBRATION[=REF_DIR] ..." >&2; exit 2; }
echo "(machine: $(nproc) cores, load at start $(cut -d' ' -f1-3 /proc/loadavg))"
echo
if [ -n "${EMISSION:-}" ]; then
  echo "| scene | default: composite PSNR | indirect relative RMSE | indirect energy | interior + calibration: composite PSNR | indirect relative RMSE | indirect energy |"
  echo "|---|---|---|---|---|---|---|"
else
  echo "| scene | preset | calibration | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
  echo "|---|---|---|---|---|---|"
fi
for arg in "$@"; do
  IFS='=' read -r name dir cal ref <<< "$arg"
  [ -n "$cal" ] && [ -f "$dir/frame_0001.exr" ] ||
    { echo "calibration.sh: expected NAME=SHOT_DIR=CALIBRATION[=REF_DIR], got $arg" >&2; exit 2; }
  in="$dir/frame_####.exr"
  ref="${ref:-$dir}/frame_####.exr"
  p="$out/$name.presets"
  mkdir -p "$p"
  if [ -n "${EMISSION:-}" ]; then
    echo '{"emission": "gathered"}' > "$p/default_gathered.json"
    echo '{}' > "$p/default.json"
    echo "{\"unseen_carry\": true, \"calibration\": \"$cal\", \"emission\": \"gathered\"}" \
      > "$p/interior_cal_gathered.json"
    echo "{\"unseen_carry\": true, \"calibration\": \"$cal\"}" > "$p/interior_cal.json"
    configs=(default_gathered default interior_cal_gathered interior_cal)
  else
    echo "{\"calibration\": \"$cal\"}" > "$p/calibrated.json"
    echo "{\"unseen_carry\": true, \"calibration\": \"$cal\"}" > "$p/interior_calibrated.json"
    configs=(calibrated interior_calibrated)
    if [ -n "${TILES:-}" ]; then
      echo "{\"calibration\": \"$cal\", \"calibration_tiles\": 0}" > "$p/calibrated_one.json"
      echo "{\"unseen_carry\": true, \"calibration\": \"$cal\", \"calibration_tiles\": 0}" \
        > "$p/interior_calibrated_one.json"
      configs=(calibrated_one calibrated interior_calibrated_one interior_calibrated)
    fi
  fi
  presets=()
  [ -n "${EMISSION:-}" ] || presets=(--preset presets/default.json --preset presets/interior.json)
  for c in "${configs[@]}"; do presets+=(--preset "$p/$c.json"); done
  "$hbil" bench "$in" -o "$out/$name" -q --runs "$runs" \
    --ref "indirect=$ref:DiffCol*DiffInd" --ref "composite=$ref:Combined" "${presets[@]}" > /dev/null
  if [ -n "${EMISSION:-}" ]; then
    python3 - "$out/$name/bench.json" "$name" <<'PY'
import json, sys
configs = {c["name"]: c["layers"] for c in json.load(open(sys.argv[1]))["configurations"]}
cells = [sys.argv[2]]
for before, after in (("default_gathered", "default"), ("interior_cal_gathered", "interior_cal")):
    b, a = configs[before], configs[after]
    cells.append("%.2f → %.2f dB" % (b["composite"]["psnr"], a["composite"]["psnr"]))
    cells.append("%.3f → %.3f" % (b["indirect"]["relative_rmse"], a["indirect"]["relative_rmse"]))
    cells.append("%.2f → %.2f" % (b["indirect"]["energy"], a["indirect"]["energy"]))
print("| " + " | ".join(cells) + " |")
PY
  else
    python3 bench/tables.py "$out/$name" --prefix "$name" \
      --label "default=default | none" --label "interior=interior | none" \
      --label "calibrated=default | $(basename "$cal")" \
      --label "interior_calibrated=interior | $(basename "$cal")" \
      --label "calibrated_one=default | $(basename "$cal"), one factor" \
      --label "interior_calibrated_one=interior | $(basename "$cal"), one factor" \
      indirect:rmp composite:rmp s
  fi
done
echo
echo "(load at end $(cut -d' ' -f1-3 /proc/loadavg))"
