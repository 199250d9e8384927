#!/usr/bin/env bash
# measure.sh: the numbers in README.md, from commands anyone can rerun.
#   bench/measure.sh [BUILD_DIR]     (default: build)
# For each preset and Blender sample scene: hbil run (seconds per frame, from its summary
# line) and hbil compare of `ao` against the Cycles AO pass (RMSE, mean error, PSNR over all
# 8 frames). Then seconds per frame at 1920x1080 on a sample upscaled with oiiotool (timing
# only: upscaling blurs silhouettes, so no accuracy is claimed there).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
hbil="$build/hbil"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

echo "| scene | preset | AO RMSE | AO mean error | AO PSNR (dB) | s/frame (256x144) |"
echo "|---|---|---|---|---|---|"
for scene in courtyard room_poles; do
  for preset in fast default quality reference; do
    log=$("$hbil" run "samples/$scene/frame_####.exr" -o "$tmp/$scene-$preset/f_####.exr" \
      --preset "presets/$preset.json" 2>&1 | tail -n 1)
    spf=$(sed -n 's/.* \([0-9.]*\) s per frame.*/\1/p' <<<"$log")
    "$hbil" compare "$tmp/$scene-$preset/f_####.exr" "samples/$scene/frame_####.exr" \
      --layer ao --ref-layer AO --json >"$tmp/c.json"
    python3 - "$scene" "$preset" "$spf" "$tmp/c.json" <<'PY'
import json, sys
scene, preset, spf, path = sys.argv[1:]
o = json.load(open(path))["overall"]
print(f"| {scene} | {preset} | {o['rmse']:.4f} | {o['mean_error']:+.4f} | {o['psnr']:.2f} | {spf} |")
PY
  done
done

# Indirect light (work in progress, issue 3): AO, indirect (1 bounce) against Cycles
# DiffCol x DiffInd rendered with 1 diffuse bounce, and composite against Combined (main
# render, 8 bounces), for both occlusion methods at the default parameters.
echo
echo "| scene | method | AO PSNR | indirect vs 1-bounce DiffCol*DiffInd: RMSE / mean / PSNR | composite vs Combined: RMSE / mean / PSNR | s/frame |"
echo "|---|---|---|---|---|---|"
for scene in courtyard room_poles; do
  for method in horizon bitmask; do
    out="$tmp/gi-$scene-$method"
    log=$("$hbil" run "samples/$scene/frame_####.exr" -o "$out/f_####.exr" --set method=$method \
      --set 'outputs=["ao","irradiance","indirect","composite"]' 2>&1 | tail -n 1)
    spf=$(sed -n 's/.* \([0-9.]*\) s per frame.*/\1/p' <<<"$log")
    "$hbil" compare "$out/f_####.exr" "samples/$scene/frame_####.exr" --layer ao --ref-layer AO --json >"$tmp/a.json"
    "$hbil" compare "$out/f_####.exr" "samples/$scene/bounce1/frame_####.exr" --layer indirect \
      --ref-layer 'DiffCol*DiffInd' --json >"$tmp/i.json"
    "$hbil" compare "$out/f_####.exr" "samples/$scene/frame_####.exr" --layer composite \
      --ref-layer Combined --json >"$tmp/c.json"
    python3 - "$scene" "$method" "$spf" "$tmp/a.json" "$tmp/i.json" "$tmp/c.json" <<'PY'
import json, sys
scene, method, spf, a, i, c = sys.argv[1:]
a, i, c = (json.load(open(f))["overall"] for f in (a, i, c))
f = lambda o: f"{o['rmse']:.4f} / {o['mean_error']:+.4f} / {o['psnr']:.2f}"
print(f"| {scene} | {method} | {a['psnr']:.2f} | {f(i)} | {f(c)} | {spf} |")
PY
  done
done

# 1920x1080: frames 1-4 of room_poles upscaled, sidecars adjusted to the new resolution.
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
echo "1920x1080, room_poles frames 1-4 upscaled:"
for preset in fast default quality; do
  log=$("$hbil" run "$tmp/hd/frame_####.exr" -o "$tmp/hd-out/$preset/f_####.exr" \
    --preset "presets/$preset.json" 2>&1 | tail -n 1)
  echo "  $preset: $log"
done
