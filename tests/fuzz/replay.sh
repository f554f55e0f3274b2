#!/usr/bin/env bash
# The regression run of one harness over its checked-in corpus (ctest's fuzz.NAME).
# Args: HARNESS CORPUS_DIR LIBFUZZER(1|0). With libFuzzer it also fuzzes for a few seconds
# (MCG_FUZZ_SECONDS, default 5), writing new inputs to a scratch directory, never the corpus.
set -euo pipefail
harness=$1 corpus=$2 libfuzzer=$3
if [ "$libfuzzer" = 1 ]; then
  scratch=$(mktemp -d)
  trap 'rm -rf "$scratch"' EXIT
  exec "$harness" -max_total_time="${MCG_FUZZ_SECONDS:-5}" -timeout=20 -rss_limit_mb=2048 \
    -print_final_stats=1 "$scratch" "$corpus"
fi
exec "$harness" "$corpus"
