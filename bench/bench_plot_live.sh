#!/usr/bin/env bash
# mcg-plot-gnuplot --live on a paced stream: rows at 500 a second (a comparison stream's columns)
# for SECONDS into `--live -o frame.png --interval 0.5`. Polled every 10 ms, the PNG's age (the
# time since a frame last replaced it: each is renamed over it, a new inode) gives the frame age's
# median, p99 and maximum; the tool's and its gnuplot's resident memory are sampled every second.
# Usage: bench_plot_live.sh TOOL_DIR [SECONDS] (default 600; a Release build).
set -euo pipefail
tools=$1
seconds=${2:-600}
command -v gnuplot >/dev/null || { echo "plot live: gnuplot missing"; exit 0; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
/usr/bin/python3 - "$tools/mcg-plot-gnuplot" "$seconds" "$work/frame.png" <<'PY'
import math, os, subprocess, sys, threading, time
tool, seconds, png = sys.argv[1], float(sys.argv[2]), sys.argv[3]
rate, interval = 500, 0.5
p = subprocess.Popen([tool, "--live", "-y", "rpm_measured,rpm", "--y2", "rpm_residual", "--window", "5",
                      "--interval", str(interval), "-o", png], stdin=subprocess.PIPE, bufsize=0)

def rss_kib(pid):
    try:
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0

def children(pid):
    try:
        with open("/proc/%d/task/%d/children" % (pid, pid)) as f:
            return [int(c) for c in f.read().split()]
    except OSError:
        return []

def pace():
    p.stdin.write(b"t,rpm_measured,rpm,rpm_residual\n")
    t0 = time.monotonic()
    n = int(rate * seconds)
    k = 0
    while k < n:
        due = t0 + k / rate
        delay = due - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        rows = []
        while k < n and t0 + k / rate <= time.monotonic():
            t = k / rate
            m = 500 + 20 * math.sin(2 * math.pi * 0.5 * t)
            rows.append(b"%.3f,%.2f,%.2f,%.2f\n" % (t, m + (k % 7) - 3, m, (k % 7) - 3))
            k += 1
        p.stdin.write(b"".join(rows))
    p.stdin.close()

writer = threading.Thread(target=pace)
writer.start()
start = time.monotonic()
inode, last_frame, frames, ages, mem = None, None, 0, [], []
next_mem = start + 1
while writer.is_alive():
    now = time.monotonic()
    try:
        st = os.stat(png)
        if st.st_ino != inode:
            inode, last_frame = st.st_ino, now
            frames += 1
    except FileNotFoundError:
        pass
    if last_frame is not None:
        ages.append(now - last_frame)
    if now >= next_mem:
        pids = [p.pid] + children(p.pid)
        mem.append((now - start, rss_kib(p.pid), sum(rss_kib(c) for c in pids[1:])))
        next_mem += 1
    time.sleep(0.01)
writer.join()
status = p.wait()
ages.sort()
q = lambda x: 1e3 * ages[min(len(ages) - 1, int(x * len(ages)))]
minute = next(m for m in mem if m[0] >= min(60, mem[-1][0]))
grow_tool = max(m[1] for m in mem if m[0] >= minute[0]) - minute[1]
grow_gp = max(m[2] for m in mem if m[0] >= minute[0]) - minute[2]
print("mcg-plot-gnuplot --live at %d rows/s for %.0f s, interval %.1f s: exit %d, %d frames, "
      "frame age median %.0f ms, p99 %.0f ms, max %.0f ms; VmRSS %d KiB at 60 s, %d KiB at the end "
      "(growth after the first minute %d KiB), gnuplot %d KiB at 60 s, %d KiB at the end (growth %d KiB)"
      % (rate, seconds, interval, status, frames, q(0.5), q(0.99), 1e3 * ages[-1], minute[1], mem[-1][1],
         grow_tool, minute[2], mem[-1][2], grow_gp))
PY
