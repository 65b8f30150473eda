#!/usr/bin/env bash
# Regenerates the README's pictures (docs/images/): the lssview sphere preview of each
# tutorial assembly and one lssplot slice plot, each made by the command printed under it
# in the README. Runs in a temporary folder; needs a build (bash tools/build.sh).
# usage: bash tools/gallery.sh [PATHS]   (default 20000 paths per slice)
set -euo pipefail
cd "$(dirname "$0")/.."
P=${1:-20000}
OUT=docs/images
mkdir -p "$OUT"
[ -x build/lsqt-cl ] && [ -x build/lssview ] || bash tools/build.sh
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
for name in Lambertian Rough Substr Dusty Silver; do
  cp "examples/tutorial/$name.lsqt" "$W/"
  ./build/lsqt-cl -q -p "$P" -wi 300 "$W/$name.lsqt"
  ./build/lssview -q --image-dim 256 "$W/$name.lsqt.lss" -o "$OUT/$name.png"
  echo "gallery: $OUT/$name.png  (lsqt-cl -p $P -wi 300 $name.lsqt; lssview --image-dim 256 $name.lsqt.lss)"
done
# the slice plot: four slices, so the curves can be told apart
mkdir -p "$W/plot" && cp examples/tutorial/Substr.lsqt "$W/plot/"
./build/lsqt-cl -q -p "$P" -wo 4 -wi 300 "$W/plot/Substr.lsqt"
tools/lssplot "$W/plot/Substr.lsqt.lss" -o "$OUT/Substr-slices.png" --log --lsqt-cl build/lsqt-cl
echo "gallery: $OUT/Substr-slices.png  (lsqt-cl -p $P -wo 4 -wi 300 Substr.lsqt; lssplot Substr.lsqt.lss --log)"
