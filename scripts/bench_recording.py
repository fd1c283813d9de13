"""Benchmark: ``simulate`` with the compiled recording loop (towenv.core.recording) against the per-record
Python loop (``simulate(..., _compiled=False)``), wall time of a 300 s run, median of 3, one core.

    python scripts/bench_recording.py
    python scripts/bench_recording.py --duration 120 --repeats 5 --no-planar
"""
from __future__ import annotations

import argparse
import statistics
import time

from towenv.core.run import simulate
from towenv.core.simulator import Simulator, load

SEA = {"sea": {"code": 4, "convention": "coastal", "spectrum": "jonswap", "heading_deg": 180.0, "seed": 1},
       "vessel.model": "coastal_survey", "vessel.excitation": None, "vessel.speed": 2.0}


def cases(planar: bool):
    for dt in (0.01, 0.05, 0.1, 0.2):
        yield (f"conventional_tow, sea code 4{', planar' if planar else ''}, dt {dt:g}",
               load("conventional_tow").with_overrides({**SEA, "solver.dt": dt, "solver.planar": planar}))
    yield "two_part_tow_1 (sinusoid), dt 0.1", load("two_part_tow_1").with_overrides({"solver.dt": 0.1})


def wall(scene, duration, compiled):
    sim = Simulator(scene)
    t0 = time.perf_counter()
    simulate(sim, duration, _compiled=compiled)
    return time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=300.0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--no-planar", action="store_true", help="3-D model for conventional_tow (default: planar)")
    args = ap.parse_args(argv)
    rows = []
    print(f"{args.duration:g} s simulated, wall time (s), median of {args.repeats}")
    print(f"{'case':50s} {'per-record':>10s} {'compiled':>10s} {'ratio':>6s}")
    for name, sc in cases(not args.no_planar):
        simulate(sc, 1.0, _compiled=True)            # compile / load the caches
        simulate(sc, 1.0, _compiled=False)
        old, new = [], []
        for _ in range(args.repeats):                # interleaved: slow drifts of the machine hit both
            old.append(wall(sc, args.duration, False))
            new.append(wall(sc, args.duration, True))
        o, n = statistics.median(old), statistics.median(new)
        rows.append((name, o, n))
        print(f"{name:50s} {o:10.3f} {n:10.3f} {o / n:6.2f}", flush=True)
    return rows


if __name__ == "__main__":
    main()
