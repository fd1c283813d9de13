"""``towenv/CompensatorGains-v0``: tune a passive heave compensator's stiffness and damping online.

The agent acts as a semi-active controller: every control step it sets the spring stiffness k and the
damping b of the passive compensator at the vessel sheave (``Simulator.set_compensator``), within the
scene's ``[compensator] stiffness_bounds`` / ``damping_bounds``.

Action ``a ∈ [-1, 1]²`` is mapped **logarithmically** (the ranges span decades; rl-conventions §4)::

    k = k_lo · (k_hi / k_lo) ** ((a0 + 1) / 2)        b = b_lo · (b_hi / b_lo) ** ((a1 + 1) / 2)

with ``[k_lo, k_hi]``/``[b_lo, b_hi]`` the scene's bounds, except that a lower bound of 0 cannot be
log-mapped: it is replaced by a small positive floor, ``stiffness_floor`` / ``damping_floor`` (default
1e-3 × the upper bound; for the default scene b ∈ [50, 50 000] N s/m, so a = −1 gives 50 N s/m, not 0).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import checks as C
from . import measurements as MS
from . import stepper as ST
from .base import TowEnv

__all__ = ["CompensatorGainsEnv", "COMPENSATOR_CLASSES"]

#: Named compensator classes (stroke = total travel, m; apparent mass, kg). ``sheave_2m`` is the default scene's
#: small-craft sheave compensator (2 m travel, 50 kg, illustrative); ``deep_tow_4m`` is the travel and apparent
#: mass Hover et al. (1994, §IV-B) give for the MBARI SWATH's bobbing-crane compensator ("the available
#: compensator travel is 4.0 m", m_comp = 530 kg, Table II). ``None`` keeps the scene's values. The
#: semi-active force k·s + b·ṡ is bounded by the gain bounds and the stroke (no separate force limit: the
#: reports give the largest force used).
COMPENSATOR_CLASSES = {
    "sheave_2m": {"stroke": 2.0, "mass": 50.0},
    "deep_tow_4m": {"stroke": 4.0, "mass": 530.0},
}


class CompensatorGainsEnv(TowEnv):
    """Semi-active heave compensation by online (k, b) tuning. See ``docs/environments.md``.

    Extra keywords: ``compensator_class`` (:data:`COMPENSATOR_CLASSES`; default None = the scene's stroke and
    mass), ``stiffness_floor`` and ``damping_floor`` (N/m, N s/m) — positive floors used for
    the log map when a scene bound is 0 (default 1e-3 × the upper bound). The scene's compensator is
    put in ``passive`` mode (the gains act only there)."""

    DEFAULT_OBSERVATIONS = ("tow_heave", "tow_vel_z", "tow_acc_z", "tow_vel_along", "top_tension", "comp_stroke",
                            "comp_stroke_vel", "fish_heave_dev", "fish_pitch_dev", "fish_heave_rate", "fish_pitch_rate",
                            "last_action")
    ACTION_DIM = 2
    ACT_KIND = ST.ACT_COMP_GAINS
    ACTUATOR_KEYS = ("comp_stroke", "comp_stroke_vel", "end_stop_hits", "comp_stiffness", "comp_damping", "effort")

    def __init__(self, *, compensator_class: str | None = None, stiffness_floor: float | None = None,
                 damping_floor: float | None = None, **kwargs):
        own = type(self).__name__
        C.choice(own, "compensator_class", compensator_class, sorted(COMPENSATOR_CLASSES),
                 none="the scene's stroke and mass")
        self.compensator_class = compensator_class
        self.stiffness_floor = C.real(own, "stiffness_floor", stiffness_floor, 0.0, lo_open=True, unit="N/m",
                                      none="1e-3 × the upper bound")
        self.damping_floor = C.real(own, "damping_floor", damping_floor, 0.0, lo_open=True, unit="N s/m",
                                    none="1e-3 × the upper bound")
        super().__init__(**kwargs)

    # ------------------------------------------------------------------ hooks
    def _prepare_scene(self, scene):
        if scene.compensator is None:
            raise ValueError(f"CompensatorGainsEnv: scene {scene.name!r} has no [compensator] section")
        ov = {}
        if scene.compensator.mode != "passive":
            ov["compensator.mode"] = "passive"
        if self.compensator_class is not None:
            ov.update({f"compensator.{k}": v for k, v in COMPENSATOR_CLASSES[self.compensator_class].items()})
        return scene.with_overrides(ov) if ov else scene

    @staticmethod
    def _log_range(bounds, floor, what):
        lo, hi = float(bounds[0]), float(bounds[1])
        if hi <= 0:
            raise ValueError(f"CompensatorGainsEnv: the {what} upper bound must be > 0 (got {bounds})")
        f = 1e-3 * hi if floor is None else float(floor)
        if not (math.isfinite(f) and 0 < f <= hi):
            raise C.ConfigError(f"CompensatorGainsEnv: {what}_floor must be in (0, {hi:g}] (got {floor!r})")
        lo_eff = lo if lo > 0 else f
        return lo_eff, hi, lo, hi

    def _check_actuator(self, sim):
        c = sim.scene.compensator
        self._k_map = self._log_range(c.stiffness_bounds, self.stiffness_floor, "stiffness")
        self._b_map = self._log_range(c.damping_bounds, self.damping_floor, "damping")
        self._half_stroke = 0.5 * float(c.stroke)

    @staticmethod
    def _to_gain(a, mp):
        lo, hi, blo, bhi = mp
        return log_gain(float(a), float(lo), float(hi), float(blo), float(bhi))

    @staticmethod
    def _to_action(g, mp):
        lo, hi = mp[0], mp[1]
        if hi <= lo or g <= 0:
            return -1.0
        return float(np.clip(2.0 * math.log(g / lo) / math.log(hi / lo) - 1.0, -1.0, 1.0))

    @property
    def stiffness_range(self) -> tuple[float, float, float, float]:
        """The action → stiffness map: ``(lo, hi, bound_lo, bound_hi)`` N/m (log-linear from ``lo`` at −1 to
        ``hi`` at +1, clipped to the compensator's bounds; ``lo`` is ``stiffness_floor`` when the lower bound is 0)."""
        return self._k_map

    @property
    def damping_range(self) -> tuple[float, float, float, float]:
        """The action → damping map, as :attr:`stiffness_range` (N s/m)."""
        return self._b_map

    @property
    def half_stroke(self) -> float:
        """Half the compensator's stroke (m): the stroke runs ±half_stroke about mid-stroke, the end stops beyond."""
        return self._half_stroke

    def gains(self, action) -> tuple[float, float]:
        """(stiffness N/m, damping N s/m) of an action in [-1, 1]²."""
        a0, a1 = (min(max(float(x), -1.0), 1.0) for x in np.asarray(action, float).reshape(2))
        return self._to_gain(a0, self._k_map), self._to_gain(a1, self._b_map)

    def action_of(self, stiffness: float, damping: float) -> np.ndarray:
        """Inverse of :meth:`gains` (clipped to [-1, 1])."""
        return np.array([self._to_action(stiffness, self._k_map), self._to_action(damping, self._b_map)])

    @property
    def _hits(self) -> int:
        """Compensator end-stop hits counted so far in the episode."""
        return int(self._rows.stepper.refs[self._row, MS.R_HITS])

    def _commands(self, A, rows, U, amap):
        return _log_gains(A, rows, amap, U)

    def _actuator_refs(self, ref, amap):
        self._check_actuator(self.sim)          # bounds are per configuration (same for all by default)
        amap[0:4] = self._k_map
        amap[4:8] = self._b_map
        ref[MS.R_HALF_STROKE] = self._half_stroke
        ref[MS.R_HITS] = 0.0

    def _reset_action(self):
        cs = self.sim.compensator_state()
        return self.action_of(cs["stiffness"], cs["damping"])


@njit(cache=True)
def log_gain(a, lo, hi, blo, bhi):
    """The action → gain map (one formula for :meth:`CompensatorGainsEnv.gains` and the batched
    :func:`_log_gains`): log-linear from ``lo`` at a = −1 to ``hi`` at a = +1, clipped to [blo, bhi]."""
    if hi <= lo:
        g = lo
    else:
        g = lo * (hi / lo) ** (0.5 * (a + 1.0))
    return min(max(g, blo), bhi)


@njit(cache=True)
def _log_gains(A, rows, amap, U):
    """Clean actions ``A[rows]`` in place (NaN → 0, clip to [−1, 1]) and map them to gains (the
    arithmetic of :meth:`CompensatorGainsEnv.gains`). Returns the number of action entries cleaned."""
    n_bad = 0
    for k in range(rows.shape[0]):
        b = rows[k]
        for d in range(2):
            a = A[b, d]
            if not (-1.0 <= a <= 1.0):      # NaN -> 0; ±inf, |a| > 1 -> ±1
                n_bad += 1
                if a != a:
                    a = 0.0
                a = min(max(a, -1.0), 1.0)
            A[b, d] = a
            U[b, d] = log_gain(a, amap[b, 4 * d], amap[b, 4 * d + 1], amap[b, 4 * d + 2], amap[b, 4 * d + 3])
    return n_bad
