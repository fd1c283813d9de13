"""Numba kernels of the equivalent (harmonic / stochastic) linearisation of the drag loads.

Every drag element (one end of a cable segment, a point body, a rigid body) is a function ``f(m + x)`` of
its mean input ``m`` (mean relative velocity; for a rigid body also the angular velocity, mean 0) and a
fluctuation ``x``. The equivalent damping matrix is the least-squares fit of the fluctuating force over
the fluctuation's distribution (Krylov–Bogoliubov for a harmonic fluctuation, Gaussian statistical
linearisation for a random one):

    C_eq = −⟨(f − ⟨f⟩) xᵀ⟩ ⟨x xᵀ⟩⁺  +  C_0 (I − ⟨x xᵀ⟩⁺⟨x xᵀ⟩)

* harmonic: ``x(φ) = Re(X e^{iφ})``, ⟨·⟩ the mean over a cycle (``nphi`` equally spaced phases, exact for
  the trigonometric content below harmonic ``nphi − 1``). For a scalar ``|v|v`` about zero mean this is
  Hover's ``8/(3π)·|X|``.
* stochastic: ``x ~ N(0, Σ)``, ⟨·⟩ the Gauss–Hermite expectation over the (up to ``kmax``) principal axes
  of Σ. By Stein's lemma the fit equals ``E[∂f/∂v]``; for a scalar ``|v|v`` about zero mean it is
  ``√(8/π)·σ``.

Directions the fluctuation does not visit (``⟨x xᵀ⟩`` singular: a planar ellipse, or no motion) get
``C_0``: for cable ends and point bodies the average of the tangent damping ``−∂f/∂v`` over the same
samples (the damping a small cross-flow motion meets in the presence of the oscillation; for rigid bodies ``−∂f/∂v`` at the mean.
Damping is returned as ``C`` with ``f ≈ f̄ − C x``.
"""
from __future__ import annotations

import math

import numpy as np
from ..core.layout import BP_CB

from ..core.jit import njit
from ..core.cable_loads import current_at, morison_damping, morison_drag
from ..core.kernels import body_loads, rotation_matrix


@njit(cache=True)
def _regress(X, F, w, C0, out):
    """out = −⟨(F − F̄) xᵀ⟩⟨x xᵀ⟩⁺ + C0 (I − ⟨x xᵀ⟩⁺⟨x xᵀ⟩). X (n, d), F (n, p), w (n,) summing to 1."""
    n, d = X.shape
    p = F.shape[1]
    A = np.zeros((d, d))
    fb = np.zeros(p)
    for k in range(n):
        for i in range(p):
            fb[i] += w[k] * F[k, i]
        for i in range(d):
            for j in range(d):
                A[i, j] += w[k] * X[k, i] * X[k, j]
    B = np.zeros((p, d))
    for k in range(n):
        for i in range(p):
            fi = w[k] * (F[k, i] - fb[i])
            for j in range(d):
                B[i, j] += fi * X[k, j]
    lam, U = np.linalg.eigh(A)
    lmax = 0.0
    for i in range(d):
        if lam[i] > lmax:
            lmax = lam[i]
    pinv = np.zeros((d, d))
    proj = np.zeros((d, d))
    thr = 1e-10 * lmax
    for k in range(d):
        if lmax > 1e-300 and lam[k] > thr:
            for i in range(d):
                for j in range(d):
                    pinv[i, j] += U[i, k] * U[j, k] / lam[k]
                    proj[i, j] += U[i, k] * U[j, k]
    for i in range(p):
        for j in range(d):
            s = 0.0
            for k in range(d):
                s -= B[i, k] * pinv[k, j]
                s += C0[i, k] * ((1.0 if k == j else 0.0) - proj[k, j])
            out[i, j] = s


@njit(cache=True)
def _harm_regress(V, F, nphi, C0, out):
    """Harmonic fit from the fundamental Fourier coefficients (no d×d eigen-solve).

    With x(φ) = a cos φ − b sin φ (a, b = Re, Im of V), W = [a b], G = WᵀW and R = [⟨f cos⟩, −⟨f sin⟩]:
    ⟨x xᵀ⟩ = ½ W Wᵀ and ⟨f xᵀ⟩ = R Wᵀ, so C = −2 R G⁻¹ Wᵀ + C0 (I − W G⁻¹ Wᵀ) (rank-1 via the eigen-axes of G)."""
    d = V.shape[0]
    p = F.shape[1]
    c1 = np.zeros(p)
    s1 = np.zeros(p)
    for k in range(nphi):
        ph = 2.0 * math.pi * k / nphi
        c = math.cos(ph) / nphi
        sn = math.sin(ph) / nphi
        for i in range(p):
            c1[i] += F[k, i] * c
            s1[i] -= F[k, i] * sn
    g11 = 0.0
    g12 = 0.0
    g22 = 0.0
    for i in range(d):
        a = V[i].real
        b = V[i].imag
        g11 += a * a
        g12 += a * b
        g22 += b * b
    # eigen-axes of the 2x2 Gram matrix
    tr = g11 + g22
    det = g11 * g22 - g12 * g12
    disc = math.sqrt(max(0.25 * (g11 - g22) ** 2 + g12 * g12, 0.0))
    lam1 = 0.5 * tr + disc
    lam2 = 0.5 * tr - disc
    if abs(g12) > 1e-300 * (1.0 + tr):
        q11, q21 = lam1 - g22, g12
    elif g11 >= g22:
        q11, q21 = 1.0, 0.0
    else:
        q11, q21 = 0.0, 1.0
    nq = math.sqrt(q11 * q11 + q21 * q21)
    q11 /= nq
    q21 /= nq
    q12, q22 = -q21, q11
    _ = det
    for i in range(p):
        for j in range(d):
            out[i, j] = C0[i, j]
    for kk in range(2):
        g = lam1 if kk == 0 else lam2
        qa = q11 if kk == 0 else q12
        qb = q21 if kk == 0 else q22
        if not (tr > 1e-300 and g > 1e-10 * tr):
            continue
        # W' column = W q, R' column = R q
        wcol = np.empty(d)
        for j in range(d):
            wcol[j] = V[j].real * qa + V[j].imag * qb
        for i in range(p):
            rc = c1[i] * qa + s1[i] * qb
            # C0 w w^T / g  (projection removed from the tangent part)
            c0w = 0.0
            for j in range(d):
                c0w += C0[i, j] * wcol[j]
            for j in range(d):
                out[i, j] += (-2.0 * rc - c0w) * wcol[j] / g


@njit(cache=True)
def _harmonic_samples(V, nphi, X, w):
    d = V.shape[0]
    for k in range(nphi):
        ph = 2.0 * math.pi * k / nphi
        c = math.cos(ph)
        s = math.sin(ph)
        for i in range(d):
            X[k, i] = V[i].real * c - V[i].imag * s
        w[k] = 1.0 / nphi


@njit(cache=True)
def _gauss_samples(Sig, gx, gw, kmax, X, w):
    """Gauss–Hermite points of N(0, Sig) over its ``kmax`` largest principal axes. Returns the count."""
    d = Sig.shape[0]
    lam, U = np.linalg.eigh(Sig)
    ng = gx.shape[0]
    # principal axes, largest first, above a relative threshold
    order = np.argsort(-lam)
    lmax = max(lam[order[0]], 0.0)
    k = 0
    axes = np.zeros((d, kmax))
    for jj in range(d):
        j = order[jj]
        if k < kmax and lmax > 1e-300 and lam[j] > 1e-10 * lmax:
            sq = math.sqrt(lam[j])
            for i in range(d):
                axes[i, k] = U[i, j] * sq
            k += 1
    if k == 0:
        for i in range(d):
            X[0, i] = 0.0
        w[0] = 1.0
        return 1
    n = ng ** k
    idx = np.zeros(k, np.int64)
    for m in range(n):
        r = m
        wt = 1.0
        for a in range(k):
            idx[a] = r % ng
            r //= ng
            wt *= gw[idx[a]]
        for i in range(d):
            s = 0.0
            for a in range(k):
                s += axes[i, a] * gx[idx[a]]
            X[m, i] = s
        w[m] = wt
    return n


@njit(cache=True)
def _point_jacobian(m0, m1, m2, kd, out):
    vm = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
    m = (m0, m1, m2)
    for i in range(3):
        for j in range(3):
            out[i, j] = kd * (vm * (1.0 if i == j else 0.0) + (m[i] * m[j] / vm if vm > 1e-12 else 0.0))


@njit(cache=True)
def cable_equivalent(mode, mean, tang, kn, kt, V, Sig, nphi, gx, gw, out):
    """Equivalent damping of every cable drag element.

    mode 0: harmonic, ``V`` (nf, ne, 3) complex velocity amplitudes, out (nf, ne, 3, 3): the cycle fit on
    the plane of the velocity ellipse, the cycle average of −∂f/∂v across it;
    mode 1: stochastic, ``Sig`` (ne, 3, 3) velocity covariances, out (1, ne, 3, 3): the Gaussian
    least-squares fit (= E[−∂f/∂v] by Stein's lemma, but smoother to integrate) on the span of Σ, the
    sample average of −∂f/∂v across it."""
    ne = mean.shape[0]
    nf = V.shape[0] if mode == 0 else 1
    nmax = nphi if mode == 0 else gx.shape[0] ** 3
    X = np.empty((nmax, 3))
    F = np.empty((nmax, 3))
    w = np.empty(nmax)
    Jk4 = np.empty((1, 1, 3, 3))
    Jk = Jk4[0, 0]
    Jav = np.empty((3, 3))
    f3 = np.empty(3)
    res = np.empty((3, 3))
    vk = np.empty(3)
    for e in range(ne):
        for f in range(nf):
            if mode == 0:
                _harmonic_samples(V[f, e], nphi, X, w)
                n = nphi
            else:
                n = _gauss_samples(Sig[e], gx, gw, 3, X, w)
            for i in range(3):
                for j in range(3):
                    Jav[i, j] = 0.0
            for k in range(n):
                for i in range(3):
                    vk[i] = mean[e, i] + X[k, i]
                te = tang[e]
                f3[0], f3[1], f3[2] = morison_drag(vk[0], vk[1], vk[2], te[0], te[1], te[2], kn[e], kt[e])
                morison_damping(vk[0], vk[1], vk[2], te[0], te[1], te[2], kn[e], kt[e], Jk4, 0, 0)
                for i in range(3):
                    F[k, i] = f3[i]
                    for j in range(3):
                        Jav[i, j] += w[k] * Jk[i, j]
            if mode == 0:
                _harm_regress(V[f, e], F, nphi, Jav, res)
            else:
                _regress(X[:n], F[:n], w[:n], Jav, res)
            for i in range(3):
                for j in range(3):
                    out[f, e, i, j] = res[i, j]


@njit(cache=True)
def point_equivalent(mode, mean, kd, V, Sig, nphi, gx, gw, out):
    """Isotropic quadratic drag ``−kd |v| v`` of point bodies; layout and rules as :func:`cable_equivalent`."""
    ne = mean.shape[0]
    nf = V.shape[0] if mode == 0 else 1
    nmax = nphi if mode == 0 else gx.shape[0] ** 3
    X = np.empty((nmax, 3))
    F = np.empty((nmax, 3))
    w = np.empty(nmax)
    Jk = np.empty((3, 3))
    Jav = np.empty((3, 3))
    res = np.empty((3, 3))
    for e in range(ne):
        m = mean[e]
        for f in range(nf):
            if mode == 0:
                _harmonic_samples(V[f, e], nphi, X, w)
                n = nphi
            else:
                n = _gauss_samples(Sig[e], gx, gw, 3, X, w)
            for i in range(3):
                for j in range(3):
                    Jav[i, j] = 0.0
            for k in range(n):
                v0 = m[0] + X[k, 0]
                v1 = m[1] + X[k, 1]
                v2 = m[2] + X[k, 2]
                a = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
                F[k, 0] = -kd[e] * a * v0
                F[k, 1] = -kd[e] * a * v1
                F[k, 2] = -kd[e] * a * v2
                _point_jacobian(v0, v1, v2, kd[e], Jk)
                for i in range(3):
                    for j in range(3):
                        Jav[i, j] += w[k] * Jk[i, j]
            if mode == 0:
                _harm_regress(V[f, e], F, nphi, Jav, res)
            else:
                _regress(X[:n], F[:n], w[:n], Jav, res)
            for i in range(3):
                for j in range(3):
                    out[f, e, i, j] = res[i, j]


@njit(cache=True)
def body_generalised_hydro(b, ang, E, vnode, thdot, zc_node, bp, btab_n, btab, rho, g, cur_z, cur_v, out):
    """Generalised hydrodynamic + damping loads of rigid body ``b`` for a tow-point velocity ``vnode``
    (global) and Euler-angle rates ``thdot``: out[:3] = Λᵀ f (global force), out[3:] = Eᵀ m (generalised
    moment on the Euler angles), at the frozen orientation ``ang``."""
    lam = np.empty((3, 3))
    rotation_matrix(ang[0], ang[1], ang[2], lam)
    vb = np.empty(3)
    for i in range(3):
        vb[i] = lam[i, 0] * vnode[0] + lam[i, 1] * vnode[1] + lam[i, 2] * vnode[2]
    w = np.empty(3)
    for i in range(3):
        w[i] = E[i, 0] * thdot[0] + E[i, 1] * thdot[1] + E[i, 2] * thdot[2]
    zc = zc_node + lam[0, 2] * bp[b, BP_CB] + lam[1, 2] * bp[b, BP_CB + 1] + lam[2, 2] * bp[b, BP_CB + 2]
    cur = np.empty(3)
    current_at(zc, cur_z, cur_v, cur)
    f = np.empty(3)
    m = np.empty(3)
    bd = np.empty(1)
    body_loads(b, lam, vb, w, bp, btab_n, btab, rho, g, cur, f, m, bd)
    for i in range(3):
        out[i] = lam[0, i] * f[0] + lam[1, i] * f[1] + lam[2, i] * f[2]
        out[3 + i] = E[0, i] * m[0] + E[1, i] * m[1] + E[2, i] * m[2]


@njit(cache=True)
def body_equivalent(mode, b, ang, E, umean, zc_node, bp, btab_n, btab, rho, g, cur_z, cur_v, V, Sig, nphi, gx, gw,
                    out):
    """Equivalent 6×6 damping of rigid body ``b`` on (tow-point velocity, Euler rates).

    mode 0: ``V`` (nf, 6) complex amplitudes, out (nf, 6, 6); mode 1: ``Sig`` (6, 6), out (1, 6, 6). The
    stochastic expectation runs over the 3 largest principal axes of Σ (Gauss–Hermite), the rest keep the
    tangent damping at the mean (central differences)."""
    nf = V.shape[0] if mode == 0 else 1
    nmax = nphi if mode == 0 else gx.shape[0] ** 3
    X = np.empty((nmax, 6))
    F = np.empty((nmax, 6))
    w = np.empty(nmax)
    C0 = np.empty((6, 6))
    res = np.empty((6, 6))
    vn = np.empty(3)
    td = np.empty(3)
    o1 = np.empty(6)
    o2 = np.empty(6)
    vmag = math.sqrt(umean[0] ** 2 + umean[1] ** 2 + umean[2] ** 2)
    for j in range(6):
        h = 1e-6 * (1.0 + vmag) if j < 3 else 1e-6
        for s in range(2):
            for i in range(3):
                vn[i] = umean[i]
                td[i] = 0.0
            sg = 1.0 if s == 0 else -1.0
            if j < 3:
                vn[j] += sg * h
            else:
                td[j - 3] += sg * h
            body_generalised_hydro(b, ang, E, vn, td, zc_node, bp, btab_n, btab, rho, g, cur_z, cur_v,
                                   o1 if s == 0 else o2)
        for i in range(6):
            C0[i, j] = -(o1[i] - o2[i]) / (2.0 * h)
    out6 = np.empty(6)
    for f in range(nf):
        if mode == 0:
            _harmonic_samples(V[f], nphi, X, w)
            n = nphi
        else:
            n = _gauss_samples(Sig, gx, gw, 3, X, w)
        for k in range(n):
            for i in range(3):
                vn[i] = umean[i] + X[k, i]
                td[i] = X[k, 3 + i]
            body_generalised_hydro(b, ang, E, vn, td, zc_node, bp, btab_n, btab, rho, g, cur_z, cur_v, out6)
            for i in range(6):
                F[k, i] = out6[i]
        if mode == 0:
            _harm_regress(V[f], F, nphi, C0, res)
        else:
            _regress(X[:n], F[:n], w[:n], C0, res)
        for i in range(6):
            for j in range(6):
                out[f, i, j] = res[i, j]


# ----------------------------------------------------------------------------------------------
# tree-structured block solve of the frequency-domain system
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def _csolve(A, B, s, m):
    """In place: B[:s, :m] ← A[:s, :s]⁻¹ B[:s, :m] (Gaussian elimination, partial pivoting). False if singular."""
    for k in range(s):
        p = k
        best = abs(A[k, k])
        for i in range(k + 1, s):
            if abs(A[i, k]) > best:
                best = abs(A[i, k])
                p = i
        if not (best > 0.0):
            return False
        if p != k:
            for j in range(s):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
            for j in range(m):
                tmp = B[k, j]
                B[k, j] = B[p, j]
                B[p, j] = tmp
        piv = 1.0 / A[k, k]
        for i in range(k + 1, s):
            f = A[i, k] * piv
            if f != 0.0:
                for j in range(k + 1, s):
                    A[i, j] -= f * A[k, j]
                for j in range(m):
                    B[i, j] -= f * B[k, j]
    for k in range(s - 1, -1, -1):
        piv = 1.0 / A[k, k]
        for j in range(m):
            acc = B[k, j]
            for i in range(k + 1, s):
                acc -= A[k, i] * B[i, j]
            B[k, j] = acc * piv
    return True


@njit(cache=True)
def tree_solve(omega, Kq, Mq, C, Cadd, rhs, gdofs, gsize, parent, order, X):
    """Solve (K − ω²M + iω(C + C_add)) X = rhs for every frequency, the matrix being block-tree sparse.

    Groups of generalised coordinates (a free node's 3 displacements, a body's tow-point node with its 3
    angles, the compensator stroke) couple only to their parent group (segments form a tree), so
    eliminating groups leaves-first (``order``) creates no fill: O(number of groups) per frequency.
    ``C`` is (nf or 1, n, n). Returns False if a pivot block is singular."""
    nf = omega.shape[0]
    ng = gsize.shape[0]
    smax = gdofs.shape[1]
    D = np.empty((ng, smax, smax), np.complex128)
    Lp = np.empty((ng, smax, smax), np.complex128)
    Y = np.empty((ng, smax, smax + 1), np.complex128)
    x = np.empty((ng, smax), np.complex128)
    for f in range(nf):
        w = omega[f]
        cf = f if C.shape[0] > 1 else 0
        for g in range(ng):
            s = gsize[g]
            p = parent[g]
            sp = gsize[p] if p >= 0 else 0
            for i in range(s):
                di = gdofs[g, i]
                for j in range(s):
                    dj = gdofs[g, j]
                    D[g, i, j] = complex(Kq[di, dj] - w * w * Mq[di, dj], w * (C[cf, di, dj] + Cadd[di, dj]))
                for j in range(sp):
                    dj = gdofs[p, j]
                    Y[g, i, j] = complex(Kq[di, dj] - w * w * Mq[di, dj], w * (C[cf, di, dj] + Cadd[di, dj]))
                    Lp[g, j, i] = complex(Kq[dj, di] - w * w * Mq[dj, di], w * (C[cf, dj, di] + Cadd[dj, di]))
                Y[g, i, sp] = rhs[f, di]
        for k in range(ng):
            g = order[k]
            s = gsize[g]
            p = parent[g]
            sp = gsize[p] if p >= 0 else 0
            if not _csolve(D[g], Y[g], s, sp + 1):
                return False
            if p < 0:
                continue
            # D_p −= L_g (D_g⁻¹ U_g);  b_p −= L_g (D_g⁻¹ b_g)
            for i in range(sp):
                for j in range(sp + 1):
                    acc = 0.0j
                    for k2 in range(s):
                        acc += Lp[g, i, k2] * Y[g, k2, j]
                    if j < sp:
                        D[p, i, j] -= acc
                    else:
                        Y[p, i, gsize[parent[p]] if parent[p] >= 0 else 0] -= acc
        for k in range(ng - 1, -1, -1):
            g = order[k]
            s = gsize[g]
            p = parent[g]
            sp = gsize[p] if p >= 0 else 0
            for i in range(s):
                acc = Y[g, i, sp]
                for j in range(sp):
                    acc -= Y[g, i, j] * x[p, j]
                x[g, i] = acc
                X[f, gdofs[g, i]] = acc
    return True
