#!/usr/bin/env bash
# The sanitizer suite (CI's second tier, after tools/test.sh): builds everything (C and
# lssview's C++) with clang under AddressSanitizer + UBSan, leak checking on, in
# build-fuzz/, and runs the whole ctest suite there (OpenCL tests included, on the
# default device). Extra arguments go to that ctest. `--configure` only configures
# build-fuzz/ (tools/fuzz/run.sh builds its fuzz targets there).
set -euo pipefail
cd "$(dirname "$0")/.."
CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Debug -DLSQT_FUZZ=ON -DLSQT_SANITIZE=ON \
  -DLSQT_WERROR=ON >/dev/null
if [ "${1:-}" = --configure ]; then exit 0; fi
cmake --build build-fuzz -j "$(nproc)"
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
# Without the power tests (they add paths, not host code paths: the kernels run in PoCL,
# outside the sanitizers) and the GPU-path checks (offline compilers, a simulator); the
# release build runs them (.ci/run).
(cd build-fuzz && ctest --output-on-failure -j 2 -LE 'power|gpu' "$@") || { bash tools/ctest_tail.sh build-fuzz; exit 8; }
