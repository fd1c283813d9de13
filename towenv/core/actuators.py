"""Actuators: the heave-compensator sheave node (passive spring/damper, locked, position or force
command) with its end stops, and the winch's payout speed (speed command or constant tension) within its
speed and acceleration limits.
"""
from __future__ import annotations

import math


from .jit import njit
from .layout import (COMP_FORCE, COMP_LOCKED, COMP_POSITION, C_B, C_K, C_MASS, C_PRELOAD, C_SMAX, C_SMIN, C_TRIAL,
                     WINCH_TENSION, WS_LEN, WS_V, W_AMAX, W_DEADBAND, W_GAIN, W_LMAX, W_LMIN, W_MODE, W_SEG, W_TSET,
                     W_VCMD, W_VMAX)


@njit(cache=True)
def _compensator_node(a, ship, comp, cmode, act, dt, rs, r_t, r_tm1, r_tm2, node_nseg, node_segs, tang, stretched,
                      tens, mnode, bnode, fnode, acon, qvec):
    """Heave-compensator sheave (model.md 2.7, Hover §IV-A): the cable's top node moves with the ship
    tow point except along e_c = e_z, where its stroke z obeys

        m_eff z̈ = e·(Σ σ T t + F_o) − k z − b ż + F_pre − e·M_n a_ship − m_c a_ship,z  (+ end stops),
        m_eff = m_c + e·M_n e,

    F_pre being the preload that holds the static cable force at mid-stroke (Hover's model is linear
    about the mean). Houbolt gives z = A_c + Σ σ T q_k, written into ``acon``/``qvec`` in the same form
    as a free node, so the tension Jacobian picks up the compensator term by the general rule.
    Locked and position-controlled sheaves are prescribed (q = 0)."""
    idt2 = 1.0 / (dt * dt)
    z_t = r_t[a, 2] - r_t[ship, 2]
    z_tm1 = r_tm1[a, 2] - r_tm1[ship, 2]
    z_tm2 = r_tm2[a, 2] - r_tm2[ship, 2]
    ns = node_nseg[a]
    contact = comp[C_TRIAL]
    if cmode == COMP_LOCKED or cmode == COMP_POSITION or contact != 0.0:
        if contact > 0.0:
            znew = comp[C_SMAX]
        elif contact < 0.0:
            znew = comp[C_SMIN]
        else:
            znew = z_t if cmode == COMP_LOCKED else act
        for i in range(3):
            acon[a, i] = rs[ship, i]
        acon[a, 2] += znew
        for k in range(ns):
            for i in range(3):
                qvec[a, k, i] = 0.0
        return
    a_ship0 = (2.0 * rs[ship, 0] - 5.0 * r_t[ship, 0] + 4.0 * r_tm1[ship, 0] - r_tm2[ship, 0]) * idt2
    a_ship1 = (2.0 * rs[ship, 1] - 5.0 * r_t[ship, 1] + 4.0 * r_tm1[ship, 1] - r_tm2[ship, 1]) * idt2
    a_ship2 = (2.0 * rs[ship, 2] - 5.0 * r_t[ship, 2] + 4.0 * r_tm1[ship, 2] - r_tm2[ship, 2]) * idt2
    m_eff = comp[C_MASS] + mnode[a, 2, 2]
    h_z = 2.5 * z_t - 2.0 * z_tm1 + 0.5 * z_tm2
    zd_hist = (-18.0 * z_t + 9.0 * z_tm1 - 2.0 * z_tm2) / (6.0 * dt)
    c116 = 11.0 / (6.0 * dt)
    z_star = rs[a, 2] - rs[ship, 2]
    kk = comp[C_K]
    bb = comp[C_B]
    rhs = 2.0 * m_eff * h_z * idt2 - bb * zd_hist + comp[C_PRELOAD]
    if cmode == COMP_FORCE:
        rhs += act
    # loads on the node along e, the ship-acceleration (transport) terms, implicit drag and string stiffness
    beb = bnode[a, 2, 2]
    kg = 0.0
    for k in range(ns):
        sk = node_segs[a, k]
        if stretched[sk] > 0.0:
            kg += tens[sk] / stretched[sk] * (1.0 - tang[sk, 2] * tang[sk, 2])
    rhs += fnode[a, 2] - (mnode[a, 2, 0] * a_ship0 + mnode[a, 2, 1] * a_ship1 + mnode[a, 2, 2] * a_ship2) \
        - comp[C_MASS] * a_ship2 + (c116 * beb + kg) * z_star
    d = 2.0 * m_eff * idt2 + kk + c116 * (bb + beb) + kg
    for i in range(3):
        acon[a, i] = rs[ship, i]
    acon[a, 2] += rhs / d
    for k in range(ns):
        s = node_segs[a, k]
        qvec[a, k, 0] = 0.0
        qvec[a, k, 1] = 0.0
        qvec[a, k, 2] = tang[s, 2] / d


@njit(cache=True)
def _end_stop_force(a, ship, comp, dt, rs, r_t, r_tm1, r_tm2, node_nseg, node_segs, node_sgn, tang, tens,
                    mnode, fnode):
    """Force the end stop must exert on the sheave (+ up) to hold it where it is: the residual of the
    sheave equation at the converged step (used to release a contact that would have to pull)."""
    idt2 = 1.0 / (dt * dt)
    z = rs[a, 2] - rs[ship, 2]
    z_t = r_t[a, 2] - r_t[ship, 2]
    z_tm1 = r_tm1[a, 2] - r_tm1[ship, 2]
    z_tm2 = r_tm2[a, 2] - r_tm2[ship, 2]
    zdd = (2.0 * z - 5.0 * z_t + 4.0 * z_tm1 - z_tm2) * idt2
    zd = (11.0 * z - 18.0 * z_t + 9.0 * z_tm1 - 2.0 * z_tm2) / (6.0 * dt)
    a0 = (2.0 * rs[ship, 0] - 5.0 * r_t[ship, 0] + 4.0 * r_tm1[ship, 0] - r_tm2[ship, 0]) * idt2
    a1 = (2.0 * rs[ship, 1] - 5.0 * r_t[ship, 1] + 4.0 * r_tm1[ship, 1] - r_tm2[ship, 1]) * idt2
    a2 = (2.0 * rs[ship, 2] - 5.0 * r_t[ship, 2] + 4.0 * r_tm1[ship, 2] - r_tm2[ship, 2]) * idt2
    f = fnode[a, 2] - comp[C_K] * z - comp[C_B] * zd + comp[C_PRELOAD] \
        - (mnode[a, 2, 0] * a0 + mnode[a, 2, 1] * a1 + mnode[a, 2, 2] * a2) - comp[C_MASS] * a2
    for k in range(node_nseg[a]):
        s = node_segs[a, k]
        f += node_sgn[a, k] * tens[s] * tang[s, 2]
    return (comp[C_MASS] + mnode[a, 2, 2]) * zdd - f


@njit(cache=True)
def _winch_speed(winch, wstate, tens_hist, dt):
    """Payout speed for the next step (payout > 0): the command (or the constant-tension law), limited
    in acceleration and speed, and clipped so the deployed length stays within [L_min, L_max]."""
    mode = int(winch[W_MODE])
    v = wstate[WS_V]
    if mode == WINCH_TENSION:
        err = tens_hist[0, int(winch[W_SEG])] - winch[W_TSET]
        if abs(err) <= winch[W_DEADBAND]:
            vcmd = 0.0
        else:
            vcmd = winch[W_GAIN] * (err - math.copysign(winch[W_DEADBAND], err))
    else:
        vcmd = winch[W_VCMD]
    dv = vcmd - v
    amax = winch[W_AMAX] * dt
    if dv > amax:
        dv = amax
    elif dv < -amax:
        dv = -amax
    v = v + dv
    if v > winch[W_VMAX]:
        v = winch[W_VMAX]
    elif v < -winch[W_VMAX]:
        v = -winch[W_VMAX]
    length = wstate[WS_LEN] + v * dt
    if length > winch[W_LMAX]:
        v = (winch[W_LMAX] - wstate[WS_LEN]) / dt
    elif length < winch[W_LMIN]:
        v = (winch[W_LMIN] - wstate[WS_LEN]) / dt
    return v
