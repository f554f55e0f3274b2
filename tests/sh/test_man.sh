#!/usr/bin/env bash
# Lints every man page with mandoc and checks that each long option a tool's --help
# lists (for the tool and each subcommand) appears in the tool's page.
# Usage: test_man.sh TOOL_DIR SOURCE_DIR
set -u
tool_dir=$1
src=$2
command -v mandoc >/dev/null || { echo "mandoc missing: skipped"; exit 125; }
source "$(dirname "$0")/lib.sh"
for page in "$src"/man/*.[157]; do
  out=$(mandoc -T lint -W warning "$page" 2>&1)
  if [ -z "$out" ]; then pass; else fail "$(basename "$page"): $out"; fi
done
for tool in "$tool_dir"/mcg-*; do
  [ -x "$tool" ] || continue
  name=$(basename "$tool")
  page="$src/man/$name.1"
  if [ ! -f "$page" ]; then fail "$name has no man page"; continue; fi
  text=$(mandoc -T ascii "$page" | sed "s/.\x08//g")
  helps=$("$tool" --help 2>&1)
  for sub in $("$tool" --help 2>&1 | awk 'tolower($0) ~ /^subcommands:/{s=1;next} s&&/^  [a-z]/{print $1}'); do
    helps="$helps
$("$tool" "$sub" --help 2>&1)"
  done
  for opt in $(printf '%s\n' "$helps" | grep -oE -- '--[a-z][a-z0-9-]*' | sort -u); do
    case "$opt" in --help|--version) continue ;; esac
    if printf '%s' "$text" | grep -qF -- "$opt"; then pass; else fail "$name: $opt is in --help but not in $name.1"; fi
  done
done
# The built mcg-sim(1) (its EFFECTS generated from the catalog) lints clean, and each effect the
# tool prints has an entry that names each of its parameters and states its default.
if [ -x "$tool_dir/mcg-sim" ]; then
  effects_page="$tool_dir/../../man/mcg-sim.1"
  if [ ! -f "$effects_page" ]; then fail "the built mcg-sim.1 is missing"; fi
  out=$(mandoc -T lint -W warning "$effects_page" 2>&1)
  if [ -z "$out" ]; then pass; else fail "built mcg-sim.1: $out"; fi
  while IFS=$'\t' read -r effect param unit def lo hi meaning; do
    para=$(awk -v e="$effect" '/^\.SH /{s = ($0 == ".SH EFFECTS")} s && $0 == ".B " e {p = 1; next}
      p && /^\.(TP|SH)/ {p = 0} p' "$effects_page")
    if [ -z "$para" ]; then fail "mcg-sim.1 EFFECTS: no entry for $effect"; continue; fi
    if printf '%s' "$para" | grep -qF -- "$param" && printf '%s' "$para" | grep -qF -- "$def"; then
      pass
    else
      fail "mcg-sim.1 EFFECTS: $effect does not state $param (default $def)"
    fi
  done < <("$tool_dir/mcg-sim" --list-effects | grep -v '^#' | tail -n +2)
fi
finish man
