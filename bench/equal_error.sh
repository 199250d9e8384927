#!/usr/bin/env bash
# equal_error.sh: what Cycles costs at hbil's error (the "equal-error ladder").
#
#   bench/equal_error.sh [HBIL]                 (default: build/hbil)
#   SCENES="room_poles" bench/equal_error.sh    scenes (default: room_poles courtyard)
#   KEEP=/tmp/ladder bench/equal_error.sh       keep the renders and logs there (default: a
#                                               temp folder, removed at exit)
#   REUSE=1 KEEP=/tmp/ladder ...                reuse rungs already complete in KEEP (their
#                                               times are read back from the EXR headers)
#   LADDER="1 2 4 8 16 32 64" RUNS=3 BLENDER=blender   (the defaults)
#   PRESET=presets/interior.json ...            hbil's preset (default: presets/default.json)
#   PANORAMA=1 ...                              hbil with a small panorama of each frame
#                                               (samples/blender/panorama.py, 128x64, 4 spp;
#                                               README "A panorama of each frame"), whose
#                                               Cycles render time counts as hbil's
#   ESCAPE=CHANNEL ESCAPE_SECONDS=S ...         hbil with passes.escape=CHANNEL (the input
#                                               frames must hold it: an AO pass rendered with
#                                               a distance beyond the scene); S, the Cycles
#                                               render time that pass costs per frame, counts
#                                               as hbil's (README "What escapes the scene,
#                                               from the render")
#   CALIBRATE=1 ...                             hbil calibrated (`calibration`) on the
#                                               ladder's 1-spp full-GI render of the first
#                                               frame, whose Cycles render time, spread over
#                                               the frames, counts as hbil's (hbil bench
#                                               counts it)
#   SCENES="hall street" SAMPLES_DIR=/tmp/heldout FRAMES=1-4 ...
#                                               scenes not committed: SAMPLES_DIR/S/ holds
#                                               their reference, rendered as the committed
#                                               ones are (512 spp, seed 1, back faces merged)
#
# For every scene S (samples/blender/S.py; reference: SAMPLES_DIR/S/, by default the committed
# samples/S/, 512 spp, 8 diffuse bounces, seed 1, frames FRAMES, by default 1-8):
#  1. Cycles ladder: frames FRAMES rendered at N spp for every N in LADDER, seed 7, with full GI
#     (`--mode main`, the committed settings) and with direct light only (`--bounces 0`).
#     Time per frame = Cycles' own `cycles.ViewLayer.render_time` from each EXR header (path
#     tracing only: no scene load, no sync, no EXR write), mean over the frames. Blender writes
#     it truncated to 10 ms; bench adds 5 ms to each frame's value (unbiased for the mean).
#  2. hbil bench on the reference frames (default preset, RUNS timed runs, median), with every
#     full-GI rung as a --render: composite PSNR of hbil and of every rung over R, G, B
#     (non-background pixels of all the frames, peak 1) against the reference's Combined, and
#     bench's equal-error speedup. A second bench gives the direct-only rungs' times the same
#     way (their PSNR is not used).
#  3. Cycles' time at hbil's PSNR, as bench interpolates it: log(time) linear in PSNR between
#     the two neighbouring rungs (beyond the ladder, bench gives a bound: ">" or "<"). The
#     equivalent spp and the direct-only time are interpolated at the same point; full minus
#     direct-only is Cycles' marginal cost of the indirect light there.
# Output (stdout): machine load at start and end, a summary table per scene, the full ladder.
# Cost: a few minutes per scene on 2 idle cores (both ladders of 1-64 sum to 2 x 127 spp x 8
# frames).
# Needs blender 3.4 and python3.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

hbil=${1:-build/hbil}
[[ $hbil == /* ]] || hbil="$root/$hbil"
[ -x "$hbil" ] || { echo "equal_error.sh: no hbil binary at $hbil" >&2; exit 2; }
scenes=${SCENES:-room_poles courtyard}
ladder=${LADDER:-1 2 4 8 16 32 64}
runs=${RUNS:-3}
preset=${PRESET:-presets/default.json}
blender=${BLENDER:-blender}
samples=${SAMPLES_DIR:-samples}
frames=${FRAMES:-1-8}
[[ $frames =~ ^([0-9]+)-([0-9]+)$ ]] || { echo "equal_error.sh: FRAMES must be A-B" >&2; exit 2; }
n_frames=$((10#${BASH_REMATCH[2]} - 10#${BASH_REMATCH[1]} + 1))
first_frame=$((10#${BASH_REMATCH[1]}))
seed=7
command -v "$blender" > /dev/null || { echo "equal_error.sh: $blender not found" >&2; exit 2; }

if [ -n "${KEEP:-}" ]; then
  work=$KEEP
  mkdir -p "$work"
else
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi

log() { echo "[$(date +%T)] $*" >&2; }

# fresh DIR LABEL: succeeds, with DIR emptied, when DIR is to be rendered; fails when REUSE
# finds it complete (its "done" marker).
fresh() {
  if [ -n "${REUSE:-}" ] && [ -f "$1/done" ]; then
    log "$2: reused"
    return 1
  fi
  rm -rf "$1"
  mkdir -p "$1"
  log "$2: rendering"
}

# rung S KIND N: renders one rung (unless reusable) into $work/S/KIND_sppN.
rung() {
  local s=$1 kind=$2 n=$3 dir extra=() nf
  dir="$work/$s/${kind}_spp$n"
  [ "$kind" = direct ] && extra=(--bounces 0)
  if fresh "$dir" "$s $kind $n spp"; then
    "$blender" -b --factory-startup --python "samples/blender/$s.py" -- --out "$dir" \
      --mode main --samples "$n" --seed "$seed" --frames "$frames" "${extra[@]}" \
      > "$dir/blender.log" 2>&1 || { tail -n 20 "$dir/blender.log" >&2; exit 1; }
    touch "$dir/done"
  fi
  nf=$(find "$dir" -name 'frame_*.exr' | wc -l)
  [ "$nf" = "$n_frames" ] || { echo "equal_error.sh: $dir has $nf frames, not $n_frames" >&2; exit 1; }
}

# panorama S: renders S's panoramas (unless reusable) into $work/S/pano and writes their mean
# Cycles render time per frame (render_time + 5 ms, as bench takes it) to $work/S/pano/seconds.
panorama() {
  local s=$1 dir f t
  dir="$work/$s/pano"
  if fresh "$dir" "$s panorama"; then
    { "$blender" -b --factory-startup --python "samples/blender/$s.py" -- \
        --save-blend "$dir/scene.blend" --no-render &&
      "$blender" -b "$dir/scene.blend" --python samples/blender/panorama.py -- --out "$dir" \
        --frames "$frames"; } > "$dir/blender.log" 2>&1 || { tail -n 20 "$dir/blender.log" >&2; exit 1; }
    touch "$dir/done"
  fi
  for f in "$dir"/pano_*.exr; do
    t=$(iinfo -v "$f" | sed -n 's/^ *cycles\.ViewLayer\.render_time: *"\(.*\)"/\1/p')
    [ -n "$t" ] || { echo "equal_error.sh: $f has no render_time" >&2; exit 1; }
    echo "$t"
  done | python3 -c 'import sys
t = [sum(float(p) * 60 ** k for k, p in enumerate(reversed(l.split(":")))) + 0.005
     for l in sys.stdin.read().split()]
if len(t) != int(sys.argv[1]):
    sys.exit("equal_error.sh: %d panoramas, not %s" % (len(t), sys.argv[1]))
print("%.4f" % (sum(t) / len(t)))' "$n_frames" > "$dir/seconds"
}

echo "# Equal-error ladder: Cycles vs hbil"
echo
echo "- date: $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores, $("$blender" --version 2> /dev/null | head -n 1), hbil: $hbil, preset $preset"
echo "- load at start: $(uptime)"

read -r -a rungs <<< "$ladder"
for s in $scenes; do
  [ -f "samples/blender/$s.py" ] && [ -f "$samples/$s/frame_0001.exr" ] ||
    { echo "equal_error.sh: unknown scene $s" >&2; exit 2; }
  mkdir -p "$work/$s"
  full=() direct=()
  for n in "${rungs[@]}"; do
    rung "$s" full "$n"
    rung "$s" direct "$n"
    full+=(--render "$work/$s/full_spp$n/frame_####.exr")
    direct+=(--render "$work/$s/direct_spp$n/frame_####.exr")
  done
  in="$samples/$s/frame_####.exr"
  pano=()
  rm -f "$work/$s/bench_panorama"
  if [ -n "${PANORAMA:-}" ]; then
    panorama "$s"
    pano=(--set "panorama=$work/$s/pano/pano_####.exr")
    cp "$work/$s/pano/seconds" "$work/$s/bench_panorama"
  fi
  esc=()
  rm -f "$work/$s/bench_escape"
  if [ -n "${ESCAPE:-}" ]; then
    [ -n "${ESCAPE_SECONDS:-}" ] || { echo "equal_error.sh: ESCAPE needs ESCAPE_SECONDS" >&2; exit 2; }
    esc=(--set "passes.escape=$ESCAPE")
    echo "$ESCAPE_SECONDS" > "$work/$s/bench_escape"
  fi
  cal=()
  if [ -n "${CALIBRATE:-}" ]; then
    # bench counts the calibration render's own time (its header's) over the frames.
    [[ " $ladder " == *" 1 "* ]] || { echo "equal_error.sh: CALIBRATE needs 1 in LADDER" >&2; exit 2; }
    c=$(printf '%s/%s/full_spp1/frame_%04d.exr' "$work" "$s" "$first_frame")
    cal=(--set "calibration=$c")
  fi
  log "$s: hbil bench, $runs runs"
  "$hbil" bench "$in" -o "$work/$s/bench" -q --runs "$runs" --preset "$preset" "${pano[@]}" "${esc[@]}" "${cal[@]}" \
    --frames "$frames" --ref "composite=$in:Combined" "${full[@]}" > /dev/null
  "$hbil" bench "$in" -o "$work/$s/bench_direct" -q --preset presets/default.json \
    --frames "$frames" --ref "composite=$in:Combined" "${direct[@]}" > /dev/null
done

python3 - "$work" "$frames" $scenes << 'EOF'
import json, math, sys
work, frames, scenes = sys.argv[1], sys.argv[2], sys.argv[3:]
summary, ladders, notes = [], [], []
for s in scenes:
    j = json.load(open("%s/%s/bench/bench.json" % (work, s)))
    jd = json.load(open("%s/%s/bench_direct/bench.json" % (work, s)))
    c = j["configurations"][0]
    p, t_run = c["layers"]["composite"]["psnr"], c["seconds_per_frame"]
    # With PANORAMA, the panoramas' render time per frame is part of hbil's cost; with
    # CALIBRATE, the calibration render's, spread over the frames (bench counts it).
    def extra(name):
        try:
            return float(open("%s/%s/bench_%s" % (work, s, name)).read())
        except OSError:
            return 0.0
    t_pano = extra("panorama") + extra("escape")
    t_cal = c.get("calibration_render_seconds_per_frame", 0.0)
    if t_cal is None:
        sys.exit("equal_error.sh: %s: the calibration render has no render time" % s)
    t_h = t_run + t_pano + t_cal
    full = {r["samples"]: r for r in j["renders"]}
    direct = {r["samples"]: r for r in jd["renders"]}
    spps = sorted(full)
    # bench's interpolation: the first rung (by time) at or above hbil's PSNR and the one before
    by_t = sorted(full.values(), key=lambda r: r["seconds_per_frame"])
    i = next((k for k, r in enumerate(by_t) if r["composite"]["psnr"] >= p), len(by_t))
    if 0 < i < len(by_t):
        a, b = by_t[i - 1], by_t[i]
        u = (p - a["composite"]["psnr"]) / (b["composite"]["psnr"] - a["composite"]["psnr"])
        lerp = lambda x, y: math.exp((1 - u) * math.log(x) + u * math.log(y))
        spp = lerp(a["samples"], b["samples"])
        t_d = lerp(direct[a["samples"]]["seconds_per_frame"],
                   direct[b["samples"]]["seconds_per_frame"])
        how = "interpolated %d-%d spp" % (a["samples"], b["samples"])
    else:
        r = by_t[-1] if i == len(by_t) else by_t[0]
        spp, t_d = r["samples"], direct[r["samples"]]["seconds_per_frame"]
        how = "beyond the ladder: bound at %d spp" % r["samples"]
    bound = c.get("equal_error_speedup_bound", "")
    # bench's speedup is against hbil's run and the calibration render's share
    t_c = c["equal_error_speedup"] * (t_run + t_cal)
    sp = t_c / t_h
    summary.append("| %s | %.2f | %.3f | %s%.3f | %s%.1f | %.1f (%s) | %.3f | %.3f | %.2f |" % (
        s, p, t_h, bound, t_c, bound, sp, spp, how, t_d, t_c - t_d, (t_c - t_d) / t_h))
    ladders.append("\n### %s\n\nhbil: %.3f s/frame (runs: %s), composite PSNR %.2f dB; %s\n" % (
        s, t_h, ", ".join("%.3f" % t for t in c["runs"]), p, j["machine"]))
    if t_pano > 0:
        ladders.append("(hbil's %.3f s/frame: its run, %.3f, plus the %s's Cycles render "
                       "time, %.4f)\n" % (t_h, t_run, "escape pass" if extra("escape") else
                                           "panorama", t_pano))
    if t_cal > 0:
        ladders.append("(hbil's %.3f s/frame: its run, %.3f, plus the calibration render's "
                       "Cycles time over the frames, %.4f)\n" % (t_h, t_run, t_cal))
    ladders.append("| spp | PSNR full GI | s/frame full GI | s/frame direct-only |")
    ladders.append("|---|---|---|---|")
    for n in spps:
        ladders.append("| %d | %.2f | %.3f | %.3f |" % (
            n, full[n]["composite"]["psnr"], full[n]["seconds_per_frame"],
            direct[n]["seconds_per_frame"] if n in direct else float("nan")))
    if any(full[spps[k + 1]]["composite"]["psnr"] < full[spps[k]]["composite"]["psnr"]
           for k in range(len(spps) - 1)):
        notes.append("%s: the full-GI PSNR is not monotonic in spp" % s)

print("\n## Cycles at hbil's error\n")
print("PSNR in dB over R, G, B, non-background pixels of frames %s, against the "
      "512-spp 8-bounce reference (hbil bench); s/frame: hbil's whole run (read + compute + "
      "write, median of the timed runs), Cycles' render_time (path tracing only).\n" % frames)
print("| scene | hbil PSNR | hbil s/frame | Cycles s/frame at equal PSNR | Cycles / hbil | "
      "equal-PSNR spp | Cycles direct-only s/frame at that spp | Cycles marginal GI s/frame | "
      "marginal GI / hbil |")
print("|---|---|---|---|---|---|---|---|---|")
print("\n".join(summary))
print("\n## Ladder (Cycles, seed 7, frames %s)" % frames)
print("\n".join(ladders))
for n in notes:
    print("\nNote: " + n)
EOF
echo
echo "- load at end: $(uptime)"
