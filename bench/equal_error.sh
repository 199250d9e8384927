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
#
# For every scene S (samples/blender/S.py; committed reference: samples/S/, 512 spp, 8 diffuse
# bounces, seed 1, frames 1-8):
#  1. Cycles ladder: frames 1-8 rendered at N spp for every N in LADDER, seed 7, with full GI
#     (`--mode main`, the committed settings) and with direct light only (`--bounces 0`).
#     Time per frame = Cycles' own `cycles.ViewLayer.render_time` from each EXR header (path
#     tracing only: no scene load, no sync, no EXR write), mean over the frames. Blender writes
#     it truncated to 10 ms, so 5 ms is added to each frame's value (unbiased for the mean).
#     The "wall" columns are the whole render call per frame (sync + render + write; the
#     HBIL_FRAME lines of hbil_common.render_frames), for reference.
#  2. Error: `hbil compare RENDER samples/S --layer Combined --ref-layer Combined --json`
#     (non-background pixels of all 8 frames, peak 1). PSNR is over R, G, B: compare's
#     "overall" also averages in alpha, which every image here matches exactly, so it reads
#     10*log10(4/3) = 1.25 dB higher; the equal-error point is the same either way.
#  3. hbil: `hbil run samples/S/frame_####.exr --no-display` (default preset), RUNS times,
#     interleaved with the Cycles rungs (before the first, in the middle, after the last),
#     median "s per frame" (its summary line: read + camera + compute + write); its composite
#     is compared like the renders (`--layer composite --ref-layer Combined`).
#  4. Cycles' time at hbil's PSNR: linear interpolation of log2(time) against PSNR between the
#     two neighbouring rungs (extrapolated from the two lowest, resp. highest, rungs when
#     hbil's PSNR lies outside the ladder; the table says so). The equivalent spp and the
#     direct-only time are interpolated at the same point; full minus direct-only is Cycles'
#     marginal cost of the indirect light there.
# Output (stdout): machine load at start and end, a summary table per scene, the full ladder.
# Cost: a few minutes per scene on 2 idle cores (both ladders sum to 2 x 127 spp x 8 frames).
# Needs blender 3.4, iinfo (openimageio-tools) and python3.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

hbil=${1:-build/hbil}
[[ $hbil == /* ]] || hbil="$root/$hbil"
[ -x "$hbil" ] || { echo "equal_error.sh: no hbil binary at $hbil" >&2; exit 2; }
scenes=${SCENES:-room_poles courtyard}
ladder=${LADDER:-1 2 4 8 16 32 64}
runs=${RUNS:-3}
blender=${BLENDER:-blender}
frames=1-8
seed=7
command -v "$blender" > /dev/null || { echo "equal_error.sh: $blender not found" >&2; exit 2; }
command -v iinfo > /dev/null || { echo "equal_error.sh: iinfo not found (openimageio-tools)" >&2; exit 2; }

if [ -n "${KEEP:-}" ]; then
  work=$KEEP
  mkdir -p "$work"
else
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi

log() { echo "[$(date +%T)] $*" >&2; }

# psnr_of JSON_FILE: "rgb_psnr overall_psnr alpha_rmse" from `hbil compare --json`.
psnr_of() {
  python3 - "$1" << 'EOF'
import json, math, sys
j = json.load(open(sys.argv[1]))
se = n = 0.0
alpha = 0.0
for c in j["channels"]:
    if c["test"].endswith(".A") or c["test"] == "A":
        alpha = max(alpha, c["rmse"])
        continue
    se += c["rmse"] ** 2 * c["pixels"]
    n += c["pixels"]
mse = se / n
psnr = float("inf") if mse == 0 else -10 * math.log10(mse)
o = j["overall"]["psnr"]
print("%.4f %s %.6f" % (psnr, o if isinstance(o, str) else "%.4f" % o, alpha))
EOF
}

# render_time DIR: mean Cycles render_time (s) per frame from the EXR headers (+5 ms each).
render_time() {
  local f
  for f in "$1"/frame_*.exr; do
    iinfo -v "$f" | sed -n 's/^ *cycles\.ViewLayer\.render_time: *"\(.*\)"/\1/p'
  done | python3 -c '
import sys
v = []
for line in sys.stdin:
    s = 0.0
    for part in line.strip().split(":"):
        s = 60 * s + float(part)
    v.append(s + 0.005)
print("%.4f %d" % (sum(v) / len(v), len(v)) if v else "nan 0")'
}

# rung S KIND N: renders (unless reusable) and measures one rung; appends to results.tsv.
rung() {
  local s=$1 kind=$2 n=$3 dir extra=() rt nf wall p
  dir="$work/$s/${kind}_spp$n"
  [ "$kind" = direct ] && extra=(--bounces 0)
  if [ -n "${REUSE:-}" ] && [ -f "$dir/done" ]; then
    log "$s $kind $n spp: reused"
  else
    rm -rf "$dir"
    mkdir -p "$dir"
    log "$s $kind $n spp: rendering"
    "$blender" -b --factory-startup --python "samples/blender/$s.py" -- --out "$dir" \
      --mode main --samples "$n" --seed "$seed" --frames "$frames" "${extra[@]}" \
      > "$dir/blender.log" 2>&1 || { tail -n 20 "$dir/blender.log" >&2; exit 1; }
    touch "$dir/done"
  fi
  read -r rt nf < <(render_time "$dir")
  [ "$nf" = 8 ] || { echo "equal_error.sh: $dir has $nf frames, not 8" >&2; exit 1; }
  wall=$(sed -n 's/^HBIL_TIMING .*mean_seconds=\([0-9.]*\).*/\1/p' "$dir/blender.log")
  "$hbil" compare "$dir/frame_####.exr" "samples/$s/frame_####.exr" --layer Combined \
    --ref-layer Combined --json > "$dir/compare.json"
  p=$(psnr_of "$dir/compare.json")
  echo "$kind $n $p $rt ${wall:-nan}" >> "$work/$s/results.tsv"
}

# hbil_run S I: one timed hbil run; appends its s/frame to results.tsv.
hbil_run() {
  local s=$1 i=$2 spf
  log "$s hbil run $i"
  rm -rf "$work/$s/hbil"
  "$hbil" run "samples/$s/frame_####.exr" -o "$work/$s/hbil/frame_####.exr" --no-display \
    > /dev/null 2> "$work/$s/hbil_run$i.log" || { tail "$work/$s/hbil_run$i.log" >&2; exit 1; }
  spf=$(tail -n 1 "$work/$s/hbil_run$i.log" | sed -n 's/.* \([0-9.]*\) s per frame.*/\1/p')
  echo "hbil_time $i $spf" >> "$work/$s/results.tsv"
}

echo "# Equal-error ladder: Cycles vs hbil"
echo
echo "- date: $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores, $("$blender" --version 2> /dev/null | head -n 1), hbil: $hbil"
echo "- load at start: $(uptime)"

read -r -a rungs <<< "$ladder"
npairs=${#rungs[@]}
for s in $scenes; do
  [ -f "samples/blender/$s.py" ] && [ -f "samples/$s/frame_0001.exr" ] ||
    { echo "equal_error.sh: unknown scene $s" >&2; exit 2; }
  mkdir -p "$work/$s"
  : > "$work/$s/results.tsv"
  # the hbil runs go before pair pos_i (i = 0..runs-1), spread from the first to after the last
  declare -A at=()
  for ((i = 0; i < runs; i++)); do
    if ((runs > 1)); then pos=$(((i * npairs + (runs - 1) / 2) / (runs - 1))); else pos=0; fi
    at[$pos]="${at[$pos]:-} $((i + 1))"
  done
  for ((k = 0; k <= npairs; k++)); do
    for i in ${at[$k]:-}; do hbil_run "$s" "$i"; done
    ((k < npairs)) || break
    rung "$s" full "${rungs[$k]}"
    rung "$s" direct "${rungs[$k]}"
  done
  unset at
  "$hbil" compare "$work/$s/hbil/frame_####.exr" "samples/$s/frame_####.exr" --layer composite \
    --ref-layer Combined --json > "$work/$s/hbil_compare.json"
  echo "hbil_psnr 0 $(psnr_of "$work/$s/hbil_compare.json")" >> "$work/$s/results.tsv"
done

python3 - "$work" $scenes << 'EOF'
import math, statistics, sys
work, scenes = sys.argv[1], sys.argv[2:]
summary, ladders, notes = [], [], []
for s in scenes:
    full, direct, hb_t = {}, {}, []
    hb = None
    for line in open("%s/%s/results.tsv" % (work, s)):
        f = line.split()
        if f[0] in ("full", "direct"):
            (full if f[0] == "full" else direct)[int(f[1])] = dict(
                psnr=float(f[2]), overall=f[3], alpha=float(f[4]), t=float(f[5]),
                wall=float(f[6]))
        elif f[0] == "hbil_time":
            hb_t.append(float(f[2]))
        elif f[0] == "hbil_psnr":
            hb = dict(psnr=float(f[2]), overall=f[3], alpha=float(f[4]))
    spps = sorted(full)
    for d in list(full.values()) + list(direct.values()) + [hb]:
        if d["alpha"] > 0:
            notes.append("%s: alpha differs from the reference (rmse %.4g): the RGB PSNR and "
                         "compare's overall PSNR differ by more than 1.25 dB" % (s, d["alpha"]))
    t_h = statistics.median(hb_t)
    p = hb["psnr"]
    # the segment of the ladder (in spp order) whose PSNR range holds p
    where = None
    for i in range(len(spps) - 1):
        a, b = full[spps[i]]["psnr"], full[spps[i + 1]]["psnr"]
        if min(a, b) <= p <= max(a, b):
            where = i
            break
    if where is None:
        if p < full[spps[0]]["psnr"]:
            where, how = 0, "extrapolated below %d spp" % spps[0]
        else:
            where, how = len(spps) - 2, "extrapolated above %d spp" % spps[-1]
    else:
        how = "interpolated %d-%d spp" % (spps[where], spps[where + 1])
    na, nb = spps[where], spps[where + 1]
    u = (p - full[na]["psnr"]) / (full[nb]["psnr"] - full[na]["psnr"])
    lerp2 = lambda x, y: 2 ** ((1 - u) * math.log2(x) + u * math.log2(y))
    t_c = lerp2(full[na]["t"], full[nb]["t"])
    t_d = lerp2(direct[na]["t"], direct[nb]["t"])
    spp = lerp2(na, nb)
    summary.append("| %s | %.2f | %.3f | %.3f | %.2f | %.1f (%s) | %.3f | %.3f | %.2f |" % (
        s, p, t_h, t_c, t_c / t_h, spp, how, t_d, t_c - t_d, (t_c - t_d) / t_h))
    ladders.append("\n### %s\n\nhbil: %s s/frame (runs: %s), composite PSNR %.2f dB "
                   "(compare's overall, with alpha: %s)\n" % (
                       s, "%.3f" % t_h, ", ".join("%.3f" % t for t in hb_t), p, hb["overall"]))
    ladders.append("| spp | PSNR full GI | s/frame full GI | PSNR direct-only | "
                   "s/frame direct-only | wall s/frame full GI | wall s/frame direct-only |")
    ladders.append("|---|---|---|---|---|---|---|")
    for n in spps:
        F, D = full[n], direct[n]
        ladders.append("| %d | %.2f | %.3f | %.2f | %.3f | %.2f | %.2f |" % (
            n, F["psnr"], F["t"], D["psnr"], D["t"], F["wall"], D["wall"]))
    if any(full[spps[i + 1]]["psnr"] < full[spps[i]]["psnr"] for i in range(len(spps) - 1)):
        notes.append("%s: the full-GI PSNR is not monotonic in spp; the first segment that "
                     "holds hbil's PSNR was used" % s)

print("\n## Cycles at hbil's error\n")
print("PSNR in dB over R, G, B, non-background pixels of frames 1-8, against the committed "
      "512-spp 8-bounce render; s/frame: hbil's whole run (read + compute + write), Cycles' "
      "render_time (path tracing only).\n")
print("| scene | hbil PSNR | hbil s/frame | Cycles s/frame at equal PSNR | Cycles / hbil | "
      "equal-PSNR spp | Cycles direct-only s/frame at that spp | Cycles marginal GI s/frame | "
      "marginal GI / hbil |")
print("|---|---|---|---|---|---|---|---|---|")
print("\n".join(summary))
print("\n## Ladder (Cycles, seed 7, frames 1-8)")
print("\n".join(ladders))
for n in notes:
    print("\nNote: " + n)
EOF
echo
echo "- load at end: $(uptime)"
