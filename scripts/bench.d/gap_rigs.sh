# mcg-fit gap on varied self-made rigs (tests/sh/rigs_lib.sh: a small motor behind a driver dead
# band, a gearmotor sampled slowly, a current-driven drive), each given to gap by its datasheet
# without friction or dead band: one row per rig with what gap named against the withheld truth
# and its wall time against the budget (one thread, bench/bench_gap_rigs.sh). GAP_RIGS lists the
# rigs as KIND:SEED (default: deadband:1 gearmotor:2 current:3); GAP_RIGS_BUDGET the budget. A
# last row runs the gearmotor rig (7500 rows at 100 Hz) on two threads against the goal of a
# 7000-row file in 10 s.
# Sourced by scripts/bench.sh (row, met, wanted, $work, $raw, $root, $tools).
if wanted gap_rigs; then
  rigs_budget=${GAP_RIGS_BUDGET:-120}
  read -ra rigs <<<"${GAP_RIGS:-deadband:1 gearmotor:2 current:3}"
  bash "$root/bench/bench_gap_rigs.sh" "$tools" "$rigs_budget" "${rigs[@]}" >"$work/gap_rigs.txt" 2>&1 || true
  cat "$work/gap_rigs.txt" >>"$raw"
  # A line: "KIND:SEED | want W | got G | shrink S | exit E | T s, cpu C s | parameters".
  while IFS='|' read -r spec want got shrink status seconds params; do
    want=${want# want } want=${want% } got=${got# got } got=${got% }
    cpu=${seconds#*, } cpu=${cpu% } seconds=${seconds# } seconds=${seconds%% s*}
    ok=$(met "$seconds" "<=" "$(awk -v b="$rigs_budget" 'BEGIN {print b * 1.1}')")
    [[ $got == "$want" ]] || ok="missed (named $got)"
    row "\`mcg-fit gap\` on the self-made rig ${spec% } (\`bench/bench_gap_rigs.sh\`, one thread)" whole-process \
      "the withheld effects named, <= budget ${rigs_budget} s + 10 %" \
      "${seconds} s (${cpu}), named ${got} (withheld ${want}),${shrink% } %,${status% };${params}" "$ok"
  done <"$work/gap_rigs.txt"
  GAP_RIGS_THREADS=2 GAP_RIGS_KEEP="$work/gap_rows" bash "$root/bench/bench_gap_rigs.sh" "$tools" "$rigs_budget" \
    gearmotor:2 >"$work/gap_rows.txt" 2>&1 || true
  cat "$work/gap_rows.txt" >>"$raw"
  nrows=$(cat "$work/gap_rows/gearmotor-2/train.csv" "$work/gap_rows/gearmotor-2/validate.csv" 2>/dev/null |
    awk '!/^#/ && !/^t,/ { n++ } END { print n + 0 }')
  IFS='|' read -r spec want got shrink status seconds params <"$work/gap_rows.txt"
  got=${got# got } got=${got% } cpu=${seconds#*, } cpu=${cpu% } seconds=${seconds# } seconds=${seconds%% s*}
  ok=$(met "$seconds" "<=" 10)
  row "\`mcg-fit gap\` on a ${nrows}-row gearmotor file (the rig gearmotor:2 at 100 Hz, two threads)" whole-process \
    "<= 10 s" "${seconds} s (${cpu}), named ${got}" "$ok"
fi
