#!/usr/bin/env bash
# Builds the ORIGINAL layered-sqt (M. Grady Saunders, 2020) from its public source, to
# measure lsqt-cl beside it (tools/bench_original.py). Not part of the build, the tests or CI.
# usage: tools/original/build.sh DEST
#   clones layered-sqt into DEST/src and its submodule preform into DEST/src/lib/preform,
#   at the commits pinned below, builds Release (upstream's flags: -O2 -march=native) into
#   DEST/build and prints the path of the layered-sqt binary.
#   LAYERED_SQT_GIT and PREFORM_GIT override the repositories (a local mirror or bare clone).
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: $0 DEST" >&2; exit 2; }
mkdir -p "$1"
DEST=$(cd "$1" && pwd)
LAYERED_SQT_GIT=${LAYERED_SQT_GIT:-https://github.com/mgradysaunders/layered-sqt}
PREFORM_GIT=${PREFORM_GIT:-https://github.com/mgradysaunders/preform}
LAYERED_SQT_REV=2ec931b4459a10d337efaaf8e546a6eeead78697  # "chmod no exec", the last commit
PREFORM_REV=f06367ac56b7bb92a698a6ec5fd6422a91629499      # the submodule lib/preform at it
src=$DEST/src pf=$DEST/src/lib/preform

[ -d "$src/.git" ] || git clone -q --no-checkout "$LAYERED_SQT_GIT" "$src"
git -C "$src" -c advice.detachedHead=false checkout -q --detach "$LAYERED_SQT_REV"
if [ ! -d "$pf/.git" ]; then
  rm -rf "$pf"
  git clone -q --no-checkout "$PREFORM_GIT" "$pf"
  # The build reads only preform's headers (include/); checking out just those also works
  # from a mirror that lacks preform's large data files (data/simple_scene/*.obj; git then
  # prints 'invalid object' for them, which is harmless).
  git -C "$pf" sparse-checkout set include
fi
git -C "$pf" -c advice.detachedHead=false checkout -q --detach "$PREFORM_REV"

# Patch for g++ >= 11 (Debian 12's g++ 12): preform's byte_order.hpp throws
# std::invalid_argument without including <stdexcept>, which older libstdc++ headers
# pulled in through <string>. One include, nothing else changes.
bo=$pf/include/preform/byte_order.hpp
grep -q '#include <stdexcept>' "$bo" || sed -i 's|^#include <string>$|#include <stdexcept>\n#include <string>|' "$bo"

cmake -S "$src" -B "$DEST/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$DEST/build" -j "$(nproc)" >/dev/null
echo "$DEST/build/layered-sqt"
