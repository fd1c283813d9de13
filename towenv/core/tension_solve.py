"""The tension (length-constraint) system of the Newton iteration: its assembly from the node-local
solves (``assemble_tension_system``), the tree LDLᵀ solve (``tree_ldlt_solve``), the thesis's recursion
(``thesis_recursion_solve``, solver.tension_solve = "as_published") and node positions from tensions.
"""
from __future__ import annotations

import math

from .jit import njit
from .layout import (COMPENSATOR, FREE)


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


@njit(cache=True)
def thesis_recursion_solve(order, seg_up, seg_uplocal, seg_lo, node_nseg, node_segs, kd, kb, rhs, x, work, scratch):
    """The thesis's printed shooting recursion (4.38)–(4.40), *as published*, for a single chain — the
    labelled "as published" variant of the tension solve (``solver.tension_solve = "as_published"``).

    With segments numbered from the bottom, ``E δT_{i−1} − F δT_i + G δT_{i+1} = −ER_i`` is solved by
    ``δT_i = μ_i δT_0 + η_i`` and closed at the top. The homogeneous recurrence grows like λⁿ
    (λ + 1/λ = 2 + s, s = 2(l/(c_L Δt))²), so for stiff cables at large steps round-off swamps the
    answer (model.md 5.6, erratum E15). Kept to show that failure; the default is ``tree_ldlt_solve``.
    Returns False if a G coefficient is zero or the result is not finite. ``scratch``: (6, n) work array (the
    Houbolt step runs without numba's reference counting, so nothing here allocates)."""
    n = order.shape[0]
    # E_i, F_i, G_i in bottom-up order (J = −K: E = −K[i, i−1], F = K[i, i], G = −K[i, i+1])
    for j in range(6):
        for i in range(n):
            scratch[j, i] = 0.0
    mu = scratch[0]
    eta = scratch[1]
    E = scratch[2]
    F = scratch[3]
    G = scratch[4]
    R = scratch[5]
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
