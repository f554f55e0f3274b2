# mcg-sim against scipy's LSODA (max_step 10 ms) on the same scenario, side by side in one run:
# 60 s of the coupled rig at 1 ms, a 12 V step, whole processes with CSV in and out
# (bench/sim_scipy.py, Debian's python3-scipy; the row says so when it is absent). The two
# outputs must agree (RMS of the rpm difference) before the times mean anything. Sourced by
# scripts/bench.sh (row, met, wanted, wall_ms, $work, $raw).
if wanted sim_scipy; then
  if ! /usr/bin/python3 -c 'import scipy' 2>/dev/null; then
    row "\`mcg-sim\` against scipy LSODA, 60 s coupled step" whole-process ">= 5x faster" \
      "not measured: python3-scipy is not installed" "missed (install python3-scipy)"
  else
    mcg-sweep step --column v --level 12 --at 0.5 --duration 60 >"$work/scipy_in.csv"
    mcg-fit model --list >"$work/scipy_params.txt"
    sim_ms=$(wall_ms 5 "mcg-sim < '$work/scipy_in.csv' > '$work/scipy_mcg.csv'")
    py_ms=$(wall_ms 3 "/usr/bin/python3 '$root/bench/sim_scipy.py' '$work/scipy_params.txt' '$work/scipy_in.csv' '$work/scipy_py.csv'")
    rms=$(paste -d, <(grep -v '^#' "$work/scipy_mcg.csv" | awk -F, 'NR == 1 {for (k = 1; k <= NF; k++) if ($k == "rpm") c = k} {print $c}') \
      <(cut -d, -f2 "$work/scipy_py.csv") | awk -F, 'NR > 1 {d = $1 - $2; s += d * d; n++} END {printf "%.3g", sqrt(s / n)}')
    ratio=$(awk -v a="$py_ms" -v b="$sim_ms" 'BEGIN {printf "%.1f", a / b}')
    echo "== mcg-sim vs scipy LSODA: mcg-sim $sim_ms ms, scipy $py_ms ms, rpm RMS difference $rms rpm" >>"$raw"
    ok=$(met "$ratio" ">=" 5)
    [[ $(met "$rms" "<=" 1) == yes ]] || ok="missed (the outputs differ: $rms rpm)"
    row "\`mcg-sim\` against scipy LSODA (max_step 10 ms), 60 s coupled step, CSV in and out" whole-process \
      ">= 5x faster" "${sim_ms} ms against ${py_ms} ms = ${ratio}x (rpm RMS difference ${rms} rpm)" "$ok"
  fi
fi
