# Varied self-made rigs for mcg-fit gap (after lib.sh): small motors behind a driver with a duty
# dead band, gearmotors sampled slowly, current-driven drives. Each rig draws its physics from a
# seed (no two alike), is described to gap by a datasheet model WITHOUT friction or dead band,
# and is driven as a lab person would: staircases in both directions, a slow ramp each way, steps.
#
# rig KIND SEED DIR: writes DIR/truth.ini (the rig), DIR/given.ini (its datasheet), DIR/train.csv,
# DIR/validate.csv, DIR/args (gap's drive options, one per line) and DIR/truth (one line per
# withheld parameter as gap names it: "effect.key value"; the first line "effects NAME+NAME" is
# what gap should name). KIND:
#  - deadband: a 6-24 V motor of random R, Ke, J, L behind a duty dead band of 2-10 %, Coulomb
#    friction worth 3-8 % of the supply with breakaway 10-40 % above it and a little viscous drag;
#    speed only, 1-2 kHz, encoder counts over one sample, noise of 0.4-1 counts' step;
#  - gearmotor: 20:1-100:1 sampled at 50-200 Hz (the output shaft's counts over one sample), a
#    1-2 V friction offset with breakaway 10-30 % above, the ratio in the datasheet's
#    [measurement]; speed only;
#  - current: a current-driven drive (an ideal current loop: i is the command) on a motor with a
#    load inertia, Coulomb + viscous friction (+ an asymmetry on odd seeds), speed noise above
#    what the encoder states, and on seeds divisible by 3 a drive that low-passes the speed it
#    logs (speed_filter metadata). Integrated here, by an event-exact stick-slip of its own.
# deadband_aprbs, gearmotor_aprbs, current_aprbs: the same rig (same seed, same physics) driven as
# a lab validates one: the training run adds braking steps from speed to a small drive of either
# sign (half the dead band, 0.5 V on a gearmotor, 3 % of the current range), and the held-out run
# is a random-level step run (an amplitude-modulated PRBS) in which a third of the levels are
# small, most of them after speed, so the two runs hold many brakes to a drive the rig cannot
# start from. These rows tell a driver's dead band (the bridge shorts the motor: v_m = 0) from a
# brush drop (v_m = v + V_b while the motor generates) and from Coulomb friction (v_m = v).

# draw SEED: shell assignments of uniform draws u1..u12 in [0, 1) for SEED (awk's generator).
draw() {
  awk -v s="$1" 'BEGIN { srand(s * 7919 + 13); for (k = 1; k <= 12; k++) printf "u%d=%.6f\n", k, rand() }'
}

# lin U LO HI / log U LO HI: U mapped onto [LO, HI], linearly or logarithmically.
lin() { awk -v u="$1" -v a="$2" -v b="$3" 'BEGIN { printf "%.6g", a + u * (b - a) }'; }
logu() { awk -v u="$1" -v a="$2" -v b="$3" 'BEGIN { printf "%.6g", exp(log(a) + u * (log(b) - log(a))) }'; }
calc() { awk "BEGIN { printf \"%.6g\", $1 }"; }

# aprbs SEED N AMP SMALL TMIN TMAX: segments() text of N random-level steps from rest back to rest:
# each level uniform in [-AMP, AMP], or with probability 1/3 in [-SMALL, SMALL], held for a time
# uniform in [TMIN, TMAX] s (awk's generator, its own stream for SEED).
aprbs() {
  awk -v s="$1" -v n="$2" -v a="$3" -v sm="$4" -v t0="$5" -v t1="$6" 'BEGIN {
    srand(s * 104729 + 71); printf "hold 0 0.2"
    for (k = 0; k < n; ++k) {
      l = rand() < 1 / 3 ? sm * (2 * rand() - 1) : a * (2 * rand() - 1)
      printf ";hold %.4g %.4g", l, t0 + rand() * (t1 - t0)
    }
    printf ";hold 0 %.4g", t1
  }'
}

# brakes FAST SMALL HOLD: segments() text braking from +-FAST to a drive of +-SMALL, both signs of
# each (with the motion and against it), each level held HOLD s, ending at rest.
brakes() {
  local f=$1 s=$2 h=$3
  printf 'hold %s %s;hold %s %s;hold -%s %s;hold -%s %s;hold %s %s;hold -%s %s;hold -%s %s;hold %s %s;hold 0 %s' \
    "$f" "$h" "$s" "$h" "$f" "$h" "$s" "$h" "$f" "$h" "$s" "$h" "$f" "$h" "$s" "$h" "$h"
}

# noisy SEED SIGMA: adds Gaussian noise of SIGMA to the rpm column of a CSV on stdin.
noisy() {
  awk -F, -v OFS=, -v s="$1" -v sd="$2" 'BEGIN { srand(s) }
    /^#/ { print; next }
    !h { for (k = 1; k <= NF; k++) if ($k == "rpm") c = k; h = 1; print; next }
    { u1 = rand(); if (u1 < 1e-12) u1 = 1e-12
      $c = sprintf("%.6g", $c + sd * sqrt(-2 * log(u1)) * cos(6.283185307 * rand())); print }'
}

# voltage_ini R L KT J TS TC C1 SUPPLY [RATIO]: a motor alone, its friction in N m.
voltage_ini() {
  printf '[motor]\nR_ohm = %s\nL_H = %s\nKt_Nm_A = %s\nKe_V_s_rad = %s\n' "$1" "$2" "$3" "$3"
  printf 'J_kg_m2 = %s\nTs_Nm = %s\nTc_Nm = %s\nvisc1_Nm_s_rad = %s\n' "$4" "$5" "$6" "$7"
  printf 'visc2_Nm_s2_rad2 = 0\nvisc3_Nm_s3_rad3 = 0\n'
  printf '[drive]\nsupply_V = %s\n' "$8"
  [[ -z ${9:-} ]] || printf '[measurement]\ngear_ratio = %s\n' "$9"
}

# measure_v DIR DT CPR SEED SIGMA: the truth's run of the inputs on stdin, speed only, noisy.
measure_v() {
  mcg-sim --config "$1/truth.ini" --encoder --window "$2" --counts-per-rev "$3" --seed "$4" |
    awk -F, -v OFS=, '/^#/ { print; next } { print $1, $2, $3, $4, $6 }' | noisy "$4" "$5"
}

rig_deadband() {
  local dir=$1 seed=$2 aprbs=${3:-}
  eval "$(draw "$seed")"
  local vs=$(awk -v u="$u1" 'BEGIN { print u < 0.33 ? 6 : u < 0.67 ? 12 : 24 }')
  local r=$(logu "$u2" 1 8) w0=$(logu "$u3" 300 1000) j=$(logu "$u4" 1e-6 2e-5) te=$(logu "$u5" 2e-4 1e-3)
  local kt=$(calc "$vs / $w0") l=$(calc "$r * $te") db=$(lin "$u6" 0.02 0.10)
  local tc=$(calc "$(lin "$u7" 0.03 0.08) * $vs * $kt / $r")
  local tx=$(calc "$(lin "$u8" 0.1 0.4) * $tc")
  local c1=$(calc "$(lin "$u9" 0.03 0.1) * $vs * $kt / $r / $w0")
  local dt=$(awk -v u="$u10" 'BEGIN { print u < 0.5 ? 0.0005 : 0.001 }')
  local cpr=$(awk -v u="$u11" 'BEGIN { print u < 0.33 ? 2048 : u < 0.67 ? 4096 : 16384 }')
  local sigma=$(calc "$(lin "$u12" 0.4 1) * 60 / ($cpr * $dt)")
  voltage_ini "$r" "$l" "$kt" "$j" "$(calc "$tc + $tx")" "$tc" "$c1" "$vs" >"$dir/truth.ini"
  printf '[effect.hbridge]\nR_on_ohm = 0\ndeadband = %s\n' "$db" >>"$dir/truth.ini"
  voltage_ini "$r" "$l" "$kt" "$j" 0 0 0 "$vs" >"$dir/given.ini"
  local a=$(calc "0.25 * $vs") b=$(calc "0.5 * $vs") c=$(calc "0.75 * $vs") m=$(calc "0.2 * $vs")
  local train="hold 0 0.2;hold $a 0.5;hold $b 0.5;hold $c 0.5;hold $b 0.5;hold 0 0.5;hold -$a 0.5;\
hold -$b 0.5;hold -$c 0.5;hold 0 0.5;ramp 0 $m 3;hold 0 0.5;ramp 0 -$m 3;hold 0 0.5"
  [[ -z $aprbs ]] || train+=";$(brakes "$b" "$(calc "0.5 * $db * $vs")" 0.4)"
  segments "$dt" "$train" | measure_v "$dir" "$dt" "$cpr" "$seed" "$sigma" >"$dir/train.csv"
  a=$(calc "0.35 * $vs") b=$(calc "0.6 * $vs") m=$(calc "0.18 * $vs")
  local validate="hold 0 0.2;hold $a 0.5;hold $b 0.5;hold 0 0.5;hold -$a 0.5;hold -$b 0.5;hold 0 0.5;\
ramp 0 $m 2;hold 0 0.5;ramp 0 -$m 2;hold 0 0.5"
  [[ -z $aprbs ]] || validate=$(aprbs "$seed" 30 "$(calc "0.7 * $vs")" "$(calc "$db * $vs")" 0.1 0.4)
  segments "$dt" "$validate" | measure_v "$dir" "$dt" "$cpr" "$((seed + 1000))" "$sigma" >"$dir/validate.csv"
  : >"$dir/args"
  printf 'effects hbridge+friction_levels\nhbridge.deadband %s\n' "$db" >"$dir/truth"
  printf 'friction_levels.Tc_Nm %s\n' "$tc" >>"$dir/truth"
  printf 'friction_levels.Ts_excess_Nm %s\nfriction_levels.c1_Nm_s_rad %s\n' "$tx" "$c1" >>"$dir/truth"
  printf 'rig deadband %s V, R %s, Kt %s, J %s, L %s, %s s, %s counts/rev, noise %s rpm\n' \
    "$vs" "$r" "$kt" "$j" "$l" "$dt" "$cpr" "$sigma" >"$dir/about"
}

rig_gearmotor() {
  local dir=$1 seed=$2 aprbs=${3:-}
  eval "$(draw "$seed")"
  local n=$(awk -v u="$u1" 'BEGIN { printf "%d", 20 + int(u * 81) }')
  local r=$(logu "$u2" 1 5) kt=$(logu "$u3" 0.005 0.02) j=$(logu "$u4" 1e-6 1e-5)
  local l=$(calc "$r * 5e-4")
  local voff=$(lin "$u5" 1 2) tc tx c1
  tc=$(calc "$voff * $kt / $r")
  tx=$(calc "$(lin "$u6" 0.1 0.3) * $tc")
  c1=$(calc "$(lin "$u7" 0.02 0.08) * 12 * $kt / $r * $kt / 12")
  local dt=$(awk -v u="$u8" 'BEGIN { print u < 0.33 ? 0.005 : u < 0.67 ? 0.01 : 0.02 }')
  local cpr=$(awk -v u="$u9" -v n="$n" 'BEGIN { printf "%d", 4 * (u < 0.5 ? 7 : 16) * n }')
  local sigma=$(calc "$u10 * 60 / ($cpr * $dt)")
  voltage_ini "$r" "$l" "$kt" "$j" "$(calc "$tc + $tx")" "$tc" "$c1" 12 "$n" >"$dir/truth.ini"
  voltage_ini "$r" "$l" "$kt" "$j" 0 0 0 12 "$n" >"$dir/given.ini"
  local train="hold 0 0.5;hold 3 2;hold 6 2;hold 9 2;hold 12 2;hold 0 2;hold -3 2;hold -6 2;hold -9 2;\
hold 0 2;ramp 0 3.5 10;hold 0 1;ramp 0 -3.5 10;hold 0 1"
  [[ -z $aprbs ]] || train+=";$(brakes 8 0.5 1.5)"
  segments "$dt" "$train" | measure_v "$dir" "$dt" "$cpr" "$seed" "$sigma" >"$dir/train.csv"
  local validate="hold 0 0.5;hold 4 2;hold 8 2;hold 11 2;hold 0 2;hold -4 2;hold -8 2;hold -11 2;hold 0 2;\
ramp 0 3 8;hold 0 1;ramp 0 -3 8;hold 0 1"
  [[ -z $aprbs ]] || validate=$(aprbs "$seed" 25 11 1.5 0.8 2.5)
  segments "$dt" "$validate" | measure_v "$dir" "$dt" "$cpr" "$((seed + 1000))" "$sigma" >"$dir/validate.csv"
  : >"$dir/args"
  printf 'effects friction_levels\nfriction_levels.Tc_Nm %s\n' "$tc" >"$dir/truth"
  printf 'friction_levels.Ts_excess_Nm %s\n' "$tx" >>"$dir/truth"
  printf 'friction_levels.c1_Nm_s_rad %s\n' "$c1" >>"$dir/truth"
  printf 'rig gearmotor %s:1, R %s, Kt %s, J %s, %s s, %s counts/out rev, offset %s V, noise %s rpm\n' \
    "$n" "$r" "$kt" "$j" "$dt" "$cpr" "$voff" "$sigma" >"$dir/about"
}

# current_run DT KT J TS TC C1 DT_ASYM CPR TAU SEED SIGMA SEGMENTS: the current-driven rig's run
# (t, i, rpm; the current of row n acts over [t(n), t(n+1)), rpm(n) counts over (t(n) - DT, t(n)]
# as mcg-sim's encoder): the motor shaft J dw/dt = Kt i - dT - F, F = sign(w) (Tc + c1 |w|) moving, held at
# rest while |Kt i - dT| <= Ts; solved exactly (an exponential between events, the stop at w = 0
# at its instant) in steps of DT/20; rpm the encoder's counts over one sample (CPR counts/rev),
# low-passed with TAU (0: none), plus Gaussian noise SIGMA. SEGMENTS as segments(), in A.
current_run() {
  segments "$1" "${12}" | awk -F, -v OFS=, -v dt="$1" -v kt="$2" -v J="$3" -v ts="$4" -v tc="$5" \
    -v c1="$6" -v da="$7" -v cpr="$8" -v tau="$9" -v seed="${10}" -v sd="${11}" '
    BEGIN { srand(seed); w = 0; th = 0; y = 0; m = 20; h = dt / m; last = 0; T = J / c1 }
    /^#/ { print; next }
    /^t,/ { if (tau > 0) print "# speed_filter: first-order low-pass, time constant " tau " s"
            print "# rpm_estimator: counts over " dt " s window, " cpr " counts/rev"
            print "t,i,rpm"; next }
    {
      i = $2
      x = th * cpr / 6.283185307; cnt = int(x); if (cnt > x) cnt--
      rpm = (cnt - last) / cpr / dt * 60; last = cnt
      if (tau > 0) { y += (rpm - y) * (1 - exp(-dt / tau)) } else y = rpm
      u1 = rand(); if (u1 < 1e-12) u1 = 1e-12
      print $1, i, sprintf("%.6g", y + sd * sqrt(-2 * log(u1)) * cos(6.283185307 * rand()))
      for (k = 0; k < m; k++) {
        drive = kt * i - da
        if (w == 0) {
          if (drive > ts) s = 1; else if (drive < -ts) s = -1; else continue
        } else s = w > 0 ? 1 : -1
        wi = (drive - s * tc) / c1
        e = exp(-h / T); wn = wi + (w - wi) * e
        if (w != 0 && wn * s <= 0) {
          t0 = T * log((w - wi) / -wi)
          th += wi * t0 + (w - wi) * T * (1 - exp(-t0 / T)); w = 0
        } else if (w == 0 && wn * s <= 0) {
          w = 0
        } else { th += wi * h + (w - wi) * T * (1 - e); w = wn }
      }
    }'
}

rig_current() {
  local dir=$1 seed=$2 aprbs=${3:-}
  eval "$(draw "$seed")"
  local kt=$(logu "$u1" 0.02 0.1) j=$(logu "$u2" 1e-5 1e-4) imax=$(lin "$u3" 1 4)
  local tc=$(calc "$(lin "$u4" 0.05 0.15) * $kt * $imax")
  local tx=$(calc "$(lin "$u5" 0.1 0.3) * $tc")
  local c1=$(calc "$(lin "$u6" 0.5 0.9) * $kt * $imax / 300")
  local da=0
  ((seed % 2)) && da=$(calc "$(lin "$u7" 0.15 0.35) * $tc")
  local tau=0
  ((seed % 3 == 0)) && tau=$(lin "$u8" 0.005 0.02)
  local dt=$(awk -v u="$u9" 'BEGIN { print u < 0.5 ? 0.001 : 0.002 }') cpr=4000
  local sigma=$(calc "(0.5 + $u10) * 60 / ($cpr * $dt)")
  printf '[motor]\nR_ohm = 1\nL_H = 0.001\nKt_Nm_A = %s\nKe_V_s_rad = %s\nJ_kg_m2 = %s\n' "$kt" "$kt" "$j" \
    >"$dir/given.ini"
  printf 'Ts_Nm = 0\nTc_Nm = 0\nvisc1_Nm_s_rad = 0\n' >>"$dir/given.ini"
  printf 'visc2_Nm_s2_rad2 = 0\nvisc3_Nm_s3_rad3 = 0\n' >>"$dir/given.ini"
  [[ $tau == 0 ]] || printf '[measurement]\nspeed_filter = first-order low-pass, time constant %s s\n' \
    "$tau" >>"$dir/given.ini"
  cp "$dir/given.ini" "$dir/truth.ini"
  local q=$(calc "0.3 * $imax") h=$(calc "0.6 * $imax") f=$(calc "$imax") m=$(calc "0.25 * $imax")
  local train="hold 0 0.2;hold $q 0.6;hold $h 0.6;hold $f 0.6;hold 0 0.6;hold -$q 0.6;hold -$h 0.6;hold -$f 0.6;\
hold 0 0.6;ramp 0 $m 3;hold 0 0.5;ramp 0 -$m 3;hold 0 0.5"
  [[ -z $aprbs ]] || train+=";$(brakes "$h" "$(calc "0.03 * $imax")" 0.5)"
  current_run "$dt" "$kt" "$j" "$(calc "$tc + $tx")" "$tc" "$c1" "$da" "$cpr" "$tau" "$seed" "$sigma" \
    "$train" >"$dir/train.csv"
  q=$(calc "0.4 * $imax") h=$(calc "0.8 * $imax") m=$(calc "0.22 * $imax")
  local validate="hold 0 0.2;hold $q 0.6;hold $h 0.6;hold 0 0.6;hold -$q 0.6;hold -$h 0.6;hold 0 0.6;\
ramp 0 $m 2;hold 0 0.5;ramp 0 -$m 2;hold 0 0.5"
  [[ -z $aprbs ]] || validate=$(aprbs "$seed" 20 "$(calc "0.9 * $imax")" "$(calc "0.1 * $imax")" 0.2 0.6)
  current_run "$dt" "$kt" "$j" "$(calc "$tc + $tx")" "$tc" "$c1" "$da" "$cpr" "$tau" "$((seed + 1000))" \
    "$sigma" "$validate" >"$dir/validate.csv"
  echo --current >"$dir/args"
  if [[ $da == 0 ]]; then
    echo 'effects friction_levels' >"$dir/truth"
  else
    printf 'effects friction_levels+friction_asymmetry\nfriction_asymmetry.dT_Nm %s\n' "$da" >"$dir/truth"
  fi
  printf 'friction_levels.Tc_Nm %s\nfriction_levels.Ts_excess_Nm %s\nfriction_levels.c1_Nm_s_rad %s\n' \
    "$tc" "$tx" "$c1" >>"$dir/truth"
  printf 'rig current Kt %s, J %s, imax %s A, %s s, filter %s s, noise %s rpm\n' \
    "$kt" "$j" "$imax" "$dt" "$tau" "$sigma" >"$dir/about"
}

rig_deadband_aprbs() { rig_deadband "$1" "$2" aprbs; }
rig_gearmotor_aprbs() { rig_gearmotor "$1" "$2" aprbs; }
rig_current_aprbs() { rig_current "$1" "$2" aprbs; }

rig() { mkdir -p "$3" && "rig_$1" "$3" "$2"; }
