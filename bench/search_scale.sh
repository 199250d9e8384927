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
# The frame is both hbil's input and its reference. Per DIR, one `hbil bench` of the single
# frame (--set temporal=false --sweep search_scale=<SCALES>, RUNS timed runs alternated,
# default 3): ao against AO, indirect against DiffCol*DiffInd and composite against Combined
# (PSNR in dB over the non-background pixels, colour on R, G, B); compute: bench's median
# compute stage.
set -euo pipefail
cd "$(dirname "$0")/.."
hbil=${HBIL:-build/hbil}
scales=${SCALES:-1 2 3}
runs=${RUNS:-3}
t=$(mktemp -d)
trap 'rm -rf "$t"' EXIT
echo "- load at start: $(uptime | sed 's/.*load average: //')"
echo "| scene | search_scale | ao | indirect | composite | compute ms |"
echo "|---|---|---|---|---|---|"
for dir in "$@"; do
  ref="$dir/frame_0001.exr"
  name=$(basename "$dir")
  "$hbil" bench "$ref" -o "$t/$name" -q --runs "$runs" --set temporal=false \
    --sweep "search_scale=$(echo $scales | tr ' ' ,)" --ref "ao=$ref:AO" \
    --ref "indirect=$ref:DiffCol*DiffInd" --ref "composite=$ref:Combined" > /dev/null
  python3 - "$t/$name/bench.json" "$name" <<'PY'
import json, sys
for c in json.load(open(sys.argv[1]))["configurations"]:
    L = c["layers"]
    print("| %s | %s | %.2f | %.2f | %.2f | %.0f |" % (
        sys.argv[2], c["name"].split("search_scale=")[1], L["ao"]["psnr"],
        L["indirect"]["psnr"], L["composite"]["psnr"], c["stages_ms"]["compute"]))
PY
done
echo "- load at end: $(uptime | sed 's/.*load average: //')"
