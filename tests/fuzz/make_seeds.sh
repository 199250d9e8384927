#!/usr/bin/env bash
# make_seeds.sh: writes the seed corpora in tests/fuzz/corpus/ from the bundled samples
# (run from the repository root after a build; needs oiiotool). The committed seeds came
# from it; rerun it only to change them.
#
#   frame/    16x9 subsamples of samples/room_poles/frame_0001.exr in the layouts the reader
#             takes: ZIP scanlines as Blender writes, RLE, PIZ, ZIPS, none, DWAA, B44, half
#             (depth float), tiled, multi-part, and only the fields AO needs; with the camera in the
#             header (worldToCamera, worldToNDC) or left to be solved from Position.
#   sidecar/  the samples' camera sidecars and tests/data/camera's.
#   preset/   presets/*.json and a few --set assignments.
#   povray/   tests/data/povray_analytic cut to 16x9, one input per file (a first byte of
#             0, 1, 2 selects camera, depth, normal; see fuzz_povray.cpp); povray_frame/
#             holds the same frame as files.
#   found_*   (kept) inputs that caused a finding once, kept as regression seeds: every run
#             of the target starts by replaying them.
set -euo pipefail
cd "$(dirname "$0")/../.."
C=tests/fuzz/corpus
find "$C" -type f ! -name "found_*" -delete 2>/dev/null || true
mkdir -p "$C"/{frame,sidecar,preset,povray,povray_frame}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# The camera attributes hbil writes for the sample's camera (NDC: the same at any size).
src=samples/room_poles/frame_0001.exr
build/hbil run "$src" -o "$tmp/cam.exr" --set 'outputs=["ao"]' --no-display >/dev/null
attr() { oiiotool --info -v "$tmp/cam.exr" | sed -n "s/^ *$1: //p" | tr -d ' '; }
wc=$(attr worldToCamera)
wn=$(attr worldToNDC)
cam=(--attrib:type=matrix worldToCamera "$wc" --attrib:type=matrix worldToNDC "$wn")

small="$tmp/small.exr"
oiiotool "$src" --resample 16x9 --eraseattrib "cycles.*" --eraseattrib "File" -o "$small"
F=$C/frame
oiiotool "$small" "${cam[@]}" --compression zip -o "$F/zip_camera.exr"
oiiotool "$small" --compression zip -o "$F/zip_position.exr"
oiiotool "$small" "${cam[@]}" --compression rle -o "$F/rle.exr"
oiiotool "$small" "${cam[@]}" --compression piz -o "$F/piz.exr"
oiiotool "$small" "${cam[@]}" --compression zips -o "$F/zips.exr"
oiiotool "$small" "${cam[@]}" --compression none -o "$F/none.exr"
oiiotool "$small" "${cam[@]}" --compression dwaa -o "$F/dwaa.exr"
# Half, but depth float: half overflows at the background's depth, and the frame would stop
# at its first pixel.
depth_float=(-d ViewLayer.Depth.Z=float -d BackFaces.Depth.Z=float)
oiiotool "$small" "${cam[@]}" --compression b44 -d half "${depth_float[@]}" -o "$F/b44_half.exr"
oiiotool "$small" "${cam[@]}" -d half "${depth_float[@]}" --compression zip -o "$F/half.exr"
oiiotool "$small" "${cam[@]}" --tile 8 8 --compression zip -o "$F/tiled.exr"
oiiotool "$small" "${cam[@]}" --ch "ViewLayer.Depth.Z,ViewLayer.Normal.X,ViewLayer.Normal.Y,ViewLayer.Normal.Z" \
  --compression zip -o "$F/ao_only.exr"
oiiotool "$small" --ch "ViewLayer.Combined.R,ViewLayer.Combined.G,ViewLayer.Combined.B,ViewLayer.Combined.A" \
  -o "$tmp/beauty.exr"
oiiotool "$tmp/beauty.exr" "$small" "${cam[@]}" --siappend --compression zip -o "$F/multipart.exr"

cp samples/room_poles/frame_0001.camera.json "$C/sidecar/room_poles.json"
cp samples/courtyard/frame_0001.camera.json "$C/sidecar/courtyard.json"
for f in tests/data/camera/*.camera.json; do cp "$f" "$C/sidecar/$(basename "$f" .camera.json).json"; done

for f in presets/*.json; do cp "$f" "$C/preset/"; done
printf -- '--set radius=0.5' >"$C/preset/set_radius"
printf -- '--set passes.depth="Depth"' >"$C/preset/set_pass"
printf -- '--set outputs=["ao","composite"]' >"$C/preset/set_outputs"

P=tests/data/povray_analytic
python3 - "$P/camera1.json" "$C/povray_frame/camera1.json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
c["width"], c["height"] = 16, 9
json.dump(c, open(sys.argv[2], "w"))
PY
oiiotool "$P/depth1.exr" --resample 16x9 -o "$C/povray_frame/depth1.exr"
oiiotool "$P/normal1.exr" --resample 16x9 -o "$C/povray_frame/normal1.exr"
k=0
for f in camera1.json depth1.exr normal1.exr; do
  { printf "\\x0$k"; cat "$C/povray_frame/$f"; } >"$C/povray/$f"
  k=$((k + 1))
done
du -sh "$C"/*
