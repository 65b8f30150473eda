#!/usr/bin/env bash
# Sets up, builds with warnings as errors, and runs every test with ctest on the default
# OpenCL device (PoCL's CPU device on a machine without a GPU); then a short fuzzing run
# of the LSQT parser and the parser tests under AddressSanitizer and UBSan.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
bash tools/build.sh -DLSQT_WERROR=ON
(cd build && ctest --output-on-failure -j 2 "$@")
bash tools/fuzz/run.sh "${LSQT_FUZZ_SECONDS:-60}"
