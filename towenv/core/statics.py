"""Quasi-static initial configuration (model.md 4.3), consistent with the lumped-mass discretisation.

The system is towed steadily at velocity ``U`` (every node moves with the tow point) through the
current. Marching from the free ends toward the ship, each node's equilibrium gives the force its
upward segment must carry, ``T_u t_u = Σ_down T_d t_d − F_node(t_u)`` (the node's half-segment drag
depends on ``t_u``, so it is a small fixed-point iteration per node). Rigid bodies first find their
static pitch by a root-find on the pitch moment about the tow point, with yaw along the relative flow
and zero roll. Positions then follow from the ship downward with the stretched lengths
``l(1 + T/EA)`` (the sign of the thesis's (4.8) is corrected). Depth-dependent current is handled by
repeating the two passes. The dynamic solver then settles the remaining 3-D details.
"""
from __future__ import annotations

import math

import numpy as np
from .layout import BP_AFT_TOW_POINT

from .cable_loads import morison_drag
from .kernels import FREE, PRESCRIBED_AFT, body_loads, current_at, rotation_matrix
from .system import System


def _segment_drag(t, vrel, rho, diam, l0, cn, ct):
    """Morison drag of a whole segment (the kernels' :func:`~towenv.core.cable_loads.morison_drag`)."""
    return np.array(morison_drag(vrel[0], vrel[1], vrel[2], t[0], t[1], t[2], 0.5 * rho * cn * diam * l0,
                                 0.5 * rho * ct * diam * l0))


def _current(sys: System, z):
    out = np.empty(3)
    current_at(float(z), sys.cur_z, sys.cur_v, out)
    return out


def body_static_load(sys: System, ib: int, U, z, tail_force=None, pitch=None):
    """Global force of rigid body ``ib`` on its tow-point node, and its static Euler angles.

    If ``pitch`` is None it is found from the pitch-moment balance about the tow point."""
    cur = _current(sys, z)
    vrel = np.asarray(U, float) - cur
    yaw = math.atan2(vrel[1], vrel[0]) if np.hypot(vrel[0], vrel[1]) > 1e-9 else 0.0
    lam = np.empty((3, 3))
    f = np.empty(3)
    m = np.empty(3)
    bd = np.empty(1)
    w0 = np.zeros(3)
    bp = sys.bp

    def loads(alpha):
        rotation_matrix(0.0, alpha, yaw, lam)
        vb = lam @ np.asarray(U, float)
        body_loads(ib, lam, vb, w0, bp, sys.btab_n, sys.btab, sys.rho, sys.g, cur, f, m, bd)
        ff = f.copy()
        mm = m.copy()
        if tail_force is not None:
            fb = lam @ tail_force
            ff += fb
            mm += np.cross(bp[ib, BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3], fb)
        return ff, mm, lam.copy()

    if pitch is None:
        from scipy.optimize import brentq          # imported on first use: `import towenv` stays light
        grid = np.radians(np.linspace(-70, 70, 141))
        my = np.array([loads(a)[1][1] for a in grid])
        roots = []
        for i in range(len(grid) - 1):
            if my[i] == 0.0:
                roots.append(grid[i])
            elif my[i] * my[i + 1] < 0 and my[i] > 0:   # stable root: moment decreasing through zero
                roots.append(brentq(lambda a: loads(a)[1][1], grid[i], grid[i + 1], xtol=1e-12))
        if not roots:
            for i in range(len(grid) - 1):
                if my[i] * my[i + 1] < 0:
                    roots.append(brentq(lambda a: loads(a)[1][1], grid[i], grid[i + 1], xtol=1e-12))
        pitch = min(roots, key=abs) if roots else float(grid[np.argmin(np.abs(my))])
    ff, mm, lam = loads(pitch)
    return lam.T @ ff, np.array([0.0, pitch, yaw])


def quasi_static(sys: System, top_position, U, n_passes=None):
    """Return (node positions (N,3), segment tensions (S,), rigid-body Euler angles (B,3))."""
    U = np.asarray(U, float)
    nn, ns = sys.n_nodes, sys.n_segments
    r = np.zeros((nn, 3))
    r[sys.top_node] = top_position
    tens = np.zeros(ns)
    tang = np.zeros((ns, 3))
    ang = np.zeros((sys.n_rigid, 3))
    rigid_of_node = {int(sys.body_node[i]): i for i in range(sys.n_rigid)}
    aft_of_node = {int(sys.body_aft_node[i]): i for i in range(sys.n_rigid) if sys.body_aft_node[i] >= 0}
    uniform = sys.cur_z.shape[0] == 1
    passes = n_passes or (1 if uniform else 4)
    # initial guess of depths: lines hanging at 45 degrees
    for a in sys.post_order[::-1]:
        s = sys.node_up_seg[a]
        if s >= 0:
            r[a] = r[sys.seg_up[s]] + sys.l0[s] * np.array([-0.7071, 0.0, -0.7071])
        elif sys.node_parent[a] >= 0:
            r[a] = r[sys.node_parent[a]]
    g = sys.g
    reaction = {}
    for _ in range(passes):
        reaction.clear()
        for a in sys.post_order:
            a = int(a)
            if a == sys.top_node:
                continue
            # forces from below and own loads except those that depend on t_u
            f_fixed = np.zeros(3)
            down = []
            for k in range(sys.node_nseg[a]):
                s = sys.node_segs[a, k]
                if sys.node_sgn[a, k] < 0:       # a is the upper node of s: s hangs below a
                    down.append(s)
                    f_fixed -= tens[s] * tang[s]
                    vr = U - 0.5 * (_current(sys, r[a, 2]) + _current(sys, r[sys.seg_lo[s], 2]))
                    f_fixed += 0.5 * _segment_drag(tang[s], vr, sys.rho, sys.diam[s], sys.l0[s], sys.cn[s], sys.ct[s])
                wet = 0.5 * (sys.mu[s] - sys.rho * 0.25 * math.pi * sys.diam[s] ** 2) * g * sys.l0[s]
                f_fixed[2] -= wet
            if sys.pb_mass[a] > 0:
                f_fixed[2] -= (sys.pb_mass[a] - sys.rho * sys.pb_vol[a]) * g
                vr = U - _current(sys, r[a, 2])
                f_fixed -= 0.5 * sys.rho * sys.pb_cda[a] * np.linalg.norm(vr) * vr
            if a in rigid_of_node:
                ib = rigid_of_node[a]
                c = sys.body_aft_node[ib]
                tail = reaction.get(int(c)) if c >= 0 else None
                fb, ang[ib] = body_static_load(sys, ib, U, r[a, 2], tail)
                f_fixed += fb
            if sys.node_kind[a] == PRESCRIBED_AFT:
                reaction[a] = f_fixed.copy()       # force on the carrying body
                continue
            s = sys.node_up_seg[a]
            if s < 0:
                continue
            vr = U - 0.5 * (_current(sys, r[a, 2]) + _current(sys, r[sys.seg_up[s], 2]))
            t = -f_fixed / max(np.linalg.norm(f_fixed), 1e-300)
            if not np.all(np.isfinite(t)) or np.linalg.norm(f_fixed) == 0:
                t = np.array([0.0, 0.0, 1.0])
            for _it in range(200):
                fu = -(f_fixed + 0.5 * _segment_drag(t, vr, sys.rho, sys.diam[s], sys.l0[s], sys.cn[s], sys.ct[s]))
                nrm = np.linalg.norm(fu)
                if nrm == 0:
                    break
                t_new = fu / nrm
                # damped update for robustness with heavy drag
                t_new = 0.5 * (t_new + t)
                t_new /= np.linalg.norm(t_new)
                if np.max(np.abs(t_new - t)) < 1e-14:
                    t = t_new
                    break
                t = t_new
            fu = -(f_fixed + 0.5 * _segment_drag(t, vr, sys.rho, sys.diam[s], sys.l0[s], sys.cn[s], sys.ct[s]))
            tens[s] = max(float(fu @ t), 0.0)
            tang[s] = t
        # positions, from the ship downward
        for a in sys.post_order[::-1]:
            a = int(a)
            if a == sys.top_node:
                continue
            if a == sys.comp_node:
                r[a] = r[sys.top_node]
                continue
            if sys.node_kind[a] == PRESCRIBED_AFT:
                ib = aft_of_node[a]
                lam = np.empty((3, 3))
                rotation_matrix(ang[ib, 0], ang[ib, 1], ang[ib, 2], lam)
                r[a] = r[sys.body_node[ib]] + lam.T @ sys.bp[ib, BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3]
                continue
            s = sys.node_up_seg[a]
            stretch = 1.0 if np.isinf(sys.ea[s]) else 1.0 + tens[s] / sys.ea[s]
            r[a] = r[sys.seg_up[s]] - sys.l0[s] * stretch * tang[s]
    if sys.anchors:
        _anchored_lines(sys, r, tens)
    _ = FREE
    return r, tens, ang


def _anchored_lines(sys: System, r, tens):
    """Lines ending at an anchor start straight between their top node and the anchor, under the
    tension of their own weight; the dynamic settle (``solver.settle_time``) finds the true shape."""
    for lm in sys.lines:
        bottom = int(lm.nodes[-1])
        if bottom not in sys.anchors:
            continue
        top = r[int(lm.nodes[0])]
        anchor = sys.anchors[bottom]
        lengths = sys.l0[lm.segments]
        frac = np.concatenate([[0.0], np.cumsum(lengths) / lengths.sum()])
        for f, nd in zip(frac, lm.nodes):
            r[int(nd)] = top + f * (anchor - top)
        span = np.linalg.norm(anchor - top)
        w = np.abs((sys.mu[lm.segments] - sys.rho * 0.25 * np.pi * sys.diam[lm.segments] ** 2) * sys.g)
        strain = max(span / lengths.sum() - 1.0, 0.0)
        tens[lm.segments] = np.maximum(sys.ea[lm.segments] * strain, 0.5 * w * lengths.sum())
