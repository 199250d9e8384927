#!/usr/bin/env bash
# measure.sh: the numbers in README.md, from commands anyone can rerun.
#   bench/measure.sh [BUILD_DIR]          (default: build)
#   HELDOUT=/path/to/study bench/measure.sh   also measure a scene rendered with
#       samples/blender/study.py (frames 1-4 + bounce1/; README "Held-out scene")
#   SKIP_HD=1 bench/measure.sh            skip the 1920x1080 timings
# Every accuracy figure is `hbil compare` (RMSE, mean error, PSNR with peak 1, over the
# non-background pixels of all frames); every time is the "s per frame" of `hbil run`'s
# summary line (reading, camera, computing, writing; display PNGs off).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
hbil="$build/hbil"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# run NAME INPUT_PATTERN [hbil run options...]: runs hbil, prints its s/frame.
run() {
  local name=$1 input=$2
  shift 2
  "$hbil" run "$input" -o "$tmp/$name/f_####.exr" --no-display "$@" 2>&1 | tail -n 1 |
    sed -n 's/.* \([0-9.]*\) s per frame.*/\1/p'
}
# cmp NAME REFERENCE_PATTERN LAYER REF_LAYER: "rmse / mean / psnr".
cmp() {
  "$hbil" compare "$tmp/$1/f_####.exr" "$2" --layer "$3" --ref-layer "$4" --json |
    python3 -c 'import json,sys; o=json.load(sys.stdin)["overall"]
print("%.4f / %+.4f / %.2f" % (o["rmse"], o["mean_error"], o["psnr"]))'
}
psnr() { sed 's|.* / ||' <<<"$1"; }

echo "AO and bent cones only (outputs [\"ao\",\"bentcone\"]), ao against the Cycles AO pass:"
echo
echo "| scene | preset | AO RMSE / mean / PSNR (dB) | s/frame (256x144) |"
echo "|---|---|---|---|"
for scene in courtyard room_poles; do
  for preset in fast default quality reference; do
    in="samples/$scene/frame_####.exr"
    spf=$(run "ao-$scene-$preset" "$in" --preset "presets/$preset.json" \
      --set 'outputs=["ao","bentcone"]')
    echo "| $scene | $preset | $(cmp "ao-$scene-$preset" "$in" ao AO) | $spf |"
  done
done

# gi SCENE_DIR FRAMES: AO, indirect against the 1-bounce reference and composite against
# Combined for the occlusion models, all else default (outputs "auto").
gi() {
  local dir=$1 scene
  scene=$(basename "$dir")
  for cfg in "horizon|--set method=horizon" \
    "bitmask, constant thickness 0.4|--set passes.backdepth=\"\"" \
    "bitmask, back-face thickness (default)|"; do
    local label=${cfg%%|*} args=${cfg#*|} name spf a i c
    name="gi-$scene-${label%%,*}-${#args}"
    # shellcheck disable=SC2086
    spf=$(eval run "$name" "'$dir/frame_####.exr'" $args)
    a=$(cmp "$name" "$dir/frame_####.exr" ao AO)
    i=$(cmp "$name" "$dir/bounce1/frame_####.exr" indirect 'DiffCol*DiffInd')
    c=$(cmp "$name" "$dir/frame_####.exr" composite Combined)
    echo "| $scene | $label | $(psnr "$a") | $i | $c | $spf |"
  done
}
echo
echo "Default outputs (ao, bentcone, irradiance, indirect, composite), one in-frame bounce;"
echo "indirect against Cycles DiffCol*DiffInd rendered with 1 diffuse bounce, composite"
echo "against Cycles Combined (8 bounces):"
echo
echo "| scene | occlusion | AO PSNR | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
echo "|---|---|---|---|---|---|"
gi samples/courtyard
gi samples/room_poles

echo
echo "In-frame bounces (default otherwise), against the 8-bounce render: indirect against"
echo "DiffCol*DiffInd, composite against Combined:"
echo
echo "| scene | bounces | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
echo "|---|---|---|---|---|"
for scene in courtyard room_poles; do
  for b in 1 2 3 4; do
    in="samples/$scene/frame_####.exr"
    spf=$(run "b-$scene-$b" "$in" --set bounces=$b --set 'outputs=["indirect","composite"]')
    echo "| $scene | $b | $(cmp "b-$scene-$b" "$in" indirect 'DiffCol*DiffInd') |" \
      "$(cmp "b-$scene-$b" "$in" composite Combined) | $spf |"
  done
done

if [ -n "${HELDOUT:-}" ]; then
  echo
  echo "Held-out scene $HELDOUT (default preset, never used for tuning):"
  echo
  echo "| scene | occlusion | AO PSNR | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
  echo "|---|---|---|---|---|---|"
  gi "$HELDOUT"
fi

[ -n "${SKIP_HD:-}" ] && exit 0
# 1920x1080: frames 1-4 of room_poles upscaled, sidecars adjusted to the new resolution
# (timing only: upscaling blurs silhouettes, so no accuracy is claimed there).
mkdir -p "$tmp/hd"
for f in 1 2 3 4; do
  n=$(printf %04d $f)
  oiiotool "samples/room_poles/frame_$n.exr" --resize 1920x1080 -o "$tmp/hd/frame_$n.exr"
  python3 - "samples/room_poles/frame_$n.camera.json" "$tmp/hd/frame_$n.camera.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1])); j["resolution"] = [1920, 1080]
json.dump(j, open(sys.argv[2], "w"))
PY
done
echo
echo "1920x1080 (room_poles frames 1-4 upscaled), s/frame:"
echo
echo "| preset | ao + bentcone | default outputs |"
echo "|---|---|---|"
for preset in fast default quality; do
  a=$(run "hd-ao-$preset" "$tmp/hd/frame_####.exr" --preset "presets/$preset.json" \
    --set 'outputs=["ao","bentcone"]')
  g=$(run "hd-gi-$preset" "$tmp/hd/frame_####.exr" --preset "presets/$preset.json")
  echo "| $preset | $a | $g |"
done
