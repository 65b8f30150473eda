#!/usr/bin/env bash
# Sets up, builds, and runs lsqt-cl on the first tutorial example (a 60% Lambertian):
# writes examples/tutorial/Lambertian.lsqt.raw and .lss (-R: start over each time), then
# its preview, examples/tutorial/Lambertian.lsqt.lss.png (lssview).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
bash tools/build.sh
./build/lsqt-cl -R examples/tutorial/Lambertian.lsqt "$@"
./build/lssview examples/tutorial/Lambertian.lsqt.lss
