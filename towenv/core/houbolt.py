"""The Houbolt time step with the Newton iteration on segment tensions (model.md §§ 3–5), and ``advance``:
many steps with the tow point's path, step halving on failure, the winch and the attitude re-charting.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import njit, njit_internal
from .layout import (BK_DAMPING, BK_INERTIA, BK_STIFFNESS, BP_AFT_TOW_POINT, BP_CB, BP_REDUCED_DOF, BP_TAIL_MASS, COMPENSATOR,
                     COMP_FORCE, COMP_PASSIVE, COMP_POSITION, CS_ACT, CS_CONTACT, CS_HITS, CS_PEN, C_CMD, C_MODE,
                     C_B, C_K, C_NODE, C_RATE, C_SHIP, C_SMAX, C_SMIN, C_TAU, C_TRIAL, FAIL_ANGLE, FAIL_NAN, FAIL_NEWTON,
                     FAIL_STRETCH, FREE, NEED_REMESH, N_ITERATIONS, N_MAX_ITERATIONS, N_RECHARTS, N_STEPS,
                     N_STEP_CUTS, OK, PITCH_LIMIT, RECHART_PITCH, RETRY_CONTACT, S_ANGLE_TOLERANCE, S_AS_PUBLISHED,
                     PS_BODY_AGE, PS_BODY_VALID, CABLE_REUSE_EXTRA_ITERATIONS, PS_CABLE_AGE, PS_CABLE_ITERATIONS, PS_CABLE_VALID, PS_HIGHER, PS_VALID, S_BODY_REFRESH, S_CABLE_REFRESH, S_MAX_ITERATIONS, S_MAX_STEP_CUTS, S_MAX_STRAIN, S_NEWTON_ESTIMATE, S_PLANAR,
                     S_PREDICTOR, S_RECHART_PITCH,
                     S_RELATIVE_TOLERANCE, S_TOLERANCE, WS_LEN, WS_PAID, WS_V, W_LNOM, W_MODE, W_SEG)
from .actuators import _compensator_node, _end_stop_force, _winch_speed
from .body_dynamics import (_condense, _rotational_stiffness, _translational_damping, aft_rotational_stiffness,
                            aft_segment_stiffness, aft_transfer, body_loads, place_aft_nodes)
from .cable_loads import current_at, node_assembly, node_reaction, segment_loads
from .orbital_flow import _wave_flow
from .rotations import (_chart_rotation, _inv3, euler_rates_to_omega, omega_dot_to_euler_acc,
                        rechart_body)
from .tension_solve import (_positions_from_tensions, assemble_tension_system, thesis_recursion_solve,
                            tree_ldlt_solve)


@njit_internal
def houbolt_step(dt, r_top_new, top_node, topo, segp, bodyp, env, settings, state, ws, comp):
    """Advance one step of size dt. Returns (status, iterations, element, max|δT| of the last iteration).

    The step in its phases, each a compiled function of its own below: :func:`actuator_lag` and
    :func:`predict`; then per Newton iteration :func:`iterate_coefficients` (the loads at the iterate: cable
    segments, node assembly, rigid bodies condensed onto their tow-point nodes), :func:`node_local_solve`
    (every free node's 3×3 solve), :func:`tension_system`, the tree solve of the tension update and
    :func:`tension_apply`, :func:`body_angle_update`, and the convergence test; then :func:`end_stop_contact`
    and :func:`commit`.

    The step and its phases are compiled without numba's reference counting (``_nrt=False``; nothing they
    call allocates — the as-published recursion works in ``ws.recursion``). With it, numba takes and
    releases a reference on every array a function receives or reads out of a structure: the phases, called
    a few times per Newton iteration with 10–75 arrays each, measured 11–45 % slower per step than the
    single function they came from; without it they are 6–12 % faster than it (docs/architecture.md).

    On success ``state`` holds the new time level; on failure ``state`` is left untouched (the trial
    solution lives in the work arrays), so the caller can retry with a smaller step.
    """
    seg_lo, seg_up, node_kind = topo.seg_lo, topo.seg_up, topo.node_kind
    node_nseg, node_segs, node_sgn, order, pos = topo.node_nseg, topo.node_segs, topo.node_sgn, topo.order, topo.pos
    body_node, body_aft_node = topo.body_node, topo.body_aft_node
    # the tension tree: the lists above with aft tow points merged into their bodies' nodes (monolithic series
    # coupling, system.tension_cliques; identical to them otherwise)
    tn_nseg, tn_segs, tn_sgn, tseg_up, tseg_uplocal = topo.tn_nseg, topo.tn_segs, topo.tn_sgn, topo.tseg_up, topo.tseg_uplocal
    l0, diam, mu, cn, ct, can, cat, ea = segp.l0, segp.diam, segp.mu, segp.cn, segp.ct, segp.can, segp.cat, segp.ea
    bp, btab_n, btab, pb_mass, pb_vol = bodyp.bp, bodyp.btab_n, bodyp.btab, bodyp.pb_mass, bodyp.pb_vol
    pb_cda, pb_ca = bodyp.pb_cda, bodyp.pb_ca
    rho, g, cur_z, cur_v = env.rho, env.g, env.cur_z, env.cur_v
    tol_abs = settings[S_TOLERANCE]
    tol_rel = settings[S_RELATIVE_TOLERANCE]
    maxit = int(settings[S_MAX_ITERATIONS])
    max_strain = settings[S_MAX_STRAIN]
    ang_tol = settings[S_ANGLE_TOLERANCE]
    as_published = settings[S_AS_PUBLISHED] == 1.0
    # 2-D vertical-plane model (solver.planar): lateral node DOF and body roll/yaw frozen
    planar = settings.shape[0] > S_PLANAR and settings[S_PLANAR] != 0.0
    # Newton stopping on the estimated remaining error (solver.newton_stop = "estimate")
    stop_estimate = settings.shape[0] > S_NEWTON_ESTIMATE and settings[S_NEWTON_ESTIMATE] != 0.0
    # the predictor's orders chosen step by step from its memory (solver.predictor = "adaptive")
    adaptive = settings.shape[0] > S_PREDICTOR and settings[S_PREDICTOR] != 0.0
    prev_d = 0.0
    prev_a = 0.0
    hist_r, hist_ang, tens_hist, top_react = state.hist_r, state.hist_ang, state.tens_hist, state.top_react
    cstate, chart = state.cstate, state.chart
    older_r, older_ang, older_tens = state.older_r, state.older_ang, state.older_tens
    cubic_r, cubic_ang, quad_tens, pred_state = state.cubic_r, state.cubic_ang, state.quad_tens, state.pred_state
    body_relax, body_damp = state.body_relax, state.body_damp
    node_matrix, node_inverse = state.node_matrix, state.node_inverse
    # the bodies' load derivatives: computed on this step's first iteration, or those of an earlier step reused
    # (solver.body_derivative_refresh)
    body_fresh = body_derivatives_due(settings, pred_state)
    tang, stretched, drag, bmat, madd, mnode = ws.tang, ws.stretched, ws.drag, ws.bmat, ws.madd, ws.mnode
    bnode, fnode, acon, qvec, rs, vs, kd, kb = ws.bnode, ws.fnode, ws.acon, ws.qvec, ws.rs, ws.vs, ws.kd, ws.kb
    rhs, dT, gres, tens, bX, by, blam, angs = ws.rhs, ws.dT, ws.gres, ws.tens, ws.bX, ws.by, ws.blam, ws.angs
    dang, omg, hvec, tmp3, tmp33, tmp33b, att = ws.dang, ws.omg, ws.hvec, ws.tmp3, ws.tmp33, ws.tmp33b, ws.att
    atr, arr, arrinv, cur_b, fb, mb, bdiag = ws.atr, ws.arr, ws.arrinv, ws.cur_b, ws.fb, ws.mb, ws.bdiag
    react, bkc, bdmat, scr, flow = ws.react, ws.bkc, ws.bdmat, ws.scr, ws.flow
    gaft, haft, qaft = ws.gaft, ws.haft, ws.qaft

    nb = body_node.shape[0]
    r_t = hist_r[0]
    r_tm1 = hist_r[1]
    r_tm2 = hist_r[2]

    cmode = int(comp[C_MODE])
    cnode = int(comp[C_NODE])
    act_new = actuator_lag(dt, comp, cmode, cstate)
    predict(top_node, r_top_new, hist_r, hist_ang, tens_hist, chart, body_node, body_aft_node, bp, rs, angs, tens,
            tmp33, older_r, older_ang, older_tens, cubic_r, cubic_ang, quad_tens, pred_state)

    # series tows only: the body–tail relaxation below is skipped entirely without an aft tow point
    any_aft, any_merged = series_flags(body_aft_node, tn_nseg)
    # the free nodes' Newton matrices: built at every iteration of this step, or those of an earlier step reused
    # (solver.cable_jacobian_refresh)
    cable_fresh = cable_jacobian_due(settings, pred_state, any_aft)
    status = FAIL_NEWTON
    elem = -1
    it = 0
    maxd = 0.0
    for it in range(1, maxit + 1):
        # --- coefficients at the current iterate
        bad = iterate_coefficients(it, dt, planar, any_aft, r_t, r_tm1, r_tm2, hist_ang, flow, seg_lo, seg_up,
                                   node_kind, node_nseg, node_segs, node_sgn, body_node, body_aft_node, l0, diam, mu,
                                   cn, ct, can, cat, ea, bp, btab_n, btab, pb_mass, pb_vol, pb_cda, pb_ca, rho, g,
                                   cur_z, cur_v, chart, rs, vs, angs, tang, stretched, drag, bmat, madd, mnode, bnode,
                                   fnode, tens, dang, blam, omg, tmp3, cur_b, fb, mb, bdiag, bkc, scr, tmp33, bdmat,
                                   react, att, atr, arr, arrinv, hvec, tmp33b, bX, by, tn_nseg, gaft, haft,
                                   body_fresh, body_relax, body_damp, cable_fresh, ws.no_bmat)
        if bad:
            return FAIL_NAN, it, -1, 0.0
        # --- node-local solve: r_a = A_a + Σ σ T q_a,k
        a_bad = node_local_solve(dt, any_aft, planar, comp, cmode, act_new, r_t, r_tm1, r_tm2, rs, node_kind,
                                 node_nseg, node_segs, body_node, body_aft_node, bp, l0, ea, tang, stretched, tens,
                                 mnode, bnode, fnode, acon, qvec, att, tmp33, tmp33b, hvec, tmp3, tn_nseg, tn_segs,
                                 haft, cable_fresh, node_matrix, node_inverse)
        if a_bad >= 0:
            return FAIL_NAN, it, a_bad, 0.0
        if any_merged:
            aft_point_influence(dt, planar, body_node, body_aft_node, tn_nseg, tn_segs, node_nseg, bp, blam, angs, bX,
                                bkc, gaft, tang, qvec, qaft, tmp33, tmp33b)
        # --- positions at the current tensions, residuals, Newton update of the tensions
        tmax = tension_system(seg_lo, seg_up, tseg_up, node_kind, tn_nseg, tn_segs, tn_sgn, l0, ea, tang, qvec,
                              acon, tens, rs, angs, chart, body_node, body_aft_node, bp, tmp33, gres, rhs, kd, kb,
                              node_nseg, qaft)
        if as_published:
            if not thesis_recursion_solve(order, tseg_up, tseg_uplocal, seg_lo, tn_nseg, tn_segs, kd, kb, rhs, dT,
                                          gres, ws.recursion):
                return FAIL_NEWTON, it, -1, 0.0
        elif not tree_ldlt_solve(order, tseg_up, tseg_uplocal, node_kind, tn_nseg, tn_segs, pos, kd, kb, rhs, dT):
            return FAIL_NEWTON, it, -1, 0.0
        elem, maxd, any_slack = tension_apply(node_kind, tn_nseg, tn_segs, tn_sgn, acon, qvec, dT, tens, rs)
        if not math.isfinite(maxd):
            return FAIL_NAN, it, elem, maxd
        if any_merged:
            aft_pull_on_rotation(body_aft_node, tn_nseg, node_nseg, node_segs, node_sgn, tang, tens, gaft, by)
        # --- body rotations: ω̇ = A_rr⁻¹(M − A_rt a), Houbolt on the Euler angles
        b_bad, dang_max = body_angle_update(dt, planar, r_t, r_tm1, r_tm2, rs, hist_ang, angs, dang, omg, blam,
                                            body_node, bp, bX, by, bkc, tmp3, hvec, body_aft_node, tn_nseg)
        if b_bad >= 0:
            return FAIL_ANGLE, it, b_bad, maxd
        if not math.isfinite(dang_max):
            return FAIL_NAN, it, -1, maxd
        place_aft_nodes(rs, angs, chart, body_node, body_aft_node, bp, tmp33)
        # --- convergence test
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
        if not cable_fresh and it >= pred_state[PS_CABLE_ITERATIONS] + CABLE_REUSE_EXTRA_ITERATIONS:
            # the kept matrices converge too slowly here: give up, advance retries the step with fresh ones
            break
        prev_d = maxd
        prev_a = dang_max
    if status != OK:
        return status, it, elem, maxd
    # --- end-stop contact: exact (the sheave is held at the stop while the stop pushes)
    if cmode == COMP_PASSIVE or cmode == COMP_FORCE:
        if end_stop_contact(dt, top_node, cnode, comp, r_t, r_tm1, r_tm2, rs, node_nseg, node_segs, node_sgn, tang,
                            tens, mnode, fnode):
            return RETRY_CONTACT, it, cnode, maxd
    # --- checks and commit
    bad_kind, bad_elem = commit(dt, top_node, cnode, cmode, act_new, max_strain, comp, cstate, ea, tens, rs, angs,
                                r_t, r_tm1, r_tm2, hist_r, hist_ang, tens_hist, top_react, react, node_nseg, node_segs,
                                node_sgn, tang, mnode, fnode, adaptive, it, older_r, older_ang, older_tens, cubic_r,
                                cubic_ang, quad_tens, pred_state)
    if bad_kind != OK:
        return bad_kind, it, bad_elem, maxd
    if body_fresh:
        pred_state[PS_BODY_VALID] = 1.0
        pred_state[PS_BODY_AGE] = 1.0
    else:
        pred_state[PS_BODY_AGE] += 1.0
    if cable_fresh:
        pred_state[PS_CABLE_VALID] = 1.0
        pred_state[PS_CABLE_AGE] = 1.0
        pred_state[PS_CABLE_ITERATIONS] = it
    else:
        pred_state[PS_CABLE_AGE] += 1.0
        if it > pred_state[PS_CABLE_ITERATIONS]:
            # the kept matrices slowed the iteration down: the next step builds them afresh
            pred_state[PS_CABLE_VALID] = 0.0
    return OK, it, -1, maxd


@njit_internal
def keep_body_derivatives(b, bkc, bdmat, body_relax, body_damp):
    """Body ``b``'s rotational stiffness and damping (``bkc``, BK_STIFFNESS/BK_DAMPING) and translational damping
    (``bdmat``) kept in ``body_relax``/``body_damp`` for the next steps."""
    for i in range(3):
        body_relax[b, i] = bkc[b, BK_STIFFNESS + i]
        body_relax[b, 3 + i] = bkc[b, BK_DAMPING + i]
        for j in range(3):
            body_damp[b, i, j] = bdmat[b, i, j]


@njit_internal
def reuse_body_derivatives(b, body_relax, body_damp, bkc, bdmat):
    """The kept derivatives of body ``b`` (:func:`keep_body_derivatives`) back into ``bkc``/``bdmat``."""
    for i in range(3):
        bkc[b, BK_STIFFNESS + i] = body_relax[b, i]
        bkc[b, BK_DAMPING + i] = body_relax[b, 3 + i]
        for j in range(3):
            bdmat[b, i, j] = body_damp[b, i, j]


@njit_internal
def body_derivatives_due(settings, pred_state):
    """Whether the next step computes the rigid bodies' load derivatives afresh (finite differences on its first
    iteration: :func:`towenv.core.body_dynamics._rotational_stiffness` and ``_translational_damping``) rather
    than reuse those kept in ``TimeLevels.body_relax``/``body_damp``: always with ``solver.body_derivative_refresh``
    ≤ 1 (or a settings array without it), when none are kept (``PS_BODY_VALID`` = 0: initial state, a restore
    without them, a re-chart, a failed step) and when they have served ``refresh`` steps."""
    refresh = settings[S_BODY_REFRESH] if settings.shape[0] > S_BODY_REFRESH else 1.0
    return refresh <= 1.0 or pred_state[PS_BODY_VALID] == 0.0 or pred_state[PS_BODY_AGE] >= refresh


@njit_internal
def cable_jacobian_due(settings, pred_state, any_aft):
    """Whether this step builds the free nodes' Newton matrices M̃ = M + (11Δt/12) B + ½Δt² K_g and their inverses
    at every iteration (:func:`node_local_solve`) rather than reuse those kept in ``TimeLevels.node_matrix`` /
    ``node_inverse`` (a modified Newton; a compensator's sheave node keeps its vertical drag damping there too):
    always with ``solver.cable_jacobian_refresh`` ≤ 1 (or a settings array without it), with a series tow's aft tow
    point (its coupling terms are built with the matrix), when none are kept (``PS_CABLE_VALID`` = 0:
    initial state, a restore without them, a remesh, a failed step) and when they have served ``refresh`` steps."""
    refresh = settings[S_CABLE_REFRESH] if settings.shape[0] > S_CABLE_REFRESH else 1.0
    return (refresh <= 1.0 or any_aft or pred_state[PS_CABLE_VALID] == 0.0 or pred_state[PS_CABLE_AGE] >= refresh)


@njit_internal
def series_flags(body_aft_node, tn_nseg):
    """(any body tows a tail from an aft tow point, any such point is merged into its body's node).

    A function of its own for the compiler's sake: computed inline from ``False`` literals, numba's type
    inference first saw ``any_aft`` as the literal ``False`` and compiled the phases that take it
    (:func:`iterate_coefficients`, :func:`node_local_solve`) a second time for that type."""
    any_aft = False
    any_merged = False
    for b in range(body_aft_node.shape[0]):
        if body_aft_node[b] >= 0:
            any_aft = True
            if tn_nseg[body_aft_node[b]] == 0:
                any_merged = True
    return any_aft, any_merged


@njit_internal
def actuator_lag(dt, comp, cmode, cstate):
    """The compensator actuator's command after this step: first-order lag with a rate limit (explicit, once per
    step) in position/force mode; its current value otherwise."""
    act_new = cstate[CS_ACT]
    if cmode == COMP_POSITION or cmode == COMP_FORCE:
        rate = (comp[C_CMD] - cstate[CS_ACT]) / max(comp[C_TAU], dt)
        if rate > comp[C_RATE]:
            rate = comp[C_RATE]
        elif rate < -comp[C_RATE]:
            rate = -comp[C_RATE]
        act_new = cstate[CS_ACT] + dt * rate
    return act_new


@njit_internal
def predict(top_node, r_top_new, hist_r, hist_ang, tens_hist, chart, body_node, body_aft_node, bp, rs, angs, tens,
            tmp33, older_r, older_ang, older_tens, cubic_r, cubic_ang, quad_tens, pred_state):
    """Predictor of the Newton iteration: node positions and body angles extrapolated quadratically from the last
    three time levels, the tow point at its new position, tensions extrapolated linearly (clamped at 0) — or, per
    node, body and segment where the predictor's memory says so (written by :func:`choose_predictor` under
    ``solver.predictor = "adaptive"``), one order higher with the level before: cubically, and quadratically."""
    nn = rs.shape[0]
    nb = body_node.shape[0]
    ns = tens.shape[0]
    for a in range(nn):
        for i in range(3):
            rs[a, i] = 3.0 * hist_r[0, a, i] - 3.0 * hist_r[1, a, i] + hist_r[2, a, i]
    for b in range(nb):
        for i in range(3):
            angs[b, i] = 3.0 * hist_ang[0, b, i] - 3.0 * hist_ang[1, b, i] + hist_ang[2, b, i]
    for s in range(ns):
        tp = 2.0 * tens_hist[0, s] - tens_hist[1, s]      # linear extrapolation of the tensions
        tens[s] = tp if tp > 0.0 else 0.0
    if pred_state[PS_VALID] != 0.0:
        for a in range(nn):
            if cubic_r[a] != 0.0:
                for i in range(3):
                    rs[a, i] = 4.0 * hist_r[0, a, i] - 6.0 * hist_r[1, a, i] + 4.0 * hist_r[2, a, i] - older_r[a, i]
        for b in range(nb):
            if cubic_ang[b] != 0.0:
                for i in range(3):
                    angs[b, i] = (4.0 * hist_ang[0, b, i] - 6.0 * hist_ang[1, b, i] + 4.0 * hist_ang[2, b, i]
                                  - older_ang[b, i])
        for s in range(ns):
            if quad_tens[s] != 0.0:
                tp = 3.0 * tens_hist[0, s] - 3.0 * tens_hist[1, s] + older_tens[s]
                tens[s] = tp if tp > 0.0 else 0.0
    for i in range(3):
        rs[top_node, i] = r_top_new[i]
    place_aft_nodes(rs, angs, chart, body_node, body_aft_node, bp, tmp33)


@njit_internal
def choose_predictor(iterations, rs, angs, tens, hist_r, hist_ang, tens_hist, older_r, older_ang, older_tens,
                     cubic_r, cubic_ang, quad_tens, pred_state):
    """The predictor's choice for the next step, per node, body and segment: the extrapolation that would have
    predicted this step's converged solution better (a node's or body's largest error over its three coordinates,
    a segment's with the tensions clamped at 0 as the predictor clamps them; a tie keeps the lower order); without
    a valid memory the lower orders. Then the oldest levels go into the memory (before :func:`commit` shifts the
    history). The quadratic prediction's error is q, the cubic one's q + d with d = h⁰ − 3h¹ + 3h² − h³ (the
    difference of the two extrapolations).

    A step that converged on its first iteration from the lower orders everywhere keeps them without comparing
    (the comparison costs ~1 µs per 100 nodes: 4–5 % of a step of the 1 km turn, where every step takes one
    iteration)."""
    valid = pred_state[PS_VALID] != 0.0
    if valid and iterations <= 1 and pred_state[PS_HIGHER] == 0.0:
        remember_levels(hist_r, hist_ang, tens_hist, older_r, older_ang, older_tens, pred_state)
        return
    higher = 0.0
    for a in range(rs.shape[0]):
        cubic_r[a] = 1.0 if valid and _cubic_better(hist_r, rs, older_r, a) else 0.0
        higher += cubic_r[a]
    for b in range(angs.shape[0]):
        cubic_ang[b] = 1.0 if valid and _cubic_better(hist_ang, angs, older_ang, b) else 0.0
        higher += cubic_ang[b]
    for s in range(tens.shape[0]):
        t1 = 2.0 * tens_hist[0, s] - tens_hist[1, s]
        t2 = 3.0 * tens_hist[0, s] - 3.0 * tens_hist[1, s] + older_tens[s]
        e2 = abs((t1 if t1 > 0.0 else 0.0) - tens[s])
        e3 = abs((t2 if t2 > 0.0 else 0.0) - tens[s])
        quad_tens[s] = 1.0 if valid and e3 < e2 else 0.0
        higher += quad_tens[s]
    pred_state[PS_HIGHER] = higher
    remember_levels(hist_r, hist_ang, tens_hist, older_r, older_ang, older_tens, pred_state)


@njit_internal
def _cubic_better(hist, x, older, k):
    """Whether row ``k`` (a node or a body: three coordinates) of the converged ``x`` was predicted better by the cubic
    extrapolation (with ``older``) than by the quadratic one, comparing each one's largest error over the
    coordinates; a tie is not better."""
    e2 = 0.0
    e3 = 0.0
    for i in range(3):
        h0 = hist[0, k, i]
        h1 = hist[1, k, i]
        h2 = hist[2, k, i]
        q = 3.0 * h0 - 3.0 * h1 + h2 - x[k, i]
        d = h0 - 3.0 * h1 + 3.0 * h2 - older[k, i]
        e2 = max(e2, abs(q))
        e3 = max(e3, abs(q + d))
    return e3 < e2


@njit_internal
def remember_levels(hist_r, hist_ang, tens_hist, older_r, older_ang, older_tens, pred_state):
    """The oldest time levels into the predictor's memory (before :func:`commit` shifts the history)."""
    for a in range(hist_r.shape[1]):
        for i in range(3):
            older_r[a, i] = hist_r[2, a, i]
    for b in range(hist_ang.shape[1]):
        for i in range(3):
            older_ang[b, i] = hist_ang[2, b, i]
    for s in range(tens_hist.shape[1]):
        older_tens[s] = tens_hist[1, s]
    pred_state[PS_VALID] = 1.0


@njit_internal
def iterate_coefficients(it, dt, planar, any_aft, r_t, r_tm1, r_tm2, hist_ang, flow, seg_lo, seg_up, node_kind,
                         node_nseg, node_segs, node_sgn, body_node, body_aft_node, l0, diam, mu, cn, ct, can, cat, ea,
                         bp, btab_n, btab, pb_mass, pb_vol, pb_cda, pb_ca, rho, g, cur_z, cur_v, chart, rs, vs, angs,
                         tang, stretched, drag, bmat, madd, mnode, bnode, fnode, tens, dang, blam, omg, tmp3, cur_b,
                         fb, mb, bdiag, bkc, scr, tmp33, bdmat, react, att, atr, arr, arrinv, hvec, tmp33b, bX, by,
                         tn_nseg, gaft, haft, body_fresh, body_relax, body_damp, cable_fresh, no_bmat):
    """Loads and their linearisations at the current iterate ``rs`` (Newton iteration ``it``): node velocities
    (Houbolt, relative to the orbital flow), cable segment loads, node assembly, the rigid bodies' loads
    condensed onto their tow-point nodes (their rotational stiffness and damping on the first iteration), and
    for series tows the tail's restoring moment. With the monolithic series coupling (an aft node ``c`` with
    ``tn_nseg[c] == 0``) the tail segments' pull is left out of the body's loads here — it enters the tension
    solve through H_b and the rotation through G_b (``gaft``, ``haft``: :func:`aft_transfer`) — and only the aft
    node's own loads and inertia are a load on the body. The bodies' load derivatives (first iteration): with
    ``body_fresh`` by finite differences, kept in ``body_relax``/``body_damp``; otherwise those kept, reused.
    The cable drag Jacobians (``bmat``, assembled into ``bnode``) only when the nodes' Newton matrices are built
    (``cable_fresh``; an empty ``bmat`` tells :func:`segment_loads` and :func:`node_assembly` to skip them).
    Returns True when a body's condensation failed (NaN)."""
    nn = rs.shape[0]
    nb = body_node.shape[0]
    i6dt = 1.0 / (6.0 * dt)
    hdt2 = 0.5 * dt * dt
    for a in range(nn):
        for i in range(3):
            # velocity relative to the wave orbital flow (zero unless [sea] orbital_velocities is on);
            # the current is subtracted where each load is evaluated
            vs[a, i] = (11.0 * rs[a, i] - 18.0 * r_t[a, i] + 9.0 * r_tm1[a, i] - 2.0 * r_tm2[a, i]) * i6dt \
                - flow[a, i]
    jac = bmat if cable_fresh else no_bmat
    segment_loads(rs, vs, seg_lo, seg_up, l0, diam, mu, cn, ct, can, cat, rho, g, cur_z, cur_v,
                  tang, stretched, drag, jac, madd)
    node_assembly(rs, vs, node_kind, node_nseg, node_segs, node_sgn, l0, diam, mu, rho, g, drag, jac, madd,
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
            if body_fresh:
                _rotational_stiffness(b, angs[b], chart, vs[a], w, bp, btab_n, btab, rho, g, cur_b, mb, bkc, scr,
                                      tmp33, reduced)
                _translational_damping(b, lam, tmp3, w, bp, btab_n, btab, rho, g, cur_b, fb, bdmat[b], scr, planar)
                keep_body_derivatives(b, bkc, bdmat, body_relax, body_damp)
            else:
                reuse_body_derivatives(b, body_relax, body_damp, bkc, bdmat)
        c = body_aft_node[b]
        merged = c >= 0 and tn_nseg[c] == 0
        if merged:
            if it == 1:
                # the tail's restoring moment at a fixed pull (its change with the stretch is in the Newton
                # step: aft_point_influence)
                # (axial = not merged = False, as a runtime bool: literal True/False arguments made numba compile
                # the function once per literal)
                aft_rotational_stiffness(b, a, c, rs, lam, node_nseg, node_segs, seg_up, tang, stretched, tens, l0,
                                         ea, hdt2, bp[b, BP_TAIL_MASS], bkc, not merged)
            # the condensation's implicit rotation: P = diag(½Δt² k + (11Δt/12) c), ω̇* of the iterate
            iterate_omega_dot(dt, b, angs, hist_ang, dang, omg, scr[5], scr[4], tmp33b)
            for i in range(3):
                scr[4, i] = hdt2 * bkc[b, BK_STIFFNESS + i] + 11.0 * dt / 12.0 * bkc[b, BK_DAMPING + i]
            aft_node_point_mass(b, a, c, dt, lam, rs, r_t, r_tm1, r_tm2, mnode, bnode, tmp33, scr[3])
        if c >= 0:
            node_reaction(c, rs, r_t, r_tm1, r_tm2, dt, node_nseg, node_segs, node_sgn, tang, tens,
                          mnode, fnode, react)
            if merged:
                # monolithic series coupling: the tail segments' pull is solved with the tensions
                for k in range(node_nseg[c]):
                    sk = node_segs[c, k]
                    for i in range(3):
                        react[i] -= node_sgn[c, k] * tens[sk] * tang[sk, i]
        if not _condense(b, a, c >= 0, lam, w, react, bp, fb, mb, att, atr, arr, arrinv, hvec, tmp3,
                         tmp33b, bX[b], by[b], mnode, fnode, reduced, merged, scr[4], scr[5], tmp33, scr[3]):
            return True
        if merged:
            aft_transfer(b, lam, atr, arrinv, bp, gaft[b], haft[b])
            for i in range(3):
                arr[i, i] -= scr[4, i]
        for i in range(3):
            bkc[b, BK_INERTIA + i] = arr[i, i]
        # body hydrodynamic damping −∂F/∂v (body axes, full matrix) rotated to global: Λᵀ D Λ (the products
        # Λ_ki D_km, the same for every j, are formed once per i in tmp33: the same arithmetic in the same order)
        for i in range(3):
            for k in range(3):
                for m in range(3):
                    tmp33[k, m] = lam[k, i] * bdmat[b, k, m]
            for j in range(3):
                sacc = 0.0
                for k in range(3):
                    for m in range(3):
                        sacc += tmp33[k, m] * lam[m, j]
                bnode[a, i, j] += sacc
    if it == 1 and any_aft:
        # series tows: the tail's restoring moment relaxes the body-angle update (rate only)
        for b in range(nb):
            c = body_aft_node[b]
            relaxed = c >= 0 and tn_nseg[c] != 0
            if relaxed:                          # (relaxed coupling; the monolithic one did it above)
                aft_rotational_stiffness(b, body_node[b], c, rs, blam[b], node_nseg, node_segs, seg_up, tang,
                                         stretched, tens, l0, ea, hdt2, bp[b, BP_TAIL_MASS], bkc, relaxed)
    return False


@njit_internal
def node_local_solve(dt, any_aft, planar, comp, cmode, act_new, r_t, r_tm1, r_tm2, rs, node_kind, node_nseg,
                     node_segs, body_node, body_aft_node, bp, l0, ea, tang, stretched, tens, mnode, bnode, fnode,
                     acon, qvec, att, tmp33, tmp33b, hvec, tmp3, tn_nseg, tn_segs, haft, cable_fresh, node_matrix,
                     node_inverse):
    """Every free node's position as a function of its segments' tensions, r_a = A_a + Σ σ T q_a,k (acon,
    qvec; over the node's list in the tension tree), from the node's 3×3 system at the current iterate; the
    compensator's sheave node by its own law. A body's tow-point node with a merged aft tow point (monolithic
    series coupling) also carries the tail segments: q = ½Δt² M̃⁻¹ H_b t. With ``cable_fresh`` each node's M̃ is
    built at the iterate and inverted, and both are kept in ``node_matrix``/``node_inverse``; otherwise the kept
    ones serve (a modified Newton: M̃_kept r = M h + (M̃_kept − M) r* + ½Δt² F, whose fixed point is the same
    M r = M h + ½Δt² F as with the matrix of the iterate — only the rate changes). Returns the index of a node
    whose matrix is singular, or −1."""
    nn = rs.shape[0]
    nb = body_node.shape[0]
    c11 = 11.0 * dt / 12.0
    hdt2 = 0.5 * dt * dt
    for a in range(nn):
        if node_kind[a] == COMPENSATOR:
            # the sheave's law reads the node's vertical drag damping, a rate-only term of its implicit update: kept
            # with the node matrices (in this non-free node's unused slot) and restored when they are reused
            if cable_fresh:
                node_matrix[a, 2, 2] = bnode[a, 2, 2]
            else:
                bnode[a, 2, 2] = node_matrix[a, 2, 2]
            _compensator_node(a, int(comp[C_SHIP]), comp, cmode, act_new, dt, rs, r_t, r_tm1, r_tm2, node_nseg,
                              node_segs, tang, stretched, tens, mnode, bnode, fnode, acon, qvec)
            continue
        if node_kind[a] != FREE:
            continue
        hb = -1
        if cable_fresh:
            # M̃ = M + (11Δt/12) B + ½Δt² K_g: implicit drag and the node's own geometric (string)
            # stiffness K_g = Σ (T/ℓ)(1 − t tᵀ). Both are linearisations about the iterate r*, added on
            # both sides, so they change the convergence rate only, never the converged solution.
            # (K_g accumulates in att segment by segment: per entry the same sum in the same order as a sum per
            # entry, with T/ℓ divided once per segment instead of once per entry)
            for i in range(3):
                for j in range(3):
                    att[i, j] = 0.0
            for k in range(node_nseg[a]):
                sk = node_segs[a, k]
                if stretched[sk] > 0.0:
                    t_over_l = tens[sk] / stretched[sk]
                    for i in range(3):
                        for j in range(3):
                            att[i, j] += t_over_l * ((1.0 if i == j else 0.0) - tang[sk, i] * tang[sk, j])
            for i in range(3):
                for j in range(3):
                    att[i, j] = c11 * bnode[a, i, j] + hdt2 * att[i, j]
                    tmp33[i, j] = mnode[a, i, j] + att[i, j]
            # a body towing a tail from its aft tow point. Relaxed coupling: the tail's pull is a load on the body
            # inside the Newton loop (block Gauss–Seidel); its stiffness against the body's motion, ½Δt²(k_ax t tᵀ
            # + T/ℓ (1 − t tᵀ)), is added to both sides like K_g above (rate only, aft_segment_stiffness).
            # Monolithic coupling: the pull is in the tension solve, the aft node's inertia and drag in the body's
            # condensation (body_dynamics._condense); the tail segments' string stiffness, which moves with the tow
            # point, enters both sides through H (again the rate only)
            for b in range(nb if any_aft else 0):
                c = body_aft_node[b]
                if body_node[b] != a or c < 0:
                    continue
                if tn_nseg[c] == 0:
                    hb = b
                    for i in range(3):
                        for j in range(3):
                            tmp33b[i, j] = 0.0
                    for k in range(node_nseg[c]):
                        sk = node_segs[c, k]
                        kax, kgeo = aft_segment_stiffness(sk, bp[b, BP_TAIL_MASS], stretched, tens, l0, ea, hdt2)
                        if kgeo == 0.0:
                            continue
                        for i in range(3):
                            for j in range(3):
                                tmp33b[i, j] += hdt2 * kgeo * ((1.0 if i == j else 0.0) - tang[sk, i] * tang[sk, j])
                    for i in range(3):
                        for j in range(3):
                            add = haft[b, i, 0] * tmp33b[0, j] + haft[b, i, 1] * tmp33b[1, j] + haft[b, i, 2] * tmp33b[2, j]
                            att[i, j] += add
                            tmp33[i, j] += add
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
                return a
            for i in range(3):
                for j in range(3):
                    node_matrix[a, i, j] = tmp33[i, j]
                    node_inverse[a, i, j] = tmp33b[i, j]
        else:
            # the kept M̃ and its inverse; att = M̃ − M of this iterate's M (the rate terms on both sides)
            for i in range(3):
                for j in range(3):
                    tmp33b[i, j] = node_inverse[a, i, j]
                    att[i, j] = node_matrix[a, i, j] - mnode[a, i, j]
        for j in range(3):
            hvec[j] = 2.5 * r_t[a, j] - 2.0 * r_tm1[a, j] + 0.5 * r_tm2[a, j]
        for i in range(3):
            hi = 0.0
            for j in range(3):
                hi += mnode[a, i, j] * hvec[j] + att[i, j] * rs[a, j]
            tmp3[i] = hi + hdt2 * fnode[a, i]
        for i in range(3):
            acon[a, i] = tmp33b[i, 0] * tmp3[0] + tmp33b[i, 1] * tmp3[1] + tmp33b[i, 2] * tmp3[2]
        for k in range(tn_nseg[a]):
            s = tn_segs[a, k]
            if k < node_nseg[a]:
                for i in range(3):
                    hvec[i] = tang[s, i]
            else:       # a tail segment of the merged aft tow point: its pull moves the node through H_b
                for i in range(3):
                    hvec[i] = haft[hb, i, 0] * tang[s, 0] + haft[hb, i, 1] * tang[s, 1] + haft[hb, i, 2] * tang[s, 2]
            for i in range(3):
                qvec[a, k, i] = hdt2 * (tmp33b[i, 0] * hvec[0] + tmp33b[i, 1] * hvec[1] + tmp33b[i, 2] * hvec[2])
    if planar:
        # vertical-plane model: free nodes hold their lateral coordinate. The scenes it accepts have no
        # x–y or y–z coupling in M̃ (no lateral tangent, velocity or body asymmetry), so the (x, z) rows
        # of the 3-D solve are the plane's own solve (a separate 2×2 path measured slower)
        for a in range(nn):
            if node_kind[a] == FREE:
                acon[a, 1] = r_t[a, 1]
                for k in range(tn_nseg[a]):
                    qvec[a, k, 1] = 0.0
    return -1


@njit_internal
def tension_system(seg_lo, seg_up, tseg_up, node_kind, node_nseg, node_segs, node_sgn, l0, ea, tang, qvec, acon, tens,
                   rs, angs, chart, body_node, body_aft_node, bp, tmp33, gres, rhs, kd, kb, own_nseg, qaft):
    """The Newton system of the segment tensions on the tree: positions at the current tensions, the length
    residuals g_s = ℓ_s − ℓ0_s (1 + T_s/EA_s) as the right-hand side, the tension matrix (kd, kb) with slack
    segments held at T = 0. ``node_*`` and ``tseg_up`` are the tension tree's lists (aft tow points merged
    under the monolithic series coupling); ``seg_up`` the cable's own upper nodes (where the length is
    measured). Under the monolithic series coupling the rows of the tail segments hanging from a merged aft
    point (slots ``own_nseg[a]`` and up of the body node's list) use ∂r_aft/∂T (``qaft``, the body's rotation
    included) in place of the node's ∂r_a/∂T. Returns the largest tension (for the relative tolerance)."""
    ns = tens.shape[0]
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
    assemble_tension_system(node_kind, node_nseg, node_segs, node_sgn, tang, qvec, l0, ea, tens, kd, kb)
    for b in range(body_node.shape[0]):
        c = body_aft_node[b]
        if c < 0 or node_nseg[c] != 0:
            continue
        a = body_node[b]
        for k1 in range(own_nseg[a], node_nseg[a]):
            s1 = node_segs[a, k1]
            for k2 in range(node_nseg[a]):
                val = node_sgn[a, k1] * node_sgn[a, k2] * (tang[s1, 0] * qaft[b, k2, 0] + tang[s1, 1] * qaft[b, k2, 1]
                                                           + tang[s1, 2] * qaft[b, k2, 2])
                if k1 == k2:
                    kd[s1] += val - node_sgn[a, k1] * node_sgn[a, k2] * (
                        tang[s1, 0] * qvec[a, k2, 0] + tang[s1, 1] * qvec[a, k2, 1] + tang[s1, 2] * qvec[a, k2, 2])
                else:
                    kb[a, k1, k2] = val
    for s in range(ns):
        rhs[s] = gres[s]
        if tens[s] <= 0.0 and gres[s] < 0.0:
            # slack segment: hold T = 0 (row and column replaced by identity)
            kd[s] = 1.0
            rhs[s] = -tens[s]
            for e in range(2):
                a = seg_lo[s] if e == 0 else tseg_up[s]
                for k in range(node_nseg[a]):
                    if node_segs[a, k] == s:
                        for k2 in range(node_nseg[a]):
                            kb[a, k, k2] = 0.0
                            kb[a, k2, k] = 0.0
    return tmax


@njit_internal
def tension_apply(node_kind, node_nseg, node_segs, node_sgn, acon, qvec, dT, tens, rs):
    """The Newton update T ← max(T + δT, 0) and the node positions at the new tensions (same coefficients).
    Returns (segment of the largest change, the largest change — NaN-safe —, any segment slack)."""
    ns = tens.shape[0]
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
    if math.isfinite(maxd):
        _positions_from_tensions(node_kind, node_nseg, node_segs, node_sgn, tens, acon, qvec, rs)
    return elem, maxd, any_slack


@njit_internal
def aft_node_point_mass(b, a, c, dt, lam, rs, r_t, r_tm1, r_tm2, mnode, bnode, pmass, astar):
    """For the condensation of a body with a monolithically coupled tail (``body_dynamics._condense``): the aft
    node's mass and drag damping, P_m = Λ (M_c + (11Δt/12) B_c) Λᵀ (body axes) — they ride on the aft point —
    and the iterate's tow-point acceleration a* = Λ r̈ (Houbolt), body axes. Without them the aft node's loads
    reach the body only as its reaction at the iterate, and the angle iteration of a light body whose aft node
    is heavy or strongly damped (a 50 kg connector towing an array at 4 m/s) converges slowly or diverges."""
    c11 = 11.0 * dt / 12.0
    idt2 = 1.0 / (dt * dt)
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                for m in range(3):
                    acc += lam[i, k] * (mnode[c, k, m] + c11 * bnode[c, k, m]) * lam[j, m]
            pmass[i, j] = acc
    for i in range(3):
        astar[i] = 0.0
    for k in range(3):
        ak = (2.0 * rs[a, k] - 5.0 * r_t[a, k] + 4.0 * r_tm1[a, k] - r_tm2[a, k]) * idt2
        for i in range(3):
            astar[i] += lam[i, k] * ak


@njit_internal
def iterate_omega_dot(dt, b, angs, hist_ang, dang, omg, out, zero, w):
    """The body angular acceleration ω̇* = W θ̈* + Ẇ θ̇ of the iterate's Euler angles (Houbolt θ̈*), into
    ``out``; ``zero``: (3,) scratch, ``w``: (3, 3) scratch."""
    idt2 = 1.0 / (dt * dt)
    for i in range(3):
        zero[i] = 0.0
    # θ̈ = W⁻¹ ω̇ + e(θ, θ̇, ω): e from ω̇ = 0
    omega_dot_to_euler_acc(angs[b], dang[b], omg[b], zero, out)
    cb = math.cos(angs[b, 0])
    sb = math.sin(angs[b, 0])
    ca = math.cos(angs[b, 1])
    sa = math.sin(angs[b, 1])
    for i in range(3):
        w[0, i] = (2.0 * angs[b, i] - 5.0 * hist_ang[0, b, i] + 4.0 * hist_ang[1, b, i] - hist_ang[2, b, i]) * idt2 \
            - out[i]
    e0 = w[0, 0]
    e1 = w[0, 1]
    e2 = w[0, 2]
    out[0] = e0 - sa * e2
    out[1] = cb * e1 + ca * sb * e2
    out[2] = -sb * e1 + ca * cb * e2


@njit_internal
def aft_point_influence(dt, planar, body_node, body_aft_node, tn_nseg, tn_segs, own_nseg, bp, blam, angs, bX,
                        bkc, gaft, tang, qvec, qaft, w, m):
    """Monolithic series coupling: ∂r_c/∂T_k (per unit σ_k T_k, like ``qvec``) of each merged aft tow point c for
    the tensions of its body node's tension-tree list (``qaft[b, k]``), the body's rotation within the iteration
    included, so that the tension
    solve and the body-angle update form one Newton step for a light body whose pitch the tail drives.

    r_c = r_a + Λᵀ r_aft: ∂r_a/∂T_k = q_k (``qvec``); the angle update moves the body by the small rotation
    δφ = W D W⁻¹ ½Δt² δω̇ (body axes; W the Euler-rate map, D = diag(1/relaxation factor) of
    :func:`body_angle_update`: 1 for these bodies, zero for held roll/yaw), with δω̇ = G σ t_k (a tail segment's pull, G =
    ``gaft``) − X Λ (2/Δt²) q_k (the tow point's acceleration), and the aft point by Λᵀ (δφ × r_aft). A
    linearisation in the Jacobian only: the residuals are evaluated at the iterate, so the converged solution
    does not depend on it. ``w``, ``m``: (3, 3) scratch."""
    hdt2 = 0.5 * dt * dt
    i2 = 2.0 / (dt * dt)
    for b in range(body_node.shape[0]):
        c = body_aft_node[b]
        if c < 0 or tn_nseg[c] != 0:
            continue
        a = body_node[b]
        lam = blam[b]
        reduced = planar or bp[b, BP_REDUCED_DOF] != 0.0
        # W (ω = W θ̇) and its inverse
        cb = math.cos(angs[b, 0])
        sb = math.sin(angs[b, 0])
        ca = math.cos(angs[b, 1])
        sa = math.sin(angs[b, 1])
        w[0, 0] = 1.0
        w[0, 1] = 0.0
        w[0, 2] = -sa
        w[1, 0] = 0.0
        w[1, 1] = cb
        w[1, 2] = ca * sb
        w[2, 0] = 0.0
        w[2, 1] = -sb
        w[2, 2] = ca * cb
        if not _inv3(w, m):
            continue            # at the chart's singularity: keep the translational coupling only
        # m ← D W⁻¹ (rows scaled), then w ← W D W⁻¹ · ½Δt²
        for i in range(3):
            # the angle update of a merged body is not relaxed (its rotational stiffness is inside the
            # condensation): D = 1, except held roll/yaw
            d = 0.0 if reduced and i != 1 else 1.0
            for j in range(3):
                m[i, j] *= d
        for i in range(3):
            r0 = w[i, 0]
            r1 = w[i, 1]
            r2 = w[i, 2]
            for j in range(3):
                w[i, j] = hdt2 * (r0 * m[0, j] + r1 * m[1, j] + r2 * m[2, j])
        rx = bp[b, BP_AFT_TOW_POINT]
        ry = bp[b, BP_AFT_TOW_POINT + 1]
        rz = bp[b, BP_AFT_TOW_POINT + 2]
        for k in range(tn_nseg[a]):
            s = tn_segs[a, k]
            # δω̇ (body axes) per unit T_k
            for i in range(3):
                acc = 0.0
                for j in range(3):
                    lq = lam[j, 0] * qvec[a, k, 0] + lam[j, 1] * qvec[a, k, 1] + lam[j, 2] * qvec[a, k, 2]
                    acc -= bX[b, i, j] * i2 * lq
                if k >= own_nseg[a]:      # (like qvec, per unit σ_k T_k: the sign is applied in the tension system)
                    acc += gaft[b, i, 0] * tang[s, 0] + gaft[b, i, 1] * tang[s, 1] + gaft[b, i, 2] * tang[s, 2]
                m[0, i] = acc
            # δφ = w δω̇, δr_c = Λᵀ (δφ × r_aft)
            p0 = w[0, 0] * m[0, 0] + w[0, 1] * m[0, 1] + w[0, 2] * m[0, 2]
            p1 = w[1, 0] * m[0, 0] + w[1, 1] * m[0, 1] + w[1, 2] * m[0, 2]
            p2 = w[2, 0] * m[0, 0] + w[2, 1] * m[0, 1] + w[2, 2] * m[0, 2]
            u0 = p1 * rz - p2 * ry
            u1 = p2 * rx - p0 * rz
            u2 = p0 * ry - p1 * rx
            for i in range(3):
                qaft[b, k, i] = qvec[a, k, i] + lam[0, i] * u0 + lam[1, i] * u1 + lam[2, i] * u2


@njit_internal
def aft_pull_on_rotation(body_aft_node, tn_nseg, node_nseg, node_segs, node_sgn, tang, tens, gaft, by):
    """Monolithic series coupling: the tail segments' pull at the new tensions, f = Σ σ T t over the aft node's
    segments, added to the body's angular acceleration term, y_b += G_b f (its moment about the tow point;
    the condensation left it out of ``by``)."""
    for b in range(body_aft_node.shape[0]):
        c = body_aft_node[b]
        if c < 0 or tn_nseg[c] != 0:
            continue
        f0 = 0.0
        f1 = 0.0
        f2 = 0.0
        for k in range(node_nseg[c]):
            s = node_segs[c, k]
            w = node_sgn[c, k] * tens[s]
            f0 += w * tang[s, 0]
            f1 += w * tang[s, 1]
            f2 += w * tang[s, 2]
        for i in range(3):
            by[b, i] += gaft[b, i, 0] * f0 + gaft[b, i, 1] * f1 + gaft[b, i, 2] * f2


@njit_internal
def body_angle_update(dt, planar, r_t, r_tm1, r_tm2, rs, hist_ang, angs, dang, omg, blam, body_node, bp, bX, by, bkc,
                      tmp3, hvec, body_aft_node, tn_nseg):
    """Body rotations at the new node positions: ω̇ = A_rr⁻¹(M − A_rt a) from the condensed body equations,
    Houbolt on the Euler angles, relaxed by the implicit diagonal rotational stiffness and damping. Returns (a
    body past the chart's pitch limit or −1, the largest angle change)."""
    nb = body_node.shape[0]
    c11 = 11.0 * dt / 12.0
    hdt2 = 0.5 * dt * dt
    idt2 = 1.0 / (dt * dt)
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
        merged = body_aft_node[b] >= 0 and tn_nseg[body_aft_node[b]] == 0
        for i in range(3):
            if reduced and i != 1:
                angs[b, i] = hist_ang[0, b, i]      # roll and yaw held
                continue
            na = 2.5 * hist_ang[0, b, i] - 2.0 * hist_ang[1, b, i] + 0.5 * hist_ang[2, b, i] + hdt2 * hvec[i]
            # implicit (diagonal) treatment of the rotational stiffness and damping: a relaxation
            # of the fixed-point update that leaves the converged solution unchanged (inside the
            # condensation for a body with a monolithically coupled tail: iterate_coefficients)
            if not merged:
                na = angs[b, i] + (na - angs[b, i]) / (
                    1.0 + (hdt2 * bkc[b, BK_STIFFNESS + i] + c11 * bkc[b, BK_DAMPING + i]) / bkc[b, BK_INERTIA + i])
            dd = abs(na - angs[b, i])
            if not (dd <= dang_max):
                dang_max = dd
            angs[b, i] = na
        if abs(angs[b, 1]) > PITCH_LIMIT:     # ~85 deg in the chart: only if re-charting (advance) could not keep up
            return b, dang_max
    return -1, dang_max


@njit_internal
def end_stop_contact(dt, top_node, cnode, comp, r_t, r_tm1, r_tm2, rs, node_nseg, node_segs, node_sgn, tang, tens,
                     mnode, fnode):
    """The compensator's end-stop active set (passive/force mode): True when the converged step contradicts the
    contact state it was solved with (the sheave passed a stop, or the stop would have to pull) — the contact
    trial ``comp[C_TRIAL]`` is updated and the step must be redone."""
    z_new = rs[cnode, 2] - rs[top_node, 2]
    trial = comp[C_TRIAL]
    if trial == 0.0:
        if z_new > comp[C_SMAX]:
            comp[C_TRIAL] = 1.0
            return True
        if z_new < comp[C_SMIN]:
            comp[C_TRIAL] = -1.0
            return True
    else:
        fs = _end_stop_force(cnode, top_node, comp, dt, rs, r_t, r_tm1, r_tm2, node_nseg, node_segs, node_sgn,
                             tang, tens, mnode, fnode)
        if trial * fs > 0.0:       # the stop would have to pull: release
            comp[C_TRIAL] = 0.0
            return True
    return False


@njit_internal
def commit(dt, top_node, cnode, cmode, act_new, max_strain, comp, cstate, ea, tens, rs, angs, r_t, r_tm1, r_tm2,
           hist_r, hist_ang, tens_hist, top_react, react, node_nseg, node_segs, node_sgn, tang, mnode, fnode,
           adaptive, iterations, older_r, older_ang, older_tens, cubic_r, cubic_ang, quad_tens, pred_state):
    """Checks of the converged step (strain limit, finite positions) and, if they pass, the commit: the top
    reaction, the compensator's contact/hit/penetration state and the time levels shifted — with ``adaptive``
    (solver.predictor) the predictor's choice for the next step made (:func:`choose_predictor`) and the oldest
    level kept in its memory. Returns (OK, −1) or (FAIL_STRETCH, segment) / (FAIL_NAN, node) with ``state``
    untouched."""
    nn = rs.shape[0]
    ns = tens.shape[0]
    nb = angs.shape[0]
    for s in range(ns):
        if not math.isinf(ea[s]) and tens[s] / ea[s] > max_strain:
            return FAIL_STRETCH, s
    for a in range(nn):
        for i in range(3):
            if not math.isfinite(rs[a, i]):
                return FAIL_NAN, a
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
    if adaptive:
        choose_predictor(iterations, rs, angs, tens, hist_r, hist_ang, tens_hist, older_r, older_ang, older_tens,
                         cubic_r, cubic_ang, quad_tens, pred_state)
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
    return OK, -1


@njit_internal
def _quad_interp(y1, y0, ym1, tau):
    """Quadratic through (τ=1, y1), (0, y0), (−1, ym1) evaluated at τ (history re-spacing)."""
    return ym1 * tau * (tau - 1.0) * 0.5 + y0 * (1.0 - tau * tau) + y1 * tau * (tau + 1.0) * 0.5


@njit_internal
def _quad3(y0, ym1, ym2, tau):
    """Quadratic through (0, y0), (−1, ym1), (−2, ym2) evaluated at τ ≤ 0 (in units of the old step)."""
    return y0 * (tau + 1.0) * (tau + 2.0) * 0.5 - ym1 * tau * (tau + 2.0) + ym2 * tau * (tau + 1.0) * 0.5


@njit_internal
def _copy_into(dst, src):
    """dst[:] = src for 1-D arrays, as a loop (a slice assignment needs numba's reference counting)."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@njit_internal
def _copy_step_state(hist_r, hist_ang, tens_hist, cstate, to_r, to_ang, to_tens, to_cstate):
    """Copy the time levels a step changes (positions, body angles, tensions, compensator state) into the
    ``to_*`` arrays of the same shapes: the save before a step cut, and the restore after a failed one."""
    _copy_into(to_r.reshape(-1), hist_r.reshape(-1))
    _copy_into(to_ang.reshape(-1), hist_ang.reshape(-1))
    _copy_into(to_tens.reshape(-1), tens_hist.reshape(-1))
    _copy_into(to_cstate, cstate)


@njit(cache=True, _nrt=False, no_cpython_wrapper=True, no_cfunc_wrapper=True, inline="always")
def _step(dt, top, top_node, topo, segp, bodyp, env, settings, state, ws, comp):
    """houbolt_step with the end-stop active set: start from the contact state of the last step and redo
    the step (at most twice) when the converged solution contradicts it.

    Inlined into :func:`advance` by numba (``inline="always"``; a few lines): as a compiled function of its own
    it was one more level that links and re-generates the machine code of the whole step below it (numba
    links every callee's code into each caller's library), ~3–5 s of the first run's compilation."""
    cstate = state.cstate
    comp[C_TRIAL] = cstate[CS_CONTACT]
    its = 0
    for attempt in range(3):
        st, it, el, md = houbolt_step(dt, top, top_node, topo, segp, bodyp, env, settings, state, ws, comp)
        its += it
        if st != RETRY_CONTACT:
            return st, its, el, md
    return FAIL_NEWTON, its, el, md


@njit_internal
def record_row(rec, j, hist_r, hist_ang, chart, tens_hist, top_react, comp):
    """Write record j of this ``advance`` call into ``rec`` (:class:`towenv.core.model.Recording`)."""
    i = rec.plan[1] + j
    R, RB, A, C, T, F, bnodes = rec.R, rec.RB, rec.A, rec.C, rec.T, rec.F, rec.bnodes
    nn = hist_r.shape[1]
    nb = hist_ang.shape[1]
    for a in range(nn):
        for c in range(3):
            R[i, a, c] = hist_r[0, a, c]
    for lv in range(3):
        for b in range(bnodes.shape[0]):
            for c in range(3):
                RB[i, lv, b, c] = hist_r[lv, bnodes[b], c]
        for b in range(nb):
            for c in range(3):
                A[i, lv, b, c] = hist_ang[lv, b, c]
    for b in range(nb):
        for r in range(3):
            for c in range(3):
                C[i, b, r, c] = chart[b, r, c]
    for s in range(tens_hist.shape[1]):
        T[i, s] = tens_hist[0, s]
    for c in range(3):
        F[i, c] = top_react[c]
    if rec.CZ.shape[0] > 0:
        for lv in range(3):
            rec.CZ[j, lv, 0] = hist_r[lv, rec.cnodes[0], 2]
            rec.CZ[j, lv, 1] = hist_r[lv, rec.cnodes[1], 2]
        rec.CKB[j, 0] = comp[C_K]
        rec.CKB[j, 1] = comp[C_B]


@njit(cache=True, _nrt=False)
def advance(n_steps, dt, top_path, top_node, topo, segp, bodyp, env, settings, state, ws, saved, counters,
            comp, winch, wstate, t0, wave, rec):
    """Advance ``n_steps`` steps of size ``dt``; ``top_path[k]`` is the vessel tow point at the end of step k.

    ``rec`` (:class:`towenv.core.model.Recording`): with ``rec.plan[0] = every > 0`` a record is written after
    every ``every`` steps (``towenv.simulate``'s compiled recording), and the time of step k is reckoned from
    its record's start, ``(plan[2] + every·j)·dt + (k − every·j + 1)·dt``, as a loop of ``advance`` calls of
    ``every`` steps from Python would (bit-identical to it); ``Recording.none()``: no records, times
    ``t0 + (k + 1)·dt``. The recording lives here rather than in a compiled loop around ``advance`` because
    numba links each callee's code into its caller and generates it again there: a loop around ``advance``
    was one more such level, ~10 % of the first run's compilation.

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
    hist_r, hist_ang, tens_hist = state.hist_r, state.hist_ang, state.tens_hist
    cstate, chart = state.cstate, state.chart
    s_hist_r, s_hist_ang, s_tens, s_cstate = saved.hist_r, saved.hist_ang, saved.tens_hist, saved.cstate
    l0 = segp.l0
    max_cuts = int(settings[S_MAX_STEP_CUTS])
    nn = hist_r.shape[1]
    nb = hist_ang.shape[1]
    ns = tens_hist.shape[1]
    # scratch from the work arrays, not allocated here: advance is compiled without reference counting
    top_sub = ws.top_sub
    rc_lam, rc_lam0, rc_new, rc_tmp = ws.att, ws.atr, ws.arr, ws.tmp3     # the re-chart runs between steps
    rc_pitch = settings[S_RECHART_PITCH] if settings.shape[0] > S_RECHART_PITCH else RECHART_PITCH
    wmode = int(winch[W_MODE])
    wseg = int(winch[W_SEG])
    flow = ws.flow
    every = rec.plan[0]
    rec_step0 = rec.plan[2]
    any_aft = series_flags(topo.body_aft_node, topo.tn_nseg)[0]
    for k in range(n_steps):
        # moving attitude chart: a body whose local pitch has passed RECHART_PITCH restarts from a chart
        # centred on its current attitude (between steps, so a failed step's retries stay in one chart)
        for b in range(nb):
            if abs(hist_ang[0, b, 1]) > rc_pitch:
                rechart_body(b, hist_ang, chart, rc_lam, rc_lam0, rc_new, rc_tmp)
                state.pred_state[PS_VALID] = 0.0       # the memory's angles are in the old chart
                state.pred_state[PS_BODY_VALID] = 0.0  # (the kept derivatives too: fresh ones at the new attitude)
                if counters.shape[0] > 4:
                    counters[N_RECHARTS] += 1
        if every > 0:
            jr = k // every
            t_k = (rec_step0 + every * jr) * dt + (k - every * jr + 1) * dt
        else:
            t_k = t0 + (k + 1) * dt
        _wave_flow(t_k, hist_r[0], hist_r[1], hist_r[2], wave, flow, ws.flow_v)
        dl = 0.0
        l_old = 0.0
        v_new = 0.0
        if wmode > 0:
            v_new = _winch_speed(winch, wstate, tens_hist, dt)
            dl = v_new * dt
            l_old = l0[wseg]
            l0[wseg] = l_old + dl
        reused = (nb > 0 and not body_derivatives_due(settings, state.pred_state)) or not cable_jacobian_due(
            settings, state.pred_state, any_aft)
        st, it, el, md = _step(dt, top_path[k], top_node, topo, segp, bodyp, env, settings, state, ws, comp)
        counters[N_STEPS] += 1
        counters[N_ITERATIONS] += it
        if it > counters[N_MAX_ITERATIONS]:
            counters[N_MAX_ITERATIONS] = it
        if st != OK and (reused or (state.pred_state[PS_VALID] != 0.0 and state.pred_state[PS_HIGHER] != 0.0)):
            # the adaptive predictor's higher-order start or reused body derivatives failed: the same step again
            # from the lower orders with fresh derivatives before cutting it (at the stability map's longest
            # steps the higher orders can start the Newton iteration where it does not converge; the state is
            # untouched by the failed attempt)
            state.pred_state[PS_VALID] = 0.0
            state.pred_state[PS_BODY_VALID] = 0.0
            state.pred_state[PS_CABLE_VALID] = 0.0
            st, it, el, md = _step(dt, top_path[k], top_node, topo, segp, bodyp, env, settings, state, ws, comp)
            counters[N_ITERATIONS] += it
        if st != OK:
            _copy_step_state(hist_r, hist_ang, tens_hist, cstate, s_hist_r, s_hist_ang, s_tens, s_cstate)
            # the sub-steps re-space the history: the predictor's memory does not continue it (nor, after them,
            # the history restored to the spacing dt); the sub-steps start with fresh body derivatives
            state.pred_state[PS_VALID] = 0.0
            state.pred_state[PS_BODY_VALID] = 0.0
            state.pred_state[PS_CABLE_VALID] = 0.0
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
                _copy_into(cstate, s_cstate)
                good = True
                for j in range(1, nsub + 1):
                    tau = j / nsub
                    for i in range(3):
                        top_sub[i] = _quad_interp(top_path[k, i], s_hist_r[0, top_node, i], s_hist_r[1, top_node, i], tau)
                    if wmode > 0:
                        l0[wseg] = l_old + tau * dl
                    state.pred_state[PS_VALID] = 0.0        # sub-steps start from the lower orders
                    state.pred_state[PS_CABLE_VALID] = 0.0  # and build the nodes' Newton matrices (full Newton)
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
                    state.pred_state[PS_VALID] = 0.0
                    ok = True
                    break
            if not ok:
                _copy_step_state(s_hist_r, s_hist_ang, s_tens, s_cstate, hist_r, hist_ang, tens_hist, cstate)
                state.pred_state[PS_VALID] = 0.0
                state.pred_state[PS_BODY_VALID] = 0.0
                state.pred_state[PS_CABLE_VALID] = 0.0
                if wmode > 0:
                    l0[wseg] = l_old
                return st, k, el, md
        if wmode > 0:
            wstate[WS_V] = v_new
            wstate[WS_LEN] += dl
            wstate[WS_PAID] += dl
            if l0[wseg] > 1.5 * winch[W_LNOM] or (l0[wseg] < 0.5 * winch[W_LNOM] and dl < 0.0):
                return NEED_REMESH, k, wseg, 0.0
        if every > 0 and (k + 1) % every == 0:
            record_row(rec, (k + 1) // every - 1, hist_r, hist_ang, chart, tens_hist, state.top_react, comp)
    return OK, -1, -1, 0.0


@njit(cache=True, _nrt=False)
def houbolt_step_entry(dt, r_top_new, top_node, topo, segp, bodyp, env, settings, state, ws, comp):
    """:func:`houbolt_step` callable from Python (the tests' entry: the step itself is compiled without a Python
    wrapper, :func:`towenv.core.jit.njit_internal`). Compiled on first use only."""
    return houbolt_step(dt, r_top_new, top_node, topo, segp, bodyp, env, settings, state, ws, comp)
