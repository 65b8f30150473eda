#!/usr/bin/env bash
# test_gpu_path: the GPU code path (LSQT_GPU_PATH=1: next-event records evaluated by
# lsqt_estimate, work-groups of 64, one RNG block) against the CPU code path (per-path
# sums in the walk, work-groups of 1, the four-block RNG) on PoCL, both at vector width 2
# and in double: every model family (slab, Dust, Rough, Substr with its RRSS pilot,
# Dusty, Silver, SGGX, Rayleigh over Oren-Nayar, the MCX-like slab, a transmitting stack
# from both sides) gives
# byte-identical RAW, LSS tallies and work counts (lsqt-cl info). The records hold exactly
# the values the CPU path evaluates and the per-path sums are made in the same order, so
# any slip in a record's packing, a lost or repeated vertex, or a path cut short shows
# here. Substr runs again with a record budget of 30 (LSQT_NEE_RECORD_CAP), which cuts
# every launch into parts and grows the buffer for a path with more; so does a run with
# bands (gold). Band blocks (their spread records, below) are compared the same way.
# (Between vector widths the bytes may differ: PoCL's double exp2 at 16 and 4 lanes
# differs in a last bit at some arguments, which can move a path's sum by one unit.)
# usage: test_gpu_path.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
cli_workdir
printf 'Medium\nLayer z=20 MicrosurfaceDielectricBsdf alpha=1e-4 use_multiple_scattering=false\nMedium eta=1.37 mus=10 mua=0.01 HenyeyGreensteinPhase g=0.9\nLayer z=0 MicrosurfaceDielectricBsdf alpha=1e-4 use_multiple_scattering=false\nMedium\n' > mcx.lsqt
printf 'Medium\nLayer z=1 LambertianBsdf fR=0.3 fT=0.5\nMedium\nLayer z=0 LambertianBsdf fR=0.2 fT=0.6\nMedium\n' > two.lsqt

# same NAME FILE FLAGS...: both paths, double, width 2 (the GPU's); RAW and info must match.
same() {
  local name=$1 file=$2
  shift 2
  for g in 0 1; do
    if ! LSQT_GPU_PATH=$g LSQT_VECTOR_WIDTH=2 "$BIN" -q -R "$file" --double -o "$name.$g.raw" --lss "$name.$g.lss" "$@"; then
      bad "$name: the run with LSQT_GPU_PATH=$g failed"
      return
    fi
    "$BIN" info "$name.$g.lss" | grep -v '^file:' > "$name.$g.info"
  done
  # every RAW: the one, those from below, those of each band (NAME.0.550nm.raw)
  local f n=0
  for f in "$name.0.raw" "$name".0.*.raw; do
    [ -f "$f" ] || continue
    n=$((n + 1))
    if cmp -s "$f" "$name.1.${f#"$name.0."}"; then ok; else bad "$name: $f differs between the code paths"; fi
  done
  [ "$n" -gt 0 ] || bad "$name: no RAW written"
  if cmp -s "$name.0.info" "$name.1.info"; then ok; else bad "$name: lsqt-cl info differs: $(diff "$name.0.info" "$name.1.info" | head -4)"; fi
}

same slab "$EX/slab.lsqt" -p 600 -wo 4 -wi 24 --wi-spread
same Dust "$EX/tutorial/Dust.lsqt" -p 300 -wo 4 -wi 24 --wi-spread
same Rough "$EX/tutorial/Rough.lsqt" -p 300 -wo 4 -wi 24
same Substr "$EX/tutorial/Substr.lsqt" -p 300 -wo 4 -wi 24
same Dusty "$EX/tutorial/Dusty.lsqt" -p 300 -wo 4 -wi 24 --wi-spread
same Silver "$EX/tutorial/Silver.lsqt" -p 300 -wo 4 -wi 24 --wi-spread
same SGGX "$EX/sggx-dust.lsqt" -p 300 -wo 4 -wi 24 --wi-spread
same Rayleigh-ON "$EX/rayleigh-oren-nayar.lsqt" -p 300 -wo 4 -wi 24 --wi-spread --from-below
same Tabulated "$EX/mie-fog.lsqt" -p 300 -wo 4 -wi 24 --wi-spread
same MCX mcx.lsqt -p 300 -wo 4 -wi 24 --wi-spread
same two two.lsqt -p 300 -wo 4 -wi 24 --wi-spread --from-below
LSQT_NEE_RECORD_CAP=30 same Substr-parts "$EX/tutorial/Substr.lsqt" -p 300 -wo 4 -wi 24 --wi-spread
# Bands sharing their paths (the GPU path's spread records, evaluated by lsqt_estimate):
# three in one block (RGB; its RRSS on their sum); gold's hidden conductor, whose n and k
# change by band, with a record budget of 30; six bands whose extinction, albedo, phase
# function and Lambertian factors all differ (each band's own medium records; the layer's
# transmitted terms cross the medium below it, deeper in some bands), from both sides, in
# two blocks of 3 (LSQT_BAND_BLOCK=4 and LSQT_BAND_DIVERGENCE=inf on both paths: the
# GPU's blocks are at most 4 wide, the CPU's 16). Then one band per block, the blocks
# lending each other one record buffer.
same RGB "$EX/paint-rgb.lsqt" -p 300 -wo 4 -wi 24
LSQT_NEE_RECORD_CAP=30 same Gold "$EX/gold-coat.lsqt" -p 300 -wo 4 -wi 24 --wi-spread --wavelengths 450:650:100
printf '400 2.0\n700 0.3\n' > mus.txt
printf '400 0.01\n700 0.6\n' > mua.txt
printf '400 0.1\n700 0.6\n' > fr.txt
printf '400 0.5\n700 0.2\n' > ft.txt
printf '400 -0.3\n700 0.8\n' > g.txt
printf 'Medium\nLayer z=1 LambertianBsdf fR=@fr.txt fT=@ft.txt\nMedium mus=@mus.txt mua=@mua.txt HenyeyGreensteinPhase g=@g.txt\nLayer z=0 NullBsdf\nMedium\n' > six.lsqt
LSQT_BAND_BLOCK=4 LSQT_BAND_DIVERGENCE=inf same Six six.lsqt -p 300 -wo 4 -wi 24 --wi-spread --from-below --wavelengths 400:650:50
LSQT_BAND_BLOCK=1 same RGB-apart "$EX/paint-rgb.lsqt" -p 300 -wo 4 -wi 24
# The GPU path's blocks, as -v says: three bands in one (that can share: the model of
# what sharing pays would keep paint-rgb's third band apart).
if LSQT_GPU_PATH=1 LSQT_BAND_DIVERGENCE=inf "$BIN" -v -R "$EX/paint-rgb.lsqt" -p 64 -wo 4 -wi 16 -o v.raw --lss v.lss 2>&1 | grep -q "3 bands in 1 block of up to 3"; then ok; else bad "the GPU path does not run 3 bands in one block"; fi
finish test_gpu_path
