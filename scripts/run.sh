#!/usr/bin/env bash
# Installs what is missing, builds the tools, and runs the main job on the built-in rig.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
BUILD_DIR="$root/build" TARGETS=tools "$root/scripts/build.sh"
"$root/scripts/main-job.sh" "$root/build/src/tools" "${OUT_DIR:-$root/out}"
