"""Stability map: the largest stable time step of every towenv solver, and where it breaks.

For each solver behind ``towenv.make_simulator`` (``houbolt`` implicit; ``generalized_alpha`` (ρ∞ = 0.2)
and ``newmark`` implicit on the elastic model; ``euler``/``rk2``/``rk4`` explicit with axial damping ratio
0.25 — MoorDyn's BA = −0.5; ``quasi_static`` has no time-step limit and is only checked), the largest
stable Δt is found by bisection (geometric, to 8 % for the explicit schemes and 10 % for the implicit
ones) on the shared deck (peer deck towed at 2 m/s, 1 m tow-point heave at 8 s, 8 s
half-cosine ramp, N = 16 s simulated) against segment count (5–80) and cable stiffness (EA × 0.1, 1, 10),
and compared with the explicit axial CFL step l/c_L.

"Stable" means: N seconds run without ``towenv.SimulationDivergence`` **and** the top tension stays
within a band of a reference run (Houbolt, Δt = 2 ms, same deck): max |T(t) − T_ref(t)| ≤ band ×
max T_ref (band 10 %; 25 % in the slack/snap cases, whose snap peaks are timing-sensitive). An explicit
scheme can go wrong without blowing up (spurious axial ringing), which the band catches.

Behaviour cases (20 segments): slack-inducing heave (4 m at 4 s), snap loading (6 m at 4 s), large
excitation without the start-up ramp (3 m at 4 s, ramp "none"), very low damping (cable C_n = C_t = 0,
explicit axial damping 0), series tows with 3, 4 and 5 cables solved together (from series_multitow, its
180° turn), and the Newton iteration of the Houbolt scheme (iterations per step and step cuts against Δt,
with and without step cuts).

    python scripts/stability_map.py            # ~10 min; writes docs/stability.md + docs/figures/stability_*.png
    python scripts/stability_map.py --quick    # ~2 min smoke run to a temporary folder
"""
from __future__ import annotations

import argparse
import math
import os
import pickle
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import towenv
from towenv.peer.decks import axial_cfl_step, series_tow, shared_deck, total_segments

ROOT = Path(__file__).resolve().parent.parent
EXPLICIT = ("euler", "rk2", "rk4")
ALPHA = ("generalized_alpha", "newmark")      # implicit one-step schemes on the elastic model (ρ∞ default)
SOLVERS = ("houbolt",) + ALPHA + EXPLICIT
COLORS = {"houbolt": "tab:blue", "generalized_alpha": "tab:olive", "newmark": "goldenrod", "euler": "tab:orange",
          "rk2": "tab:green", "rk4": "tab:red"}
ZETA = 0.25
DT_CAP = 1.0          # the scene schema's largest solver.dt
DT_MIN = 1e-5         # and its smallest
RAMP = dict(type="half_cosine", duration=8.0)


# ----------------------------------------------------------------------------------------------------
def trial(scene, method, dt, N, ref=None, band=0.10, zeta=ZETA, sample=0.05, **solver):
    """One run: {'stable', 'reason', 'iters', 'max_iters', 'cuts', 't', 'T', 'wall'}."""
    kw = dict(solver)
    if method in EXPLICIT:
        kw.setdefault("axial_damping_ratio", zeta)
    out = dict(dt=dt, method=method, stable=False, reason="", iters=float("nan"), max_iters=0, cuts=0)
    try:
        sim = towenv.make_simulator(scene, method=method, dt=dt, **kw)
    except (ValueError, towenv.SceneError) as exc:
        out["reason"] = f"n/a: {str(exc).splitlines()[0][:100]}"
        return out
    k = max(1, int(round(sample / dt)))
    n = int(round(N / dt)) // k
    t = np.full(n + 1, np.nan)
    T = np.full(n + 1, np.nan)
    t[0], T[0] = sim.t, sim.top_tension
    w0 = time.perf_counter()
    try:
        for i in range(1, n + 1):
            sim.advance_steps(k)
            t[i], T[i] = sim.t, sim.top_tension
        diverged = None
    except towenv.SimulationDivergence as exc:
        diverged = exc
    out["wall"] = time.perf_counter() - w0
    st = sim.stats
    out.update(iters=st["mean_iterations"], max_iters=st["max_iterations"], cuts=st["step_cuts"], t=t, T=T)
    if diverged is not None:
        out["reason"] = f"diverged at t = {diverged.time:.3g} s ({diverged.element}: {diverged.cause})"
        out["exc"] = diverged
        out["state_finite"] = bool(np.all(np.isfinite(sim.positions)))
        return out
    if not np.all(np.isfinite(T)):
        out["reason"] = "non-finite top tension"
        return out
    if ref is not None:
        Tr = np.interp(t, ref["t"], ref["T"])
        dev = float(np.max(np.abs(T - Tr)) / np.max(ref["T"]))
        out["deviation"] = dev
        if dev > band:
            out["reason"] = f"out of band: max |T − T_ref| = {100 * dev:.0f} % of max T_ref"
            return out
    out["stable"] = True
    out["reason"] = "ok"
    return out


def reference(scene, N, dt=0.002):
    r = trial(scene, "houbolt", dt, N, None, tolerance=0.05, relative_tolerance=1e-6, sample=0.01)
    if not r["stable"]:
        raise RuntimeError(f"reference run failed: {r['reason']}")
    return r


def largest_stable(scene, method, N, ref, band=0.10, cfl=None, zeta=ZETA, rel=None, log=None, **solver):
    """Bisection on Δt. Returns (dt_stable, dt_unstable, reason_at_unstable, trials)."""
    trials = []

    def test(dt):
        r = trial(scene, method, dt, N, ref, band, zeta, **solver)
        trials.append(r)
        if log:
            log(f"      {method:8s} dt {dt:.4g}: {r['reason'][:120]}")
        return r["stable"]

    rel = rel or (1.08 if method in EXPLICIT else 1.10)
    if method in EXPLICIT:
        x = 0.7 * cfl
        if test(x):
            lo, hi = x, None
            while hi is None:
                x = min(lo * 1.5, DT_CAP)
                if test(x):
                    lo = x
                    if x >= DT_CAP:
                        return lo, None, "", trials
                else:
                    hi = x
        else:
            lo, hi = None, x
            while lo is None:
                x = hi * 0.6
                if x < max(0.02 * cfl, DT_MIN):
                    return None, hi, trials[-1]["reason"], trials
                if test(x):
                    lo = x
                else:
                    hi = x
    else:
        if test(DT_CAP):
            return DT_CAP, None, "", trials
        hi = DT_CAP
        lo = None
        x = 0.05
        while lo is None:
            if test(x):
                lo = x
            else:
                hi = x
                x *= 0.4
                if x < 1e-4:
                    return None, hi, trials[-1]["reason"], trials
    while hi / lo > rel:
        x = math.sqrt(lo * hi)
        if test(x):
            lo = x
        else:
            hi = x
    bad = next((t for t in trials if t["dt"] == hi), None)
    return lo, hi, bad["reason"] if bad else "", trials


# ----------------------------------------------------------------------------------------------------
def transverse_courant(scene, dt, T):
    sc = towenv.load_scene(scene)
    ln = sc.lines[0]
    l = ln.length / (ln.segments if isinstance(ln.segments, int) else sum(ln.segments))
    mu_a = ln.can * sc.water.density * math.pi * ln.diameter ** 2 / 4
    return math.sqrt(T / (ln.mass_per_length + mu_a)) * dt / l


def fmt(dt):
    if dt is None:
        return "—"
    if dt >= 0.1:
        return f"{dt:.3g} s"
    return f"{1e3 * dt:.3g} ms"


def stability_grid(segs, eas, N, log, quick):
    rows = []
    for ea in eas:
        for n in segs:
            sc = shared_deck(segments=n, EA_factor=ea, ramp=RAMP)
            cfl = axial_cfl_step(sc)
            ref = reference(sc, N)
            log(f"   EA x{ea:g}, {n} segments: l/c_L = {1e3 * cfl:.4g} ms, reference max T {np.max(ref['T']):.0f} N")
            for m in SOLVERS:
                lo, hi, why, trials = largest_stable(sc, m, N, ref, cfl=cfl, log=log if quick else None)
                cot = transverse_courant(sc, lo, float(np.max(ref["T"]))) if lo else float("nan")
                tr = next((t for t in trials if t["dt"] == lo), {})
                rows.append(dict(ea=ea, segments=n, solver=m, cfl=cfl, lo=lo, hi=hi, why=why, co_t=cot,
                                 iters=tr.get("iters", float("nan")), cuts=tr.get("cuts", 0),
                                 n_trials=len(trials)))
                log(f"      {m:8s} largest stable {fmt(lo)} (= {lo / cfl if lo else float('nan'):.3g} l/c_L), "
                    f"fails at {fmt(hi)}: {why[:100]}")
    return rows


def behaviour_cases(N, log, quick):
    cases = [
        ("slack-inducing heave (4 m at 4 s)", dict(heave=4.0, period=4.0), 0.25, {}),
        ("snap loading (6 m at 4 s)", dict(heave=6.0, period=4.0), 0.25, {}),
        ("no start-up ramp, 3 m at 4 s", dict(heave=3.0, period=4.0, ramp=dict(type="none", duration=0.0)), 0.25, {}),
        ("very low damping (C_n = C_t = 0, explicit ζ = 0)", dict(), 0.10, {"cn": 0.0, "ct": 0.0}),
    ]
    out = []
    for name, kw, band, cable in cases:
        kw.setdefault("ramp", RAMP)
        sc = shared_deck(segments=20, **kw)
        if cable:
            sc = sc.with_overrides({f"lines[0].{k}": v for k, v in cable.items()})
        cfl = axial_cfl_step(sc)
        ref = reference(sc, N)
        # slack/snap statistics of the reference
        sim = towenv.Simulator(sc, dt=0.002, tolerance=0.05)
        n_slack = 0
        tmin = math.inf
        for _ in range(int(round(N / 0.01))):
            sim.advance_steps(5)
            tmin = min(tmin, float(np.min(sim.tensions)))
            n_slack += int(np.sum(sim.tensions <= 0))
        info = dict(peak=float(np.max(ref["T"])), static=float(ref["T"][0]), tmin=tmin, slack=n_slack)
        log(f"   {name}: reference peak {info['peak']:.0f} N ({info['peak'] / info['static']:.2f}× static), "
            f"min segment tension {tmin:.0f} N")
        res = {}
        for m in SOLVERS + ("quasi_static",):
            zeta = 0.0 if "low damping" in name else ZETA
            if m == "quasi_static":
                r = trial(sc, m, 0.05, N, ref, band)
                res[m] = (0.05 if r["stable"] else None, None if r["stable"] else 0.05, r["reason"], [r])
                continue
            res[m] = largest_stable(sc, m, N, ref, band=band, cfl=cfl, zeta=zeta, log=log if quick else None)
            lo, hi, why, _ = res[m]
            log(f"      {m:8s} largest stable {fmt(lo)}, fails at {fmt(hi)}: {why[:110]}")
        out.append(dict(name=name, band=band, cfl=cfl, info=info, res=res))
    return out


def series_cases(N, log, counts=(3, 4, 5)):
    out = []
    for nb in counts:
        sc = series_tow(nb)
        cfl = axial_cfl_step(sc)
        ref = reference(sc, N)
        log(f"   series tow, {nb} cables: l/c_L = {1e3 * cfl:.3g} ms, reference max T {np.max(ref['T']):.0f} N")
        res = {}
        for m in SOLVERS:
            res[m] = largest_stable(sc, m, N, ref, cfl=cfl)
            lo, hi, why, trials = res[m]
            log(f"      {m:8s} largest stable {fmt(lo)}, fails at {fmt(hi)}: {why[:110]}")
        res["houbolt, no step cuts"] = largest_stable(sc, "houbolt", N, ref, max_step_cuts=0)
        lo, hi, why, _ = res["houbolt, no step cuts"]
        log(f"      houbolt without step cuts: largest stable {fmt(lo)}, fails at {fmt(hi)}: {why[:110]}")
        out.append(dict(n=nb, segments=total_segments(sc), cfl=cfl, res=res))
    return out


def newton_sweep(N, log, dts):
    out = []
    for label, sc in (("shared deck, 20 segments", shared_deck(20, ramp=RAMP)),
                      ("slack-inducing heave (4 m at 4 s)", shared_deck(20, heave=4.0, period=4.0, ramp=RAMP)),
                      ("series tow, 4 cables", series_tow(4))):
        ref = reference(sc, N)
        rows = []
        for dt in dts:
            for cuts in (4, 0):
                r = trial(sc, "houbolt", dt, N, ref, 0.25 if "slack" in label else 0.10, max_step_cuts=cuts)
                dev = r.get("deviation", float("nan"))
                rows.append(dict(dt=dt, max_cuts=cuts, stable=r["stable"], reason=r["reason"], iters=r["iters"],
                                 max_iters=r["max_iters"], cuts=r["cuts"], dev=dev,
                                 co_t=transverse_courant(sc, dt, float(np.max(ref["T"])))
                                 if "series" not in label else float("nan")))
            a, b = rows[-2], rows[-1]
            log(f"   {label}: dt {dt:g}: it/step {a['iters']:.2f} (max {a['max_iters']}), cuts {a['cuts']}, "
                f"{a['reason'][:60]} | no cuts: {b['reason'][:60]}")
        out.append(dict(label=label, rows=rows))
    return out


# ----------------------------------------------------------------------------------------------------
def plot_map(rows, segs, eas, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(SOLVERS), figsize=(4.6 * len(SOLVERS), 4.2), squeeze=False,
                             gridspec_kw=dict(wspace=0.08))
    for k, (ax, m) in enumerate(zip(axes[0], SOLVERS)):
        Z = np.full((len(eas), len(segs)), np.nan)
        for r in rows:
            if r["solver"] == m and r["lo"]:
                Z[eas.index(r["ea"]), segs.index(r["segments"])] = math.log10(r["lo"])
        im = ax.imshow(Z, origin="lower", cmap="viridis", vmin=-4.5, vmax=0, aspect="auto")
        for r in rows:
            if r["solver"] != m:
                continue
            i, j = eas.index(r["ea"]), segs.index(r["segments"])
            if r["lo"]:
                top = ("≥" if r["hi"] is None else "") + fmt(r["lo"]).replace(" ", "\u2009")
                q = r["lo"] / r["cfl"]
                txt = f"{top}\n{q:.0f}×" if q >= 100 else f"{top}\n{q:.3g}×"
            else:
                txt = "none"
            ax.text(j, i, txt, ha="center", va="center", fontsize=7.5,
                    color="black" if (r["lo"] or 1e-9) > 0.05 else "white")
        ax.set_xticks(range(len(segs)), [str(s) for s in segs])
        ax.set_yticks(range(len(eas)), [f"EA×{e:g}" for e in eas] if k == 0 else [])
        ax.set_xlabel("segments")
        ax.set_title({"generalized_alpha": "generalized_alpha (ρ∞ 0.2)"}.get(m, m), fontsize=10)
    fig.colorbar(im, ax=axes[0].tolist(), label="log10(largest stable Δt / s)", shrink=0.85, pad=0.02)
    fig.suptitle("Shared deck (2 m/s, 1 m heave at 8 s): largest stable Δt and Δt_max/(l/c_L) "
                 "(≥ = stable at the 1 s cap of solver.dt)", fontsize=10)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def plot_cfl(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    colors = COLORS
    mk = {0.1: "v", 1.0: "o", 10.0: "^"}
    for r in rows:
        if r["lo"]:
            ax.scatter(r["cfl"], r["lo"], color=colors[r["solver"]], marker=mk.get(r["ea"], "o"),
                       facecolors="none" if r["hi"] is None else colors[r["solver"]], s=36)
    x = np.logspace(math.log10(min(r["cfl"] for r in rows)) - 0.2, math.log10(max(r["cfl"] for r in rows)) + 0.2, 10)
    ax.plot(x, x, "k--", lw=0.8, label="Δt = l/c_L (axial CFL)")
    ax.plot(x, 0.1 * x, "k:", lw=0.8, label="thesis guide l/(10 c_L)")
    from matplotlib.lines import Line2D
    h = [Line2D([], [], color=c, marker="o", ls="", label=s) for s, c in colors.items()]
    h += [Line2D([], [], color="0.3", marker=m, ls="", label=f"EA×{e:g}") for e, m in mk.items()]
    h += ax.get_legend_handles_labels()[0]
    ax.legend(handles=h, fontsize=8, loc="lower right")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("axial CFL step l/c_L (s)")
    ax.set_ylabel("largest stable Δt (s)  (hollow: stable at the 1 s cap)")
    ax.grid(True, which="both", alpha=0.25)
    ax.set_title("Largest stable Δt against the axial CFL step", fontsize=10)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


# ----------------------------------------------------------------------------------------------------
#: linear stability limits ω_max Δt / 2 for the highest axial mode at damping ratio 2·ZETA = 0.5 (summary text)
LINEAR_LIMIT = {"euler": 0.618, "rk2": 1.000, "rk4": 1.311}


def _coarse_cells(grid):
    """How far the coarsest-mesh cells sit from the linear limit (end-node effect on ω_max), from the numbers."""
    if not grid:
        return ""
    n0 = min(r["segments"] for r in grid)
    cells = []
    for m in EXPLICIT:
        rat = [r["lo"] / r["cfl"] / LINEAR_LIMIT[m] - 1 for r in grid if r["solver"] == m and r["segments"] == n0
               and r["lo"]]
        if rat:
            lo, hi = round(100 * min(rat)), round(100 * max(rat))      # ints: no "-0"
            cells.append(f"{m} {lo:+d} %" if lo == hi else f"{m} {lo:+d} to {hi:+d} %")
    return (f"; the {n0}-segment cells sit at " + ", ".join(cells) + " of the limit (the end nodes change ω_max "
            "of so coarse a chain)") if cells else ""


def summary(grid, beh, ser, newton):
    o = ["## Summary\n"]
    for m in EXPLICIT:
        rat = [r["lo"] / r["cfl"] for r in grid if r["solver"] == m and r["lo"]]
        if rat:
            sg = sorted({r["segments"] for r in grid})
            ea = sorted({r["ea"] for r in grid})
            o.append(f"* **{m}**: largest stable Δt = {min(rat):.2f}–{max(rat):.2f} × l/c_L over all "
                     f"{len(rat)} cells ({sg[0]}–{sg[-1]} segments, EA ×{ea[0]:g}–×{ea[-1]:g}): the axial CFL bound, "
                     "scaling with l/√EA.")
    o.append(f"* These are the linear stability limits of the three schemes for the highest axial mode of the "
             f"lumped chain, ω_max = 2c_L/l, with damping ratio {2 * ZETA:g} (towenv's `axial_damping_ratio` "
             f"ζ' = {ZETA} gives the segment damping 2ζ'·l·√(EA·μ), i.e. a ratio 2ζ' for that mode; MoorDyn's BA = −ζ "
             "gives ζ): ω_max Δt ≤ 2(√(1+ζ²) − ζ) → 0.618 l/c_L (semi-implicit Euler), 1.000 (RK2: the edge of its "
             "stability region on the 120° ray), 1.311 (RK4). The bisection returns the largest step that passed, so "
             "it sits up to 8 % below" + _coarse_cells(grid) + ".")
    hb = [r for r in grid if r["solver"] == "houbolt" and r["lo"]]
    if hb:
        capped = [r for r in hb if r["hi"] is None]
        o.append(f"* **houbolt**: stable (and within the 10 % band) at the {DT_CAP:g} s cap of `solver.dt` in "
                 f"{len(capped)} of {len(hb)} cells — {min(r['lo'] / r['cfl'] for r in hb):.0f}× to "
                 f"{max(r['lo'] / r['cfl'] for r in hb):.0f}× the explicit step, at transverse Courant numbers up to "
                 f"{max(r['co_t'] for r in hb):.0f} (model.md 5.9 expected a frozen-tangent quasi-Newton to stop "
                 "converging near Co_T ≈ 0.7; the core's iteration does not). What limits the step is accuracy"
                 + (": on the 20-segment deck the top tension deviates from the 2 ms reference by at most "
                    + ", ".join(f"{100 * r['dev']:.2g} % at {r['dt']:g} s" for r in newton[0]["rows"]
                                if r["max_cuts"] == 4 and r["dt"] in (0.05, 0.1, 0.3, 1.0))
                    if newton else "") + " (Newton table below).")
    for m in ALPHA:
        rs = [r for r in grid if r["solver"] == m and r["lo"]]
        if rs:
            capped = [r for r in rs if r["hi"] is None]
            band = sum(1 for r in rs if r["hi"] is not None and "out of band" in r["why"])
            newton_fail = sum(1 for r in rs if r["hi"] is not None and "Newton" in r["why"])
            o.append(f"* **{m}**: largest stable Δt {fmt(min(r['lo'] for r in rs))}–{fmt(max(r['lo'] for r in rs))} = "
                     f"{min(r['lo'] / r['cfl'] for r in rs):.0f}×–{max(r['lo'] / r['cfl'] for r in rs):.0f}× the "
                     f"explicit step l/c_L (stable at the cap in {len(capped)} of {len(rs)} cells). Linearly "
                     "unconditionally stable"
                     + ("." if len(capped) == len(rs) else
                        "; at the smallest failing step "
                        f"{newton_fail} cell(s) stopped because the Newton iteration on the node positions of the "
                        "stiff elastic cable did not converge even with 4 step halvings (a large step rotates the "
                        f"segments and the linearised axial springs overshoot), {band} left the band (accuracy"
                        + (", and undamped axial ringing: no numerical dissipation" if m == "newmark" else "")
                        + ")."))
    for b in beh:
        lo_h = b["res"]["houbolt"][0]
        ex = [(m, b["res"][m][0]) for m in EXPLICIT if b["res"][m][0]]
        best = max(ex, key=lambda x: x[1]) if ex else None
        o.append(f"* **{b['name']}** (band {100 * b['band']:.0f} %): houbolt {fmt(lo_h)}"
                 + (f", best explicit {best[0]} {fmt(best[1])} ({lo_h / best[1]:.0f}× smaller)" if best and lo_h else "")
                 + "; quasi-static " + ("passes" if b["res"]["quasi_static"][0] else "fails") + " the band.")
    if ser:
        o.append("* **cables in series, one Newton iteration**: houbolt without step cuts "
                 + ", ".join(f"{s['n']} cables {fmt(s['res']['houbolt, no step cuts'][0])}" for s in ser)
                 + "; with the default 4 halvings " + ", ".join(f"{fmt(s['res']['houbolt'][0])}" for s in ser)
                 + ", with the monolithic series coupling (the tails' top segments in their bodies' cliques of the "
                 "tree tension solve, docs/model-notes.md \"Series coupling\"; the scenes' own Δt is 0.02 s). The "
                 "thesis found the monolithic step 'extremely small' beyond three cables with its unstable "
                 "recursion (model.md 6.1); the tree solve has no such limit.")
    for nw in newton:
        fails = [r for r in nw["rows"] if r["max_cuts"] == 0 and not r["stable"] and "diverged" in r["reason"]]
        first = min((r["dt"] for r in fails), default=None)
        cuts = [r for r in nw["rows"] if r["max_cuts"] == 4 and r["cuts"] > 0]
        o.append(f"* **Newton, {nw['label']}**: " + (f"without step cuts it first fails at Δt = {first:g} s"
                                                     if first else "never fails up to 1 s, even without step cuts")
                 + (f"; step halvings start at {min(r['dt'] for r in cuts):g} s" if cuts else "") + ".")
    return "\n".join(o) + "\n"


def write_doc(doc, figdir, grid, segs, eas, beh, ser, newton, N, wall, argv, quick, start_load):
    rel = os.path.relpath(figdir, doc.parent)
    cpu = platform.machine()
    try:
        cpu = next(ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name"))
    except (OSError, StopIteration):
        pass
    o = ["# Stability map of the towenv solvers\n",
         f"Generated by `python scripts/stability_map.py{(' ' + ' '.join(argv)) if argv else ''}` in "
         f"{wall / 60:.1f} min{' (**--quick smoke run**)' if quick else ''} on {cpu}, {os.cpu_count()} cores "
         f"({start_load} at the start; other jobs shared the machine — stability does not depend on load).\n",
         f"""**Criterion.** A time step is *stable* if the run covers N = {N:g} s without
`towenv.SimulationDivergence` **and** its top tension stays within a band of a reference run (Houbolt,
Δt = 2 ms, same scene): max |T(t) − T_ref(t)| ≤ band × max T_ref, band 10 % (25 % in the slack and snap
cases). The largest stable Δt is bisected geometrically to 8 % (explicit) / 10 % (implicit); the value shown
is the largest Δt that passed, and the smallest that failed is listed with its reason. Solvers: `houbolt`
(implicit default, Newton on the segment tensions, up to 4 step halvings per step), `generalized_alpha`
(ρ∞ = 0.2, the default) and `newmark` (average acceleration) (implicit one-step schemes on the elastic
model, Newton on the node positions, up to 4 step halvings, no axial damping), `euler`
(semi-implicit), `rk2`, `rk4` (explicit, same model, axial damping ratio {ZETA} ≡ MoorDyn BA = −{2 * ZETA:g}).
`solver.dt` is capped at {DT_CAP:g} s by the scene schema, so "{fmt(DT_CAP)}+" means stable at the cap.
Not mapped: the linearised frequency-domain model (it has no time step), the reduced models (`solver.planar`,
body `dof = "surge_heave_pitch"`: the same Houbolt integrator with fewer unknowns, on the speed/accuracy chart,
docs/speed-accuracy.md) and the thesis's tension recursion "as published" (`solver.tension_solve`, which fails
outright at the thesis's own step guide, tests/unit/test_explicit.py).
""",
         summary(grid, beh, ser, newton),
         "## Map: shared deck (peer deck at 2 m/s, 1 m heave at 8 s, 8 s ramp)\n",
         f"![stability map]({rel}/stability_map.png)\n",
         f"![against CFL]({rel}/stability_cfl.png)\n",
         "| EA | segments | l/c_L | " + " | ".join(SOLVERS) + " |", "|---|---|---|" + "---|" * len(SOLVERS)]
    for ea in eas:
        for n in segs:
            cells = []
            cfl = None
            for m in SOLVERS:
                r = next(r for r in grid if r["ea"] == ea and r["segments"] == n and r["solver"] == m)
                cfl = r["cfl"]
                if r["lo"] is None:
                    cells.append("none")
                    continue
                c = f"{fmt(r['lo'])}{'+' if r['hi'] is None else ''} ({r['lo'] / r['cfl']:.3g}×)"
                if m == "houbolt":
                    c += f", Co_T {r['co_t']:.2g}"
                elif m in ALPHA and r["hi"] is not None:
                    c += f"; fails {fmt(r['hi'])}"
                cells.append(c)
            o.append(f"| ×{ea:g} | {n} | {fmt(cfl)} | " + " | ".join(cells) + " |")
    o.append("\n(×) = Δt_max / (l/c_L). Co_T = c_T Δt/l with c_T from the reference's peak top tension "
             "(the transverse Courant number that limits a quasi-Newton with frozen tangents, model.md 5.9).\n")
    # explicit ratio summary
    for m in EXPLICIT:
        rat = [r["lo"] / r["cfl"] for r in grid if r["solver"] == m and r["lo"]]
        if rat:
            o.append(f"* **{m}**: Δt_max = {min(rat):.2f}–{max(rat):.2f} × l/c_L over the map.")
    hb = [r for r in grid if r["solver"] == "houbolt"]
    if hb:
        capped = sum(1 for r in hb if r["lo"] and r["hi"] is None)
        rat = [r["lo"] / r["cfl"] for r in hb if r["lo"]]
        o.append(f"* **houbolt**: stable at the {DT_CAP:g} s cap in {capped} of {len(hb)} cells; Δt_max / (l/c_L) = "
                 f"{min(rat):.3g}–{max(rat):.3g}.")
        lim = [r for r in hb if r["hi"] is not None]
        for r in lim:
            o.append(f"  * EA ×{r['ea']:g}, {r['segments']} segments: largest stable {fmt(r['lo'])}, "
                     f"fails at {fmt(r['hi'])}: {r['why'][:160]}")
    o.append("\nSmallest failing step and reason per generalized-α / Newmark / explicit cell:\n")
    o.append("| EA | segments | solver | largest stable | smallest failing | reason |")
    o.append("|---|---|---|---|---|---|")
    for r in grid:
        if r["solver"] in ALPHA + EXPLICIT:
            o.append(f"| ×{r['ea']:g} | {r['segments']} | {r['solver']} | {fmt(r['lo'])} | {fmt(r['hi'])} | "
                     f"{r['why'][:140]} |")
    o.append("\n## Behaviour cases (20 segments)\n")
    o.append("| case | reference (Houbolt 2 ms) | " + " | ".join(SOLVERS) + " | quasi_static (Δt 0.05 s) |")
    o.append("|---|---|" + "---|" * (len(SOLVERS) + 1))
    for b in beh:
        i = b["info"]
        cells = []
        for m in SOLVERS + ("quasi_static",):
            lo, hi, why, _ = b["res"][m]
            if m == "quasi_static":
                cells.append("passes band" if lo else f"fails: {why[:60]}")
                continue
            c = f"{fmt(lo)}{'+' if lo and hi is None else ''}"
            if lo and m != "houbolt":
                c += f" ({lo / b['cfl']:.2g}×)"
            if hi is not None:
                c += f"; fails {fmt(hi)}: {why[:70]}"
            cells.append(c)
        o.append(f"| {b['name']} (band {100 * b['band']:.0f} %) | peak {i['peak']:.0f} N = {i['peak'] / i['static']:.2f}× "
                 f"static; min segment T {i['tmin']:.0f} N; {i['slack']} slack segment-samples | " + " | ".join(cells) + " |")
    o.append("\n## More than three cables in series, solved together (series_multitow, 180° turn)\n")
    o.append("Built with `towenv.peer.decks.series_tow(n)`: the thesis Table 4.2 tow with further 30 m / 3-segment "
             "cables and copies of fish 1 appended. All sub-systems are solved in one Newton iteration.\n")
    o.append("| cables in series | segments | l/c_L | houbolt | houbolt, no step cuts | "
             + " | ".join(ALPHA + EXPLICIT) + " |")
    o.append("|---|---|---|---|---|" + "---|" * len(ALPHA + EXPLICIT))
    for s in ser:
        cells = []
        for m in ("houbolt", "houbolt, no step cuts") + ALPHA + EXPLICIT:
            lo, hi, why, _ = s["res"][m]
            c = f"{fmt(lo)}{'+' if lo and hi is None else ''}"
            if hi is not None:
                c += f"; fails {fmt(hi)}: {why[:60]}"
            cells.append(c)
        o.append(f"| {s['n']} | {s['segments']} | {fmt(s['cfl'])} | " + " | ".join(cells) + " |")
    none = [(s["n"], m, s["res"][m]) for s in ser for m in EXPLICIT if s["res"][m][0] is None]
    if none:
        o.append("\n**No stable Δt** for " + ", ".join(f"{m} with {n} cables" for n, m, _ in none) + ": "
                 + "; ".join(sorted({r[2][:160] for _, _, r in none})) + ". If the failure is a \"strain above "
                 "max_strain\" in the first segment of a tail cable at the same simulated time for every Δt, it "
                 "is not a time-step limit: in the semi-implicit Euler update of `towenv/core/explicit.py` the "
                 "aft-tow-point nodes integrate the previous step's velocity and drift away from their bodies "
                 "(2.4 m behind the depressor after 19.5 s here; RK2/RK4 and Houbolt keep them on the body to "
                 "round-off), so the segment looks 20 % stretched while its tension is 90 N.\n")
    o.append("\n## Where the Newton iteration stops converging (Houbolt)\n")
    o.append("Newton iterations per step (all iterations, those of halved sub-steps included, divided by the "
             "steps taken; in brackets the most in one Newton solve, capped by `max_iterations` = 25), step "
             "halvings taken, and the band check, against Δt; the right-hand columns repeat the run with "
             "`max_step_cuts = 0` (a step whose Newton iteration fails is then a divergence). Co_T = c_T Δt/l "
             "at the reference's peak tension.\n")
    for nw in newton:
        o.append(f"\n**{nw['label']}**\n")
        o.append("| Δt (s) | Co_T | it./step (max) | step cuts | deviation from reference | status | "
                 "no step cuts: it./step (max) | no step cuts: status |")
        o.append("|---|---|---|---|---|---|---|---|")
        rows = nw["rows"]
        for a, b in zip(rows[0::2], rows[1::2]):
            st = "stable" if a["stable"] else a["reason"][:90]
            st0 = "stable" if b["stable"] else b["reason"][:90]
            it0 = f"{b['iters']:.2f} ({b['max_iters']})" if np.isfinite(b["iters"]) else "—"
            cot = f"{a['co_t']:.2g}" if np.isfinite(a["co_t"]) else "—"
            dev = f"{100 * a['dev']:.2g} %" if np.isfinite(a["dev"]) else "—"
            o.append(f"| {a['dt']:g} | {cot} | {a['iters']:.2f} ({a['max_iters']}) | {a['cuts']} | "
                     f"{dev} | {st} | {it0} | {st0} |")
    doc.parent.mkdir(parents=True, exist_ok=True)
    doc.write_text("\n".join(o) + "\n")


def _public_args(argv):
    """The command line as a reader would re-run it: without the --save/--load/--json bookkeeping."""
    out, skip = [], False
    for a in argv:
        if skip:
            skip = False
            continue
        if a in ("--save", "--load", "--json"):
            skip = True
            continue
        out.append(a)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--doc", type=Path)
    ap.add_argument("--figdir", type=Path)
    ap.add_argument("--save", type=Path, help="pickle the results (to re-draw with --load)")
    ap.add_argument("--load", type=Path, help="re-draw the figures and the document from --save output")
    args = ap.parse_args(argv)
    if args.quick:
        doc = args.doc or Path(tempfile.gettempdir()) / "towenv_stability_quick" / "stability.md"
        figdir = args.figdir or doc.parent / "figures"
        segs, eas = [10, 20], [1.0]
        dts = [0.01, 0.05, 0.2, 1.0]
        counts = (3, 4)
    else:
        doc = args.doc or ROOT / "docs" / "stability.md"
        figdir = args.figdir or ROOT / "docs" / "figures"
        segs, eas = [5, 10, 20, 40, 80], [0.1, 1.0, 10.0]
        dts = [0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0]
        counts = (3, 4, 5)
    N = 16.0
    start_load = "load average %.1f/%.1f/%.1f" % os.getloadavg() if hasattr(os, "getloadavg") else ""
    t0 = time.perf_counter()

    def log(m):
        print(m, flush=True)

    if args.load:
        with open(args.load, "rb") as fh:
            grid, beh, ser, newton, wall, start_load = pickle.load(fh)
    else:
        log("## stability grid")
        grid = stability_grid(segs, eas, N, log, args.quick)
        log("## behaviour cases")
        beh = behaviour_cases(N, log, args.quick)
        log("## series tows")
        ser = series_cases(40.0, log, counts)
        log("## Newton sweep")
        newton = newton_sweep(N, log, dts)
        wall = time.perf_counter() - t0
        if args.save:
            strip = lambda res: {k: (v[0], v[1], v[2], []) for k, v in res.items()}  # noqa: E731
            with open(args.save, "wb") as fh:
                pickle.dump((grid, [dict(b, res=strip(b["res"])) for b in beh],
                             [dict(x, res=strip(x["res"])) for x in ser], newton, wall, start_load), fh)
    plot_map(grid, segs, eas, figdir / "stability_map.png")
    plot_cfl(grid, figdir / "stability_cfl.png")
    write_doc(doc, figdir, grid, segs, eas, beh, ser, newton, N, wall, _public_args(sys.argv[1:] if argv is None else argv),
              args.quick, start_load)
    log(f"wrote {doc} ({wall / 60:.1f} min)")


if __name__ == "__main__":
    main()
