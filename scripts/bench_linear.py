"""Benchmark of the linearised frequency-domain model (towenv.linear): speed and accuracy.

1. Median wall time of a 50-frequency RAO set (0.05–2 rad/s, 1 m top heave, harmonic linearisation) for
   hover_deep_tow and the two-part tow two_part_tow_1, plus the spectral (stochastic) solve and a
   compensator (k, b) grid.
2. Significant heights (4σ) of the linear model vs the nonlinear time-domain simulator in moderate seas:
   Hover's deep tow in SS5 (Bretschneider, constant deck-heave RAO calibrated as in validation case 3,
   locked and passive compensator) and the two-part coastal tow in its own SS4 (vessel RAO, 3 m/s).

Usage: python scripts/bench_linear.py [--quick] [--seeds N] [--duration S]
Single-threaded BLAS (set below) as the other benchmarks; the numbers in docs/linear.md come from it.
"""
from __future__ import annotations

import os
import sys

# one thread per process (set before numpy/numba load their pools). Loaded into a process that has already loaded
# numba (a test), NUMBA_NUM_THREADS is left alone: numba re-reads its configuration at every compilation and refuses
# a thread count that differs from the pool it launched (agents/train.py does the same)
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    if _v != "NUMBA_NUM_THREADS" or "numba" not in sys.modules:
        os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from towenv.linear import LinearModel  # noqa: E402
from towenv.scene import load_scene  # noqa: E402
from towenv.validation import hover as H  # noqa: E402
from towenv.validation.common import run_scene  # noqa: E402


def median_time(fn, n=15):
    """(median wall, min wall, median CPU) seconds of fn() after one warm-up call."""
    fn()
    ts, cs = [], []
    for _ in range(n):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        ts.append(time.perf_counter() - t0)
        cs.append(time.process_time() - c0)
    return float(np.median(ts)), float(np.min(ts)), float(np.median(cs))


def _highpass(x, dt, w_cut):
    """Remove the content below w_cut (rad/s) by zeroing FFT bins (record demeaned)."""
    X = np.fft.rfft(x - x.mean())
    w = 2 * np.pi * np.fft.rfftfreq(len(x), dt)
    X[w < w_cut] = 0.0
    return np.fft.irfft(X, len(x))


def td_stats(outs, fish, line, t_skip, w_cut):
    """4σ of the demeaned records pooled over runs (each after t_skip), total and above w_cut (the
    wave-frequency band: the linear model has no slow-drift content)."""
    parts = [o.result.window(t_skip) for o in outs if o.result.t[-1] - t_skip >= 300.0]
    if not parts:
        return None
    getters = {
        "top_heave": lambda w: w.tow_point[:, 2],
        "fish_heave": lambda w: w.bodies[fish]["position"][:, 2],
        "fish_pitch": lambda w: w.bodies[fish]["euler"][:, 1],
        "fish_tension": lambda w: w.lines[line]["tensions"][:, -1],
        "top_tension": lambda w: w.top_tension,
    }
    if parts[0].actuators and "stroke" in parts[0].actuators:
        getters["stroke"] = lambda w: w.actuators["stroke"]
    out, band = {}, {}
    for k, f in getters.items():
        out[k] = 4.0 * float(np.std(np.concatenate([f(w) - f(w).mean() for w in parts])))
        band[k] = 4.0 * float(np.std(np.concatenate([_highpass(f(w), float(w.t[1] - w.t[0]), w_cut)
                                                    for w in parts])))
    out["band"] = band
    out["seconds"] = float(sum(w.t[-1] - w.t[0] for w in parts))
    out["min_fish_tension"] = float(min(w.lines[line]["tensions"][:, -1].min() for w in parts))
    ten = np.concatenate([w.lines[line]["tensions"][:, -1] for w in parts])
    out["slack_pct"] = 100.0 * float(np.mean(ten <= 1e-6))
    return out


def compare(label, scene_dict, fish, line, seeds, duration, t_skip, rows):
    lm = LinearModel(scene_dict)
    sc = lm.scene
    t0 = time.perf_counter()
    s = lm.spectral(sc.sea.sea_state())
    t_lin = time.perf_counter() - t0
    outs = []
    t0 = time.process_time()
    for seed in seeds:
        d = dict(scene_dict)
        d["sea"] = dict(d["sea"], seed=seed)
        outs.append(run_scene(d, duration, record_interval=0.2))
    t_td = time.process_time() - t0
    w_cut = 0.5 * float(np.min(s.omega_e))
    td = td_stats(outs, fish, line, t_skip, w_cut)
    fails = [f"{o.failed_at:.0f} s" for o in outs if not o.ok]
    print(f"\n{label}: linear {t_lin * 1e3:.0f} ms ({s.iterations} iterations, {s.tow_point_model}); "
          f"time domain {len(seeds)} x {duration:.0f} s, {td['seconds'] if td else 0:.0f} s pooled after {t_skip:.0f} s, "
          f"{t_td:.1f} s CPU; runs stopped early: {fails or 'none'}; min {fish} cable tension "
          f"{td['min_fish_tension'] if td else float('nan'):.0f} N, slack {td['slack_pct'] if td else float('nan'):.1f} % "
          "of the time")
    print(f"  {'quantity':<18} {'linear 4σ':>11} {'TD 4σ':>11} {'lin/TD':>7} {'TD 4σ band':>11} {'lin/band':>8}"
          f"   (band: ω > {w_cut:.2f} rad/s)")
    for k in ("top_heave", "fish_heave", "fish_pitch", "fish_tension", "top_tension", "stroke"):
        lk = k.replace("fish", fish)
        if td is None or k not in td or lk not in s.significant:
            continue
        lin = s.significant[lk]
        ratio = lin / td[k] if td[k] > 0 else float("nan")
        bratio = lin / td["band"][k] if td["band"][k] > 0 else float("nan")
        unit = {"fish_pitch": "rad", "fish_tension": "N", "top_tension": "N"}.get(k, "m")
        print(f"  {lk:<18} {lin:11.4g} {td[k]:11.4g} {ratio:7.3f} {td['band'][k]:11.4g} {bratio:8.3f}   ({unit})")
        rows.append((label, lk, lin, td[k], ratio, td["band"][k], bratio))
    return s, td


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1 seed, 400 s records (smoke test)")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--duration", type=float, default=1300.0, help="time-domain record per seed (s)")
    a = ap.parse_args()
    seeds = (1,) if a.quick else tuple(range(1, a.seeds + 1))
    duration = 400.0 if a.quick else a.duration

    print("== speed: 50-frequency RAO set, 0.05-2 rad/s, 1 m top heave, harmonic linearisation ==")
    om = np.linspace(0.05, 2.0, 50)
    for name in ("hover_deep_tow", "two_part_tow_1"):
        t0 = time.perf_counter()
        lm = LinearModel(name)
        setup = time.perf_counter() - t0
        r = lm.response(om)
        med, mn, cpu = median_time(lambda: lm.response(om))
        print(f"  {name:<16} DOFs {len(lm.Mq):4d}  setup (statics + Jacobians) {setup * 1e3:7.1f} ms   "
              f"RAO set median wall {med * 1e3:6.1f} ms (min {mn * 1e3:.1f}), median CPU {cpu * 1e3:.1f} ms   "
              f"iterations {r.iterations}")
    lm = LinearModel("hover_deep_tow")
    ss5 = H._sea(5)
    med, _, cpu = median_time(lambda: lm.spectral(ss5), n=7)
    print(f"  hover_deep_tow spectral SS5 (stochastic, 60 wave frequencies): median wall {med * 1e3:.1f} ms, "
          f"CPU {cpu * 1e3:.1f} ms")
    t0 = time.perf_counter()
    tun = lm.tune_compensator(ss5, np.logspace(3, 6, 7), np.logspace(3, 6, 7), H.HOVER_TRAVEL, mass=H.HOVER_M_COMP)
    print(f"  compensator grid 7 x 7 in SS5: {time.perf_counter() - t0:.2f} s; best feasible {tun.best}")

    print("\n== accuracy: significant heights (4σ) vs the nonlinear time-domain simulator ==")
    rows = []
    gain = H.deck_gain()
    tmp = tempfile.mkdtemp(prefix="bench_linear_")
    rao = H._rao_csv(tmp, gain)
    d_locked = H._comp_scene(rao, 5, "locked", 0.0, 0.0, 40.0, seed=1)
    compare("Hover deep tow, SS5, locked compensator", d_locked, "towfish", "cable", seeds, duration, 100.0, rows)
    kb = tun.best or {"k": 1e4, "b": 1e4}
    d_pass = H._comp_scene(rao, 5, "passive", kb["k"], kb["b"], 40.0, seed=1)
    compare(f"Hover deep tow, SS5, passive compensator k = {kb['k']:.3g}, b = {kb['b']:.3g}", d_pass, "towfish",
            "cable", seeds, duration, 100.0, rows)
    for code in (3, 4):
        d3 = load_scene("conventional_tow").to_dict()
        d3["vessel"].update(excitation=[], model="coastal_survey", ramp={"type": "half_cosine", "duration": 20.0})
        d3["sea"] = {"code": code, "convention": "coastal", "spectrum": "jonswap", "heading_deg": 180.0, "seed": 0}
        compare(f"conventional_tow at 3 m/s, sea code {code} coastal (JONSWAP, head seas), coastal_survey RAO",
                d3, "fish", "tow", seeds, min(duration, 900.0), 150.0, rows)
    for code in (3, 4):
        d2 = load_scene("two_part_coastal_ss4").to_dict()
        d2["sea"]["code"] = code
        compare(f"two_part_coastal_ss4 scene with sea code {code}: the depressor (primary cable)", d2, "depressor",
                "primary", seeds, min(duration, 900.0), 150.0, rows)
        d2 = load_scene("two_part_coastal_ss4").to_dict()
        d2["sea"]["code"] = code
        compare(f"two_part_coastal_ss4 scene with sea code {code} (3 m/s, coastal JONSWAP, vessel RAO, "
                "passive compensator): the fish on the light secondary", d2, "fish", "secondary", seeds,
                min(duration, 900.0), 150.0, rows)
    print("\nsummary, |linear/TD - 1| (total record | wave-frequency band):")
    for r in rows:
        print(f"  {r[0][:60]:<60} {r[1]:<18} {100 * abs(r[4] - 1):6.1f} % | {100 * abs(r[6] - 1):6.1f} %")


if __name__ == "__main__":
    main()
