#!/usr/bin/env bash
# Configures and builds lsqt-cl into build/ (extra CMake arguments pass through).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@" >/dev/null
cmake --build build -j "$(nproc)"
