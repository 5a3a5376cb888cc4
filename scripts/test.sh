#!/usr/bin/env bash
# Sets up, builds and runs the whole test suite (unit tests and the bumpy-plane regressions).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bash "$root/scripts/setup.sh"
bash "$root/scripts/build.sh"
ctest --test-dir "$root/build" --output-on-failure -j "${MSD_JOBS:-$(nproc)}"
