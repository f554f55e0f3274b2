#!/usr/bin/env bash
# Runs the README's walkthrough as it stands, in an empty directory, and every command of every
# man page's EXAMPLES section, and fails when a command fails or its shown output drifts. The rule (stated in the README): the lines under a `$`
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

cd "$work" || exit 1
for pid in "${bg_pids[@]}"; do kill "$pid" 2> /dev/null; done
wait 2> /dev/null
bg_pids=()

# The man pages' EXAMPLES: each .EX/.EE or .nf/.fi block whose first line is a command is run,
# in a fresh directory per page, its troff escapes undone (\- is -, \e is \). A line ending in
# a backslash continues the command, `for` runs to its `done`; a line that starts no command is
# the shown output of the command above it, compared as in the walkthrough. Blocks that show
# data or bytes (mcg-csv(5)'s table, mcg-protocol(7)'s frames) start no command and are not run.
# The rig's port /dev/ttyUSB0 is an emulated board (mcg-sim --board) started for the page; the
# inputs an example names without making them are made first from the model (make_inputs); an
# example on published data outside the project (EMPS) is skipped.
make_inputs() {
  mcg-sweep prbs --bias 6 --amp 3 --clock 0.05 --duration 1 --clutch 2 > in.csv
  mcg-sweep chirp --bias 6 --amp 2 --f0 1 --f1 100 --duration 4 --clutch 2 | mcg-sim |
    mcg-sweep bode --in v --out omega > bode.csv
  mcg-sweep step --level 12 --at 0.1 --duration 1 --clutch 2 | mcg-sim --encoder > measured.csv
  mcg-sweep step --level 12 --at 0.1 --duration 1 --clutch 2 | mcg-sim > simulated.csv
  mcg-sweep staircase --amp 14 --steps 10 --hold 0.3 --clutch 0 | mcg-sim > staircase.csv
  mkdir -p runs
  mcg-sweep prbs --bias 6 --amp 6 --clock 0.02 --duration 4 --clutch 2 --r-load-schedule inf@0,5.6@2 --seed 1 |
    mcg-sim --encoder > runs/a.csv
  mcg-sweep prbs --bias 9 --amp 6 --clock 0.05 --duration 4 --clutch 0 --seed 2 | mcg-sim --encoder > runs/b.csv
}
# run_man_command PAGE N: runs $page_dir/cmd.N (background when it ends in &), compares out.N.
run_man_command() {
  local page=$1 k=$2 cmd label status link
  cmd=$(cat "$page_dir/cmd.$k")
  label="$page: $(head -1 "$page_dir/cmd.$k" | cut -c1-80)"
  # Published data of another drive, outside the project (test_emps.sh runs it when present).
  if grep -q 'emps' "$page_dir/cmd.$k" && [ ! -e emps_estimation_DATA_EMPS.csv ]; then
    echo "skip $label (the EMPS data is not in the project)"
    return
  fi
  if [[ "$cmd" =~ \&[[:space:]]*$ ]]; then
    bash -c "exec ${cmd%&}" > "$page_dir/bg.$k" 2>&1 &
    bg_pids+=($!)
    link=$(grep -o -- '--\(board\|link\) [^ ]*' "$page_dir/cmd.$k" | head -1 | cut -d' ' -f2)
    check "background: $label" wait_for "$link"
    return
  fi
  timeout 120 bash -o pipefail -c "$cmd" > "$page_dir/got.$k" 2>&1
  status=$?
  check "exits 0: $label" eval '[ "$status" = 0 ] || { head -5 "$page_dir/got.$k"; false; }'
  if [ -s "$page_dir/out.$k" ]; then
    check "shown output: $label" eval 'diff "$page_dir/out.$k" "$page_dir/got.$k"'
  fi
}
man_commands=0
for man in "$src"/man/*.[157]; do
  page=$(basename "$man")
  page_dir=$work/man-$page
  mkdir -p "$page_dir/run"
  awk '/^\.SH EXAMPLES?/ { on = 1; next } /^\.SH/ { on = 0 } on' "$man" |
    awk -v dir="$page_dir" '
      function is_cmd(l) { return l ~ /^(mcg-[a-z-]+|for|done|sed|awk|printf|cat|cd)([ \t]|$)/ }
      /^\.(EX|nf)$/ { block = 1; first = 1; next }
      /^\.(EE|fi)$/ { block = 0; cont = 0; loop = 0; next }
      !block || /^\.(RS|RE|PP|IP)/ { next }
      {
        gsub(/\\-/, "-"); gsub(/\\e/, "\\"); gsub(/\\\(mu/, "x")
        line = $0
        if (first && !is_cmd(line)) { block = 0; next }
        first = 0
        if (cont || loop) { print line > (dir "/cmd." n); cont = line ~ /\\$/; if (line ~ /^done/) loop = 0; next }
        if (is_cmd(line)) {
          n++; print line > (dir "/cmd." n); printf "" > (dir "/out." n)
          cont = line ~ /\\$/; loop = line ~ /^for /; next
        }
        print line > (dir "/out." n)
      }
      END { print n + 0 > (dir "/count") }'
  count=$(cat "$page_dir/count")
  [ "$count" = 0 ] && continue
  man_commands=$((man_commands + count))
  cd "$page_dir/run" || exit 1
  make_inputs
  sed -i 's|/dev/ttyUSB0|./ttyRIG|g' "$page_dir"/cmd.*
  if grep -q -- '-p ./ttyRIG' "$page_dir"/cmd.*; then
    timeout 300 mcg-sim --board ./ttyRIG --speed 4 > "$page_dir/rig.log" 2>&1 &
    bg_pids+=($!)
    wait_for ./ttyRIG
  fi
  for k in $(seq "$count"); do run_man_command "$page" "$k"; done
  for pid in "${bg_pids[@]}"; do kill "$pid" 2> /dev/null; done
  wait 2> /dev/null
  bg_pids=()
  cd "$work" || exit 1
done
check "the man pages' EXAMPLES have commands ($man_commands)" [ "$man_commands" -gt 30 ]

echo "docs: $((checks - failures)) of $checks checks passed"
[ "$failures" = 0 ]
