"""Explicit time integration of the same lumped-mass model (the kind of scheme MoorDyn uses).

Same scene, same loads (``segment_loads``, ``node_assembly``, ``body_loads``, ``condense_body``); only
the time integration differs: segments are tension-only springs ``T = max(EA ε + c ε̇, 0)``
(``c`` = axial damping, N·s, default 0) and the state (positions, velocities, body Euler angles and
body rates) is advanced with semi-implicit Euler, RK2 (midpoint) or RK4. These schemes are stable only
below the axial CFL limit ``Δt ≲ l_min/c_L`` (model.md 8.2; verification.md V4); beyond it the run
blows up, which is detected (non-finite state, strain above ``max_strain`` or pitch beyond ±85°) and
reported as :class:`towenv.SimulationDivergence` — never returned as NaN.

Compensator and winch scenes are not supported by this integrator.
"""
from __future__ import annotations

import math

import numpy as np
from .layout import BP_AFT_TOW_POINT, BP_CB
from numba import njit

from . import kernels as K
from .model import ExplicitWork
from .schemes import TimeScheme
from .simulator import Simulator

EULER, RK2, RK4 = 0, 1, 2
SCHEMES = {"euler": EULER, "rk2": RK2, "rk4": RK4}


@njit(cache=True)
def _rates(r, v, ang, omg, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, out_a, out_dang, out_domg, tens):
    """Accelerations of the free nodes, Euler-angle rates and body angular accelerations at a state.
    Prescribed nodes take ``top_r/top_v`` (vessel) or follow their body (aft tow points)."""
    seg_lo, seg_up, seg_uplocal, node_kind = topo.seg_lo, topo.seg_up, topo.seg_uplocal, topo.node_kind
    node_nseg, node_segs, node_sgn, order, pos = topo.node_nseg, topo.node_segs, topo.node_sgn, topo.order, topo.pos
    body_node, body_aft_node = topo.body_node, topo.body_aft_node
    l0, diam, mu, cn, ct, can, cat, ea = segp.l0, segp.diam, segp.mu, segp.cn, segp.ct, segp.can, segp.cat, segp.ea
    bp, btab_n, btab, pb_mass, pb_vol = bodyp.bp, bodyp.btab_n, bodyp.btab, bodyp.pb_mass, bodyp.pb_vol
    pb_cda, pb_ca = bodyp.pb_cda, bodyp.pb_ca
    rho, g, cur_z, cur_v = env.rho, env.g, env.cur_z, env.cur_v
    tang, stretched, drag, bmat, madd, mnode = ws.tang, ws.stretched, ws.drag, ws.bmat, ws.madd, ws.mnode
    bnode, fnode, lam, tmp3, fb, mb, att, atr = ws.bnode, ws.fnode, ws.lam, ws.tmp3, ws.fb, ws.mb, ws.att, ws.atr
    arr, arrinv, hvec, aeff, bX, by, react = ws.arr, ws.arrinv, ws.hvec, ws.aeff, ws.bX, ws.by, ws.react
    cur_b, minv, bdiag, wbody = ws.cur_b, ws.minv, ws.bdiag, ws.wbody
    nn = node_kind.shape[0]
    ns = l0.shape[0]
    nb = body_node.shape[0]
    # aft tow points ride on their body
    for b in range(nb):
        c = body_aft_node[b]
        if c < 0:
            continue
        K.rotation_matrix(ang[b, 0], ang[b, 1], ang[b, 2], lam)
        a = body_node[b]
        _cross_add(omg[b], bp[b, BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3], lam, v[a], r[a], r[c], v[c])
    K.segment_loads(r, v, seg_lo, seg_up, l0, diam, mu, cn, ct, can, cat, rho, g, cur_z, cur_v,
                    tang, stretched, drag, bmat, madd)
    K.node_assembly(r, v, node_kind, node_nseg, node_segs, node_sgn, l0, diam, mu, rho, g, drag, bmat, madd,
                    pb_mass, pb_vol, pb_cda, pb_ca, cur_z, cur_v, mnode, bnode, fnode)
    for s in range(ns):
        p = seg_lo[s]
        q = seg_up[s]
        strain = stretched[s] / l0[s] - 1.0
        rate = 0.0
        for i in range(3):
            rate += (v[q, i] - v[p, i]) * tang[s, i]
        t = ea[s] * strain + c_axial[s] * rate / l0[s]
        tens[s] = t if (t > 0.0 and strain > 0.0) else 0.0
    # tension forces into fnode
    for s in range(ns):
        p = seg_lo[s]
        q = seg_up[s]
        for i in range(3):
            fnode[p, i] += tens[s] * tang[s, i]
            fnode[q, i] -= tens[s] * tang[s, i]
    # rigid bodies, condensed onto their tow-point node
    for b in range(nb):
        a = body_node[b]
        K.rotation_matrix(ang[b, 0], ang[b, 1], ang[b, 2], lam)
        for i in range(3):
            tmp3[i] = lam[i, 0] * v[a, 0] + lam[i, 1] * v[a, 1] + lam[i, 2] * v[a, 2]
        zc = r[a, 2] + lam[0, 2] * bp[b, BP_CB] + lam[1, 2] * bp[b, BP_CB + 1] + lam[2, 2] * bp[b, BP_CB + 2]
        K.current_at(zc, cur_z, cur_v, cur_b)
        for i in range(3):
            wbody[i] = omg[b, i]
        K.body_loads(b, lam, tmp3, wbody, bp, btab_n, btab, rho, g, cur_b, fb, mb, bdiag)
        c = body_aft_node[b]
        if c >= 0:
            # force of the tail cable on the aft point (its own half-segment loads included, inertia not)
            for i in range(3):
                react[i] = fnode[c, i]
        if not K.condense_body(b, a, c >= 0, lam, wbody, react, bp, fb, mb, att, atr, arr, arrinv, hvec, tmp3, aeff,
                               bX[b], by[b], mnode, fnode):
            return False
    for a in range(nn):
        if node_kind[a] != K.FREE:
            for i in range(3):
                out_a[a, i] = 0.0
            continue
        if not K._inv3(mnode[a], minv):
            return False
        for i in range(3):
            out_a[a, i] = minv[i, 0] * fnode[a, 0] + minv[i, 1] * fnode[a, 1] + minv[i, 2] * fnode[a, 2]
    for b in range(nb):
        a = body_node[b]
        K.rotation_matrix(ang[b, 0], ang[b, 1], ang[b, 2], lam)
        for i in range(3):
            tmp3[i] = lam[i, 0] * out_a[a, 0] + lam[i, 1] * out_a[a, 1] + lam[i, 2] * out_a[a, 2]
        for i in range(3):
            out_domg[b, i] = by[b, i] - (bX[b, i, 0] * tmp3[0] + bX[b, i, 1] * tmp3[1] + bX[b, i, 2] * tmp3[2])
        # Euler-angle rates from body rates (model.md 1.4)
        cb = math.cos(ang[b, 0])
        sb = math.sin(ang[b, 0])
        ca = math.cos(ang[b, 1])
        ta = math.sin(ang[b, 1]) / ca
        p_ = omg[b, 0]
        q_ = omg[b, 1]
        r_ = omg[b, 2]
        out_dang[b, 0] = p_ + (q_ * sb + r_ * cb) * ta
        out_dang[b, 1] = q_ * cb - r_ * sb
        out_dang[b, 2] = (q_ * sb + r_ * cb) / ca
    return True


@njit(cache=True)
def _cross_add(w, rt, lam, v_tp, r_tp, r_out, v_out):
    """Position and velocity of an aft tow point rigidly carried by its body."""
    for i in range(3):
        r_out[i] = r_tp[i] + lam[0, i] * rt[0] + lam[1, i] * rt[1] + lam[2, i] * rt[2]
    # ω × r_t in body axes, rotated to global
    c0 = w[1] * rt[2] - w[2] * rt[1]
    c1 = w[2] * rt[0] - w[0] * rt[2]
    c2 = w[0] * rt[1] - w[1] * rt[0]
    for i in range(3):
        v_out[i] = v_tp[i] + lam[0, i] * c0 + lam[1, i] * c1 + lam[2, i] * c2


@njit(cache=True)
def explicit_advance(n_steps, dt, scheme, top_path, top_prev, top_node, topo, segp, bodyp, env, c_axial, max_strain,
                     r, v, ang, omg, tens, ws, k1, k2, k3, k4):
    """Advance ``n_steps`` explicit steps. ``top_path[k]`` is the tow point at the end of step k and
    ``top_prev`` at the start of the run (linear in between). Returns (status, step, element)."""
    nn = r.shape[0]
    nb = ang.shape[0]
    r0 = np.empty_like(r)
    v0 = np.empty_like(v)
    a0 = np.empty_like(ang)
    w0 = np.empty_like(omg)
    t0 = np.empty_like(tens)
    top_r = np.empty(3)
    top_v = np.empty(3)
    prev = np.empty(3)
    for i in range(3):
        prev[i] = top_prev[i]
    for k in range(n_steps):
        for i in range(3):
            top_v[i] = (top_path[k, i] - prev[i]) / dt
        r0[:] = r
        v0[:] = v
        a0[:] = ang
        w0[:] = omg
        t0[:] = tens
        nst = 1 if scheme == EULER else (2 if scheme == RK2 else 4)
        for stage in range(nst):
            if scheme == RK2:
                frac = 0.0 if stage == 0 else 0.5
            elif scheme == RK4:
                frac = 0.0 if stage == 0 else (0.5 if stage < 3 else 1.0)
            else:
                frac = 0.0
            kk = k1 if stage == 0 else (k2 if stage == 1 else (k3 if stage == 2 else k4))
            if stage > 0:
                prevk = k1 if stage == 1 else (k2 if stage == 2 else k3)
                h = frac * dt
                for a in range(nn):
                    for i in range(3):
                        r[a, i] = r0[a, i] + h * prevk[0][a, i]
                        v[a, i] = v0[a, i] + h * prevk[1][a, i]
                for b in range(nb):
                    for i in range(3):
                        ang[b, i] = a0[b, i] + h * prevk[2][b, i]
                        omg[b, i] = w0[b, i] + h * prevk[3][b, i]
            for i in range(3):
                top_r[i] = prev[i] + frac * dt * top_v[i]
                r[top_node, i] = top_r[i]
                v[top_node, i] = top_v[i]
            if not _rates(r, v, ang, omg, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, kk[1], kk[2], kk[3], tens):
                _restore(r, v, ang, omg, tens, r0, v0, a0, w0, t0)
                return K.FAIL_NAN, k, -1
            for a in range(nn):
                for i in range(3):
                    kk[0][a, i] = v[a, i]
        if scheme == EULER:
            # semi-implicit (symplectic) Euler: v first, then r with the new v
            for a in range(nn):
                for i in range(3):
                    v[a, i] = v0[a, i] + dt * k1[1][a, i]
                    r[a, i] = r0[a, i] + dt * v[a, i]
            for b in range(nb):
                for i in range(3):
                    omg[b, i] = w0[b, i] + dt * k1[3][b, i]
                    ang[b, i] = a0[b, i] + dt * k1[2][b, i]
        elif scheme == RK2:
            for a in range(nn):
                for i in range(3):
                    r[a, i] = r0[a, i] + dt * k2[0][a, i]
                    v[a, i] = v0[a, i] + dt * k2[1][a, i]
            for b in range(nb):
                for i in range(3):
                    ang[b, i] = a0[b, i] + dt * k2[2][b, i]
                    omg[b, i] = w0[b, i] + dt * k2[3][b, i]
        else:
            for a in range(nn):
                for i in range(3):
                    r[a, i] = r0[a, i] + dt / 6.0 * (k1[0][a, i] + 2 * k2[0][a, i] + 2 * k3[0][a, i] + k4[0][a, i])
                    v[a, i] = v0[a, i] + dt / 6.0 * (k1[1][a, i] + 2 * k2[1][a, i] + 2 * k3[1][a, i] + k4[1][a, i])
            for b in range(nb):
                for i in range(3):
                    ang[b, i] = a0[b, i] + dt / 6.0 * (k1[2][b, i] + 2 * k2[2][b, i] + 2 * k3[2][b, i] + k4[2][b, i])
                    omg[b, i] = w0[b, i] + dt / 6.0 * (k1[3][b, i] + 2 * k2[3][b, i] + 2 * k3[3][b, i] + k4[3][b, i])
        for i in range(3):
            r[top_node, i] = top_path[k, i]
            v[top_node, i] = top_v[i]
            prev[i] = top_path[k, i]
        # aft tow points are carried by their bodies, not integrated
        lam = ws.lam
        for b in range(nb):
            c = topo.body_aft_node[b]
            if c < 0:
                continue
            K.rotation_matrix(ang[b, 0], ang[b, 1], ang[b, 2], lam)
            a = topo.body_node[b]
            _cross_add(omg[b], bodyp.bp[b, BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3], lam, v[a], r[a], r[c], v[c])
        # failure detection
        for a in range(nn):
            for i in range(3):
                if not math.isfinite(r[a, i]) or not math.isfinite(v[a, i]):
                    _restore(r, v, ang, omg, tens, r0, v0, a0, w0, t0)
                    return K.FAIL_NAN, k, a
        ea = segp.ea
        l0 = segp.l0
        seg_lo = topo.seg_lo
        seg_up = topo.seg_up
        for s in range(l0.shape[0]):
            dx = r[seg_up[s], 0] - r[seg_lo[s], 0]
            dy = r[seg_up[s], 1] - r[seg_lo[s], 1]
            dz = r[seg_up[s], 2] - r[seg_lo[s], 2]
            if math.sqrt(dx * dx + dy * dy + dz * dz) / l0[s] - 1.0 > max_strain:
                _restore(r, v, ang, omg, tens, r0, v0, a0, w0, t0)
                return K.FAIL_STRETCH, k, s
        for b in range(nb):
            if abs(ang[b, 1]) > K.PITCH_LIMIT or not math.isfinite(ang[b, 1]):
                _restore(r, v, ang, omg, tens, r0, v0, a0, w0, t0)
                return K.FAIL_ANGLE, k, b
    return K.OK, -1, -1


@njit(cache=True)
def _restore(r, v, ang, omg, tens, r0, v0, a0, w0, t0):
    """Put the state of the last good step back after a failed one (the simulator keeps it)."""
    r[:] = r0
    v[:] = v0
    ang[:] = a0
    omg[:] = w0
    tens[:] = t0


class ExplicitScheme(TimeScheme):
    """The same scene integrated explicitly (``solver.method`` = "euler" (semi-implicit), "rk2" or "rk4").

    The start is the same quasi-static configuration; the explicit state is (positions, velocities, Euler
    angles, body rates), written back to the Simulator's history arrays after every call (outputs,
    snapshots)."""

    def __init__(self, sim, name: str = "rk2", axial_damping_ratio: float = 0.0):
        super().__init__(sim)
        if name not in SCHEMES:
            raise ValueError(f"scheme: must be one of {sorted(SCHEMES)} (got {name!r})")
        if not (axial_damping_ratio >= 0 and np.isfinite(axial_damping_ratio)):
            raise ValueError(f"axial_damping_ratio: must be >= 0 (got {axial_damping_ratio!r})")
        self.name = name
        self.axial_damping_ratio = float(axial_damping_ratio)

    def start(self):
        sim = self.sim
        s = sim.system
        # a damping ratio of each segment's axial mode, c = 2ζ l √(EA μ) (MoorDyn's BA = −2ζ gives the same c)
        self.axial_damping = 2 * self.axial_damping_ratio * s.l0 * np.sqrt(s.ea * s.mu)
        if sim.comp[K.C_MODE] > 0 or sim.winch[K.W_MODE] > 0:
            raise ValueError(f"solver.method = {self.name!r}: scenes with a compensator or winch are not supported")
        dt = sim.settings.dt
        self.xr = sim.hist_r[0].copy()
        self.xv = (3 * sim.hist_r[0] - 4 * sim.hist_r[1] + sim.hist_r[2]) / (2 * dt)
        self.xang = sim.hist_ang[0].copy()
        self.xomg = np.zeros_like(self.xang)
        for b in range(s.n_rigid):
            dang = (3 * sim.hist_ang[0, b] - 4 * sim.hist_ang[1, b] + sim.hist_ang[2, b]) / (2 * dt)
            K.euler_rates_to_omega(sim.hist_ang[0, b], dang, self.xomg[b])
        self.xtens = sim.tens_hist[0].copy()
        nn, nb = s.n_nodes, s.n_rigid
        z = np.zeros
        self._xws = ExplicitWork.allocate(nn, s.n_segments, nb)
        self._k = [(z((nn, 3)), z((nn, 3)), z((nb, 3)), z((nb, 3))) for _ in range(4)]
        self._x_initial = (self.xr.copy(), self.xv.copy(), self.xang.copy(), self.xomg.copy(), self.xtens.copy())

    def reset(self):
        for dst, src in zip((self.xr, self.xv, self.xang, self.xomg, self.xtens), self._x_initial):
            dst[...] = src

    def run(self, tops, dt, t_start):
        sim = self.sim
        s = sim.system
        prev = self.xr[s.top_node].copy()
        st, k, el = explicit_advance(len(tops), dt, SCHEMES[self.name], tops, prev, s.top_node, s.topo(), s.segp(),
                                     s.bodyp(), s.env(), self.axial_damping, sim.settings.max_strain, self.xr,
                                     self.xv, self.xang, self.xomg, self.xtens, self._xws, *self._k)
        self._sync()
        if st != K.OK:
            from ..errors import SimulationDivergence
            if st == K.FAIL_ANGLE:
                cause = K.NO_CHART_REFUSAL.format(scheme=f"explicit {self.name}")
            else:
                cause = f"explicit {self.name} step unstable: " + {
                    K.FAIL_NAN: "non-finite state",
                    K.FAIL_STRETCH: f"strain above solver.max_strain = {sim.settings.max_strain:g}"}.get(st, str(st))
            raise SimulationDivergence(t_start + (k + 1) * dt, self._explicit_element(st, el),
                                       cause + f" (Δt = {dt:g} s; the state is left at the last good step)")

    def _explicit_element(self, st, el):
        if st == K.FAIL_NAN and el >= 0:
            return self.sim._node_name(el)
        return self.sim._element_name(st, el)

    def _sync(self):
        """Expose the explicit state through the Simulator's history arrays (outputs, snapshots)."""
        sim = self.sim
        dt = sim.settings.dt
        sim.hist_r[0] = self.xr
        sim.hist_r[1] = self.xr - dt * self.xv
        sim.hist_r[2] = self.xr - 2 * dt * self.xv
        sim.tens_hist[1] = sim.tens_hist[0]
        sim.tens_hist[0] = self.xtens
        sim.forget_step_memory()
        for b in range(sim.system.n_rigid):
            # angle history consistent with the current Euler-angle rates
            ca, sb, cb = np.cos(self.xang[b, 1]), np.sin(self.xang[b, 0]), np.cos(self.xang[b, 0])
            p, q, r = self.xomg[b]
            dang = np.array([p + (q * sb + r * cb) * np.tan(self.xang[b, 1]), q * cb - r * sb, (q * sb + r * cb) / ca])
            sim.hist_ang[0, b] = self.xang[b]
            sim.hist_ang[1, b] = self.xang[b] - dt * dang
            sim.hist_ang[2, b] = self.xang[b] - 2 * dt * dang
        # tow-point reaction: tension and half-segment loads at the top node; unlike the implicit solver's
        # reaction it leaves out the top node's own inertia (m_node · a, a few N on the peer deck)
        sim.top_react[...] = self._xws.fnode[sim.system.top_node]

    def snapshot(self, snap):
        snap.explicit = tuple(a.copy() for a in (self.xr, self.xv, self.xang, self.xomg, self.xtens))

    def restore(self, snap):
        if hasattr(snap, "explicit"):
            for dst, src in zip((self.xr, self.xv, self.xang, self.xomg, self.xtens), snap.explicit):
                dst[...] = src


def ExplicitSimulator(scene, scheme: str = "rk2", axial_damping_ratio: float = 0.0, **overrides) -> Simulator:
    """A :class:`~towenv.core.simulator.Simulator` whose ``solver.method`` is the explicit ``scheme``
    ("euler", "rk2", "rk4") — shorthand for ``Simulator(scene, method=scheme, axial_damping_ratio=…)``."""
    if scheme not in SCHEMES:
        raise ValueError(f"scheme: must be one of {sorted(SCHEMES)} (got {scheme!r})")
    if isinstance(axial_damping_ratio, bool) or not (axial_damping_ratio >= 0 and np.isfinite(axial_damping_ratio)):
        raise ValueError(f"axial_damping_ratio: must be >= 0 (got {axial_damping_ratio!r})")
    return Simulator(scene, **{**overrides, "solver.method": scheme, "solver.axial_damping_ratio": float(axial_damping_ratio)})
