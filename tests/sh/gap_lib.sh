# Shared by test_gap.sh and test_gap_range.sh (after lib.sh): one diagnosis case run and read.

# diagnose NAME [GAP ARGS...]: mcg-fit gap on $work/NAME-{train,validate}.csv, its CSV in
# $work/NAME.csv and its stderr in $work/NAME.err; sets effect (column 1 of the first data row)
# and shrink (gap_shrink_pct, column 7). Counts a failure and returns 1 when mcg-fit fails.
diagnose() {
  local name=$1
  shift
  local out="$work/$name.csv" row
  if ! mcg-fit gap --train "$work/$name-train.csv" --validate "$work/$name-validate.csv" "$@" >"$out" \
    2>"$work/$name.err"; then
    fail "$name: mcg-fit gap failed: $(tail -1 "$work/$name.err")"
    return 1
  fi
  row=$(grep -v '^#' "$out" | sed -n 2p)
  effect=$(cut -d, -f1 <<<"$row")
  shrink=$(cut -d, -f7 <<<"$row")
}
