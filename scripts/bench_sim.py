"""Benchmark: real-time factor of the simulator core and its error against a converged reference.

For each scene and time step it prints the real-time factor (simulated seconds per wall second, one
core, median of ``--repeats`` runs of ``Simulator.advance`` from the same initial state, no recording),
the mean Newton iterations per step, and the relative error of the towed bodies' significant heave and
pitch amplitudes (2·std after the start-up window) against a reference run at Δt/8 with a 100× tighter
Newton tolerance. For scenes with a manoeuvre the error is the largest deviation of the body depth
history from the reference, relative to the body's depth change during the run.

    python scripts/bench_sim.py                       # the default set of scenes (about 2 minutes)
    python scripts/bench_sim.py two_part_tow_1 --dt 0.02 0.05 0.1 --duration 120
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import numpy as np

import towenv

DEFAULT = {
    "two_part_tow_1": (120.0, [0.02, 0.05, 0.1]),
    "conventional_tow": (120.0, [0.02, 0.05, 0.1]),
    "ablow_turn_1km": (600.0, [0.05, 0.1, 0.2]),
    "series_multitow": (60.0, [0.02, 0.05, 0.1]),
    "parallel_multitow": (60.0, [0.02, 0.05]),
}


def _record(sim, duration, every_s=0.1):
    """Run with light recording (body positions and pitch) for the error measures."""
    dt = sim.dt
    k = max(1, int(round(every_s / dt)))
    n = int(round(duration / dt)) // k
    names = [b.name for b in sim.system.bodies]
    z = {b: np.empty(n) for b in names}
    pitch = {b: np.empty(n) for b in names}
    t = np.empty(n)
    for i in range(n):
        sim.advance_steps(k)
        t[i] = sim.t
        for b in names:
            st = sim.body_state(b)
            z[b][i] = st["position"][2]
            pitch[b][i] = st["euler"][1]
    return t, z, pitch


def _errors(run, ref, discard, manoeuvre):
    t, z, p = run
    tr, zr, pr = ref
    out = {}
    for b in z:
        zi = np.interp(tr, t, z[b])
        pi = np.interp(tr, t, p[b])
        m = tr >= discard
        if manoeuvre:
            change = np.ptp(zr[b][m])
            out[b] = (np.max(np.abs(zi[m] - zr[b][m])) / max(change, 1e-9), float("nan"))
        else:
            sh, sp = 2 * np.std(zr[b][m]), 2 * np.std(pr[b][m])
            out[b] = (abs(2 * np.std(zi[m]) / sh - 1) if sh > 1e-9 else float("nan"),
                      abs(2 * np.std(pi[m]) / sp - 1) if sp > 1e-9 else float("nan"))
    return out


def bench(scene, duration, dts, repeats):
    rows = []
    base = towenv.Simulator(scene)
    manoeuvre = bool(getattr(base.scene.vessel, "manoeuvres", None))
    ramp = getattr(getattr(base.scene.vessel, "ramp", None), "duration", 0.0) or 0.0
    discard = min(max(ramp + 10.0, 0.25 * duration), 0.5 * duration)
    dt_ref = min(dts) / 8
    ref_sim = towenv.Simulator(scene, dt=dt_ref, tolerance=base.settings.tolerance / 100,
                               relative_tolerance=base.settings.relative_tolerance / 100)
    ref = _record(ref_sim, duration)
    for dt in dts:
        try:
            sim = towenv.Simulator(scene, dt=dt)
            walls = []
            for _ in range(repeats):
                _fresh(sim)
                t0 = time.perf_counter()
                sim.advance(duration)
                walls.append(time.perf_counter() - t0)
            stats = sim.stats
            sim.reset()
            err = _errors(_record(sim, duration), ref, discard, manoeuvre)
            rows.append(dict(scene=scene, dt=dt, nodes=sim.system.n_nodes, rtf=duration / statistics.median(walls),
                             iters=stats["mean_iterations"], cuts=stats["step_cuts"], err=err, failed=None))
        except towenv.SimulationDivergence as exc:
            rows.append(dict(scene=scene, dt=dt, nodes=base.system.n_nodes, rtf=float("nan"), iters=float("nan"),
                             cuts=0, err={}, failed=str(exc)))
    return rows, manoeuvre, dt_ref


def _fresh(sim):
    """Reset and forget the cached tow-point blocks: a repeat must pay for the vessel motion like a first run
    (with the cache kept, repeats of an irregular-sea run measured ~1.9× faster than the first)."""
    sim.reset()
    sim.__dict__.pop("_top_blocks", None)


def actuator_overhead(repeats, duration=300.0, dt=0.05):
    repeats = max(repeats, 5)
    """Real-time factor of the two-part tow in a coastal sea state 4 (small craft, head seas): bare
    (tow point on the ship), with the passive compensator active, and with the winch paying out."""
    base = towenv.load_scene("two_part_coastal_ss4")
    cases = {
        "bare core (sea, no compensator)": base.with_overrides(compensator=None),
        "compensator active": base,
        "winch paying out 0.1 m/s (85 → 115 m)": base.with_overrides(compensator=None,
                                                                    winch={"speed": 0.1, "max_length": 400.0}),
    }
    print("\n| two_part_coastal_ss4, dt = %.2f s | real-time factor | overhead vs bare | nodes at end |" % dt)
    print("|---|---|---|---|")
    ref = None
    for label, sc in cases.items():
        sim = towenv.Simulator(sc, dt=dt)
        walls = []
        for _ in range(repeats):
            _fresh(sim)
            t0 = time.perf_counter()
            sim.advance(duration)
            walls.append(time.perf_counter() - t0)
        rtf = duration / statistics.median(walls)
        ref = ref or rtf
        print(f"| {label} | {rtf:.0f}× | {100 * (ref / rtf - 1):+.1f} % | {sim.system.n_nodes} |", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*")
    ap.add_argument("--dt", type=float, nargs="*")
    ap.add_argument("--duration", type=float)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    plan = {s: DEFAULT.get(s, (120.0, [0.02, 0.05])) for s in (args.scenes or DEFAULT)}
    # compile once so the first measurement does not include numba's cache load
    towenv.Simulator("peer_deck").advance(1.0)
    print(f"# towenv {towenv.__version__} bench_sim — {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, python {platform.python_version()}")
    print("| scene | nodes | dt (s) | real-time factor | Newton it./step | step cuts | error (per body) |")
    print("|---|---|---|---|---|---|---|")
    for scene, (duration, dts) in plan.items():
        duration = args.duration or duration
        dts = args.dt or dts
        rows, manoeuvre, dt_ref = bench(scene, duration, dts, args.repeats)
        for r in rows:
            if r["failed"]:
                print(f"| {scene} | {r['nodes']} | {r['dt']} | failed | | | {r['failed'][:80]} |")
                continue
            if manoeuvre:
                e = ", ".join(f"{b}: depth {100 * v[0]:.2f} %" for b, v in r["err"].items())
            else:
                e = ", ".join(f"{b}: heave {100 * v[0]:.2f} %, pitch {100 * v[1]:.2f} %" for b, v in r["err"].items())
            print(f"| {scene} | {r['nodes']} | {r['dt']} | {r['rtf']:.0f}× | {r['iters']:.2f} | {r['cuts']} | {e} |",
                  flush=True)
    if not args.scenes:
        actuator_overhead(args.repeats)
    for scene in ("two_part_tow_1", "ablow_turn_1km"):
        sim = towenv.Simulator(scene)
        snap = sim.snapshot()
        times = []
        for _ in range(1000):
            t0 = time.perf_counter()
            sim.restore(snap)
            times.append(time.perf_counter() - t0)
        print(f"\nsnapshot restore, {scene} ({sim.system.n_nodes} nodes): median {1e6 * statistics.median(times):.1f} µs")
    print(f"\nreference: Δt = smallest Δt / 8, Newton tolerance / 100; duration per scene as in DEFAULT; "
          f"real-time factor = median of {args.repeats} runs")


if __name__ == "__main__":
    main()
