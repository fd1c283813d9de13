"""Numba kernels of the lumped-mass tow simulator (Houbolt + Newton on segment tensions).

Everything here works on flat arrays (see :mod:`towenv.core.system` for their meaning). Each public
kernel has a plain-numpy twin in :mod:`towenv.verification.twin` that the tests compare against.

Where each force is computed (one search finds it):

* cable drag, weight, mass and added mass of a segment ...... ``segment_loads``
* assembly of node mass matrices and non-tension forces ....... ``node_assembly``
* point bodies (ball / clump) ................................. ``node_assembly`` (``pb_*`` arrays)
* rigid towed bodies: hydrodynamics, weight/buoyancy, damping ... ``body_loads``
* condensation of a rigid body onto its tow-point node ........ ``body_condense``
* the tension (length-constraint) system and its tree LDLᵀ .... ``assemble_tension_system``, ``tree_ldlt_solve``
* one Houbolt step with the Newton iteration ................. ``houbolt_step``

Sign conventions: ``t_s`` is the unit tangent of segment ``s`` pointing from its lower node to its upper
node (toward the ship); a positive tension pulls the lower node by ``+T t`` and the upper node by
``-T t``. ``F_o`` are all non-tension forces on a node (positive along the global axes). Gravity is
``-g e_z``.
"""
from __future__ import annotations

import math

import numpy as np
from .layout import S_ANGLE_TOLERANCE, S_AS_PUBLISHED, S_MAX_ITERATIONS, S_MAX_STEP_CUTS, S_MAX_STRAIN, S_NEWTON_ESTIMATE, S_PLANAR, S_RECHART_PITCH, S_RELATIVE_TOLERANCE, S_TOLERANCE
from .layout import N_ITERATIONS, N_MAX_ITERATIONS, N_RECHARTS, N_STEPS, N_STEP_CUTS
from .layout import BP_ADDED_INERTIA, BP_ADDED_MASS, BP_AFT_TOW_POINT, BP_AREA, BP_CB, BP_CG, BP_INERTIA, BP_LENGTH, BP_LIFT_SLOPE, BP_MASS, BP_QUAD_ROT_DAMPING, BP_REDUCED_DOF, BP_ROT_DAMPING, BP_TAIL_MASS, BP_VOLUME
from numba import njit as _njit

# reassociation/contraction allowed; NaN/Inf semantics kept (failure detection relies on them)
_FASTMATH = {"reassoc", "contract", "arcp", "nsz"}


def njit(*args, **kw):
    kw.setdefault("fastmath", _FASTMATH)
    return _njit(*args, **kw)

# status codes returned by the step kernels
OK = 0
FAIL_NEWTON = 1        # iteration cap reached / residual growing
FAIL_NAN = 2           # non-finite number appeared
FAIL_STRETCH = 3       # non-physical strain in a segment
FAIL_ANGLE = 4         # body pitch reached ±85° inside its attitude chart (guard: re-charting keeps it far below)

FREE = 0
PRESCRIBED_TOP = 1
PRESCRIBED_AFT = 2
PRESCRIBED_FIXED = 3   # anchor: fixed in space
COMPENSATOR = 4        # cable top node on a heave-compensator sheave: moves with the ship except along z
NEED_REMESH = 10       # advance(): not a failure — the winch line needs a node inserted/removed
RETRY_CONTACT = 11     # houbolt_step(): the sheave's end-stop contact state changed; redo the step

# moving attitude chart (see ``body_rotation``): a body whose local pitch exceeds this at the start of a
# step is re-charted (its local Euler angles restart from zero). Default of ``settings[7]``
# (``SolverSettings.rechart_pitch``) when the settings array is shorter.
RECHART_PITCH = math.pi / 6.0
# pitch (rad, ~85°) inside a body's attitude chart at which a step fails (FAIL_ANGLE): the Euler-angle
# singularity guard of every scheme
PITCH_LIMIT = 1.48

# heave compensator parameter layout (float64[16])
C_MODE, C_K, C_B, C_MASS, C_PRELOAD, C_SMIN, C_SMAX, C_TRIAL, C_UNUSED, C_CMD, C_TAU, C_RATE, C_NODE, C_SHIP = range(14)
# compensator state layout (float64[8]): hits, in-contact flag, max penetration, actuator state
CS_HITS, CS_CONTACT, CS_PEN, CS_ACT = range(4)
COMP_PASSIVE, COMP_LOCKED, COMP_POSITION, COMP_FORCE = 1, 2, 3, 4
# winch parameter layout (float64[12]) and state (float64[4])
W_MODE, W_VCMD, W_VMAX, W_AMAX, W_LMIN, W_LMAX, W_TSET, W_GAIN, W_DEADBAND, W_SEG, W_LNOM = range(11)
WS_V, WS_LEN, WS_PAID = range(3)
WINCH_SPEED, WINCH_TENSION = 1, 2
# array sizes (the layouts above name fewer slots; the rest is spare)
COMP_SIZE, COMP_STATE_SIZE, WINCH_SIZE, WINCH_STATE_SIZE = 16, 8, 12, 4


# ----------------------------------------------------------------------------------------------
# small 3-vector / 3x3 helpers
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def _inv3(a, out):
    """Inverse of a 3x3 matrix (closed form). Returns False if singular."""
    c00 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c01 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c02 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * c00 + a[0, 1] * c01 + a[0, 2] * c02
    if det == 0.0 or not math.isfinite(det):
        return False
    idet = 1.0 / det
    out[0, 0] = c00 * idet
    out[0, 1] = (a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]) * idet
    out[0, 2] = (a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]) * idet
    out[1, 0] = c01 * idet
    out[1, 1] = (a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]) * idet
    out[1, 2] = (a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]) * idet
    out[2, 0] = c02 * idet
    out[2, 1] = (a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]) * idet
    out[2, 2] = (a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]) * idet
    return True


@njit(cache=True)
def rotation_matrix(roll, pitch, yaw, out):
    """Λ_f: global -> body components (model.md 1.4; yaw, then pitch (nose down +), then roll)."""
    cb = math.cos(roll)
    sb = math.sin(roll)
    ca = math.cos(pitch)
    sa = math.sin(pitch)
    cg = math.cos(yaw)
    sg = math.sin(yaw)
    out[0, 0] = cg * ca
    out[0, 1] = sg * ca
    out[0, 2] = -sa
    out[1, 0] = -sg * cb + cg * sa * sb
    out[1, 1] = cg * cb + sg * sa * sb
    out[1, 2] = ca * sb
    out[2, 0] = cg * sa * cb + sg * sb
    out[2, 1] = sg * sa * cb - cg * sb
    out[2, 2] = ca * cb


@njit(cache=True)
def body_rotation(ang, chart, out):
    """Λ = Λ_f(φ, θ, ψ) · C: global -> body components of a body whose attitude is stored as local Euler
    angles ``ang`` (roll, pitch, yaw) relative to its chart ``C`` (a constant rotation, global -> chart
    components; the identity until the body's pitch first passes ``RECHART_PITCH``).

    The body rates do not depend on the chart (Λ̇ = Λ̇_f C = −S(ω) Λ), so the Euler-rate kinematics and the
    Houbolt differences work on the local angles unchanged. With C = 𝟙 the product is skipped, so a run
    whose bodies never re-chart gives the same bits as a plain Euler-angle attitude."""
    rotation_matrix(ang[0], ang[1], ang[2], out)
    if chart[0, 0] == 1.0 and chart[1, 1] == 1.0 and chart[2, 2] == 1.0:
        return
    for i in range(3):
        a0 = out[i, 0]
        a1 = out[i, 1]
        a2 = out[i, 2]
        for j in range(3):
            out[i, j] = a0 * chart[0, j] + a1 * chart[1, j] + a2 * chart[2, j]


@njit(cache=True)
def _chart_rotation(a0, a1, a2, chart, b, out):
    """``body_rotation`` for body ``b`` of the per-body chart array (hot paths: no array view created)."""
    rotation_matrix(a0, a1, a2, out)
    if chart[b, 0, 0] == 1.0 and chart[b, 1, 1] == 1.0 and chart[b, 2, 2] == 1.0:
        return
    for i in range(3):
        x0 = out[i, 0]
        x1 = out[i, 1]
        x2 = out[i, 2]
        for j in range(3):
            out[i, j] = x0 * chart[b, 0, j] + x1 * chart[b, 1, j] + x2 * chart[b, 2, j]


@njit(cache=True)
def euler_from_rotation(lam, out):
    """Euler angles (roll, pitch, yaw) of Λ_f (global -> body) with pitch in [−90°, 90°] and roll, yaw in
    (−180°, 180°]. At pitch ±90° exactly (roll and yaw not separable) roll is set to 0."""
    c = math.sqrt(lam[0, 0] * lam[0, 0] + lam[0, 1] * lam[0, 1])
    out[1] = math.atan2(-lam[0, 2], c)
    if c > 1e-12:
        out[0] = math.atan2(lam[1, 2], lam[2, 2])
        out[2] = math.atan2(lam[0, 1], lam[0, 0])
    else:
        out[0] = 0.0
        out[2] = math.atan2(-lam[1, 0], lam[1, 1])


@njit(cache=True)
def rechart_body(b, hist_ang, chart, lam, lam0, cnew, tmp):
    """Move body ``b`` to a new attitude chart centred on its current attitude: C ← Λ(ang⁰) (re-orthonormalised),
    and each stored time level k gets the local angles of Λ(ang^k) C_newᵀ (so ang⁰ = 0 and the older levels
    are small). The map between charts is smooth, so the Houbolt history stays a consistent sample of the
    same motion."""
    body_rotation(hist_ang[0, b], chart[b], lam0)
    # Gram–Schmidt on the rows (keeps C a rotation to round-off over any number of re-charts)
    for r in range(3):
        for j in range(3):
            cnew[r, j] = lam0[r, j]
        for q in range(r):
            d = cnew[r, 0] * cnew[q, 0] + cnew[r, 1] * cnew[q, 1] + cnew[r, 2] * cnew[q, 2]
            for j in range(3):
                cnew[r, j] -= d * cnew[q, j]
        nrm = math.sqrt(cnew[r, 0] * cnew[r, 0] + cnew[r, 1] * cnew[r, 1] + cnew[r, 2] * cnew[r, 2])
        for j in range(3):
            cnew[r, j] /= nrm
    for lv in range(2, -1, -1):
        body_rotation(hist_ang[lv, b], chart[b], lam)
        # local matrix in the new chart: Λ C_newᵀ
        for i in range(3):
            for j in range(3):
                lam0[i, j] = lam[i, 0] * cnew[j, 0] + lam[i, 1] * cnew[j, 1] + lam[i, 2] * cnew[j, 2]
        euler_from_rotation(lam0, tmp)
        for i in range(3):
            hist_ang[lv, b, i] = tmp[i]
    for i in range(3):
        hist_ang[0, b, i] = 0.0
        for j in range(3):
            chart[b, i, j] = cnew[i, j]


@njit(cache=True)
def current_at(z, cur_z, cur_v, out):
    """Current velocity at height z (depth = -z), linear in depth, held beyond the table ends."""
    n = cur_z.shape[0]
    depth = -z
    if n == 1 or depth <= cur_z[0]:
        for k in range(3):
            out[k] = cur_v[0, k]
        return
    if depth >= cur_z[n - 1]:
        for k in range(3):
            out[k] = cur_v[n - 1, k]
        return
    i = 0
    while cur_z[i + 1] < depth:
        i += 1
    f = (depth - cur_z[i]) / (cur_z[i + 1] - cur_z[i])
    for k in range(3):
        out[k] = cur_v[i, k] * (1.0 - f) + cur_v[i + 1, k] * f


@njit(cache=True)
def table_lookup(x, xs, ys, n):
    """Piecewise-linear table lookup, end values held outside the table (never extrapolated)."""
    if x <= xs[0]:
        return ys[0]
    if x >= xs[n - 1]:
        return ys[n - 1]
    i = 0
    while xs[i + 1] < x:
        i += 1
    f = (x - xs[i]) / (xs[i + 1] - xs[i])
    return ys[i] * (1.0 - f) + ys[i + 1] * f


# ----------------------------------------------------------------------------------------------
# cable segment loads
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def segment_loads(r, v, seg_lo, seg_up, l0, diam, mu, cn, ct, can, cat, rho, g, cur_z, cur_v,
                  tang, stretched, drag, bmat, madd):
    """Per-segment tangent, stretched length, Morison drag, drag damping matrices and added mass.

    Drag is evaluated at each end node with that node's relative velocity ``ṙ − V_c(r)`` and the
    segment's tangent (vector normal form, opposing the relative velocity, model.md 2.3 / erratum E6):
    ``drag[s, e] = −½ρ D l (C_n |v_n| v_n + C_t |v_t| v_t)`` for end ``e`` (0 = lower, 1 = upper node);
    each end node receives half of its own value (trapezoidal rule along the segment). This differs from
    the thesis's midpoint rule (drag of the mean end velocity, (3.10)) only at second order in the
    segment length, but makes the drag of a node depend on that node's velocity alone, so the implicit
    drag linearisation ``bmat[s, e] = −∂drag[s, e]/∂v`` is exact inside the node-local solve (the
    Newton iteration then converges in a few sweeps even when drag dominates inertia).
    ``madd[s]``: added-mass tensor of the whole segment. Wet weight and dry mass are added in
    ``node_assembly``.
    """
    nseg = seg_lo.shape[0]
    vc = np.empty(3)
    for s in range(nseg):
        a = seg_lo[s]
        b = seg_up[s]
        dx = r[b, 0] - r[a, 0]
        dy = r[b, 1] - r[a, 1]
        dz = r[b, 2] - r[a, 2]
        ell = math.sqrt(dx * dx + dy * dy + dz * dz)
        stretched[s] = ell
        if ell > 0.0:
            tang[s, 0] = dx / ell
            tang[s, 1] = dy / ell
            tang[s, 2] = dz / ell
        else:
            tang[s, 0] = 0.0
            tang[s, 1] = 0.0
            tang[s, 2] = 1.0
        t0 = tang[s, 0]
        t1 = tang[s, 1]
        t2 = tang[s, 2]
        kn = 0.5 * rho * cn[s] * diam[s] * l0[s]
        kt = 0.5 * rho * ct[s] * diam[s] * l0[s]
        for e in range(2):
            nd = a if e == 0 else b
            current_at(r[nd, 2], cur_z, cur_v, vc)
            vr0 = v[nd, 0] - vc[0]
            vr1 = v[nd, 1] - vc[1]
            vr2 = v[nd, 2] - vc[2]
            vt_mag = vr0 * t0 + vr1 * t1 + vr2 * t2
            vn0 = vr0 - vt_mag * t0
            vn1 = vr1 - vt_mag * t1
            vn2 = vr2 - vt_mag * t2
            vn_abs = math.sqrt(vn0 * vn0 + vn1 * vn1 + vn2 * vn2)
            avt = abs(vt_mag)
            drag[s, e, 0] = -kn * vn_abs * vn0 - kt * avt * vt_mag * t0
            drag[s, e, 1] = -kn * vn_abs * vn1 - kt * avt * vt_mag * t1
            drag[s, e, 2] = -kn * vn_abs * vn2 - kt * avt * vt_mag * t2
            # B = kn(|vn|(1 - t t^T) + vn vn^T/|vn|) + 2 kt |vt| t t^T
            for i in range(3):
                for j in range(3):
                    tt = tang[s, i] * tang[s, j]
                    proj = (1.0 if i == j else 0.0) - tt
                    bmat[s, e, i, j] = kn * vn_abs * proj + 2.0 * kt * avt * tt
            if vn_abs > 1e-12:
                vn = (vn0, vn1, vn2)
                for i in range(3):
                    for j in range(3):
                        bmat[s, e, i, j] += kn * vn[i] * vn[j] / vn_abs
        area = 0.25 * math.pi * diam[s] * diam[s]
        amt = cat[s] * rho * area * l0[s]
        amn = can[s] * rho * area * l0[s]
        for i in range(3):
            for j in range(3):
                tt = tang[s, i] * tang[s, j]
                madd[s, i, j] = amt * tt + amn * ((1.0 if i == j else 0.0) - tt)


@njit(cache=True)
def node_assembly(r, v, node_kind, node_nseg, node_segs, node_sgn, l0, diam, mu, rho, g, drag, bmat, madd,
                  pb_mass, pb_vol, pb_cda, pb_ca, cur_z, cur_v, mnode, bnode, fnode):
    """Node mass matrices (dry + added mass), drag damping matrices and non-tension forces.

    Each segment gives half of its mass, added mass and wet weight to each end node (thesis §3.3), and
    half of the drag evaluated at that node (see ``segment_loads``). Point bodies (ball/clump) add their
    mass + added mass (isotropic), wet weight and isotropic quadratic drag ``-½ρ CdA |v_r| v_r``.
    """
    nn = node_kind.shape[0]
    vc = np.empty(3)
    for a in range(nn):
        for i in range(3):
            fnode[a, i] = 0.0
            for j in range(3):
                mnode[a, i, j] = 0.0
                bnode[a, i, j] = 0.0
        for k in range(node_nseg[a]):
            s = node_segs[a, k]
            e = 0 if node_sgn[a, k] > 0.0 else 1
            m_half = 0.5 * mu[s] * l0[s]
            wet = 0.5 * (mu[s] - rho * 0.25 * math.pi * diam[s] * diam[s]) * g * l0[s]
            for i in range(3):
                mnode[a, i, i] += m_half
                fnode[a, i] += 0.5 * drag[s, e, i]
                for j in range(3):
                    mnode[a, i, j] += 0.5 * madd[s, i, j]
                    bnode[a, i, j] += 0.5 * bmat[s, e, i, j]
            fnode[a, 2] -= wet
        # point body
        if pb_mass[a] > 0.0:
            mtot = pb_mass[a] + pb_ca[a] * rho * pb_vol[a]
            for i in range(3):
                mnode[a, i, i] += mtot
            fnode[a, 2] -= (pb_mass[a] - rho * pb_vol[a]) * g
            if pb_cda[a] > 0.0:
                current_at(r[a, 2], cur_z, cur_v, vc)
                v0 = v[a, 0] - vc[0]
                v1 = v[a, 1] - vc[1]
                v2 = v[a, 2] - vc[2]
                vm = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
                kd = 0.5 * rho * pb_cda[a]
                fnode[a, 0] -= kd * vm * v0
                fnode[a, 1] -= kd * vm * v1
                fnode[a, 2] -= kd * vm * v2
                vv = (v0, v1, v2)
                for i in range(3):
                    bnode[a, i, i] += kd * vm
                    if vm > 1e-12:
                        for j in range(3):
                            bnode[a, i, j] += kd * vv[i] * vv[j] / vm


# ----------------------------------------------------------------------------------------------
# rigid towed bodies (fish, depressor)
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def _table_coefficients(theta, inc, cd, cl, cm, n):
    """Drag, lift (or side force) and weathervane-moment coefficients at incidence ``theta`` (deg).

    Reverse flow (|θ| > 90°, the body moving tail first) beyond a table that stops at ±90° is folded
    fore–aft: at θ' = sign(θ)(180° − |θ|) the drag and the moment keep their values and the lift changes
    sign (a fore–aft symmetric body: the normal force still pushes the body the way the cross-flow goes,
    and the centre of pressure stays aft of the tow point). Without the fold the table's ±90° cross-flow
    values would be used for a body that merely reverses (reported by the validation of Hover's deep tow).
    Tables that cover |θ| > 90° themselves are used as given."""
    if abs(theta) > 90.0 and (theta > inc[n - 1] or theta < inc[0]) and inc[n - 1] <= 90.0 and inc[0] >= -90.0:
        tf = 180.0 - abs(theta)
        if theta < 0.0:
            tf = -tf
        return (table_lookup(tf, inc, cd, n), -table_lookup(tf, inc, cl, n), table_lookup(tf, inc, cm, n))
    return table_lookup(theta, inc, cd, n), table_lookup(theta, inc, cl, n), table_lookup(theta, inc, cm, n)


@njit(cache=True)
def body_loads(b, lam, vbody, omega, bp, btab_n, btab, rho, g, cur_global, f_out, m_out, bdiag_out):
    """Hydrodynamic, weight/buoyancy and rotational damping loads on rigid body ``b``.

    Body-axis force ``f_out`` acting at the tow point and moment ``m_out`` about the tow point.
    ``bp[b]`` packs the body parameters (columns: :mod:`towenv.core.layout`); ``btab[b]`` the coefficient tables
    (rows: incidence_deg, drag, lift, moment for the vertical plane, then the horizontal plane).
    ``bdiag_out`` returns an isotropic estimate of the translational drag derivative (for the implicit
    drag of the node mass; it affects only the convergence rate, never the converged answer).
    """
    mass = bp[b, BP_MASS]
    vol = bp[b, BP_VOLUME]
    area = bp[b, BP_AREA]
    length = bp[b, BP_LENGTH]
    xb = bp[b, BP_CB]
    yb = bp[b, BP_CB + 1]
    zb = bp[b, BP_CB + 2]
    xg = bp[b, BP_CG]
    yg = bp[b, BP_CG + 1]
    zg = bp[b, BP_CG + 2]
    # weight and buoyancy (body axes)
    gb0 = -lam[0, 2] * g
    gb1 = -lam[1, 2] * g
    gb2 = -lam[2, 2] * g
    wnet = mass - rho * vol
    f_out[0] = wnet * gb0
    f_out[1] = wnet * gb1
    f_out[2] = wnet * gb2
    # moments r_G x m g_b  -  r_B x rho V g_b
    m_out[0] = mass * (yg * gb2 - zg * gb1) - rho * vol * (yb * gb2 - zb * gb1)
    m_out[1] = mass * (zg * gb0 - xg * gb2) - rho * vol * (zb * gb0 - xb * gb2)
    m_out[2] = mass * (xg * gb1 - yg * gb0) - rho * vol * (xb * gb1 - yb * gb0)
    # relative velocity of the centroid in body axes
    vc0 = lam[0, 0] * cur_global[0] + lam[0, 1] * cur_global[1] + lam[0, 2] * cur_global[2]
    vc1 = lam[1, 0] * cur_global[0] + lam[1, 1] * cur_global[1] + lam[1, 2] * cur_global[2]
    vc2 = lam[2, 0] * cur_global[0] + lam[2, 1] * cur_global[1] + lam[2, 2] * cur_global[2]
    ur = vbody[0] + (omega[1] * zb - omega[2] * yb) - vc0
    vr = vbody[1] + (omega[2] * xb - omega[0] * zb) - vc1
    wr = vbody[2] + (omega[0] * yb - omega[1] * xb) - vc2
    vmag = math.sqrt(ur * ur + vr * vr + wr * wr)
    qa = 0.5 * rho * area
    nv = btab_n[b, 0]
    nh = btab_n[b, 1]
    bdiag_out[0] = 0.0
    if vmag > 1e-9:
        th_v = math.degrees(math.atan2(wr, ur))    # vertical incidence (docs/scene-format.md)
        th_h = math.degrees(math.atan2(vr, ur))    # horizontal incidence (sideslip)
        cd_v, cl_v, cm_v = _table_coefficients(th_v, btab[b, 0], btab[b, 1], btab[b, 2], btab[b, 3], nv)
        cd_h, cy_h, cm_h = _table_coefficients(th_h, btab[b, 4], btab[b, 5], btab[b, 6], btab[b, 7], nh)
        cd0 = table_lookup(0.0, btab[b, 0], btab[b, 1], nv)
        cd = cd_v + cd_h - cd0
        if cd < 0.0:
            cd = 0.0
        q = qa * vmag * vmag
        # drag along -v_r
        f_out[0] -= q * cd * ur / vmag
        f_out[1] -= q * cd * vr / vmag
        f_out[2] -= q * cd * wr / vmag
        # lift in the x'z' plane, perpendicular to v_r, positive toward +z'
        tv = math.radians(th_v)
        f_out[0] -= q * cl_v * math.sin(tv)
        f_out[2] += q * cl_v * math.cos(tv)
        # side force in the x'y' plane, perpendicular to v_r, positive toward +y'
        th = math.radians(th_h)
        f_out[0] -= q * cy_h * math.sin(th)
        f_out[1] += q * cy_h * math.cos(th)
        # weathervane moments about the tow point (C_m > 0 turns the nose toward v_r): incidence > 0
        # in the vertical plane means v_r points above the nose -> nose-up (negative pitch) moment;
        # in the horizontal plane v_r points to port of the nose -> positive yaw moment
        m_out[1] -= q * length * cm_v
        m_out[2] += q * length * cm_h
        # isotropic drag-derivative estimate for the implicit drag
        bdiag_out[0] = qa * vmag * (2.0 * cd + bp[b, BP_LIFT_SLOPE])
    # rotational damping: linear rotary derivatives + Hover (17) quadratic term
    for k in range(3):
        lin = bp[b, BP_ROT_DAMPING + k]
        quad = bp[b, BP_QUAD_ROT_DAMPING + k]
        w = omega[k]
        m_out[k] -= qa * length * length * vmag * lin * w + qa * quad * length ** 3 / 32.0 * w * abs(w)


@njit(cache=True)
def body_mass_blocks(b, bp, att, atr, arr):
    """Rigid-body + added mass blocks about the tow point: A = [[A_tt, A_tr], [A_rt, A_rr]], A_rt = A_trᵀ."""
    mass = bp[b, BP_MASS]
    xg = bp[b, BP_CG]
    yg = bp[b, BP_CG + 1]
    zg = bp[b, BP_CG + 2]
    rg = (xg, yg, zg)
    for i in range(3):
        for j in range(3):
            att[i, j] = 0.0
            arr[i, j] = 0.0
        att[i, i] = mass + bp[b, BP_ADDED_MASS + i]
    r2 = xg * xg + yg * yg + zg * zg
    for i in range(3):
        for j in range(3):
            arr[i, j] = -mass * rg[i] * rg[j]
        arr[i, i] += mass * r2 + bp[b, BP_INERTIA + i] + bp[b, BP_ADDED_INERTIA + i]
    # A_tr = -m S(r_G)   (S(a) b = a x b)
    atr[0, 0] = 0.0
    atr[0, 1] = mass * zg
    atr[0, 2] = -mass * yg
    atr[1, 0] = -mass * zg
    atr[1, 1] = 0.0
    atr[1, 2] = mass * xg
    atr[2, 0] = mass * yg
    atr[2, 1] = -mass * xg
    atr[2, 2] = 0.0


@njit(cache=True)
def condense_body(b, a, has_tail, lam, w, tail_force, bp, fb, mb, att, atr, arr, arrinv, hvec, tmp3, aeff, X, y,
                  mnode, fnode):
    """Condense rigid body ``b`` onto its tow-point node ``a`` (all three rotations free): see ``_condense``."""
    return _condense(b, a, has_tail, lam, w, tail_force, bp, fb, mb, att, atr, arr, arrinv, hvec, tmp3, aeff, X, y,
                     mnode, fnode, False)


@njit(cache=True)
def _condense(b, a, has_tail, lam, w, tail_force, bp, fb, mb, att, atr, arr, arrinv, hvec, tmp3, aeff, X, y,
              mnode, fnode, reduced):
    """Condense rigid body ``b`` onto its tow-point node ``a`` (model.md 3.4, Schur complement).

    ``reduced``: the body pitches only (roll and yaw held by constraint moments), so only the pitch row and
    column of A_rr take part: A_rr⁻¹ is replaced by e_y e_yᵀ / A_rr,yy.

    On entry ``fb``/``mb`` hold the body-axis loads from :func:`body_loads`; ``tail_force`` (global) is
    the reaction of a series-tow tail cable at the aft tow point. Adds the rigid-body Coriolis and
    centripetal terms, forms A = M_RB + M_A about the tow point, and adds ``Λᵀ A_eff Λ`` to the node
    mass and ``Λᵀ (F − A_tr A_rr⁻¹ M)`` to the node force. Returns ``X = A_rr⁻¹ A_rt`` and
    ``y = A_rr⁻¹ M`` so that afterwards ``ω̇ = y − X a`` (a = Λ r̈). False if A_rr is singular."""
    if has_tail:
        f0 = lam[0, 0] * tail_force[0] + lam[0, 1] * tail_force[1] + lam[0, 2] * tail_force[2]
        f1 = lam[1, 0] * tail_force[0] + lam[1, 1] * tail_force[1] + lam[1, 2] * tail_force[2]
        f2 = lam[2, 0] * tail_force[0] + lam[2, 1] * tail_force[1] + lam[2, 2] * tail_force[2]
        fb[0] += f0
        fb[1] += f1
        fb[2] += f2
        _cross(bp[b, BP_AFT_TOW_POINT], bp[b, BP_AFT_TOW_POINT + 1], bp[b, BP_AFT_TOW_POINT + 2], f0, f1, f2, tmp3)
        for i in range(3):
            mb[i] += tmp3[i]
    # Coriolis / centripetal terms to the right-hand side
    mass = bp[b, BP_MASS]
    _cross(w[0], w[1], w[2], bp[b, BP_CG], bp[b, BP_CG + 1], bp[b, BP_CG + 2], tmp3)
    wx0 = tmp3[0]
    wx1 = tmp3[1]
    wx2 = tmp3[2]
    _cross(w[0], w[1], w[2], wx0, wx1, wx2, tmp3)
    for i in range(3):
        fb[i] -= mass * tmp3[i]
    body_mass_blocks(b, bp, att, atr, arr)
    # gyroscopic term ω × (A_rr ω) with the whole rotational inertia about the tow point, rigid AND added
    # (Kirchhoff; A_rr is what multiplies ω̇ below — leaving the added inertia out of this term, as the thesis
    # does, makes a tumbling body with unequal added inertias gain energy: docs/validation.md, problem 3)
    for i in range(3):
        hvec[i] = 0.0
        for j in range(3):
            hvec[i] += arr[i, j] * w[j]
    _cross(w[0], w[1], w[2], hvec[0], hvec[1], hvec[2], tmp3)
    for i in range(3):
        mb[i] -= tmp3[i]
    if reduced:
        if not arr[1, 1] > 0.0:
            return False
        for i in range(3):
            for j in range(3):
                arrinv[i, j] = 0.0
        arrinv[1, 1] = 1.0 / arr[1, 1]
    elif not _inv3(arr, arrinv):
        return False
    # X = A_rr⁻¹ A_rt (A_rt = A_trᵀ), y = A_rr⁻¹ M
    for i in range(3):
        y[i] = arrinv[i, 0] * mb[0] + arrinv[i, 1] * mb[1] + arrinv[i, 2] * mb[2]
        for j in range(3):
            X[i, j] = arrinv[i, 0] * atr[j, 0] + arrinv[i, 1] * atr[j, 1] + arrinv[i, 2] * atr[j, 2]
    # A_eff = A_tt − A_tr X ;  f_eff = F − A_tr y
    for i in range(3):
        fi = fb[i]
        for k in range(3):
            fi -= atr[i, k] * y[k]
        tmp3[i] = fi
        for j in range(3):
            e = att[i, j]
            for k in range(3):
                e -= atr[i, k] * X[k, j]
            aeff[i, j] = e
    # global: M += Λᵀ A_eff Λ ; F += Λᵀ f_eff
    for i in range(3):
        for j in range(3):
            sacc = 0.0
            for k in range(3):
                for m in range(3):
                    sacc += lam[k, i] * aeff[k, m] * lam[m, j]
            mnode[a, i, j] += sacc
        fnode[a, i] += lam[0, i] * tmp3[0] + lam[1, i] * tmp3[1] + lam[2, i] * tmp3[2]
    return True


@njit(cache=True)
def euler_rates_to_omega(ang, dang, out):
    """Body rates (p, q, r) from Euler angles (roll, pitch, yaw) and their time derivatives."""
    cb = math.cos(ang[0])
    sb = math.sin(ang[0])
    ca = math.cos(ang[1])
    sa = math.sin(ang[1])
    out[0] = dang[0] - dang[2] * sa
    out[1] = dang[1] * cb + dang[2] * ca * sb
    out[2] = -dang[1] * sb + dang[2] * ca * cb


@njit(cache=True)
def euler_rates_to_omega_series(ang, dang, out):
    """:func:`euler_rates_to_omega` for each row of ``ang``, ``dang`` (n, 3) into ``out`` (n, 3) — one compiled
    call for a whole recorded time series (the same scalar function per row, so bit-identical to a loop)."""
    w = np.empty(3)
    for i in range(ang.shape[0]):
        euler_rates_to_omega(ang[i], dang[i], w)
        out[i, 0] = w[0]
        out[i, 1] = w[1]
        out[i, 2] = w[2]


@njit(cache=True)
def omega_dot_to_euler_acc(ang, dang, omega, domega, out):
    """Euler-angle accelerations from body angular acceleration (exact z-y-x kinematics, model.md 1.4)."""
    cb = math.cos(ang[0])
    sb = math.sin(ang[0])
    ca = math.cos(ang[1])
    sa = math.sin(ang[1])
    ta = sa / ca
    p = omega[0]
    q = omega[1]
    r = omega[2]
    qsrc = q * sb + r * cb
    qcrs = q * cb - r * sb
    # H(θ) dω
    h0 = domega[0] + (domega[1] * sb + domega[2] * cb) * ta
    h1 = domega[1] * cb - domega[2] * sb
    h2 = (domega[1] * sb + domega[2] * cb) / ca
    # (dH/dt) ω
    db = dang[0]
    da = dang[1]
    out[0] = h0 + qcrs * ta * db + qsrc / (ca * ca) * da
    out[1] = h1 - qsrc * db
    out[2] = h2 + qcrs / ca * db + qsrc * sa / (ca * ca) * da
    _ = p


# ----------------------------------------------------------------------------------------------
# tension system
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def assemble_tension_system(node_kind, node_nseg, node_segs, node_sgn, tang, qvec, l0, ea, tens,
                            kd, kb):
    """K = −J of the length constraints g_s = ℓ_s − l_s(1 + T_s/EA_s), row-scaled (model.md 5.3–5.6).

    ``qvec[a, k] = ½Δt² M̃_a⁻¹ t_{s_k}`` is ∂r_a/∂T_{s_k} up to the sign σ. Off-diagonal entries live in
    the node blocks ``kb[a]`` (two segments share at most one node in a tree), diagonals in ``kd``.
    Rows use the same (frozen) tangents as the coefficients, so K is exactly symmetric positive definite.
    """
    nseg = l0.shape[0]
    for s in range(nseg):
        if math.isinf(ea[s]):
            kd[s] = 0.0
        else:
            kd[s] = l0[s] / ea[s]
    nn = node_kind.shape[0]
    for a in range(nn):
        ns = node_nseg[a]
        for k1 in range(ns):
            for k2 in range(ns):
                kb[a, k1, k2] = 0.0
        if node_kind[a] != FREE and node_kind[a] != COMPENSATOR:
            continue
        for k1 in range(ns):
            s1 = node_segs[a, k1]
            for k2 in range(ns):
                val = node_sgn[a, k1] * node_sgn[a, k2] * (
                    tang[s1, 0] * qvec[a, k2, 0] + tang[s1, 1] * qvec[a, k2, 1] + tang[s1, 2] * qvec[a, k2, 2])
                if k1 == k2:
                    kd[s1] += val
                else:
                    kb[a, k1, k2] = val
    _ = tens


@njit(cache=True)
def tree_ldlt_solve(order, seg_up, seg_uplocal, node_kind, node_nseg, node_segs, pos, kd, kb, rhs, x):
    """Solve K x = rhs for the tree-structured tension matrix by LU (LDLᵀ when K is symmetric) without fill-in.

    ``order`` eliminates segments from the free ends toward the ship (each after every segment below
    it). A segment's later neighbours all sit at its upper node, whose segments form a clique, so the
    elimination creates no fill (model.md 5.6). O(n); ``kd``, ``kb`` and ``rhs`` are overwritten.
    K is symmetric positive definite when every node mass matrix is symmetric; a rigid body's full
    (non-symmetric) hydrodynamic damping makes its node's block slightly non-symmetric, which this
    elimination handles as an LU without pivoting (the matrix stays strongly diagonal).
    Returns False if a pivot is not positive.
    """
    n = order.shape[0]
    for ip in range(n):
        p = order[ip]
        d = kd[p]
        if not (d > 0.0):
            return False
        a = seg_up[p]
        if node_kind[a] != FREE and node_kind[a] != COMPENSATOR:
            continue
        kp = seg_uplocal[p]
        ns = node_nseg[a]
        for k1 in range(ns):
            q1 = node_segs[a, k1]
            if pos[q1] <= ip:
                continue
            l1 = kb[a, k1, kp]
            if l1 == 0.0:
                continue
            f = l1 / d
            rhs[q1] -= f * rhs[p]
            kd[q1] -= f * kb[a, kp, k1]
            for k2 in range(ns):
                q2 = node_segs[a, k2]
                if k2 == k1 or pos[q2] <= ip:
                    continue
                kb[a, k1, k2] -= f * kb[a, kp, k2]
    for ip in range(n - 1, -1, -1):
        p = order[ip]
        acc = rhs[p]
        a = seg_up[p]
        if node_kind[a] == FREE or node_kind[a] == COMPENSATOR:
            kp = seg_uplocal[p]
            for k in range(node_nseg[a]):
                q = node_segs[a, k]
                if pos[q] > ip:
                    acc -= kb[a, kp, k] * x[q]
        x[p] = acc / kd[p]
    return True


# ----------------------------------------------------------------------------------------------
# one Houbolt step
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def _cross(a0, a1, a2, b0, b1, b2, out):
    out[0] = a1 * b2 - a2 * b1
    out[1] = a2 * b0 - a0 * b2
    out[2] = a0 * b1 - a1 * b0


@njit(cache=True)
def place_aft_nodes(r, ang, chart, body_node, body_aft_node, bp, lam):
    """Aft tow points are rigidly carried by their body: r_aft = r_tp + Λᵀ r_t (Λ = Λ_f(ang) C)."""
    for b in range(body_node.shape[0]):
        c = body_aft_node[b]
        if c < 0:
            continue
        _chart_rotation(ang[b, 0], ang[b, 1], ang[b, 2], chart, b, lam)
        a = body_node[b]
        for i in range(3):
            r[c, i] = r[a, i] + lam[0, i] * bp[b, BP_AFT_TOW_POINT] + lam[1, i] * bp[b, BP_AFT_TOW_POINT + 1] + lam[2, i] * bp[b, BP_AFT_TOW_POINT + 2]


@njit(cache=True)
def node_reaction(c, r, r_t, r_tm1, r_tm2, dt, node_nseg, node_segs, node_sgn, tang, tens, mnode, fnode, out):
    """Force that the cable system exerts on the support of a prescribed node c (global axes).

    = Σ σ T t + F_o − M r̈ (its own half-segment weight, drag and inertia included, model.md 2.6)."""
    idt2 = 1.0 / (dt * dt)
    for i in range(3):
        out[i] = fnode[c, i]
    for k in range(node_nseg[c]):
        s = node_segs[c, k]
        sg = node_sgn[c, k]
        for i in range(3):
            out[i] += sg * tens[s] * tang[s, i]
    for i in range(3):
        acc_i = 0.0
        for j in range(3):
            accj = (2.0 * r[c, j] - 5.0 * r_t[c, j] + 4.0 * r_tm1[c, j] - r_tm2[c, j]) * idt2
            acc_i += mnode[c, i, j] * accj
        out[i] -= acc_i


@njit(cache=True)
def _rotational_stiffness(b, ang, chart, vnode, w, bp, btab_n, btab, rho, g, cur_b, m0, bkc, scr, lam, reduced):
    """Diagonal estimates of −∂M_i/∂θ_i (stiffness) and −∂M_i/∂ω_i (damping) of the body loads, by
    finite differences, clipped at zero. Used only to relax the body-angle update (convergence rate).
    ``reduced``: pitch only (the roll and yaw entries are set to 0)."""
    vb = scr[0]
    f = scr[1]
    m = scr[2]
    bd = scr[3]
    ang2 = scr[4]
    w2 = scr[5]
    eps_a = 1e-5
    eps_w = 1e-4
    for i in range(3):
        if reduced and i != 1:
            bkc[b, i] = 0.0
            bkc[b, 3 + i] = 0.0
            continue
        for k in range(3):
            ang2[k] = ang[k]
            w2[k] = w[k]
        ang2[i] += eps_a
        _chart_rotation(ang2[0], ang2[1], ang2[2], chart, b, lam)
        for k in range(3):
            vb[k] = lam[k, 0] * vnode[0] + lam[k, 1] * vnode[1] + lam[k, 2] * vnode[2]
        body_loads(b, lam, vb, w, bp, btab_n, btab, rho, g, cur_b, f, m, bd)
        kk = -(m[i] - m0[i]) / eps_a
        bkc[b, i] = kk if kk > 0.0 else 0.0
        _chart_rotation(ang[0], ang[1], ang[2], chart, b, lam)
        for k in range(3):
            vb[k] = lam[k, 0] * vnode[0] + lam[k, 1] * vnode[1] + lam[k, 2] * vnode[2]
        w2[i] += eps_w
        body_loads(b, lam, vb, w2, bp, btab_n, btab, rho, g, cur_b, f, m, bd)
        cc = -(m[i] - m0[i]) / eps_w
        bkc[b, 3 + i] = cc if cc > 0.0 else 0.0


@njit(cache=True)
def thesis_recursion_solve(order, seg_up, seg_uplocal, seg_lo, node_nseg, node_segs, kd, kb, rhs, x, work):
    """The thesis's printed shooting recursion (4.38)–(4.40), *as published*, for a single chain — the
    labelled "as published" variant of the tension solve (``solver.tension_solve = "as_published"``).

    With segments numbered from the bottom, ``E δT_{i−1} − F δT_i + G δT_{i+1} = −ER_i`` is solved by
    ``δT_i = μ_i δT_0 + η_i`` and closed at the top. The homogeneous recurrence grows like λⁿ
    (λ + 1/λ = 2 + s, s = 2(l/(c_L Δt))²), so for stiff cables at large steps round-off swamps the
    answer (model.md 5.6, erratum E15). Kept to show that failure; the default is ``tree_ldlt_solve``.
    Returns False if a G coefficient is zero or the result is not finite."""
    n = order.shape[0]
    # E_i, F_i, G_i in bottom-up order (J = −K: E = −K[i, i−1], F = K[i, i], G = −K[i, i+1])
    mu = np.zeros(n)
    eta = np.zeros(n)
    E = np.zeros(n)
    F = np.zeros(n)
    G = np.zeros(n)
    R = np.zeros(n)
    for i in range(n):
        p = order[i]
        F[i] = kd[p]
        R[i] = -rhs[p]
        if i + 1 < n:
            u = order[i + 1]
            a = seg_up[p]
            ku = -1
            for k in range(node_nseg[a]):
                if node_segs[a, k] == u:
                    ku = k
            if ku < 0:
                return False       # not a chain
            G[i] = -kb[a, seg_uplocal[p], ku]
            E[i + 1] = -kb[a, ku, seg_uplocal[p]]
    mu[0] = 1.0
    for i in range(n - 1):
        if G[i] == 0.0:
            return False
        mu_m = mu[i - 1] if i > 0 else 0.0
        eta_m = eta[i - 1] if i > 0 else 0.0
        mu[i + 1] = (F[i] * mu[i] - E[i] * mu_m) / G[i]
        eta[i + 1] = (R[i] + F[i] * eta[i] - E[i] * eta_m) / G[i]
    i = n - 1
    mu_m = mu[i - 1] if n > 1 else 0.0
    eta_m = eta[i - 1] if n > 1 else 0.0
    den = E[i] * mu_m - F[i] * mu[i]
    if den == 0.0:
        return False
    d0 = (R[i] - E[i] * eta_m + F[i] * eta[i]) / den
    for i in range(n):
        v = mu[i] * d0 + eta[i]
        if not math.isfinite(v):
            return False
        x[order[i]] = v
    return True


@njit(cache=True)
def _positions_from_tensions(node_kind, node_nseg, node_segs, node_sgn, tens, acon, qvec, rs):
    """Node positions from the tensions through each node's linear map r_a = A_a + Σ σ T q_a,k."""
    for a in range(node_kind.shape[0]):
        if node_kind[a] != FREE and node_kind[a] != COMPENSATOR:
            continue
        for i in range(3):
            x = acon[a, i]
            for k in range(node_nseg[a]):
                x += node_sgn[a, k] * tens[node_segs[a, k]] * qvec[a, k, i]
            rs[a, i] = x


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
def _translational_damping(b, lam, vbody, w, bp, btab_n, btab, rho, g, cur_b, f0, out, scr, planar):
    """D = −∂F/∂v of the body's hydrodynamic force (body axes) by finite differences. Used only as the
    implicit-damping linearisation of the tow-point node (convergence rate, not the solution).
    ``planar``: the lateral (body y = global y) column is not needed (set to 0)."""
    f = scr[1]
    m = scr[2]
    bd = scr[3]
    v2 = scr[4]
    vmag = math.sqrt(vbody[0] ** 2 + vbody[1] ** 2 + vbody[2] ** 2)
    eps = 1e-6 * (1.0 + vmag)
    for j in range(3):
        if planar and j == 1:
            for i in range(3):
                out[i, j] = 0.0
            continue
        for k in range(3):
            v2[k] = vbody[k]
        v2[j] += eps
        body_loads(b, lam, v2, w, bp, btab_n, btab, rho, g, cur_b, f, m, bd)
        for i in range(3):
            out[i, j] = -(f[i] - f0[i]) / eps


@njit(cache=True)
def aft_segment_stiffness(s, m_tail, stretched, tens, l0, ea, hdt2):
    """Stiffness of a taut series-tow tail segment ``s`` (hanging from an aft tow point) against motion of
    the aft point within one step: (axial, geometric). Axial: the segment's compliance l/EA in series with
    the inertia of everything hanging below it, ``m_tail`` (½Δt²/m; ``system.tail_masses``: the tail
    moves with the aft point when Δt is long against its axial period); geometric: T/ℓ. Zero when slack.

    Used only to relax the block Gauss–Seidel coupling of a body with its tail (the tail's pull is a load
    on the body inside the Newton loop; unrelaxed, the iteration's gain is about m_tail / m_body and it
    diverges when the tail outweighs the body). Added to both sides of the body's update, it changes the
    convergence rate, never the converged solution (docs/model-notes.md "Series coupling")."""
    if tens[s] <= 0.0 or stretched[s] <= 0.0:
        return 0.0, 0.0
    comp = 0.0 if math.isinf(ea[s]) else l0[s] / ea[s]
    if m_tail > 0.0 and not math.isinf(m_tail):
        comp += hdt2 / m_tail
    kax = 1.0 / comp if comp > 0.0 else 0.0
    return kax, tens[s] / stretched[s]


@njit(cache=True)
def aft_rotational_stiffness(b, a, c, rs, lam, node_nseg, node_segs, seg_up, tang, stretched, tens, l0, ea, hdt2,
                             m_tail, bkc):
    """Adds to ``bkc[b, 0:3]`` the restoring stiffness of the tail's pull about the body's axes
    (e_i = body axis i): for a rotation δθ about e the aft point moves by u = e × d (d = aft point − body
    node) and K = T (d·t − (e·d)(e·t)) + k_ax (t·u)² + (T/ℓ)(|u|² − (t·u)²), clipped at 0 (t: direction
    of the pull). Relaxation only (see :func:`aft_segment_stiffness`)."""
    d0 = rs[c, 0] - rs[a, 0]
    d1 = rs[c, 1] - rs[a, 1]
    d2 = rs[c, 2] - rs[a, 2]
    for k in range(node_nseg[c]):
        s = node_segs[c, k]
        kax, kgeo = aft_segment_stiffness(s, m_tail, stretched, tens, l0, ea, hdt2)
        if kax == 0.0 and kgeo == 0.0:
            continue
        # the pull on the aft point is along the segment, away from it
        sg = 1.0 if seg_up[s] == c else -1.0
        t0 = -sg * tang[s, 0]
        t1 = -sg * tang[s, 1]
        t2 = -sg * tang[s, 2]
        for i in range(3):
            e0 = lam[i, 0]
            e1 = lam[i, 1]
            e2 = lam[i, 2]
            u0 = e1 * d2 - e2 * d1
            u1 = e2 * d0 - e0 * d2
            u2 = e0 * d1 - e1 * d0
            tu = t0 * u0 + t1 * u1 + t2 * u2
            kk = (tens[s] * ((d0 * t0 + d1 * t1 + d2 * t2)
                             - (e0 * d0 + e1 * d1 + e2 * d2) * (e0 * t0 + e1 * t1 + e2 * t2))
                  + kax * tu * tu + kgeo * (u0 * u0 + u1 * u1 + u2 * u2 - tu * tu))
            if kk > 0.0:
                bkc[b, i] += kk


@njit(cache=True)
def houbolt_step(dt, r_top_new, top_node, topo, segp, bodyp, env, settings, state, ws, comp):
    """Advance one step of size dt. Returns (status, iterations, element, max|δT| of the last iteration).

    On success ``state`` holds the new time level; on failure ``state`` is left untouched (the trial
    solution lives in the work arrays), so the caller can retry with a smaller step.
    """
    seg_lo, seg_up, seg_uplocal, node_kind = topo.seg_lo, topo.seg_up, topo.seg_uplocal, topo.node_kind
    node_nseg, node_segs, node_sgn, order, pos = topo.node_nseg, topo.node_segs, topo.node_sgn, topo.order, topo.pos
    body_node, body_aft_node = topo.body_node, topo.body_aft_node
    l0, diam, mu, cn, ct, can, cat, ea = segp.l0, segp.diam, segp.mu, segp.cn, segp.ct, segp.can, segp.cat, segp.ea
    bp, btab_n, btab, pb_mass, pb_vol = bodyp.bp, bodyp.btab_n, bodyp.btab, bodyp.pb_mass, bodyp.pb_vol
    pb_cda, pb_ca = bodyp.pb_cda, bodyp.pb_ca
    rho, g, cur_z, cur_v = env.rho, env.g, env.cur_z, env.cur_v
    tol_abs = settings[S_TOLERANCE]
    tol_rel = settings[S_RELATIVE_TOLERANCE]
    maxit = int(settings[S_MAX_ITERATIONS])
    max_strain = settings[S_MAX_STRAIN]
    ang_tol = settings[S_ANGLE_TOLERANCE]
    # 2-D vertical-plane model (solver.planar): lateral node DOF and body roll/yaw frozen
    planar = settings.shape[0] > S_PLANAR and settings[S_PLANAR] != 0.0
    # Newton stopping on the estimated remaining error (solver.newton_stop = "estimate")
    stop_estimate = settings.shape[0] > S_NEWTON_ESTIMATE and settings[S_NEWTON_ESTIMATE] != 0.0
    prev_d = 0.0
    prev_a = 0.0
    hist_r, hist_ang, tens_hist, top_react = state.hist_r, state.hist_ang, state.tens_hist, state.top_react
    cstate, chart = state.cstate, state.chart
    tang, stretched, drag, bmat, madd, mnode = ws.tang, ws.stretched, ws.drag, ws.bmat, ws.madd, ws.mnode
    bnode, fnode, acon, qvec, rs, vs, kd, kb = ws.bnode, ws.fnode, ws.acon, ws.qvec, ws.rs, ws.vs, ws.kd, ws.kb
    rhs, dT, gres, tens, bX, by, blam, angs = ws.rhs, ws.dT, ws.gres, ws.tens, ws.bX, ws.by, ws.blam, ws.angs
    dang, omg, hvec, tmp3, tmp33, tmp33b, att = ws.dang, ws.omg, ws.hvec, ws.tmp3, ws.tmp33, ws.tmp33b, ws.att
    atr, arr, arrinv, cur_b, fb, mb, bdiag = ws.atr, ws.arr, ws.arrinv, ws.cur_b, ws.fb, ws.mb, ws.bdiag
    react, bkc, bdmat, scr, flow = ws.react, ws.bkc, ws.bdmat, ws.scr, ws.flow

    nn = node_kind.shape[0]
    ns = l0.shape[0]
    nb = body_node.shape[0]
    r_t = hist_r[0]
    r_tm1 = hist_r[1]
    r_tm2 = hist_r[2]
    c11 = 11.0 * dt / 12.0
    hdt2 = 0.5 * dt * dt
    i6dt = 1.0 / (6.0 * dt)
    idt2 = 1.0 / (dt * dt)

    cmode = int(comp[C_MODE])
    cnode = int(comp[C_NODE])
    act_new = cstate[CS_ACT]
    if cmode == COMP_POSITION or cmode == COMP_FORCE:
        # first-order actuator lag with a rate limit (explicit, once per step)
        rate = (comp[C_CMD] - cstate[CS_ACT]) / max(comp[C_TAU], dt)
        if rate > comp[C_RATE]:
            rate = comp[C_RATE]
        elif rate < -comp[C_RATE]:
            rate = -comp[C_RATE]
        act_new = cstate[CS_ACT] + dt * rate

    # predictor
    for a in range(nn):
        for i in range(3):
            rs[a, i] = 3.0 * r_t[a, i] - 3.0 * r_tm1[a, i] + r_tm2[a, i]
    for i in range(3):
        rs[top_node, i] = r_top_new[i]
    for b in range(nb):
        for i in range(3):
            angs[b, i] = 3.0 * hist_ang[0, b, i] - 3.0 * hist_ang[1, b, i] + hist_ang[2, b, i]
    place_aft_nodes(rs, angs, chart, body_node, body_aft_node, bp, tmp33)
    for s in range(ns):
        tp = 2.0 * tens_hist[0, s] - tens_hist[1, s]      # linear extrapolation of the tensions
        tens[s] = tp if tp > 0.0 else 0.0

    # series tows only: the body–tail relaxation below is skipped entirely without an aft tow point
    any_aft = False
    for b in range(nb):
        if body_aft_node[b] >= 0:
            any_aft = True
    status = FAIL_NEWTON
    elem = -1
    it = 0
    maxd = 0.0
    for it in range(1, maxit + 1):
        # --- coefficients at the current iterate -------------------------------------------------
        for a in range(nn):
            for i in range(3):
                # velocity relative to the wave orbital flow (zero unless [sea] orbital_velocities is on);
                # the current is subtracted where each load is evaluated
                vs[a, i] = (11.0 * rs[a, i] - 18.0 * r_t[a, i] + 9.0 * r_tm1[a, i] - 2.0 * r_tm2[a, i]) * i6dt \
                    - flow[a, i]
        segment_loads(rs, vs, seg_lo, seg_up, l0, diam, mu, cn, ct, can, cat, rho, g, cur_z, cur_v,
                      tang, stretched, drag, bmat, madd)
        node_assembly(rs, vs, node_kind, node_nseg, node_segs, node_sgn, l0, diam, mu, rho, g, drag, bmat, madd,
                      pb_mass, pb_vol, pb_cda, pb_ca, cur_z, cur_v, mnode, bnode, fnode)
        for b in range(nb):
            a = body_node[b]
            for i in range(3):
                dang[b, i] = (11.0 * angs[b, i] - 18.0 * hist_ang[0, b, i] + 9.0 * hist_ang[1, b, i]
                              - 2.0 * hist_ang[2, b, i]) * i6dt
            lam = blam[b]
            _chart_rotation(angs[b, 0], angs[b, 1], angs[b, 2], chart, b, lam)
            euler_rates_to_omega(angs[b], dang[b], omg[b])
            w = omg[b]
            for i in range(3):
                tmp3[i] = lam[i, 0] * vs[a, 0] + lam[i, 1] * vs[a, 1] + lam[i, 2] * vs[a, 2]
            zc = rs[a, 2] + lam[0, 2] * bp[b, BP_CB] + lam[1, 2] * bp[b, BP_CB + 1] + lam[2, 2] * bp[b, BP_CB + 2]
            current_at(zc, cur_z, cur_v, cur_b)
            body_loads(b, lam, tmp3, w, bp, btab_n, btab, rho, g, cur_b, fb, mb, bdiag)
            reduced = planar or bp[b, BP_REDUCED_DOF] != 0.0
            if it == 1:
                _rotational_stiffness(b, angs[b], chart, vs[a], w, bp, btab_n, btab, rho, g, cur_b, mb, bkc, scr, tmp33,
                                      reduced)
                _translational_damping(b, lam, tmp3, w, bp, btab_n, btab, rho, g, cur_b, fb, bdmat[b], scr, planar)
            c = body_aft_node[b]
            if c >= 0:
                node_reaction(c, rs, r_t, r_tm1, r_tm2, dt, node_nseg, node_segs, node_sgn, tang, tens,
                              mnode, fnode, react)
            if not _condense(b, a, c >= 0, lam, w, react, bp, fb, mb, att, atr, arr, arrinv, hvec, tmp3,
                             tmp33b, bX[b], by[b], mnode, fnode, reduced):
                return FAIL_NAN, it, -1, 0.0
            for i in range(3):
                bkc[b, 6 + i] = arr[i, i]
            # body hydrodynamic damping −∂F/∂v (body axes, full matrix) rotated to global: Λᵀ D Λ
            for i in range(3):
                for j in range(3):
                    sacc = 0.0
                    for k in range(3):
                        for m in range(3):
                            sacc += lam[k, i] * bdmat[b, k, m] * lam[m, j]
                    bnode[a, i, j] += sacc
        if it == 1 and any_aft:
            # series tows: the tail's restoring moment relaxes the body-angle update (rate only)
            for b in range(nb):
                c = body_aft_node[b]
                if c >= 0:
                    aft_rotational_stiffness(b, body_node[b], c, rs, blam[b], node_nseg, node_segs, seg_up, tang,
                                             stretched, tens, l0, ea, hdt2, bp[b, BP_TAIL_MASS], bkc)
        # --- node-local solve: r_a = A_a + Σ σ T q_a,k ------------------------------------------
        for a in range(nn):
            if node_kind[a] == COMPENSATOR:
                _compensator_node(a, int(comp[C_SHIP]), comp, cmode, act_new, dt, rs, r_t, r_tm1, r_tm2, node_nseg,
                                  node_segs, tang, stretched, tens, mnode, bnode, fnode, acon, qvec)
                continue
            if node_kind[a] != FREE:
                continue
            # M̃ = M + (11Δt/12) B + ½Δt² K_g: implicit drag and the node's own geometric (string)
            # stiffness K_g = Σ (T/ℓ)(1 − t tᵀ). Both are linearisations about the iterate r*, added on
            # both sides, so they change the convergence rate only, never the converged solution.
            for i in range(3):
                for j in range(3):
                    kg = 0.0
                    for k in range(node_nseg[a]):
                        sk = node_segs[a, k]
                        if stretched[sk] > 0.0:
                            kg += tens[sk] / stretched[sk] * ((1.0 if i == j else 0.0) - tang[sk, i] * tang[sk, j])
                    att[i, j] = c11 * bnode[a, i, j] + hdt2 * kg
                    tmp33[i, j] = mnode[a, i, j] + att[i, j]
            # a body towing a tail from its aft tow point: the tail's pull is a load on the body inside the
            # Newton loop (block Gauss–Seidel); its stiffness against the body's motion, ½Δt²(k_ax t tᵀ +
            # T/ℓ (1 − t tᵀ)), is added to both sides like K_g above (rate only, aft_segment_stiffness)
            for b in range(nb if any_aft else 0):
                c = body_aft_node[b]
                if body_node[b] != a or c < 0:
                    continue
                for k in range(node_nseg[c]):
                    sk = node_segs[c, k]
                    kax, kgeo = aft_segment_stiffness(sk, bp[b, BP_TAIL_MASS], stretched, tens, l0, ea, hdt2)
                    if kax == 0.0 and kgeo == 0.0:
                        continue
                    for i in range(3):
                        for j in range(3):
                            tt = tang[sk, i] * tang[sk, j]
                            add = hdt2 * (kax * tt + kgeo * ((1.0 if i == j else 0.0) - tt))
                            att[i, j] += add
                            tmp33[i, j] += add
            if not _inv3(tmp33, tmp33b):
                return FAIL_NAN, it, a, 0.0
            for j in range(3):
                hvec[j] = 2.5 * r_t[a, j] - 2.0 * r_tm1[a, j] + 0.5 * r_tm2[a, j]
            for i in range(3):
                hi = 0.0
                for j in range(3):
                    hi += mnode[a, i, j] * hvec[j] + att[i, j] * rs[a, j]
                tmp3[i] = hi + hdt2 * fnode[a, i]
            for i in range(3):
                acon[a, i] = tmp33b[i, 0] * tmp3[0] + tmp33b[i, 1] * tmp3[1] + tmp33b[i, 2] * tmp3[2]
            for k in range(node_nseg[a]):
                s = node_segs[a, k]
                for i in range(3):
                    qvec[a, k, i] = hdt2 * (tmp33b[i, 0] * tang[s, 0] + tmp33b[i, 1] * tang[s, 1]
                                            + tmp33b[i, 2] * tang[s, 2])

        if planar:
            # vertical-plane model: free nodes hold their lateral coordinate. The scenes it accepts have no
            # x–y or y–z coupling in M̃ (no lateral tangent, velocity or body asymmetry), so the (x, z) rows
            # of the 3-D solve are the plane's own solve (a separate 2×2 path measured slower)
            for a in range(nn):
                if node_kind[a] == FREE:
                    acon[a, 1] = r_t[a, 1]
                    for k in range(node_nseg[a]):
                        qvec[a, k, 1] = 0.0
        # positions at the current tensions, and residuals
        _positions_from_tensions(node_kind, node_nseg, node_segs, node_sgn, tens, acon, qvec, rs)
        place_aft_nodes(rs, angs, chart, body_node, body_aft_node, bp, tmp33)
        tmax = 0.0
        for s in range(ns):
            p = seg_lo[s]
            q = seg_up[s]
            dx = rs[q, 0] - rs[p, 0]
            dy = rs[q, 1] - rs[p, 1]
            dz = rs[q, 2] - rs[p, 2]
            ell = math.sqrt(dx * dx + dy * dy + dz * dz)
            if math.isinf(ea[s]):
                gres[s] = ell - l0[s]
            else:
                gres[s] = ell - l0[s] * (1.0 + tens[s] / ea[s])
            if tens[s] > tmax:
                tmax = tens[s]
        # --- Newton update of the tensions ----------------------------------------------------
        assemble_tension_system(node_kind, node_nseg, node_segs, node_sgn, tang, qvec, l0, ea, tens, kd, kb)
        for s in range(ns):
            rhs[s] = gres[s]
            if tens[s] <= 0.0 and gres[s] < 0.0:
                # slack segment: hold T = 0 (row and column replaced by identity)
                kd[s] = 1.0
                rhs[s] = -tens[s]
                for e in range(2):
                    a = seg_lo[s] if e == 0 else seg_up[s]
                    for k in range(node_nseg[a]):
                        if node_segs[a, k] == s:
                            for k2 in range(node_nseg[a]):
                                kb[a, k, k2] = 0.0
                                kb[a, k2, k] = 0.0
        if settings[S_AS_PUBLISHED] == 1.0:
            if not thesis_recursion_solve(order, seg_up, seg_uplocal, seg_lo, node_nseg, node_segs, kd, kb, rhs, dT,
                                          gres):
                return FAIL_NEWTON, it, -1, 0.0
        elif not tree_ldlt_solve(order, seg_up, seg_uplocal, node_kind, node_nseg, node_segs, pos, kd, kb,
                                 rhs, dT):
            return FAIL_NEWTON, it, -1, 0.0
        maxd = 0.0
        elem = -1
        any_slack = False
        for s in range(ns):
            tn = tens[s] + dT[s]
            if tn < 0.0:
                tn = 0.0
            if tn <= 0.0:
                any_slack = True
            d = abs(tn - tens[s])
            if not (d <= maxd):     # also catches NaN
                maxd = d
                elem = s
            tens[s] = tn
        if not math.isfinite(maxd):
            return FAIL_NAN, it, elem, maxd
        # positions with the updated tensions (same coefficients)
        _positions_from_tensions(node_kind, node_nseg, node_segs, node_sgn, tens, acon, qvec, rs)
        # --- body rotations: ω̇ = A_rr⁻¹(M − A_rt a), Houbolt on the Euler angles -------------------
        dang_max = 0.0
        for b in range(nb):
            a = body_node[b]
            lam = blam[b]
            for i in range(3):
                tmp3[i] = (2.0 * rs[a, i] - 5.0 * r_t[a, i] + 4.0 * r_tm1[a, i] - r_tm2[a, i]) * idt2
            for i in range(3):
                hvec[i] = lam[i, 0] * tmp3[0] + lam[i, 1] * tmp3[1] + lam[i, 2] * tmp3[2]
            for i in range(3):
                tmp3[i] = by[b, i] - (bX[b, i, 0] * hvec[0] + bX[b, i, 1] * hvec[1] + bX[b, i, 2] * hvec[2])
            omega_dot_to_euler_acc(angs[b], dang[b], omg[b], tmp3, hvec)
            reduced = planar or bp[b, BP_REDUCED_DOF] != 0.0
            for i in range(3):
                if reduced and i != 1:
                    angs[b, i] = hist_ang[0, b, i]      # roll and yaw held
                    continue
                na = 2.5 * hist_ang[0, b, i] - 2.0 * hist_ang[1, b, i] + 0.5 * hist_ang[2, b, i] + hdt2 * hvec[i]
                # implicit (diagonal) treatment of the rotational stiffness and damping: a relaxation
                # of the fixed-point update that leaves the converged solution unchanged
                na = angs[b, i] + (na - angs[b, i]) / (1.0 + (hdt2 * bkc[b, i] + c11 * bkc[b, 3 + i]) / bkc[b, 6 + i])
                dd = abs(na - angs[b, i])
                if not (dd <= dang_max):
                    dang_max = dd
                angs[b, i] = na
            if abs(angs[b, 1]) > PITCH_LIMIT:     # ~85 deg in the chart: only if re-charting (advance) could not keep up
                return FAIL_ANGLE, it, b, maxd
        if not math.isfinite(dang_max):
            return FAIL_NAN, it, -1, maxd
        place_aft_nodes(rs, angs, chart, body_node, body_aft_node, bp, tmp33)
        tol_t = tol_abs + tol_rel * tmax
        if maxd <= tol_t and dang_max <= ang_tol:
            status = OK
            break
        if stop_estimate and it >= 2 and not any_slack:
            # remaining error of a contracting iteration ≈ last change · ρ/(1 − ρ), ρ = ratio of the last two
            # changes; trusted only while ρ ≤ 1/2 (then the estimate is at most the last change) and no
            # segment is slack (the T ≥ 0 clamp makes the contraction non-smooth)
            ok_t = maxd <= tol_t or (maxd <= 0.5 * prev_d and maxd * maxd / (prev_d - maxd) <= tol_t)
            ok_a = dang_max <= ang_tol or (dang_max <= 0.5 * prev_a
                                           and dang_max * dang_max / (prev_a - dang_max) <= ang_tol)
            if ok_t and ok_a:
                status = OK
                break
        prev_d = maxd
        prev_a = dang_max
    if status != OK:
        return status, it, elem, maxd
    # --- end-stop contact: exact (the sheave is held at the stop while the stop pushes) --------------
    if cmode == COMP_PASSIVE or cmode == COMP_FORCE:
        z_new = rs[cnode, 2] - rs[top_node, 2]
        trial = comp[C_TRIAL]
        if trial == 0.0:
            if z_new > comp[C_SMAX]:
                comp[C_TRIAL] = 1.0
                return RETRY_CONTACT, it, cnode, maxd
            if z_new < comp[C_SMIN]:
                comp[C_TRIAL] = -1.0
                return RETRY_CONTACT, it, cnode, maxd
        else:
            fs = _end_stop_force(cnode, top_node, comp, dt, rs, r_t, r_tm1, r_tm2, node_nseg, node_segs, node_sgn,
                                 tang, tens, mnode, fnode)
            if trial * fs > 0.0:       # the stop would have to pull: release
                comp[C_TRIAL] = 0.0
                return RETRY_CONTACT, it, cnode, maxd
    # --- checks and commit ------------------------------------------------------------------------
    for s in range(ns):
        if not math.isinf(ea[s]) and tens[s] / ea[s] > max_strain:
            return FAIL_STRETCH, it, s, maxd
    for a in range(nn):
        for i in range(3):
            if not math.isfinite(rs[a, i]):
                return FAIL_NAN, it, a, maxd
    # reaction at the cable's top (the vessel tow point, or the compensator sheave) at the converged
    # state (coefficients of the last iterate)
    rnode = cnode if cmode > 0 else top_node
    node_reaction(rnode, rs, r_t, r_tm1, r_tm2, dt, node_nseg, node_segs, node_sgn, tang, tens,
                  mnode, fnode, react)
    if cmode > 0:
        z = rs[cnode, 2] - rs[top_node, 2]
        pen = z - comp[C_SMAX]
        if comp[C_SMIN] - z > pen:
            pen = comp[C_SMIN] - z
        if pen > cstate[CS_PEN]:
            cstate[CS_PEN] = pen
        if comp[C_TRIAL] != 0.0 and cstate[CS_CONTACT] == 0.0:
            cstate[CS_HITS] += 1.0
        cstate[CS_CONTACT] = comp[C_TRIAL]
        cstate[CS_ACT] = act_new
    for i in range(3):
        top_react[i] = react[i]
    for a in range(nn):
        for i in range(3):
            hist_r[2, a, i] = hist_r[1, a, i]
            hist_r[1, a, i] = hist_r[0, a, i]
            hist_r[0, a, i] = rs[a, i]
    for b in range(nb):
        for i in range(3):
            hist_ang[2, b, i] = hist_ang[1, b, i]
            hist_ang[1, b, i] = hist_ang[0, b, i]
            hist_ang[0, b, i] = angs[b, i]
    for s in range(ns):
        tens_hist[1, s] = tens_hist[0, s]
        tens_hist[0, s] = tens[s]
    return OK, it, -1, maxd


@njit(cache=True)
def _quad_interp(y1, y0, ym1, tau):
    """Quadratic through (τ=1, y1), (0, y0), (−1, ym1) evaluated at τ (history re-spacing)."""
    return ym1 * tau * (tau - 1.0) * 0.5 + y0 * (1.0 - tau * tau) + y1 * tau * (tau + 1.0) * 0.5


@njit(cache=True)
def _quad3(y0, ym1, ym2, tau):
    """Quadratic through (0, y0), (−1, ym1), (−2, ym2) evaluated at τ ≤ 0 (in units of the old step)."""
    return y0 * (tau + 1.0) * (tau + 2.0) * 0.5 - ym1 * tau * (tau + 2.0) + ym2 * tau * (tau + 1.0) * 0.5


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
def _wave_flow(t, r_t, r_tm1, r_tm2, wave, flow):
    """Orbital velocity at every node's predicted position for the step ending at t (frozen during the
    step's Newton iteration). ``wave`` is a :class:`towenv.core.model.WaveField`; ``wave.options =
    [enabled, z_cut]``: nodes below ``z_cut`` (where every component has decayed below
    1e-6 m/s) are skipped."""
    amp, omega, kx, ky, k, phase, opts = wave.amplitude, wave.omega, wave.kx, wave.ky, wave.k, wave.phase, wave.options
    nn = flow.shape[0]
    v = np.empty(3)
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


@njit(cache=True)
def _step(dt, top, top_node, topo, segp, bodyp, env, settings, state, ws, comp):
    """houbolt_step with the end-stop active set: start from the contact state of the last step and redo
    the step (at most twice) when the converged solution contradicts it."""
    cstate = state.cstate
    comp[C_TRIAL] = cstate[CS_CONTACT]
    its = 0
    for attempt in range(3):
        st, it, el, md = houbolt_step(dt, top, top_node, topo, segp, bodyp, env, settings, state, ws, comp)
        its += it
        if st != RETRY_CONTACT:
            return st, its, el, md
    return FAIL_NEWTON, its, el, md


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


@njit(cache=True)
def advance(n_steps, dt, top_path, top_node, topo, segp, bodyp, env, settings, state, ws, saved, counters,
            comp, winch, wstate, t0, wave):
    """Advance ``n_steps`` steps of size ``dt``; ``top_path[k]`` is the vessel tow point at the end of step k.

    ``state = (hist_r, hist_ang, tens_hist, top_react, cstate, chart)``: ``hist_ang`` holds each rigid body's
    Euler angles at the last three time levels *relative to its chart* ``chart[b]`` (see ``body_rotation``);
    before each step a body whose pitch in its chart exceeds ``settings[7]`` (default ``RECHART_PITCH``) is
    re-charted (``rechart_body``), so the attitude has no singularity. ``settings[8]`` ≠ 0 selects the
    vertical-plane model. A step whose Newton iteration fails is retried as 2, 4, … 2^max_cuts sub-steps
    with the Houbolt history re-interpolated quadratically at the new spacing (model.md 5.7). ``counters``
    accumulates [steps, iterations, max iterations, step cuts] and, if it has a fifth element, attitude
    re-charts. With a winch, the top segment's unstretched length
    follows the payout (model.md 2.8); when it leaves [0.5, 1.5]·l_nom the loop stops with
    ``NEED_REMESH`` after that step so the caller can insert or remove a node.
    Returns (status, step index (failed, or last done for NEED_REMESH), element, max|δT|).
    """
    hist_r, hist_ang, tens_hist, top_react = state.hist_r, state.hist_ang, state.tens_hist, state.top_react
    cstate, chart = state.cstate, state.chart
    s_hist_r, s_hist_ang, s_tens, s_cstate = saved.hist_r, saved.hist_ang, saved.tens_hist, saved.cstate
    l0 = segp.l0
    max_cuts = int(settings[S_MAX_STEP_CUTS])
    nn = hist_r.shape[1]
    nb = hist_ang.shape[1]
    ns = tens_hist.shape[1]
    top_sub = np.empty(3)
    rc_lam = np.empty((3, 3))
    rc_lam0 = np.empty((3, 3))
    rc_new = np.empty((3, 3))
    rc_tmp = np.empty(3)
    rc_pitch = settings[S_RECHART_PITCH] if settings.shape[0] > S_RECHART_PITCH else RECHART_PITCH
    wmode = int(winch[W_MODE])
    wseg = int(winch[W_SEG])
    flow = ws.flow
    for k in range(n_steps):
        # moving attitude chart: a body whose local pitch has passed RECHART_PITCH restarts from a chart
        # centred on its current attitude (between steps, so a failed step's retries stay in one chart)
        for b in range(nb):
            if abs(hist_ang[0, b, 1]) > rc_pitch:
                rechart_body(b, hist_ang, chart, rc_lam, rc_lam0, rc_new, rc_tmp)
                if counters.shape[0] > 4:
                    counters[N_RECHARTS] += 1
        _wave_flow(t0 + (k + 1) * dt, hist_r[0], hist_r[1], hist_r[2], wave, flow)
        dl = 0.0
        l_old = 0.0
        v_new = 0.0
        if wmode > 0:
            v_new = _winch_speed(winch, wstate, tens_hist, dt)
            dl = v_new * dt
            l_old = l0[wseg]
            l0[wseg] = l_old + dl
        st, it, el, md = _step(dt, top_path[k], top_node, topo, segp, bodyp, env, settings, state, ws, comp)
        counters[N_STEPS] += 1
        counters[N_ITERATIONS] += it
        if it > counters[N_MAX_ITERATIONS]:
            counters[N_MAX_ITERATIONS] = it
        if st != OK:
            s_hist_r[:] = hist_r
            s_hist_ang[:] = hist_ang
            s_tens[:] = tens_hist
            s_cstate[:] = cstate
            ok = False
            for cut in range(1, max_cuts + 1):
                nsub = 2 ** cut
                h = dt / nsub
                counters[N_STEP_CUTS] += 1
                for lv in range(3):
                    tau = -lv / nsub
                    for a in range(nn):
                        for i in range(3):
                            hist_r[lv, a, i] = _quad3(s_hist_r[0, a, i], s_hist_r[1, a, i], s_hist_r[2, a, i], tau)
                    for b in range(nb):
                        for i in range(3):
                            hist_ang[lv, b, i] = _quad3(s_hist_ang[0, b, i], s_hist_ang[1, b, i], s_hist_ang[2, b, i], tau)
                for s in range(ns):
                    tens_hist[0, s] = s_tens[0, s]
                    tens_hist[1, s] = s_tens[0, s]
                cstate[:] = s_cstate
                good = True
                for j in range(1, nsub + 1):
                    tau = j / nsub
                    for i in range(3):
                        top_sub[i] = _quad_interp(top_path[k, i], s_hist_r[0, top_node, i], s_hist_r[1, top_node, i], tau)
                    if wmode > 0:
                        l0[wseg] = l_old + tau * dl
                    st, it, el, md = _step(h, top_sub, top_node, topo, segp, bodyp, env, settings, state, ws, comp)
                    counters[N_ITERATIONS] += it
                    if st != OK:
                        good = False
                        break
                if good:
                    # restore the history spacing dt exactly: [r^{t+dt}, r^t, r^{t-dt}]
                    for a in range(nn):
                        for i in range(3):
                            hist_r[1, a, i] = s_hist_r[0, a, i]
                            hist_r[2, a, i] = s_hist_r[1, a, i]
                    for b in range(nb):
                        for i in range(3):
                            hist_ang[1, b, i] = s_hist_ang[0, b, i]
                            hist_ang[2, b, i] = s_hist_ang[1, b, i]
                    for s in range(ns):
                        tens_hist[1, s] = s_tens[0, s]
                    ok = True
                    break
            if not ok:
                hist_r[:] = s_hist_r
                hist_ang[:] = s_hist_ang
                tens_hist[:] = s_tens
                cstate[:] = s_cstate
                if wmode > 0:
                    l0[wseg] = l_old
                return st, k, el, md
        if wmode > 0:
            wstate[WS_V] = v_new
            wstate[WS_LEN] += dl
            wstate[WS_PAID] += dl
            if l0[wseg] > 1.5 * winch[W_LNOM] or (l0[wseg] < 0.5 * winch[W_LNOM] and dl < 0.0):
                return NEED_REMESH, k, wseg, 0.0
    return OK, -1, -1, 0.0
