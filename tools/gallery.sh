#!/usr/bin/env bash
# Regenerates the README's pictures (docs/images/): the lssview sphere preview of each
# tutorial assembly and one lssplot slice plot, each made by the command printed under it
# in the README. Runs in a temporary folder; needs a build (bash tools/build.sh).
# usage: bash tools/gallery.sh [PATHS]   (default 20000 paths per slice)
# LSQT_BUILD=DIR: take lsqt-cl and lssview from the build folder DIR (relative to the
# current folder) instead of build/, which is built with tools/build.sh when it lacks them.
set -euo pipefail
here=$PWD
cd "$(dirname "$0")/.."
P=${1:-20000}
OUT=docs/images
mkdir -p "$OUT"
if [ -n "${LSQT_BUILD:-}" ]; then
  B=$(cd "$here" && cd "$LSQT_BUILD" && pwd)
  [ -x "$B/lsqt-cl" ] && [ -x "$B/lssview" ] || { echo "gallery: no lsqt-cl and lssview in $B" >&2; exit 2; }
else
  B=build
  [ -x build/lsqt-cl ] && [ -x build/lssview ] || bash tools/build.sh
fi
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
for name in Lambertian Rough Substr Dusty Silver; do
  cp "examples/tutorial/$name.lsqt" "$W/"
  "$B/lsqt-cl" -q -p "$P" -wi 300 "$W/$name.lsqt"
  "$B/lssview" -q --image-dim 256 "$W/$name.lsqt.lss" -o "$OUT/$name.png"
  echo "gallery: $OUT/$name.png  (lsqt-cl -p $P -wi 300 $name.lsqt; lssview --image-dim 256 $name.lsqt.lss)"
done
# the slice plot: four slices, so the curves can be told apart
mkdir -p "$W/plot" && cp examples/tutorial/Substr.lsqt "$W/plot/"
"$B/lsqt-cl" -q -p "$P" -wo 4 -wi 300 "$W/plot/Substr.lsqt"
tools/lssplot "$W/plot/Substr.lsqt.lss" -o "$OUT/Substr-slices.png" --log --lsqt-cl "$B/lsqt-cl"
echo "gallery: $OUT/Substr-slices.png  (lsqt-cl -p $P -wo 4 -wi 300 Substr.lsqt; lssplot Substr.lsqt.lss --log)"
# The RGL tensor file in a renderer: Mitsuba 3's sphere beside lssview's, one LSS, one scene
# (tools/rgl_render.py; needs a Python with mitsuba: LSQT_CLIENT_VENV, or build/client-venv,
# which test_rgl makes).
PY=${LSQT_CLIENT_VENV:-build/client-venv}/bin/python
[ -x "$PY" ] || PY=build/validate-venv/bin/python
if "$PY" -c 'import mitsuba' 2>/dev/null; then
  mkdir -p "$W/rgl" && cp examples/tutorial/Substr.lsqt "$W/rgl/"
  "$B/lsqt-cl" -q -p "$((P * 5))" --rgl-grid 9,33 "$W/rgl/Substr.lsqt"
  "$B/lsqt-cl" export -q "$W/rgl/Substr.lsqt.lss" -o "$W/rgl/Substr.bsdf" --rgl
  "$B/lssview" -q --image-dim 256 "$W/rgl/Substr.lsqt.lss" -o "$OUT/Substr-rgl-lssview.png"
  "$PY" tools/rgl_render.py "$W/rgl/Substr.bsdf" "$OUT/Substr-rgl-mitsuba.png" --spp 1024
  echo "gallery: $OUT/Substr-rgl-{lssview,mitsuba}.png  (lsqt-cl -p $((P * 5)) --rgl-grid 9,33 Substr.lsqt;" \
       "lsqt-cl export Substr.lsqt.lss -o Substr.bsdf --rgl; lssview; tools/rgl_render.py --spp 1024)"
else
  echo "gallery: no Python with mitsuba ($PY): the RGL pictures are not remade"
fi
