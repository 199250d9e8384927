#!/usr/bin/env bash
# equal_error_hd.sh: hbil against Cycles at 1920x1080, timed in one run (README "Against Cycles
# at equal error").
#
#   HD_ROOM_POLES=dir HD_COURTYARD=dir bench/equal_error_hd.sh [HBIL]   (default: build/hbil)
#   SPP_ROOM_POLES="8 16" SPP_COURTYARD="4 8"   the Cycles rungs around hbil's equal-error
#       point of the 256x144 ladder (bench/equal_error.sh), the defaults
#   RUNS=3 BLENDER=blender KEEP=dir
#   SCENES="hall street" HD_HALL=dir SPP_HALL="16 32" ...   other scenes of samples/blender
#       (default: room_poles courtyard); HD_<SCENE> and SPP_<SCENE> as above
#   PANO_STREET=dir ...   hbil runs with the panoramas in dir (pano_####.exr, one per frame of
#       HD_<SCENE>, as samples/blender/panorama.py renders them; bench/equal_error.sh
#       PANORAMA=1 KEEP=k leaves them in k/<scene>/pano) and their mean Cycles render time is
#       printed, to be counted as hbil's
#   CAL_STREET=file ...   hbil runs calibrated on that render (`calibration`: any resolution,
#       e.g. the 256x144 ladder's 1-spp frame 1), whose Cycles render time is printed, to be
#       counted as hbil's over the frames
#   PRESET=presets/interior.json   hbil's preset (default: none, the built-in defaults)
#   OUTPUTS='["composite"]'   each hbil run is followed by one that computes and writes only
#       these outputs (Cycles writes one image; a compositor taking hbil's composite in its
#       place needs only that layer), and their median is printed too
#
# Each dir holds a 1920x1080 sequence of the scene rendered as samples/README.md says
# (`--size 1920x1080 --samples 1`, back faces merged, sidecars), frames 1-4 or more (the
# README: room_poles 1-6, courtyard 1-8). For every scene:
#  - Cycles renders frame 1 at 1920x1080 at each rung, seed 7, with full GI (`--mode main`)
#    and with direct light only (`--bounces 0`); its time is `cycles.ViewLayer.render_time`
#    from the EXR header (path tracing only), as in equal_error.sh;
#  - `hbil run DIR/frame_####.exr --no-display` (default preset, or PRESET) RUNS times, before, between
#    and after the renders, so that a shared machine's load falls on both; median of its
#    summary line's "s per frame" (reading, computing, writing).
# Prints one line per render and per hbil run, then the medians. The equal-error time is
# interpolated in log time between the rungs by the caller (README), at the spp the 256x144
# ladder gives; Cycles' noise per pixel at a given spp, and so its PSNR, does not depend on
# the resolution.
set -euo pipefail
cd "$(dirname "$0")/.."
hbil=${1:-build/hbil}
runs=${RUNS:-3}
blender=${BLENDER:-blender}
preset=()
[ -n "${PRESET:-}" ] && preset=(--preset "$PRESET")
work=${KEEP:-$(mktemp -d)}
[ -n "${KEEP:-}" ] || trap 'rm -rf "$work"' EXIT
mkdir -p "$work"
echo "- date: $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores, load at start: $(uptime | sed 's/.*load average: //')"

seconds() {  # "00:06.21" -> 6.215 (Blender truncates to 10 ms)
  python3 -c 'import sys
s = 0.0
for part in sys.argv[1].split(":"): s = 60 * s + float(part)
print("%.3f" % (s + 0.005))' "$1"
}
render() {  # render SCENE KIND SPP
  local s=$1 kind=$2 n=$3 dir extra=() t
  dir="$work/$s/${kind}_$n"
  [ "$kind" = direct ] && extra=(--bounces 0)
  rm -rf "$dir"
  mkdir -p "$dir"
  "$blender" -b --factory-startup --python "samples/blender/$s.py" -- --out "$dir" --mode main \
    --samples "$n" --seed 7 --frames 1-1 --size 1920x1080 "${extra[@]}" > "$dir/log" 2>&1 ||
    { tail -n 20 "$dir/log" >&2; exit 1; }
  t=$(iinfo -v "$dir/frame_0001.exr" | sed -n 's/^ *cycles\.ViewLayer\.render_time: *"\(.*\)"/\1/p')
  echo "$s cycles $kind $n spp: $(seconds "$t") s"
}
pano=() cal=()
hbil_run() {  # hbil_run SCENE DIR
  rm -rf "$work/out"
  "$hbil" run "$2/frame_####.exr" -o "$work/out/frame_####.exr" --no-display "${preset[@]}" \
    "${pano[@]}" "${cal[@]}" 2>&1 | sed -n "s/.* \([0-9.]*\) s per frame.*/$1 hbil: \1 s per frame/p"
  [ -n "${OUTPUTS:-}" ] || return 0
  rm -rf "$work/out"
  "$hbil" run "$2/frame_####.exr" -o "$work/out/frame_####.exr" --no-display "${preset[@]}" \
    "${pano[@]}" "${cal[@]}" --set "outputs=$OUTPUTS" 2>&1 |
    sed -n "s/.* \([0-9.]*\) s per frame.*/$1 hbil, outputs $OUTPUTS: \1 s per frame/p"
}

for s in ${SCENES:-room_poles courtyard}; do
  var=HD_${s^^}
  dir=${!var:-}
  [ -n "$dir" ] || { echo "- $s: $var not set, skipped"; continue; }
  spp_var=SPP_${s^^}
  default_spp="8 16"
  [ "$s" = courtyard ] && default_spp="4 8"
  read -r -a rungs <<< "${!spp_var:-$default_spp}"
  jobs=()
  for n in "${rungs[@]}"; do jobs+=("main $n" "direct $n"); done
  pano=()
  pano_var=PANO_${s^^}
  if [ -n "${!pano_var:-}" ]; then
    pano=(--set "panorama=${!pano_var}/pano_####.exr")
    for f in "${!pano_var}"/pano_*.exr; do
      t=$(iinfo -v "$f" | sed -n 's/^ *cycles\.ViewLayer\.render_time: *"\(.*\)"/\1/p')
      seconds "${t:?$f has no render_time}"
    done | python3 -c 'import sys
t = [float(x) for x in sys.stdin]
print("'"$s"' panorama: %.4f s per frame (Cycles, mean of %d)" % (sum(t) / len(t), len(t)))'
  fi
  cal=()
  cal_var=CAL_${s^^}
  if [ -n "${!cal_var:-}" ]; then
    cal=(--set "calibration=${!cal_var}")
    t=$(iinfo -v "${!cal_var}" | sed -n 's/^ *cycles\.ViewLayer\.render_time: *"\(.*\)"/\1/p')
    echo "$s calibration render: $(seconds "${t:?${!cal_var} has no render_time}") s (Cycles)"
  fi
  {
    hbil_run "$s" "$dir"
    for ((k = 0; k < ${#jobs[@]}; ++k)); do
      read -r kind n <<< "${jobs[$k]}"
      render "$s" "$kind" "$n"
      # hbil between the renders, RUNS times in all
      if ((k < runs - 2)); then hbil_run "$s" "$dir"; fi
    done
    hbil_run "$s" "$dir"
  } | tee "$work/$s.txt"
  python3 - "$work/$s.txt" "$s" <<'PY'
import re, statistics, sys
text = open(sys.argv[1]).read()
t = [float(x) for x in re.findall(r"hbil: ([0-9.]+) s per frame", text)]
print("%s: hbil median %.3f s per frame over %d runs" % (sys.argv[2], statistics.median(t), len(t)))
o = re.findall(r"hbil, (outputs .*): ([0-9.]+) s per frame", text)
if o:
    print("%s: hbil, %s, median %.3f s per frame over %d runs" % (
        sys.argv[2], o[0][0], statistics.median(float(x) for _, x in o), len(o)))
PY
done
echo "- load at end: $(uptime | sed 's/.*load average: //')"
