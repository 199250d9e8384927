#!/usr/bin/env bash
# Build and render the hbil sample sequences from scratch.
#
#   samples/blender/render_all.sh                 # all scenes
#   samples/blender/render_all.sh courtyard       # one scene
#   MAIN_SAMPLES=128 BOUNCE1_SAMPLES=64 samples/blender/render_all.sh   # quick test
#
# Per scene: build the scene (Python, factory startup) -> render frames 1-8
# (main: 8 diffuse bounces, all passes) -> render the 1-bounce reference
# (bounce1/) -> render frame 1 again with another seed and estimate the
# per-pixel noise -> render the back faces (backfaces.py, 1 spp) -> repack every
# EXR (half / float, ZIP) -> add BackFaces.Depth.Z to the main frames -> check sidecars
# (reprojection of Position, standalone export_camera.py == render-time).
# Needs: blender (3.4), python3 with OpenImageIO + numpy (Debian:
# python3-openimageio python3-numpy).  Logs and scratch go to $WORK.
set -euo pipefail

# ---- settings -------------------------------------------------------------
MAIN_SAMPLES=${MAIN_SAMPLES:-512}      # spp, main render (8 diffuse bounces)
BOUNCE1_SAMPLES=${BOUNCE1_SAMPLES:-512} # spp, 1-bounce reference
NOISE_SAMPLES=${NOISE_SAMPLES:-$MAIN_SAMPLES}  # spp of the 2nd-seed noise frame
SEED=${SEED:-1}                        # fixed Cycles seed of the sequences
NOISE_SEED=${NOISE_SEED:-2}            # seed of the extra noise-estimate frame
FRAMES=${FRAMES:-1-8}
NOISE_FRAME=${NOISE_FRAME:-1}
DO_NOISE=${DO_NOISE:-1}                # 0: skip the noise frame
BLENDER=${BLENDER:-blender}
PYTHON=${PYTHON:-/usr/bin/python3}     # needs OpenImageIO + numpy
# ---------------------------------------------------------------------------

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
SAMPLES=$(dirname "$HERE")
WORK=${WORK:-/tmp/hbil_samples_work}
mkdir -p "$WORK"
SCENES=("$@")
[ ${#SCENES[@]} -gt 0 ] || SCENES=(room_poles courtyard)

stamp() { date +%s; }
log() { echo "[$(date +%H:%M:%S)] $*"; }

blender_scene() {  # scene logname args...
  local scene=$1 logname=$2; shift 2
  local logf="$WORK/$scene.$logname.log"
  # Blender prints a progress line per tile/sample batch: keep them out of the log
  "$BLENDER" -b --factory-startup --python "$HERE/$scene.py" -- "$@" 2>&1 \
    | grep --line-buffered -v '^Fra:' > "$logf" || true
  if ! grep -q '^HBIL_TIMING' "$logf"; then
    echo "Blender failed, see $logf" >&2; tail -20 "$logf" >&2; exit 1
  fi
  grep '^HBIL_' "$logf" | sed "s|^|$scene/$logname: |" >> "$WORK/times.txt"
}

T_ALL=$(stamp)
: > "$WORK/times.txt"
for scene in "${SCENES[@]}"; do
  out="$SAMPLES/$scene"
  log "== $scene: clean $out"
  rm -rf "$out/bounce1"
  rm -f "$out"/frame_*.exr "$out"/frame_*.camera.json "$out"/noise_estimate.json
  mkdir -p "$out"

  log "$scene: main render, $MAIN_SAMPLES spp, frames $FRAMES"
  t=$(stamp)
  blender_scene "$scene" main --out "$out" --mode main --samples "$MAIN_SAMPLES" \
    --seed "$SEED" --frames "$FRAMES" --save-blend "$WORK/$scene.blend"
  log "$scene: main done in $(( $(stamp) - t )) s"

  log "$scene: bounce1 render, $BOUNCE1_SAMPLES spp"
  t=$(stamp)
  blender_scene "$scene" bounce1 --out "$out/bounce1" --mode bounce1 \
    --samples "$BOUNCE1_SAMPLES" --seed "$SEED" --frames "$FRAMES"
  log "$scene: bounce1 done in $(( $(stamp) - t )) s"

  if [ "$DO_NOISE" = 1 ]; then
    log "$scene: noise frame $NOISE_FRAME, seed $NOISE_SEED"
    rm -rf "$WORK/noise_$scene"
    blender_scene "$scene" noise --out "$WORK/noise_$scene" --mode main \
      --samples "$NOISE_SAMPLES" --seed "$NOISE_SEED" --frames "$NOISE_FRAME"
    f=$(printf 'frame_%04d.exr' "$NOISE_FRAME")
    "$PYTHON" "$HERE/noise_estimate.py" "$out/$f" "$WORK/noise_$scene/$f" \
      --json "$out/noise_estimate.json" | tee "$WORK/$scene.noise.txt"
  fi

  log "$scene: back faces (1 spp) -> BackFaces.Depth.Z in the main frames"
  rm -rf "$WORK/back_$scene"
  blender_scene "$scene" backfaces --out "$WORK/back_$scene" --mode backfaces --samples 1 \
    --seed "$SEED" --frames "$FRAMES"

  log "$scene: repack"
  "$PYTHON" "$HERE/repack_exr.py" "$out"/frame_*.exr > "$WORK/$scene.repack.log"
  # Blender writes Combined even with the pass off: drop it from the 1-bounce files
  "$PYTHON" "$HERE/repack_exr.py" --drop Combined "$out"/bounce1/frame_*.exr \
    >> "$WORK/$scene.repack.log"
  tail -n 2 "$WORK/$scene.repack.log"
  "$PYTHON" "$HERE/merge_backdepth.py" "$out" "$WORK/back_$scene" | tee "$WORK/$scene.back.txt"

  log "$scene: check sidecars"
  "$PYTHON" "$HERE/check_sidecar.py" "$out"/frame_*.exr | tee "$WORK/$scene.check.txt"
  rm -rf "$WORK/sidecar_$scene"
  "$BLENDER" -b "$WORK/$scene.blend" --python "$HERE/export_camera.py" -- \
    --output "$WORK/sidecar_$scene/frame_####.exr" --frames "$FRAMES" > /dev/null 2>&1
  for j in "$WORK/sidecar_$scene"/*.camera.json; do
    cmp -s "$j" "$out/$(basename "$j")" || { echo "standalone sidecar differs: $j" >&2; exit 1; }
  done
  log "$scene: standalone export_camera.py reproduces all sidecars"
done

log "total $(( $(stamp) - T_ALL )) s"
grep HBIL_TIMING "$WORK/times.txt" || true
du -sh "$SAMPLES"
