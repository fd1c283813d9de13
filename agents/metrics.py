"""Rollouts with common random numbers, per-episode metrics and bootstrap confidence intervals.

Definitions (``shared/reference/rl-conventions.md`` §10, written out in ``docs/agents.md``):

* scored window: ``t >= discard`` (default 60 s of a 300 s episode: the 20 s start-up ramp plus the
  transient), capped at half the episode;
* significant amplitude of x = ``2 σ(x)``, σ the standard deviation over the window (about its mean);
* compensation ratio ``CR_x = 1 − σ(x) / σ(x_uncomp)`` with ``x_uncomp`` the *same wave realisation*
  (same sea state and wave seed) with the compensator locked (CompensatorGains) or the winch fixed
  (WinchPayout); the set-point variant ``CR_x,sp`` uses the RMS about the steady-tow value instead of σ;
* rates against thesis Table 6.1: heave 1 m/s, pitch 6.28 °/s (RMS, peak and fraction of time over);
* stroke use: largest |stroke| / half stroke, stroke height (max − min) and its Rayleigh 1/1000-highest
  estimate ``2 × 3.72 σ(stroke)`` against the available travel; end-stop hits over the whole episode;
* tensions: top-tension maximum, minimum and σ; the smallest segment tension of all lines, slack steps.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from .common import env_kind

__all__ = ["EpisodeRecord", "rollout", "episode_metrics", "metric_columns", "bootstrap_mean_ci", "paired_reduction_ci",
           "HEAVE_RATE_LIMIT", "PITCH_RATE_LIMIT_DEG", "default_discard"]

HEAVE_RATE_LIMIT = 1.0            # m/s, thesis Table 6.1
PITCH_RATE_LIMIT_DEG = 6.28       # deg/s, thesis Table 6.1
RAYLEIGH_1_1000 = math.sqrt(2.0 * math.log(1000.0))    # 3.717: amplitude exceeded by 1/1000 of amplitudes


def default_discard(episode_seconds: float) -> float:
    return float(min(60.0, 0.5 * float(episode_seconds)))


@dataclass
class EpisodeRecord:
    """Time series of one episode (one row per control step, after the step)."""
    kind: str
    sea: Any
    sea_seed: int
    dt: float
    data: dict[str, np.ndarray] = field(default_factory=dict)
    ret: float = 0.0
    steps: int = 0
    terminated: bool = False
    failure: str | None = None
    termination: str | None = None
    half_stroke: float | None = None
    winch_travel: float | None = None
    wall_seconds: float = 0.0

    def window(self, discard: float) -> np.ndarray:
        t = self.data["t"]
        w = t >= discard
        if w.sum() < 8:                   # too short an episode: use its second half
            w = t >= 0.5 * t[-1]
        return w


_COLUMNS_COMMON = ("t", "heave", "pitch", "heave_rate", "pitch_rate", "tow_z", "top_tension", "min_tension",
                   "reward")
_COLUMNS = {"compensator": _COLUMNS_COMMON + ("stroke", "stroke_vel", "stiffness", "damping", "hits"),
            "winch": _COLUMNS_COMMON + ("winch_speed", "winch_dev")}


def rollout(env, policy, sea, sea_seed: int, seed: int | None = None, max_steps: int | None = None,
            policy_env=None) -> EpisodeRecord:
    """Run one episode of ``policy`` on ``env`` in ``(sea, sea_seed)`` and record it.

    ``env`` is a (possibly wrapped) towenv environment; ``policy`` has SB3's ``predict``; ``seed`` seeds the
    environment's ``np_random`` (sensor noise) — by default ``sea_seed``, so every controller sees the same
    noise too. ``policy_env`` is unused (kept for symmetry with baselines bound to an env)."""
    import time
    t0 = time.perf_counter()
    u = env.unwrapped
    kind = env_kind(u)
    obs, info = env.reset(seed=int(sea_seed if seed is None else seed),
                          options={"sea_state": sea, "sea_seed": int(sea_seed)})
    sim = u.sim
    body = u.body
    n = int(max_steps or u.max_steps)
    cols = _COLUMNS[kind]
    buf = np.zeros((n, len(cols)))
    state = None
    start = np.ones((1,), dtype=bool)
    ret = 0.0
    hits = 0
    rec = EpisodeRecord(kind, sea, int(sea_seed), float(u.dt))
    if kind == "compensator":
        rec.half_stroke = float(u.half_stroke) if hasattr(u, "half_stroke") else 0.5 * float(sim.scene.compensator.stroke)
        L0 = None
    else:
        rec.winch_travel = float(getattr(u, "winch_travel", 10.0))
        L0 = float(sim.winch_state()["length"])
    i = 0
    for i in range(n):
        action, state = policy.predict(obs, state=state, episode_start=start, deterministic=True)
        start = np.zeros((1,), dtype=bool)
        obs, r, term, trunc, info = env.step(action)
        sim = u.sim                               # the winch may rebuild nothing here, but be safe
        b = sim.body_state(body)
        ret += float(r)
        row = [info["t"], info["fish_heave"], info["fish_pitch"], b["velocity"][2], b["omega"][1],
               float(sim.positions[sim.system.top_node, 2]),
               info["top_tension"], float(sim.tensions.min()), float(r)]
        if kind == "compensator":
            cs = sim.compensator_state()
            hits += int(info.get("end_stop_hits", 0))
            row += [cs["stroke"], cs["stroke_velocity"], cs["stiffness"], cs["damping"], hits]
        else:
            ws = sim.winch_state()
            row += [ws["speed"], ws["length"] - L0]
        buf[i] = row
        if term or trunc:
            if term:
                rec.terminated = True
                rec.termination = info.get("termination")
            if info.get("solver_failure"):
                rec.failure = info.get("failure", "solver failure")
            break
    m = i + 1
    rec.data = {c: buf[:m, j].copy() for j, c in enumerate(cols)}
    rec.ret = ret
    rec.steps = m
    rec.wall_seconds = time.perf_counter() - t0
    return rec


def _std(x):
    return float(np.std(x)) if x.size else math.nan


#: the keys :func:`episode_metrics` returns, in its order: every episode, then the winch's or the compensator's own
#: (``tests/agents`` checks them against the function; ``--reuse`` compares an earlier report's columns with them
#: before any episode runs)
COMMON_METRICS = ("sig_heave", "rms_heave", "rms_heave_sp", "mean_heave", "sig_pitch_deg", "rms_pitch_deg",
                  "mean_pitch_deg", "rms_heave_rate", "max_heave_rate", "frac_heave_rate_over", "rms_pitch_rate_deg",
                  "max_pitch_rate_deg", "frac_pitch_rate_over", "sig_tow_heave", "heave_transmissibility",
                  "top_tension_max", "top_tension_min", "top_tension_std", "top_tension_max_all", "min_tension_all",
                  "slack_steps", "slack_frac", "return", "steps", "terminated", "failure")
KIND_METRICS = {"compensator": ("stroke_max_frac", "stroke_height", "stroke_1000_frac", "end_stop_hits",
                                "mean_stiffness", "mean_damping"),
                "winch": ("winch_dev_max_frac", "winch_rms_speed", "winch_frac_at_limit", "winch_peak_power_kw")}


def metric_columns(kind: str) -> tuple[str, ...]:
    """The per-episode metric names of an environment kind (``"winch"`` or ``"compensator"``)."""
    if kind not in KIND_METRICS:
        raise ValueError(f"kind must be one of {sorted(KIND_METRICS)} (got {kind!r})")
    return COMMON_METRICS + KIND_METRICS[kind]


def episode_metrics(rec: EpisodeRecord, discard: float = 60.0) -> dict[str, float]:
    """Per-episode metrics over the scored window (plain floats; see the module docstring)."""
    d = rec.data
    w = rec.window(discard)
    h, th = d["heave"][w], d["pitch"][w]
    hr, pr = d["heave_rate"][w], np.degrees(d["pitch_rate"][w])
    tz = d["tow_z"][w]
    out = {
        "sig_heave": 2.0 * _std(h),
        "rms_heave": _std(h),
        "rms_heave_sp": float(np.sqrt(np.mean(h * h))),
        "mean_heave": float(np.mean(h)),
        "sig_pitch_deg": 2.0 * math.degrees(_std(th)),
        "rms_pitch_deg": math.degrees(_std(th)),
        "mean_pitch_deg": math.degrees(float(np.mean(th))),
        "rms_heave_rate": float(np.sqrt(np.mean(hr * hr))),
        "max_heave_rate": float(np.max(np.abs(hr))),
        "frac_heave_rate_over": float(np.mean(np.abs(hr) > HEAVE_RATE_LIMIT)),
        "rms_pitch_rate_deg": float(np.sqrt(np.mean(pr * pr))),
        "max_pitch_rate_deg": float(np.max(np.abs(pr))),
        "frac_pitch_rate_over": float(np.mean(np.abs(pr) > PITCH_RATE_LIMIT_DEG)),
        "sig_tow_heave": 2.0 * _std(tz),
        "heave_transmissibility": _std(h) / max(_std(tz), 1e-12),
        "top_tension_max": float(np.max(d["top_tension"][w])),
        "top_tension_min": float(np.min(d["top_tension"][w])),
        "top_tension_std": _std(d["top_tension"][w]),
        "top_tension_max_all": float(np.max(d["top_tension"])),
        "min_tension_all": float(np.min(d["min_tension"])),
        "slack_steps": float(np.sum(d["min_tension"] <= 1.0)),
        "slack_frac": float(np.mean(d["min_tension"][w] <= 1.0)),
        "return": float(rec.ret),
        "steps": float(rec.steps),
        "terminated": float(rec.terminated),
        "failure": float(rec.failure is not None),
    }
    if rec.kind == "compensator":
        s = d["stroke"]
        sw = s[w]
        half = rec.half_stroke or 1.0
        out.update({
            "stroke_max_frac": float(np.max(np.abs(s))) / half,
            "stroke_height": float(np.max(sw) - np.min(sw)),
            "stroke_1000_frac": 2.0 * RAYLEIGH_1_1000 * _std(sw) / (2.0 * half),
            "end_stop_hits": float(d["hits"][-1]) if s.size else 0.0,
            "mean_stiffness": float(np.mean(d["stiffness"][w])),
            "mean_damping": float(np.mean(d["damping"][w])),
        })
    else:
        dev = d["winch_dev"]
        trav = rec.winch_travel or 10.0
        out.update({
            "winch_dev_max_frac": float(np.max(np.abs(dev))) / trav,
            "winch_rms_speed": float(np.sqrt(np.mean(d["winch_speed"][w] ** 2))),
            "winch_frac_at_limit": float(np.mean(np.abs(dev) >= trav - 1e-3)),
            "winch_peak_power_kw": float(np.max(np.abs(d["winch_speed"] * d["top_tension"]))) / 1e3,
        })
    return out


def bootstrap_mean_ci(x: Sequence[float], n_boot: int = 2000, level: float = 0.95, seed: int = 0):
    """(mean, lo, hi): percentile bootstrap CI of the mean of ``x`` (NaNs dropped)."""
    a = np.asarray([v for v in x if v is not None and math.isfinite(v)], float)
    if a.size == 0:
        return math.nan, math.nan, math.nan
    if a.size == 1:
        return float(a[0]), float(a[0]), float(a[0])
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, a.size, (n_boot, a.size))
    means = a[idx].mean(axis=1)
    q = (1.0 - level) / 2.0
    return float(a.mean()), float(np.quantile(means, q)), float(np.quantile(means, 1.0 - q))


def paired_reduction_ci(x: Sequence[float], ref: Sequence[float], n_boot: int = 2000, level: float = 0.95,
                        seed: int = 0, stat: Callable | None = None):
    """Relative reduction ``1 − mean(x)/mean(ref)`` over paired episodes (same sea and seed), with a
    paired percentile bootstrap CI (episodes resampled jointly). Returns (value, lo, hi)."""
    a, b = np.asarray(x, float), np.asarray(ref, float)
    ok = np.isfinite(a) & np.isfinite(b)
    a, b = a[ok], b[ok]
    if a.size == 0:
        return math.nan, math.nan, math.nan
    val = 1.0 - a.mean() / b.mean()
    if a.size == 1:
        return float(val), float(val), float(val)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, a.size, (n_boot, a.size))
    red = 1.0 - a[idx].mean(axis=1) / b[idx].mean(axis=1)
    q = (1.0 - level) / 2.0
    return float(val), float(np.quantile(red, q)), float(np.quantile(red, 1.0 - q))
