"""Series tows (bodies towing a tail from their aft tow point) across time steps: wall time, Newton
iterations per step, step cuts and fish heave standard deviation for 120 s runs (docs/model-notes.md,
"Series coupling"), with the relaxed and the monolithic (default) coupling. The Srivastava array joined by
50 kg connectors (validation problem 2) is re-run at the end.

    python scripts/bench_series.py
"""
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

from towenv.verification.fidelity_cases import sea  # noqa: E402
from towenv.core.run import simulate  # noqa: E402
from towenv.core.simulator import Simulator, load  # noqa: E402


def main():
    cases = [("series_multitow", {}), ("series_multitow", sea(3)), ("two_part_tow_2", {}), ("two_part_tow_2", sea(5))]
    for name, ov in cases:
        for coupling in ("relaxed", "monolithic"):
            for dt in (0.02, 0.05, 0.1, 0.2):
                sc = load(name).with_overrides({**ov, "solver.dt": dt, "solver.series_coupling": coupling})
                try:
                    sim = Simulator(sc)
                    t = time.perf_counter()
                    res = simulate(sim, 120.0)
                    w = time.perf_counter() - t
                    c = sim.counters
                    heave = np.std(res.bodies[sc.bodies[-1].name]["heave"][res.t > 40])
                    print(f"{name:16s} {'SS' if ov else 'sin':3s} {coupling:10s} dt {dt:5.2f} wall {w:6.3f} s  "
                          f"iterations/step {c[1] / c[0]:.2f} (max {c[2]})  step cuts {c[3]}  fish heave std "
                          f"{heave:.4f} m", flush=True)
                except Exception as exc:  # noqa: BLE001 - reported
                    print(f"{name} {coupling} dt {dt}: FAILED {str(exc)[:150]}", flush=True)
    from towenv.validation.problems import series_connector
    print(series_connector()["text"])


if __name__ == "__main__":
    main()
