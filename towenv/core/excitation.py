"""Prescribed tow-point motion: steady tow, manoeuvres (turns, speed changes) and oscillatory excitation.

The path is piecewise analytic (constant speed and heading rate, or linearly changing speed at constant
heading), so the position at any time is exact and independent of how the caller chunks time — which
keeps runs deterministic across snapshot/restore. Only the oscillatory part (sinusoids, time series, and
later sea-state vessel motion) is multiplied by the start-up ramp (model.md 7).

Vessel motion from sea states plugs in as another ``Excitation`` (anything with ``offset(t)``).
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np


from ..scene import scene_field as _get  # noqa: E402  (the one scene accessor; defaults are the schema's)


@dataclass
class _Piece:
    t0: float
    t1: float
    x0: np.ndarray        # position at t0
    heading: float        # heading at t0 (rad)
    speed: float          # speed at t0
    accel: float          # dv/dt
    turn_rate: float      # dψ/dt (rad/s)


class Ramp:
    """The scene's start-up ramp (towenv.scene.Ramp: kind and duration) evaluated on time arrays."""

    def __init__(self, kind, duration):
        self.kind = kind
        self.duration = float(duration)

    def __call__(self, t):
        t = np.asarray(t, float)
        if self.kind == "none" or self.duration <= 0:
            return np.ones_like(t)
        if self.kind == "exponential":
            return 1.0 - np.exp(-np.maximum(t, 0.0) / self.duration)
        x = np.clip(t / self.duration, 0.0, 1.0)
        return 0.5 * (1.0 - np.cos(np.pi * x))


class Sinusoid:
    def __init__(self, axis, amplitude, period, phase_deg=0.0):
        self.k = "xyz".index(axis)
        self.amp = float(amplitude)
        self.omega = 2 * math.pi / float(period)
        self.phase = math.radians(phase_deg)

    def offset(self, t):
        out = np.zeros((len(t), 3))
        out[:, self.k] = self.amp * np.sin(self.omega * t + self.phase)
        return out


class TimeSeries:
    def __init__(self, path):
        with open(path, newline="") as fh:
            rows = list(csv.DictReader(fh))
        self.t = np.array([float(r["t"]) for r in rows])
        self.xyz = np.array([[float(r[k]) for k in "xyz"] for r in rows])

    def offset(self, t):
        return np.stack([np.interp(t, self.t, self.xyz[:, k]) for k in range(3)], axis=1)


class TowPointPath:
    """Position of the vessel tow point at any time t ≥ 0 (global axes)."""

    def __init__(self, vessel=None, base_dir: Path | None = None, default_data_dir: Path | None = None):
        from ..scene import Vessel
        if vessel is None:                      # a path with no vessel: at rest at the origin
            vessel = Vessel()
        elif not isinstance(vessel, Vessel):    # a plain mapping: validated, so the defaults are the schema's
            vessel = Vessel.model_validate(dict(vessel))
        x0 = np.asarray(vessel.tow_point, float)
        speed = float(vessel.speed)
        heading = math.radians(float(vessel.heading_deg))
        self.initial_speed = speed
        self.initial_heading = heading
        self.pieces: list[_Piece] = []
        t, x, psi, v = 0.0, x0.copy(), heading, speed
        mans = list(vessel.manoeuvres)
        for man in sorted(mans, key=lambda m: float(m.start_time)):
            ts = float(man.start_time)
            if ts > t:
                self.pieces.append(_Piece(t, ts, x.copy(), psi, v, 0.0, 0.0))
                x, psi, v = self._end(self.pieces[-1])
                t = ts
            kind = _get(man, "type")
            if kind == "turn":
                vt = _get(man, "speed")
                vt = v if vt is None else float(vt)
                if vt != v:
                    raise ValueError("vessel.manoeuvres: a turn must start at the current speed "
                                     "(use a speed_change before it)")
                radius = float(_get(man, "radius"))
                ang = math.radians(float(_get(man, "angle_deg")))
                if v <= 0:
                    raise ValueError("vessel.manoeuvres: a turn needs a positive speed")
                rate = math.copysign(v / radius, ang)
                dur = abs(ang) / abs(rate)
                self.pieces.append(_Piece(t, t + dur, x.copy(), psi, v, 0.0, rate))
            elif kind == "speed_change":
                dur = float(_get(man, "duration"))
                vf = float(_get(man, "final_speed"))
                self.pieces.append(_Piece(t, t + dur, x.copy(), psi, v, (vf - v) / dur, 0.0))
            else:
                raise ValueError(f"vessel.manoeuvres: unknown type {kind!r}")
            x, psi, v = self._end(self.pieces[-1])
            t = self.pieces[-1].t1
        self.pieces.append(_Piece(t, math.inf, x.copy(), psi, v, 0.0, 0.0))
        self.starts = np.array([p.t0 for p in self.pieces])
        self.oscillations = []
        for ex in vessel.excitation:
            kind = _get(ex, "type")
            if kind == "sinusoid":
                self.oscillations.append(Sinusoid(_get(ex, "axis"), _get(ex, "amplitude"), _get(ex, "period"),
                                                  ex.phase_deg))
            elif kind == "time_series":
                p = Path(_get(ex, "file"))
                if not p.is_absolute():
                    cands = [d / p for d in (base_dir, default_data_dir) if d is not None]
                    p = next((c for c in cands if c.exists()), cands[0] if cands else p)
                self.oscillations.append(TimeSeries(p))
            else:
                raise ValueError(f"vessel.excitation: unknown type {kind!r}")
        ramp = vessel.ramp
        self.ramp = Ramp(ramp.type, ramp.duration)

    @staticmethod
    def _end(p: _Piece):
        x, psi, v = TowPointPath._eval_piece(p, np.array([p.t1 - p.t0]))
        return x[0], float(psi[0]), float(v[0])

    @staticmethod
    def _eval_piece(p: _Piece, tau):
        v = p.speed + p.accel * tau
        if p.turn_rate != 0.0:
            w = p.turn_rate
            psi = p.heading + w * tau
            dx = (p.speed / w) * (np.sin(psi) - math.sin(p.heading))
            dy = (p.speed / w) * (-np.cos(psi) + math.cos(p.heading))
        else:
            psi = np.full_like(tau, p.heading)
            s = p.speed * tau + 0.5 * p.accel * tau * tau
            dx = s * math.cos(p.heading)
            dy = s * math.sin(p.heading)
        x = np.empty((len(tau), 3))
        x[:, 0] = p.x0[0] + dx
        x[:, 1] = p.x0[1] + dy
        x[:, 2] = p.x0[2]
        return x, psi, v

    def mean_path(self, t):
        """Path without oscillations: (positions (n,3), heading (n,), speed (n,))."""
        t = np.atleast_1d(np.asarray(t, float))
        idx = np.searchsorted(self.starts, t, side="right") - 1
        idx = np.clip(idx, 0, len(self.pieces) - 1)
        if len(t) and idx[0] == idx[-1] and (len(self.pieces) == 1 or (idx == idx[0]).all()):
            # all on one piece (the common case: a straight track, a block of steps): the same arithmetic
            # as below without the per-piece masks
            p = self.pieces[idx[0]]
            return self._eval_piece(p, t - p.t0)
        x = np.empty((len(t), 3))
        psi = np.empty(len(t))
        v = np.empty(len(t))
        for i in np.unique(idx):
            m = idx == i
            p = self.pieces[i]
            x[m], psi[m], v[m] = self._eval_piece(p, t[m] - p.t0)
        return x, psi, v

    def position(self, t):
        t = np.atleast_1d(np.asarray(t, float))
        x, _, _ = self.mean_path(t)
        if self.oscillations:
            osc = np.zeros_like(x)
            for o in self.oscillations:
                osc += o.offset(t)
            x = x + osc * self.ramp(t)[:, None]
        return x

    def initial_velocity(self):
        return np.array([self.initial_speed * math.cos(self.initial_heading),
                         self.initial_speed * math.sin(self.initial_heading), 0.0])
