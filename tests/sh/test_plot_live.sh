#!/usr/bin/env bash
# mcg-plot-gnuplot --live as a person watches it: a simulated run paced to about real time
# drawn as it arrives, (a) into a PNG rewritten while the stream runs (every look at it a
# whole PNG, showing the newest window; a shaft at rest drawn without a gnuplot warning),
# (b) as text redrawn in place in a tmux pane, (c) in an x11 window under Xvfb, screenshotted,
# (d) frames still arriving at the interval after 30 s of paced rows (the reader hands on what
# the pipe has instead of waiting for a buffer to fill).
# Args: TOOL_DIR SOURCE_DIR; exit 125 = skipped.
set -u
tools=$1
export PATH="$tools:$PATH" LC_ALL=C
for p in gnuplot tmux Xvfb xwd xwdtopnm pnmtopng ppmhist; do
  command -v "$p" >/dev/null || { echo "skipped: $p missing"; exit 125; }
done
gnuplot -e "set print '-'; print GPVAL_TERMINALS" | grep -qw x11 || { echo "skipped: gnuplot without x11"; exit 125; }
source "$(dirname "$0")/lib.sh"
session=mcg-live-$$
trap 'tmux -L "$session" kill-server 2>/dev/null; cleanup' EXIT

# A 4 s run, sent at about real time (50 rows, then 50 ms).
mcg-sweep prbs --bias 6 --amp 3 --clock 0.1 --duration 4 --seed 5 | mcg-sim >"$work/run.csv"
cat >"$work/paced.sh" <<'PACE'
awk '/^#/ || /^t,/ { print; next } { print } NR % 50 == 0 { fflush(); system("sleep 0.05") }' "$1"
PACE

# whole_png FILE: a PNG signature at the start and the IEND chunk at the end.
whole_png() {
  [[ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" == 89504e470d0a1a0a ]] &&
    [[ "$(tail -c 8 "$1" | od -An -tx1 | tr -d ' \n')" == 49454e44ae426082 ]]
}

# (a) A PNG rewritten as the rows arrive.
bash "$work/paced.sh" "$work/run.csv" |
  mcg-plot-gnuplot --live -y rpm --window 1 --interval 0.2 -o "$work/live.png" 2>"$work/png.err" &
pid=$!
looks=0 versions=0 last=
for _ in $(seq 40); do
  sleep 0.1
  [[ -f "$work/live.png" ]] || continue
  cp "$work/live.png" "$work/look.png" 2>/dev/null || continue
  looks=$((looks + 1))
  whole_png "$work/look.png" || fail "png: a look at the file found a partial PNG"
  sum=$(md5sum <"$work/look.png")
  [[ "$sum" != "$last" ]] && versions=$((versions + 1)) && last=$sum
done
wait "$pid" || fail "png: exit $? ($(tail -1 "$work/png.err"))"
if ((versions >= 3)); then
  echo "ok   png: $versions versions of the PNG in $looks looks while streaming, each whole"
else
  fail "png: only $versions versions in $looks looks"
fi
[[ -e "$work/live.png.part" ]] && fail "png: the temporary file was left behind"
# A shaft at rest for the first 1.5 s: frames of one value, drawn without a gnuplot warning.
mcg-sweep step --level 6 --at 1.5 --duration 2 | mcg-sim >"$work/rest.csv"
bash "$work/paced.sh" "$work/rest.csv" |
  mcg-plot-gnuplot --live -y rpm --y2 i --window 1 --interval 0.2 -o "$work/rest.png" 2>"$work/rest.err" ||
  fail "png at rest: exit $?"
if [[ -s "$work/rest.err" ]]; then
  fail "png at rest: stderr: $(head -1 "$work/rest.err")"
else
  echo "ok   png at rest: frames of one value drawn without a warning"
fi

# (b) Text redrawn in place in a terminal.
tmux -L "$session" new-session -d -s "$session" -x 110 -y 36 \
  "bash $work/paced.sh $work/run.csv | mcg-plot-gnuplot --live --term dumb --size 100,30 -y rpm --window 1 --interval 0.2; echo live-exit=\$?; sleep 30"
sleep 1.5
tmux -L "$session" capture-pane -p -t "$session" >"$work/pane1.txt"
sleep 1.2
tmux -L "$session" capture-pane -p -t "$session" >"$work/pane2.txt"
for pane in pane1 pane2; do
  n=$(grep -c 't (s)' "$work/$pane.txt")
  [[ $n -eq 1 ]] || fail "dumb: $pane shows the x label $n times (frames must replace each other)"
done
if cmp -s "$work/pane1.txt" "$work/pane2.txt"; then
  fail "dumb: the pane did not change between looks"
else
  echo "ok   dumb: one frame on the pane at a time, redrawn as the stream goes on"
fi
for _ in $(seq 50); do
  grep -q 'live-exit=' <(tmux -L "$session" capture-pane -p -t "$session") && break
  sleep 0.2
done
tmux -L "$session" capture-pane -p -t "$session" | grep -q 'live-exit=0' || fail "dumb: did not end with status 0"

# (c) A window under Xvfb, screenshotted while the stream runs.
for display in $(seq 90 110); do
  [[ -e /tmp/.X11-unix/X$display || -e /tmp/.X$display-lock ]] || break
done
Xvfb ":$display" -screen 0 1100x700x24 -nolisten tcp 2>"$work/xvfb.err" &
xvfb_pid=$!
bg_pids+=("$xvfb_pid")
for _ in $(seq 50); do
  [[ -e /tmp/.X11-unix/X$display ]] && break
  sleep 0.1
done
bash "$work/paced.sh" "$work/run.csv" |
  DISPLAY=":$display" mcg-plot-gnuplot --live -y rpm --window 1 --interval 0.2 --size 1000,600 2>"$work/x11.err" &
pid=$!
sleep 2.5
xwd -root -display ":$display" 2>/dev/null | xwdtopnm 2>/dev/null | pnmtopng >"$work/window.png" 2>/dev/null
wait "$pid" || fail "x11: exit $? ($(tail -1 "$work/x11.err"))"
colours=$(pngtopnm "$work/window.png" 2>/dev/null | ppmhist -noheader 2>/dev/null | wc -l)
if ((colours >= 3)); then
  echo "ok   x11: the window drew the plot ($colours colours on the screenshot)"
  [[ -n "${MCG_KEEP_SCREENSHOT:-}" ]] && cp "$work/window.png" "$MCG_KEEP_SCREENSHOT"
else
  fail "x11: the screenshot is blank ($colours colours)"
fi

# (d) 36 s of rows at about 500 a second (50 rows, then 0.1 s), into a PNG redrawn every 0.5 s:
# between 30 s and 35 s the PNG must still be replaced at about the interval (each frame is
# renamed over it: a new inode). A reader that waits to fill a growing buffer drew at 0.6, 1.6,
# 3.2, 6.2, 12.2, 24.2 s and then not before 48 s.
awk 'BEGIN { print "t,y"; for (k = 0; k < 18000; k++) { printf "%.3f,%d\n", k * 0.002, k % 100
  if (k % 50 == 49) { fflush(); system("sleep 0.1") } } }' |
  mcg-plot-gnuplot --live -y y --window 5 --interval 0.5 -o "$work/long.png" 2>"$work/long.err" &
pid=$!
start=$EPOCHREALTIME last_inode= frames=()
while :; do
  now=$EPOCHREALTIME
  elapsed=$(awk -v a="$start" -v b="$now" 'BEGIN { printf "%.3f", b - a }')
  awk -v e="$elapsed" 'BEGIN { exit !(e >= 35) }' && break
  inode=$(stat -c %i "$work/long.png" 2>/dev/null)
  if [[ -n "$inode" && "$inode" != "$last_inode" ]]; then
    frames+=("$elapsed")
    last_inode=$inode
  fi
  sleep 0.05
done
wait "$pid" || fail "long: exit $? ($(tail -1 "$work/long.err"))"
# Frames drawn from 30 s on, and the longest wait for one (from 30 s, between frames, to 35 s).
read -r late gap < <(printf '%s\n' "${frames[@]}" | awk -v from=30 -v to=35 '
  BEGIN { prev = from }
  $1 >= from { n++; if ($1 - prev > gap) gap = $1 - prev; prev = $1 }
  END { if (to - prev > gap) gap = to - prev; printf "%d %.2f\n", n, gap }')
if ((late >= 4)) && awk -v g="$gap" 'BEGIN { exit !(g <= 2) }'; then
  echo "ok   long: $late frames between 30 s and 35 s of a paced stream (longest wait $gap s; interval 0.5 s)"
else
  fail "long: $late frames between 30 s and 35 s, longest wait $gap s" \
    "(interval 0.5 s; ${#frames[@]} frames in all)"
fi

((failures == 0))
