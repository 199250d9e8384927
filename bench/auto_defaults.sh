#!/usr/bin/env bash
# auto_defaults.sh: gather_radius, thickness and gather_thickness "auto" against the former
# fixed defaults (4 m, 0.4) and against the best of a grid, per scene (README "Defaults that
# fit the scene").
#
#   bench/auto_defaults.sh DIR...        (HBIL=build/hbil by default)
#
# Each DIR holds frame_####.exr (8 diffuse bounces, with AO, DiffCol, DiffInd, Combined), as
# samples/blender/<scene>.py renders them (`--mode main` into DIR). `indirect` is judged
# against the 8-bounce DiffCol*DiffInd of those frames: the temporal chain's feedback, on by
# default, aims at every bounce, and against a 1-bounce render the configurations that lose
# light score best (room_poles' best of the grid would be a 0.5 m gather radius, 2.2 dB below
# auto's composite). INDIRECT=bounce1 judges it against DIR/bounce1/frame_####.exr (1 diffuse
# bounce, `--mode bounce1`) instead. The back-face layer, where a scene has one, is not used
# (passes.backdepth ""): the rule is for renders without it.
# For each scene, `hbil bench` runs the default preset over all its frames with gather_radius
# in {auto, 0.5, 1, 2, 4, 8, 16, 32} x thickness in {auto, 0.02, 0.05, 0.1, 0.2, 0.4, 0.8,
# 1.6} (a given thickness is the gather's too) and prints: indirect relative RMSE, AO RMSE
# against the AO pass, composite PSNR against Combined, for auto, for the former defaults
# (4, 0.4) and for the best configuration of the grid on each measure; and auto's ratio to
# the best (1.0 = as good as the best).
# With TUNE=1, a second table: auto against `hbil tune` (--tolerance 0, objective indirect,
# then ao), searching the keys auto sets (--keys gather_radius,thickness,gather_thickness);
# searching every key but the fill's (unseen_radiance, unseen_carry: what lies beyond the
# frame, not what auto sets) within auto's own time per frame (--budget: the default preset's
# seconds per frame, median of 3 timed runs, plus 10 %: at exactly its own time auto itself
# would fit or not by the timing's noise); and every key within that budget; auto's ratio to
# each. GRID=0 skips the first
# table.
set -euo pipefail
cd "$(dirname "$0")/.."
hbil=${HBIL:-build/hbil}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "- machine: $(nproc) cores; load at start: $(uptime | sed 's/.*load average: //')"
indirect_ref() {  # indirect_ref DIR: the reference expression of `indirect`
  if [ "${INDIRECT:-}" = bounce1 ]; then echo "$1/bounce1/frame_####.exr:DiffCol*DiffInd"
  else echo "$1/frame_####.exr:DiffCol*DiffInd"; fi
}
echo
if [ "${GRID:-1}" != 0 ]; then
  echo "| scene | median depth | gather_radius / thickness / gather_thickness (auto) | indirect rel. RMSE: auto / 4 m, 0.4 / best (auto ÷ best) | AO RMSE: auto / 4 m, 0.4 / best (auto ÷ best) | composite PSNR: auto / 4 m, 0.4 |"
  echo "|---|---|---|---|---|---|"
fi
for dir in "$@"; do
  [ "${GRID:-1}" != 0 ] || break
  name=$(basename "$dir")
  s="$dir/frame_####.exr"
  auto=$("$hbil" info "$dir/frame_0001.exr" --set 'passes.backdepth=""' | sed -n 's/^auto: //p')
  "$hbil" bench "$s" -o "$tmp/$name" -q --set 'passes.backdepth=""' \
    --ref "ao=$s:AO" --ref "indirect=$(indirect_ref "$dir")" \
    --ref "composite=$s:Combined" \
    --sweep 'gather_radius="auto",0.5,1,2,4,8,16,32' \
    --sweep 'thickness="auto",0.02,0.05,0.1,0.2,0.4,0.8,1.6' > /dev/null
  python3 - "$tmp/$name/bench.json" "$name" "$auto" <<'PY'
import json, re, sys
j = json.load(open(sys.argv[1]))
cs = {c["name"]: c for c in j["configurations"]}
auto = cs['default gather_radius="auto" thickness="auto"']
old = cs["default gather_radius=4 thickness=0.4"]
ind = lambda c: c["layers"]["indirect"]["relative_rmse"]
ao = lambda c: c["layers"]["ao"]["rmse"]
comp = lambda c: c["layers"]["composite"]["psnr"]
bi = min(cs.values(), key=ind)
ba = min(cs.values(), key=ao)
m = re.search(r"median depth ([0-9.e+]+)", sys.argv[3])
vals = re.findall(r"(gather_radius|thickness|gather_thickness) ([0-9.e+]+)", sys.argv[3])
print("| %s | %s m | %s | %.3f / %.3f / %.3f (%.2f) | %.4f / %.4f / %.4f (%.2f) | %.2f / %.2f dB |" % (
    sys.argv[2], m.group(1) if m else "?", " / ".join(v for _, v in vals),
    ind(auto), ind(old), ind(bi), ind(auto) / ind(bi),
    ao(auto), ao(old), ao(ba), ao(auto) / ao(ba), comp(auto), comp(old)))
PY
done
[ -n "${TUNE:-}" ] || exit 0
echo
echo "| scene | budget s/frame | indirect rel. RMSE: auto / tuned auto keys / all but the fill's in budget / all in budget (auto ÷ each) | AO RMSE: auto / tuned auto keys / all keys in budget (auto ÷ each) | what tune changed for indirect (all but the fill's; all) |"
echo "|---|---|---|---|---|"
for dir in "$@"; do
  name=$(basename "$dir")
  s="$dir/frame_####.exr"
  refs=(--ref "ao=$s:AO" --ref "indirect=$(indirect_ref "$dir")")
  # the budget: auto's own time per frame (the default preset alone, 3 timed runs) + 10 %
  "$hbil" bench "$s" -o "$tmp/$name-auto" -q --runs 3 --set 'passes.backdepth=""' "${refs[@]}" \
    > /dev/null
  budget=$(python3 -c 'import json,sys
print("%.4f" % (1.1 * json.load(open(sys.argv[1]))["configurations"][0]["seconds_per_frame"]))' \
    "$tmp/$name-auto/bench.json")
  for layer in indirect ao; do
    "$hbil" tune "$s" -q --set 'passes.backdepth=""' "${refs[@]}" --layer $layer --tolerance 0 \
      --keys gather_radius,thickness,gather_thickness -o "$tmp/$name-$layer-keys.json" > /dev/null
    [ $layer = ao ] ||  # the AO objective searches no fill key: its all-keys run is that
      "$hbil" tune "$s" -q --set 'passes.backdepth=""' "${refs[@]}" --layer $layer \
        --keys method,slices,steps,gather_steps,gather_radius,thickness,gather_thickness \
        --budget "$budget" -o "$tmp/$name-$layer-nofill.json" > /dev/null
    "$hbil" tune "$s" -q --set 'passes.backdepth=""' "${refs[@]}" --layer $layer \
      --budget "$budget" -o "$tmp/$name-$layer-budget.json" > /dev/null
  done
  python3 - "$tmp" "$name" "$budget" <<'PY'
import json, sys
t, name, budget = sys.argv[1], sys.argv[2], sys.argv[3]
auto = json.load(open("%s/%s-auto/bench.json" % (t, name)))["configurations"][0]
tuned = lambda layer, kind: json.load(open("%s/%s-%s-%s.json" % (t, name, layer, kind)))
ind = lambda kind: tuned("indirect", kind)["tuned"]["errors"]["indirect"]["relative_rmse"]
ao = lambda kind: tuned("ao", kind)["tuned"]["errors"]["ao"]["rmse"]
ai, aa = auto["layers"]["indirect"]["relative_rmse"], auto["layers"]["ao"]["rmse"]
defaults = json.load(open("presets/default.json"))
def changed(kind):
    j = tuned("indirect", kind)
    c = [k + "=" + json.dumps(v) for k, v in j.items()
         if k in defaults and k != "passes" and v != defaults[k]]
    return ", ".join(c) or "nothing"
print("| %s | %s | %.3f / %.3f / %.3f / %.3f (%.2f, %.2f, %.2f) | %.4f / %.4f / %.4f (%.2f, %.2f) | %s; %s |" % (
    name, budget, ai, ind("keys"), ind("nofill"), ind("budget"),
    ai / ind("keys"), ai / ind("nofill"), ai / ind("budget"),
    aa, ao("keys"), ao("budget"), aa / ao("keys"), aa / ao("budget"),
    changed("nofill"), changed("budget")))
PY
done
