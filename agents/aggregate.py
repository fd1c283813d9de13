"""Aggregation across training seeds, as ``rliable`` does it (Agarwal et al., NeurIPS 2021).

Scores are a matrix ``(n_runs, n_tasks)``: one row per training seed (run), one column per task — here
an evaluation episode (same sea state, wave seed and environment seed for every run).

* :func:`iqm` — interquartile mean over all runs × tasks: ``scipy.stats.trim_mean(x, 0.25)`` on the
  flattened scores (rliable's ``metrics.aggregate_iqm``); it trims the lowest and highest 25 % of
  *all* scores, so with episodes of very different sea states it is a statistic of the pooled
  distribution (dominated by the middle episodes), not the pooled mean;
* :func:`mean` — mean of the per-task means (rliable's ``aggregate_mean``); :func:`median` — median of the
  per-task means over runs (rliable's ``aggregate_median``);
* :func:`stratified_bootstrap_ci` — percentile CI from the stratified bootstrap (rliable's
  ``StratifiedBootstrap`` without task bootstrap): every resample draws ``n_runs`` runs with replacement
  **independently within each task**; tasks are kept. The CI therefore measures the spread over training
  seeds on this fixed set of episodes. ``rliable`` is used when it imports (it needs ``arch``, which
  must match the installed pandas), otherwise an equivalent numpy implementation.
"""
from __future__ import annotations

import functools
import math
import re as _re
from typing import Callable

import numpy as np
from scipy import stats as _stats

__all__ = ["iqm", "mean", "median", "STATS", "stratified_bootstrap_ci", "aggregate_policies", "rliable_available",
           "seed_groups", "across_seeds", "GOAL_BASELINE"]


def iqm(x) -> float:
    """Interquartile mean of all entries of ``x`` (25 % trimmed mean, rliable's definition)."""
    return float(_stats.trim_mean(np.asarray(x, float), proportiontocut=0.25, axis=None))


def mean(x) -> float:
    """Mean over tasks of the per-task mean over runs (for a full matrix: the plain mean)."""
    a = np.asarray(x, float)
    return float(np.mean(np.mean(a, axis=0))) if a.ndim == 2 else float(np.mean(a))


def median(x) -> float:
    """Median over tasks of the per-task mean over runs (rliable's ``aggregate_median``)."""
    a = np.asarray(x, float)
    return float(np.median(np.mean(a, axis=0))) if a.ndim == 2 else float(np.median(a))


STATS: dict[str, Callable] = {"iqm": iqm, "mean": mean, "median": median}

#: the same statistics over a stack of resamples (n, n_runs, n_tasks) -> (n,)
_VECTORISED = {
    iqm: lambda r: _stats.trim_mean(r.reshape(r.shape[0], -1), proportiontocut=0.25, axis=1),
    mean: lambda r: r.mean(axis=1).mean(axis=1),
    median: lambda r: np.median(r.mean(axis=1), axis=1),
}


@functools.lru_cache(maxsize=1)
def _rliable():
    """``(library, metrics)`` of rliable, or None when it does not import or does not run: rliable 1.2
    needs ``arch`` < 8 (arch 8 dropped the ``random_state`` keyword it passes), and arch 7 does not import
    under pandas 3 — so a tiny bootstrap is run once to make sure."""
    try:
        from rliable import library as rly, metrics as rmetrics
        state = np.random.get_state()
        try:
            rly.get_interval_estimates({"x": np.arange(6.0).reshape(2, 3)},
                                       lambda s: np.array([rmetrics.aggregate_iqm(s)]), reps=4)
        finally:
            np.random.set_state(state)
    except Exception:       # ImportError, or arch's TypeError under a newer pandas / newer arch
        return None
    return rly, rmetrics


def rliable_available() -> bool:
    return _rliable() is not None


def _as_matrix(scores) -> np.ndarray:
    a = np.asarray(scores, float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.size == 0:
        raise ValueError(f"scores must be a non-empty (n_runs, n_tasks) array, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("scores contain NaN or inf")
    return a


def _resolve(stat) -> Callable:
    if isinstance(stat, str):
        try:
            return STATS[stat]
        except KeyError:
            raise ValueError(f"unknown statistic {stat!r} (one of {', '.join(STATS)})") from None
    return stat


def stratified_bootstrap_ci(scores, stat="iqm", reps: int = 2000, level: float = 0.95, seed: int = 0,
                            backend: str = "auto") -> tuple[float, float, float]:
    """``(point, lo, hi)``: ``stat(scores)`` and its percentile CI under the stratified bootstrap.

    ``scores`` is ``(n_runs, n_tasks)``; each of ``reps`` resamples draws, for every task separately,
    ``n_runs`` runs with replacement. ``stat`` is a callable on a ``(n_runs, n_tasks)`` matrix returning a
    scalar, or one of ``"iqm"``, ``"mean"``, ``"median"``. ``backend``: ``"rliable"`` (error if it does not
    import), ``"numpy"``, or ``"auto"`` (rliable when it imports). rliable draws from numpy's global
    generator, which is seeded with ``seed`` for the call and restored afterwards. With one run the CI
    collapses to the point estimate."""
    a = _as_matrix(scores)
    fn = _resolve(stat)
    if not (0.0 < level < 1.0):
        raise ValueError(f"level must be in (0, 1), got {level}")
    point = float(fn(a))
    if a.shape[0] == 1:
        return point, point, point
    lib = None
    if backend in ("auto", "rliable"):
        lib = _rliable()
        if lib is None and backend == "rliable":
            raise ImportError("rliable does not import (not installed, or its arch dependency is broken)")
    elif backend != "numpy":
        raise ValueError(f"unknown backend {backend!r}")
    if lib is not None:
        rly, _ = lib
        state = np.random.get_state()
        np.random.seed(seed)
        try:
            pe, ie = rly.get_interval_estimates({"x": a}, lambda s: np.array([fn(s)]), method="percentile",
                                                reps=int(reps), confidence_interval_size=level)
        finally:
            np.random.set_state(state)
        return float(np.ravel(pe["x"])[0]), float(ie["x"][0, 0]), float(ie["x"][1, 0])
    n_runs, n_tasks = a.shape
    rng = np.random.default_rng(seed)
    cols = np.arange(n_tasks)[None, None, :]
    boot = np.empty(int(reps))
    vec = _VECTORISED.get(fn)
    chunk = max(1, min(int(reps), 2_000_000 // a.size))
    for b0 in range(0, int(reps), chunk):
        n = min(chunk, int(reps) - b0)
        res = a[rng.integers(0, n_runs, (n, n_runs, n_tasks)), cols]        # (n, n_runs, n_tasks)
        boot[b0:b0 + n] = vec(res) if vec is not None else [fn(r) for r in res]
    q = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(boot, [q, 100.0 - q])
    return point, float(lo), float(hi)


def aggregate_policies(per_policy_scores: dict, reps: int = 2000, level: float = 0.95, seed: int = 0,
                       backend: str = "auto") -> dict:
    """For every ``name -> (n_runs, n_tasks)`` score matrix: ``{"iqm", "mean", "median"}`` as
    ``(point, lo, hi)`` with stratified-bootstrap CIs, plus ``n_runs``, ``n_tasks`` and ``backend``."""
    out = {}
    lib = "rliable" if (backend in ("auto", "rliable") and rliable_available()) else "numpy"
    for name, scores in per_policy_scores.items():
        a = _as_matrix(scores)
        d = {k: stratified_bootstrap_ci(a, k, reps=reps, level=level, seed=seed, backend=backend) for k in STATS}
        d.update(n_runs=int(a.shape[0]), n_tasks=int(a.shape[1]), backend=lib)
        out[name] = d
    return out



# ------------------------------------------------------------------------------ seed groups of a report
#: a policy name ``<family>_s<k>`` or ``<family>_seed<k>``: training seed k of the recipe ``<family>``
SEED_SUFFIX = _re.compile(r"^(?P<family>.+?)_(?:s|seed)(?P<seed>\d+)$")

#: the baseline a policy's paired reduction is taken against (the goals' comparison baseline)
GOAL_BASELINE = {"winch": "along_cable", "compensator": "best_passive"}

#: metrics of the "Across training seeds" section: key -> (label, percent?, digits)
SEED_METRICS = {"rms_heave": ("RMS fish heave σ (m)", False, 3),
                "cr_heave": ("heave compensation ratio CR", True, 3),
                "sig_pitch_deg": ("significant fish pitch (deg)", False, 2)}


def seed_groups(names) -> dict[str, list[tuple[str, int]]]:
    """``{family: [(name, seed), ...]}`` for the names ending in ``_s<k>`` / ``_seed<k>`` (sorted by seed).
    Every family is returned, also with one member; a name without the suffix belongs to no group."""
    out: dict[str, list[tuple[str, int]]] = {}
    for n in names:
        m = SEED_SUFFIX.match(n)
        if m:
            out.setdefault(m.group("family"), []).append((n, int(m.group("seed"))))
    return {f: sorted(v, key=lambda t: t[1]) for f, v in out.items()}


def across_seeds(res, members: list[tuple[str, int]], family: str, reps: int = 2000, level: float = 0.95,
                 seed: int = 0, backend: str = "auto") -> dict:
    """Seed-group summary of an :class:`agents.evaluation.EvalResult`: runs = the ``members`` (training
    seeds), tasks = the evaluation episodes. IQM / mean / median with stratified-bootstrap CIs of the
    per-episode RMS heave, compensation ratio, significant pitch and the paired reduction
    ``1 − rms_heave/rms_heave_base`` against :data:`GOAL_BASELINE` (same episode), and per seed the
    pooled means (the reduction pooled as ``1 − mean(x)/mean(x_base)``, as the goals do)."""
    names = [n for n, _ in members]
    base = GOAL_BASELINE.get(res.kind)
    if base not in res.metrics:
        base = res.reference
    keys = list(SEED_METRICS)
    red_key = f"reduction_vs_{base}"
    mats = {k: np.array([[m[k] for m in res.metrics[n]] for n in names], float) for k in keys}
    b = np.array([m["rms_heave"] for m in res.metrics[base]], float)
    x = mats["rms_heave"]
    mats[red_key] = 1.0 - x / np.maximum(b, 1e-12)[None, :]
    ok = np.all(np.isfinite(np.stack(list(mats.values()))), axis=(0, 1)) & np.isfinite(b)
    labels = {k: SEED_METRICS[k][0] for k in keys}
    labels[red_key] = f"RMS heave reduction vs `{base}` (paired)"
    pct = {k: SEED_METRICS[k][1] for k in keys} | {red_key: True}
    digits = {k: SEED_METRICS[k][2] for k in keys} | {red_key: 3}
    lib = "rliable" if (backend in ("auto", "rliable") and rliable_available()) else "numpy"
    metrics = {}
    for k, a in mats.items():
        a = a[:, ok]
        d = {st: (stratified_bootstrap_ci(a, st, reps=reps, level=level, seed=seed, backend=backend) if a.size
                  else (math.nan,) * 3) for st in STATS}
        metrics[k] = d | {"label": labels[k], "pct": pct[k], "digits": digits[k]}
    per_seed = {}
    for i, n in enumerate(names):
        row = {k: float(np.mean(mats[k][i, ok])) if ok.any() else math.nan for k in keys}
        row[red_key] = float(1.0 - np.mean(x[i, ok]) / np.mean(b[ok])) if ok.any() else math.nan
        per_seed[n] = row
    return {"family": family, "members": [(n, int(s)) for n, s in members], "n_seeds": len(members),
            "n_tasks": int(ok.sum()), "reps": int(reps), "level": level, "backend": lib, "baseline": base,
            "metrics": metrics, "metric_labels": labels, "per_seed": per_seed,
            "dropped_episodes": [int(i) for i in np.flatnonzero(~ok)]}
