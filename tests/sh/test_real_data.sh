#!/usr/bin/env bash
# The rules for real measurements in tests/data/real/NAME/ (docs/hacking.md, "How to add a real
# data set"), checked for every set: a LICENSE file and a PROVENANCE.md that names the source and
# a licence that lets the data live here (MIT, BSD, Apache-2.0, CC0, CC BY) and documents every
# column of every data file; no data file of 2 MB or more; a shell suite or unit test that uses
# the set; and each file the set's gap.args names (gap's options for the set, run by the bench
# row gap_real) present beside it. Needs no tool. Args: TOOL_DIR SOURCE_DIR.
src=$(cd "$2" && pwd)
source "$(dirname "$0")/lib.sh"

sets=0
for dir in "$src"/tests/data/real/*/; do
  [[ -d $dir ]] || continue
  name=$(basename "$dir")
  sets=$((sets + 1))
  prov="$dir/PROVENANCE.md"
  check "$name: LICENSE is there and not empty" test -s "$dir/LICENSE"
  check "$name: PROVENANCE.md is there" test -s "$prov"
  [[ -s $prov ]] || continue
  check "$name: PROVENANCE.md has a Source section" grep -q '^## Source' "$prov"
  check "$name: PROVENANCE.md names a licence that allows the data here" \
    grep -Eq 'MIT|BSD|Apache-2\.0|CC0|CC BY' "$prov"
  for csv in "$dir"/*.csv; do
    [[ -f $csv ]] || continue
    file=$(basename "$csv")
    check "$name/$file is under 2 MB" test "$(wc -c <"$csv")" -lt 2000000
    header=$(awk '!/^#/ {print; exit}' "$csv")
    IFS=, read -ra columns <<<"$header"
    for column in "${columns[@]}"; do
      check "$name/$file: column '$column' is described in PROVENANCE.md" grep -qF "\`$column\`" "$prov"
    done
  done
  check "$name: a test uses the set" \
    eval 'grep -q "tests/data/real/$name" "$src"/tests/sh/test_*.sh "$src"/tests/unit/*.cpp'
  if [[ -f $dir/gap.args ]]; then
    for word in $(grep -v '^[[:space:]]*#' "$dir/gap.args"); do
      [[ $word == *.csv || $word == *.ini ]] || continue
      check "$name: $word, named in gap.args, is there" test -f "$dir/$word"
    done
  fi
done
check "at least one real data set ships ($sets)" test "$sets" -ge 1
finish real_data
