#!/usr/bin/env bash
# mcg-plot-gnuplot with the real gnuplot: PNG, SVG, PDF and text output, a Bode plot of a
# mcg-sweep response, an overlay, and hostile headers, titles and file names that must not
# run anything. Usage: test_plot.sh TOOL_DIR SOURCE_DIR (exit 125 = skipped: no gnuplot).
set -u
tool_dir=$1
export PATH="$tool_dir:$PATH" LC_ALL=C
command -v gnuplot >/dev/null || { echo "gnuplot missing: skipped"; exit 125; }
source "$(dirname "$0")/lib.sh"
cd "$work" || exit 1
magic() { head -c "$2" "$1" | od -An -tx1 | tr -d ' \n'; }

# A step with a first-order speed and a current, both measured and "simulated".
mcg-sweep step --level 12 --at 0.1 --then 6@0.5 --duration 1 --clutch 2 --r-load 5.6 |
  awk -F, '/^#/ {print; next} /^t/ {print $0 ",rpm,i"; next}
           {printf "%s,%.6g,%.6g\n", $0, $2 * 100 * (1 - exp(-$1 * 10)), $2 * 0.3}' >step.csv
awk -F, 'BEGIN {OFS = ","} /^#/ || /^t/ {print; next} {$5 = $5 * 1.05; print}' step.csv >sim.csv

mcg-plot-gnuplot -y rpm --y2 i -o step.png <step.csv
expect "PNG written with the PNG signature" '[ "$(magic step.png 8)" = 89504e470d0a1a0a ]'
mcg-plot-gnuplot -y rpm,v -o step.svg <step.csv
expect "SVG written" 'grep -q "<svg" step.svg && grep -q "rpm (rev/min)" step.svg'
mcg-plot-gnuplot -y rpm -o step.pdf step.csv --overlay sim.csv
expect "PDF written" '[ "$(head -c 4 step.pdf)" = "%PDF" ]'

mcg-plot-gnuplot -y rpm --term dumb --size 90,25 <step.csv >step.txt
expect "text plot on stdout" '[ "$(wc -l <step.txt)" -ge 20 ] && grep -q "t (s)" step.txt'
expect "title from the excitation metadata" 'grep -q "step on v: 12 V at 0.1 s" step.txt'
expect "legend names the column" 'grep -q "rpm" step.txt'

mcg-sweep multisine --f0 1 --f1 100 --lines 10 --duration 3 |
  awk -F, '/^#/ {print; next} /^t/ {print $0 ",omega"; next} {h[NR] = $2; printf "%s,%.17g\n", $0, (NR > 3 ? h[NR - 3] : 0)}' |
  mcg-sweep bode >bode.csv
mcg-plot-gnuplot --bode -o bode.png <bode.csv
expect "Bode PNG" '[ "$(magic bode.png 8)" = 89504e470d0a1a0a ]'
mcg-plot-gnuplot --bode --term dumb <bode.csv >bode.txt
# Two panels: two frames, each with its own frequency axis label (one panel has one).
expect "Bode text has both panels" '[ "$(grep -c "frequency (Hz)" bode.txt)" -eq 2 ] && [ "$(grep -Ec "^ +[-+0-9.e]+ \+-+\+ *$" bode.txt)" -eq 4 ]'

# Hostile input: a header, metadata title, --title and file name built to break out of a
# gnuplot string and call system(). Nothing may be created but the plots.
printf '%s\n' "# title: x' ; system('touch pwned1') ; print '" \
  't,x"; system("touch pwned2"); ",`touch pwned3`,@GPVAL_PWD' '0,1,2,3' '1,2,3,4' >"evil'\"\`touch pwned4\`.csv"
mcg-plot-gnuplot -o evil.png "evil'\"\`touch pwned4\`.csv" --overlay "evil'\"\`touch pwned4\`.csv"
expect "hostile table plots" '[ "$(magic evil.png 8)" = 89504e470d0a1a0a ]'
mcg-plot-gnuplot --term dumb --title "$(printf 'ok\nsystem("touch pwned5")\n')" <"evil'\"\`touch pwned4\`.csv" >evil.txt
expect "newline in --title stays text" 'grep -q "oksystem" evil.txt'
mcg-plot-gnuplot --term dumb --title "'; system('touch pwned6'); '" <"evil'\"\`touch pwned4\`.csv" >/dev/null
gnuplot -e 'system("touch control")' >/dev/null
expect "a real system() call would have been seen" '[ -e control ]'
expect "nothing ran" '[ -z "$(ls -d pwned1 pwned2 pwned3 pwned4 pwned5 pwned6 2>/dev/null)" ]'

# gnuplot reports its own errors; the tool then fails with one line.
printf 't,x\n0,1\n' >one.csv
mcg-plot-gnuplot --logy -y x -o one.png <one.csv 2>err.txt >/dev/null
expect "a single point still plots" '[ "$(magic one.png 8)" = 89504e470d0a1a0a ]'

finish "plot"
