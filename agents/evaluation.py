"""Run trained policies and the baselines on the evaluation sea states with common random numbers.

Every controller runs every episode of the evaluation list — ``env.unwrapped.eval_sea_states()``
(optionally with ``replicates`` extra wave seeds per entry: seed + 100·r) — with the same sea state,
wave seed and environment seed, so paired comparisons (compensation ratios, relative reductions) are
per episode.
"""
from __future__ import annotations

import math
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .baselines import REFERENCE, baseline_names, load_tuned, make_baseline
from .common import env_kind, sea_key, sea_label
from .metrics import bootstrap_mean_ci, default_discard, episode_metrics, paired_reduction_ci, rollout

__all__ = ["Controller", "EvalResult", "eval_episodes", "make_eval_env", "run_evaluation", "GOALS"]

#: physics-relevant keywords that must agree between a policy's environment and the baselines'
_PHYSICS_KEYS = ("scene", "scene_overrides", "control_hz", "dt", "winch_max_speed", "winch_max_acceleration",
                 "winch_travel", "stiffness_floor", "damping_floor", "sim_overrides", "body")


def make_eval_env(env_id: str, env_kwargs: dict | None = None, wrappers=None):
    import gymnasium as gym
    import towenv.envs  # noqa: F401
    from .zoo import apply_wrappers
    env = gym.make(env_id, **dict(env_kwargs or {}))
    return apply_wrappers(env, wrappers) if wrappers else env


@dataclass
class Controller:
    name: str
    policy: Any
    env: Any
    kind: str                       # "trained" | "baseline"
    description: str = ""
    meta: dict = field(default_factory=dict)


def eval_episodes(env, replicates: int = 1, indices=None, seed_offset: int = 0):
    """The evaluation list ``[(group_key, label, sea, seed)]``: the environment's fixed set (entries
    ``indices``, default all), each with ``replicates`` wave seeds (seed + seed_offset, + 100, ...)."""
    ev = env.unwrapped.eval_sea_states()
    codes = getattr(env.unwrapped, "sea_codes", ())
    idx = range(len(ev)) if indices is None else indices
    out = []
    per_code = max(1, len(ev) // max(1, len(codes))) if codes else len(ev)
    for i in idx:
        sea, seed = ev[i]
        code = codes[i // per_code] if codes and i // per_code < len(codes) else None
        for r in range(max(1, replicates)):
            out.append((sea_key(sea), sea_label(sea, code), sea, int(seed) + int(seed_offset) + 100 * r))
    return out


@dataclass
class EvalResult:
    env_id: str
    kind: str
    env_kwargs: dict
    episodes: list                  # [(group, label, sea, seed)]
    controllers: list               # [Controller]
    metrics: dict                   # name -> [per-episode metric dict]
    records: dict                   # name -> {episode index: EpisodeRecord} (the plotted ones)
    reference: str
    discard: float
    wall_seconds: float
    summary: dict = field(default_factory=dict)     # name -> group -> metric -> (mean, lo, hi)
    goals: list = field(default_factory=list)

    @property
    def groups(self):
        return list(OrderedDict.fromkeys(g for g, *_ in self.episodes))

    def group_label(self, g):
        for gg, lab, *_ in self.episodes:
            if gg == g:
                return lab
        return g


GOALS = {
    "compensator": "significant fish heave ≥ 15 % below the best fixed passive (k, b) and the skyhook semi-active "
                   "law, pitch not worse, no more end-stop hits — or, where the clairvoyant active bound cannot reach "
                   "15 %, within 80 % of the bound's reduction",
    "winch": "compensation ratio ≥ 0.9 × the clairvoyant reference's (pooled and per sea state), RMS heave ≥ 10 % "
             "below the along-cable feed-forward baseline, pitch σ and pitch-rate exceedance not worse than it; "
             "stretch: CR ≥ 90 %",
}

def run_evaluation(env_id: str, trained: list[tuple[str, Any, dict]], baselines: list[str] | None = None,
                   env_kwargs: dict | None = None, replicates: int = 1, indices=None, discard: float | None = None,
                   keep_records: str = "first", n_boot: int = 2000, tuned: dict | None = None,
                   progress: bool = True, seed_offset: int = 0) -> EvalResult:
    """Evaluate ``trained`` policies ``[(name, SB3Policy-like, meta)]`` and the ``baselines``.

    The baselines run on ``gym.make(env_id, **env_kwargs)``; each trained policy on its own environment
    made from its metadata's keywords and wrappers (with ``env_kwargs`` on top), so that its observation
    layout is the one it was trained with."""
    t0 = time.time()
    env_kwargs = dict(env_kwargs or {})
    base_env = make_eval_env(env_id, env_kwargs)
    kind = env_kind(base_env.unwrapped)
    tuned = load_tuned() if tuned is None else tuned
    names = baseline_names(kind) if baselines is None else list(baselines)
    ref = REFERENCE[kind]
    if ref not in names:
        names.insert(0, ref)
    ctrls: list[Controller] = []
    for name, pol, meta in trained:
        kw = dict(meta.get("env_kwargs") or {})
        kw.update(env_kwargs)
        for k in _PHYSICS_KEYS:
            if kw.get(k) != env_kwargs.get(k):
                raise ValueError(f"{name}: environment keyword {k!r} = {kw.get(k)!r} differs from the "
                                 f"evaluation's ({env_kwargs.get(k)!r}); pass it with --env-kwargs")
        penv = make_eval_env(env_id, kw, meta.get("env_wrapper"))
        if hasattr(pol, "bind_env"):        # a policy that reads the sea-state estimate (agents.ars.ARSPolicy)
            pol.bind_env(penv)
        desc = f"{meta.get('algo', '?').upper()} policy"
        if meta.get("algo") == "ars":
            fs = meta.get("feature_set", "v1")
            more = ("" if fs == "v1" else " and the winch speed, last action, top tension, cable angle, fish pitch "
                    "and pitch rate")
            desc += (f", linear residual on `along_cable` over the MRU along-cable history{more} (feature set {fs}, "
                     f"{meta.get('iterations', '?')} ARS iterations, training seed {meta.get('seed', '?')})")
        elif meta.get("algo") == "ars_skyhook":
            desc = ("ARS policy, linear residual on `skyhook` over the tow-point heave history and stroke features "
                    f"({meta.get('iterations', '?')} ARS iterations, training seed {meta.get('seed', '?')})")
        for w in meta.get("env_wrapper") or []:
            if isinstance(w, dict):
                for wn, wkw in w.items():
                    if wn.endswith("ResidualAction"):
                        wkw = dict(wkw or {})
                        base = wkw.pop("base", "?")
                        desc += (f", residual on `{base}` (" + ", ".join(f"{k}={v}" for k, v in wkw.items()) + ")")
                    else:
                        desc += f", wrapper {wn}"
        ctrls.append(Controller(name, pol, penv, "trained", desc, meta))
    for n in names:
        b = make_baseline(n, base_env, tuned)
        ctrls.append(Controller(n, b, base_env, "baseline", b.describe()))
    episodes = eval_episodes(base_env, replicates, indices, seed_offset)
    u = base_env.unwrapped
    discard = default_discard(u.episode_seconds) if discard is None else float(discard)
    metrics: dict[str, list] = {c.name: [] for c in ctrls}
    records: dict[str, dict] = {c.name: {} for c in ctrls}
    first_of_group = {}
    for i, (g, *_rest) in enumerate(episodes):
        first_of_group.setdefault(g, i)
    keep = set(first_of_group.values()) if keep_records == "first" else set(range(len(episodes)))
    for c in ctrls:
        tc = time.time()
        for i, (g, lab, sea, seed) in enumerate(episodes):
            rec = rollout(c.env, c.policy, sea, seed)
            metrics[c.name].append(episode_metrics(rec, discard))
            if i in keep:
                records[c.name][i] = rec
        if progress:
            sh = np.mean([m["sig_heave"] for m in metrics[c.name]])
            print(f"[evaluate] {c.name:>18s}: {len(episodes)} episodes, mean significant heave {sh:.3f} m "
                  f"({time.time() - tc:.0f} s)", flush=True)
    # compensation ratios against the reference (same episode)
    for c in ctrls:
        for m, r in zip(metrics[c.name], metrics[ref]):
            m["cr_heave"] = 1.0 - m["rms_heave"] / max(r["rms_heave"], 1e-12)
            m["cr_heave_sp"] = 1.0 - m["rms_heave_sp"] / max(r["rms_heave_sp"], 1e-12)
            m["cr_pitch"] = 1.0 - m["rms_pitch_deg"] / max(r["rms_pitch_deg"], 1e-12)
    res = EvalResult(env_id, kind, env_kwargs, episodes, ctrls, metrics, records, ref, discard, 0.0)
    res.summary = summarize(res, n_boot)
    res.goals = assess_goals(res, n_boot)
    for c in ctrls:
        if c.env is not base_env:
            c.env.close()
    res.wall_seconds = time.time() - t0
    return res


def summarize(res: EvalResult, n_boot: int = 2000) -> dict:
    out = {}
    for c in res.controllers:
        ms = res.metrics[c.name]
        per = {}
        for g in res.groups + ["all"]:
            idx = [i for i, e in enumerate(res.episodes) if g == "all" or e[0] == g]
            per[g] = {k: bootstrap_mean_ci([ms[i][k] for i in idx], n_boot) for k in ms[0]}
        out[c.name] = per
    return out


def _paired(res, name, ref, key, idx, n_boot):
    a = [res.metrics[name][i][key] for i in idx]
    b = [res.metrics[ref][i][key] for i in idx]
    return paired_reduction_ci(a, b, n_boot)


def _ratio_ci(res, name, ref, key, idx, n_boot, seed=0):
    """mean(x)/mean(x_ref) over paired episodes ``idx`` with a paired percentile bootstrap CI."""
    a = np.array([res.metrics[name][i][key] for i in idx], float)
    b = np.array([res.metrics[ref][i][key] for i in idx], float)
    ok = np.isfinite(a) & np.isfinite(b)
    a, b = a[ok], b[ok]
    if a.size == 0 or b.mean() == 0:
        return math.nan, math.nan, math.nan
    val = float(a.mean() / b.mean())
    if a.size == 1:
        return val, val, val
    rng = np.random.default_rng(seed)
    ix = rng.integers(0, a.size, (n_boot, a.size))
    r = a[ix].mean(axis=1) / b[ix].mean(axis=1)
    return val, float(np.quantile(r, 0.025)), float(np.quantile(r, 0.975))


def _groups_idx(res):
    return {g: [i for i, e in enumerate(res.episodes) if e[0] == g] for g in res.groups}


def assess_goals(res: EvalResult, n_boot: int = 2000) -> list[dict]:
    """Issue 14's goals for every trained policy (pooled over the evaluation set, and per sea state), plus the
    check that the clairvoyant reference beats every causal controller (a reference a causal controller beats
    is not a reference)."""
    from .baselines import CLAIRVOYANT, STRONGEST
    goals = []
    all_idx = list(range(len(res.episodes)))
    gidx = _groups_idx(res)
    strongest, clair = STRONGEST[res.kind], CLAIRVOYANT[res.kind]
    have = set(res.metrics)
    for c in res.controllers:
        if c.kind != "trained":
            continue
        if res.kind == "compensator":
            for base in ("best_passive", "skyhook"):
                if base not in have:
                    continue
                red = _paired(res, c.name, base, "sig_heave", all_idx, n_boot)
                per = {g: _paired(res, c.name, base, "sig_heave", ix, n_boot) for g, ix in gidx.items()}
                goals.append({"policy": c.name, "criterion": f"significant heave reduction vs {base} ≥ 15 %",
                              "value": red, "target": 0.15, "met": red[0] >= 0.15, "per_group": per})
            if "best_passive" in have:
                pitch = _paired(res, c.name, "best_passive", "sig_pitch_deg", all_idx, n_boot)
                per_pitch = {g: _paired(res, c.name, "best_passive", "sig_pitch_deg", ix, n_boot)
                             for g, ix in gidx.items()}
                goals.append({"policy": c.name, "criterion": "significant pitch not worse than best_passive "
                                                             "(reduction ≥ 0)",
                              "value": pitch, "target": 0.0, "met": pitch[0] >= 0.0, "per_group": per_pitch})
                hits = sum(m.get("end_stop_hits", 0.0) for m in res.metrics[c.name])
                hits_bp = sum(m.get("end_stop_hits", 0.0) for m in res.metrics["best_passive"])
                goals.append({"policy": c.name, "criterion": "end-stop hits not more than best_passive's",
                              "value": (hits, hits, hits), "target": hits_bp, "met": hits <= hits_bp,
                              "per_group": {}, "count": True})
                if clair in have:
                    bound = _paired(res, clair, "best_passive", "sig_heave", all_idx, n_boot)
                    red = _paired(res, c.name, "best_passive", "sig_heave", all_idx, n_boot)
                    frac = red[0] / bound[0] if bound[0] > 0 else math.nan
                    goals.append({"policy": c.name, "criterion": f"within 80 % of the clairvoyant active bound's "
                                                                 f"reduction vs best_passive ({100 * bound[0]:.1f} %)",
                                  "value": (frac, frac, frac), "target": 0.8,
                                  "met": bool(math.isfinite(frac) and frac >= 0.8), "per_group": {}, "ratio": True,
                                  "bound": bound, "bound_below_goal": bound[0] < 0.15})
        else:
            if clair in have:
                r = _ratio_ci(res, c.name, clair, "cr_heave", all_idx, n_boot)
                per = {g: _ratio_ci(res, c.name, clair, "cr_heave", ix, n_boot) for g, ix in gidx.items()}
                met = r[0] >= 0.9 and all(v[0] >= 0.9 for v in per.values())
                goals.append({"policy": c.name, "criterion": "CR ≥ 0.9 × the clairvoyant reference's CR (pooled and "
                                                             "every sea state)",
                              "value": r, "target": 0.9, "met": met, "per_group": per, "ratio": True})
            if strongest in have:
                red = _paired(res, c.name, strongest, "rms_heave", all_idx, n_boot)
                per = {g: _paired(res, c.name, strongest, "rms_heave", ix, n_boot) for g, ix in gidx.items()}
                goals.append({"policy": c.name, "criterion": f"RMS heave reduction vs {strongest} ≥ 10 %",
                              "value": red, "target": 0.10, "met": red[0] >= 0.10, "per_group": per})
                pitch = _paired(res, c.name, strongest, "rms_pitch_deg", all_idx, n_boot)
                per_p = {g: _paired(res, c.name, strongest, "rms_pitch_deg", ix, n_boot) for g, ix in gidx.items()}
                goals.append({"policy": c.name, "criterion": f"pitch σ not worse than {strongest} (reduction ≥ 0)",
                              "value": pitch, "target": 0.0, "met": pitch[0] >= 0.0, "per_group": per_p})
                fo = float(np.mean([m["frac_pitch_rate_over"] for m in res.metrics[c.name]]))
                fb = float(np.mean([m["frac_pitch_rate_over"] for m in res.metrics[strongest]]))
                goals.append({"policy": c.name, "criterion": f"pitch-rate exceedance (fraction of time over 6.28 °/s) "
                                                             f"not above {strongest}'s ({100 * fb:.1f} %)",
                              "value": (fo, fo, fo), "target": fb, "met": fo <= fb + 1e-12, "per_group": {},
                              "fraction": True})
            cr = bootstrap_mean_ci([m["cr_heave"] for m in res.metrics[c.name]], n_boot)
            per_cr = {g: bootstrap_mean_ci([res.metrics[c.name][i]["cr_heave"] for i in ix], n_boot)
                      for g, ix in gidx.items()}
            goals.append({"policy": c.name, "criterion": "stretch: heave compensation ratio CR = 1 − σ/σ_fixed ≥ 90 %",
                          "value": cr, "target": 0.90, "met": cr[0] >= 0.90, "per_group": per_cr})
    if clair in have:
        for c in res.controllers:
            if c.name in (clair, REFERENCE[res.kind]):
                continue
            key = "rms_heave"
            worse = [g for g, ix in gidx.items()
                     if np.mean([res.metrics[clair][i][key] for i in ix]) > np.mean([res.metrics[c.name][i][key]
                                                                                     for i in ix])]
            red = _paired(res, clair, c.name, key, all_idx, n_boot)
            goals.append({"policy": clair, "criterion": f"reference check: lower RMS heave than {c.name} "
                                                        f"(pooled and every sea state)",
                          "value": red, "target": 0.0, "met": red[0] > 0 and not worse, "per_group": {},
                          "reference_check": True})
    return goals
