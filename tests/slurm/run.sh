#!/usr/bin/env bash
# run.sh HBIL SAMPLE_DIR: hbil's farm commands on a real Slurm cluster of one node.
#
# Starts munged, slurmctld and slurmd on localhost with slurm.conf.in (everything in a
# temporary folder, ports chosen at random), then over the 8 frames of SAMPLE_DIR:
#   1. a whole run, the reference;
#   2. `hbil farm plan --chunk 3` (3 chunks) and `hbil farm slurm --submit`: the job array and
#      the check after it, with frame 8's input cut short so that the last chunk fails;
#   3. the check's log and `hbil farm check` name that chunk (exit 9); the frames made
#      before the failure, 1-7, are in place and the whole run's;
#   4. frame 8 restored, `sbatch --array=2` runs that chunk alone again, and the shot is
#      complete: every EXR and PNG is byte for byte the whole run's.
# Exits 0 when all holds, 1 when something does not, 77 (ctest: skipped) when Slurm or munge
# is not installed or its daemons cannot run here, saying why.
set -uo pipefail
H=$1
SAMPLE=$2
skip() {
  echo "SKIP: $*"
  exit 77
}
fail() {
  echo "FAIL: $*"
  for f in "$D"/log/*.log "$W"/logs/*; do
    [ -f "$f" ] && { echo "--- $f"; tail -n 20 "$f"; }
  done
  exit 1
}
for c in munged mungekey slurmctld slurmd sbatch squeue sinfo scancel; do
  command -v "$c" >/dev/null || skip "$c is not installed (.ci/setup installs slurm-wlm and munge)"
done

D=$(mktemp -d /tmp/hbil-slurm.XXXXXX)
W=$D/work
cleanup() {
  scancel --user="$(id -un)" >/dev/null 2>&1
  for pid in "$D"/slurmd.pid "$D"/slurmctld.pid "$D"/munge/munged.pid; do
    [ -f "$pid" ] && kill "$(cat "$pid")" 2>/dev/null
  done
  sleep 1
  rm -rf "$D"
}
trap cleanup EXIT
mkdir -p "$D"/munge "$D"/state "$D"/spool "$D"/log "$W"/in
chmod 700 "$D"/munge

# munge: a key of our own, a socket in our folder.
mungekey --create --keyfile="$D/munge/munge.key" >/dev/null 2>&1 ||
  skip "mungekey cannot make a key"
munged --force --key-file="$D/munge/munge.key" --socket="$D/munge/munge.sock" \
  --pid-file="$D/munge/munged.pid" --log-file="$D/munge/munged.log" \
  --seed-file="$D/munge/munged.seed" >/dev/null 2>&1 || skip "munged does not start here"

# Slurm: the configuration with this folder, free ports, this machine's cores and memory.
port=$((20000 + RANDOM % 20000))
mem_mb=$(awk '/MemTotal/ { printf "%d", $2 / 1024 * 0.8 }' /proc/meminfo)
sed -e "s|@DIR@|$D|g" -e "s|@USER@|$(id -un)|g" -e "s|@CTLD_PORT@|$port|g" \
  -e "s|@SLURMD_PORT@|$((port + 1))|g" -e "s|@CPUS@|$(nproc)|g" -e "s|@MEMORY_MB@|$mem_mb|g" \
  "$(dirname "$0")/slurm.conf.in" >"$D/slurm.conf"
export SLURM_CONF=$D/slurm.conf
slurmctld -f "$SLURM_CONF" >/dev/null 2>&1 || skip "slurmctld does not start here"
slurmd -f "$SLURM_CONF" -N localhost >/dev/null 2>&1 || skip "slurmd does not start here"
for _ in $(seq 60); do
  [ "$(sinfo -h -o %t 2>/dev/null)" = idle ] && break
  sleep 0.5
done
state=$(sinfo -h -o %t 2>/dev/null)
[ "$state" = idle ] || skip "the node did not come up (state \"$state\"): $(tail -n 3 "$D"/log/*.log)"
echo "slurm: slurmctld and slurmd up on localhost:$port, $(nproc) cores, $mem_mb MB"

# Waits until no job of ours is left (at most $1 seconds).
wait_jobs() {
  for _ in $(seq "$1"); do
    [ -z "$(squeue -h 2>/dev/null)" ] && return 0
    sleep 1
  done
  fail "jobs still queued after $1 s: $(squeue)"
}

# The inputs are copies with their time stamps (the job digest holds them).
for n in 1 2 3 4 5 6 7 8; do
  cp -p "$SAMPLE/frame_000$n.exr" "$SAMPLE/frame_000$n.camera.json" "$W/in/" ||
    fail "cannot copy frame $n of $SAMPLE"
done
cd "$W" || fail "no work folder"
"$H" run in/frame_####.exr -o whole/f_####.exr -q || fail "the whole run failed"
"$H" farm plan in/frame_####.exr -o plan.json --chunk 3 -- -o out/f_####.exr ||
  fail "farm plan failed"
[ "$(grep -c '"frames"' plan.json)" = 3 ] || fail "the plan does not have 3 chunks"

# Frame 8 cut short: the last chunk (frames 7-8) fails, the others do not.
cp -p in/frame_0008.exr frame_0008.keep
head -c 3000 frame_0008.keep >in/frame_0008.exr
"$H" farm slurm plan.json -o job.sbatch --cpus-per-task 1 --submit || fail "farm slurm failed"
wait_jobs 300
grep -q "incomplete" logs/*-check-*.out || fail "the check job did not find the failed chunk"
grep -q "sbatch --array=2 $W/job.sbatch" logs/*-check-*.out ||
  fail "the check job does not name chunk 2 to submit again: $(cat logs/*-check-*.out)"
"$H" farm check plan.json >check.out
rc=$?
[ "$rc" = 9 ] || fail "farm check exited $rc on an incomplete shot, not 9"
# Frame 8's header is whole: chunk 2 made frame 7 and failed on frame 8's pixels.
for n in 1 2 3 4 5 6 7; do
  cmp -s "whole/f_000$n.exr" "out/f_000$n.exr" || fail "frame $n differs from the whole run's"
  cmp -s "whole/f_000$n.png" "out/f_000$n.png" || fail "frame $n's PNG differs"
done
[ ! -e out/f_0008.exr ] && [ ! -e out/f_0008.png ] || fail "the failed frame 8 left files"
grep -q "chunk 2 (frames 7-8): 1 frame not done" check.out || fail "farm check: $(cat check.out)"
echo "slurm: chunk 2 failed at frame 8's cut-short input; frames 1-7 match the whole run"

# Frame 8 restored: only chunk 2 runs again, and the shot is the whole run's, byte for byte.
cp -p frame_0008.keep in/frame_0008.exr
sbatch --parsable --array=2 job.sbatch >/dev/null || fail "cannot submit chunk 2 again"
wait_jobs 300
"$H" farm check plan.json || fail "farm check after the resubmission: $(cat logs/*_2.out)"
for n in 1 2 3 4 5 6 7 8; do
  cmp -s "whole/f_000$n.exr" "out/f_000$n.exr" || fail "frame $n differs from the whole run's"
  cmp -s "whole/f_000$n.png" "out/f_000$n.png" || fail "frame $n's PNG differs"
done
grep -q '"event":"end","exit":3' logs/chunk-2.jsonl ||
  fail "chunk 2's run log lacks its failure (exit 3)"
grep -q '"event":"skip","frames":\[7\]' logs/chunk-2.jsonl ||
  fail "chunk 2 run again did not leave frame 7 as done"
[ "$(grep -c '"event":"end","exit":0' logs/chunk-2.jsonl)" = 1 ] ||
  fail "chunk 2's run log lacks its success"
echo "slurm: chunk 2 run again alone (frame 7 left as done); all 8 frames are the whole run's"
