#!/usr/bin/env bash
# Style kept by a machine. (1) No source line over .clang-format's ColumnLimit in src/, firmware/,
# tests/ and bench/ beyond the allowance tests/style/long_lines.txt grants a file (the lines that
# predate the check; a file may only go down): needs no git, so a fresh clone checks it too.
# (2) With git and git-clang-format, the lines changed since the base (MCG_STYLE_BASE, else the
# merge base with origin/main or main) are as clang-format would write them; on a clone whose
# HEAD is the base nothing has changed and (1) alone speaks.
# Args: TOOL_DIR SOURCE_DIR.
src=$(cd "$2" && pwd)
source "$(dirname "$0")/lib.sh"
cd "$src" || exit 1

limit=$(awk -F': *' '$1 == "ColumnLimit" { print $2 }' .clang-format)
check "the column limit is read from .clang-format" test -n "$limit"

# Long lines per file now, against the allowance.
find src firmware tests bench -type f \( -name '*.c' -o -name '*.h' -o -name '*.cpp' -o -name '*.hpp' \) \
  -not -path '*/corpus/*' | LC_ALL=C sort | while read -r f; do
  n=$(LC_ALL=C.UTF-8 awk -v m="$limit" 'length($0) > m { c++ } END { print c + 0 }' "$f")
  [ "$n" -gt 0 ] && echo "$f $n"
done > "$work/long.txt"
over=$(awk 'NR == FNR && /^#/ { next }
  NR == FNR { allowed[$1] = $2; next }
  $2 > allowed[$1] + 0 { printf "%s: %d lines over the limit, %d allowed\n", $1, $2, allowed[$1] + 0 }' \
  tests/style/long_lines.txt "$work/long.txt")
check "no file has more lines over $limit columns than tests/style/long_lines.txt allows" \
  eval '[ -z "$over" ] || { echo "$over" | sed "s/^/  /"; false; }'

base=${MCG_STYLE_BASE:-}
if [ -z "$base" ] && git rev-parse --git-dir > /dev/null 2>&1; then
  for ref in origin/main main; do
    base=$(git merge-base HEAD "$ref" 2> /dev/null) && break
  done
fi
if [ -n "$base" ] && command -v git-clang-format > /dev/null; then
  diff=$(git clang-format --quiet --diff "$base" -- src firmware/core firmware/include tests bench 2>&1)
  check "lines changed since ${base:0:12} are as clang-format writes them" \
    eval '[ -z "$diff" ] || [ "$diff" = "no modified files to format" ] || { echo "$diff" | head -40; false; }'
else
  echo "skip clang-format on changed lines: no git base or no git-clang-format"
fi
finish style
