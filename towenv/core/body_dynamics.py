"""Rigid towed bodies (fish, depressor): hydrodynamic loads from the coefficient tables with weight,
buoyancy and damping (``body_loads``), mass blocks and condensation of a body onto its tow-point node
(``condense_body``), aft tow points of series tows, and the stiffness/damping estimates the Newton
iteration uses to relax the body-angle update.
"""
from __future__ import annotations

import math


from .jit import njit
from .layout import (BK_DAMPING, BK_STIFFNESS, BP_ADDED_CORIOLIS, BP_ADDED_COUPLED, BP_ADDED_COUPLING,
                     BP_EXTERNAL_FORCE, BP_HAS_EXTERNAL,
                     BP_ADDED_INERTIA, BP_ADDED_MASS, BP_AFT_TOW_POINT, BP_AREA, BP_CB,
                     BP_CG, BP_INERTIA, BP_LENGTH, BP_LIFT_SLOPE, BP_MASS, BP_QUAD_ROT_DAMPING, BP_ROT_DAMPING,
                     BP_VOLUME)
from .rotations import _chart_rotation, _cross, _inv3


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


@njit(cache=True)
def _table_coefficients(theta, inc, cd, cl, cm, n):
    """Drag, lift (or side force) and weathervane-moment coefficients at incidence ``theta`` (deg).

    Reverse flow (|θ| > 90°, the body moving tail first) beyond a table that stops at ±90° is folded
    fore–aft: at θ' = sign(θ)(180° − |θ|) the drag and the moment keep their values and the lift changes
    sign (a fore–aft symmetric body: the normal force still pushes the body the way the cross-flow goes,
    and the centre of pressure stays aft of the tow point). Without the fold the table's ±90° cross-flow
    values would be used for a body that merely reverses (reported by the validation of Hover's deep tow).
    Tables that cover |θ| > 90° themselves are used as given."""
    sign = 1.0
    if abs(theta) > 90.0 and (theta > inc[n - 1] or theta < inc[0]) and inc[n - 1] <= 90.0 and inc[0] >= -90.0:
        tf = 180.0 - abs(theta)
        if theta < 0.0:
            tf = -tf
        theta = tf
        sign = -1.0
    # the three tables share the incidences: one search, then table_lookup's arithmetic on each
    if theta <= inc[0]:
        return cd[0], sign * cl[0], cm[0]
    if theta >= inc[n - 1]:
        return cd[n - 1], sign * cl[n - 1], cm[n - 1]
    i = 0
    while inc[i + 1] < theta:
        i += 1
    f = (theta - inc[i]) / (inc[i + 1] - inc[i])
    return (cd[i] * (1.0 - f) + cd[i + 1] * f, sign * (cl[i] * (1.0 - f) + cl[i + 1] * f),
            cm[i] * (1.0 - f) + cm[i + 1] * f)


@njit(cache=True)
def body_loads(b, lam, vbody, omega, bp, btab_n, btab, rho, g, cur_global, f_out, m_out, bdiag_out):
    """Hydrodynamic, weight/buoyancy, external (thruster) and rotational damping loads on rigid body ``b``.

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
    if bp[b, BP_HAS_EXTERNAL] != 0.0:
        # constant external force (thrusters holding station), global axes, acting at the centre of gravity
        fx = bp[b, BP_EXTERNAL_FORCE]
        fy = bp[b, BP_EXTERNAL_FORCE + 1]
        fz = bp[b, BP_EXTERNAL_FORCE + 2]
        e0 = lam[0, 0] * fx + lam[0, 1] * fy + lam[0, 2] * fz
        e1 = lam[1, 0] * fx + lam[1, 1] * fy + lam[1, 2] * fz
        e2 = lam[2, 0] * fx + lam[2, 1] * fy + lam[2, 2] * fz
        f_out[0] += e0
        f_out[1] += e1
        f_out[2] += e2
        m_out[0] += yg * e2 - zg * e1
        m_out[1] += zg * e0 - xg * e2
        m_out[2] += xg * e1 - yg * e0
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
    if bp[b, BP_ADDED_CORIOLIS] != 0.0:
        added_mass_coriolis(b, bp, vbody[0] - vc0, vbody[1] - vc1, vbody[2] - vc2, omega, f_out, m_out)


@njit(cache=True)
def _added_mass_entry(b, bp, i, j):
    """Entry (i, j) of the 6×6 added mass about the tow point (diagonal + coupling columns of ``bp``)."""
    if i == j:
        return bp[b, BP_ADDED_MASS + i] if i < 3 else bp[b, BP_ADDED_INERTIA + i - 3]
    return bp[b, BP_ADDED_COUPLING + 6 * i + j]


@njit(cache=True)
def added_mass_coriolis(b, bp, v0, v1, v2, omega, f_out, m_out):
    """Coriolis/centripetal loads of the added mass (Kirchhoff's equations; Fossen's −C_A(ν_r)ν_r), added to the
    body-axis force ``f_out`` and the moment ``m_out`` about the tow point. They include the **Munk moment**
    −v × (A₁₁ v).

    With ν_r = (v, ω) the tow point's velocity relative to the water (body axes) and M_A = [[A₁₁, A₁₂], [A₂₁,
    A₂₂]] about the tow point, the fluid's momentum is p = A₁₁ v + A₁₂ ω, its angular momentum h = A₂₁ v + A₂₂ ω,
    and the added-mass loads are −(ṗ + ω × p) and −(ḣ + ω × h + v × p) with body-frame derivatives. The mass
    matrix multiplies the *inertial* acceleration a = v̇ + ω × v (the condensation's unknown), so
    A₁₁ v̇ = A₁₁ a − A₁₁ (ω × v): the loads not in the mass matrix are

        f += A₁₁ (ω × v) − ω × p,      m += A₂₁ (ω × v) − ω × (A₂₁ v) − v × p,

    the remaining −ω × (A₂₂ ω) being the gyroscopic term ``_condense`` applies to the whole rotational inertia.
    With them a body with no damping in still water keeps its kinetic energy ½ νᵀ(M_RB + M_A)ν (tested)."""
    w0 = omega[0]
    w1 = omega[1]
    w2 = omega[2]
    # ω × v
    c0 = w1 * v2 - w2 * v1
    c1 = w2 * v0 - w0 * v2
    c2 = w0 * v1 - w1 * v0
    v = (v0, v1, v2)
    w = (w0, w1, w2)
    c = (c0, c1, c2)
    p0 = 0.0
    p1 = 0.0
    p2 = 0.0
    h0 = 0.0
    h1 = 0.0
    h2 = 0.0
    for i in range(3):
        pi = 0.0
        hv = 0.0        # (A21 v)_i
        fc = 0.0        # (A11 (ω×v))_i
        mc = 0.0        # (A21 (ω×v))_i
        for j in range(3):
            a11 = _added_mass_entry(b, bp, i, j)
            a12 = _added_mass_entry(b, bp, i, j + 3)
            a21 = _added_mass_entry(b, bp, i + 3, j)
            pi += a11 * v[j] + a12 * w[j]
            hv += a21 * v[j]
            fc += a11 * c[j]
            mc += a21 * c[j]
        if i == 0:
            p0 = pi
            h0 = hv
        elif i == 1:
            p1 = pi
            h1 = hv
        else:
            p2 = pi
            h2 = hv
        f_out[i] += fc
        m_out[i] += mc
    # − ω × p,  − ω × (A21 v),  − v × p
    f_out[0] -= w1 * p2 - w2 * p1
    f_out[1] -= w2 * p0 - w0 * p2
    f_out[2] -= w0 * p1 - w1 * p0
    m_out[0] -= (w1 * h2 - w2 * h1) + (v1 * p2 - v2 * p1)
    m_out[1] -= (w2 * h0 - w0 * h2) + (v2 * p0 - v0 * p2)
    m_out[2] -= (w0 * h1 - w1 * h0) + (v0 * p1 - v1 * p0)


@njit(cache=True)
def body_mass_blocks(b, bp, att, atr, arr):
    """Rigid-body + added mass blocks about the tow point: A = [[A_tt, A_tr], [A_rt, A_rr]], A_rt = A_trᵀ
    (the added mass's coupling blocks are symmetric: its A₂₁ = A₁₂ᵀ)."""
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
    if bp[b, BP_ADDED_COUPLED] != 0.0:
        # off-diagonal added mass (a full 6x6 matrix about the tow point): A_tt, A_tr, A_rr
        for i in range(3):
            for j in range(3):
                att[i, j] += bp[b, BP_ADDED_COUPLING + 6 * i + j]
                atr[i, j] += bp[b, BP_ADDED_COUPLING + 6 * i + j + 3]
                arr[i, j] += bp[b, BP_ADDED_COUPLING + 6 * (i + 3) + j + 3]


@njit(cache=True)
def condense_body(b, a, has_tail, lam, w, tail_force, bp, fb, mb, att, atr, arr, arrinv, hvec, tmp3, aeff, X, y,
                  mnode, fnode):
    """Condense rigid body ``b`` onto its tow-point node ``a`` (all three rotations free): see ``_condense``."""
    return _condense(b, a, has_tail, lam, w, tail_force, bp, fb, mb, att, atr, arr, arrinv, hvec, tmp3, aeff, X, y,
                     mnode, fnode, False, False, tmp3, tmp3, aeff, tmp3)


@njit(cache=True)
def _condense(b, a, has_tail, lam, w, tail_force, bp, fb, mb, att, atr, arr, arrinv, hvec, tmp3, aeff, X, y,
              mnode, fnode, reduced, implicit, prot, wdot, pmass, astar):
    """Condense rigid body ``b`` onto its tow-point node ``a`` (model.md 3.4, Schur complement).

    ``implicit`` (the Houbolt step's bodies with a monolithically coupled tail): the rotational stiffness and
    damping estimates enter the condensation itself, as ``prot`` = diag(½Δt² k + (11Δt/12) c) added to both
    sides of the rotational equation, (A_rr + P) ω̇ = M − A_rt a + P ω̇*, with ω̇* (``wdot``) the angular
    acceleration of the current iterate: at convergence ω̇ = ω̇* and the equation is the body's own; during
    the iteration the tow-point node sees the rotation the relaxed update will make (and the angle update is
    then not relaxed again: ``houbolt.body_angle_update``). With it, ``pmass`` (body axes) is the mass (and
    (11Δt/12)-scaled drag damping) of the tail's aft node, which rides on the aft point r_aft: as a point mass
    there it adds ΔA = [[P_m, −P_m S(r)], [S(r) P_m, −S(r) P_m S(r)]] to the mass blocks, and ΔA·(a*, ω̇*) to the
    loads (``astar``: the iterate's tow-point acceleration, body axes) — again both sides, so the converged
    step is unchanged while the iteration sees the aft node move with the body (its loads reach the body as
    the aft node's reaction at the iterate: ``tail_force``).

    ``reduced``: the body pitches only (roll and yaw held by constraint moments), so only the pitch row and
    column of A_rr take part: A_rr⁻¹ is replaced by e_y e_yᵀ / A_rr,yy.

    On entry ``fb``/``mb`` hold the body-axis loads from :func:`body_loads`; ``tail_force`` (global) is
    the reaction of a series-tow tail cable at the aft tow point. Adds the rigid-body Coriolis and
    centripetal terms, forms A = M_RB + M_A about the tow point, and adds ``Λᵀ A_eff Λ`` to the node
    mass and ``Λᵀ (F − A_tr A_rr⁻¹ M)`` to the node force. Returns ``X = A_rr⁻¹ A_rt`` and
    ``y = A_rr⁻¹ M`` so that afterwards ``ω̇ = y − X a`` (a = Λ r̈). False if A_rr is singular. ``att`` is
    scratch on return (A_tt is overwritten by the last rotation's products)."""
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
    if implicit:
        r0 = bp[b, BP_AFT_TOW_POINT]
        r1 = bp[b, BP_AFT_TOW_POINT + 1]
        r2 = bp[b, BP_AFT_TOW_POINT + 2]
        # aeff as scratch (written below): dtr = −P_m S(r) in aeff
        for i in range(3):
            aeff[i, 0] = -(pmass[i, 1] * r2 - pmass[i, 2] * r1)
            aeff[i, 1] = -(-pmass[i, 0] * r2 + pmass[i, 2] * r0)
            aeff[i, 2] = -(pmass[i, 0] * r1 - pmass[i, 1] * r0)
        for i in range(3):
            # (S(r) P_m)[i, :] = r × column ... row i of S times P_m
            for j in range(3):
                if i == 0:
                    srp = -r2 * pmass[1, j] + r1 * pmass[2, j]
                    srd = -r2 * aeff[1, j] + r1 * aeff[2, j]
                elif i == 1:
                    srp = r2 * pmass[0, j] - r0 * pmass[2, j]
                    srd = r2 * aeff[0, j] - r0 * aeff[2, j]
                else:
                    srp = -r1 * pmass[0, j] + r0 * pmass[1, j]
                    srd = -r1 * aeff[0, j] + r0 * aeff[1, j]
                # loads: F += P_m a* + dtr ω̇*, M += S P_m a* + (S dtr) ω̇*  (S dtr = −S P_m S)
                fb[i] += pmass[i, j] * astar[j] + aeff[i, j] * wdot[j]
                mb[i] += srp * astar[j] + srd * wdot[j]
                arr[i, j] += srd
        for i in range(3):
            for j in range(3):
                att[i, j] += pmass[i, j]
                atr[i, j] += aeff[i, j]
        for i in range(3):
            arr[i, i] += prot[i]
            mb[i] += prot[i] * wdot[i]
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
    # global: M += Λᵀ A_eff Λ ; F += Λᵀ f_eff (the products Λ_ki A_eff,km, the same for every j, are formed
    # once per i in att — A_tt is not needed any more: the same arithmetic in the same order)
    for i in range(3):
        for k in range(3):
            for m in range(3):
                att[k, m] = lam[k, i] * aeff[k, m]
        for j in range(3):
            sacc = 0.0
            for k in range(3):
                for m in range(3):
                    sacc += att[k, m] * lam[m, j]
            mnode[a, i, j] += sacc
        fnode[a, i] += lam[0, i] * tmp3[0] + lam[1, i] * tmp3[1] + lam[2, i] * tmp3[2]
    return True


@njit(cache=True)
def aft_transfer(b, lam, atr, arrinv, bp, G, H):
    """The condensed body's response to a global force f at its aft tow point (after :func:`_condense`, whose
    ``atr`` and ``arrinv`` — the reduced one for pitch-only bodies — it reads): its angular acceleration gains
    G f, G = A_rr⁻¹ S(r_aft) Λ, and its tow-point node's force gains H f, H = 1 − Λᵀ A_tr G (the force less
    the inertial reaction of the rotation it causes). The monolithic series coupling puts the tail's pull into
    the tension solve through H (``houbolt.node_local_solve``) and into the rotation through G."""
    r0 = bp[b, BP_AFT_TOW_POINT]
    r1 = bp[b, BP_AFT_TOW_POINT + 1]
    r2 = bp[b, BP_AFT_TOW_POINT + 2]
    for j in range(3):
        # S(r_aft) Λ e_j = r_aft × (column j of Λ)
        c0 = r1 * lam[2, j] - r2 * lam[1, j]
        c1 = r2 * lam[0, j] - r0 * lam[2, j]
        c2 = r0 * lam[1, j] - r1 * lam[0, j]
        for i in range(3):
            G[i, j] = arrinv[i, 0] * c0 + arrinv[i, 1] * c1 + arrinv[i, 2] * c2
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                # (Λᵀ A_tr)[i, k] = Σ_m Λ[m, i] A_tr[m, k]
                acc += (lam[0, i] * atr[0, k] + lam[1, i] * atr[1, k] + lam[2, i] * atr[2, k]) * G[k, j]
            H[i, j] = (1.0 if i == j else 0.0) - acc


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
    # damping first: its three loads share the unperturbed attitude, rotated once (each load is evaluated at the
    # same arguments as when the two estimates alternated per axis)
    _chart_rotation(ang[0], ang[1], ang[2], chart, b, lam)
    for k in range(3):
        vb[k] = lam[k, 0] * vnode[0] + lam[k, 1] * vnode[1] + lam[k, 2] * vnode[2]
    for i in range(3):
        if reduced and i != 1:
            bkc[b, BK_DAMPING + i] = 0.0
            continue
        for k in range(3):
            w2[k] = w[k]
        w2[i] += eps_w
        body_loads(b, lam, vb, w2, bp, btab_n, btab, rho, g, cur_b, f, m, bd)
        cc = -(m[i] - m0[i]) / eps_w
        bkc[b, BK_DAMPING + i] = cc if cc > 0.0 else 0.0
    for i in range(3):
        if reduced and i != 1:
            bkc[b, BK_STIFFNESS + i] = 0.0
            continue
        for k in range(3):
            ang2[k] = ang[k]
        ang2[i] += eps_a
        _chart_rotation(ang2[0], ang2[1], ang2[2], chart, b, lam)
        for k in range(3):
            vb[k] = lam[k, 0] * vnode[0] + lam[k, 1] * vnode[1] + lam[k, 2] * vnode[2]
        body_loads(b, lam, vb, w, bp, btab_n, btab, rho, g, cur_b, f, m, bd)
        kk = -(m[i] - m0[i]) / eps_a
        bkc[b, BK_STIFFNESS + i] = kk if kk > 0.0 else 0.0


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
                             m_tail, bkc, axial):
    """Adds to ``bkc[b, BK_STIFFNESS:BK_STIFFNESS + 3]`` the restoring stiffness of the tail's pull about the
    body's axes
    (e_i = body axis i): for a rotation δθ about e the aft point moves by u = e × d (d = aft point − body
    node) and K = T (d·t − (e·d)(e·t)) + k_ax (t·u)² + (T/ℓ)(|u|² − (t·u)²), clipped at 0 (t: direction
    of the pull). ``axial`` False leaves out the k_ax term (the monolithic series coupling solves the pull's
    change with the stretch in the Newton step). Relaxation only (see :func:`aft_segment_stiffness`)."""
    d0 = rs[c, 0] - rs[a, 0]
    d1 = rs[c, 1] - rs[a, 1]
    d2 = rs[c, 2] - rs[a, 2]
    for k in range(node_nseg[c]):
        s = node_segs[c, k]
        kax, kgeo = aft_segment_stiffness(s, m_tail, stretched, tens, l0, ea, hdt2)
        if kax == 0.0 and kgeo == 0.0:
            continue
        if not axial:
            kax = 0.0
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
                bkc[b, BK_STIFFNESS + i] += kk
