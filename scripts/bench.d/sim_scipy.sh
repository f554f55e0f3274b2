# mcg-sim against scipy's LSODA (max_step 10 ms) on the same scenarios, side by side in one run,
# whole processes with CSV in and out (bench/sim_scipy.py, Debian's python3-scipy; the rows say
# so when it is absent): 60 s of the coupled rig at 1 ms under a 12 V step, and the staircase
# through zero (0 -> 12 V -> -12 V -> 0 in 2 V steps of 2.5 s, clutch engaged, 5.6 ohm load:
# reversals, sticking and breakaway). The two outputs must agree (RMS of the rpm difference)
# before the times mean anything. Sourced by scripts/bench.sh (row, met, wanted, wall_ms, $work,
# $raw).
if wanted sim_scipy; then
  # side_by_side NAME WHAT SPEED_GOAL RATIO_GOAL RMS_GOAL: times mcg-sim and sim_scipy.py on
  # $work/NAME_in.csv and adds the row.
  side_by_side() {
    local name=$1 what=$2 speed_goal=$3 ratio_goal=$4 rms_goal=$5 in="$work/$1_in.csv"
    local sim_ms py_ms rms ratio x ok goal
    sim_ms=$(wall_ms 5 "mcg-sim < '$in' > '$work/${name}_mcg.csv'")
    # LSODA may chatter at a speed's sign change: one run, bounded, says whether it finishes at all.
    if ! timeout 120 /usr/bin/python3 "$root/bench/sim_scipy.py" "$work/scipy_params.txt" "$in" "$work/${name}_py.csv"; then
      row "\`mcg-sim\` against scipy LSODA (max_step 10 ms), $what, CSV in and out" whole-process \
        ">= ${ratio_goal}x faster" "mcg-sim ${sim_ms} ms; LSODA did not finish within 120 s" "not compared"
      return
    fi
    py_ms=$(wall_ms 3 "/usr/bin/python3 '$root/bench/sim_scipy.py' '$work/scipy_params.txt' '$in' '$work/${name}_py.csv'")
    rms=$(paste -d, <(grep -v '^#' "$work/${name}_mcg.csv" | awk -F, 'NR == 1 {for (k = 1; k <= NF; k++) if ($k == "rpm") c = k} {print $c}') \
      <(cut -d, -f2 "$work/${name}_py.csv") | awk -F, 'NR > 1 {d = $1 - $2; s += d * d; n++} END {printf "%.3g", sqrt(s / n)}')
    ratio=$(awk -v a="$py_ms" -v b="$sim_ms" 'BEGIN {printf "%.1f", a / b}')
    x=$(awk -v ms="$sim_ms" 'BEGIN {printf "%.0f", 60000 / ms}')
    echo "== mcg-sim vs scipy LSODA, $name: mcg-sim $sim_ms ms, scipy $py_ms ms, rpm RMS difference $rms rpm" >>"$raw"
    ok=$(met "$ratio" ">=" "$ratio_goal")
    goal=">= ${ratio_goal}x faster"
    if [[ -n $speed_goal ]]; then
      goal="$goal, >= ${speed_goal}x real time"
      [[ $(met "$x" ">=" "$speed_goal") == yes ]] || ok=missed
    fi
    [[ $(met "$rms" "<=" "$rms_goal") == yes ]] || ok="missed (the outputs differ: $rms rpm)"
    row "\`mcg-sim\` against scipy LSODA (max_step 10 ms), $what, CSV in and out" whole-process \
      "$goal, within $rms_goal rpm RMS" \
      "${sim_ms} ms (${x}x real time) against ${py_ms} ms = ${ratio}x (rpm RMS difference ${rms} rpm)" "$ok"
  }
  if ! /usr/bin/python3 -c 'import scipy' 2>/dev/null; then
    row "\`mcg-sim\` against scipy LSODA, 60 s coupled step and staircase through zero" whole-process \
      ">= 5x / >= 20x faster" "not measured: python3-scipy is not installed" "missed (install python3-scipy)"
  else
    mcg-fit model --list >"$work/scipy_params.txt"
    mcg-sweep step --column v --level 12 --at 0.5 --duration 60 >"$work/step_in.csv"
    side_by_side step "60 s coupled step" "" 5 1
    mcg-sweep staircase --amp 12 --steps 6 --hold 2.5 --duration 60 --clutch 2 --r-load 5.6 >"$work/stair_in.csv"
    side_by_side stair "60 s staircase through zero (0 -> 12 V -> -12 V -> 0, clutch engaged, 5.6 ohm load)" \
      2000 20 0.2
  fi
fi
