#!/usr/bin/env bash
# The README's test command: what a user runs to trust the tool (budget: 10 minutes on
# 2 cores with an empty PoCL kernel cache). Installs what is missing (tools/setup.sh),
# builds with warnings as errors, runs every ctest test in the release build on the
# default OpenCL device (PoCL's CPU device on a machine without a GPU), then fuzzes the
# LSQT parser, the LSS reader and the --wi-file parser briefly under ASan+UBSan
# (LSQT_FUZZ_SECONDS, default 30 in all). Extra arguments go to that ctest.
# CI (.ci/run) runs this, then the sanitizer suite and the mutation check: docs/testing.md.
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/timing.sh
step setup bash tools/setup.sh
step build bash tools/build.sh -DLSQT_WERROR=ON
# The power tests (label "power": many paths, one regime each), the GPU-path checks
# (label "gpu": offline GPU builds, oclgrind) and the real clients that come from PyPI
# (label "clients": Mitsuba 3) are CI's (.ci/run).
step ctest bash -c '(cd build && ctest --output-on-failure -j 2 -LE "power|gpu|clients" "$@") || { bash tools/ctest_tail.sh build; exit 8; }' \
  ctest "$@"
step fuzz bash tools/fuzz/run.sh "${LSQT_FUZZ_SECONDS:-30}"
steps_done "tools/test.sh" 600
