"""The strongest causal classical controllers: along-cable feed-forward winch and skyhook semi-active compensator.

Both act on the observation vector only (the sensors of ``docs/environments.md``: MRU, sheave angle, tension,
actuator and fish sensors), so they are *causal*: nothing of the future of the sea enters. The gain tables are
per sea state (Hs, Tp) — the sea-state estimate an operator has from the MRU spectrum or a wave buoy — and are
tuned on the tuning seeds only (``python -m agents.tuning --only along skyhook``).

``along_cable`` (WinchPayout)::

    v = g_ff·(v_al + τ·a_al) − k_l·(ΔL − g_ff·d_al) + k_p·h' + k_d·ḣ          (payout > 0)

v_al, a_al, d_al = tow-point velocity, acceleration and displacement projected on the top cable (the MRU's
3-axis motion and the sheave angle sensor: a payout only changes the cable's length, so only the along-cable
part of the tow point's motion can be cancelled, rl-conventions §9 item 3); τ = lead time for the winch's
acceleration lag; ΔL = winch-line length change, pulled toward the feed-forward's own length target
g_ff·d_al (removes the integration drift without fighting the feed-forward); h', ḣ = fish heave about its
running mean and heave rate (feedback on what is left). With g_ff = 1 and no feedback it is plain
along-cable cancellation.

``skyhook`` (CompensatorGains), the classical semi-active law of Karnopp et al. (1974) for a variable damper:
the sheave should feel the force −c_sky·ż_abs of a damper to the "sky" (an inertial reference);
a passive damper between ship and sheave can only produce −b·ṡ (ṡ = stroke velocity), so::

    b = clip(c_sky·ż_abs / ṡ, b_0, b_max)   if ż_abs·ṡ > 0   else b_0        (ż_abs = ż_ship + ṡ)

with a floor damping b_0, and the spring is k_0 except near the end stops, where it stiffens linearly to
k_stop over the last ``margin`` of the half stroke (keeps the stroke off the stops). With c_sky = 0 and
k_stop = k_0 it is the fixed passive (k_0, b_0): the tuning starts there, from the best passive setting.
"""
from __future__ import annotations

import math

import numpy as np

from .baselines import Baseline
from .common import nearest_key

__all__ = ["AlongCableWinch", "along_cable_velocity", "SkyhookCompensator", "DEFAULT_ALONG_GAINS", "DEFAULT_SKYHOOK_GAINS"]

#: gains used when no tuned table exists (plain along-cable cancellation with weak centring/feedback)
DEFAULT_ALONG_GAINS = {"g_ff": 1.0, "tau": 0.1, "kl": 0.05, "kp": 0.2, "kd": 0.1}
#: skyhook gains used when no tuned table exists: c_sky (N s/m), b0 floor damping (N s/m), k0 spring (N/m),
#: margin (fraction of the half stroke), k_stop (N/m)
DEFAULT_SKYHOOK_GAINS = {"c_sky": 5000.0, "b0": 1000.0, "k0": 1000.0, "margin": 0.3, "k_stop": 50000.0}


def along_cable_velocity(g_ff, tau, kl, kp, kd, v_al, a_al, d_al, dL, h, hd):
    """The along-cable law (module docstring), payout speed in m/s; element-wise, so the same arithmetic serves
    one observation (floats) and a batch (arrays, ``agents.ars``). Arguments in :attr:`AlongCableWinch.CHANNELS`
    order after the gains."""
    ff = g_ff * (v_al + tau * a_al)
    centre = -kl * (dL - g_ff * d_al)
    fb = kp * h + kd * hd
    return ff + centre + fb


class AlongCableWinch(Baseline):
    """Along-cable feed-forward + feedback winch law (module docstring); gains per sea state from the
    ``along_cable`` table of ``agents/hyperparams/baselines.yml`` or one set (``gains=``)."""
    name = "along_cable"
    kind = "winch"
    acts_on = "observations"
    CHANNELS = ("tow_vel_along", "tow_acc_along", "tow_disp_along", "winch_length_dev", "fish_heave_dev",
                "fish_heave_rate")

    def __init__(self, env, gains: dict | None = None, table: dict | None = None, name: str | None = None):
        super().__init__(env)
        missing = [c for c in self.CHANNELS if not self.reader.has(c)]
        if missing:
            raise ValueError(f"along_cable needs the observation channels {missing}")
        self.table = table or None
        if self.table:
            self.acts_on = "observations + sea state"
        self.fixed = dict(DEFAULT_ALONG_GAINS | (gains or {}))
        self.g = dict(self.fixed)
        self.vmax = float(self.u.winch_max_speed)
        if name:
            self.name = name

    def reset(self):
        if self.table:
            self.g = dict(DEFAULT_ALONG_GAINS | self.table[nearest_key(self.table, self.u.sea[0])])

    def velocity(self, obs, g: dict | None = None) -> float:
        r = self.reader
        g = self.g if g is None else g
        return along_cable_velocity(g["g_ff"], g["tau"], g["kl"], g["kp"], g["kd"], *(r(obs, c) for c in self.CHANNELS))

    def act(self, obs):
        return np.array([min(max(self.velocity(obs) / self.vmax, -1.0), 1.0)])

    def describe(self):
        if self.table:
            parts = [f"{k}: " + ", ".join(f"{n}={float(v):.3g}" for n, v in e.items() if n in DEFAULT_ALONG_GAINS)
                     for k, e in self.table.items()]
            return "along-cable feed-forward + feedback winch, gains per sea state (" + "; ".join(parts) + ")"
        return "along-cable feed-forward + feedback winch (" + ", ".join(f"{n}={v:.3g}" for n, v in self.g.items()) + ")"


class SkyhookCompensator(Baseline):
    """Skyhook semi-active compensator (module docstring): variable damping from the stroke velocity and the
    sheave's absolute vertical velocity, soft spring stiffening near the end stops. Gains per sea state from
    the ``skyhook`` table, or one set (``gains=``)."""
    name = "skyhook"
    kind = "compensator"
    acts_on = "observations"
    CHANNELS = ("comp_stroke", "comp_stroke_vel", "tow_vel_z")

    def __init__(self, env, gains: dict | None = None, table: dict | None = None, name: str | None = None):
        super().__init__(env)
        missing = [c for c in self.CHANNELS if not self.reader.has(c)]
        if missing:
            raise ValueError(f"skyhook needs the observation channels {missing}")
        self.table = table or None
        if self.table:
            self.acts_on = "observations + sea state"
        self.fixed = dict(DEFAULT_SKYHOOK_GAINS | (gains or {}))
        self.g = dict(self.fixed)
        self._kmap, self._bmap = self.u.stiffness_range, self.u.damping_range
        if name:
            self.name = name

    def reset(self):
        if self.table:
            self.g = dict(DEFAULT_SKYHOOK_GAINS | self.table[nearest_key(self.table, self.u.sea[0])])

    def gains(self, obs) -> tuple[float, float]:
        r, g = self.reader, self.g
        k_lo, k_hi = self._kmap[0], self._kmap[1]
        b_lo, b_hi = self._bmap[0], self._bmap[1]
        s = r(obs, "comp_stroke")                 # fraction of the half stroke
        sd = r(obs, "comp_stroke_vel")            # m/s
        z_abs = r(obs, "tow_vel_z") + sd          # sheave absolute vertical velocity
        b0 = min(max(g["b0"], b_lo), b_hi)
        if z_abs * sd > 0.0 and abs(sd) > 1e-6:
            b = min(max(g["c_sky"] * z_abs / sd, b0), b_hi)
        else:
            b = b0
        m = min(max(g["margin"], 1e-3), 1.0)
        x = (abs(s) - (1.0 - m)) / m              # 0 at the margin's edge, 1 at the stop
        k0 = min(max(g["k0"], k_lo), k_hi)
        k = k0 + max(g["k_stop"] - k0, 0.0) * min(max(x, 0.0), 1.0)
        return float(min(max(k, k_lo), k_hi)), float(b)

    def act(self, obs):
        k, b = self.gains(obs)
        return self.u.action_of(k, b)

    def describe(self):
        if self.table:
            parts = [f"{k}: " + ", ".join(f"{n}={float(v):.3g}" for n, v in e.items() if n in DEFAULT_SKYHOOK_GAINS)
                     for k, e in self.table.items()]
            return "skyhook semi-active compensator, gains per sea state (" + "; ".join(parts) + ")"
        return "skyhook semi-active compensator (" + ", ".join(f"{n}={v:.3g}" for n, v in self.g.items()) + ")"
