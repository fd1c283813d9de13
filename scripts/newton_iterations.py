"""Newton iterations and wall time per Houbolt step against the time step, and why: the error of the first
iterate (the predictor) against the convergence criteria, traced by the numpy twin.

    python scripts/newton_iterations.py [--dt 0.01 0.04 0.09] [--newton-stop change estimate]

Scene: two_part_tow_1 at 3 m/s in a coastal SS4 JONSWAP sea from 165° (seed 13), 300 s, the scene's segments
(twice them at Δt = 0.01 s: the fine default of towenv.fidelity), with each Newton stopping rule asked for
(``solver.newton_stop``: ``change`` — the simulator's default — and ``estimate``, used by the fidelity choices).
Quoted in docs/fidelity.md.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from towenv import fidelity as F
from towenv.verification import twin
from towenv.core.run import simulate
from towenv.core.simulator import Simulator, load

SCENE = ("two_part_tow_1", {"sea": {"code": 4, "convention": "coastal", "spectrum": "jonswap", "heading_deg": 165.0,
                                    "seed": 13},
                            "vessel.model": "coastal_survey", "vessel.excitation": None, "vessel.speed": 3.0})


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dt", type=float, nargs="+", default=[0.01, 0.04, 0.09])
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per step size (median; default 3)")
    ap.add_argument("--newton-stop", nargs="+", default=["change", "estimate"], choices=["change", "estimate"],
                    help="solver.newton_stop rules to run (default: both)")
    args = ap.parse_args(argv)
    base = load(SCENE[0]).with_overrides(SCENE[1])
    simulate(base, 5.0)                 # warm-up: load the compiled kernels
    print(f"{'stop':>8} {'dt (s)':>7} {'segments':>9} {'iterations/step':>16} {'wall/step (us)':>15}   first iterate vs "
          "criteria (3 steps from t = 100 s): max|dT| / tol_T, max|d angle| / tol_angle")
    for stop, dt in [(s, d) for s in args.newton_stop for d in args.dt]:
        ov = {"solver.dt": dt, "solver.newton_stop": stop}
        factor = F.FINE_SEGMENT_FACTOR if dt <= F.FINE_DT else 1.0
        for ln, n in F.scaled_segments(base, factor).items():
            ov[f"lines.{ln}.segments"] = list(n) if isinstance(n, tuple) else n
        sc = base.with_overrides(ov)
        walls = []
        for _ in range(max(1, args.repeats)):
            sim = Simulator(sc)
            t0 = time.perf_counter()
            sim.advance(300.0)
            walls.append(time.perf_counter() - t0)
        st = sim.stats
        per_step = 1e6 * float(np.median(walls)) / st["steps"]
        sim = Simulator(sc)
        sim.advance(100.0)
        s = sim.settings.array()
        firsts = []
        for _ in range(3):
            top = sim.path.position(np.array([sim.t + sim.dt]))[0]
            trace = []
            twin.houbolt_step_np(sim, sim.dt, top, trace=trace)
            tol_t = s[0] + s[1] * float(np.max(sim.tens_hist[0]))
            firsts.append(f"{trace[0]['max_dT'] / tol_t:.2g} / {trace[0]['dang_max'] / s[4]:.2g} "
                          f"({len(trace)} it)")
            sim.advance_steps(1)
        nseg = sum(int(np.sum(n)) for n in F.scaled_segments(base, factor).values())
        print(f"{stop:>8} {dt:7.3f} {nseg:9d} {st['mean_iterations']:16.2f} {per_step:15.1f}   " + "; ".join(firsts))


if __name__ == "__main__":
    main()
