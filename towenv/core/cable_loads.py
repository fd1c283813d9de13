"""Cable loads (Morison): drag, weight, buoyancy, mass and added mass of each segment
(``segment_loads``), their assembly into node mass matrices and non-tension node forces, point bodies
(``node_assembly``), the current profile (``current_at``) and the reaction of the cable on a node
(``node_reaction``).
"""
from __future__ import annotations

import math

from .jit import njit


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
def current_xyz(z, cur_z, cur_v):
    """:func:`current_at` returned as three numbers (no array: the kernels called once per Newton iteration
    run without numba's reference counting, which forbids allocating)."""
    n = cur_z.shape[0]
    depth = -z
    if n == 1 or depth <= cur_z[0]:
        return cur_v[0, 0], cur_v[0, 1], cur_v[0, 2]
    if depth >= cur_z[n - 1]:
        return cur_v[n - 1, 0], cur_v[n - 1, 1], cur_v[n - 1, 2]
    i = 0
    while cur_z[i + 1] < depth:
        i += 1
    f = (depth - cur_z[i]) / (cur_z[i + 1] - cur_z[i])
    return (cur_v[i, 0] * (1.0 - f) + cur_v[i + 1, 0] * f, cur_v[i, 1] * (1.0 - f) + cur_v[i + 1, 1] * f,
            cur_v[i, 2] * (1.0 - f) + cur_v[i + 1, 2] * f)


@njit(cache=True)
def relative_velocity_parts(vr0, vr1, vr2, t0, t1, t2):
    """Split a relative velocity ``v_r`` against a unit tangent ``t``: (v_t = v_r·t, v_n = v_r − v_t t (three
    numbers), |v_n|)."""
    vt_mag = vr0 * t0 + vr1 * t1 + vr2 * t2
    vn0 = vr0 - vt_mag * t0
    vn1 = vr1 - vt_mag * t1
    vn2 = vr2 - vt_mag * t2
    return vt_mag, vn0, vn1, vn2, math.sqrt(vn0 * vn0 + vn1 * vn1 + vn2 * vn2)


@njit(cache=True)
def morison_force(vt_mag, vn0, vn1, vn2, vn_abs, t0, t1, t2, kn, kt):
    """Morison drag of a cable element, vector normal form (model.md 2.3 / erratum E6):
    ``−kn |v_n| v_n − kt |v_t| v_t t`` with ``kn = ½ρ C_n D l``, ``kt = ½ρ C_t D l`` (three numbers). The one
    drag formula of the project — the time-step kernels, the statics and the linearisation use it (the numpy
    twin in towenv.verification keeps an independent copy on purpose: it is the check)."""
    avt = abs(vt_mag)
    return (-kn * vn_abs * vn0 - kt * avt * vt_mag * t0, -kn * vn_abs * vn1 - kt * avt * vt_mag * t1,
            -kn * vn_abs * vn2 - kt * avt * vt_mag * t2)


@njit(cache=True)
def morison_jacobian(vt_mag, vn0, vn1, vn2, vn_abs, t0, t1, t2, kn, kt, out, s, e):
    """Its Jacobian ``−∂drag/∂v_r = kn(|v_n|(1 − t tᵀ) + v_n v_nᵀ/|v_n|) + 2 kt |v_t| t tᵀ``, written to
    ``out[s, e]`` (a 4-D array of 3×3 blocks: the kernels' per-segment-end layout)."""
    avt = abs(vt_mag)
    for i in range(3):
        # components by selection, not by indexing a tuple with the loop variable (measured 3 % slower
        # per step: numba spills such a tuple to memory)
        ti = t0 if i == 0 else (t1 if i == 1 else t2)
        for j in range(3):
            tj = t0 if j == 0 else (t1 if j == 1 else t2)
            tt = ti * tj
            proj = (1.0 if i == j else 0.0) - tt
            out[s, e, i, j] = kn * vn_abs * proj + 2.0 * kt * avt * tt
    if vn_abs > 1e-12:
        for i in range(3):
            vi = vn0 if i == 0 else (vn1 if i == 1 else vn2)
            for j in range(3):
                vj = vn0 if j == 0 else (vn1 if j == 1 else vn2)
                out[s, e, i, j] += kn * vi * vj / vn_abs


@njit(cache=True)
def morison_drag(vr0, vr1, vr2, t0, t1, t2, kn, kt):
    """:func:`morison_force` at relative velocity ``v_r`` (three numbers)."""
    vt_mag, vn0, vn1, vn2, vn_abs = relative_velocity_parts(vr0, vr1, vr2, t0, t1, t2)
    return morison_force(vt_mag, vn0, vn1, vn2, vn_abs, t0, t1, t2, kn, kt)


@njit(cache=True)
def morison_damping(vr0, vr1, vr2, t0, t1, t2, kn, kt, out, s, e):
    """:func:`morison_jacobian` at relative velocity ``v_r``, into ``out[s, e]``."""
    vt_mag, vn0, vn1, vn2, vn_abs = relative_velocity_parts(vr0, vr1, vr2, t0, t1, t2)
    morison_jacobian(vt_mag, vn0, vn1, vn2, vn_abs, t0, t1, t2, kn, kt, out, s, e)


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
    ``node_assembly``. An empty ``bmat`` (no rows): the drag Jacobians are not wanted (the Houbolt step reusing
    its nodes' Newton matrices, solver.cable_jacobian_refresh).
    """
    nseg = seg_lo.shape[0]
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
            vc0, vc1, vc2 = current_xyz(r[nd, 2], cur_z, cur_v)
            vr0 = v[nd, 0] - vc0
            vr1 = v[nd, 1] - vc1
            vr2 = v[nd, 2] - vc2
            vt_mag, vn0, vn1, vn2, vn_abs = relative_velocity_parts(vr0, vr1, vr2, t0, t1, t2)
            d0, d1, d2 = morison_force(vt_mag, vn0, vn1, vn2, vn_abs, t0, t1, t2, kn, kt)
            drag[s, e, 0] = d0
            drag[s, e, 1] = d1
            drag[s, e, 2] = d2
            if bmat.shape[0] > 0:
                morison_jacobian(vt_mag, vn0, vn1, vn2, vn_abs, t0, t1, t2, kn, kt, bmat, s, e)
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
    jac = bmat.shape[0] > 0     # (empty: no drag Jacobians wanted, segment_loads; bnode then holds the point bodies')
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
                    if jac:
                        bnode[a, i, j] += 0.5 * bmat[s, e, i, j]
            fnode[a, 2] -= wet
        # point body
        if pb_mass[a] > 0.0:
            mtot = pb_mass[a] + pb_ca[a] * rho * pb_vol[a]
            for i in range(3):
                mnode[a, i, i] += mtot
            fnode[a, 2] -= (pb_mass[a] - rho * pb_vol[a]) * g
            if pb_cda[a] > 0.0:
                vc0, vc1, vc2 = current_xyz(r[a, 2], cur_z, cur_v)
                v0 = v[a, 0] - vc0
                v1 = v[a, 1] - vc1
                v2 = v[a, 2] - vc2
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
