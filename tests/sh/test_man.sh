#!/usr/bin/env bash
# Lints every man page with mandoc and checks that each long option a tool's --help
# lists (for the tool and each subcommand) appears in the tool's page.
# Usage: test_man.sh TOOL_DIR SOURCE_DIR
set -u
tool_dir=$1
src=$2
command -v mandoc >/dev/null || { echo "mandoc missing: skipped"; exit 125; }
passed=0
failed=0
check() {
  if [ "$1" = ok ]; then passed=$((passed + 1)); else failed=$((failed + 1)); echo "FAIL: $2"; fi
}
for page in "$src"/man/*.[157]; do
  out=$(mandoc -T lint -W warning "$page" 2>&1)
  if [ -z "$out" ]; then check ok; else check bad "$(basename "$page"): $out"; fi
done
for tool in "$tool_dir"/mcg-*; do
  [ -x "$tool" ] || continue
  name=$(basename "$tool")
  page="$src/man/$name.1"
  if [ ! -f "$page" ]; then check bad "$name has no man page"; continue; fi
  text=$(mandoc -T ascii "$page" | sed "s/.\x08//g")
  helps=$("$tool" --help 2>&1)
  for sub in $("$tool" --help 2>&1 | awk 'tolower($0) ~ /^subcommands:/{s=1;next} s&&/^  [a-z]/{print $1}'); do
    helps="$helps
$("$tool" "$sub" --help 2>&1)"
  done
  for opt in $(printf '%s\n' "$helps" | grep -oE -- '--[a-z][a-z0-9-]*' | sort -u); do
    case "$opt" in --help|--version) continue ;; esac
    if printf '%s' "$text" | grep -qF -- "$opt"; then check ok; else check bad "$name: $opt is in --help but not in $name.1"; fi
  done
done
echo "man: $passed passed, $failed failed"
[ "$failed" = 0 ]
