#!/usr/bin/env bash
# emission.sh: the Emit pass gathered as light or not (`emission`; README "Emitting surfaces"),
# every figure from `hbil bench`.
#
#   bench/emission.sh NAME=SHOT_DIR=CALIBRATION[=REF_DIR] ... [BUILD_DIR via BUILD=build]
#
# For each scene NAME: SHOT_DIR/frame_####.exr holds its frames, REF_DIR/frame_####.exr (default
# SHOT_DIR) its 8-bounce reference (Combined, DiffCol, DiffInd), CALIBRATION a low-sample render
# with global illumination of some of its frames (as bench/calibration.sh takes it). One bench
# per scene, four configurations alternating in RUNS timed runs (default 1): the default preset
# with `emission` "gathered" and with its default "auto", and presets/interior.json with
# `calibration`, each way. Prints one row per scene: composite PSNR, indirect relative RMSE
# and indirect energy (sum of indirect over the sum of DiffCol x DiffInd), gathered -> auto.
#   OUT=/tmp/em bench/emission.sh ...   keep each bench's folder there
set -euo pipefail
cd "$(dirname "$0")/.."
hbil="${BUILD:-build}/hbil"
runs=${RUNS:-1}
if [ -n "${OUT:-}" ]; then
  out=$OUT
  mkdir -p "$out"
else
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi
[ $# -gt 0 ] || { echo "usage: bench/emission.sh NAME=SHOT_DIR=CALIBRATION[=REF_DIR] ..." >&2; exit 2; }
echo "(machine: $(nproc) cores, load at start $(cut -d' ' -f1-3 /proc/loadavg))"
echo
echo "| scene | default: composite PSNR | indirect relative RMSE | indirect energy | interior + calibration: composite PSNR | indirect relative RMSE | indirect energy |"
echo "|---|---|---|---|---|---|---|"
for arg in "$@"; do
  IFS='=' read -r name dir cal ref <<< "$arg"
  ref=${ref:-$dir}
  [ -n "$cal" ] && [ -f "$dir/frame_0001.exr" ] ||
    { echo "emission.sh: expected NAME=SHOT_DIR=CALIBRATION[=REF_DIR], got $arg" >&2; exit 2; }
  p="$out/$name.presets"
  mkdir -p "$p"
  echo '{"emission": "gathered"}' > "$p/default_gathered.json"
  echo '{}' > "$p/default.json"
  echo "{\"unseen_carry\": true, \"calibration\": \"$cal\", \"emission\": \"gathered\"}" \
    > "$p/interior_cal_gathered.json"
  echo "{\"unseen_carry\": true, \"calibration\": \"$cal\"}" > "$p/interior_cal.json"
  "$hbil" bench "$dir/frame_####.exr" -o "$out/$name" -q --runs "$runs" \
    --ref "indirect=$ref/frame_####.exr:DiffCol*DiffInd" \
    --ref "composite=$ref/frame_####.exr:Combined" \
    --preset "$p/default_gathered.json" --preset "$p/default.json" \
    --preset "$p/interior_cal_gathered.json" --preset "$p/interior_cal.json" > /dev/null
  python3 - "$out/$name/bench.json" "$name" <<'EOF'
import json, sys
configs = {c["name"]: c["layers"] for c in json.load(open(sys.argv[1]))["configurations"]}
cells = [sys.argv[2]]
for before, after in (("default_gathered", "default"), ("interior_cal_gathered", "interior_cal")):
    b, a = configs[before], configs[after]
    cells.append("%.2f → %.2f dB" % (b["composite"]["psnr"], a["composite"]["psnr"]))
    cells.append("%.3f → %.3f" % (b["indirect"]["relative_rmse"], a["indirect"]["relative_rmse"]))
    cells.append("%.2f → %.2f" % (b["indirect"]["energy"], a["indirect"]["energy"]))
print("| " + " | ".join(cells) + " |")
EOF
done
echo
echo "(load at end $(cut -d' ' -f1-3 /proc/loadavg))"
