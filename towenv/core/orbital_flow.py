"""Wave orbital velocity at the nodes ([sea] orbital_velocities = true): linear deep-water theory,
summed over the wave components, evaluated once per step at the predicted positions.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import njit


@njit(cache=True)
def wave_orbital_velocity(x, y, z, t, amp, omega, kx, ky, k, phase, out):
    """Deep-water linear (Airy) orbital velocity at (x, y, z) and time t, global axes (towenv.sea's
    convention): P = ω t − kx x − ky y + φ, u = Σ a ω e^{kz} cos P (kx, ky)/k, w = −Σ a ω e^{kz} sin P.
    Points above the mean surface get the surface value (no stretching)."""
    out[0] = 0.0
    out[1] = 0.0
    out[2] = 0.0
    zz = z if z < 0.0 else 0.0
    for j in range(amp.shape[0]):
        f = amp[j] * omega[j] * math.exp(k[j] * zz)
        if f < 1e-12:
            continue
        p = omega[j] * t - kx[j] * x - ky[j] * y + phase[j]
        c = math.cos(p)
        fc = f * c / k[j]
        out[0] += fc * kx[j]
        out[1] += fc * ky[j]
        out[2] -= f * math.sin(p)


@njit(cache=True)
def _wave_flow(t, r_t, r_tm1, r_tm2, wave, flow, v):
    """Orbital velocity at every node's predicted position for the step ending at t (frozen during the
    step's Newton iteration). ``wave`` is a :class:`towenv.core.model.WaveField`; ``wave.options =
    [enabled, z_cut]``: nodes below ``z_cut`` (where every component has decayed below
    1e-6 m/s) are skipped. ``v``: a (3,) scratch array (nothing here allocates: ``houbolt.advance`` is compiled
    without reference counting)."""
    amp, omega, kx, ky, k, phase, opts = wave.amplitude, wave.omega, wave.kx, wave.ky, wave.k, wave.phase, wave.options
    nn = flow.shape[0]
    for a in range(nn):
        flow[a, 0] = 0.0
        flow[a, 1] = 0.0
        flow[a, 2] = 0.0
    if opts[0] == 0.0:
        return
    for a in range(nn):
        z = 3.0 * r_t[a, 2] - 3.0 * r_tm1[a, 2] + r_tm2[a, 2]
        if z < opts[1]:
            continue
        x = 3.0 * r_t[a, 0] - 3.0 * r_tm1[a, 0] + r_tm2[a, 0]
        y = 3.0 * r_t[a, 1] - 3.0 * r_tm1[a, 1] + r_tm2[a, 1]
        wave_orbital_velocity(x, y, z, t, amp, omega, kx, ky, k, phase, v)
        flow[a, 0] = v[0]
        flow[a, 1] = v[1]
        flow[a, 2] = v[2]
