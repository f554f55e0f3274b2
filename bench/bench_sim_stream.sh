#!/usr/bin/env bash
# mcg-sim as a whole process and as a live filter: the real-time factor on 60 s of the coupled
# rig under the report's PI at 1 ms (CSV in and out), the peak memory on 600 s, and the latency
# from a row entering the pipe to its output row at 500 rows/s.
# Usage: bench_sim_stream.sh TOOL_DIR (the directory holding mcg-sim; a Release build).
set -euo pipefail
tools=$1
sim=$tools/mcg-sim
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# rows SECONDS: the closed-loop program at 1 ms, the speed command (a whole rpm in the board's
# 120..720) stepping every 0.5 s, the load toggling every 0.7 s, the clutch engaged.
rows() {
  awk -v n="$(($1 * 1000))" 'BEGIN {
    print "t,rpm_cmd,clutch,r_load"
    for (k = 0; k < n; k++) {
      t = k / 1000; s = sin(0.37 * int(t / 0.5)); if (s < 0) s = -s
      printf "%.3f,%d,2,%s\n", t, int(150 + 550 * s), ((t - 1.4 * int(t / 1.4)) < 0.7) ? "5.6" : "inf"
    }
  }'
}
rows 60 > "$work/60.csv"
rows 600 > "$work/600.csv"

best=1e9
for _ in 1 2 3 4 5; do
  start=$(date +%s.%N)
  "$sim" < "$work/60.csv" > "$work/out.csv"
  end=$(date +%s.%N)
  best=$(awk -v a="$start" -v b="$end" -v m="$best" 'BEGIN {d = b - a; print (d < m) ? d : m}')
done
cpu=$( { /usr/bin/time -f "%U %S" "$sim" < "$work/60.csv" > /dev/null; } 2>&1 | awk '{print $1 + $2}')
awk -v w="$best" -v c="$cpu" 'BEGIN {
  printf "mcg-sim 60 s closed loop at 1 ms, whole process, CSV in and out: %.3f s wall (best of 5), %.0fx real time; %.3f s CPU (%.0fx)\n", w, 60 / w, c, 60 / c }'

peak_kb=$( { /usr/bin/time -f "%M" "$sim" < "$work/600.csv" > /dev/null; } 2>&1 | tail -1)
echo "mcg-sim 600 s at 1 ms (600000 rows): peak memory $((peak_kb / 1024)) MiB"

/usr/bin/python3 - "$sim" << 'PY'
import subprocess, sys, threading, time
sim = sys.argv[1]
rate, seconds = 500, 10
n = rate * seconds
p = subprocess.Popen([sim, "--encoder"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, bufsize=0)
sent = [0.0] * n
lat = []
def reader():
    k = 0
    for line in p.stdout:
        if line[:1].isdigit():
            lat.append(time.monotonic() - sent[k])
            k += 1
t = threading.Thread(target=reader)
t.start()
p.stdin.write(b"t,rpm_cmd\n")
t0 = time.monotonic()
for k in range(n):
    due = t0 + k / rate
    delay = due - time.monotonic()
    if delay > 0:
        time.sleep(delay)
    sent[k] = time.monotonic()
    p.stdin.write(b"%.3f,300\n" % (k / rate))
p.stdin.close()
t.join()
p.wait()
lat.sort()
ms = lambda q: 1e3 * lat[min(len(lat) - 1, int(q * len(lat)))]
print("mcg-sim live at %d rows/s for %d s: %d rows, latency median %.2f ms, p99 %.2f ms, max %.2f ms"
      % (rate, seconds, len(lat), ms(0.5), ms(0.99), 1e3 * lat[-1]))
PY
