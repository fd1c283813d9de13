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

Winch limits come from a named class (:data:`WINCH_CLASSES`, ``winch_class=``; docs/environments.md
"Actuators" gives the derivation and the sources): ``standard`` (default; 1.5 m/s, 1.5 m/s²) and
``high_performance`` (2.5 m/s, 2.5 m/s²), both with a ±10 m payout window about the initial length (a drum
winch has no stroke: the window is the allowed depth band). ``winch_max_speed`` / ``winch_max_acceleration``
/ ``winch_travel`` override single limits.
"""
from __future__ import annotations

import math

from numba import njit

from . import checks as C
from . import measurements as MS
from . import stepper as ST
from .base import TowEnv

__all__ = ["WinchPayoutEnv", "WINCH_CLASSES"]

#: Named winch classes (limits of the payout speed, acceleration and payout window; rated power for the
#: reports). No vendor datasheet with AHC line speeds/accelerations was reachable from this project's
#: library; the classes are sized by the kinematic demand of following the tow point's motion (docs/
#: environments.md "Actuators"): ``standard`` follows the significant wave of the coastal code-3/4 seas
#: (demand ≈ 0.9–1.3 m/s, 1.1 m/s²) and saturates in the largest waves; ``high_performance`` follows the
#: near-maximum wave of Hs 3 m (2.35 m/s, 2.0 m/s²). Power = the class's rated top tension × max speed.
WINCH_CLASSES = {
    "standard": {"max_speed": 1.5, "max_acceleration": 1.5, "travel": 10.0, "rated_power": 15e3},
    "high_performance": {"max_speed": 2.5, "max_acceleration": 2.5, "travel": 10.0, "rated_power": 40e3},
}


class WinchPayoutEnv(TowEnv):
    """Winch payout-speed control. Extra keywords: ``winch_class`` (:data:`WINCH_CLASSES`, default
    ``"standard"``) and single-limit overrides ``winch_max_speed`` (m/s), ``winch_max_acceleration`` (m/s²),
    ``winch_travel`` (m either side of the initial length). A scene that already has a ``[winch]`` keeps it,
    with these limits applied on top."""

    DEFAULT_OBSERVATIONS = ("tow_vel_along", "tow_acc_along", "tow_disp_along", "cable_angle", "tow_vel_x",
                            "tow_vel_z", "tow_acc_x", "tow_acc_z", "top_tension", "winch_speed", "winch_length_dev",
                            "fish_heave_dev", "fish_pitch_dev", "fish_heave_rate", "fish_pitch_rate", "last_action")
    ACTION_DIM = 1
    ACT_KIND = ST.ACT_WINCH_SPEED
    ACTUATOR_KEYS = ("winch_speed", "winch_length_dev", "winch_length", "effort", "winch_power")

    def __init__(self, *, winch_class: str = "standard", winch_max_speed: float | None = None,
                 winch_max_acceleration: float | None = None, winch_travel: float | None = None, **kwargs):
        own = type(self).__name__
        C.choice(own, "winch_class", winch_class, sorted(WINCH_CLASSES))
        cls = WINCH_CLASSES[winch_class]
        self.winch_class = winch_class
        self.winch_rated_power = float(cls["rated_power"])
        winch_max_speed = C.real(own, "winch_max_speed", winch_max_speed, 0.0, lo_open=True, unit="m/s",
                                 none="the class's value")
        winch_max_acceleration = C.real(own, "winch_max_acceleration", winch_max_acceleration, 0.0, lo_open=True,
                                        unit="m/s²", none="the class's value")
        winch_travel = C.real(own, "winch_travel", winch_travel, 0.0, lo_open=True, unit="m",
                              none="the class's value")
        winch_max_speed = cls["max_speed"] if winch_max_speed is None else winch_max_speed
        winch_max_acceleration = cls["max_acceleration"] if winch_max_acceleration is None else winch_max_acceleration
        winch_travel = cls["travel"] if winch_travel is None else winch_travel
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
        try:
            return sc.with_overrides({"winch.min_length": max(L - self.winch_travel, 1e-3),
                                      "winch.max_length": L + self.winch_travel})
        except ValueError as exc:
            raise C.ConfigError(f"{type(self).__name__}: the payout window winch_travel = ±{self.winch_travel:g} m "
                                f"about the {L:g} m winch line{'' if length is None else ' (cable_length)'} does "
                                f"not fit the scene: {exc}") from exc

    def _check_actuator(self, sim):
        sim.winch_state()                      # raises ValueError without a winch

    @property
    def _L0(self) -> float:
        """Deployed winch-line length at the start of the episode (m)."""
        return float(self._rows.stepper.refs[self._row, MS.R_L0])

    def _commands(self, A, rows, U, amap):
        return _speed_commands(A, rows, self.winch_max_speed, U)

    def _actuator_refs(self, ref, amap):
        ref[MS.R_VMAX] = self.winch_max_speed
        ref[MS.R_L0] = float(self.sim.winch_state()["length"])
        ref[MS.R_EFFORT] = 1.0


@njit(cache=True)
def _speed_commands(A, rows, vmax, U):
    """Clean actions ``A[rows]`` in place (NaN → 0, clip to [−1, 1]); payout speed command a·max_speed.
    Returns the number of actions that were cleaned."""
    n_bad = 0
    for k in range(rows.shape[0]):
        b = rows[k]
        a = A[b, 0]
        if not (-1.0 <= a <= 1.0):              # NaN, ±inf, |a| > 1
            n_bad += 1
            if a != a:
                a = 0.0
            a = min(max(a, -1.0), 1.0)
        A[b, 0] = a
        U[b, 0] = min(max(a * vmax, -vmax), vmax)
    return n_bad
