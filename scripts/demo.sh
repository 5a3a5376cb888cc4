#!/usr/bin/env bash
# Sets up, builds and runs the main job on built-in data.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bash "$root/scripts/setup.sh"
bash "$root/scripts/build.sh"
"$root/build/apps/msdeform" info --scene lift --resolution 100k
