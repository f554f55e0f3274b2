#!/usr/bin/python3
"""The coupled rig of mcg-sim in scipy, for a side-by-side benchmark (scripts/bench.d/sim_scipy.sh).

Usage: sim_scipy.py PARAMS INPUT.csv OUTPUT.csv
PARAMS is `mcg-fit model --list` (the model's own numbers, one owner); INPUT has t and v
and optionally r_load (clutch engaged throughout; without r_load the generator is open). The
same equations as mcg's plant (model/model.hpp): L di/dt = v - R i - Ke w,
Lg dig/dt = Keg w - (Rg + r_load) ig, (Jm + Jg) dw/dt = Kt i - Ktg ig - F(w), F the sum of the
motor's, the engaged clutch's and the generator's friction, sign(w) (Tc + c1|w| + c2 w^2 + c3|w|^3)
moving, holding up to Ts at rest. One LSODA integration (max_step 10 ms, rtol 1e-6) over the
run with each input row held until the next, as mcg-sim holds it.
Whole process: numpy and scipy imports, CSV in and out included.
"""
import math
import sys

import numpy as np
from scipy.integrate import solve_ivp


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

    def rhs(tt, y):
        i, w, ig = y
        # The input row in force, held until the next row, as mcg-sim holds it.
        n = max(0, min(len(t) - 1, int(np.searchsorted(t, tt, side="right")) - 1))
        vin = min(max(v[n], -supply), supply)
        di = (vin - R * i - Ke * w) / L
        # An open generator (r_load inf) carries no current: ig stays 0.
        dig = (Keg * w - (Rg + r_load[n]) * ig) / Lg if math.isfinite(r_load[n]) else 0.0
        T = Kt * i - Ktg * ig
        if abs(w) < 1e-9 and abs(T) <= Ts:
            return [di, 0.0, dig]  # held by static friction
        a = abs(w)
        F = math.copysign(Tc + a * (c1 + a * (c2 + a * c3)), w if w != 0.0 else T)
        return [di, (T - F) / J, dig]

    sol = solve_ivp(rhs, (t[0], t[-1]), [0.0, 0.0, 0.0], method="LSODA", max_step=0.01, t_eval=t,
                    rtol=1e-6, atol=[1e-9, 1e-6, 1e-9])
    if not sol.success:
        sys.exit(f"sim_scipy.py: {sol.message}")
    cur, rpm = sol.y[0], sol.y[1] * 30.0 / math.pi
    with open(sys.argv[3], "w") as out:
        out.write("t,rpm,i\n")
        for n in range(len(t)):
            out.write(f"{t[n]:.10g},{rpm[n]:.10g},{cur[n]:.10g}\n")


if __name__ == "__main__":
    main()
