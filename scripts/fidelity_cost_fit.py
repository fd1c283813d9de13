"""Fit the cost model of towenv.fidelity.step_cost to timed Houbolt runs.

The model (µs per step): a₀ + a_sea·[irregular sea] + it(Δt)·(b₀ + b_seg·segments + b_body·rigid bodies),
it(Δt) = 1 + k·Δt Newton iterations per step, plus a per-run constant c/steps; a_sea is the vessel motion
evaluated every step when an irregular sea drives the vessel. Runs only scenes that are *not* held out in
scripts/fidelity_check.py (Table 4.1 sinusoid tows and coastal-sea variants of them), 3-D, 300 s each
(the check's duration), median of 3 repeats, and prints the fitted constants and the fit's error.

    python scripts/fidelity_cost_fit.py
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

ROOT = Path(__file__).resolve().parents[1]

from towenv.verification.fidelity_cases import sea  # noqa: E402
from towenv import fidelity as F  # noqa: E402
from towenv.core.run import simulate  # noqa: E402
from towenv.core.simulator import Simulator, load  # noqa: E402

CASES = [("two_part_tow_1", {}, False), ("conventional_tow", {}, False), ("two_part_tow_2", {}, False),
         ("conventional_tow", sea(4), True), ("two_part_tow_2", sea(4), True), ("two_part_coastal_ss4", {}, True),
         ("series_multitow", sea(3), True)]
DTS = (0.01, 0.02, 0.05, 0.1, 0.2)
FACTORS = (0.5, 1.0, 2.0)
DURATION = 300.0


def model(p, n, nb, dt, irregular, steps):
    """Wall seconds per simulated second."""
    a0, a_sea, k, b0, b_seg, b_body, c = p
    per_step = a0 + a_sea * irregular + (1.0 + k * dt) * (b0 + b_seg * n + b_body * nb)
    return 1e-6 * (per_step + 1e3 * c / steps) / dt


def main():
    rows = []
    for name, ov, irregular in CASES:
        base = load(name).with_overrides(ov) if ov else load(name)
        for f in FACTORS:
            segs = F.scaled_segments(base, f)
            n = F._n_nodes(segs)
            nb = sum(1 for b in base.bodies if getattr(b, "kind", "") in ("fish", "depressor"))
            for dt in DTS:
                sc = F._with_segments(base, segs).with_overrides({"solver.dt": dt})
                walls = []
                for _ in range(3):
                    sim = Simulator(sc)
                    t = time.perf_counter()
                    simulate(sim, DURATION)
                    walls.append(time.perf_counter() - t)
                w = float(np.median(walls)) / DURATION
                rows.append((n, nb, dt, irregular, w, sim.stats["mean_iterations"], sim.stats["step_cuts"]))
                print(f"{name:22s} {'sea' if irregular else 'sin'} segments {n:3d} dt {dt:5.2f}  {1e3 * w:7.3f} ms/s  "
                      f"it/step {rows[-1][5]:.2f}  cuts {rows[-1][6]}", flush=True)
    n, nb, dt, irr, w = (np.array([r[i] for r in rows], float) for i in range(5))
    steps = DURATION / dt

    def resid(p):
        return np.log(model(p, n, nb, dt, irr, steps)) - np.log(w)

    fit = least_squares(resid, x0=[3.0, 10.0, 20.0, 5.0, 0.3, 2.0, 5.0], bounds=(0, np.inf))
    p = fit.x
    err = np.exp(np.abs(resid(p))) - 1
    print(f"\nfit over {len(rows)} runs (µs per step): a0 = {p[0]:.2f}, a_sea = {p[1]:.2f}, it(dt) = 1 + {p[2]:.1f} dt, "
          f"per iteration {p[3]:.2f} + {p[4]:.3f}/segment + {p[5]:.2f}/rigid body; per run {p[6]:.1f} ms")
    print(f"relative error of the fit: median {100 * np.median(err):.1f} %, max {100 * err.max():.1f} %")
    its = np.array([r[5] for r in rows])
    kk = np.sum((its - 1) * dt) / np.sum(dt * dt)
    print(f"measured Newton iterations per step: least-squares it = 1 + {kk:.1f} dt")


if __name__ == "__main__":
    main()
