#!/usr/bin/env bash
# mcg-fit gap across each effect's range, not at the example points: for every catalog
# effect three parameter sets are drawn (seeded): one near the weak end of the range
# where the effect still stands above the rig's measurement noise, one near the strong end
# of what the rig can carry, one drawn uniformly (log-uniformly for scale parameters) in
# between. Each case trains and validates on different excitations with different noise
# seeds, and asserts the named effect and a shrink of the gap above the noise of at least
# 60 %. Plus: nominal parameters off (param_mismatch) and no effect at all with twice the
# rig's current noise (none).
# The ranges (physical, for the report's Pittman rig at 1 kHz):
#   dead_time tau_d_s        1 .. 10 ms        (one sample .. a third of the mechanical time constant)
#   supply_sag R_s_ohm       0.5 .. 5 ohm      (a bench supply's lead .. a small battery's)
#   brush_drop V_b_V         0.3 .. 2 V        (metal graphite .. carbon brushes, both brushes)
#   stribeck v_s_rad_s       3 .. 30 rad/s, shape_exp 0.7 .. 2.5
#   cogging T_c_Nm           0.8 .. 4 mN m (a third .. 1.5 times the Coulomb level),
#           N_per_rev        4 .. 20, phase_rad -pi .. pi (the ripple N w / 2 pi stays below the
#                            5 ms estimator window's 100 Hz at the validation speeds, ~30 rad/s:
#                            a faster ripple is averaged away and invisible to any diagnosis)
#   clutch_compliance k      0.03 .. 1 N m/rad (mode 10 .. 60 Hz), zeta 0.03 .. 0.5
#   hbridge R_on_ohm         0.2 .. 1.5 ohm, deadband 0.02 .. 0.1
#   clutch_engage_lag T_max  0.02 .. 0.2 N m, tau_s 0.01 .. 0.1 s
#   thermal R_th_K_W         4 .. 20 K/W, tau_th_s 2 .. 10 s
# Args: TOOL_DIR SOURCE_DIR. About 30 cases of a few seconds each (ctest label gap-range).
set -euo pipefail
tools=$1
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"
require_tools mcg-sweep mcg-sim mcg-fit
source "$(dirname "$0")/gap_lib.sh"
seed=1

# measure EFFECTS SEED NOISE_A: stdin (an input table) -> stdout (a measured run)
measure() {
  local effects=$1 s=$2 noise=${3:-0.003} args=()
  local e
  for e in $effects; do args+=(--effect "$e"); done
  mcg-sim --encoder --noise-i "$noise" --adc --seed "$s" "${args[@]}"
}

# Excitations (3 s each, 1 kHz), as test_gap.sh.
steps_load() { mcg-sweep step --level 4 --at 0.1 --then 9@0.6,6@1.1,12@1.6,3@2.1,8@2.5 --duration 3 --clutch "$1" \
  --r-load-schedule inf@0,5.6@0.9,inf@1.9; }
prbs_at() { mcg-sweep prbs --bias "$1" --amp "$2" --clock 0.006 --duration 3 --clutch "$3" --seed "$4"; }
prbs_loaded() { mcg-sweep prbs --bias "$1" --amp "$2" --clock 0.006 --duration 3 --clutch 2 --r-load 5.6 --seed "$3"; }
chirp_at() { mcg-sweep chirp --bias "$1" --amp "$2" --f0 1 --f1 60 --duration 3 --clutch "$3"; }
stairs_low() { mcg-sweep staircase --amp "$1" --steps 6 --hold 0.2 --duration 3 --clutch "$2"; }
engage() { mcg-sweep step --level 7 --at 0.1 --then 10@1.2,5@2.2 --duration 3 --clutch-schedule "1@0,2@0.6,1@1.5,2@1.9"; }
engage2() { mcg-sweep step --level 9 --at 0.1 --then 6@1.4 --duration 3 --clutch-schedule 0@0,2@0.8,1@1.8,2@2.3; }

# draw POINT LO HI SCALE: low (5 % into the range), high (95 %) or mid (uniform in 20..80 %,
# seeded by $seed and the range, so that parameters are drawn independently); SCALE log
# draws in log space.
draw() {
  awk -v p="$1" -v lo="$2" -v hi="$3" -v s="$4" -v seed="$seed" 'BEGIN {
    srand(seed * 1009 + int(1000 * (lo + hi)) % 1000); u = (p == "low") ? 0.05 : (p == "high") ? 0.95 : 0.2 + 0.6 * rand();
    if (s == "log") { v = exp(log(lo) + u * (log(hi) - log(lo))) } else { v = lo + u * (hi - lo) }
    printf "%.4g", v }'
}

# Points where the diagnosis is known to fall short today (reported, not counted; an xpass
# means it has been fixed and the entry should go):
#   cogging-high   T_c 3.7 mN m, N 18: cogging shrinks the gap by 41 % only, unexplained
#   thermal-mid   R_th 12.8 K/W, tau 6.4 s: thermal named, under 60 % shrink (or paired); on a
#                  3 s training run only the heat capacity tau/R_th shows (t << tau), R_th
#                  runs to its bound 200 K/W
#   thermal-high  R_th 18.5 K/W, tau 9.2 s: the same, and since a candidate whose parameters the
#                  data do not determine cannot be the diagnosis, unexplained with thermal named
#                  as the best candidate, flagged (R_th at its bound, R_th and tau correlated 1.0)
#   dead_time-4.2ms   4.2 ms, trained on clutch 0 only, validated engaged and loaded: unexplained
#                  (the param_mismatch refit on clutch-0 data makes the engaged validation
#                  worse, 110 against 27.7 rpm, and every effect is fitted on top of it)
#   stribeck-low  v_s 3.4 rad/s, shape 0.79: stribeck named, the gap above the noise shrinks by
#                  58-59 % (60 % before the exponential circuit step, the motor-sized effect
#                  bounds and the joint discrepancy refit landed together; not yet traced)
# (pair-2.5ms-1.1V, dead_time + brush_drop, where brush_drop alone was named, is found since
# mixtures are formed by forward selection; cogging-low, T_c 0.87 mN m at N 4, once unexplained
# below the significance margin, is named with a 93 % shrink.)
declare -A known=([cogging-high]=1 [thermal-mid]=1 [thermal-high]=1 [dead_time-4.2ms]=1
  [stribeck-low]=1)
xfail() {
  if [[ -n "${known[$1]:-}" ]]; then
    echo "xfail $2"
  else
    echo "FAIL $2"
    failures=$((failures + 1))
  fi
}

# check NAME EXPECTED EFFECTS: the diagnosis of $work/NAME-{train,validate}.csv
check() {
  local name=$1 expected=$2
  local effect shrink
  diagnose "$name" || return 0
  if [[ "$effect" != "$expected" ]]; then
    xfail "$name" "$name: diagnosis '$effect' (gap shrink $shrink %), expected '$expected' for ${3:-no effect}"
  elif [[ "$expected" != none && "$expected" != param_mismatch ]] && ! awk -v s="$shrink" 'BEGIN { exit !(s >= 60) }'; then
    xfail "$name" "$name: gap above the noise shrinks by $shrink %, expected at least 60 % for $3"
  else
    echo "${known[$name]:+x}ok   $name: $effect (gap shrink $shrink %) for ${3:-no effect}"
  fi
}

# case NAME EXPECTED EFFECTS TRAIN VALIDATE [NOISE [TRAIN_SEED VALIDATE_SEED]]
run_case() {
  local name=$1 expected=$2 effects=$3 noise=${6:-0.003}
  if [[ -z "${GAP_RANGE_ONLY:-}" || "$name" =~ $GAP_RANGE_ONLY ]]; then
    eval "$4" | measure "$effects" "${7:-$((100 + seed))}" "$noise" >"$work/$name-train.csv"
    eval "$5" | measure "$effects" "${8:-$((200 + seed))}" "$noise" >"$work/$name-validate.csv"
    check "$name" "$expected" "$effects"
  fi
  seed=$((seed + 1))
}

for p in low mid high; do
  run_case "dead_time-$p" dead_time "dead_time:tau_d_s=$(draw $p 0.001 0.01 log)" "prbs_at 8 2.5 0 $seed" "steps_load 2"
  run_case "supply_sag-$p" supply_sag "supply_sag:R_s_ohm=$(draw $p 0.5 5 log)" "steps_load 2" "prbs_at 9 3 2 $seed"
  run_case "brush_drop-$p" brush_drop "brush_drop:V_b_V=$(draw $p 0.3 2 log)" "stairs_low 6 1" "chirp_at 7 2 2"
  run_case "stribeck-$p" stribeck "stribeck:v_s_rad_s=$(draw $p 3 30 log),shape_exp=$(draw $p 0.7 2.5 lin)" \
    "stairs_low 4 0" "prbs_at 3 1.5 2 $seed"
  run_case "cogging-$p" cogging \
    "cogging:T_c_Nm=$(draw $p 0.0008 0.004 log),N_per_rev=$(draw $p 4 20 log | awk '{ printf "%d", $1 + 0.5 }'),phase_rad=$(draw mid -3.14 3.14 lin)" \
    "stairs_low 2.5 0" "prbs_at 2.2 0.8 0 $seed"
  run_case "clutch_compliance-$p" clutch_compliance \
    "clutch_compliance:k_Nm_per_rad=$(draw $p 0.03 1 log),zeta=$(draw $p 0.03 0.5 log)" "chirp_at 7 2.5 2" "engage"
  run_case "hbridge-$p" hbridge "hbridge:R_on_ohm=$(draw $p 0.2 1.5 log),deadband=$(draw $p 0.02 0.1 lin)" \
    "steps_load 2" "prbs_at 6 2 0 $seed"
  run_case "clutch_engage_lag-$p" clutch_engage_lag \
    "clutch_engage_lag:T_max_Nm=$(draw $p 0.02 0.2 log),tau_s=$(draw $p 0.01 0.1 log)" "engage" "engage2"
  run_case "thermal-$p" thermal "thermal:R_th_K_W=$(draw $p 4 20 log),tau_th_s=$(draw $p 2 10 log)" \
    "steps_load 2" "prbs_loaded 10 3 $seed"
done
# Nominal parameters off (inertia +30 %, Kt and Ke -10 %, Coulomb x2): a refit explains it.
run_case param_mismatch param_mismatch "param_mismatch:J_scale=1.3,Kt_scale=0.9,coulomb_scale=2" \
  "steps_load 2" "prbs_at 7 2 0 $seed"
# Two fixed points found wanting (see the known list above), kept as they were found.
run_case dead_time-4.2ms dead_time "dead_time:tau_d_s=0.0042" "prbs_at 8 2.5 0 1" "steps_load 2" 0.003 11 12
run_case pair-2.5ms-1.1V "dead_time+brush_drop" "dead_time:tau_d_s=0.0025 brush_drop:V_b_V=1.1" \
  "prbs_at 8 2.5 2 6" "steps_load 0" 0.003 11 12
# Nothing missing, twice the rig's current noise: none.
run_case none-noisy none "" "steps_load 2" "prbs_at 7 2 0 $seed" 0.006

if ((failures > 0)); then
  echo "$failures case(s) failed"
  exit 1
fi
