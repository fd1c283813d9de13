"""Benchmark (issue 15): what an irregular sea costs the simulator core, per Newton iteration.

Runs the two-part tow in calm water (two_part_tow_1) and in coastal sea state 4 (two_part_coastal_ss4) at the
same Δt, interleaved ``--repeats`` times, and prints per scene the CPU per step, the Newton iterations per
step, the CPU per Newton iteration and the cost of the tow-point path alone (``Simulator._tow_points`` for the
same steps, fresh cache). The sea's extra iterations per step are physics (a moving tow point); the goal is
the CPU per iteration: sea / calm ≤ 1.1.

    python scripts/bench_sea_cost.py                      # Δt 0.05 s, 300 s, 5 repeats (~1 minute)
    python scripts/bench_sea_cost.py --dt 0.02 --duration 120
"""
from __future__ import annotations

import argparse
import statistics
import time

import towenv

SCENES = ("two_part_tow_1", "two_part_coastal_ss4")


def one(scene, dt, duration):
    sim = towenv.Simulator(scene, dt=dt)
    sim.advance(1.0)                                    # compile / load the kernels
    sim.reset()
    n = int(round(duration / dt))
    t0 = time.process_time()
    sim.advance_steps(n)
    cpu = time.process_time() - t0
    its = sim.stats["iterations"]
    fresh = towenv.Simulator(scene, dt=dt)
    t0 = time.process_time()
    fresh._tow_points(1, n)
    tp = time.process_time() - t0
    return cpu / n * 1e6, its / n, cpu / its * 1e6, tp / n * 1e6


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dt", type=float, default=0.05)
    ap.add_argument("--duration", type=float, default=300.0)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args(argv)
    rows = {s: [] for s in SCENES}
    for _ in range(a.repeats):
        for s in SCENES:
            rows[s].append(one(s, a.dt, a.duration))
    med = {s: [statistics.median(r[i] for r in rows[s]) for i in range(4)] for s in SCENES}
    print(f"Δt = {a.dt:g} s, {a.duration:g} s simulated, median of {a.repeats} interleaved runs (process CPU)")
    print(f"{'scene':24s} {'µs/step':>9s} {'iter/step':>10s} {'µs/iter':>9s} {'tow point µs/step':>18s}")
    for s in SCENES:
        m = med[s]
        print(f"{s:24s} {m[0]:9.2f} {m[1]:10.2f} {m[2]:9.2f} {m[3]:18.2f}")
    ratios = [rows[SCENES[1]][k][2] / rows[SCENES[0]][k][2] for k in range(a.repeats)]
    print(f"CPU per Newton iteration, sea / calm: median {statistics.median(ratios):.3f} "
          f"(min {min(ratios):.3f}, max {max(ratios):.3f}; goal ≤ 1.1)")


if __name__ == "__main__":
    main()
