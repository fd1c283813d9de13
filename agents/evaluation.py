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
from .metrics import bootstrap_mean_ci, default_discard, episode_metrics, metric_columns, paired_reduction_ci, rollout

__all__ = ["Controller", "EvalResult", "eval_episodes", "make_eval_env", "run_evaluation", "GOALS", "read_report_rows",
           "REUSE_REL_TOL", "ReuseError"]

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


#: relative agreement required, per episode, between a controller's RMS heave in this run and in the report whose
#: rows are reused: metrics.csv stores 6 significant digits (rounding error ≤ 5e-6 relative), so 1e-5 passes a
#: re-run of the same physics and refuses any change of the episodes' outcome beyond the file's precision
REUSE_REL_TOL = 1e-5
#: metrics.csv columns that identify an episode (not metrics) or are recomputed (compensation ratios)
_ID_COLUMNS = ("controller", "episode", "sea_state", "heading_deg", "wave_seed")
_RECOMPUTED = ("cr_heave", "cr_heave_sp", "cr_pitch")


class ReuseError(ValueError):
    """Rows of an earlier report cannot be reused here (the message names the baseline and the reason)."""


def read_report_rows(report_dir) -> tuple[dict, dict]:
    """A written report's ``summary.json`` and its per-episode rows: ``(summary, {controller: [(sea_key,
    heading_deg, wave_seed, {metric: value}), ...]})`` in episode order. ValueError naming the folder if it is not
    a complete report."""
    import csv
    import json
    from pathlib import Path
    d = Path(report_dir)
    if not (d / "summary.json").is_file() or not (d / "metrics.csv").is_file():
        raise ReuseError(f"{d}: not a complete report folder (needs summary.json and metrics.csv)")
    try:
        summary = json.loads((d / "summary.json").read_text())
        if not isinstance(summary, dict):
            raise TypeError("summary.json is not a JSON object")
        rows: dict[str, list] = {}
        with open(d / "metrics.csv", newline="") as f:
            for r in csv.DictReader(f):
                m = {k: float(v) for k, v in r.items() if k not in _ID_COLUMNS and k not in _RECOMPUTED}
                rows.setdefault(r["controller"], []).append(
                    (int(r["episode"]), r["sea_state"], float(r["heading_deg"]), int(r["wave_seed"]), m))
    except (ValueError, KeyError, TypeError, AttributeError, OSError) as exc:
        raise ReuseError(f"{d}: unreadable report ({type(exc).__name__}: {exc})") from None
    out = {}
    for n, rs in rows.items():
        rs.sort(key=lambda t: t[0])
        if [t[0] for t in rs] != list(range(len(rs))):
            raise ReuseError(f"{d}: metrics.csv has a gap in {n}'s episodes")
        out[n] = [t[1:] for t in rs]
    return summary, out


#: what a report's controller description says after a baseline's rows were reused (then the report's folder)
REUSED_MARK = " — rows reused from the report "


def reused_origin(description: str) -> tuple[str, str | None]:
    """(the baseline's own description, the report its rows were reused from or None) of a controller description
    in a report: a report that reused a baseline's rows can lend them again, its description compared without the
    reuse note."""
    own, sep, rest = description.partition(REUSED_MARK)
    if not sep:
        return description, None
    return own, rest.split(" (not re-run", 1)[0].split(" (which reused", 1)[0]


def _reused_rows(name: str, report_dir, env_id: str, env_kwargs: dict, description: str, episodes, discard: float):
    """The rows of baseline ``name`` from ``report_dir`` for exactly these ``episodes`` (same sea state, heading
    and wave seed, in order), environment keywords, start-up window and baseline description (its tuned gains
    and settings; a report that reused the rows itself is compared without its reuse note, :func:`reused_origin`);
    :class:`ReuseError` naming what differs. Returns (rows, all rows, the report the rows were first reused from or
    None)."""
    try:
        summary, rows = read_report_rows(report_dir)
    except ReuseError as exc:
        raise ReuseError(f"--reuse {name}: {exc}") from None
    if summary.get("env_id") != env_id:
        raise ReuseError(f"--reuse {name}: {report_dir} is a report of {summary.get('env_id')!r}, not {env_id!r}")
    old_kw = summary.get("env_kwargs") or {}
    if old_kw != _jsonable_kwargs(env_kwargs):
        raise ReuseError(f"--reuse {name}: {report_dir} ran with environment keywords {old_kw}, this run with "
                         f"{_jsonable_kwargs(env_kwargs)}")
    if name not in rows:
        raise ReuseError(f"--reuse {name}: {report_dir} has no rows of {name!r} (it has {', '.join(sorted(rows))})")
    old_desc = ((summary.get("controllers") or {}).get(name) or {}).get("description")
    origin = None
    if isinstance(old_desc, str):
        old_desc, origin = reused_origin(old_desc)
    if old_desc != description:
        raise ReuseError(f"--reuse {name}: its description differs (settings or tuned gains changed): this run "
                         f"{description!r}; {report_dir}: {old_desc!r}")
    try:
        old_discard = float(summary.get("discard"))
    except (TypeError, ValueError):
        old_discard = math.nan
    if not abs(old_discard - float(discard)) <= 1e-9:
        raise ReuseError(f"--reuse {name}: {report_dir} scored after {summary.get('discard')} s, this run after "
                         f"{discard:g} s")
    for n, rs in rows.items():
        if len(rs) != len(episodes):
            raise ReuseError(f"--reuse {name}: {report_dir} has {len(rs)} episodes of {n}, this run {len(episodes)}")
    for i, ((g, _lab, sea, seed), (g0, head0, seed0, _m)) in enumerate(zip(episodes, rows[name])):
        if g != g0 or int(seed) != seed0 or abs(float(sea.heading_deg) - head0) > 1e-9:
            raise ReuseError(f"--reuse {name}: episode {i} differs: this run {g}, heading {sea.heading_deg:g}, wave "
                             f"seed {seed}; {report_dir}: {g0}, heading {head0:g}, wave seed {seed0}")
    return [dict(m) for *_x, m in rows[name]], rows, origin


def _jsonable_kwargs(kw: dict) -> dict:
    import json
    return json.loads(json.dumps(dict(kw or {}), default=str))


def _check_shared(n: str, folder, name: str, mine: list, old: list) -> float:
    """Largest relative RMS-heave difference between a shared baseline's episodes here and in the report whose
    rows of ``n`` are reused; :class:`ReuseError` when one exceeds :data:`REUSE_REL_TOL` (NaN included)."""
    worst = 0.0
    for i, (m, (*_x, m0)) in enumerate(zip(mine, old)):
        a, b = float(m["rms_heave"]), float(m0.get("rms_heave", math.nan))
        d = abs(a - b) / max(abs(a), 1e-12)
        if not d <= REUSE_REL_TOL:
            raise ReuseError(f"--reuse {n}: {name}'s RMS heave in episode {i} is {a:.6g} m here and {b:.6g} m in "
                             f"{folder} (relative difference {d:.1e} > {REUSE_REL_TOL:g}): not the same physics "
                             f"or episodes; re-run {n}")
        worst = max(worst, d)
    return worst


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
    reused: dict = field(default_factory=dict)      # name -> reuse check (agents.evaluation.run_evaluation)

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

def _hinge_thresholds(feature_set: str) -> tuple:
    """The hinge thresholds (m/s²) of a WinchPayout ARS/GN feature set (agents/ars.py HINGES; () if none)."""
    from .ars import HINGES
    return tuple(HINGES.get(feature_set, ()))


def trained_description(meta: dict) -> str:
    """The report's one-line description of a trained policy from its file's metadata (algorithm, method, feature
    set, iterations, start, training seed, residual wrappers)."""
    desc = f"{meta.get('algo', '?').upper()} policy"
    gn = meta.get("method") == "gauss-newton"
    hp = meta.get("hyperparameters") or {}
    start = (f" after {hp['init']}" if gn and hp.get("init") else "")
    if meta.get("algo") == "ars":
        fs = meta.get("feature_set", "v1")
        more = ("" if fs == "v1" else " and the winch speed, last action, top tension, cable angle, fish pitch "
                "and pitch rate") + (" and its own earlier actions and a longer MRU velocity history"
                                     if fs == "v3" else "") + (
            " and the along-cable motion 0.2-2.0 s ahead predicted from 10 s of MRU history (agents/predictor.py)"
            if fs in ("v2q", "v2qa") else "") + (
            " and hinges of its predicted along-cable acceleration beyond "
            + " and ".join(f"{c:.1f}" for c in _hinge_thresholds(fs)) + " m/s²" if _hinge_thresholds(fs) else "")
        if gn:
            desc = "Gauss-Newton policy search (the ARS policy class)"
        desc += (f", linear residual on `along_cable` over the MRU along-cable history{more} (feature set {fs}, "
                 f"{meta.get('iterations', '?')} {'Gauss-Newton' if gn else 'ARS'} iterations{start}, training "
                 f"seed {meta.get('seed', '?')})")
    elif meta.get("algo") == "ars_skyhook" and meta.get("method") == "weight-average":
        members = meta.get("members") or []
        runs = "; ".join(f"{m.get('name', '?')}: {m.get('iterations', '?')} "
                         f"{'Gauss-Newton' if m.get('method') == 'gauss-newton' else 'ARS'} iterations"
                         + (f" after {m['init']}" if m.get("init") else "") + f", training seed {m.get('seed', '?')}"
                         for m in members)
        desc = (f"Mean of the weights of {len(members)} policies of the ARS compensator class (linear residual on "
                f"`skyhook`, feature set {meta.get('feature_set', '?')}; scripts/average_compensator.py; {runs})")
    elif meta.get("algo") == "ars_skyhook" and meta.get("trainer") == "probe_semiactive_imitation":
        desc = ("imitation of clairvoyant semi-active teacher plans (the ARS compensator policy class, ridge "
                f"{meta.get('ridge', '?')}, {len(meta.get('plans') or [])} plans; "
                "scripts/probe_semiactive_imitation.py)")
    elif meta.get("algo") == "ars_skyhook":
        desc = ("Gauss-Newton policy search (the ARS compensator policy class)" if gn else "ARS policy") + (
                ", linear residual on `skyhook` over the tow-point heave history and stroke features"
                + (" and the tow point's vertical motion 0.2-2.0 s ahead predicted from 10 s of MRU history "
                   "(agents/predictor.py)" if meta.get("feature_set") == "hq" else "")
                + (", each with a second weight while skyhook damps" if meta.get("feature_set") in ("hs", "hst")
                   else "")
                + (", and the top tension and along-cable velocity over the last 2 s"
                   if meta.get("feature_set") == "hst" else "")
                + (f" (feature set {meta.get('feature_set')})" if meta.get("feature_set") in ("hs", "hst") else "")
                + f" ({meta.get('iterations', '?')} {'Gauss-Newton' if gn else 'ARS'} iterations{start}, training "
                f"seed {meta.get('seed', '?')})")
    for w in meta.get("env_wrapper") or []:
        if isinstance(w, dict):
            for wn, wkw in w.items():
                if wn.endswith("ResidualAction"):
                    wkw = dict(wkw or {})
                    base = wkw.pop("base", "?")
                    desc += (f", residual on `{base}` (" + ", ".join(f"{k}={v}" for k, v in wkw.items()) + ")")
                else:
                    desc += f", wrapper {wn}"
    return desc


def run_evaluation(env_id: str, trained: list[tuple[str, Any, dict]], baselines: list[str] | None = None,
                   env_kwargs: dict | None = None, replicates: int = 1, indices=None, discard: float | None = None,
                   keep_records: str = "first", n_boot: int = 2000, tuned: dict | None = None,
                   progress: bool = True, seed_offset: int = 0, reuse: dict | None = None) -> EvalResult:
    """Evaluate ``trained`` policies ``[(name, SB3Policy-like, meta)]`` and the ``baselines``.

    ``reuse`` ``{baseline name: report folder}``: that baseline is not run; its per-episode metrics are read from
    the earlier report (``metrics.csv``), which must hold the same episodes, environment keywords, start-up window,
    baseline description and metric columns, and every other *baseline* the two runs share (the reference always
    runs) must agree per episode to :data:`REUSE_REL_TOL` in RMS heave — so the rows belong to the same physics.
    The reference itself cannot be reused. For the clairvoyant winch, whose plans cost ~2 min per episode.

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
        desc = trained_description(meta)
        ctrls.append(Controller(name, pol, penv, "trained", desc, meta))
    reuse = dict(reuse or {})
    unknown = [n for n in reuse if n not in names]
    if unknown:
        raise ReuseError(f"--reuse: {', '.join(unknown)} not among the baselines of this run ({', '.join(names)})")
    if ref in reuse:
        raise ReuseError(f"--reuse: the reference {ref} always runs (the reuse check and the compensation ratios "
                         f"need it)")
    episodes = eval_episodes(base_env, replicates, indices, seed_offset)
    u = base_env.unwrapped
    discard = default_discard(u.episode_seconds) if discard is None else float(discard)
    reused, old_rows = {}, {}
    for n in names:
        b = make_baseline(n, base_env, tuned)
        desc = b.describe()
        if n in reuse:
            reused[n], old_rows[n], origin = _reused_rows(n, reuse[n], env_id, env_kwargs, desc, episodes, discard)
            diff = sorted(set(reused[n][0]) ^ set(metric_columns(kind)))    # before any episode runs
            if diff:
                raise ReuseError(f"--reuse {n}: {reuse[n]}'s metric columns differ from this version's "
                                 f"({', '.join(diff)})")
            desc += (f"{REUSED_MARK}{reuse[n]}" + (f" (which reused them from {origin})" if origin else "")
                     + " (not re-run; see the reuse check)")
        ctrls.append(Controller(n, b, base_env, "baseline", desc))
    checks = {n: {"from": str(reuse[n]), "checked_against": [], "max_rel_diff": 0.0} for n in reused}
    metrics: dict[str, list] = {c.name: [] for c in ctrls}
    records: dict[str, dict] = {c.name: {} for c in ctrls}
    first_of_group = {}
    for i, (g, *_rest) in enumerate(episodes):
        first_of_group.setdefault(g, i)
    keep = set(first_of_group.values()) if keep_records == "first" else set(range(len(episodes)))
    for c in ctrls:
        tc = time.time()
        if c.name in reused:
            metrics[c.name] = reused[c.name]
            if progress:
                print(f"[evaluate] {c.name:>18s}: {len(episodes)} episodes reused from {reuse[c.name]}", flush=True)
            continue
        for i, (g, lab, sea, seed) in enumerate(episodes):
            rec = rollout(c.env, c.policy, sea, seed)
            metrics[c.name].append(episode_metrics(rec, discard))
            if i in keep:
                records[c.name][i] = rec
        for n, rows in old_rows.items():       # the reused rows belong to the same physics: shared baselines agree
            if c.kind == "baseline" and c.name in rows:
                d = _check_shared(n, reuse[n], c.name, metrics[c.name], rows[c.name])
                checks[n]["checked_against"].append(c.name)
                checks[n]["max_rel_diff"] = max(checks[n]["max_rel_diff"], d)
        if progress:
            sh = np.mean([m["sig_heave"] for m in metrics[c.name]])
            print(f"[evaluate] {c.name:>18s}: {len(episodes)} episodes, mean significant heave {sh:.3f} m "
                  f"({time.time() - tc:.0f} s)", flush=True)
    for n, chk in checks.items():
        if not chk["checked_against"]:         # the reference always runs and every report has it: not reached
            raise ReuseError(f"--reuse {n}: {reuse[n]} shares no baseline with this run to check it against")
        if progress:
            print(f"[evaluate] reuse check for {n}: {', '.join(chk['checked_against'])} agree with {reuse[n]} in "
                  f"every episode (RMS heave, largest relative difference {chk['max_rel_diff']:.1e})", flush=True)
    # compensation ratios against the reference (same episode)
    for c in ctrls:
        for m, r in zip(metrics[c.name], metrics[ref]):
            m["cr_heave"] = 1.0 - m["rms_heave"] / max(r["rms_heave"], 1e-12)
            m["cr_heave_sp"] = 1.0 - m["rms_heave_sp"] / max(r["rms_heave_sp"], 1e-12)
            m["cr_pitch"] = 1.0 - m["rms_pitch_deg"] / max(r["rms_pitch_deg"], 1e-12)
    res = EvalResult(env_id, kind, env_kwargs, episodes, ctrls, metrics, records, ref, discard, 0.0)
    res.reused = checks
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
