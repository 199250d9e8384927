#!/usr/bin/env bash
# search_scale.sh: what searching one pixel in n x n costs in accuracy and saves in time
# (README "The reduced search").
#
#   bench/search_scale.sh DIR [DIR ...]        (HBIL=build/hbil, SCALES="1 2 3" by default)
#
# Each DIR holds frame_0001.exr (+ sidecar): a render of a scene script with its AO pass and
# back faces merged, e.g. at 1920x1080 with 64 spp:
#   blender -b --factory-startup --python samples/blender/room_poles.py -- --out DIR \
#     --mode main --samples 64 --seed 1 --frames 1-1 --size 1920x1080
#   (and --mode backfaces --samples 1 into DIR_back; repack_exr.py; merge_backdepth.py)
# The frame is both hbil's input and its reference. For every n in SCALES: `hbil run -v
# --set temporal=false --set search_scale=n` (a single frame) and `hbil compare` of ao
# against AO, indirect against DiffCol*DiffInd and composite against Combined (PSNR in dB
# over the non-background pixels); compute as `hbil run -v` reports it.
set -euo pipefail
cd "$(dirname "$0")/.."
hbil=${HBIL:-build/hbil}
scales=${SCALES:-1 2 3}
t=$(mktemp -d)
trap 'rm -rf "$t"' EXIT
psnr() {
  "$hbil" compare "$t/o.exr" "$1" --layer "$2" --ref-layer "$3" --json |
    python3 -c 'import json,sys; print("%.2f" % json.load(sys.stdin)["overall"]["psnr"])'
}
echo "- load at start: $(uptime | sed 's/.*load average: //')"
echo "| scene | search_scale | ao | indirect | composite | compute ms |"
echo "|---|---|---|---|---|---|"
for dir in "$@"; do
  ref="$dir/frame_0001.exr"
  for n in $scales; do
    rm -f "$t/o.exr"
    ms=$("$hbil" run "$ref" -o "$t/o.exr" --no-display -v --set temporal=false \
      --set search_scale="$n" 2>&1 | sed -n 's/.*compute \([0-9]*\) ms.*/\1/p')
    echo "| $(basename "$dir") | $n | $(psnr "$ref" ao AO) | $(psnr "$ref" indirect 'DiffCol*DiffInd') | $(psnr "$ref" composite Combined) | $ms |"
  done
done
echo "- load at end: $(uptime | sed 's/.*load average: //')"
