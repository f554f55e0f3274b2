# Shared by the shell suites (source it first): a work directory and background processes that
# are always cleaned up, checks that count failures, and the summary line with the exit status.
export LC_ALL=C TZ=UTC
work=$(mktemp -d)
bg_pids=()
failures=0
checks=0

cleanup() {
  local pid
  for pid in "${bg_pids[@]}"; do kill "$pid" 2> /dev/null; done
  wait 2> /dev/null
  rm -rf "$work"
}
trap cleanup EXIT

# require_tools TOOL...: ends the suite as skipped (exit 125) unless each TOOL is built in $tools.
require_tools() {
  local t
  for t in "$@"; do
    [[ -x "$tools/$t" ]] || { echo "skipped: $t not built"; exit 125; }
  done
}

# check DESCRIPTION COMMAND...: runs COMMAND, counts a failure when it fails
# (a shell expression: check DESCRIPTION eval 'EXPRESSION').
check() {
  local what=$1
  shift
  checks=$((checks + 1))
  if "$@"; then
    echo "ok   $what"
  else
    echo "FAIL $what"
    failures=$((failures + 1))
  fi
}

# fail MESSAGE: counts a failure found without check.
fail() {
  checks=$((checks + 1))
  failures=$((failures + 1))
  echo "FAIL $*"
}

# same FILE TEXT: FILE holds exactly TEXT (plus the final newline).
same() {
  if [ "$(cat "$1")" != "$2" ]; then
    echo "  expected: $2"
    echo "  got:      $(cat "$1")"
    return 1
  fi
}

# finish [NAME]: the summary line; the suite's status (the last command of a suite).
finish() {
  echo "${1:-$(basename "$0")}: $((checks - failures)) of $checks checks passed"
  [ "$failures" = 0 ]
}

# expect DESCRIPTION EXPRESSION: check DESCRIPTION eval EXPRESSION.
expect() { check "$1" eval "$2"; }

# pass: counts a check that passed without check (its failures go through fail).
pass() { checks=$((checks + 1)); }

# near WHAT VALUE TRUTH TOL: VALUE within TOL (relative) of TRUTH.
near() {
  if awk -v v="$2" -v w="$3" -v t="$4" 'BEGIN { d = v - w; if (d < 0) d = -d; a = w < 0 ? -w : w; exit !(d <= t * a) }'; then
    pass
    echo "ok   $1 = $2 (truth $3)"
  else
    fail "$1 = $2, truth $3 (tolerance $4)"
  fi
}

# within_se WHAT VALUE SE REFERENCE: |VALUE - REFERENCE| <= 2 SE, SE finite and > 0.
within_se() {
  if awk -v v="$2" -v s="$3" -v r="$4" 'BEGIN { d = v - r; if (d < 0) d = -d; exit !(s > 0 && s < 1e300 && d <= 2 * s) }'; then
    pass
    echo "ok   $1 = $2 +- $3 (against $4)"
  else
    fail "$1 = $2 +- $3: $4 is not within two standard errors"
  fi
}

# segments DT SEGMENTS: open-loop inputs at a sample period of DT s, clutch 0, relay open, from
# ";"-separated "hold V SECONDS" and "ramp V0 V1 SECONDS" (sample_period in the metadata).
segments() {
  awk -v dt="$1" -v prog="$2" 'BEGIN {
    t = 0; print "# sample_period: " dt; print "t,v,clutch,r_load"
    n = split(prog, seg, ";")
    for (s = 1; s <= n; ++s) {
      split(seg[s], f, " ")
      if (f[1] == "hold") { v0 = f[2]; v1 = f[2]; d = f[3] } else { v0 = f[2]; v1 = f[3]; d = f[4] }
      rows = int(d / dt + 0.5)
      for (k = 0; k < rows; ++k) { printf "%.10g,%.10g,0,inf\n", t, v0 + (v1 - v0) * k / rows; t += dt }
    }
  }'
}

# gap_on_real DIR WANT WHAT [FROM=TO...]: mcg-fit gap with a real set's own options, DIR/gap.args
# (run in DIR; an argument FROM replaced by TO), into $work/gap.txt and $work/gap.err; passes when
# the diagnosis matches the pattern WANT. WHAT names the model given, for the messages.
gap_on_real() {
  local dir=$1 want=$2 what=$3 diagnosis a sub
  shift 3
  local -a given args=()
  read -ra given <<<"$(grep -v '^[[:space:]]*#' "$dir/gap.args" | tr '\n' ' ')"
  for a in "${given[@]}"; do
    for sub in "$@"; do [[ $a == "${sub%%=*}" ]] && a=${sub#*=}; done
    args+=("$a")
  done
  (cd "$dir" && mcg-fit gap "${args[@]}" --format text --residuals "$work/gap_residuals.csv") \
    >"$work/gap.txt" 2>"$work/gap.err" || true
  diagnosis=$(sed -n 's/^diagnosis: //p' "$work/gap.txt")
  # shellcheck disable=SC2053 # WANT is a pattern
  if [[ $diagnosis == $want ]]; then
    pass
    echo "ok   gap on $what names $diagnosis"
  else
    fail "gap on $what: diagnosis '${diagnosis:-none}' is not $want: $(tail -1 "$work/gap.err")"
  fi
}

# gap_closes_most FILE: gap's text report FILE closes >= 60 % of the validation speed error.
gap_closes_most() {
  local shrink
  shrink=$(sed -n 's/^validation \(omega\|rpm\) RMS: .*(\([0-9]*\) % less).*/\2/p' "$1")
  if [[ -n $shrink ]] && ((shrink >= 60)); then
    pass
    echo "ok   gap closes $shrink % of the validation speed error"
  else
    fail "gap closes '${shrink:-?}' % of the validation speed error (>= 60 % expected)"
  fi
}

# warnings_hold_values FILE: every "NAME = VALUE ... at its lower/upper bound" warning of gap's
# text report FILE names the value its fitted-parameters line gives (within its 4 digits).
warnings_hold_values() {
  local bad
  bad=$(awk '/^(best candidate.s )?fitted parameters/ { sub(/^[^:]*: /, ""); n = split($0, f, " ")
      for (k = 1; k <= n; k++) { split(f[k], p, "="); split(p[2], q, "[+]-"); v[p[1]] = q[1] } }
    /^warning: .* is at its (lower|upper) bound/ { w[$2] = $4 }
    END { for (x in w) if (x in v) { d = w[x] - v[x]; if (d < 0) d = -d; a = v[x] < 0 ? -v[x] : v[x]
            if (d > 1e-3 * a + 1e-300) print x " warned at " w[x] ", reported " v[x] } }' "$1")
  if [[ -z $bad ]]; then
    pass
    echo "ok   every bound warning names the value reported"
  else
    fail "a warning names a value the report does not hold: $bad"
  fi
}

# small_motor_ini TS TC C1: a small 12 V motor alone (2.5 ohm, 1 mH, Kt = Ke = 0.015, J 3e-6 kg m^2),
# its friction in N m (1 V of drive = 0.006 N m).
small_motor_ini() {
  printf '[motor]\nR_ohm = 2.5\nL_H = 0.001\nKt_Nm_A = 0.015\nKe_V_s_rad = 0.015\nJ_kg_m2 = 3e-6\n'
  printf 'Ts_Nm = %s\nTc_Nm = %s\nvisc1_Nm_s_rad = %s\n' "$1" "$2" "$3"
  printf 'visc2_Nm_s2_rad2 = 0\nvisc3_Nm_s3_rad3 = 0\n'
  printf '[drive]\nsupply_V = 12\n'
}

# encoder_speed_only CONFIG DT SEED: CONFIG's run of the inputs on stdin, its speed counted by a
# 16384-count encoder over one sample of DT; the drive and the measured rpm only.
encoder_speed_only() {
  mcg-sim --config "$1" --encoder --window "$2" --counts-per-rev 16384 --seed "$3" |
    awk -F, -v OFS=, '/^#/ { print; next } { print $1, $2, $3, $4, $6 }'
}
