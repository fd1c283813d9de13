"""``towenv/WinchPayout-v0``: active heave compensation with the winch.

The scene is the default two-part coastal scene with its passive compensator **removed** and a speed-
controlled winch at the top of the primary cable added::

    load_scene("two_part_coastal_ss4").with_overrides(compensator=None,
        winch={"mode": "speed", "max_speed": 1.5, "max_acceleration": 1.5,
               "min_length": L - 10, "max_length": L + 10})

(``Scene.with_overrides``: a value of ``None`` removes the key, i.e. restores the default, which for
``compensator`` is "no compensator"). Action ``a ∈ [-1, 1]`` → payout speed command ``a · max_speed``
(payout > 0); the simulator applies the acceleration limit and the length limits (model.md 2.8:
nodes are inserted/removed at the top as the cable pays out/hauls in).

ASSUMED winch limits (illustrative, not from the thesis): 1.5 m/s, 1.5 m/s², ±10 m of travel about the
initial length — enough to follow a small craft's stern heave in coastal sea states 3–5.
"""
from __future__ import annotations

import math

from numba import njit

from ..core import batch as BT
from .base import TowEnv

__all__ = ["WinchPayoutEnv"]


class WinchPayoutEnv(TowEnv):
    """Winch payout-speed control. Extra keywords: ``winch_max_speed`` (m/s), ``winch_max_acceleration``
    (m/s²), ``winch_travel`` (m either side of the initial length). A scene that already has a
    ``[winch]`` keeps it, with these limits applied on top."""

    DEFAULT_OBSERVATIONS = ("tow_vel_z", "tow_acc_z", "top_tension", "winch_speed", "winch_length_dev",
                            "fish_heave", "fish_pitch", "fish_heave_rate", "fish_pitch_rate", "last_action")
    ACTION_DIM = 1
    ACT_KIND = BT.ACT_WINCH_SPEED
    ACTUATOR_KEYS = ("winch_speed", "winch_length_dev", "winch_length", "effort")

    def __init__(self, *, winch_max_speed: float = 1.5, winch_max_acceleration: float = 1.5,
                 winch_travel: float = 10.0, **kwargs):
        for nm, v in (("winch_max_speed", winch_max_speed), ("winch_max_acceleration", winch_max_acceleration),
                      ("winch_travel", winch_travel)):
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"WinchPayoutEnv: {nm} must be > 0 (got {v!r})")
        self.winch_max_speed = float(winch_max_speed)
        self.winch_max_acceleration = float(winch_max_acceleration)
        self.winch_travel = float(winch_travel)
        super().__init__(**kwargs)

    def _prepare_scene(self, scene):
        ov = {"winch.mode": "speed", "winch.speed": 0.0, "winch.max_speed": self.winch_max_speed,
              "winch.max_acceleration": self.winch_max_acceleration}
        if scene.winch is None:
            ov = {"compensator": None, "winch": {"mode": "speed", "max_speed": self.winch_max_speed,
                                                 "max_acceleration": self.winch_max_acceleration}}
        return scene.with_overrides(ov)

    def _winch_line(self, scene):
        if scene.winch.line is not None:
            return scene.line(scene.winch.line)
        return [ln for ln in scene.lines if ln.top_kind == "vessel"][0]

    def _config_scene(self, speed, length):
        sc = super()._config_scene(speed, length)
        L = self._winch_line(sc).length
        return sc.with_overrides({"winch.min_length": max(L - self.winch_travel, 1e-3),
                                  "winch.max_length": L + self.winch_travel})

    def _check_actuator(self, sim):
        sim.winch_state()                      # raises ValueError without a winch

    @property
    def _L0(self) -> float:
        """Deployed winch-line length at the start of the episode (m)."""
        return float(self._rows.stepper.refs[self._row, BT.R_L0])

    def _commands(self, A, rows, U, amap):
        _speed_commands(A, rows, self.winch_max_speed, U)

    def _actuator_refs(self, ref, amap):
        ref[BT.R_VMAX] = self.winch_max_speed
        ref[BT.R_L0] = float(self.sim.winch_state()["length"])
        ref[BT.R_EFFORT] = 1.0


@njit(cache=True)
def _speed_commands(A, rows, vmax, U):
    """Clean actions ``A[rows]`` in place (NaN → 0, clip to [−1, 1]); payout speed command a·max_speed."""
    for k in range(rows.shape[0]):
        b = rows[k]
        a = A[b, 0]
        if a != a:
            a = 0.0
        a = min(max(a, -1.0), 1.0)
        A[b, 0] = a
        U[b, 0] = min(max(a * vmax, -vmax), vmax)
