"""Check automatic fidelity selection (towenv.fidelity.select) against the fine default in the time domain.

For every case (scene × excitation) and tolerance, ``select`` picks a configuration; both it and the fine
default (Houbolt, Δt = 0.01 s or the scene's smaller Δt, twice the scene's segments, 3-D) are simulated with the same sea seed, and
the relative error of the fish's heave and pitch standard deviations (∝ significant amplitudes) is
measured. *Build* cases were used to set ``towenv.fidelity.SAFETY``; *held-out* cases were not looked at
while building it. Writes docs/fidelity.md (and a figure) — one command:

    python scripts/fidelity_check.py            # ~10 min on 2 cores
    python scripts/fidelity_check.py --quick    # two cases, one tolerance (CI-sized)
"""
from __future__ import annotations

import argparse
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

from towenv import fidelity as F
from towenv.core.run import simulate
from towenv.core.simulator import load
from towenv.verification.fidelity_cases import CASES, HEAVE8, fish_name, fish_stats, pm_sea, sea  # noqa: F401

ROOT = Path(__file__).resolve().parents[1]


TOLERANCES = (0.02, 0.05, 0.10)

HISTORY = """### Why the speed-ups are what they are, and the history of this check

Where the choice is slow, the tolerance is tight in a head or bow sea: the fish's statistics then change by
1–2 % between Δt = 0.01 and 0.05 s, so 2 % allows Δt ≈ 0.035–0.05 s and 5 % Δt ≈ 0.05–0.075 s. A coarser step
costs more per step, so the speed-up stays below the ratio of the steps: measured on two_part_tow_1 at
3 m/s in SS4 (300 s), the fine default takes 1.61 Newton iterations per step, Δt = 0.04 s 2.65 and 0.09 s 3.74
with the plain stopping rule. A traced step shows why: at 0.04 s the first iterate misses both convergence
criteria — its tension change is 1.5–4 times the tension criterion (0.54 N; the tensions are extrapolated
linearly) and its body-angle change 4–7 times the angle criterion (10⁻⁵ rad; the angles quadratically) — so
every step takes a second iteration; at 0.06–0.09 s the angle change of the second iterate is still 2–10 times
the criterion, so most steps take a third, although the iteration contracts by a factor 5–10 per iteration
and the error left after the second is already within the criterion. Since round 7 the chosen configurations
stop on that estimated remaining error (`solver.newton_stop = "estimate"`, :data:`towenv.fidelity.NEWTON_STOP`;
docs/model-notes.md): 10–25 % fewer iterations at Δt 0.04–0.15 s in head and bow seas (1–6 % in a following
sea or a series tow), the fish statistics moved by ≤ 0.35 % in 15 measured choices, and nothing saved at the fine default's 0.01 s, where almost every step converges within two
iterations (tests/unit/test_newton_stop.py) — so the speed-up is not bought by a looser fine default. An
irregular sea adds the vessel motion (~11–17 µs) to every step. (`python scripts/newton_iterations.py`
reproduces the iteration figures.)

The check has been run in eight rounds, the fourth an experiment that was reverted; each round's held-out
cases were defined and committed before its rules were run on them, and became "tuned" when the next round's
rules were set after looking at them:

* **Round 1**: SAFETY, the slack and flow rules, a Δt ≤ 0.02 s cap for series tows; 27 held-out runs:
  **96 %** within tolerance, median speed-up **4.5×** (12 of 26 ≥ 5×).
* **Round 2**: the series cap replaced by the body–tail relaxation of the simulator and a 40 s pilot run that
  rejects step cuts and divergence, Δt candidates up to 0.3 s, the compiled record loop, a refitted cost
  model; 36 held-out runs: **81 %**, median **5.2×** (19 of 36 ≥ 5×). Misses: a slack series tow in SS5, a
  parallel tow whose turn put the following sea on its bow, a slack two-part tow at the 10 % step.
* **Round 3**: the pilot also compares the statistics with the fine default's over an 80 s window after the
  ramp and the last manoeuvre (× the safety factor); 30 held-out runs: **93 %**, median **4.7×** (11 of 30 ≥
  5×). Misses: the series tow at 2.5 m/s through its turn at 5 % and 10 % (intermittent snap loads of its
  slack sub-cables; the 80 s window under-samples them).
* **Round 4 — an experiment (reverted):** a Newton stopping test on the estimated remaining error, made the
  simulator's default, gave **90 %** / **5.3×** on 10 further cases but made very long steps less robust (the
  stability map lost Houbolt's 1 s cap in 3 of 15 cells); not shipped. Its misses were hover_deep_tow at 2 m/s
  in SS5, whose 3-D fine default rolls over after ~150 s — a lateral instability of the towfish that the 2-D
  choice cannot have.
* **Round 5**: Δt candidates spaced ≤ 1.33× below 0.15 s (0.03 → 0.05 s had been a 1.67× jump); a fish with
  little mean flow no longer forces the fine default — the pilot alone decides, with the slack rule's safety
  factor; 2-D refused when the linearised model has an unstable lateral mode (`LinearModel.damped_modes`; it
  predicts the simulator's round-off growth rate to 0.3 %, docs/linear.md); timings are medians of 3 runs
  after a warm-up (single timings vary by ±30 % on this machine — the earlier rounds used single timings).
  30 held-out runs: **100 %** within tolerance, median **4.1×** (14 of 30 ≥ 5×). Four runs got the fine
  default (0.7–0.9×) because the pilots, trying the cheapest candidates one Δt at a time, used up
  MAX_PILOTS = 6 (a slack series tow at 1.5 m/s at every tolerance; hover_deep_tow at 1.5 m/s at 10 % while
  2 % and 5 % found choices).
* **Round 6**: a pilot that misses the statistics by a factor e/target prunes every candidate
  with no more segments and a Δt above its Δt·(target/e)^½ (the error falls at least as Δt²), and
  MAX_PILOTS = 8. 30 held-out runs: **100 %** within tolerance, median **4.0×** (11 of 30 ≥ 5×).
* **Round 7**: the round-4 stopping test again, this time only in the chosen configurations
  (`solver.newton_stop = "estimate"`, with guards: from the second iteration, contraction ρ ≤ ½, no slack
  segment; the fine default and the simulator's default keep the plain rule, so the stability map is
  unchanged), and the recorded body rates computed in one compiled call instead of a Python loop per record
  (30–45 ms less per 300 s run, for every configuration alike). Tried first on round 6's cases (then relabelled
  tuned): 100 %, median 5.5× there, against 4.0× with the round-6 rules. 30 held-out runs: **100 %** within
  tolerance, median **4.4×** (14 of 30 ≥ 5×).
* **Round 8** (this report): the safety factors recalibrated. Where cables go slack — 37 of 42 tuned cases,
  the two-part and multi-tows' light secondaries are slack 35–65 % of the time in these seas — round 7 put
  SAFETY_SLACK = 2.5 on both the linear prediction and the pilot's measured difference, set in round 1 before
  the pilot compared statistics at all. `scripts/fidelity_calibration.py` ran 1260 configurations of 42 tuned
  cases (segment factors 1, 1.5, 2 × ten Δt from 0.03 to 0.3 s, 300 s each) against their fine defaults: the
  raw prediction matches the measured error in the median but scatters (measured / predicted: median 0.98,
  90th percentile 2.9); the 80 s pilot window scatters less (measured / pilot: median 1.0, 90th percentile
  2.1 with slack cables, 1.5 without). Replaying the selection on those runs (`--replay`), factors 2.5/2.5
  met the tolerance in 99.2 % of 126 selections, screen 1.0 with pilot 1.5 in 98.4 % at ~25 % more speed;
  the shipped rule is the latter (`SCREEN_SAFETY`, `PILOT_SAFETY`; without pilots the prediction alone
  decides with SAFETY / SAFETY_SLACK as before; a fish with little mean flow keeps SAFETY_SLACK on both).
  The ten held-out cases were committed (8d9bf51) before the calibration was run or the factors changed;
  round 7's cases are tuned now. Its result on the held-out cases, on the kernels of that day: 97 %, median
  5.01× — the 5× goal met, narrowly (the "held-out" line above is the regeneration on later, faster kernels). A second timing of the same (deterministic) choices, `python
  scripts/fidelity_check.py --roles held-out --doc /tmp/replicate.md`, gave 97 % and 5.85× (17 of 30 ≥ 5×):
  timings on this machine vary by that much between runs. The held-out miss: series_multitow at 165°, seed 57,
  at 2 % (Δt 0.1 s: 2.6 %). The same case at 10 % got the fine default (1.0×): its eight pilots, cheapest
  first, were all spent on the scene's own segment count at Δt 0.06–0.25 s (step cuts, or 17 % off), while
  at 2 % and 5 % twice the segments ran at Δt 0.1 s — a looser tolerance ending up slower than a tighter one
  (left as found; a rule for it would need a new held-out round)."""


def run_config(scene, overrides, duration, repeats=1):
    """Simulate ``duration`` s; the wall time is the median of ``repeats`` identical runs (the runs are
    deterministic, so the results are the same; single timings on this machine vary by ±30 %)."""
    sc = scene.with_overrides(overrides) if overrides else scene
    walls = []
    res = None
    for _ in range(max(1, repeats)):
        t = time.perf_counter()
        res = simulate(sc, duration)
        walls.append(time.perf_counter() - t)
    return res, float(np.median(walls))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="two cases, tolerance 5 %% only, short records")
    ap.add_argument("--doc", type=Path, default=ROOT / "docs" / "fidelity.md")
    ap.add_argument("--duration", type=float, default=300.0, help="simulated seconds per run (default 300)")
    ap.add_argument("--roles", default="build,tuned,held-out", help="comma-separated roles to run (default: all)")
    ap.add_argument("--repeats", type=int, default=3,
                    help="timed runs per configuration; the speed-up uses the median wall times (default 3)")
    args = ap.parse_args(argv)
    roles = set(args.roles.split(","))
    cases = [c for c in CASES if c[3] in roles] if not args.quick else [CASES[2], CASES[4]]
    tols = TOLERANCES if not args.quick else (0.05,)
    duration = args.duration if not args.quick else 120.0
    t_start = 60.0 if not args.quick else 40.0
    repeats = args.repeats if not args.quick else 1
    if repeats < 1:
        ap.error("--repeats: must be at least 1")
    rows = []
    wall0 = time.perf_counter()
    # warm-up: the first simulation in a process loads the compiled kernels from numba's cache (~1 s), which
    # would otherwise be charged to the first case's fine default
    simulate(load(cases[0][1]), 5.0)
    for label, name, ov, role in cases:
        base = load(name).with_overrides(ov) if ov else load(name)
        fish = fish_name(base)
        fine_ov = F.fine_default(base).overrides()
        try:
            ref, ref_wall = run_config(base, fine_ov, duration, repeats)
            ref_stats = fish_stats(ref, fish, t_start)
        except Exception as exc:  # noqa: BLE001 - reported in the table
            rows.append(dict(case=label, role=role, tol=None, error=f"fine default failed: {exc}"))
            print(f"{label}: fine default failed: {exc}", flush=True)
            continue
        for tol in tols:
            ch = F.select(base, tolerance=tol)
            rec = dict(case=label, role=role, tol=tol, choice=ch.summary(), method=ch.method, dt=ch.dt,
                       factor=ch.segment_factor, planar=ch.planar, pred=ch.error, select_s=ch.seconds,
                       pilot_err=ch.pilot_error,
                       ref_wall=ref_wall, ref=ref_stats)
            if ch.method == "linear":
                from towenv.linear import LinearModel
                t = time.perf_counter()
                lm = LinearModel(base)
                st = F._Predictor(base, F._sea_of(base, None), F.OUTPUTS).stats(1.0, None)[0]
                wall = time.perf_counter() - t
                got = st
            else:
                try:
                    res, wall = run_config(base, ch.overrides(), duration, repeats)
                    got = fish_stats(res, fish, t_start)
                except Exception as exc:  # noqa: BLE001
                    rec.update(error=f"chosen configuration failed: {exc}")
                    rows.append(rec)
                    print(f"{label} tol {tol}: chosen failed: {exc}", flush=True)
                    continue
            errs = {k: abs(got[k] / ref_stats[k] - 1.0) for k in got if ref_stats[k] > 0}
            rec.update(wall=wall, got=got, err=max(errs.values()), errs=errs, speedup=ref_wall / max(wall, 1e-9),
                       ok=max(errs.values()) <= tol)
            rows.append(rec)
            print(f"{label:45s} tol {100 * tol:4.0f} %  {ch.summary()}\n    measured error {100 * rec['err']:.2f} %"
                  f" ({'ok' if rec['ok'] else 'MISSED'}), speed-up {rec['speedup']:.1f}×", flush=True)
    total = time.perf_counter() - wall0
    write_doc(args.doc, rows, total, duration, t_start, args.quick, repeats)
    held = [r for r in rows if r["role"] == "held-out" and r.get("tol") is not None]
    if held:
        frac = np.mean([bool(r.get("ok", False)) for r in held])
        sp = np.median([r["speedup"] for r in held if "speedup" in r])
        print(f"held-out: {100 * frac:.0f} % within tolerance ({len(held)} runs, failures count as misses), "
              f"median speed-up {sp:.1f}×")


def write_doc(path, rows, total, duration, t_start, quick, repeats=1):
    lines = ["# Automatic fidelity selection", "",
             f"Generated by `python scripts/fidelity_check.py{' --quick' if quick else ''}` in {total / 60:.1f} min "
             f"on {platform.processor() or platform.machine()} ({platform.system()}).", ""]
    lines += [F.__doc__.split("How the error", 1)[0].strip(), "", "## How the error is predicted", "",
              "How the error" + F.__doc__.split("How the error", 1)[1].rstrip(), ""]
    lines += ["## Result", ""]
    for name in ("held-out", "tuned", "build"):
        grp = [r for r in rows if r["role"] == name and r.get("tol") is not None]   # failed runs count as misses
        timed = [r for r in grp if "speedup" in r]
        if grp:
            frac = np.mean([bool(r.get("ok", False)) for r in grp])
            nfail = sum(1 for r in grp if "ok" not in r)
            sp = np.median([r["speedup"] for r in timed]) if timed else float("nan")
            lines.append(f"* **{name}** cases: the chosen configuration met the tolerance in "
                         f"**{100 * frac:.0f} %** of {len(grp)} runs ({nfail} of them failed to run, counted as "
                         f"misses); median speed-up over the fine default **{sp:.1f}×** "
                         f"(min {min(r['speedup'] for r in timed):.1f}×, max {max(r['speedup'] for r in timed):.1f}×).")
    held = [r for r in rows if r["role"] == "held-out" and r.get("tol") is not None]
    if held:
        frac = np.mean([bool(r.get("ok", False)) for r in held])
        sps = [r["speedup"] for r in held if "speedup" in r]
        sp = np.median(sps)
        n5 = sum(1 for x in sps if x >= 5.0)
        lines += ["", f"**Goals (issue 5, held-out cases):** within tolerance in ≥ 90 % of cases — "
                      f"{'**met**' if frac >= 0.9 else '**not met**'} ({100 * frac:.0f} %); ≥ 5× faster than the fine "
                      f"default — {'**met**' if sp >= 5.0 else '**not met**'} on the median ({sp:.2f}×; {n5} of "
                      f"{len(sps)} runs ≥ 5×).", "", HISTORY, ""]
    skipped = [r for r in rows if r.get("tol") is None]
    for r in skipped:
        lines.append(f"* not evaluated: {r['case']} — {r['error']}")
    lines += ["", f"Each run: {duration:g} s simulated, statistics from t = {t_start:g} s; error = largest relative "
              "difference of the fish heave and pitch standard deviations from the fine default's, same seed. "
              "*Predicted*: the linear prediction of that error for the chosen configuration, as the selection "
              "screened it (× SCREEN_SAFETY when piloted, × SAFETY_SLACK where the fish has little mean flow). "
              "*Pilot window*: the same difference over the chosen configuration's pilot window "
              "(towenv.fidelity.pilot_window), measured during the selection; *selection*: wall time of `select` "
              "including its pilot runs (not included in the speed-up, which compares the runs). *Speed-up*: the "
              f"fine default's wall time over the chosen configuration's, each the median of {repeats} identical "
              "runs (single timings on this machine vary by ±30 %), after a warm-up run.", "",
              "| case | role | tol | chosen | predicted | pilot window | measured | ok | speed-up | selection |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "err" not in r:
            tol = f"{100 * r['tol']:g} %" if r.get("tol") is not None else ""
            lines.append(f"| {r['case']} | {r['role']} | {tol} | {r.get('error', '')} | | | | ❌ | | |")
            continue
        pe = f"{100 * r['pilot_err']:.2g} %" if r.get("pilot_err") is not None else "–"
        lines.append(f"| {r['case']} | {r['role']} | {100 * r['tol']:g} % | {r['choice'].split('; predicted')[0]} | "
                     f"{100 * r['pred']:.2g} % | {pe} | {100 * r['err']:.2g} % | {'✅' if r['ok'] else '❌'} | "
                     f"{r['speedup']:.1f}× | {r['select_s']:.2f} s |")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
