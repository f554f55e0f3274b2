#!/usr/bin/env bash
# The main job (scripts/main-job.sh, what scripts/run.sh runs after building) as a new user runs
# it: it ends with status 0, prints the summary the README shows, line for line up to its "  ..."
# (the directory aside), with the diagnosis' first 12 lines, and leaves every file the summary
# names. (Its summary once piped the diagnosis into head: when head left
# first, sed died of the closed pipe and the job ended with status 141, a race this cannot
# force.) Args: TOOL_DIR SOURCE_DIR.
set -u
tools=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
source "$(dirname "$0")/lib.sh"

"$src/scripts/main-job.sh" "$tools" "$work/out" > "$work/summary.txt" 2> "$work/err.txt"
status=$?
[ "$status" = 0 ] || fail "main-job.sh ended with status $status ($(tail -1 "$work/err.txt"))"
grep -q "^mcg main job on the built-in rig: files in $work/out$" "$work/summary.txt" || fail "no summary title"
grep -q "^  gap.csv, gap.txt          diagnosis: supply_sag$" "$work/summary.txt" || fail "the diagnosis is not supply_sag"
# The README's block: from its title line to the fence, without the closing "  ...".
awk '/^mcg main job on the built-in rig: files in out$/ { on = 1 } on && /^```/ { exit } on' \
  "$src/README.md" > "$work/readme.txt"
[ "$(tail -1 "$work/readme.txt")" = "  ..." ] || fail "the README's main-job block does not end in '  ...'"
sed -i '$d' "$work/readme.txt"
[ -s "$work/readme.txt" ] || fail "no main-job block in the README"
sed "1s|files in $work/out\$|files in out|" "$work/summary.txt" | head -n "$(wc -l < "$work/readme.txt")" \
  > "$work/shown.txt"
diff -u "$work/readme.txt" "$work/shown.txt" >&2 || fail "the summary differs from the README's block (diff above)"
[ "$(awk '/^  gap.csv, gap.txt / { on = 1; next } on' "$work/summary.txt" | wc -l)" = 12 ] || fail "the summary does not show the diagnosis' first 12 lines"
for f in step.csv step.png bode.csv bode.png plant.ini pi.ini verify.csv verify.png gap.csv gap.txt; do
  [ -s "$work/out/$f" ] || fail "$f missing or empty"
done
[ "$failures" = 0 ] && echo "main job: status 0, summary and files as the README says"
[ "$failures" = 0 ]
