#!/usr/bin/env bash
# speed.sh: hbil's time per frame, per stage, and peak memory, on real renders at several
# resolutions (README "Speed").
#
#   bench/speed.sh [HBIL] [BASE]      (default: build/hbil; BASE: an older binary to compare)
#   HD1080=dir HD2160=dir bench/speed.sh   also the 1920x1080 / 3840x2160 renders in those
#       folders (frame_####.exr + sidecars), rendered as samples/README.md says
#       (room_poles.py --size 1920x1080 --samples 1, back faces merged)
#   RUNS=3 (the default)   runs per configuration; the table gives medians
#
# For each resolution, each output set (the default outputs with the sRGB PNG; ao + bentcone
# only, no PNG) and each binary, `hbil run -v` runs over the whole sequence; the binaries
# alternate run by run, so that a shared machine's load falls on both alike. Per stage:
# the median over frames and runs of the -v line's read / camera / compute / write times (the
# stages overlap: a frame is read and the previous one written while it computes, so they add
# up to more than the wall time); "s/frame" is the median of the runs' summary lines (wall
# clock, all frames), "after first" the median of their seconds a frame after the first (a
# long shot's rate); peak RSS from /usr/bin/time.
set -euo pipefail
cd "$(dirname "$0")/.."
hbil=${1:-build/hbil}
base=${2:-}
runs=${RUNS:-3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "- machine: $(nproc) cores; load at start: $(uptime | sed 's/.*load average: //')"

inputs=("256x144|samples/room_poles/frame_####.exr")
[ -n "${HD1080:-}" ] && inputs+=("1920x1080|$HD1080/frame_####.exr")
[ -n "${HD2160:-}" ] && inputs+=("3840x2160|$HD2160/frame_####.exr")
sets=("default outputs + PNG|" "ao + bentcone|--no-display --set outputs=[\"ao\",\"bentcone\"]")
bins=("$hbil")
[ -n "$base" ] && bins+=("$base")

echo "| resolution | outputs | binary | read ms | camera ms | compute ms | write ms | s/frame | after first | peak RSS MB |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for input in "${inputs[@]}"; do
  res=${input%%|*} pattern=${input#*|}
  for set in "${sets[@]}"; do
    label=${set%%|*} args=${set#*|}
    for b in "${bins[@]}"; do : >"$tmp/log-$(basename "$b")"; done
    for ((r = 0; r < runs; ++r)); do
      for b in "${bins[@]}"; do
        log="$tmp/log-$(basename "$b")"
        rm -rf "$tmp/out"
        # shellcheck disable=SC2086
        /usr/bin/time -f "PEAK_KB %M" "$b" run "$pattern" -o "$tmp/out/f_####.exr" -v $args \
          >>"$log" 2>&1
      done
    done
    for b in "${bins[@]}"; do
      python3 - "$tmp/log-$(basename "$b")" "$res" "$label" "$(basename "$b")" <<'PY'
import re, statistics, sys
text = open(sys.argv[1]).read()
st = {k: [float(v) for v in re.findall(k + r" (\d+) ms", text)]
      for k in ("read", "camera", "compute", "write")}
spf = [float(v) for v in re.findall(r"([0-9.]+) s per frame", text)]
after = [float(v) for v in re.findall(r"([0-9.]+) s a frame after the first", text)]
peak = [int(v) for v in re.findall(r"PEAK_KB (\d+)", text)]
med = lambda v: statistics.median(v) if v else float("nan")
print("| %s | %s | %s | %.0f | %.0f | %.0f | %.0f | %.3f | %.3f | %.0f |" % (
    sys.argv[2], sys.argv[3], sys.argv[4], med(st["read"]), med(st["camera"]),
    med(st["compute"]), med(st["write"]), med(spf), med(after), max(peak) / 1024))
PY
    done
  done
done
echo "- load at end: $(uptime | sed 's/.*load average: //')"
