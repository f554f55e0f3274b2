#!/usr/bin/env bash
# Runs the README's walkthrough as it stands, in an empty directory, and fails when a command
# fails or its shown output drifts. The rule (stated in the README): the lines under a `$`
# command in a console block are its stdout and stderr, compared exactly; a last line `...`
# compares only the lines above it, as the first lines of the output; a command with no lines
# under it must succeed. A command ending in `&` (the emulated board) runs in the background
# until the end. Usage: test_docs.sh TOOL_DIR SOURCE_DIR
tools=$1
src=$2
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
command -v mcg-sim > /dev/null || { echo "mcg-sim not built, skipped"; exit 125; }

# Splits the walkthrough's console blocks into $work/cmd.N (one command, continuation lines
# joined by the shell) and $work/out.N (the lines shown under it).
awk -v dir="$work" '
  /^## Walkthrough/ { in_walk = 1; next }
  /^## / { in_walk = 0 }
  !in_walk { next }
  /^```console/ { in_block = 1; next }
  /^```/ { in_block = 0; cont = 0; next }
  !in_block { next }
  cont { print > (dir "/cmd." n); cont = /\\$/; next }
  /^\$ / { n++; sub(/^\$ /, ""); print > (dir "/cmd." n); printf "" > (dir "/out." n); cont = /\\$/; next }
  { print > (dir "/out." n) }
  END { print n > (dir "/count") }
' "$src/README.md"
count=$(cat "$work/count")
check "the walkthrough has commands ($count)" [ "$count" -gt 10 ]

run_dir=$work/run
mkdir -p "$run_dir"
cd "$run_dir" || exit 1
for k in $(seq "$count"); do
  cmd=$(cat "$work/cmd.$k")
  label=$(head -1 "$work/cmd.$k" | cut -c1-90)
  if [[ "$cmd" =~ \&[[:space:]]*$ ]]; then
    bash -c "exec ${cmd%&}" > "$work/bg.$k" 2>&1 &
    bg_pids+=($!)
    link=$(grep -o -- '--board [^ ]*' "$work/cmd.$k" | cut -d' ' -f2)
    check "background: $label" wait_for "$link"
    continue
  fi
  timeout 120 bash -c "$cmd" > "$work/got.$k" 2>&1
  status=$?
  check "exits 0: $label" eval '[ "$status" = 0 ] || { head -5 "$work/got.$k"; false; }'
  if [ -s "$work/out.$k" ]; then
    if [ "$(tail -1 "$work/out.$k")" = "..." ]; then
      n=$(($(wc -l < "$work/out.$k") - 1))
      check "shown output (first $n lines): $label" eval 'diff <(head -n "$n" "$work/out.$k") <(head -n "$n" "$work/got.$k")'
    else
      check "shown output: $label" eval 'diff "$work/out.$k" "$work/got.$k"'
    fi
  fi
done

echo "docs: $((checks - failures)) of $checks checks passed"
[ "$failures" = 0 ]
