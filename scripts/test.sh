#!/usr/bin/env bash
# Installs what is missing, builds with warnings as errors, runs every test, then runs the
# unit tests once more under AddressSanitizer and UndefinedBehaviorSanitizer.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
jobs=$(nproc)
BUILD_DIR="$root/build" "$root/scripts/build.sh" -DMCG_WERROR=ON
ctest --test-dir "$root/build" --output-on-failure -j "$jobs"
BUILD_DIR="$root/build-asan" BUILD_TYPE=Debug "$root/scripts/build.sh" -DMCG_WERROR=ON -DMCG_SANITIZE=ON -DMCG_BUILD_BENCH=OFF
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir "$root/build-asan" --output-on-failure -j "$jobs" -L unit
