"""Rotations and 3×3 helpers: Euler angles ↔ rotation matrices, the moving attitude chart of a rigid
body (re-charting), Euler-angle rates ↔ body angular velocity, the closed-form 3×3 inverse.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import njit


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


@njit(cache=True)
def _cross(a0, a1, a2, b0, b1, b2, out):
    out[0] = a1 * b2 - a2 * b1
    out[1] = a2 * b0 - a0 * b2
    out[2] = a0 * b1 - a1 * b0
