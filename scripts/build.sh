#!/usr/bin/env bash
# Configures and builds msdeform (Release, Ninja) into build/. Pass extra CMake options as arguments.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
jobs="${MSD_JOBS:-$(nproc)}"
cmake -S "$root" -B "$root/build" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$root/build" -j "$jobs"
