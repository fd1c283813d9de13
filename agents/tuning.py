"""Tune the gain-scheduled baselines per sea state and write ``agents/hyperparams/baselines.yml``.

    python -m agents.tuning                      # everything (~15-30 min on one core)
    python -m agents.tuning --only passive hover  # a subset (the other tables are kept)

Tuning seas: the evaluation set's (Hs, Tp, heading) presets with wave seeds **+ 500** (the evaluation
seeds themselves are never used for tuning; training validation uses + 700). Per sea state (the four
headings of one (Hs, Tp)):

* ``best_passive``: grid over stiffness × damping (+ "locked"), then a pattern search around the best;
  objective = mean significant fish heave, constraint = no end-stop hit and no termination in any of
  the tuning episodes;
* ``hover``: :func:`agents.hover.hover_design` (linear model, design seed = tuning seed + 400);
* ``pd_ff``: coordinate search over (g_ff, g_acc, kp, kd, kl); objective = mean σ(fish heave),
  constraint = the winch never at its travel limit, no termination;
* ``constant_tension``: grid over the gain; same objective and constraint;
* ``along_cable``: coordinate search over (g_ff, τ, k_l, k_p, k_d) of :class:`agents.classical.AlongCableWinch`;
  objective = mean σ(fish heave), constraint = never at the travel limit, no termination;
* ``skyhook``: coordinate search over (c_sky, margin, k_stop) of :class:`agents.classical.SkyhookCompensator`;
  objective = mean significant fish heave, constraint = no end-stop hit, no termination.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import math
import os
import sys
import time
from collections import OrderedDict
from pathlib import Path

import numpy as np

from .baselines import (DEFAULT_PD_GAINS, TUNED_PATH, ConstantTensionWinch, FixedPassive, LockedCompensator,
                        PDFeedForwardWinch, load_tuned)
from .common import COMPENSATOR_ID, WINCH_ID, sea_key, sea_label
from .metrics import episode_metrics, rollout, default_discard

__all__ = ["tuning_seas", "group_by_sea", "evaluate_config", "tune_passive", "tune_pd", "tune_ct", "tune_hover",
           "main"]

TUNING_SEED_OFFSET = 500


def _make(env_id, **kw):
    import gymnasium as gym
    import towenv.envs  # noqa: F401
    return gym.make(env_id, **kw)


def tuning_seas(env, offset: int = TUNING_SEED_OFFSET):
    return [(s, seed + offset) for s, seed in env.unwrapped.eval_sea_states()]


def group_by_sea(seas):
    g: "OrderedDict[str, list]" = OrderedDict()
    for s, seed in seas:
        g.setdefault(sea_key(s), []).append((s, seed))
    return g


def evaluate_config(env, policy, seas, discard=None) -> dict:
    """Mean metrics of ``policy`` over ``seas`` plus the constraint summary."""
    u = env.unwrapped
    discard = default_discard(u.episode_seconds) if discard is None else discard
    ms = [episode_metrics(rollout(env, policy, s, seed), discard) for s, seed in seas]
    out = {k: float(np.mean([m[k] for m in ms])) for k in ms[0]}
    out["any_terminated"] = any(m["terminated"] or m["failure"] for m in ms)
    out["total_hits"] = float(sum(m.get("end_stop_hits", 0.0) for m in ms))
    out["max_winch_limit"] = float(max(m.get("winch_frac_at_limit", 0.0) for m in ms))
    return out


def _log(msg):
    print(msg, flush=True)


# ----------------------------------------------------------------------------------- passive
def tune_passive(env, groups, k_grid=None, b_grid=None, refine_rounds: int = 2, coarse_episodes: int = 2):
    u = env.unwrapped
    c = u.sim.scene.compensator
    klo, khi = u.stiffness_range[0], u.stiffness_range[1]
    blo, bhi = u.damping_range[0], u.damping_range[1]
    k_grid = list(k_grid or [klo, 3000.0, 10000.0, 30000.0, khi])
    b_grid = list(b_grid or [blo, 300.0, 1500.0, 5000.0, 15000.0, bhi])
    table = {}
    for key, seas in groups.items():
        t0 = time.time()
        cache = {}

        def score(k, b, n=None):
            kk = None if k is None else float(min(max(k, klo), khi))
            bb = None if b is None else float(min(max(b, blo), bhi))
            ck = (("locked",) if k is None else (round(kk, 3), round(bb, 3))) + (n,)
            if ck not in cache:
                pol = LockedCompensator(env) if k is None else FixedPassive(env, kk, bb)
                r = evaluate_config(env, pol, seas[:n] if n else seas)
                feasible = (r["total_hits"] == 0) and not r["any_terminated"]
                cache[ck] = (r["sig_heave"] if feasible else math.inf, r, kk, bb)
            return cache[ck]

        # coarse grid on the first `coarse_episodes` tuning episodes, then a pattern search on all of them
        coarse = score(None, None, coarse_episodes)
        for k in k_grid:
            for b in b_grid:
                s = score(k, b, coarse_episodes)
                if s[0] < coarse[0]:
                    coarse = s
        locked = score(None, None)
        best = locked
        if coarse[2] is not None:
            s = score(coarse[2], coarse[3])
            best = s if s[0] < best[0] else best
            if not math.isfinite(s[0]):      # infeasible on the other seeds: more damping
                for fb in (1.5, 2.25, 3.4, 5.0, 7.6):
                    s = score(coarse[2], coarse[3] * fb)
                    if math.isfinite(s[0]):
                        best = s if s[0] < best[0] else best
                        break
        # pattern search around the best passive point
        if best is not locked:
            step = 1.6
            for _ in range(refine_rounds):
                improved = True
                while improved:
                    improved = False
                    _, _, k0, b0 = best
                    for fk, fb in ((1, step), (1, 1 / step), (step, 1), (1 / step, 1), (step, step),
                                   (1 / step, 1 / step)):
                        s = score(k0 * fk, b0 * fb)
                        if s[0] < best[0] - 1e-6:
                            best, improved = s, True
                step = math.sqrt(step)
        sig, r, k, b = best
        if best is locked or not math.isfinite(sig):
            entry = {"mode": "locked"}
        else:
            entry = {"mode": "passive", "stiffness": round(k, 1), "damping": round(b, 1)}
        entry.update({"label": sea_label(seas[0][0]), "tuning_sig_heave": round(r["sig_heave"], 4),
                      "tuning_sig_pitch_deg": round(r["sig_pitch_deg"], 4),
                      "tuning_stroke_max_frac": round(r.get("stroke_max_frac", 0.0), 3),
                      "locked_sig_heave": round(locked[1]["sig_heave"], 4), "evaluations": len(cache)})
        table[key] = entry
        _log(f"[tuning] best_passive {key}: {entry} ({time.time() - t0:.0f} s)")
    return table


def tune_hover(env, groups, design_offset: int = 400):
    table = {}
    from .hover import hover_design
    scene = env.unwrapped.sim.scene
    for key, seas in groups.items():
        sea, seed = seas[0]
        d = hover_design(scene, sea, seed + design_offset)
        entry = {"mode": d["mode"], "label": sea_label(sea), "k_crit": round(d["k_crit"], 1),
                 "H_deck": round(d["H_deck"], 3), "omega0": round(d["omega0"], 4), "R_max": round(d["R_max"], 4),
                 "design_seed": d["design_seed"], "model": d["model"]}
        if d["mode"] == "passive":
            entry.update(stiffness=round(d["stiffness"], 1), damping=round(d["damping"], 1),
                         predicted_p1_ratio=round(d["p1_ratio"], 4), predicted_R_ratio=round(d["R_ratio"], 4))
        else:
            entry["reason"] = d.get("reason", "")
        table[key] = entry
        _log(f"[tuning] hover {key}: {entry}")
    return table


# ----------------------------------------------------------------------------------- winch
_PD_STEPS = {"g_ff": ("add", 0.15), "g_acc": ("add", 0.1), "kp": ("mul", 1.6), "kd": ("add", 0.3),
             "kl": ("mul", 2.0)}
_PD_BOUNDS = {"g_ff": (0.0, 1.5), "g_acc": (-0.5, 1.0), "kp": (0.02, 3.0), "kd": (-1.0, 3.0), "kl": (0.002, 0.5)}


def coordinate_search(score, start: dict, steps: dict, bounds: dict, sweeps: int = 2):
    """Coordinate search: for each parameter in turn, step it up and down (``("add", d)`` or ``("mul", f)``)
    while ``score(params)[0]`` improves; halve the steps (square-root the factors) after each sweep.
    ``score`` returns (objective, ...); returns the best score tuple."""
    best = score(dict(start))
    steps = dict(steps)
    for _ in range(sweeps):
        for name in steps:
            how, st = steps[name]
            for direction in (+1, -1):
                while True:
                    g = dict(best[-1])
                    g[name] = g[name] + direction * st if how == "add" else g[name] * st ** direction
                    lo, hi = bounds[name]
                    g[name] = min(max(g[name], lo), hi)
                    s = score(g)
                    if s[0] < best[0] - 1e-6:
                        best = s
                    else:
                        break
        steps = {n: (h, (s / 2.0 if h == "add" else math.sqrt(s))) for n, (h, s) in steps.items()}
    return best


def _tune_winch_law(env, groups, make, defaults, steps, bounds, label, start=None, sweeps=2):
    """Per sea state: coordinate search of a winch law's gains; objective = mean σ(fish heave) over the tuning
    episodes, constraint = never at the travel limit and no termination."""
    table = {}
    for key, seas in groups.items():
        t0 = time.time()
        cache = {}

        def score(g):
            ck = tuple(round(g[n], 4) for n in defaults)
            if ck not in cache:
                r = evaluate_config(env, make(env, g), seas)
                feasible = r["max_winch_limit"] == 0 and not r["any_terminated"]
                cache[ck] = (r["rms_heave"] if feasible else math.inf, r, dict(g))
            return cache[ck]

        rms, r, g = coordinate_search(score, dict(defaults | (start or {})), steps, bounds, sweeps)
        entry = {n: round(float(v), 4) for n, v in g.items()}
        entry.update({"label": sea_label(seas[0][0]), "tuning_rms_heave": round(r["rms_heave"], 4),
                      "tuning_sig_heave": round(r["sig_heave"], 4),
                      "tuning_sig_pitch_deg": round(r["sig_pitch_deg"], 4), "evaluations": len(cache)})
        table[key] = entry
        _log(f"[tuning] {label} {key}: {entry} ({time.time() - t0:.0f} s)")
    return table


def tune_pd(env, groups, start=None, sweeps: int = 2):
    return _tune_winch_law(env, groups, lambda e, g: PDFeedForwardWinch(e, gains=g), DEFAULT_PD_GAINS, _PD_STEPS,
                           _PD_BOUNDS, "pd_ff", start, sweeps)


_ALONG_STEPS = {"g_ff": ("add", 0.15), "tau": ("add", 0.1), "kl": ("mul", 2.0), "kp": ("mul", 1.6), "kd": ("add", 0.2)}
_ALONG_BOUNDS = {"g_ff": (0.0, 1.5), "tau": (0.0, 1.0), "kl": (0.002, 2.0), "kp": (0.01, 5.0), "kd": (-1.0, 3.0)}


#: start points of the along-cable search (the best result over all of them is kept): plain cancellation with
#: weak feedback, and a partial, lead-compensated one (the acceleration-limited winch prefers it in rough seas)
_ALONG_STARTS = ({}, {"g_ff": 0.6, "tau": 0.3, "kl": 0.02, "kp": 0.25, "kd": 0.0})


def tune_along(env, groups, start=None, sweeps: int = 3):
    """Per sea state: coordinate search of the along-cable law from each of :data:`_ALONG_STARTS` (3 sweeps);
    the best over the starts is kept."""
    from .classical import DEFAULT_ALONG_GAINS, AlongCableWinch
    starts = [start] if start else _ALONG_STARTS
    best = {}
    for st in starts:
        tab = _tune_winch_law(env, groups, lambda e, g: AlongCableWinch(e, gains=g), DEFAULT_ALONG_GAINS,
                              _ALONG_STEPS, _ALONG_BOUNDS, "along_cable", st, sweeps)
        for k, e in tab.items():
            if k not in best or e["tuning_rms_heave"] < best[k]["tuning_rms_heave"]:
                best[k] = e
    return best


_SKY_STEPS = {"c_sky": ("add", 1500.0), "b0": ("mul", 1.6), "k0": ("mul", 1.6), "margin": ("add", 0.15),
              "k_stop": ("mul", 2.0)}
_SKY_BOUNDS = {"c_sky": (0.0, 2e5), "b0": (50.0, 5e4), "k0": (1e3, 2e5), "margin": (0.05, 0.9), "k_stop": (1e3, 2e5)}


def tune_skyhook(env, groups, start=None, sweeps: int = 2, passive: dict | None = None):
    """Per sea state: coordinate search of the skyhook gains; objective = mean significant fish heave,
    constraint = no end-stop hit and no termination in any tuning episode (as ``best_passive``). The search
    starts from the best passive setting of the sea state (``passive``: the ``best_passive`` table), i.e. the
    skyhook law with c_sky = 0 and no stiffening, so the tuned law is never worse on the tuning seeds."""
    from .classical import DEFAULT_SKYHOOK_GAINS, SkyhookCompensator
    table = {}
    for key, seas in groups.items():
        st = dict(start or {})
        bp = (passive or {}).get(key)
        if bp and bp.get("mode", "passive") == "passive" and not start:
            st = {"c_sky": 0.0, "b0": float(bp["damping"]), "k0": float(bp["stiffness"]), "margin": 0.05,
                  "k_stop": float(bp["stiffness"])}
        t0 = time.time()
        cache = {}

        def score(g):
            ck = tuple(round(g[n], 4) for n in DEFAULT_SKYHOOK_GAINS)
            if ck not in cache:
                r = evaluate_config(env, SkyhookCompensator(env, gains=g), seas)
                feasible = r["total_hits"] == 0 and not r["any_terminated"]
                cache[ck] = (r["sig_heave"] if feasible else math.inf, r, dict(g))
            return cache[ck]

        sig, r, g = coordinate_search(score, dict(DEFAULT_SKYHOOK_GAINS | st), _SKY_STEPS, _SKY_BOUNDS, sweeps)
        entry = {n: round(float(v), 4) for n, v in g.items()}
        entry.update({"label": sea_label(seas[0][0]), "tuning_sig_heave": round(r["sig_heave"], 4),
                      "tuning_sig_pitch_deg": round(r["sig_pitch_deg"], 4), "feasible": bool(math.isfinite(sig)),
                      "tuning_stroke_max_frac": round(r.get("stroke_max_frac", 0.0), 3), "evaluations": len(cache)})
        table[key] = entry
        _log(f"[tuning] skyhook {key}: {entry} ({time.time() - t0:.0f} s)")
    return table


def tune_ct(env, groups, gains=None):
    gains = list(gains or np.geomspace(1e-5, 1e-3, 7))
    table = {}
    for key, seas in groups.items():
        best = (math.inf, None, None)
        for gain in gains:
            r = evaluate_config(env, ConstantTensionWinch(env, gain=float(gain)), seas)
            feasible = r["max_winch_limit"] == 0 and not r["any_terminated"]
            v = r["rms_heave"] if feasible else math.inf
            if v < best[0] or best[1] is None:
                best = (v, r, float(gain)) if (v < best[0] or best[1] is None) else best
        v, r, gain = best
        entry = {"gain": float(f"{gain:.4g}"), "label": sea_label(seas[0][0]),
                 "tuning_rms_heave": round(r["rms_heave"], 4), "feasible": bool(math.isfinite(v))}
        table[key] = entry
        _log(f"[tuning] constant_tension {key}: {entry}")
    return table


# ----------------------------------------------------------------------------------- CLI
def main(argv=None):
    p = argparse.ArgumentParser(description="Tune the per-sea-state baselines -> agents/hyperparams/baselines.yml")
    p.add_argument("--only", nargs="*", default=["passive", "hover", "skyhook", "pd", "ct", "along"],
                   choices=["passive", "hover", "skyhook", "pd", "ct", "along"])
    p.add_argument("--out", default=str(TUNED_PATH))
    p.add_argument("--episode-seconds", type=float, default=300.0)
    p.add_argument("--codes", nargs="*", type=int, default=None, help="only these WMO codes' sea states")
    args = p.parse_args(argv)
    import yaml
    out = Path(args.out)
    tuned = load_tuned(out) if out.exists() else {}
    kw = {"episode_seconds": args.episode_seconds}
    started = time.time()
    if {"passive", "hover", "skyhook"} & set(args.only):
        env = _make(COMPENSATOR_ID, **kw)
        groups = _filter(group_by_sea(tuning_seas(env)), args.codes, env)
        if "hover" in args.only:
            tuned["hover"] = tuned.get("hover", {}) | tune_hover(env, groups)
        if "passive" in args.only:
            tuned["best_passive"] = tuned.get("best_passive", {}) | tune_passive(env, groups)
            _write(out, tuned)
        if "skyhook" in args.only:
            tuned["skyhook"] = tuned.get("skyhook", {}) | tune_skyhook(env, groups,
                                                                       passive=tuned.get("best_passive"))
        _write(out, tuned)
    if "along" in args.only:
        env = _make(WINCH_ID, **kw)
        groups = _filter(group_by_sea(tuning_seas(env)), args.codes, env)
        tuned["along_cable"] = tuned.get("along_cable", {}) | tune_along(env, groups)
        _write(out, tuned)
    if {"pd", "ct"} & set(args.only):
        env = _make(WINCH_ID, **kw)
        groups = _filter(group_by_sea(tuning_seas(env)), args.codes, env)
        if "ct" in args.only:
            tuned["constant_tension"] = tuned.get("constant_tension", {}) | tune_ct(env, groups)
            _write(out, tuned)
        if "pd" in args.only:
            tuned["pd_ff"] = tuned.get("pd_ff", {}) | tune_pd(env, groups)
        _write(out, tuned)
    tuned.setdefault("_meta", {})
    tuned["_meta"].update({"written": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
                           "tuning_seed_offset": TUNING_SEED_OFFSET, "episode_seconds": args.episode_seconds,
                           "last_run_seconds": round(time.time() - started, 1)})
    _write(out, tuned)
    _log(f"[tuning] wrote {out} ({time.time() - started:.0f} s)")
    return 0


def _filter(groups, codes, env):
    if not codes:
        return groups
    from towenv.sea import SeaState
    keep = {sea_key(SeaState.from_code(c, env.unwrapped.sea_convention)) for c in codes}
    return OrderedDict((k, v) for k, v in groups.items() if k in keep)


def _write(path: Path, tuned: dict):
    import yaml
    path.parent.mkdir(parents=True, exist_ok=True)
    head = ("# Tuned baselines per sea state (key hs<Hs>_tp<Tp>), written by `python -m agents.tuning`.\n"
            "# Tuning seeds = evaluation seeds + 500 (never the evaluation seeds). See agents/tuning.py.\n")
    order = ["_meta", "best_passive", "hover", "skyhook", "pd_ff", "constant_tension", "along_cable"]
    doc = {k: tuned[k] for k in order if k in tuned} | {k: v for k, v in tuned.items() if k not in order}
    path.write_text(head + yaml.safe_dump(doc, sort_keys=False, width=120))


if __name__ == "__main__":
    for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(_v, "1")
    sys.exit(main())
