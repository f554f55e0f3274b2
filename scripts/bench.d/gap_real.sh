# mcg-fit gap as users run it (whole process, CSV in, both cores) on each real data set the project
# ships: every tests/data/real/NAME/gap.args (the set's own gap options, which its test runs as
# well; paths are relative to that directory) is one row, its wall time set against its budget
# (gap's --budget, else the tool's default read from its --help) plus the 10 % gap promises.
# GAP_REAL names one more real capture to diagnose against itself as train and validate.
# Sourced by scripts/bench.sh (row, met, wanted, $work, $raw, $root).
if wanted gap_real; then
  # gap_row WHAT DIR ARGS...: runs mcg-fit gap ARGS in DIR and adds the row.
  gap_row() {
    local what=$1 dir=$2 budget t0 t1 s status=0 verdict nrows=0 a
    shift 2
    budget=$(mcg-fit gap --help | sed -n 's/.*--budget FLOAT:POSITIVE=\([0-9.]*\).*/\1/p')
    for ((a = 1; a <= $#; a++)); do
      [[ ${!a} == --budget ]] && { a=$((a + 1)); budget=${!a}; }
      [[ ${!a} == --budget=* ]] && budget=${!a#--budget=}
      [[ ${!a} == *.csv && -f $dir/${!a} ]] &&
        nrows=$((nrows + $(awk '!/^#/ {n++} END {print n - 1}' "$dir/${!a}")))
    done
    t0=$(date +%s%N)
    (cd "$dir" && mcg-fit gap "$@") >"$work/gap_real.csv" 2>"$work/gap_real.err" || status=$?
    t1=$(date +%s%N)
    s=$(awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.1f", (b - a) / 1e9}')
    verdict=$(awk -F, '!/^#/ && ++n == 2 {print $1; exit}' "$work/gap_real.csv")
    echo "== mcg-fit gap on $what: $s s, exit $status, diagnosis ${verdict:-none}" >>"$raw"
    sed 's/^/   /' "$work/gap_real.err" >>"$raw"
    local figure ok
    ok=$(met "$s" "<=" "$(awk -v b="$budget" 'BEGIN {print b * 1.1}')")
    # Exit 4: the budget ran out and the results so far were written, marked partial.
    case $status in
      0) figure="$s s, diagnosis ${verdict:-none}" ;;
      4) figure="$s s, partial at the budget, diagnosis so far ${verdict:-none}" ;;
      *) figure="$s s, exit $status: $(awk '/error/ {print substr($0, 1, 100); exit}' "$work/gap_real.err")"
        ok="missed (gap failed)" ;;
    esac
    row "\`mcg-fit gap\` on $what ($nrows rows)" whole-process "<= its budget ${budget} s + 10 %" \
      "$figure" "$ok"
  }
  n=0
  for args_file in "$root"/tests/data/real/*/gap.args; do
    [[ -f $args_file ]] || continue
    dir=$(dirname "$args_file")
    read -ra args <<<"$(grep -v '^[[:space:]]*#' "$args_file" | tr '\n' ' ')"
    gap_row "the real set ${dir##*/} (tests/data/real/${dir##*/}/gap.args)" "$dir" "${args[@]}"
    n=$((n + 1))
  done
  if ((n == 0)); then
    row "\`mcg-fit gap\` on each real data set (tests/data/real/*/gap.args)" whole-process \
      "<= its budget + 10 %" "not measured: no real set has a gap.args" "missed (no data)"
  fi
  if [[ -n ${GAP_REAL:-} && -f $GAP_REAL ]]; then
    gap_row "a real capture (${GAP_REAL##*/}, train = validate)" "$(dirname "$GAP_REAL")" \
      --train "${GAP_REAL##*/}" --validate "${GAP_REAL##*/}"
  fi
fi
