#!/usr/bin/env bash
# Runs the table-driven CLI cases of one tool: each case is a directory holding
#   cmd     one shell line, run with the built tools first on PATH (required)
#   stdin   fed to the command (default: empty)
#   stdout  expected stdout, byte for byte (unchecked when absent)
#   stderr  expected stderr, byte for byte (default: empty)
#   exit    expected exit status (default: 0)
# Usage: run_cases.sh TOOL_DIR SUITE_DIR
set -u
tool_dir=$1
suite=$2
export PATH="$tool_dir:$PATH" LC_ALL=C TZ=UTC
passed=0
failed=0
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for case_dir in "$suite"/*/; do
  case_dir=${case_dir%/}
  name=$(basename "$case_dir")
  [ -f "$case_dir/cmd" ] || continue
  run="$work/$name"
  mkdir -p "$run"
  stdin_file=/dev/null
  [ -f "$case_dir/stdin" ] && stdin_file="$case_dir/stdin"
  (cd "$run" && CASE_DIR="$case_dir" sh -c "$(cat "$case_dir/cmd")" <"$stdin_file" >"$run/.out" 2>"$run/.err")
  status=$?
  want_exit=0
  [ -f "$case_dir/exit" ] && want_exit=$(tr -d '[:space:]' <"$case_dir/exit")
  ok=1
  if [ "$status" != "$want_exit" ]; then
    echo "FAIL $name: exit $status, expected $want_exit"
    ok=0
  fi
  want_err=/dev/null
  [ -f "$case_dir/stderr" ] && want_err="$case_dir/stderr"
  if ! cmp -s "$want_err" "$run/.err"; then
    echo "FAIL $name: stderr differs"
    diff "$want_err" "$run/.err" | head -20
    ok=0
  fi
  if [ -f "$case_dir/stdout" ] && ! cmp -s "$case_dir/stdout" "$run/.out"; then
    echo "FAIL $name: stdout differs"
    diff "$case_dir/stdout" "$run/.out" | head -20
    ok=0
  fi
  if [ $ok = 1 ]; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
done
echo "$(basename "$suite"): $passed passed, $failed failed"
[ "$failed" = 0 ] && [ "$passed" -gt 0 ]
