#!/usr/bin/env bash
# Sets up, builds and runs the main job on built-in data: every method and detail encoding on the
# bumpy-plane and bumpy-bar benchmark edits, written to compare-out/ (open compare-out/index.html).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bash "$root/scripts/setup.sh"
bash "$root/scripts/build.sh"
cd "$root"
"$root/build/apps/msdeform" compare -o compare-out "$@"
