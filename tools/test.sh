#!/usr/bin/env bash
# Sets up and builds with warnings as errors; runs the whole suite under ASan+UBSan and
# fuzzes the LSQT parser and LSS reader briefly (LSQT_FUZZ_SECONDS, default 60); then runs
# every test with ctest on the default OpenCL device (PoCL's CPU device on a machine
# without a GPU) in the release build. Extra arguments go to that ctest. Last, the
# mutation check (tools/mutate/README.md): every planted error must make its tests fail
# (LSQT_MUTATE=0 skips it).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
bash tools/build.sh -DLSQT_WERROR=ON
bash tools/fuzz/run.sh "${LSQT_FUZZ_SECONDS:-60}"
(cd build && ctest --output-on-failure -j 2 "$@") || { bash tools/ctest_tail.sh build; exit 8; }
if [ "${LSQT_MUTATE:-1}" != 0 ]; then bash tools/mutate/run.sh; fi
