#!/usr/bin/env bash
# Varied self-made rigs (rigs_lib.sh), each described to mcg-fit gap without its friction: two
# current-driven drives whose friction is Coulomb + viscous + breakaway + a direction asymmetry
# (drawn from seeds 7 and 9). gap must name friction_levels+friction_asymmetry with shrink >= 60 %
# on the held-out run, each parameter finite in its standard error and near the truth (Coulomb,
# viscous within 2 %, the asymmetry within 5 %, the breakaway excess within 10 %). Before, both
# were named friction_levels alone: the asymmetry, fitted alone without a Coulomb level beneath
# it, ranked below the pool of effects mixtures are made from, and the breakaway excess, left at
# 0 by the fit on the regularised stick, could not be profiled (0 +- inf).
# And two small motors behind a duty dead band with Coulomb friction, speed only at 2 kHz (seeds 1
# and 4: 12 V and 24 V): gap must name hbridge+friction_levels, each parameter within 3 standard
# errors and 10 % of the truth (the breakaway excess 30 %). Before, both were named
# friction_levels alone, its Coulomb level holding the dead band too (+225 and +498 standard
# errors): the dead band, fitted alone beside that level, removed nothing and was rejected
# before its joint fit, and the held-out runs' score, near the noise already, could not drop by
# the margin of significance however well the mixture fits the coasts that tell the two apart.
# Seed 7 (24 V, a 4.5 % dead band): its joint fit spends the search's budget on the long valley
# where the dead band trades against the Coulomb level; reported from there, the two were 12
# standard errors off (0.0319 against 0.0453, Tc +12 SE). The diagnosis is now fitted on to
# convergence after the verdict.
# And two of those motors driven as a lab validates one (deadband_aprbs: braking steps from speed
# to half the dead band in training, a random-level step run held out; seeds 2 and 6), with the
# same tolerances. Before, seed 6 was named brush_drop+friction_levels (c1 +16 standard errors)
# and seed 2's c1 was pinned at 0 (truth 6.3e-6): the bridge's on-resistance, fitted on speed
# alone, traded with the viscous level through Kt, so the dead band's mixture was set aside as
# undetermined or stopped at the bound. Without a measured current it is now held at 0, and the
# status says so.
# And two gearmotors logged at 100 and 50 Hz (seeds 17 and 9), each parameter within 3 standard
# errors and 10 % of the truth (the breakaway excess 30 %). Before, the Coulomb level was 4.0 and
# 4.5 standard errors off, the viscous 3.0, and seed 9's breakaway excess 4.8 (-6.5 %): the
# exact stick's profile moved the breakaway (seed 17: 0.00019 to 0.0012, three of the fit's
# errors), but the Coulomb and viscous levels kept the values they had been fitted to around the
# old one. They are now refitted around the profile's value, and the profile taken again.
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$1
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"
source "$(dirname "$0")/rigs_lib.sh"
require_tools mcg-fit

# near_truth NAME VALUE_SE TRUTH TOL [K]: VALUE (VALUE_SE is "VALUE+-SE") within TOL (relative) of TRUTH,
# with a finite standard error (and, given K, within K of it).
near_truth() {
  local v=${2%%+-*} s=${2##*+-} k=${5:-0}
  if awk -v v="$v" -v s="$s" -v w="$3" -v t="$4" -v k="$k" \
    'BEGIN { d = v - w; if (d < 0) d = -d; a = w < 0 ? -w : w
             exit !(s + 0 > 0 && s != "inf" && d <= t * a && (k == 0 || d <= k * s)) }'; then
    pass
    echo "ok   $1 = $2 (truth $3)"
  else
    fail "$1 = $2, truth $3 (tolerance $4${5:+ and $5 standard errors}, a finite error)"
  fi
}

for spec in current:7 current:9 deadband:1 deadband:4 deadband:7 deadband_aprbs:2 deadband_aprbs:6 gearmotor:9 \
  gearmotor:17; do
  kind=${spec%%:*} seed=${spec##*:} dir="$work/$kind-$seed"
  rig "$kind" "$seed" "$dir"
  mapfile -t drive <"$dir/args"
  # The dead band's mixture comes after every single fit: a budget the verdict does not hang on.
  [[ $kind == deadband* ]] && drive+=(--budget 900)
  mcg-fit gap "${drive[@]}" --config "$dir/given.ini" --train "$dir/train.csv" \
    --validate "$dir/validate.csv" \
    >"$dir/gap.csv" 2>"$dir/gap.err" || fail "$kind $seed: gap: exit $?: $(tail -1 "$dir/gap.err")"
  row=$(grep -v '^#' "$dir/gap.csv" | sed -n 2p)
  echo "$kind $seed: $(cut -d, -f1,4,15 <<<"$row")"
  want=$(awk '$1 == "effects" { print $2 }' "$dir/truth")
  if [[ "$(cut -d, -f1 <<<"$row")" != "$want" ]]; then
    fail "$kind $seed: diagnosis $(cut -d, -f1 <<<"$row"), expected $want"
    continue
  fi
  pass
  if [[ $kind == deadband* ]]; then
    check "$kind $seed: the bridge's on-resistance is said held at 0" grep -q 'hbridge.R_on_ohm held at 0' <<<"$row"
  fi
  shrink=$(cut -d, -f4 <<<"$row")
  awk -v s="$shrink" 'BEGIN { exit !(s >= 60) }' && pass || fail "$kind $seed: shrink $shrink % < 60 %"
  while read -r key truth; do
    [[ $key == effects ]] && continue
    ses=
    case $kind:$key in
      current:*Ts_excess*) tol=0.1 ;;
      current:*dT_Nm) tol=0.05 ;;
      current:*) tol=0.02 ;;
      deadband*:*Ts_excess*) tol=0.3 ses=3 ;;
      deadband*:*) tol=0.1 ses=3 ;;
      gearmotor:*Ts_excess*) tol=0.3 ses=3 ;;
      gearmotor:*) tol=0.1 ses=3 ;;
    esac
    value=$(grep -o "$key=[^ ,]*" <<<"$row" | cut -d= -f2 || true)
    # A breakaway whose exact-stick profile stays open is pinned, and the status must say so.
    if [[ -z $value && $key == *Ts_excess* ]] && grep -q "$key pinned at 0" <<<"$row"; then
      pass
      echo "ok   $kind $seed: $key pinned at 0 and said so (truth $truth)"
      continue
    fi
    near_truth "$kind $seed: $key" "$value" "$truth" "$tol" $ses
  done <"$dir/truth"
done
# Dead-band seed 9 driven as a lab validates it (24 V, a 3.9 % dead band): on speed alone Kt
# and J trade with the viscous level along the valley that keeps the gain and the time
# constant. The fit left Kt_scale at 0.952 +- 0.008 and the viscous level 42 % high (6.6 of its
# errors): each error small, so the trade (correlated -0.9997) pinned nothing. Kt_scale must now
# be pinned at the datasheet's value as a gauge, and the viscous level within 5 % of the truth.
dir="$work/deadband_aprbs-9"
rig deadband_aprbs 9 "$dir"
mapfile -t drive <"$dir/args"
mcg-fit gap "${drive[@]}" --budget 900 --config "$dir/given.ini" --train "$dir/train.csv" \
  --validate "$dir/validate.csv" >"$dir/gap.csv" 2>"$dir/gap.err" ||
  fail "deadband_aprbs 9: gap: exit $?: $(tail -1 "$dir/gap.err")"
row=$(grep -v '^#' "$dir/gap.csv" | sed -n 2p)
echo "deadband_aprbs 9: $(cut -d, -f1,4,15 <<<"$row")"
check "deadband_aprbs 9: Kt_scale is pinned as a gauge" \
  grep -q 'param_mismatch.Kt_scale pinned at the given value (a gauge)' <<<"$row"
near_truth "deadband_aprbs 9: friction_levels.c1_Nm_s_rad" \
  "$(grep -o 'friction_levels.c1_Nm_s_rad=[^ ,]*' <<<"$row" | cut -d= -f2 || true)" \
  "$(awk '$1 == "friction_levels.c1_Nm_s_rad" { print $2 }' "$dir/truth")" 0.05
# Dead-band seed 10 (24 V, a 9.6 % dead band, R 5.5 ohm): a brush drop beside the Coulomb level
# fits these runs as well as the rig's own model does (held-out 7.33 rpm both): the runs name a
# voltage offset, not which. Either mixture may be named, and when it is not the dead band's, the
# verdict must say that the dead band in its place explains the runs as well. Before, gap named
# brush_drop+friction_levels and said nothing of the other. Said so, the dead band's mixture must
# score within 2 % of the diagnosis: with the bridge's on-resistance held, its joint fit once
# spent its budget half way along the valley where the dead band trades with the Coulomb level
# (0.693 against 0.633, dead band 0.064 against the rig's 0.096) and still said "as well".
dir="$work/deadband-10"
rig deadband 10 "$dir"
mcg-fit gap --budget 900 --config "$dir/given.ini" --train "$dir/train.csv" --validate "$dir/validate.csv" \
  >"$dir/gap.csv" 2>"$dir/gap.err" || fail "deadband 10: gap: exit $?: $(tail -1 "$dir/gap.err")"
named=$(awk -F': ' '$1 == "# diagnosis" { print $2 }' "$dir/gap.csv")
reason=$(grep -A1 '^diagnosis:' "$dir/gap.err" | tail -1)
echo "deadband 10: $named: $reason"
case $named in
  hbridge+friction_levels) pass ;;
  brush_drop+friction_levels)
    check "deadband 10: the dead band in the brush drop's place is named" \
      grep -q 'hbridge) in place of a brush drop (brush_drop), hbridge+friction_levels explains' <<<"$reason"
    # ... fitted as far as the brush drop's mixture: "as well" within 2 % of its score.
    scores=$(sed -n 's/.*explains these runs as well (score \([0-9.e+-]*\) against \([0-9.e+-]*\)).*/\1 \2/p' \
      <<<"$reason")
    check "deadband 10: the dead band's mixture scores within 2 % of the diagnosis' ($scores)" \
      awk -v s="$scores" 'BEGIN { split(s, f, " "); exit !(f[2] > 0 && f[1] <= 1.02 * f[2]) }' ;;
  *) fail "deadband 10: diagnosis $named, expected a dead band or a brush drop beside friction_levels" ;;
esac
# Gearmotor seed 21 (87:1, 200 Hz, 2436 counts a turn of the output): the breakaway's profile on
# the exact stick undulates by a few likelihood units (whole samples of each start from rest),
# its least cost 34 % above the truth and a second one near it. Its error was the one-unit
# stretch around the least cost (+- 2.8e-5, the fit's 9e-5 reported: 4.1 errors off); it now
# counts the whole profile's reach and must cover the truth within 2 errors.
dir="$work/gearmotor-21"
rig gearmotor 21 "$dir"
mapfile -t drive <"$dir/args"
mcg-fit gap "${drive[@]}" --config "$dir/given.ini" --train "$dir/train.csv" --validate "$dir/validate.csv" \
  >"$dir/gap.csv" 2>"$dir/gap.err" || fail "gearmotor 21: gap: exit $?: $(tail -1 "$dir/gap.err")"
row=$(grep -v '^#' "$dir/gap.csv" | sed -n 2p)
echo "gearmotor 21: $(cut -d, -f1,4,15 <<<"$row")"
[[ $(cut -d, -f1 <<<"$row") == friction_levels ]] && pass ||
  fail "gearmotor 21: diagnosis $(cut -d, -f1 <<<"$row"), expected friction_levels"
near_truth "gearmotor 21: friction_levels.Ts_excess_Nm" \
  "$(grep -o 'friction_levels.Ts_excess_Nm=[^ ,]*' <<<"$row" | cut -d= -f2 || true)" \
  "$(awk '$1 == "friction_levels.Ts_excess_Nm" { print $2 }' "$dir/truth")" 0.5 2
# One file of a rig, split by gap itself as a user who has only that run would have it. The
# dead-band seed 25's random-level step run (7.7 s, training on its first 4.9 s): the fit left
# the viscous level at 0 and Kt_scale at 1.07 +- 0.0002 (truth 1, the Coulomb level 15 errors
# off), since at c = 0 no correlation names the trade speed alone cannot break; and the
# breakaway's profile ended on its scan's edge and read "+- more than 0", unflagged. Kt_scale must
# now be pinned as a gauge, the Coulomb and viscous levels within 3 errors and 10 % of the truth,
# and the breakaway near the truth, or pinned, or its infinite error flagged, and said so. The gearmotor seed 25's staircase run (split at
# 28.5 s): the regularised fit left the breakaway flat (+- 0.032 of a level of 0.0009 N m), the
# profile scanned in steps wider than the level and said "+- inf, more than 0.16"; it must now
# close within 2 errors of the truth, with an error below the level's own size.
# split_one KIND SEED FILE: gap on FILE of rig KIND SEED alone; sets dir and row for what follows.
split_one() {
  local kind=$1 seed=$2 file=$3
  dir="$work/$1-$2-$3"
  rig "$kind" "$seed" "$dir"
  mapfile -t drive <"$dir/args"
  mcg-fit gap "${drive[@]}" --config "$dir/given.ini" --train "$dir/$file.csv" >"$dir/gap.csv" \
    2>"$dir/gap.err" || fail "$kind $seed $file alone: gap: exit $?: $(tail -1 "$dir/gap.err")"
  row=$(grep -v '^#' "$dir/gap.csv" | sed -n 2p)
  echo "$kind $seed $file alone: $(cut -d, -f1,4,15 <<<"$row")"
  [[ $(cut -d, -f1 <<<"$row") == "$(awk '$1 == "effects" { print $2 }' "$dir/truth")" ]] && pass ||
    fail "$kind $seed $file alone: diagnosis $(cut -d, -f1 <<<"$row")"
  check "$kind $seed $file alone: no error reads 'more than 0'" eval '! grep -q "more than 0[^.]" "$dir/gap.csv" "$dir/gap.err"'
  # A withheld parameter the row does not give a value is named in its status: never hidden.
  local key
  while read -r key _; do
    [[ $key == effects ]] && continue
    grep -q "$key=" <<<"$row" ||
      check "$kind $seed $file alone: $key, not fitted, is said so" grep -q "$key" <<<"$row"
  done <"$dir/truth"
}
truth_of() { awk -v k="$1" '$1 == k { print $2 }' "$dir/truth"; }
value_of() { grep -o "$1=[^ ,]*" <<<"$row" | cut -d= -f2 || true; }
split_one deadband_aprbs 25 validate
check "deadband_aprbs 25 alone: Kt_scale is pinned as a gauge" \
  grep -q 'param_mismatch.Kt_scale pinned at the given value (a gauge)' <<<"$row"
for key in friction_levels.Tc_Nm friction_levels.c1_Nm_s_rad; do
  near_truth "deadband_aprbs 25 alone: $key" "$(value_of $key)" "$(truth_of $key)" 0.1 3
done
key=friction_levels.Ts_excess_Nm
if [[ -z $(value_of $key) ]]; then
  check "deadband_aprbs 25 alone: $key pinned and said so" grep -q "$key pinned at 0" <<<"$row"
elif [[ $(value_of $key) == *+-inf ]]; then
  check "deadband_aprbs 25 alone: $key's infinite error is flagged" grep -q "$key not determined" <<<"$row"
else
  near_truth "deadband_aprbs 25 alone: $key" "$(value_of $key)" "$(truth_of $key)" 0.3 3
fi
# The current-driven seed 31's random-step run (split at 7.7 s): no start from rest in training,
# so friction_levels alone pinned its breakaway at 0 and said so; the mixture that extends it
# held the pin and gave no value and no word for it.
split_one current_aprbs 31 validate
check "current_aprbs 31 alone: the diagnosis' breakaway is said to be pinned" \
  grep -q 'friction_levels.Ts_excess_Nm pinned at 0' <<<"$row"
split_one gearmotor 25 train
near_truth "gearmotor 25 alone: $key" "$(value_of $key)" "$(truth_of $key)" 1 2
check "gearmotor 25 alone: $key's error is below the level's size" \
  awk -v x="$(value_of $key)" 'BEGIN { split(x, f, "[+]-"); exit !(f[2] < f[1]) }'
finish gap_rigs
