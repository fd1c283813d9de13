"""Tow-point positions for absolute physics steps: the one fast path the Simulator and the environments share.

The wave-induced part of the tow-point motion is a sum of ``n`` wave components (200 by default). Summing
them at every step costs ~90 ns per component; on a straight, steady track the phases advance linearly in
time, so each component's complex amplitude is advanced by one complex multiplication per step (a phase
recurrence) instead. The recurrence restarts from an exact evaluation at every multiple of :data:`BLOCK`
steps (absolute, not relative to the caller's request), so a step's position does not depend on how a run
is chunked — runs stay bit-for-bit reproducible — and the round-off of the recurrence stays bounded
(measured ≤ 1e-9 m from the exact sum over 3000 s; tests/unit/test_tow_point.py). Manoeuvres, motion
records and several oscillation sources fall back to the exact evaluation (``path.position``).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

#: recurrence block (physics steps): the recurrence restarts from an exact evaluation at multiples of it
BLOCK = 128


@njit(cache=True)
def _phase_recurrence(er, ei, rr, ri, gr, gi, out):
    """out[s] = Re Σ_j E_j G_j with E_j ← E_j·R_j after each row (the caller gives E at the first row)."""
    n = out.shape[0]
    m = er.shape[0]
    for s in range(n):
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        for j in range(m):
            xr = er[j]
            xi = ei[j]
            a0 += xr * gr[j, 0] - xi * gi[j, 0]
            a1 += xr * gr[j, 1] - xi * gi[j, 1]
            a2 += xr * gr[j, 2] - xi * gi[j, 2]
            er[j] = xr * rr[j] - xi * ri[j]
            ei[j] = xr * ri[j] + xi * rr[j]
        out[s, 0] = a0
        out[s, 1] = a1
        out[s, 2] = a2


class TowPointBuffer:
    """Tow-point positions of one Simulator for absolute physics steps, in aligned blocks of ``BLOCK``
    (see the module docstring). ``block(first, count)`` returns steps first … first+count−1."""

    def __init__(self, sim):
        self.sim = sim
        self.path = sim.path
        self._cache = {}

    def recurrence_possible(self) -> bool:
        """Whether any block of this path can use the phase recurrence (one sea-state vessel motion, not a
        record). When not, every step is the exact ``path.position``, which is computed element by element
        (the same bits for a step whatever range it is evaluated in), so :meth:`block` evaluates a whole
        range in one call instead of one call per :data:`BLOCK` steps (~50 µs of numpy calls each)."""
        from ..vessel import TowPointMotion
        osc = self.path.oscillations
        return len(osc) == 1 and isinstance(osc[0], TowPointMotion) and not osc[0].is_record

    def _leg(self, t_a, t_b):
        """(vessel motion, leg index, leg) if the wave phases are linear in t on [t_a, t_b] (one sea-state
        vessel motion following this path, on one straight, steady leg), else None."""
        from ..vessel import TowPointMotion
        path = self.path
        osc = path.oscillations
        if len(osc) != 1 or not isinstance(osc[0], TowPointMotion) or osc[0].is_record:
            return None
        vm = osc[0]
        if vm.track is None or getattr(vm.track, "__self__", None) is not path:
            return None
        i = int(np.clip(np.searchsorted(path.starts, t_a, side="right") - 1, 0, len(path.pieces) - 1))
        p = path.pieces[i]
        if p.accel != 0.0 or p.turn_rate != 0.0 or t_b > p.t1 or t_a < p.t0:
            return None
        return vm, i, p

    def _rotation_and_gains(self, vm, i, p, U, psi):
        """(per-step rotation re, im, gains re, im) of leg ``i`` (cached per leg; U, psi: the leg's speed and
        heading arrays from ``vm._path``)."""
        key = (id(vm), i)
        cached = self._cache.get(key)
        if cached is None or cached[0] is not vm:
            G = vm._gains_for_keys(np.array([[float(U[0]), float(psi[0])]]))
            ux, uy = p.speed * math.cos(p.heading), p.speed * math.sin(p.heading)
            R = np.exp(1j * ((vm._w - vm._kx * ux - vm._ky * uy) * self.sim.settings.dt))
            cached = self._cache[key] = (vm, R.real.copy(), R.imag.copy(), np.ascontiguousarray(G[0].real),
                                         np.ascontiguousarray(G[0].imag))
        return cached[1:]

    def _linear(self, t_a, t_b):
        """(E at t_a, per-step rotation, gains) if the wave phases are linear in t on [t_a, t_b], else None."""
        leg = self._leg(t_a, t_b)
        if leg is None:
            return None
        vm, i, p = leg
        xy, psi, U = vm._path(np.array([t_a]))
        rg = self._rotation_and_gains(vm, i, p, U, psi)
        P = t_a * vm._w - xy[0, 0] * vm._kx - xy[0, 1] * vm._ky + vm._phi
        E = np.exp(1j * P) * vm._a
        return E, rg

    def block(self, first, count, mean=False):
        """Positions (count, 3) of steps first … first+count−1. The phase recurrence restarts from an exact
        evaluation at every multiple of BLOCK, so a step's value does not depend on ``first``/``count``.
        With ``mean=True`` also the mean track (count, 4): x, y, z and heading (rad) of the same steps."""
        if count > 0 and not self.recurrence_possible():
            # the exact path only: the times as _aligned forms them (integer step numbers times dt), one call
            t = np.arange(first, first + count) * self.sim.settings.dt
            out = self.path.position(t)
            if not mean:
                return out
            x, psi, _ = self.path.mean_path(t)
            return out, np.column_stack([x, psi])
        if first % BLOCK == 0 and 0 < count <= BLOCK:
            # one aligned block (the stepper's refills): its mean track is the one _aligned evaluates, at the
            # same times (first == the block's anchor)
            out, mp = self._aligned(first, count, with_mean=True)
            if not mean:
                return out
            x, psi, _ = mp
            return out, np.column_stack([x, psi])
        out = np.empty((count, 3))
        s = first
        while s < first + count:
            end = min((s // BLOCK + 1) * BLOCK, first + count)
            out[s - first:end - first] = self._aligned(s, end - s)
            s = end
        if not mean:
            return out
        t = np.arange(first, first + count) * self.sim.settings.dt
        x, psi, _ = self.path.mean_path(t)
        return out, np.column_stack([x, psi])

    def span(self, first, nblocks):
        """Positions (nblocks·BLOCK, 3) and mean track (nblocks·BLOCK, 4) of the ``nblocks`` aligned blocks from
        step ``first`` (a multiple of BLOCK): the values of :meth:`block` bit for bit, with the blocks' exact
        anchors evaluated in one vectorised call when they all lie on one straight, steady leg (the stepper's
        refills: the Python cost of a block's anchor, ~0.3 ms, is paid once per span instead of per block)."""
        if first % BLOCK or nblocks < 1:
            raise ValueError(f"TowPointBuffer.span: first must be a multiple of {BLOCK} and nblocks >= 1 "
                             f"(got first={first}, nblocks={nblocks})")
        count = nblocks * BLOCK
        if nblocks == 1 or not self.recurrence_possible():
            return self.block(first, count, mean=True)
        t = (first + np.arange(count)) * self.sim.settings.dt
        anchors = t[::BLOCK]
        lin = self._linear_anchors(anchors, float(t[-1]))
        if lin is None:                                   # a manoeuvre inside the span: block by block
            return self.block(first, count, mean=True)
        E, (rr, ri, gr, gi) = lin
        osc = np.empty((count, 3))
        for k in range(nblocks):
            _phase_recurrence(E[k].real.copy(), E[k].imag.copy(), rr, ri, gr, gi, osc[k * BLOCK:(k + 1) * BLOCK])
        x, psi, _ = self.path.mean_path(t)
        pos = x + osc * self.path.ramp(t)[:, None]
        return pos, np.column_stack([x, psi])

    def _linear_anchors(self, t_a, t_b):
        """:meth:`_linear` for several anchors ``t_a`` (increasing) at once, the last block ending at ``t_b``:
        (E (len(t_a), M), per-step rotation, gains) if the phases are linear in t on [t_a[0], t_b], else None.
        The same element-wise arithmetic as :meth:`_linear` at each anchor (the same bits)."""
        leg = self._leg(float(t_a[0]), t_b)
        if leg is None:
            return None
        vm, i, p = leg
        xy, psi, U = vm._path(np.asarray(t_a, float))
        rg = self._rotation_and_gains(vm, i, p, U, psi)
        P = t_a[:, None] * vm._w - xy[:, 0:1] * vm._kx - xy[:, 1:2] * vm._ky + vm._phi
        E = np.exp(1j * P) * vm._a
        return E, rg

    def _aligned(self, first, count, with_mean=False):
        """Steps first … first+count−1 inside one aligned block (anchor = the block's first step); with
        ``with_mean`` also the mean track ``path.mean_path`` of those steps' times."""
        dt = self.sim.settings.dt
        a = (first // BLOCK) * BLOCK
        t = (a + np.arange(first - a + count)) * dt
        lin = self._linear(float(t[0]), float(t[-1]))
        t = t[first - a:]
        if lin is None:
            pos = self.path.position(t)
            return (pos, self.path.mean_path(t)) if with_mean else pos
        E, (rr, ri, gr, gi) = lin
        osc = np.empty((first - a + count, 3))
        _phase_recurrence(E.real.copy(), E.imag.copy(), rr, ri, gr, gi, osc)
        mp = self.path.mean_path(t)
        pos = mp[0] + osc[first - a:] * self.path.ramp(t)[:, None]
        return (pos, mp) if with_mean else pos
