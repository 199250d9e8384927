#!/usr/bin/env bash
# seam.sh: how far a farm chunk's first frame is from a whole run's, against its pre-roll.
#
#   SHOT=/tmp/long/study PREROLLS="0 4 8 12 16 24 32" bench/seam.sh build/hbil [--set k=v ...]
#
# SHOT holds frame_####.exr (e.g. 64 frames of samples/blender/study_shots.py --shot long,
# rendered as samples/README.md says). A whole run over frames 1 to START+3 (START default
# 41), then for each pre-roll P a chunk START..START+3 with --preroll P; prints the relative
# RMSE of the composite (sqrt(mean((chunk - whole)^2)) / sqrt(mean(whole^2)) over R, G, B) at
# the chunk's first frame and three frames later. Extra arguments go to every run.
set -euo pipefail
H=$(realpath "$1")
shift
shot=${SHOT:?SHOT=folder of frame_####.exr}
start=${START:-41}
prerolls=${PREROLLS:-0 4 8 12 16 24 32}
out=$(mktemp -d /tmp/hbil-seam.XXXXXX)
trap 'rm -rf "$out"' EXIT
"$H" run "$shot/frame_####.exr" -o "$out/whole/f_####.exr" --no-display -q "$@" \
  --frames "1-$((start + 3))"
rel() {
  /usr/bin/python3 - "$1" "$2" <<'PY'
import sys
import numpy as np
import OpenImageIO as oiio
def composite(path):
    b = oiio.ImageBuf(path)
    names = b.spec().channelnames
    idx = [i for i, n in enumerate(names) if n in ("composite.R", "composite.G", "composite.B")]
    return b.get_pixels(oiio.FLOAT)[..., idx].astype(np.float64)
a, r = composite(sys.argv[1]), composite(sys.argv[2])
print("%.6f" % (np.sqrt(np.mean((a - r) ** 2)) / np.sqrt(np.mean(r ** 2))))
PY
}
printf "%8s %12s %12s\n" preroll first "first+3"
for p in $prerolls; do
  "$H" run "$shot/frame_####.exr" -o "$out/p$p/f_####.exr" --no-display -q "$@" \
    --frames "$start-$((start + 3))" --preroll "$p"
  a=$(printf %04d "$start")
  b=$(printf %04d $((start + 3)))
  printf "%8s %12s %12s\n" "$p" "$(rel "$out/p$p/f_$a.exr" "$out/whole/f_$a.exr")" \
    "$(rel "$out/p$p/f_$b.exr" "$out/whole/f_$b.exr")"
done
