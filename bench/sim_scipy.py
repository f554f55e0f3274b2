#!/usr/bin/python3
"""The coupled rig of mcg-sim in scipy, for a side-by-side benchmark (scripts/bench.d/sim_scipy.sh).

Usage: sim_scipy.py PARAMS INPUT.csv OUTPUT.csv
PARAMS is `mcg-fit model --list` (the model's own numbers, one owner); INPUT has t and v
and optionally r_load (clutch engaged throughout; without r_load the generator is open). The
same equations as mcg's plant (model/model.hpp): L di/dt = v - R i - Ke w,
Lg dig/dt = Keg w - (Rg + r_load) ig, (Jm + Jg) dw/dt = Kt i - Ktg ig - F(w), F the sum of the
motor's, the engaged clutch's and the generator's friction, sign(w) (Tc + c1|w| + c2 w^2 + c3|w|^3)
moving, holding up to Ts at rest. LSODA (max_step 10 ms, rtol 1e-6) over the run with each
input row held until the next, as mcg-sim holds it, restarted at each stop and breakaway.
Whole process: numpy and scipy imports, CSV in and out included.
"""
import math
import sys

import numpy as np
from scipy.integrate import LSODA
from scipy.optimize import brentq


def params(path):
    p = {}
    with open(path) as f:
        for line in f:
            name, _, rest = line.partition(" = ")
            if rest:
                p[name.strip()] = float(rest.split(";")[0])
    return p


def main():
    p = params(sys.argv[1])
    with open(sys.argv[2]) as f:
        lines = [line for line in f if not line.startswith("#")]
    names = lines[0].strip().split(",")
    cols = [names.index("t"), names.index("v")] + ([names.index("r_load")] if "r_load" in names else [])
    data = np.loadtxt(lines[1:], delimiter=",", usecols=cols, ndmin=2)
    t, v = data[:, 0], data[:, 1]
    r_load = data[:, 2] if data.shape[1] > 2 else np.full(len(t), np.inf)
    R, L = p["motor.R_ohm"], p["motor.L_H"]
    Kt, Ke = p["motor.Kt_Nm_A"], p["motor.Ke_V_s_rad"]
    J = p["motor.J_kg_m2"] + p["generator.J_kg_m2"]
    parts = ("motor", "clutch_engaged", "generator")
    Tc = sum(p[f"{s}.Tc_Nm"] for s in parts)
    Ts = max(sum(p[f"{s}.Ts_Nm"] for s in parts), Tc)
    c1 = sum(p[f"{s}.visc1_Nm_s_rad"] for s in parts)
    c2 = sum(p[f"{s}.visc2_Nm_s2_rad2"] for s in parts)
    c3 = sum(p[f"{s}.visc3_Nm_s3_rad3"] for s in parts)
    supply = p["drive.supply_V"]
    Rg, Lg = p["generator.R_ohm"], p["generator.L_H"]
    Ktg, Keg = p["generator.Kt_Nm_A"], p["generator.Ke_V_s_rad"]

    def row(tt):
        # The input row in force, held until the next row, as mcg-sim holds it.
        return max(0, min(len(t) - 1, int(np.searchsorted(t, tt, side="right")) - 1))

    def currents(tt, y):
        n = row(tt)
        i, w, ig = y
        vin = min(max(v[n], -supply), supply)
        di = (vin - R * i - Ke * w) / L
        # An open generator (r_load inf) carries no current: ig stays 0.
        dig = (Keg * w - (Rg + r_load[n]) * ig) / Lg if math.isfinite(r_load[n]) else 0.0
        return di, dig, Kt * i - Ktg * ig

    # Stick-slip as mcg-sim steps it: a moving shaft keeps its direction d until its speed
    # reaches zero (an event), a stuck one is held at w = 0 until |T| reaches Ts (an event);
    # LSODA then restarts in the new mode, so it never chatters at the switch.
    def moving(d):
        def rhs(tt, y):
            di, dig, T = currents(tt, y)
            a = d * y[1]
            return [di, (T - d * (Tc + a * (c1 + a * (c2 + a * c3)))) / J, dig]

        return rhs, lambda tt, y: -d * y[1]

    def stuck():
        def rhs(tt, y):
            di, dig, _ = currents(tt, y)
            return [di, 0.0, dig]

        return rhs, lambda tt, y: abs(currents(tt, y)[2]) - Ts

    out = np.zeros((3, len(t)))
    k = 0  # the next output row

    def run(rhs, event, t0, y0):
        """Steps LSODA from (t0, y0) until event(t, y) rises through zero; fills the output
        rows on the way and returns (t, y) at the event, or None at the end of the input."""
        nonlocal k
        solver = LSODA(rhs, t0, y0, t[-1], max_step=0.01, rtol=1e-6, atol=[1e-9, 1e-6, 1e-9])
        g_old = event(t0, y0)
        while solver.status == "running":
            solver.step()
            if solver.status == "failed":
                sys.exit("sim_scipy.py: LSODA failed")
            dense = solver.dense_output()
            t_end, g_new = solver.t, event(solver.t, solver.y)
            hit = g_old < 0.0 <= g_new
            if hit:
                # The dense output's ends need not match the step's own values: bisect where
                # they bracket the root, interpolate linearly where they do not.
                f = lambda s: event(s, dense(s))
                fa, fb = f(solver.t_old), f(t_end)
                t_end = (brentq(f, solver.t_old, t_end, xtol=1e-12) if fa < 0.0 < fb else
                         solver.t_old + (t_end - solver.t_old) * g_old / (g_old - g_new))
            n = int(np.searchsorted(t, t_end, side="right"))
            if n > k:
                out[:, k:n] = dense(t[k:n])
                k = n
            if hit:
                return t_end, dense(t_end)
            g_old = g_new
        return None

    def mode_at(tt, y):
        T = currents(tt, y)[2]
        return 0 if abs(T) <= Ts else (1 if T > 0 else -1)

    state = (t[0], np.zeros(3))
    while state is not None:
        t0, y0 = state
        y0 = np.array(y0)
        y0[1] = 0.0
        mode = mode_at(t0, y0)
        state = run(*(moving(mode) if mode else stuck()), t0, y0)
    cur, rpm = out[0], out[1] * 30.0 / math.pi
    with open(sys.argv[3], "w") as out:
        out.write("t,rpm,i\n")
        for n in range(len(t)):
            out.write(f"{t[n]:.10g},{rpm[n]:.10g},{cur[n]:.10g}\n")


if __name__ == "__main__":
    main()
