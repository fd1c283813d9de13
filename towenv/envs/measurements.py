"""The environments' measurement row: what the sensors of a towed system read after a control step.

A *measurement row* is a float64 vector with one entry per name of :data:`MEAS_COLUMNS` (SI units; the
keys of :data:`towenv.envs.pieces.MEASUREMENTS`, plus the environment's own ``effort`` and ``time_left``).
:func:`measure_copy` fills it inside the compiled control step of :class:`towenv.envs.stepper.BatchStepper`
from a simulator's public state arrays (:func:`gather_arrays`) and the copy's per-episode reference values
(a row of ``refs``, indices ``R_*``): the tow-point motion reference unit (MRU), the sheave angle sensor,
tensions and the tension / breaking-load ratio, the towed body's heave, depth, pitch and rates and their
running means, the compensator and winch readings, the actuator effort and the fraction of the episode left.

Observers (:class:`towenv.envs.pieces.Observer`), rewards (:class:`~towenv.envs.pieces.HeavePitchReward`)
and terminations (:class:`~towenv.envs.pieces.Limits`) read the row by column (:data:`COL`). None of this
is physics: the simulator core (``towenv.core``) does not know the row.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..core import kernels as K
from ..core.jit import njit

__all__ = ["MEAS_COLUMNS", "COL", "NREF", "gather_arrays", "measure_copy"]

# ----------------------------------------------------------------------------------------------------
# layouts
# ----------------------------------------------------------------------------------------------------
MEAS_COLUMNS = ("t", "tow_vel_z", "tow_acc_z", "top_tension", "top_tension_ratio", "fish_heave", "fish_depth",
                "fish_pitch", "fish_heave_rate", "fish_pitch_rate", "min_tension", "tension_ratio",
                "comp_stroke", "comp_stroke_vel", "end_stop_hits", "comp_stiffness", "comp_damping",
                "winch_speed", "winch_length_dev", "winch_length", "effort", "time_left",
                # motion reference unit at the tow point (relative to the mean track, heading frame)
                "tow_surge", "tow_sway", "tow_heave", "tow_vel_x", "tow_vel_y", "tow_acc_x", "tow_acc_y",
                # sheave angle sensor, and the MRU motion projected on the top cable (payout-positive)
                "cable_angle", "cable_azimuth", "tow_disp_along", "tow_vel_along", "tow_acc_along",
                # fish heave / pitch about their running means (the reward's and the metrics' deviations)
                "fish_heave_dev", "fish_pitch_dev", "winch_power")
COL = {n: i for i, n in enumerate(MEAS_COLUMNS)}
(M_T, M_TOW_VEL, M_TOW_ACC, M_TOP_T, M_TOP_RATIO, M_HEAVE, M_DEPTH, M_PITCH, M_HEAVE_RATE, M_PITCH_RATE, M_MIN_T,
 M_T_RATIO, M_STROKE, M_STROKE_VEL, M_HITS, M_K, M_B, M_WSPEED, M_WLEN_DEV, M_WLEN, M_EFFORT,
 M_TIME_LEFT, M_SURGE, M_SWAY, M_TOW_HEAVE, M_TOW_VX, M_TOW_VY, M_TOW_AX, M_TOW_AY, M_CABLE_ANGLE, M_CABLE_AZ,
 M_DISP_ALONG, M_VEL_ALONG, M_ACC_ALONG, M_HEAVE_DEV, M_PITCH_DEV, M_WPOWER) = range(len(MEAS_COLUMNS))

#: per-copy reference values (float64 (B, NREF)), set by the caller at reset: ... R_MRU_DELAY = MRU output
#: delay (whole physics steps), R_MEAN_TAU = time constant of the running means (s; 0 = no running mean:
#: the deviations are then about the steady-tow values), R_HMEAN / R_PMEAN = the running means (state)
(R_ZREF, R_TREF, R_TOPINV, R_HALF_STROKE, R_VMAX, R_L0, R_HITS, R_STEPS, R_MAXSTEPS, R_EFFORT, R_MRU_DELAY,
 R_MEAN_TAU, R_HMEAN, R_PMEAN, R_PITCH0) = range(15)
NREF = 15


class Gathered(NamedTuple):
    """What :func:`measure_copy` reads of one Simulator (by reference)."""
    hist_r: np.ndarray
    hist_ang: np.ndarray
    chart: np.ndarray
    tens_hist: np.ndarray
    top_react: np.ndarray
    cstate: np.ndarray
    comp: np.ndarray            # compensator parameters (the environments write their commands here)
    winch: np.ndarray           # winch parameters (same)
    wstate: np.ndarray
    l0: np.ndarray
    idx: np.ndarray             # int64: tow-point node, body node, rigid index, sheave node, cable top node, node below
    wsegs: np.ndarray           # int64: the winch line's segments
    inv_seg: np.ndarray         # 1 / breaking load per segment


def gather_arrays(sim, body, inv_seg):
    """Arrays :func:`measure_copy` reads, from the Simulator's public state attributes (independent of the
    kernel tuples' layout): ``body`` is the towed body measured, ``inv_seg`` 1/breaking load per segment."""
    s = sim.system
    bm = s.body(body)
    comp_node = int(getattr(s, "comp_node", -1))
    wsegs = np.zeros(0, np.int64)
    if sim.winch[K.W_MODE] > 0:
        wsegs = np.asarray(s.line(sim.winch_line).segments, np.int64)
    ctop = int(s.cable_top_node)
    below = -1                          # the node below the cable's top node (the sheave angle sensor)
    for ln in s.lines:
        if len(ln.nodes) > 1 and int(ln.nodes[0]) == ctop:
            below = int(ln.nodes[1])
            break
    idx = np.array([int(s.top_node), int(bm.node), int(bm.rigid_index), comp_node, ctop, below], np.int64)
    return Gathered(sim.hist_r, sim.hist_ang, sim.body_chart, sim.tens_hist, sim.top_react, sim.cstate, sim.comp, sim.winch,
            sim.wstate, s.l0, idx, wsegs, np.ascontiguousarray(inv_seg, dtype=np.float64))


# ----------------------------------------------------------------------------------------------------
# kernels
# ----------------------------------------------------------------------------------------------------
@njit(cache=True)
def _mru(blk, mblk, o, dt, out):
    """Motion reference unit at buffer row ``o`` (clamped at 0): tow-point displacement, velocity and
    acceleration relative to the mean track, in global axes (out[0:3], [3:6], [6:9]) — the same backward
    differences as the vertical IMU channels — and the mean-track heading (out[9])."""
    o0 = max(o, 0)
    o1 = max(o - 1, 0)
    o2 = max(o - 2, 0)
    for i in range(3):
        d0 = blk[o0, i] - mblk[o0, i]
        d1 = blk[o1, i] - mblk[o1, i]
        d2 = blk[o2, i] - mblk[o2, i]
        out[i] = d0
        out[3 + i] = (3.0 * d0 - 4.0 * d1 + d2) / (2.0 * dt)
        out[6 + i] = (d0 - 2.0 * d1 + d2) / (dt * dt)
    out[9] = mblk[o0, 3]


@njit(cache=True)
def measure_copy(g, ref, dt, t, out, w3a, w3b, w3c, blk, mblk, o, n):
    """Fill measurement row ``out`` of one copy after ``n`` physics steps; the last step is row ``o`` of the
    copy's tow-point buffers ``blk`` (positions) / ``mblk`` (mean track x, y, z, heading)."""
    hist_r, hist_ang, chart, tens_hist, top_react, cstate = g.hist_r, g.hist_ang, g.chart, g.tens_hist, g.top_react, g.cstate
    comp, winch, wstate, l0, idx, wsegs, inv_seg = g.comp, g.winch, g.wstate, g.l0, g.idx, g.wsegs, g.inv_seg
    top = idx[0]
    node = idx[1]
    ri = idx[2]
    cn = idx[3]
    ctop = idx[4]
    below = idx[5]
    z0 = hist_r[0, top, 2]
    z1 = hist_r[1, top, 2]
    z2 = hist_r[2, top, 2]
    out[M_T] = t
    # motion reference unit (delayed by R_MRU_DELAY physics steps)
    mru = np.empty(10)
    _mru(blk, mblk, o - int(ref[R_MRU_DELAY]), dt, mru)
    cp = math.cos(mru[9])
    sp = math.sin(mru[9])
    out[M_TOW_VEL] = mru[5]
    out[M_TOW_ACC] = mru[8]
    out[M_SURGE] = cp * mru[0] + sp * mru[1]
    out[M_SWAY] = -sp * mru[0] + cp * mru[1]
    out[M_TOW_HEAVE] = mru[2]
    out[M_TOW_VX] = cp * mru[3] + sp * mru[4]
    out[M_TOW_VY] = -sp * mru[3] + cp * mru[4]
    out[M_TOW_AX] = cp * mru[6] + sp * mru[7]
    out[M_TOW_AY] = -sp * mru[6] + cp * mru[7]
    # sheave angle sensor: direction of the top cable segment (from the sheave down the cable)
    if below >= 0:
        ex = hist_r[0, below, 0] - hist_r[0, ctop, 0]
        ey = hist_r[0, below, 1] - hist_r[0, ctop, 1]
        ez = hist_r[0, below, 2] - hist_r[0, ctop, 2]
        en = math.sqrt(ex * ex + ey * ey + ez * ez)
        if en > 0.0:
            ex /= en
            ey /= en
            ez /= en
        out[M_CABLE_ANGLE] = math.atan2(-ez, math.sqrt(ex * ex + ey * ey))
        out[M_CABLE_AZ] = math.atan2(-sp * ex + cp * ey, -(cp * ex + sp * ey))
        # along-cable motion, payout-positive: the tow point moving away from the cable needs payout
        out[M_DISP_ALONG] = -(mru[0] * ex + mru[1] * ey + mru[2] * ez)
        out[M_VEL_ALONG] = -(mru[3] * ex + mru[4] * ey + mru[5] * ez)
        out[M_ACC_ALONG] = -(mru[6] * ex + mru[7] * ey + mru[8] * ez)
    else:
        out[M_CABLE_ANGLE] = 0.0
        out[M_CABLE_AZ] = 0.0
        out[M_DISP_ALONG] = 0.0
        out[M_VEL_ALONG] = 0.0
        out[M_ACC_ALONG] = 0.0
    tt = math.sqrt(top_react[0] * top_react[0] + top_react[1] * top_react[1] + top_react[2] * top_react[2])
    out[M_TOP_T] = tt
    out[M_TOP_RATIO] = tt / ref[R_TREF]
    z = hist_r[0, node, 2]
    out[M_HEAVE] = z - ref[R_ZREF]
    out[M_DEPTH] = -z
    out[M_HEAVE_RATE] = (3.0 * z - 4.0 * hist_r[1, node, 2] + hist_r[2, node, 2]) / (2.0 * dt)
    if ri >= 0:
        for i in range(3):
            w3a[i] = hist_ang[0, ri, i]
            w3b[i] = (3.0 * hist_ang[0, ri, i] - 4.0 * hist_ang[1, ri, i] + hist_ang[2, ri, i]) / (2.0 * dt)
        K.euler_rates_to_omega(w3a, w3b, w3c)      # body rates: independent of the attitude chart
        out[M_PITCH_RATE] = w3c[1]
        c = chart[ri]
        if c[0, 0] == 1.0 and c[1, 1] == 1.0 and c[2, 2] == 1.0:
            out[M_PITCH] = w3a[1]
        else:                                       # re-charted body: pitch of the physical attitude
            lam = np.empty((3, 3))
            K.body_rotation(w3a, c, lam)
            K.euler_from_rotation(lam, w3b)
            out[M_PITCH] = w3b[1]
    else:
        out[M_PITCH] = 0.0
        out[M_PITCH_RATE] = 0.0
    # running means (exponential, time constant R_MEAN_TAU; updated once per control step) and deviations
    tau = ref[R_MEAN_TAU]
    if tau > 0.0 and n > 0:
        f = min(1.0, n * dt / tau)
        if out[M_HEAVE] == out[M_HEAVE]:
            ref[R_HMEAN] += f * (out[M_HEAVE] - ref[R_HMEAN])
        if out[M_PITCH] == out[M_PITCH]:
            ref[R_PMEAN] += f * (out[M_PITCH] - ref[R_PMEAN])
    out[M_HEAVE_DEV] = out[M_HEAVE] - ref[R_HMEAN]
    out[M_PITCH_DEV] = out[M_PITCH] - (ref[R_PMEAN] if tau > 0.0 else ref[R_PITCH0])
    ns = tens_hist.shape[1]
    tmin = math.inf
    rmax = tt * ref[R_TOPINV]
    for s in range(ns):
        T = tens_hist[0, s]
        if T < tmin or T != T:
            tmin = T if T == T else math.nan
        r = T * inv_seg[s]
        if r > rmax or r != r:
            rmax = r
    out[M_MIN_T] = tmin
    out[M_T_RATIO] = rmax
    if cn >= 0 and comp[K.C_MODE] > 0:
        s0 = hist_r[0, cn, 2] - z0
        s1 = hist_r[1, cn, 2] - z1
        s2 = hist_r[2, cn, 2] - z2
        out[M_STROKE] = s0 / ref[R_HALF_STROKE]
        out[M_STROKE_VEL] = (3.0 * s0 - 4.0 * s1 + s2) / (2.0 * dt)
        hits = cstate[K.CS_HITS]
        out[M_HITS] = max(0.0, hits - ref[R_HITS])
        ref[R_HITS] = hits
        out[M_K] = comp[K.C_K]
        out[M_B] = comp[K.C_B]
    else:
        out[M_STROKE] = 0.0
        out[M_STROKE_VEL] = 0.0
        out[M_HITS] = 0.0
        out[M_K] = 0.0
        out[M_B] = 0.0
    if winch[K.W_MODE] > 0:
        v = wstate[K.WS_V] / ref[R_VMAX]
        length = 0.0
        for j in range(wsegs.shape[0]):
            length += l0[wsegs[j]]
        out[M_WSPEED] = v
        out[M_WLEN_DEV] = length - ref[R_L0]
        out[M_WLEN] = length
        out[M_WPOWER] = -tt * wstate[K.WS_V]          # > 0 when the winch hauls in against the top tension
    else:
        out[M_WSPEED] = 0.0
        out[M_WLEN_DEV] = 0.0
        out[M_WLEN] = 0.0
        out[M_WPOWER] = 0.0
    out[M_EFFORT] = out[M_WSPEED] if ref[R_EFFORT] == 1.0 else 0.0
    out[M_TIME_LEFT] = 1.0 - ref[R_STEPS] / ref[R_MAXSTEPS]
