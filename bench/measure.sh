#!/usr/bin/env bash
# measure.sh: the numbers in README.md, from commands anyone can rerun.
#   bench/measure.sh [BUILD_DIR]          (default: build)
#   HELDOUT=/path/to/study bench/measure.sh   also measure a scene rendered with
#       samples/blender/study.py (frames 1-4 + bounce1/; README "Held-out scene")
#   HELDOUT_MOVE=dir HELDOUT_CUT=dir bench/measure.sh   also run the temporal chain on camera
#       moves rendered with samples/blender/study_shots.py (--shot move, frames 1-16; --shot cut,
#       frames 1-12), which nothing was tuned on
#   ONLY_POVRAY=1 bench/measure.sh        only the POV-Ray tables
#   HELDOUT_POV=/tmp/pov_study bench/measure.sh   also the held-out POV-Ray scene
#       (samples/povray/study.pov, rendered as its header says); HELDOUT_POV_NOSKY=dir adds
#       the same scene rendered without its HBIL_Sky line (--reference --bounces 1)
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

# pov_rows MAIN B1 CFG...: the table of a POV-Ray scene imported into MAIN (3-bounce reference)
# and B1 (1-bounce reference); each CFG is "label|hbil run options". Prints the header too.
pov_rows() {
  local main=$1 b1=$2 cfg label args name spf i1 i3 c
  shift 2
  echo "| run | indirect vs 1 bounce RMSE / mean / PSNR | indirect vs 3 bounces PSNR | composite RMSE / mean / PSNR | s/frame |"
  echo "|---|---|---|---|---|"
  for cfg in "$@"; do
    label=${cfg%%|*} args=${cfg#*|}
    name="pov-$(basename "$(dirname "$main")")-${#label}-${#args}"
    # shellcheck disable=SC2086
    spf=$(eval run "$name" "'$main'" $args)
    i1=$(cmp "$name" "$b1" indirect 'DiffCol*DiffInd')
    i3=$(cmp "$name" "$main" indirect 'DiffCol*DiffInd')
    c=$(cmp "$name" "$main" composite Combined)
    echo "| $label | $i1 | $(psnr "$i3") | $c | $spf |"
  done
}

# POV-Ray sample (samples/povray_room): the committed passes imported twice, with the
# 3-bounce radiosity reference and with the 1-bounce one (bounce1/).
povray_table() {
  local pov=samples/povray_room
  "$hbil" import-povray -q "$pov/passes" -o "$tmp/pov/frame_####.exr"
  "$hbil" import-povray -q "$pov/passes" --reference-dir "$pov/bounce1" -o "$tmp/pov1/frame_####.exr"
  echo
  echo "POV-Ray room (samples/povray_room, 6 frames), indirect against the radiosity"
  echo "DiffCol*DiffInd with 1 and with 3 bounces, composite against the 3-bounce Combined:"
  echo
  pov_rows "$tmp/pov/frame_####.exr" "$tmp/pov1/frame_####.exr" \
    "temporal chain (default)|" \
    "single frames, bitmask, back-face thickness|--set temporal=false" \
    "single frames, bitmask, no back-face layer (thickness auto)|--set temporal=false --set passes.backdepth=\"\"" \
    "single frames, horizon|--set temporal=false --set method=horizon" \
    "temporal chain, 2 in-frame bounces|--set bounces=2" \
    "temporal chain, 3 in-frame bounces|--set bounces=3"
  # A scene of a user's own: samples/povray/study.pov, never used for tuning, rendered as its
  # header says into $HELDOUT_POV (with --reference) and ${HELDOUT_POV}_b1 (--bounces 1).
  [ -n "${HELDOUT_POV:-}" ] || return 0
  "$hbil" import-povray -q "$HELDOUT_POV/passes" --reference-dir "${HELDOUT_POV}_b1/passes" \
    -o "$tmp/povs1/frame_####.exr"
  echo
  echo "Held-out POV-Ray scene $HELDOUT_POV (samples/povray/study.pov, 8 frames, 320x180):"
  echo
  pov_rows "$HELDOUT_POV/frame_####.exr" "$tmp/povs1/frame_####.exr" \
    "temporal chain (default)|" "single frames|--set temporal=false" \
    "temporal chain, far field from the sky the kit exported (--sky 512x256)|--set 'environment=\"$HELDOUT_POV/sky.exr\"'"
  # The same scene without its sky (study.pov minus the HBIL_Sky line, rendered with
  # --reference --bounces 1 into $HELDOUT_POV_NOSKY): how much of the gap is the sky.
  [ -n "${HELDOUT_POV_NOSKY:-}" ] || return 0
  local spf i1 c
  spf=$(run povns "$HELDOUT_POV_NOSKY/frame_####.exr")
  i1=$(cmp povns "$HELDOUT_POV_NOSKY/frame_####.exr" indirect 'DiffCol*DiffInd')
  c=$(cmp povns "$HELDOUT_POV_NOSKY/frame_####.exr" composite Combined)
  echo "| temporal chain (default), scene without its sky (1-bounce reference) | $i1 | | $c | $spf |"
  echo
  echo "- 1-bounce DiffCol*DiffInd with the sky minus without it, RMSE / mean / PSNR:" \
    "$("$hbil" compare "$tmp/povs1/frame_####.exr" "$HELDOUT_POV_NOSKY/frame_####.exr" \
      --layer 'DiffCol*DiffInd' --ref-layer 'DiffCol*DiffInd' --json | python3 -c 'import json,sys
o=json.load(sys.stdin)["overall"]; print("%.4f / %+.4f / %.2f" % (o["rmse"], o["mean_error"], o["psnr"]))')"
}
if [ -n "${ONLY_POVRAY:-}" ]; then
  povray_table
  exit 0
fi

echo "Single frames (--set temporal=false), AO and bent cones only (outputs [\"ao\",\"bentcone\"]),"
echo "ao against the Cycles AO pass:"
echo
echo "| scene | preset | AO RMSE / mean / PSNR (dB) | s/frame (256x144) |"
echo "|---|---|---|---|"
for scene in courtyard room_poles; do
  for preset in fast default quality reference; do
    in="samples/$scene/frame_####.exr"
    spf=$(run "ao-$scene-$preset" "$in" --preset "presets/$preset.json" \
      --set 'outputs=["ao","bentcone"]' --set temporal=false)
    echo "| $scene | $preset | $(cmp "ao-$scene-$preset" "$in" ao AO) | $spf |"
  done
done

# gi SCENE_DIR FRAMES: AO, indirect against the 1-bounce reference and composite against
# Combined for the occlusion models, all else default (outputs "auto").
gi() {
  local dir=$1 scene
  scene=$(basename "$dir")
  for cfg in "horizon|--set method=horizon" \
    "bitmask, no back-face layer (thickness auto)|--set passes.backdepth=\"\"" \
    "bitmask, back-face thickness (default)|"; do
    local label=${cfg%%|*} args=${cfg#*|} name spf a i c
    name="gi-$scene-${label%%,*}-${#args}"
    # shellcheck disable=SC2086
    spf=$(eval run "$name" "'$dir/frame_####.exr'" --set temporal=false $args)
    a=$(cmp "$name" "$dir/frame_####.exr" ao AO)
    i=$(cmp "$name" "$dir/bounce1/frame_####.exr" indirect 'DiffCol*DiffInd')
    c=$(cmp "$name" "$dir/frame_####.exr" composite Combined)
    echo "| $scene | $label | $(psnr "$a") | $i | $c | $spf |"
  done
}
echo
echo "Single frames (--set temporal=false), default outputs (ao, bentcone, irradiance, indirect,"
echo "composite), one in-frame bounce;"
echo "indirect against Cycles DiffCol*DiffInd rendered with 1 diffuse bounce, composite"
echo "against Cycles Combined (8 bounces):"
echo
echo "| scene | occlusion | AO PSNR | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
echo "|---|---|---|---|---|---|"
gi samples/courtyard
gi samples/room_poles

echo
echo "Single frames (--set temporal=false), in-frame bounces, against the 8-bounce render: indirect against"
echo "DiffCol*DiffInd, composite against Combined:"
echo
echo "| scene | bounces | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
echo "|---|---|---|---|---|"
for scene in courtyard room_poles; do
  for b in 1 2 3 4; do
    in="samples/$scene/frame_####.exr"
    spf=$(run "b-$scene-$b" "$in" --set bounces=$b --set 'outputs=["indirect","composite"]' \
      --set temporal=false)
    echo "| $scene | $b | $(cmp "b-$scene-$b" "$in" indirect 'DiffCol*DiffInd') |" \
      "$(cmp "b-$scene-$b" "$in" composite Combined) | $spf |"
  done
done

povray_table

# The temporal chain (the default) against single frames on the camera moves.
py=${PYTHON:-/usr/bin/python3}  # with OpenImageIO and numpy (python3-openimageio)
echo
echo "Temporal chain (default) against single frames (--set temporal=false), all 8 frames:"
echo
echo "| scene | run | AO PSNR | indirect vs 1-bounce PSNR | indirect vs 8-bounce PSNR | composite vs Combined PSNR | s/frame |"
echo "|---|---|---|---|---|---|---|"
for scene in courtyard room_poles; do
  in="samples/$scene/frame_####.exr"
  for cfg in "single frames|--set temporal=false" "temporal (default)|"; do
    label=${cfg%%|*} args=${cfg#*|} name="t-$scene-${#cfg}"
    # shellcheck disable=SC2086
    spf=$(run "$name" "$in" $args)
    echo "| $scene | $label | $(psnr "$(cmp "$name" "$in" ao AO)") |" \
      "$(psnr "$(cmp "$name" "samples/$scene/bounce1/frame_####.exr" indirect 'DiffCol*DiffInd')") |" \
      "$(psnr "$(cmp "$name" "$in" indirect 'DiffCol*DiffInd')") |" \
      "$(psnr "$(cmp "$name" "$in" composite Combined)") | $spf |"
  done
done

# frames PSNR of indirect against the 8-bounce DiffCol*DiffInd, frame by frame.
per_frame() {
  "$hbil" compare "$tmp/$1/f_####.exr" "$2" --layer indirect --ref-layer 'DiffCol*DiffInd' \
    --json | python3 -c 'import json,sys
print(" / ".join("%.2f" % f["psnr"] for f in json.load(sys.stdin)["frames"]))'
}
echo
echo "Static camera (samples/room_static, 6 identical Cycles frames): flicker = mean |composite_k -"
echo "composite_(k-1)| / mean composite; indirect against the 8-bounce DiffCol*DiffInd, frame by frame:"
echo
echo "| run | flicker | indirect PSNR, frames 1-6 |"
echo "|---|---|---|"
in="samples/room_static/frame_####.exr"
for cfg in "single frames (temporal=false)|--set temporal=false" \
  "temporal, no accumulation (history_max=1)|--set history_max=1" \
  "temporal, no feedback|--set feedback=false" "temporal (default)|"; do
  label=${cfg%%|*} args=${cfg#*|} name="s-${#cfg}"
  # shellcheck disable=SC2086
  run "$name" "$in" $args >/dev/null
  echo "| $label | $("$py" bench/stability.py flicker "$tmp/$name/f_####.exr" 1-6) |" \
    "$(per_frame "$name" "$in") |"
done

echo
echo "Camera moves, frame by frame, indirect against the 8-bounce DiffCol*DiffInd (temporal default):"
echo
for scene in courtyard room_poles; do
  in="samples/$scene/frame_####.exr"
  run "pf-$scene" "$in" >/dev/null
  echo "- $scene: $(per_frame "pf-$scene" "$in") dB"
done

echo
echo "Disocclusions (history.Y = 1 after frame 1): indirect RMSE against the 8-bounce render inside"
echo "them and elsewhere, and their share of the geometry pixels:"
echo
echo "| scene | RMSE newly revealed | RMSE elsewhere | share (%) |"
echo "|---|---|---|---|"
for scene in courtyard room_poles; do
  in="samples/$scene/frame_####.exr"
  run "d-$scene" "$in" --set 'outputs=["auto","history"]' >/dev/null
  read -r a b c < <("$py" bench/stability.py disocclusion "$tmp/d-$scene/f_####.exr" "$in" 1-8)
  echo "| $scene | $a | $b | $c |"
done

echo
echo "Hard cut (samples/room_cut, cut at frame 4), indirect against the 8-bounce render:"
echo
in="samples/room_cut/frame_####.exr"
"$hbil" run "$in" -o "$tmp/cut/f_####.exr" --no-display 2>&1 | grep 'cut (' | sed 's/^/    /'
"$hbil" run "$in" -o "$tmp/cut-fresh/f_####.exr" --no-display --frames 4-6 -q
echo "- frame by frame (temporal): $(per_frame cut "$in") dB"
run cut-single "$in" --set temporal=false >/dev/null
echo "- frame by frame (single frames): $(per_frame cut-single "$in") dB"
"$hbil" compare "$tmp/cut/f_####.exr" "$tmp/cut-fresh/f_####.exr" --layer composite \
  --mask none --frames 4-4 --json | python3 -c 'import json,sys
print("- frame 4 against a run that starts at frame 4: RMSE %g" % json.load(sys.stdin)["overall"]["rmse"])'

if [ -n "${HELDOUT:-}" ]; then
  echo
  echo "Held-out scene $HELDOUT (default preset, never used for tuning):"
  echo
  echo "| scene | occlusion | AO PSNR | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
  echo "|---|---|---|---|---|---|"
  gi "$HELDOUT"
  h=$(basename "$HELDOUT")
  spf=$(run "h-temporal" "$HELDOUT/frame_####.exr")
  echo "| $h | temporal chain (default) | $(psnr "$(cmp h-temporal "$HELDOUT/frame_####.exr" ao AO)") |" \
    "$(cmp h-temporal "$HELDOUT/bounce1/frame_####.exr" indirect 'DiffCol*DiffInd') |" \
    "$(cmp h-temporal "$HELDOUT/frame_####.exr" composite Combined) | $spf |"
fi

if [ -n "${HELDOUT_MOVE:-}" ]; then
  mv_in="$HELDOUT_MOVE/frame_####.exr"
  echo
  echo "Never-seen camera move $HELDOUT_MOVE (16 frames), indirect against its 8-bounce"
  echo "DiffCol*DiffInd frame by frame, and frame-to-frame change of composite against Cycles'"
  echo "Combined (hbil / Cycles / ratio):"
  echo
  echo "| run | indirect PSNR per frame | overall | composite vs Combined PSNR | change hbil / Cycles / ratio |"
  echo "|---|---|---|---|---|"
  for cfg in "single frames|--set temporal=false" "temporal (default)|"; do
    label=${cfg%%|*} args=${cfg#*|} name="hm-${#cfg}"
    # shellcheck disable=SC2086
    run "$name" "$mv_in" $args >/dev/null
    echo "| $label | $(per_frame "$name" "$mv_in") | $(psnr "$(cmp "$name" "$mv_in" indirect 'DiffCol*DiffInd')") |" \
      "$(psnr "$(cmp "$name" "$mv_in" composite Combined)") |" \
      "$("$py" bench/stability.py changes "$tmp/$name/f_####.exr" "$mv_in" 1-16 | sed 's| | / |g') |"
  done
  whole=$name  # the last run: temporal (default)
  "$hbil" run "$mv_in" -o "$tmp/hm-chunk/f_####.exr" --no-display --frames 11-16 --preroll 4 -q
  for layer in ao irradiance composite; do
    "$hbil" compare "$tmp/hm-chunk/f_####.exr" "$tmp/$whole/f_####.exr" --layer $layer \
      --mask none --frames 11-16 --json | python3 -c 'import json,sys
print("- chunk 11-16 with 4 frames of pre-roll against the whole run, '"$layer"': RMS %.4f" % json.load(sys.stdin)["overall"]["rmse"])'
  done
fi
if [ -n "${HELDOUT_CUT:-}" ]; then
  ct_in="$HELDOUT_CUT/frame_####.exr"
  echo
  echo "Never-seen hard cut $HELDOUT_CUT (12 frames, cut at frame 7), indirect against its"
  echo "8-bounce render frame by frame:"
  echo
  "$hbil" run "$ct_in" -o "$tmp/hc/f_####.exr" --no-display 2>&1 | grep 'cut (' | sed 's/^/    /'
  echo "- temporal: $(per_frame hc "$ct_in") dB"
  run hc-single "$ct_in" --set temporal=false >/dev/null
  echo "- single frames: $(per_frame hc-single "$ct_in") dB"
fi

# Speed at 256x144, 1920x1080 and 3840x2160 on real renders: bench/speed.sh.
