#!/usr/bin/env bash
# The two routes from a board capture to a plant agree with each other and with the true plant. The
# emulated board runs a rig that differs from the nominal model (inertia x1.3, armature resistance
# x0.85, a dead time of 2 ms, a supply sagging by 1 ohm) at 45 % duty and plays a chirp on the duty,
# 0.5 -> 20 Hz over 4 s, three periods. The true response duty -> rpm is mcg-sim's on the same rig,
# read at the lines of a periodic multisine. Checked:
# - mcg-sweep bode reads the repeated chirp at its lines k / 4 s (the first period skipped): each line
#   from 0.5 to 5 Hz within 1 % and 1 degree of the truth seen through the board's measurement (the
#   16 ms rpm window, the duty as the mean of each 4 ms sample: rpm lags by 10 ms);
# - mcg-fit tf on the capture (time domain) and `mcg-sweep bode | mcg-fit tf`, two poles each, are
#   within 3 % and 2.5 degrees of the true response and of each other from 0.5 to 5 Hz.
# Usage: test_identify_routes.sh TOOL_DIR SOURCE_DIR
tools=$1
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
command -v mcg-sim > /dev/null || { echo "mcg-sim not built, skipped"; exit 125; }

printf '[motor]\nJ_kg_m2 = 9.178e-06\nR_ohm = 3.3235\n[generator]\nJ_kg_m2 = 9.178e-06\n' > "$work/rig.ini"
printf '[effect.dead_time]\ntau_d_s = 0.002\n[effect.supply_sag]\nR_s_ohm = 1\n' >> "$work/rig.ini"
tty=$work/ttyMCG
start_board "$tty" --config "$work/rig.ini" --speed 4 || exit 1
S() { timeout 60 mcg-serial -p "$tty" "$@"; }

check "a chirp on the duty at 45 %: 0.5 -> 20 Hz over 4 s, +- 10 %, three periods" eval 'S set mode open \
  > /dev/null && S set clutch 2 && S set load 0 && S set duty 45 && S set exc_kind chirp && S set exc_f0 0.5 &&
  S set exc_f1 20 && S set exc_sweep 4 && S set exc_div 1 && S set exc_amp 100 && S set exc_offset 450 &&
  S set exc_periods 3'
sleep 1
check "captured from its start" eval 'S stream --seconds 12 --then excite > "$work/chirp.csv" 2> /dev/null'
check "the true response: a multisine through the same rig" eval 'mcg-sweep multisine --column duty \
  --bias 0.45 --amp 0.1 --f0 0.5 --f1 20 --lines 40 --period 2 --duration 8 2> /dev/null |
  mcg-sim --config "$work/rig.ini" 2> /dev/null | mcg-sweep bode --in duty --out rpm > "$work/truth.csv" 2> /dev/null'
check "mcg-sweep bode reads the chirp at its lines" eval 'mcg-sweep bode "$work/chirp.csv" > "$work/bode.csv" \
  2> /dev/null && grep -q "^# estimator: multisine lines.*the lines k / 4 s of the board.s chirp" "$work/bode.csv"'

# rows "f mag_db phase_deg" of a response file
rows() { grep -v '^#' "$1" | awk -F, 'NR > 1 { print $1, $2, $3 }'; }
check "each line 0.5-5 Hz within 1 % and 1 degree of the truth through the board's measurement" eval '
  { rows "$work/truth.csv" | sed "s/^/T /"; rows "$work/bode.csv" | sed "s/^/B /"; } | awk "
    function sinc(x) { return x == 0 ? 1 : sin(x) / x }
    \$1 == \"T\" { m[\$2] = \$3; p[\$2] = \$4; next }
    \$2 >= 0.5 && \$2 <= 5 && (\$2 in m) { w = 2 * 3.141592653589793 * \$2
      dm = 100 * (10 ^ ((\$3 - m[\$2]) / 20) / (sinc(w * 0.008) / sinc(w * 0.002)) - 1)
      dp = \$4 - p[\$2] + w * 0.010 * 180 / 3.141592653589793
      n++; if (dm > 1 || dm < -1 || dp > 1 || dp < -1) { bad++; print \$2, dm, dp } }
    END { exit !(n >= 10 && bad == 0) }"'

check "route A: mcg-fit tf on the capture" eval 'mcg-fit tf --poles 2 "$work/chirp.csv" > "$work/a.ini" 2> /dev/null'
check "route B: mcg-sweep bode | mcg-fit tf" eval 'mcg-fit tf --poles 2 "$work/bode.csv" > "$work/b.ini" 2> /dev/null'
# "gain pole1 pole2" of a two-pole fit
fit() { awk -F' *= *' '$1 == "gain" || $1 ~ /^pole[12]_rad_s$/ { split($2, v, " "); printf "%s ", v[1] }' "$1"; }
check "both within 3 % and 2.5 degrees of the truth and of each other, 0.5-5 Hz" eval '
  { echo "A $(fit "$work/a.ini")"; echo "B $(fit "$work/b.ini")"; rows "$work/truth.csv" | sed "s/^/T /"; } | awk "
    function at(K, a, b, f,  w, re, im) { w = 2 * 3.141592653589793 * f
      re = 1 - w * w / (a * b); im = w / a + w / b
      M = K / sqrt(re * re + im * im); P = -atan2(im, re) * 180 / 3.141592653589793 }
    function cmp(m1, p1, m2, p2) { n++; d = 100 * (m1 / m2 - 1); e = p1 - p2
      if (d > 3 || d < -3 || e > 2.5 || e < -2.5) { bad++; print f, d, e } }
    \$1 == \"A\" { ka = \$2; a1 = \$3; a2 = \$4; next }
    \$1 == \"B\" { kb = \$2; b1 = \$3; b2 = \$4; next }
    \$2 >= 0.5 && \$2 <= 5 { f = \$2; mt = 10 ^ (\$3 / 20); pt = \$4
      at(ka, a1, a2, f); ma = M; pa = P; at(kb, b1, b2, f); mb = M; pb = P
      cmp(ma, pa, mt, pt); cmp(mb, pb, mt, pt); cmp(ma, pa, mb, pb) }
    END { exit !(n >= 30 && bad == 0) }"'
finish
