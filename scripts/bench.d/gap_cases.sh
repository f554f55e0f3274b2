# mcg-fit gap as users run it (whole process, CSV in, both cores, the default budget) on each
# public gap case: train.csv and validate.csv of every directory under GAP_CASES (default: the
# shared data beside the project's checkout, ../shared/data/gap-cases; the rows say so when it
# is absent). One run a case; the rows name the diagnosis, and the total is set against the
# goal (the eight cases in <= 40 s together on 2 cores). Real captures: gap_real.sh. Sourced by
# scripts/bench.sh (row, met, wanted, $work, $raw, $root).
if wanted gap_cases; then
  cases=${GAP_CASES:-$root/../shared/data/gap-cases}
  if [[ ! -d $cases ]]; then
    row "\`mcg-fit gap\` on each public gap case" whole-process "<= 40 s for the eight together" \
      "not measured: no gap cases at ${cases##*/} (set GAP_CASES)" "missed (no data)"
  else
    total_ms=0
    n=0
    for dir in "$cases"/*/; do
      name=$(basename "$dir")
      [[ -f $dir/train.csv && -f $dir/validate.csv ]] || continue
      t0=$(date +%s%N)
      status=0
      mcg-fit gap --train "$dir/train.csv" --validate "$dir/validate.csv" >"$work/gap_$name.csv" \
        2>"$work/gap_$name.err" || status=$?
      t1=$(date +%s%N)
      ms=$(((t1 - t0) / 1000000))
      total_ms=$((total_ms + ms))
      n=$((n + 1))
      verdict=$(awk -F, '!/^#/ && ++rows == 2 {print $1; exit}' "$work/gap_$name.csv")
      echo "== mcg-fit gap on $name: $ms ms, exit $status, diagnosis ${verdict:-(no output)}" >>"$raw"
      secs=$(awk -v m="$ms" 'BEGIN {printf "%.1f", m / 1000}')
      row "\`mcg-fit gap\` on the public case $name (train + validate CSV, 2 cores)" whole-process \
        "(the eight <= 40 s together)" "$secs s, diagnosis ${verdict:-(no output)}, exit $status" "-"
    done
    s=$(awk -v m="$total_ms" 'BEGIN {printf "%.1f", m / 1000}')
    row "\`mcg-fit gap\` on the $n public gap cases, one after another" whole-process "<= 40 s together" \
      "$s s" "$(met "$s" "<=" 40)"
  fi
fi

# The same with the fits' Jacobians by sensitivities (--jacobian sensitivities), against the
# default's diagnoses of the row above (run it with gap_cases).
if wanted gap_cases_jacobian; then
  cases=${GAP_CASES:-$root/../shared/data/gap-cases}
  if [[ -d $cases ]]; then
    total_ms=0
    same=0
    n=0
    for dir in "$cases"/*/; do
      name=$(basename "$dir")
      [[ -f $dir/train.csv && -f $dir/validate.csv ]] || continue
      t0=$(date +%s%N)
      mcg-fit gap --train "$dir/train.csv" --validate "$dir/validate.csv" --jacobian sensitivities \
        >"$work/gap_sens_$name.csv" 2>/dev/null || true
      t1=$(date +%s%N)
      total_ms=$((total_ms + (t1 - t0) / 1000000))
      n=$((n + 1))
      verdict=$(awk -F, '!/^#/ && ++rows == 2 {print $1; exit}' "$work/gap_sens_$name.csv")
      before=$(awk -F, '!/^#/ && ++rows == 2 {print $1; exit}' "$work/gap_$name.csv" 2>/dev/null || true)
      [[ -n $verdict && $verdict == "$before" ]] && same=$((same + 1))
      echo "== mcg-fit gap --jacobian sensitivities on $name: $(((t1 - t0) / 1000000)) ms, diagnosis ${verdict:-(none)}" >>"$raw"
    done
    s=$(awk -v m="$total_ms" 'BEGIN {printf "%.1f", m / 1000}')
    row "\`mcg-fit gap --jacobian sensitivities\` on the $n public gap cases, one after another" whole-process \
      "(against the default's row)" "$s s, $same of $n diagnoses as by differences" "-"
  fi
fi
