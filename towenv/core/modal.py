"""Natural frequencies of the lumped-mass model, linearised about its current (static) state.

Mass: the node mass matrices of the dynamic model (dry + added mass, point bodies, rigid bodies
condensed onto their tow-point node as Λᵀ A_eff Λ — translational degrees of freedom only).
Stiffness: per segment the consistent tangent ``(EA/l) t tᵀ + (T/ℓ)(1 − t tᵀ)`` (the elastic axial part
the thesis's (5.168) omits, erratum E19, plus the geometric string part) coupling its two end nodes.
Prescribed nodes (vessel, anchors, aft tow points) are held fixed.
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import eigh

from . import kernels as K


def mass_and_stiffness(sim):
    """Return (M, Kmat, free_nodes) for the free nodes of a Simulator at its current state."""
    s = sim.system
    r = sim.positions
    v = np.zeros_like(r)
    ws = sim._ws
    tang, stretched, drag, bmat, madd, mnode, bnode, fnode = ws[:8]
    K.segment_loads(r, v, s.seg_lo, s.seg_up, s.l0, s.diam, s.mu, s.cn, s.ct, s.can, s.cat, s.rho, s.g,
                    s.cur_z, s.cur_v, tang, stretched, drag, bmat, madd)
    K.node_assembly(r, v, s.node_kind, s.node_nseg, s.node_segs, s.node_sgn, s.l0, s.diam, s.mu, s.rho, s.g,
                    drag, bmat, madd, s.pb_mass, s.pb_vol, s.pb_cda, s.pb_ca, s.cur_z, s.cur_v, mnode, bnode, fnode)
    mn = mnode.copy()
    # rigid bodies: effective translational mass at the tow point
    for b in range(s.n_rigid):
        a = s.body_node[b]
        att = np.empty((3, 3))
        atr = np.empty((3, 3))
        arr = np.empty((3, 3))
        K.body_mass_blocks(b, s.bp, att, atr, arr)
        aeff = att - atr @ np.linalg.solve(arr, atr.T)
        ang = sim.hist_ang[0, b]
        lam = np.empty((3, 3))
        K.rotation_matrix(ang[0], ang[1], ang[2], lam)
        mn[a] += lam.T @ aeff @ lam
    free = np.where(s.node_kind == K.FREE)[0]
    index = -np.ones(s.n_nodes, int)
    index[free] = np.arange(len(free))
    n = 3 * len(free)
    M = np.zeros((n, n))
    Km = np.zeros((n, n))
    for a in free:
        i = 3 * index[a]
        M[i:i + 3, i:i + 3] = mn[a]
    tens = sim.tensions
    for seg in range(s.n_segments):
        t = tang[seg]
        tt = np.outer(t, t)
        k_el = 0.0 if np.isinf(s.ea[seg]) else s.ea[seg] / s.l0[seg]
        if np.isinf(s.ea[seg]):
            raise ValueError("modal analysis needs a finite EA on every segment")
        ks = k_el * tt + tens[seg] / stretched[seg] * (np.eye(3) - tt)
        ends = (s.seg_lo[seg], s.seg_up[seg])
        for x in ends:
            for y in ends:
                if index[x] < 0 or index[y] < 0:
                    continue
                sign = 1.0 if x == y else -1.0
                i, j = 3 * index[x], 3 * index[y]
                Km[i:i + 3, j:j + 3] += sign * ks
    return M, Km, free


def natural_frequencies(sim, n_modes: int | None = None):
    """Natural frequencies (rad/s, ascending) and mode shapes (3·n_free, n_modes) of the linearised model."""
    M, Km, _ = mass_and_stiffness(sim)
    w2, vecs = eigh(0.5 * (Km + Km.T), 0.5 * (M + M.T))
    w = np.sqrt(np.clip(w2, 0.0, None))
    if n_modes is not None:
        return w[:n_modes], vecs[:, :n_modes]
    return w, vecs
