"""Implicit one-step integrators of the elastic lumped-mass model: generalized-α and Newmark.

Same scene, same loads as the explicit schemes (:func:`towenv.core.explicit._rates`: ``segment_loads``,
``node_assembly``, ``body_loads``, ``condense_body``, segments as tension-only springs
``T = max(EA ε + c ε̇, 0)``); only the time integration differs. The model is written
``ẍ = f(x, ẋ)`` with ``f = M(x)⁻¹ F(x, ẋ)`` (the mass matrix depends on the state through the segment
tangents' added mass and the body condensation). ``x`` holds the free nodes' positions and the rigid
bodies' Euler angles (their velocities are the Euler-angle rates; the body rates ω are derived).

Chung–Hulbert generalized-α (1993) with high-frequency spectral radius ρ∞ ∈ [0, 1]::

    αm = (2ρ∞ − 1)/(ρ∞ + 1),  αf = ρ∞/(ρ∞ + 1),  γ = ½ − αm + αf,  β = ¼ (1 − αm + αf)²
    x₁ = x₀ + Δt v₀ + Δt² ((½ − β) a₀ + β a₁)
    v₁ = v₀ + Δt ((1 − γ) a₀ + γ a₁)
    (1 − αm) a₁ + αm a₀ = (1 − αf) f(x₁, v₁) + αf f(x₀, v₀)

and Newmark average acceleration (αm = αf = 0, β = ¼, γ = ½; no numerical dissipation). The
α-weighting is applied to the (algorithmic) accelerations ``a`` and to ``f = M⁻¹F`` at the step ends:
for a linear system with a constant mass matrix this is exactly Chung–Hulbert's
``M a_{n+1−αm} = F_{n+1−αf}`` (M⁻¹ commutes with the weighting), so the amplification matrix, ρ∞
and second-order accuracy are the paper's; with the state-dependent mass it keeps the scheme an ODE
integrator of ``ẍ = f`` (the form analysed by Arnold & Brüls 2007), and it needs ``f`` only at the
step ends, so the converged ``f₀`` of the previous step is reused.

The nonlinear equation for ``a₁`` is solved by Newton's method with a finite-difference Jacobian
coloured by the node graph (nodes whose rows never share a column are perturbed together: 3 × a few
residual evaluations per Jacobian), stored as a band matrix (reverse Cuthill–McKee order of the node /
body graph) and factorised by banded LU with partial pivoting. The factorisation is reused across
iterations and steps (modified Newton) and rebuilt when the residual contracts by less than a factor
2 per iteration; an update that increases the residual is halved (up to 4 times). Convergence: every free node's force imbalance ``|M (residual)|`` ≤ ``tolerance +
relative_tolerance · max T`` (N) and every body's Euler-angle error ``β Δt² |residual|`` ≤
``angle_tolerance``. A step that does not converge within ``max_iterations`` is retried as 2, 4, …
``2^max_step_cuts`` sub-steps; if it still fails, or the state goes non-finite, stretches beyond
``max_strain`` or a body pitches beyond ±85°, :class:`towenv.SimulationDivergence` is raised with the
time, the element and the cause, and the state stays at the last good step (never NaN).

The default ρ∞ = 0.2 (``solver.rho_inf``) is chosen for slack and snap loading: with ρ∞ ≥ 0.3–0.5 a
slack cable released at Δt ≫ l/c_L can sustain a spurious snap-loaded zig-zag (docs/model-notes.md).

Compensator and winch scenes are not supported (as with the explicit schemes); neither are
``solver.settle_time`` and wave orbital velocities on the drag.
"""
from __future__ import annotations

import math

import numpy as np
from .layout import S_ANGLE_TOLERANCE, S_MAX_ITERATIONS, S_MAX_STEP_CUTS, S_MAX_STRAIN, S_RELATIVE_TOLERANCE, S_TOLERANCE
from .layout import N_ITERATIONS, N_MAX_ITERATIONS, N_RECHARTS, N_STEPS, N_STEP_CUTS

from . import kernels as K
from .model import AlphaState, AlphaTrial
from .explicit import ExplicitScheme, _rates
from .simulator import Simulator

njit = K.njit

METHODS = ("generalized_alpha", "newmark")
FD_REL = 1e-7           # finite-difference step: 1e-7 (1 + |x|) m for positions, 1e-7 rad for angles


def coefficients(method: str, rho_inf: float = 0.2) -> np.ndarray:
    """(αm, αf, β, γ) of ``method`` ("generalized_alpha" with ``rho_inf``, or "newmark")."""
    if method == "newmark":
        return np.array([0.0, 0.0, 0.25, 0.5])
    am = (2 * rho_inf - 1) / (rho_inf + 1)
    af = rho_inf / (rho_inf + 1)
    return np.array([am, af, 0.25 * (1 - am + af) ** 2, 0.5 - am + af])


def amplification_matrix(omega_dt: float, method: str = "generalized_alpha", rho_inf: float = 0.2) -> np.ndarray:
    """Amplification matrix of the scheme on ``ẍ = −ω² x`` for the state (x, Δt v, Δt² a)."""
    am, af, beta, gamma = coefficients(method, rho_inf)
    w2 = omega_dt ** 2
    A = np.zeros((3, 3))
    for j in range(3):
        x0, v0, a0 = np.eye(3)[j]
        # (1−αm) a1 + αm a0 = −Ω² [(1−αf) x1 + αf x0],  x1 = x0 + v0 + (½−β) a0 + β a1
        a1 = (-w2 * ((1 - af) * (x0 + v0 + (0.5 - beta) * a0) + af * x0) - am * a0) / ((1 - am) + w2 * (1 - af) * beta)
        A[:, j] = (x0 + v0 + (0.5 - beta) * a0 + beta * a1, v0 + (1 - gamma) * a0 + gamma * a1, a1)
    return A


def principal_root(omega_dt: float, method: str = "generalized_alpha", rho_inf: float = 0.2):
    """Spectral radius of the principal (oscillatory) root, and AD / PE per exact period
    (model.md 8.1 definitions) at ``omega_dt``."""
    lam = np.linalg.eigvals(amplification_matrix(omega_dt, method, rho_inf))
    osc = lam[np.abs(lam.imag) > 1e-12 * np.maximum(np.abs(lam), 1e-300)]
    if osc.size == 0:
        raise ValueError(f"omega_dt: no oscillatory root at {omega_dt!r} (overdamped numerically)")
    lam = osc[np.argmax(np.abs(osc))]
    rho, arg = abs(lam), abs(np.angle(lam))
    steps = 2 * np.pi / omega_dt
    return rho, 1 - rho ** steps, (2 * np.pi / arg) / steps - 1


# ------------------------------------------------------------------------------------------------
# kernels
# ------------------------------------------------------------------------------------------------
@njit(cache=True)
def _residual(h, co, top_node, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, st, tr, gk, gi, R):
    """Residual of the α-weighted equation at the trial accelerations (``tr``); returns
    (ok, max force imbalance N, max Euler-angle error rad)."""
    r, v, acc, fpr, ang, dang, aacc, afpr = st.r, st.v, st.acc, st.fpr, st.ang, st.dang, st.aacc, st.afpr
    r1, v1, acc1, ang1, dang1, omg1, aacc1 = tr.r1, tr.v1, tr.acc1, tr.ang1, tr.dang1, tr.omg1, tr.aacc1
    out_a, out_dang, out_domg, qdd, tens = tr.out_a, tr.out_dang, tr.out_domg, tr.qdd, tr.tens
    am, af, beta, gamma = co[0], co[1], co[2], co[3]
    nn = r.shape[0]
    nb = ang.shape[0]
    node_kind = topo.node_kind
    c1 = h * h * (0.5 - beta)
    c2 = h * h * beta
    c3 = h * (1.0 - gamma)
    c4 = h * gamma
    for a in range(nn):
        if node_kind[a] == K.FREE:
            for i in range(3):
                r1[a, i] = r[a, i] + h * v[a, i] + c1 * acc[a, i] + c2 * acc1[a, i]
                v1[a, i] = v[a, i] + c3 * acc[a, i] + c4 * acc1[a, i]
        else:
            for i in range(3):
                r1[a, i] = r[a, i]
                v1[a, i] = v[a, i]
    for i in range(3):
        r1[top_node, i] = top_r[i]
        v1[top_node, i] = top_v[i]
    for b in range(nb):
        for i in range(3):
            ang1[b, i] = ang[b, i] + h * dang[b, i] + c1 * aacc[b, i] + c2 * aacc1[b, i]
            dang1[b, i] = dang[b, i] + c3 * aacc[b, i] + c4 * aacc1[b, i]
        K.euler_rates_to_omega(ang1[b], dang1[b], omg1[b])
    if not _rates(r1, v1, ang1, omg1, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, out_a, out_dang,
                  out_domg, tens):
        return False, np.inf, np.inf
    for b in range(nb):
        K.omega_dot_to_euler_acc(ang1[b], dang1[b], omg1[b], out_domg[b], qdd[b])
    mnode = ws.mnode
    fmax = 0.0
    amax = 0.0
    for p in range(gk.shape[0]):
        j = gi[p]
        if gk[p] == 0:
            for i in range(3):
                R[3 * p + i] = (1.0 - am) * acc1[j, i] + am * acc[j, i] - (1.0 - af) * out_a[j, i] - af * fpr[j, i]
            for i in range(3):
                f = mnode[j, i, 0] * R[3 * p] + mnode[j, i, 1] * R[3 * p + 1] + mnode[j, i, 2] * R[3 * p + 2]
                if not (abs(f) <= fmax):
                    fmax = abs(f) if math.isfinite(f) else np.inf
        else:
            for i in range(3):
                R[3 * p + i] = (1.0 - am) * aacc1[j, i] + am * aacc[j, i] - (1.0 - af) * qdd[j, i] - af * afpr[j, i]
                e = c2 * abs(R[3 * p + i])
                if not (e <= amax):
                    amax = e if math.isfinite(e) else np.inf
    return math.isfinite(fmax) and math.isfinite(amax), fmax, amax


@njit(cache=True)
def _jacobian(h, co, top_node, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, st, tr, gk, gi, R0, Rp,
              col_ptr, col_grp, infl_ptr, infl_idx, ab, kl):
    """Finite-difference Jacobian dR/da (band storage ``ab[i, j − i + kl]``), columns coloured."""
    acc1 = tr.acc1
    aacc1 = tr.aacc1
    r1 = tr.r1
    c2 = h * h * co[2]
    ab[:] = 0.0
    ncol = col_ptr.shape[0] - 1
    epsv = np.empty(gk.shape[0])
    orig = np.empty(gk.shape[0])
    for c in range(ncol):
        for comp in range(3):
            for q in range(col_ptr[c], col_ptr[c + 1]):
                p = col_grp[q]
                j = gi[p]
                if gk[p] == 0:
                    eps = FD_REL * (1.0 + abs(r1[j, comp])) / c2
                    orig[p] = acc1[j, comp]
                    acc1[j, comp] = orig[p] + eps
                    epsv[p] = (orig[p] + eps) - orig[p]
                else:
                    eps = FD_REL / c2
                    orig[p] = aacc1[j, comp]
                    aacc1[j, comp] = orig[p] + eps
                    epsv[p] = (orig[p] + eps) - orig[p]
            ok, _, _ = _residual(h, co, top_node, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, st, tr, gk,
                                 gi, Rp)
            for q in range(col_ptr[c], col_ptr[c + 1]):
                p = col_grp[q]
                j = gi[p]
                if gk[p] == 0:
                    acc1[j, comp] = orig[p]
                else:
                    aacc1[j, comp] = orig[p]
            if not ok:
                return False
            for q in range(col_ptr[c], col_ptr[c + 1]):
                p = col_grp[q]
                jj = 3 * p + comp
                for m in range(infl_ptr[p], infl_ptr[p + 1]):
                    rg = infl_idx[m]
                    for ri in range(3):
                        i = 3 * rg + ri
                        ab[i, jj - i + kl] = (Rp[i] - R0[i]) / epsv[p]
    return True


@njit(cache=True)
def band_lu(ab, kl, ku, piv):
    """In-place banded LU with partial pivoting (row-major band ``ab[i, j − i + kl]``, upper width
    kl + ku after pivoting). Returns False on a zero or non-finite pivot."""
    n = ab.shape[0]
    for k in range(n):
        p = k
        big = abs(ab[k, kl])
        for i in range(k + 1, min(n, k + kl + 1)):
            x = abs(ab[i, k - i + kl])
            if x > big:
                big = x
                p = i
        if not (big > 0.0) or not math.isfinite(big):
            return False
        piv[k] = p
        jmax = min(n - 1, k + kl + ku)
        if p != k:
            for j in range(k, jmax + 1):
                t = ab[k, j - k + kl]
                ab[k, j - k + kl] = ab[p, j - p + kl]
                ab[p, j - p + kl] = t
        d = ab[k, kl]
        for i in range(k + 1, min(n, k + kl + 1)):
            m = ab[i, k - i + kl] / d
            ab[i, k - i + kl] = m
            if m != 0.0:
                for j in range(k + 1, jmax + 1):
                    ab[i, j - i + kl] -= m * ab[k, j - k + kl]
    return True


@njit(cache=True)
def band_solve(ab, kl, ku, piv, b):
    """Solve with the factors of :func:`band_lu` (``b`` overwritten)."""
    n = ab.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            t = b[k]
            b[k] = b[p]
            b[p] = t
        for i in range(k + 1, min(n, k + kl + 1)):
            b[i] -= ab[i, k - i + kl] * b[k]
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, min(n, i + kl + ku + 1)):
            s -= ab[i, j - i + kl] * b[j]
        b[i] = s / ab[i, kl]


@njit(cache=True)
def _check(st_tr, topo, segp, max_strain, nb):
    """Failure checks of a converged trial state: (status, element)."""
    r1 = st_tr.r1
    v1 = st_tr.v1
    ang1 = st_tr.ang1
    for a in range(r1.shape[0]):
        for i in range(3):
            if not math.isfinite(r1[a, i]) or not math.isfinite(v1[a, i]):
                return K.FAIL_NAN, a
    l0 = segp.l0
    seg_lo = topo.seg_lo
    seg_up = topo.seg_up
    for s in range(l0.shape[0]):
        dx = r1[seg_up[s], 0] - r1[seg_lo[s], 0]
        dy = r1[seg_up[s], 1] - r1[seg_lo[s], 1]
        dz = r1[seg_up[s], 2] - r1[seg_lo[s], 2]
        if math.sqrt(dx * dx + dy * dy + dz * dz) / l0[s] - 1.0 > max_strain:
            return K.FAIL_STRETCH, s
    for b in range(nb):
        if not (abs(ang1[b, 1]) <= K.PITCH_LIMIT):
            return K.FAIL_ANGLE, b
    return K.OK, -1


@njit(cache=True)
def _apply(gk, gi, acc1, aacc1, d, scale):
    """acc1 −= scale · d (group order)."""
    for p in range(gk.shape[0]):
        j = gi[p]
        if gk[p] == 0:
            for i in range(3):
                acc1[j, i] -= scale * d[3 * p + i]
        else:
            for i in range(3):
                aacc1[j, i] -= scale * d[3 * p + i]


@njit(cache=True)
def _worst(R, gk):
    """Group with the largest residual component (-1 if none is finite)."""
    big = -1.0
    worst = -1
    for p in range(gk.shape[0]):
        for i in range(3):
            x = abs(R[3 * p + i])
            if math.isfinite(x) and x > big:
                big = x
                worst = p
    return worst


@njit(cache=True)
def _one_step(h, co, settings, top_node, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, st, tr, gk, gi, R, R0,
              col_ptr, col_grp, infl_ptr, infl_idx, ab, kl, ku, piv, jstate, counters):
    """One step of size ``h`` from ``st``; on success the trial ``tr`` holds the new state.
    Returns (status, element, iterations, last force residual)."""
    tol = settings[S_TOLERANCE]
    rtol = settings[S_RELATIVE_TOLERANCE]
    maxit = int(settings[S_MAX_ITERATIONS])
    atol = max(settings[S_ANGLE_TOLERANCE], 1e-300)
    r, v, acc, fpr, ang, dang, aacc, afpr = st.r, st.v, st.acc, st.fpr, st.ang, st.dang, st.aacc, st.afpr
    acc1 = tr.acc1
    aacc1 = tr.aacc1
    tens = tr.tens
    nb = ang.shape[0]
    n = R.shape[0]
    # predictor: constant (algorithmic) acceleration
    acc1[:] = acc
    aacc1[:] = aacc
    ok, fres, ares = _residual(h, co, top_node, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, st, tr, gk, gi, R)
    if not ok:
        return K.FAIL_NAN, -1, 0, fres
    fresh = False
    it = 0
    while True:
        tmax = 0.0
        for s in range(tens.shape[0]):
            tmax = max(tmax, tens[s])
        if fres <= tol + rtol * tmax and ares <= atol:
            break
        if it >= maxit:
            return K.FAIL_NEWTON, _worst(R, gk), it, fres
        if jstate[0] == 0.0 or jstate[1] != h:
            for i in range(n):
                R0[i] = R[i]
            if not _jacobian(h, co, top_node, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, st, tr, gk, gi, R0, R,
                             col_ptr, col_grp, infl_ptr, infl_idx, ab, kl):
                jstate[0] = 0.0
                return K.FAIL_NEWTON, -1, it, fres
            for i in range(n):
                R[i] = R0[i]
            if not band_lu(ab, kl, ku, piv):
                jstate[0] = 0.0
                return K.FAIL_NEWTON, -1, it, fres
            jstate[0] = 1.0
            jstate[1] = h
            counters[N_RECHARTS] += 1
            fresh = True
        band_solve(ab, kl, ku, piv, R)
        for i in range(n):
            R0[i] = R[i]                # the Newton update δ (R0 is free until the next Jacobian)
        _apply(gk, gi, acc1, aacc1, R0, 1.0)
        it += 1
        old = fres + ares / atol * tol
        ok, fres, ares = _residual(h, co, top_node, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, st, tr, gk,
                                   gi, R)
        new = fres + ares / atol * tol if ok else np.inf
        # backtracking on the full update when the residual grew (the stiff axial springs make the
        # position Newton overshoot at steps far beyond l/c_L)
        lam = 1.0
        while not (new <= old) and lam > 0.1:
            _apply(gk, gi, acc1, aacc1, R0, -0.5 * lam)
            lam *= 0.5
            ok, fres, ares = _residual(h, co, top_node, top_r, top_v, topo, segp, bodyp, env, c_axial, ws, st, tr, gk,
                                       gi, R)
            new = fres + ares / atol * tol if ok else np.inf
        if not ok:
            jstate[0] = 0.0
            return K.FAIL_NEWTON, _worst(R, gk), it, fres
        if new > 0.5 * old:
            if fresh and new > old:
                jstate[0] = 0.0
                return K.FAIL_NEWTON, _worst(R, gk), it, fres
            jstate[0] = 0.0             # slow contraction: rebuild the Jacobian at the current iterate
    status, el = _check(tr, topo, segp, settings[S_MAX_STRAIN], nb)
    return status, el, it, fres


@njit(cache=True)
def alpha_advance(n_steps, dt, top_path, top_prev, co, settings, top_node, topo, segp, bodyp, env, c_axial, ws,
                  st, tr, bk, gk, gi, R, R0, col_ptr, col_grp, infl_ptr, infl_idx, ab, kl, ku, piv, jstate,
                  counters):
    """Advance ``n_steps`` steps of ``dt``; ``top_path[k]`` is the tow point at the end of step k and
    ``top_prev`` at the start. A failing step is retried as 2, 4, … 2^max_step_cuts sub-steps.
    Returns (status, step, element, last force residual); on failure ``st`` is the last good step."""
    max_cuts = int(settings[S_MAX_STEP_CUTS])
    prev = np.empty(3)
    top_r = np.empty(3)
    top_v = np.empty(3)
    for i in range(3):
        prev[i] = top_prev[i]
    for k in range(n_steps):
        for i in range(3):
            top_v[i] = (top_path[k, i] - prev[i]) / dt
        for q in range(len(st)):
            bk[q][:] = st[q]
        status = K.OK
        el = -1
        fres = 0.0
        for cut in range(max_cuts + 1):
            nsub = 1 << cut
            h = dt / nsub
            if cut > 0:
                counters[N_STEP_CUTS] += 1
                for q in range(len(st)):
                    st[q][:] = bk[q]
            status = K.OK
            for m in range(nsub):
                for i in range(3):
                    top_r[i] = prev[i] + (m + 1) * h * top_v[i] if m + 1 < nsub else top_path[k, i]
                status, el, it, fres = _one_step(h, co, settings, top_node, top_r, top_v, topo, segp, bodyp, env,
                                                 c_axial, ws, st, tr, gk, gi, R, R0, col_ptr, col_grp, infl_ptr,
                                                 infl_idx, ab, kl, ku, piv, jstate, counters)
                counters[N_ITERATIONS] += it
                if it > counters[N_MAX_ITERATIONS]:
                    counters[N_MAX_ITERATIONS] = it
                if status != K.OK:
                    break
                # commit: the converged trial becomes the state; f at it is the next step's f₀
                st.r[:] = tr.r1
                st.v[:] = tr.v1
                st.acc[:] = tr.acc1
                st.fpr[:] = tr.out_a
                st.ang[:] = tr.ang1
                st.dang[:] = tr.dang1
                st.aacc[:] = tr.aacc1
                st.afpr[:] = tr.qdd
                counters[N_STEPS] += 1
            if status == K.OK:
                break
        if status != K.OK:
            for q in range(len(st)):
                st[q][:] = bk[q]
            return status, k, el, fres
        for i in range(3):
            prev[i] = top_path[k, i]
    return K.OK, -1, -1, 0.0


# ------------------------------------------------------------------------------------------------
# structure: unknown groups, their order, colouring
# ------------------------------------------------------------------------------------------------
def _structure(s):
    """Unknown groups (free nodes: 3 positions; rigid bodies: 3 Euler angles), which groups each
    group's residual depends on, a reverse Cuthill–McKee order, band widths and a column colouring."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import reverse_cuthill_mckee
    nn = s.n_nodes
    kind = s.node_kind
    free = [a for a in range(nn) if kind[a] == K.FREE]
    groups = [(0, a) for a in free] + [(1, b) for b in range(s.n_rigid)]
    gid_node = {a: g for g, (k, a) in enumerate(groups) if k == 0}
    gid_body = {b: g for g, (k, b) in enumerate(groups) if k == 1}
    aft_of = {int(c): b for b, c in enumerate(s.body_aft_node) if c >= 0}
    body_of_node = {int(a): b for b, a in enumerate(s.body_node)}
    nbrs = [set() for _ in range(nn)]
    for lo, up in zip(s.seg_lo, s.seg_up):
        nbrs[int(lo)].add(int(up))
        nbrs[int(up)].add(int(lo))

    def expand(a):
        if a in gid_node:
            return {gid_node[a]}
        if a in aft_of:
            b = aft_of[a]
            return expand(int(s.body_node[b])) | {gid_body[b]}
        return set()

    def around(a):
        out = set()
        for m in {a} | nbrs[a]:
            out |= expand(m)
        return out

    dep = []
    for k, x in groups:
        a = x if k == 0 else int(s.body_node[x])
        d = around(a)
        if a in body_of_node:
            b = body_of_node[a]
            d.add(gid_body[b])
            c = int(s.body_aft_node[b])
            if c >= 0:
                d |= around(c)
        dep.append(d)
    ng = len(groups)
    rows = [i for i in range(ng) for j in dep[i]]
    cols = [j for i in range(ng) for j in dep[i]]
    adj = csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(ng, ng))
    adj = adj + adj.T
    order = reverse_cuthill_mckee(adj.tocsr(), symmetric_mode=True) if ng else np.zeros(0, int)
    pos = np.empty(ng, int)
    pos[order] = np.arange(ng)
    kl = ku = 2
    for i in range(ng):
        for j in dep[i]:
            d = pos[i] - pos[j]
            kl = max(kl, 3 * d + 2)
            ku = max(ku, -3 * d + 2)
    # colouring: two columns may share a colour if no row depends on both
    conflict = [set() for _ in range(ng)]
    for i in range(ng):
        for j in dep[i]:
            conflict[j] |= dep[i]
    color = -np.ones(ng, int)
    for j in order:
        used = {color[x] for x in conflict[j] if color[x] >= 0}
        c = 0
        while c in used:
            c += 1
        color[j] = c
    ncol = int(color.max()) + 1 if ng else 0
    col_grp = np.array([pos[j] for c in range(ncol) for j in order if color[j] == c], np.int64)
    col_ptr = np.cumsum([0] + [int(np.sum(color == c)) for c in range(ncol)]).astype(np.int64)
    infl = [[] for _ in range(ng)]
    for i in range(ng):
        for j in dep[i]:
            infl[pos[j]].append(pos[i])
    infl_ptr = np.cumsum([0] + [len(x) for x in infl]).astype(np.int64)
    infl_idx = np.array([i for x in infl for i in sorted(x)], np.int64)
    gk = np.array([groups[g][0] for g in order], np.int64)
    gi = np.array([groups[g][1] for g in order], np.int64)
    return dict(gk=gk, gi=gi, kl=int(kl), ku=int(ku), col_ptr=col_ptr, col_grp=col_grp, infl_ptr=infl_ptr,
                infl_idx=infl_idx, n_colors=ncol)


# ------------------------------------------------------------------------------------------------
class AlphaScheme(ExplicitScheme):
    """Generalized-α (``solver.method = "generalized_alpha"``, high-frequency spectral radius
    ``solver.rho_inf`` ∈ [0, 1]) or Newmark average acceleration (``"newmark"``).

    The state is (positions, velocities, Euler angles, Euler-angle rates) plus the algorithmic
    accelerations and the loads ``f`` of the last step (all part of snapshots)."""

    def __init__(self, sim, method: str = "generalized_alpha", rho_inf: float = 0.2, axial_damping_ratio: float = 0.0):
        super().__init__(sim, "rk2", axial_damping_ratio)
        if method not in METHODS:
            raise ValueError(f"method: must be one of {list(METHODS)} (got {method!r})")
        if isinstance(rho_inf, bool) or not isinstance(rho_inf, (int, float, np.floating)) or not (0 <= rho_inf <= 1):
            raise ValueError(f"rho_inf: must be a number within [0, 1] (got {rho_inf!r})")
        self.name = self.method = method
        self.rho_inf = float(rho_inf)
        self.coefs = coefficients(method, self.rho_inf)

    def start(self):
        sc = self.sim.scene
        if float(getattr(sc.solver, "settle_time", 0.0) or 0.0) > 0:
            raise ValueError(f"solver.settle_time: must be 0 with solver.method = {self.method!r} (the start is already "
                             "the steady tow)")
        super().start()
        self._alpha_init()

    def _alpha_init(self):
        sim = self.sim
        s = sim.system
        nn, nb = s.n_nodes, s.n_rigid
        z = np.zeros
        self.xdang = z((nb, 3))
        for b in range(nb):
            dang = (3 * self.sim.hist_ang[0, b] - 4 * self.sim.hist_ang[1, b] + self.sim.hist_ang[2, b]) / (2 * self.sim.dt)
            self.xdang[b] = dang
        self.xacc, self.xf = z((nn, 3)), z((nn, 3))
        self.xaacc, self.xaf = z((nb, 3)), z((nb, 3))
        # state tuple (positions, velocities, accelerations, f) of nodes, then the same of the body angles
        self._st = AlphaState(self.xr, self.xv, self.xacc, self.xf, self.xang, self.xdang, self.xaacc, self.xaf)
        self._bk = AlphaState(*(a.copy() for a in self._st))
        self._tr = AlphaTrial.allocate(nn, s.n_segments, nb)
        st = _structure(s)
        self._gk, self._gi = st["gk"], st["gi"]
        self._kl, self._ku = st["kl"], st["ku"]
        self._col = (st["col_ptr"], st["col_grp"], st["infl_ptr"], st["infl_idx"])
        self.n_colors = st["n_colors"]
        n = 3 * len(self._gk)
        self._R, self._R0 = z(n), z(n)
        self._ab = z((n, 2 * self._kl + self._ku + 1))
        self._piv = np.zeros(n, np.int64)
        self._jstate = z(2)
        self._acnt = np.zeros(5, np.int64)
        # anchors are fixed in space (the shared start history moves every node with the tow velocity)
        for a in getattr(s, "anchors", {}):
            self.xv[a] = 0.0
        # consistent start: a₀ = f(x₀, v₀)
        out_a, qdd = self._loads_at_state()
        if not (np.all(np.isfinite(out_a)) and np.all(np.isfinite(qdd))):
            raise ValueError("initial state: the loads are not finite (check the scene)")
        self.xacc[...] = out_a
        self.xf[...] = out_a
        self.xaacc[...] = qdd
        self.xaf[...] = qdd
        self._sync()
        self._ga_initial = tuple(a.copy() for a in self._st) + (self.xtens.copy(), self.xomg.copy(),
                                                                 self.sim.top_react.copy(), self.sim.hist_r.copy(),
                                                                 self.sim.hist_ang.copy(), self.sim.tens_hist.copy())

    def _loads_at_state(self):
        """f = M⁻¹F at the stored state (node accelerations, Euler-angle accelerations); also refreshes
        the tensions and the load work arrays (tow-point reaction) of that state."""
        s = self.sim.system
        tr = self._tr
        for b in range(s.n_rigid):
            K.euler_rates_to_omega(self.xang[b], self.xdang[b], self.xomg[b])
        ok = _rates(self.xr, self.xv, self.xang, self.xomg, self.xr[s.top_node].copy(), self.xv[s.top_node].copy(),
                    s.topo(), s.segp(), s.bodyp(), s.env(), self.axial_damping, self._xws, tr.out_a, tr.out_dang, tr.out_domg,
                    self.xtens)
        if not ok:
            return np.full_like(tr.out_a, np.nan), np.full_like(tr.qdd, np.nan)
        for b in range(s.n_rigid):
            K.omega_dot_to_euler_acc(self.xang[b], self.xdang[b], self.xomg[b], tr.out_domg[b], tr.qdd[b])
        return tr.out_a.copy(), tr.qdd.copy()

    def run(self, tops, dt, t_start):
        if not hasattr(self, "_ga_initial"):
            raise ValueError(f"solver.settle_time: must be 0 with solver.method = {self.method!r}")
        s = self.sim.system
        prev = self.xr[s.top_node].copy()
        settings = self.sim.settings.array()
        st, k, el, fres = alpha_advance(len(tops), dt, tops, prev, self.coefs, settings, s.top_node, s.topo(),
                                        s.segp(), s.bodyp(), s.env(), self.axial_damping, self._xws, self._st,
                                        self._tr, self._bk, self._gk, self._gi, self._R, self._R0, *self._col,
                                        self._ab, self._kl, self._ku, self._piv, self._jstate, self._acnt)
        self.sim.counters[:N_RECHARTS] = self._acnt[:N_RECHARTS]    # every counter but the re-charts
        # body rates and tensions of the state (after a failure: of the last good step, re-evaluated)
        for b in range(s.n_rigid):
            K.euler_rates_to_omega(self.xang[b], self.xdang[b], self.xomg[b])
        if st == K.OK:
            self.xtens[...] = self._tr.tens
        else:
            self._loads_at_state()
        self._sync()
        if st != K.OK:
            from ..errors import SimulationDivergence
            name = self.method if self.method == "newmark" else f"generalized_alpha (rho_inf = {self.rho_inf:g})"
            cause = {K.FAIL_NEWTON: f"Newton iteration on the {name} step did not converge "
                                    f"(after {self.sim.settings.max_step_cuts} step halvings)",
                     K.FAIL_NAN: f"non-finite state in the {name} step",
                     K.FAIL_STRETCH: f"strain above solver.max_strain in the {name} step",
                     K.FAIL_ANGLE: K.NO_CHART_REFUSAL.format(scheme=name)}.get(st, str(st))
            raise SimulationDivergence(t_start + (k + 1) * dt, self._where(st, el), cause,
                                       int(self.sim.settings.max_iterations), float(fres))

    def _where(self, status, el):
        if status == K.FAIL_NEWTON and el >= 0:
            kind, j = int(self._gk[el]), int(self._gi[el])
            if kind == 1:
                return self.sim._element_name(K.FAIL_ANGLE, j)
            for lm in self.sim.system.lines:
                if j in lm.nodes:
                    return f"node {int(np.where(lm.nodes == j)[0][0])} of line {lm.name!r} (global {j})"
            return f"node {j}"
        if status == K.FAIL_NAN and el >= 0:
            return f"node {el}"
        return self.sim._element_name(status, el)

    def _sync(self):
        super()._sync()
        dt = self.sim.settings.dt
        for b in range(self.sim.system.n_rigid):
            self.sim.hist_ang[1, b] = self.xang[b] - dt * self.xdang[b]
            self.sim.hist_ang[2, b] = self.xang[b] - 2 * dt * self.xdang[b]

    def stats(self, out):
        out["jacobians"] = int(self._acnt[4]) if hasattr(self, "_acnt") else 0
        return out

    def reset(self):
        super().reset()
        if hasattr(self, "_ga_initial"):
            for dst, src in zip(self._st + (self.xtens, self.xomg, self.sim.top_react, self.sim.hist_r, self.sim.hist_ang,
                                            self.sim.tens_hist), self._ga_initial):
                dst[...] = src
            self._jstate[:] = 0.0
            self._acnt[:] = 0

    def snapshot(self, snap):
        super().snapshot(snap)
        if hasattr(self, "_ga_initial"):
            snap.alpha = (tuple(a.copy() for a in self._st), self._ab.copy(), self._piv.copy(), self._jstate.copy())

    def restore(self, snap):
        super().restore(snap)
        if hasattr(snap, "alpha") and hasattr(self, "_ga_initial"):
            arrays, ab, piv, js = snap.alpha
            for dst, src in zip(self._st, arrays):
                dst[...] = src
            self._ab[...] = ab
            self._piv[...] = piv
            self._jstate[...] = js


def GeneralizedAlphaSimulator(scene, method: str = "generalized_alpha", rho_inf: float = 0.2,
                              axial_damping_ratio: float = 0.0, **overrides) -> Simulator:
    """A :class:`~towenv.core.simulator.Simulator` whose ``solver.method`` is ``method``
    ("generalized_alpha" or "newmark") with ``solver.rho_inf`` — shorthand for ``Simulator(scene,
    method=…, rho_inf=…, axial_damping_ratio=…)``."""
    if method not in METHODS:
        raise ValueError(f"method: must be one of {list(METHODS)} (got {method!r})")
    if isinstance(rho_inf, bool) or not isinstance(rho_inf, (int, float, np.floating)) or not (0 <= rho_inf <= 1):
        raise ValueError(f"rho_inf: must be a number within [0, 1] (got {rho_inf!r})")
    if isinstance(axial_damping_ratio, bool) or not (axial_damping_ratio >= 0 and np.isfinite(axial_damping_ratio)):
        raise ValueError(f"axial_damping_ratio: must be >= 0 (got {axial_damping_ratio!r})")
    return Simulator(scene, **{**overrides, "solver.method": method, "solver.rho_inf": float(rho_inf),
                               "solver.axial_damping_ratio": float(axial_damping_ratio)})
