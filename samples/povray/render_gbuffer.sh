#!/usr/bin/env bash
# render_gbuffer.sh: renders a POV-Ray 3.7 scene that uses hbil.inc into the passes hbil
# needs, one POV-Ray render per pass, and merges them with `hbil import-povray` into one
# Blender-like multilayer EXR per frame (OUTDIR/frame_####.exr). Then: hbil run.
#
#   render_gbuffer.sh [options] SCENE.pov OUTDIR
#     --frames A-B     frames to render (default 1-1); the scene sees frame_number, and clock
#                      runs 0..1 over A..B (POV-Ray's default)
#     --size WxH       resolution (default 640x360)
#     --overscan P     render P % more on each side with the field of view widened alike: each
#                      frame is WxH as framed (its display window) inside a guard band (its
#                      data window), which hbil searches and gathers from
#     --reference      also render the radiosity reference (pass 7: Combined and DiffInd)
#     --bounces N      radiosity bounces of the reference (default 3)
#     --count N        radiosity rays per sample of the reference (default 1000)
#     --sky WxH        also render the sky (HBIL_Sky) of the first frame as an equirectangular
#                      OUTDIR/sky.exr of that size (e.g. 1024x512), for hbil's far field:
#                      hbil run ... --set 'environment="OUTDIR/sky.exr"'
#     --panorama WxH   also render each frame's panorama from the camera's location: the
#                      depth, albedo, emit and direct passes (those --passes asks for) as an
#                      equirectangular image of that size (e.g. 128x64, W = 2 H), imported as
#                      OUTDIR/pano_####.exr for hbil's panorama:
#                      hbil run ... --set 'panorama="OUTDIR/pano_####.exr"'
#     --passes LIST    comma-separated subset of depth,normal,albedo,emit,direct,backfaces
#                      (default: all; depth and normal are always rendered)
#     --hbil PATH      the hbil binary (default: hbil on PATH, else build/hbil of this tree)
#     --no-import      render the passes only (OUTDIR/passes)
# Passes and POV-Ray's logs go to OUTDIR/passes; the scene's folder and this kit's folder
# are on POV-Ray's library path. Every pass is rendered without anti-aliasing, so each
# pixel is one ray through its centre and the passes agree pixel for pixel.
set -euo pipefail
kit=$(cd "$(dirname "$0")" && pwd)
frames=1-1 size=640x360 overscan=0 reference=0 bounces=3 count=1000 hbil="" do_import=1 sky=""
panorama=""
passes=depth,normal,albedo,emit,direct,backfaces
args=()
usage() { sed -n '2,28p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
while (($#)); do
  case "$1" in
    --frames) frames=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --overscan) overscan=$2; shift 2 ;;
    --reference) reference=1; shift ;;
    --bounces) bounces=$2; shift 2 ;;
    --count) count=$2; shift 2 ;;
    --sky) sky=$2; shift 2 ;;
    --panorama) panorama=$2; shift 2 ;;
    --passes) passes=$2; shift 2 ;;
    --hbil) hbil=$2; shift 2 ;;
    --no-import) do_import=0; shift ;;
    -h|--help) usage ;;
    -*) echo "render_gbuffer.sh: unknown option $1" >&2; exit 2 ;;
    *) args+=("$1"); shift ;;
  esac
done
((${#args[@]} == 2)) || usage
[[ -f ${args[0]} ]] || { echo "render_gbuffer.sh: ${args[0]}: no such scene file" >&2; exit 3; }
scene=$(realpath "${args[0]}") out=${args[1]}
[[ $frames =~ ^([0-9]+)-([0-9]+)$ ]] || { echo "render_gbuffer.sh: --frames A-B, got $frames" >&2; exit 2; }
first=$((10#${BASH_REMATCH[1]})) last=$((10#${BASH_REMATCH[2]}))
((first <= last)) || { echo "render_gbuffer.sh: --frames A-B needs A <= B, got $frames" >&2; exit 2; }
[[ $bounces =~ ^[1-9][0-9]*$ && $count =~ ^[1-9][0-9]*$ ]] ||
  { echo "render_gbuffer.sh: --bounces and --count take positive integers" >&2; exit 2; }
[[ $size =~ ^([0-9]+)x([0-9]+)$ ]] || { echo "render_gbuffer.sh: --size WxH, got $size" >&2; exit 2; }
width=${BASH_REMATCH[1]} height=${BASH_REMATCH[2]}
[[ $overscan =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "render_gbuffer.sh: --overscan P takes a percentage, got $overscan" >&2; exit 2; }
# The guard band in pixels per side; the passes are rendered at the grown size.
guard_x=$(awk -v w="$width" -v p="$overscan" 'BEGIN { printf "%d", w * p / 100 + 0.5 }')
guard_y=$(awk -v h="$height" -v p="$overscan" 'BEGIN { printf "%d", h * p / 100 + 0.5 }')
width=$((width + 2 * guard_x)) height=$((height + 2 * guard_y))
guard=()
((guard_x > 0 || guard_y > 0)) && guard=(Declare=HBIL_Guard_X="$guard_x" Declare=HBIL_Guard_Y="$guard_y")
if [[ -n $sky ]]; then
  [[ $sky =~ ^([0-9]+)x([0-9]+)$ && ${BASH_REMATCH[1]} -eq $((2 * ${BASH_REMATCH[2]})) ]] ||
    { echo "render_gbuffer.sh: --sky WxH with W = 2 H, got $sky" >&2; exit 2; }
fi
if [[ -n $panorama ]]; then
  [[ $panorama =~ ^([0-9]+)x([0-9]+)$ && ${BASH_REMATCH[1]} -eq $((2 * ${BASH_REMATCH[2]})) && ${BASH_REMATCH[2]} -ge 2 ]] ||
    { echo "render_gbuffer.sh: --panorama WxH with W = 2 H, got $panorama" >&2; exit 2; }
fi
command -v povray >/dev/null || { echo "render_gbuffer.sh: povray not found (apt-get install povray)" >&2; exit 3; }
if ((do_import)) && [[ -z $hbil ]]; then
  hbil=$(command -v hbil || true)
  [[ -n $hbil ]] || hbil=$kit/../../build/hbil
  [[ -x $hbil ]] || { echo "render_gbuffer.sh: no hbil binary (use --hbil PATH)" >&2; exit 3; }
fi

mkdir -p "$out/passes"
passdir=$(realpath "$out/passes")
declare -A number=([depth]=1 [normal]=2 [albedo]=3 [emit]=4 [direct]=5 [backfaces]=6 [reference]=7)
list=(depth normal)
IFS=, read -ra wanted <<<"$passes"
for p in "${wanted[@]}"; do
  [[ -n ${number[$p]:-} && $p != reference ]] || { echo "render_gbuffer.sh: unknown pass $p" >&2; exit 2; }
  [[ $p == depth || $p == normal ]] || list+=("$p")
done
((reference)) && list+=(reference)

anim=(+KFI"$first" +KFF"$last")
# A single frame is rendered as frame A of A..A+1, so that POV-Ray still animates: the scene
# sees frame_number = A (clock 0) and the files carry the frame number.
((first == last)) && anim=(+KFI"$first" +KFF"$((last + 1))" +SF"$first" +EF"$first")
# render_passes DIR WxH LABEL EXTRA PASS...: renders each PASS over the frames into
# DIR/<pass><frame>.exr (one run of POV-Ray a pass, its log DIR/povray_<pass>.log), with the
# declarations in the array named EXTRA, and prints its seconds per frame. LABEL names it in
# the messages.
render_passes() {
  local dir=$1 size=$2 label=$3 p start
  local -n extra=$4
  shift 4
  for p in "$@"; do
    local opts=(+I"$scene" +O"$dir/$p.exr" +FE +W"${size%x*}" +H"${size#*x}" -A -D -V
          Display=off +L"$(dirname "$scene")" +L"$kit" "${anim[@]}" Declare=HBIL_PASS="${number[$p]}"
          "${extra[@]}")
    [[ $p == depth ]] && opts+=(+UA)
    [[ $p == reference ]] && opts+=(Declare=HBIL_Radiosity_Bounces="$bounces" Declare=HBIL_Radiosity_Count="$count")
    start=$(date +%s.%N)
    if ! (cd "$dir" && povray "${opts[@]}") >"$dir/povray_$p.log" 2>&1; then
      tail -20 "$dir/povray_$p.log" >&2
      echo "render_gbuffer.sh: povray failed on $label $p (log: $dir/povray_$p.log)" >&2
      exit 1
    fi
    awk -v l="$label" -v p="$p" -v n="${number[$p]}" -v f="$((last - first + 1))" -v s="$start" \
      -v e="$(date +%s.%N)" -v size="$size" \
      'BEGIN { printf "render_gbuffer.sh: %s %d %-9s %s, %d frame(s), %.2f s per frame\n", l, n, p, size, f, (e - s) / f }' >&2
  done
}
render_passes "$passdir" "${width}x$height" pass guard "${list[@]}"
if [[ -n $sky ]]; then
  # One frame (the first): hbil's environment is one image for the whole run.
  start=$(date +%s.%N)
  opts=(+I"$scene" +O"$passdir/sky.exr" +FE +W"${sky%x*}" +H"${sky#*x}" -A -D -V Display=off
        +L"$(dirname "$scene")" +L"$kit" +KFI"$first" +KFF"$((first + 1))" +SF"$first" +EF"$first"
        Declare=HBIL_PASS=8)
  if ! (cd "$passdir" && povray "${opts[@]}") >"$passdir/povray_sky.log" 2>&1; then
    tail -20 "$passdir/povray_sky.log" >&2
    echo "render_gbuffer.sh: povray failed on the sky (log: $passdir/povray_sky.log)" >&2
    exit 1
  fi
  rendered=("$passdir"/sky[0-9]*.exr)  # POV-Ray pads the number to the digits of first + 1
  mv "${rendered[0]}" "$out/sky.exr"
  awk -v s="$start" -v e="$(date +%s.%N)" -v size="$sky" -v o="$out/sky.exr" \
    'BEGIN { printf "render_gbuffer.sh: pass 8 sky       %s, %.2f s -> %s\n", size, e - s, o }' >&2
fi
if [[ -n $panorama ]]; then
  # The passes the panorama needs, from the camera's location over the whole sphere.
  mkdir -p "$passdir/panorama"
  pano_passes=(depth)
  for p in albedo emit direct; do [[ ",$passes," == *",$p,"* ]] && pano_passes+=("$p"); done
  pano_extra=(Declare=HBIL_Panorama=1)
  render_passes "$passdir/panorama" "$panorama" "panorama pass" pano_extra "${pano_passes[@]}"
fi
if ((do_import)); then
  "$hbil" import-povray "$passdir" -o "$out/frame_####.exr" --frames "$first-$last"
  if [[ -n $panorama ]]; then
    "$hbil" import-povray "$passdir/panorama" -o "$out/pano_####.exr" --frames "$first-$last"
  fi
fi
