"""Fit the cost model of towenv.fidelity.step_cost to timed Houbolt runs.

The model: wall time per simulated second ∝ (a₀ + it(Δt)·(1 + nodes/n₀)) / Δt with it(Δt) = 1 + k·Δt
Newton iterations per step and a₀ the per-step work outside the iteration (larger when an irregular sea
drives the vessel: its motion is evaluated every step). Runs only scenes that are *not* held out in
scripts/fidelity_check.py (Table 4.1 sinusoid tows and coastal-sea variants of them), 3-D, 100 s each,
median of 3 repeats, and prints the fitted constants and the fit's error.

    python scripts/fidelity_cost_fit.py
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from fidelity_check import sea  # noqa: E402
from towenv import fidelity as F  # noqa: E402
from towenv.core.run import simulate  # noqa: E402
from towenv.core.simulator import Simulator, load  # noqa: E402

CASES = [("two_part_tow_1", {}, False), ("conventional_tow", {}, False), ("two_part_tow_2", {}, False),
         ("conventional_tow", sea(4), True), ("two_part_tow_2", sea(4), True), ("two_part_coastal_ss4", {}, True)]
DTS = (0.01, 0.02, 0.05, 0.1, 0.2)
FACTORS = (0.5, 1.0, 2.0)
DURATION = 100.0


def model(p, n, dt, irregular):
    a0 = np.where(irregular, p[1], p[0])
    return p[4] * (a0 + (1.0 + p[2] * dt) * (1.0 + n / p[3])) / dt


def main():
    rows = []
    for name, ov, irregular in CASES:
        base = load(name).with_overrides(ov) if ov else load(name)
        for f in FACTORS:
            segs = F.scaled_segments(base, f)
            n = F._n_nodes(segs)
            for dt in DTS:
                sc = F._with_segments(base, segs).with_overrides({"solver.dt": dt})
                walls = []
                for _ in range(3):
                    sim = Simulator(sc)
                    t = time.perf_counter()
                    simulate(sim, DURATION)
                    walls.append(time.perf_counter() - t)
                w = float(np.median(walls)) / DURATION
                rows.append((n, dt, irregular, w, sim.stats["mean_iterations"], sim.stats["step_cuts"]))
                print(f"{name:22s} {'sea' if irregular else 'sin'} nodes {n:3d} dt {dt:5.2f}  {1e3 * w:7.3f} ms/s  "
                      f"it/step {rows[-1][4]:.2f}  cuts {rows[-1][5]}", flush=True)
    n, dt, irr, w = (np.array([r[i] for r in rows], float) for i in range(4))
    irr = irr.astype(bool)

    def resid(p):
        return np.log(model(p, n, dt, irr)) - np.log(w)

    fit = least_squares(resid, x0=[0.8, 4.0, 22.0, 40.0, 1e-3], bounds=([0, 0, 0, 1, 1e-8], [50, 200, 200, 1e4, 1]))
    p = fit.x
    err = np.exp(np.abs(resid(p))) - 1
    print(f"\nfit over {len(rows)} runs: a0 = {p[0]:.2f} (no sea), {p[1]:.2f} (irregular sea); it(dt) = 1 + {p[2]:.1f} dt; "
          f"n0 = {p[3]:.1f} nodes; one iteration-unit = {1e6 * p[4]:.2f} µs per step")
    print(f"relative error of the fit: median {100 * np.median(err):.1f} %, max {100 * err.max():.1f} %")
    cur = np.array([F.step_cost(int(a), b, bool(c)) for a, b, c in zip(n, dt, irr)])
    scale = np.exp(np.median(np.log(w) - np.log(cur)))
    err_cur = np.abs(np.log(cur * scale) - np.log(w))
    print(f"current towenv.fidelity.step_cost on these runs: median error {100 * (np.exp(np.median(err_cur)) - 1):.1f} %, "
          f"max {100 * (np.exp(err_cur.max()) - 1):.1f} %")


if __name__ == "__main__":
    main()
