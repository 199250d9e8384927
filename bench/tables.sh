#!/usr/bin/env bash
# tables.sh: the accuracy tables of README.md, every figure from `hbil bench`.
#   bench/tables.sh [BUILD_DIR]               (default: build)
#   OUT=/tmp/tables bench/tables.sh            keep each bench's folder (bench.json, bench.csv,
#                                              chart.svg, chart.png) there (default: removed)
#   RUNS=3 bench/tables.sh                     timed runs per configuration (default 3),
#                                              alternated within each bench; medians
#   HELDOUT=/path/to/study bench/tables.sh     also a scene rendered with
#       samples/blender/study.py (frames 1-4 + bounce1/; README "Held-out scene")
#   HELDOUT_MOVE=dir HELDOUT_CUT=dir bench/tables.sh   also the temporal chain on the camera
#       moves of samples/blender/study_shots.py (--shot move, frames 1-16; --shot cut, 1-12)
#   ONLY_POVRAY=1 bench/tables.sh              only the POV-Ray tables
#   ONLY_UNSEEN=1 bench/tables.sh              only the unseen_radiance table (0, the default
#       "auto", presets/interior.json; fast with 0 and auto); UNSEEN="dir..." adds scenes
#       rendered with samples/blender/*.py
#       (frames with Combined and DiffCol*DiffInd of the 8-bounce render)
#   HELDOUT_POV=/tmp/pov_study bench/tables.sh   also the held-out POV-Ray scene
#       (samples/povray/study.pov, rendered as its header says); HELDOUT_POV_NOSKY=dir adds
#       the same scene rendered without its HBIL_Sky line (--reference --bounces 1)
# Each table is one `hbil bench` run (its configurations alternate in the timed runs), and
# bench/tables.py prints its rows from bench.json: RMSE, mean error and PSNR (peak 1) over the
# non-background pixels of all frames, colour layers on R, G, B; s/frame is the median wall
# clock per frame of `hbil run --no-display` computing the layers judged.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
hbil="$build/hbil"
runs=${RUNS:-3}
if [ -n "${OUT:-}" ]; then
  out=$OUT
  mkdir -p "$out"
else
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi
presets="$out/presets"
mkdir -p "$presets"

# preset NAME JSON: a configuration for bench (keys over the defaults), named NAME.
preset() { echo "$2" > "$presets/$1.json"; echo "$presets/$1.json"; }
single=$(preset single '{"temporal": false}')
temporal=$(preset temporal '{}')

# b NAME SHOT [bench options...]: one bench into $out/NAME. The tables measure the
# screen-space gather alone (unseen_radiance 0), except the unseen_radiance table, whose
# configurations set it (gather_only=() there).
gather_only=(--set unseen_radiance=0)
b() {
  local name=$1 shot=$2
  shift 2
  "$hbil" bench "$shot" -o "$out/$name" -q --runs "$runs" "${gather_only[@]}" "$@" > /dev/null
}
rows() { python3 bench/tables.py "$out/$1" "${@:2}"; }
load() { echo "(machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg))"; }

# pov_table NAME MAIN B1 [bench options]: a POV-Ray scene imported into MAIN (3-bounce
# reference) and B1 (1-bounce reference).
pov_table() {
  local name=$1 main=$2 b1=$3
  shift 3
  b "$name" "$main" --ref "indirect@1bounce=$b1:DiffCol*DiffInd" \
    --ref "indirect@3bounces=$main:DiffCol*DiffInd" --ref "composite=$main:Combined" "$@"
  echo "| run | indirect vs 1 bounce RMSE / mean / PSNR | indirect vs 3 bounces PSNR | composite RMSE / mean / PSNR | s/frame |"
  echo "|---|---|---|---|---|"
  rows "$name" "${labels[@]}" indirect@1bounce:rmp indirect@3bounces:psnr composite:rmp s
}

povray_table() {
  local pov=samples/povray_room
  "$hbil" import-povray -q "$pov/passes" -o "$out/pov/frame_####.exr"
  "$hbil" import-povray -q "$pov/passes" --reference-dir "$pov/bounce1" -o "$out/pov1/frame_####.exr"
  echo
  echo "POV-Ray room (samples/povray_room, 6 frames), indirect against the radiosity"
  echo "DiffCol*DiffInd with 1 and with 3 bounces, composite against the 3-bounce Combined $(load):"
  echo
  labels=(--label "temporal=temporal chain (default)"
    --label "single=single frames, bitmask, back-face thickness"
    --label "single_nobf=single frames, bitmask, no back-face layer (thickness auto)"
    --label "single_horizon=single frames, horizon"
    --label "bounces2=temporal chain, 2 in-frame bounces"
    --label "bounces3=temporal chain, 3 in-frame bounces")
  pov_table pov "$out/pov/frame_####.exr" "$out/pov1/frame_####.exr" \
    --preset "$temporal" --preset "$single" \
    --preset "$(preset single_nobf '{"temporal": false, "passes": {"backdepth": ""}}')" \
    --preset "$(preset single_horizon '{"temporal": false, "method": "horizon"}')" \
    --preset "$(preset bounces2 '{"bounces": 2}')" --preset "$(preset bounces3 '{"bounces": 3}')"
  # A scene of a user's own: samples/povray/study.pov, never used for tuning, rendered as its
  # header says into $HELDOUT_POV (with --reference) and ${HELDOUT_POV}_b1 (--bounces 1).
  [ -n "${HELDOUT_POV:-}" ] || return 0
  "$hbil" import-povray -q "$HELDOUT_POV/passes" --reference-dir "${HELDOUT_POV}_b1/passes" \
    -o "$out/povs1/frame_####.exr"
  echo
  echo "Held-out POV-Ray scene $HELDOUT_POV (samples/povray/study.pov, 8 frames, 320x180) $(load):"
  echo
  labels=(--label "temporal=temporal chain (default)" --label "single=single frames"
    --label "sky=temporal chain, far field from the sky the kit exported (--sky 512x256)")
  pov_table povs "$HELDOUT_POV/frame_####.exr" "$out/povs1/frame_####.exr" \
    --preset "$temporal" --preset "$single" \
    --preset "$(preset sky "{\"environment\": \"$HELDOUT_POV/sky.exr\"}")"
  # The same scene without its sky (study.pov minus the HBIL_Sky line, rendered with
  # --reference --bounces 1 into $HELDOUT_POV_NOSKY): how much of the gap is the sky.
  [ -n "${HELDOUT_POV_NOSKY:-}" ] || return 0
  local ns="$HELDOUT_POV_NOSKY/frame_####.exr"
  b povns "$ns" --preset "$temporal" --ref "indirect=$ns:DiffCol*DiffInd" \
    --ref "composite=$ns:Combined"
  echo
  echo "The same scene without its sky (1-bounce reference), temporal chain (default):"
  echo
  echo "| run | indirect vs 1 bounce RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
  echo "|---|---|---|---|"
  rows povns --label "temporal=without the sky" indirect:rmp composite:rmp s
  # The sky's share of the 1-bounce indirect light: the two references compared (no hbil).
  echo
  echo "- 1-bounce DiffCol*DiffInd with the sky minus without it (hbil compare, RMSE / mean /" \
    "PSNR): $("$hbil" compare "$out/povs1/frame_####.exr" "$ns" --layer 'DiffCol*DiffInd' \
      --ref-layer 'DiffCol*DiffInd' --json | python3 -c 'import json,sys
o=json.load(sys.stdin)["overall"]; print("%.4f / %+.4f / %.2f" % (o["rmse"], o["mean_error"], o["psnr"]))')"
}
# unseen_table: the default and fast presets with unseen_radiance 0, "auto" (their default)
# and, for the default, auto with unseen_carry (presets/interior.json), temporal chain, on the
# two samples, the POV-Ray room and every folder of $UNSEEN.
unseen_table() {
  local gather_only=()
  echo
  echo "unseen_radiance 0 against \"auto\" (the default: the elevations the frame does not show"
  echo "escape) and auto with unseen_carry (interior), for the default and fast presets, temporal"
  echo "chain, indirect against the full-GI render's DiffCol*DiffInd, composite against its"
  echo "Combined $(load):"
  echo
  echo "| scene | preset | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
  echo "|---|---|---|---|---|"
  "$hbil" import-povray -q samples/povray_room/passes -o "$out/povu/frame_####.exr"
  local dir in name
  for dir in samples/room_poles samples/courtyard "$out/povu" ${UNSEEN:-}; do
    in="$dir/frame_####.exr"
    name=$(basename "$dir")
    [ "$dir" = "$out/povu" ] && name="povray_room"
    b "unseen-$name" "$in" --ref "indirect=$in:DiffCol*DiffInd" --ref "composite=$in:Combined" \
      --preset "$(preset off '{"unseen_radiance": 0}')" --preset presets/default.json \
      --preset presets/interior.json \
      --preset "$(preset fast_off '{"method": "horizon", "slices": 1, "steps": 4, "unseen_radiance": 0}')" \
      --preset presets/fast.json
    rows "unseen-$name" --prefix "$name" --label "off=unseen_radiance 0" \
      --label "default=default (auto)" --label "interior=interior (auto, unseen_carry)" \
      --label "fast_off=fast, unseen_radiance 0" --label "fast=fast (auto)" \
      indirect:rmp composite:rmp s
  done
}

if [ -n "${ONLY_POVRAY:-}" ]; then
  povray_table
  exit 0
fi
if [ -n "${ONLY_UNSEEN:-}" ]; then
  unseen_table
  exit 0
fi

echo "Single frames (--set temporal=false), ao against the Cycles AO pass $(load):"
echo
echo "| scene | preset | AO RMSE / mean / PSNR (dB) | s/frame (256x144) |"
echo "|---|---|---|---|"
for scene in courtyard room_poles; do
  in="samples/$scene/frame_####.exr"
  b "ao-$scene" "$in" --set temporal=false --ref "ao=$in:AO" --preset presets/fast.json \
    --preset presets/default.json --preset presets/quality.json --preset presets/reference.json
  rows "ao-$scene" --prefix "$scene" ao:rmp s
done

# gi NAME SCENE_DIR [extra bench options]: AO, indirect against the 1-bounce reference and
# composite against Combined for the occlusion models, single frames.
gi() {
  local name=$1 dir=$2 in="$2/frame_####.exr"
  shift 2
  b "$name" "$in" --ref "ao=$in:AO" \
    --ref "indirect@1bounce=$dir/bounce1/frame_####.exr:DiffCol*DiffInd" \
    --ref "composite=$in:Combined" \
    --preset "$(preset horizon_single '{"temporal": false, "method": "horizon"}')" \
    --preset "$(preset no_backfaces_single '{"temporal": false, "passes": {"backdepth": ""}}')" \
    --preset "$single" "$@"
  rows "$name" --prefix "$(basename "$dir")" --label "horizon_single=horizon" \
    --label "no_backfaces_single=bitmask, no back-face layer (thickness auto)" \
    --label "single=bitmask, back-face thickness (default)" \
    --label "temporal=temporal chain (default)" \
    ao:psnr indirect@1bounce:rmp composite:rmp s
}
echo
echo "Single frames (--set temporal=false), ao, indirect and composite, one in-frame bounce;"
echo "indirect against Cycles DiffCol*DiffInd rendered with 1 diffuse bounce, composite"
echo "against Cycles Combined (8 bounces) $(load):"
echo
echo "| scene | occlusion | AO PSNR | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
echo "|---|---|---|---|---|---|"
gi gi-courtyard samples/courtyard
gi gi-room_poles samples/room_poles

echo
echo "Single frames (--set temporal=false), in-frame bounces, against the 8-bounce render: indirect"
echo "against DiffCol*DiffInd, composite against Combined $(load):"
echo
echo "| scene | bounces | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
echo "|---|---|---|---|---|"
for scene in courtyard room_poles; do
  in="samples/$scene/frame_####.exr"
  b "bounces-$scene" "$in" --set temporal=false --sweep bounces=1,2,3,4 \
    --ref "indirect=$in:DiffCol*DiffInd" --ref "composite=$in:Combined"
  rows "bounces-$scene" --prefix "$scene" \
    --label "default bounces=1::1" --label "default bounces=2::2" \
    --label "default bounces=3::3" --label "default bounces=4::4" indirect:rmp composite:rmp s
done

if [ -n "${HELDOUT:-}" ]; then
  echo
  echo "Held-out scene $HELDOUT (default preset, never used for tuning) $(load):"
  echo
  echo "| scene | occlusion | AO PSNR | indirect RMSE / mean / PSNR | composite RMSE / mean / PSNR | s/frame |"
  echo "|---|---|---|---|---|---|"
  gi heldout "$HELDOUT" --preset "$temporal"
fi

povray_table
unseen_table

# temporal NAME SCENE_DIR: single frames against the chain; AO, indirect against the 1- and
# the 8-bounce reference, composite; the revealed-pixel figures of --stability on indirect.
echo
echo "Temporal chain (default) against single frames (--set temporal=false), all 8 frames $(load):"
echo
echo "| scene | run | AO PSNR | indirect vs 1-bounce PSNR | indirect vs 8-bounce PSNR | composite vs Combined PSNR | s/frame |"
echo "|---|---|---|---|---|---|---|"
tlabels=(--label "single=single frames" --label "temporal=temporal (default)")
for scene in courtyard room_poles; do
  in="samples/$scene/frame_####.exr"
  b "t-$scene" "$in" --preset "$single" --preset "$temporal" --ref "ao=$in:AO" \
    --ref "indirect@1bounce=samples/$scene/bounce1/frame_####.exr:DiffCol*DiffInd" \
    --ref "indirect@8bounces=$in:DiffCol*DiffInd" --ref "composite=$in:Combined"
  rows "t-$scene" --prefix "$scene" "${tlabels[@]}" ao:psnr indirect@1bounce:psnr \
    indirect@8bounces:psnr composite:psnr s
done

echo
echo "Static camera (samples/room_static, 6 identical Cycles frames): flicker = frame-to-frame"
echo "change of the composite (sum |c_k - c_(k-1)| / sum c_k); indirect against the 8-bounce"
echo "DiffCol*DiffInd, frame by frame:"
echo
echo "| run | flicker | indirect PSNR, frames 1-6 |"
echo "|---|---|---|"
in="samples/room_static/frame_####.exr"
b static "$in" --preset "$single" --preset "$(preset no_accumulation '{"history_max": 1}')" \
  --preset "$(preset no_feedback '{"feedback": false}')" --preset "$temporal" \
  --ref "composite=$in:Combined" --ref "indirect=$in:DiffCol*DiffInd"
rows static --label "single=single frames (temporal=false)" \
  --label "no_accumulation=temporal, no accumulation (history_max=1)" \
  --label "no_feedback=temporal, no feedback" --label "temporal=temporal (default)" \
  composite:change indirect:frames

echo
echo "Camera moves, frame by frame, indirect against the 8-bounce DiffCol*DiffInd:"
echo
echo "| scene | run | indirect PSNR, frames 1-8 |"
echo "|---|---|---|"
for scene in courtyard room_poles; do
  rows "t-$scene" --prefix "$scene" "${tlabels[@]}" indirect@8bounces:frames
done

echo
echo "Disocclusions (hbil bench --stability, indirect against the 8-bounce render): RMSE on"
echo "pixels with no accepted history (history.Y = 1 after frame 1) and elsewhere, and their"
echo "share of the geometry pixels:"
echo
echo "| scene | run | RMSE newly revealed | RMSE elsewhere | share (%) |"
echo "|---|---|---|---|---|"
for scene in courtyard room_poles; do
  in="samples/$scene/frame_####.exr"
  b "d-$scene" "$in" --preset "$temporal" --ref "indirect=$in:DiffCol*DiffInd" --stability
  rows "d-$scene" --prefix "$scene" "${tlabels[@]}" revealed
done

echo
echo "Hard cut (samples/room_cut, cut at frame 4), indirect against the 8-bounce render, frame"
echo "by frame:"
echo
echo "| run | cuts detected | indirect PSNR per frame |"
echo "|---|---|---|"
in="samples/room_cut/frame_####.exr"
b cut "$in" --preset "$temporal" --preset "$single" --ref "indirect=$in:DiffCol*DiffInd"
b cut-fresh "$in" --frames 4-6 --preset "$temporal" --ref "indirect=$in:DiffCol*DiffInd"
rows cut --label "temporal=temporal" --label "single=single frames" cuts indirect:frames
rows cut-fresh --label "temporal=temporal, a run that starts at frame 4" cuts indirect:frames

if [ -n "${HELDOUT_MOVE:-}" ]; then
  mv_in="$HELDOUT_MOVE/frame_####.exr"
  echo
  echo "Never-seen camera move $HELDOUT_MOVE (16 frames), indirect against its 8-bounce"
  echo "DiffCol*DiffInd frame by frame, and frame-to-frame change of the composite against"
  echo "Cycles' Combined's (hbil / Cycles / ratio) $(load):"
  echo
  echo "| run | indirect PSNR per frame | overall | composite vs Combined PSNR | change hbil / Cycles / ratio |"
  echo "|---|---|---|---|---|"
  b move "$mv_in" --preset "$single" --preset "$temporal" \
    --ref "indirect=$mv_in:DiffCol*DiffInd" --ref "composite=$mv_in:Combined"
  rows move "${tlabels[@]}" indirect:frames indirect:psnr composite:psnr composite:changes
  # A farm chunk against the whole run (no reference involved): run and compare.
  "$hbil" run "$mv_in" -o "$out/hm-whole/f_####.exr" --no-display -q
  "$hbil" run "$mv_in" -o "$out/hm-chunk/f_####.exr" --no-display --frames 11-16 --preroll 4 -q
  for layer in ao irradiance composite; do
    "$hbil" compare "$out/hm-chunk/f_####.exr" "$out/hm-whole/f_####.exr" --layer $layer \
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
  echo "| run | cuts detected | indirect PSNR per frame |"
  echo "|---|---|---|"
  b hcut "$ct_in" --preset "$temporal" --preset "$single" --ref "indirect=$ct_in:DiffCol*DiffInd"
  b hcut-fresh "$ct_in" --frames 7-12 --preset "$temporal" --ref "indirect=$ct_in:DiffCol*DiffInd"
  rows hcut --label "temporal=temporal" --label "single=single frames" cuts indirect:frames
  rows hcut-fresh --label "temporal=temporal, a run that starts at frame 7" cuts indirect:frames
fi
