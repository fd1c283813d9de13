"""Plain-numpy twin of :mod:`towenv.core.kernels` (no numba), for testing the kernels.

Every function here is written from the equations of ``model.md`` (sections 2, 3.3–3.4 and 5.1–5.6),
vectorised over segments and nodes where that reads naturally, and deliberately *not* by transcribing the
kernel loops (matrices instead of index loops, ``np.add.at`` scatters, a sparse C M̃⁻¹ Cᵀ product for the
tension matrix, scipy's sparse LU instead of the tree elimination). Where the kernels deliberately depart
from model.md — drag evaluated at each end node (trapezoidal rule) instead of at the mean end velocity,
and the convergence aids of the Newton iteration (implicit body damping, string stiffness, relaxed body
rotation, tension extrapolation) — the twin follows the kernels' documented choice, since the point is to
reproduce them. The tests (``tests/verification/test_twin.py``) compare each numba kernel with its twin on random
states. Speed is irrelevant here; clarity is the point.

Conventions (same as the kernels): ``t_s`` is the unit tangent of segment ``s`` from its lower node to
its upper node (toward the ship); ``σ_{a,s} = +1`` if node ``a`` is the lower node of ``s`` and ``−1`` if
it is the upper one, so the tension force on node ``a`` is ``Σ_s σ_{a,s} T_s t_s``. ``F_o`` are all the
non-tension forces on a node. Gravity is ``−g e_z``.

The functions take the :class:`towenv.core.system.System` of the tow (duck-typed: only its arrays are
read) and never modify their inputs.

Contents

* :func:`current_np`, :func:`rotation_matrix_np`, :func:`euler_rates_to_omega_np`,
  :func:`omega_dot_to_euler_acc_np` — environment and body kinematics (model.md 1.4);
  :func:`body_rotation_np`, :func:`attitude_euler_np`, :func:`rechart_np` — the moving attitude chart
* :func:`segment_loads_np` — tangents, stretched lengths, Morison drag, drag damping, added mass (2.2–2.3, 5.2)
* :func:`node_assembly_np` — node mass matrices, damping matrices, non-tension forces (2.2–2.3, point bodies)
* :func:`body_loads_np`, :func:`body_mass_blocks_np` — rigid-body loads and mass blocks (3.2–3.3)
* :func:`tension_matrix_np`, :func:`solve_tension_np` — the tension system K = −J as scipy.sparse (5.4–5.6);
  :func:`blocks_to_sparse` converts the kernel's storage (``kd``, ``kb``) for comparison
* :func:`houbolt_step_np` — one full Houbolt step with the Newton iteration (5.1–5.2, 3.4, 9), with
  :func:`geometric_stiffness_np`, :func:`translational_damping_np` and :func:`rotational_stiffness_np`
  (convergence aids of the kernel)
* :func:`thesis_shooting_recursion` — the thesis's printed recursion (4.38)–(4.40), *as published*; unstable,
  kept only to document why it is not used (model.md 5.6)
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from ..core.layout import (CABLE_REUSE_EXTRA_ITERATIONS, PRED_STATE_SIZE, PS_BODY_AGE, PS_BODY_VALID, PS_CABLE_AGE, PS_CABLE_ITERATIONS, PS_CABLE_VALID, PS_HIGHER, PS_VALID, S_ANGLE_TOLERANCE, S_BODY_REFRESH, S_CABLE_REFRESH, S_MAX_ITERATIONS, S_MAX_STRAIN, S_NEWTON_ESTIMATE, S_PLANAR, S_PREDICTOR, S_RELATIVE_TOLERANCE, S_TOLERANCE)
from ..core import layout as L
from ..core.layout import BP_AFT_TOW_POINT, BP_REDUCED_DOF, BP_TAIL_MASS
import scipy.sparse as sp
import scipy.sparse.linalg as spla

# status codes and node kinds (the same values as in towenv.core.kernels; the tests check this)
OK = 0
FAIL_NEWTON = 1
FAIL_NAN = 2
FAIL_STRETCH = 3
FAIL_ANGLE = 4
FREE = 0
PRESCRIBED_TOP = 1
PRESCRIBED_AFT = 2

_I3 = np.eye(3)


# ----------------------------------------------------------------------------------------------
# environment and body kinematics
# ----------------------------------------------------------------------------------------------
def current_np(z, cur_z, cur_v):
    """Current velocity (…, 3) at heights ``z`` (depth = −z): linear in depth, ends held (np.interp)."""
    z = np.asarray(z, float)
    depth = -z
    return np.stack([np.interp(depth, cur_z, cur_v[:, k]) for k in range(3)], axis=-1)


def _rx(b):
    c, s = math.cos(b), math.sin(b)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


def _rz(g):
    c, s = math.cos(g), math.sin(g)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_matrix_np(roll, pitch, yaw):
    """Λ_f (global → body components): yaw about Z, then pitch about the new Y, then roll about the new X.

    Built as the product of the three elementary (passive) rotations rather than the expanded formula."""
    return _rx(roll) @ _ry(pitch) @ _rz(yaw)


def body_rotation_np(ang, chart=None):
    """Λ = Λ_f(local angles) · C of a body stored in a moving attitude chart C (global -> chart components;
    None = identity). See ``kernels.body_rotation``."""
    lam = rotation_matrix_np(*ang)
    return lam if chart is None else lam @ np.asarray(chart, float)


def attitude_euler_np(lam):
    """(roll, pitch, yaw) of Λ_f (global -> body), pitch in [−90°, 90°], via scipy's intrinsic Z-Y-X
    decomposition of R = Λᵀ (body -> global = R_z(ψ) R_y(θ) R_x(φ) with active rotations, pitch nose down +)."""
    from scipy.spatial.transform import Rotation
    yaw, pitch, roll = Rotation.from_matrix(np.asarray(lam, float).T).as_euler("ZYX")
    return np.array([roll, pitch, yaw])


def rechart_np(hist_ang, chart, b):
    """Twin of ``kernels.rechart_body``: a new chart C' = Λ(ang⁰) for body ``b`` and the local angles of every
    stored level in it (level 0 becomes exactly 0). Returns new (hist_ang, chart) arrays; inputs unchanged."""
    hist_ang = np.array(hist_ang, float)
    chart = np.array(chart, float)
    lams = [body_rotation_np(hist_ang[k, b], chart[b]) for k in range(3)]
    u, _, vt = np.linalg.svd(lams[0])           # nearest rotation (the kernel uses Gram–Schmidt: same to round-off)
    new = u @ vt
    for k in range(3):
        hist_ang[k, b] = attitude_euler_np(lams[k] @ new.T)
    hist_ang[0, b] = 0.0
    chart[b] = new
    return hist_ang, chart


def _euler_rate_matrix(ang):
    """W(θ) with ω = W(θ) θ̇, θ = (roll β, pitch α, yaw γ)."""
    b, a = ang[0], ang[1]
    cb, sb, ca, sa = math.cos(b), math.sin(b), math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, -sa],
                     [0.0, cb, ca * sb],
                     [0.0, -sb, ca * cb]])


def euler_rates_to_omega_np(ang, dang):
    """Body rates (p, q, r) from Euler angles and their rates (model.md 1.4)."""
    return _euler_rate_matrix(ang) @ np.asarray(dang, float)


def omega_dot_to_euler_acc_np(ang, dang, omega, domega):
    """θ̈ = H(θ) ω̇ + Ḣ(θ, θ̇) ω with H = W⁻¹ the exact z-y-x kinematics (model.md 1.4).

    Ḣ = ∂H/∂β β̇ + ∂H/∂α α̇ (H does not depend on the yaw)."""
    b, a = ang[0], ang[1]
    cb, sb, ca, sa = math.cos(b), math.sin(b), math.cos(a), math.sin(a)
    ta = sa / ca
    H = np.array([[1.0, sb * ta, cb * ta],
                  [0.0, cb, -sb],
                  [0.0, sb / ca, cb / ca]])
    dH_db = np.array([[0.0, cb * ta, -sb * ta],
                      [0.0, -sb, -cb],
                      [0.0, cb / ca, -sb / ca]])
    dH_da = np.array([[0.0, sb / ca ** 2, cb / ca ** 2],
                      [0.0, 0.0, 0.0],
                      [0.0, sb * sa / ca ** 2, cb * sa / ca ** 2]])
    Hdot = dH_db * dang[0] + dH_da * dang[1]
    return H @ np.asarray(domega, float) + Hdot @ np.asarray(omega, float)


# ----------------------------------------------------------------------------------------------
# cable loads
# ----------------------------------------------------------------------------------------------
@dataclass
class SegmentLoads:
    tang: np.ndarray        # (S, 3) unit tangents, lower → upper node
    stretched: np.ndarray   # (S,)   ℓ_s
    drag: np.ndarray        # (S, 2, 3) whole-segment Morison drag at the relative velocity of end e (0 lower, 1 upper)
    bmat: np.ndarray        # (S, 2, 3, 3) B_e = −∂drag_e/∂v_r,e
    madd: np.ndarray        # (S, 3, 3) added-mass tensor of the whole segment


def _outer(a, b):
    return a[..., :, None] * b[..., None, :]


def morison_drag_np(vr, tang, kn, kt):
    """Quadratic drag −k_n |v_n| v_n − k_t |v_t| v_t (vector normal form, model.md 2.3 / erratum E6) and its
    damping matrix B = −∂f/∂v_r = k_n(|v_n|(𝟙 − t tᵀ) + v_n v_nᵀ/|v_n|) + 2 k_t |v_t| t tᵀ (model.md 5.2),
    for relative velocities ``vr`` (…, 3) and tangents ``tang`` (…, 3); k = ½ρ C D l.
    The v_n v_nᵀ/|v_n| term (→ 0 with |v_n|) is dropped below |v_n| = 1e-12 m/s."""
    vt = np.einsum("...i,...i->...", vr, tang)
    vn = vr - vt[..., None] * tang
    vn_abs = np.linalg.norm(vn, axis=-1)
    f = -(kn * vn_abs)[..., None] * vn - (kt * np.abs(vt) * vt)[..., None] * tang
    tt = _outer(tang, tang)
    inv_vn = np.where(vn_abs > 1e-12, 1.0 / np.where(vn_abs > 1e-12, vn_abs, 1.0), 0.0)
    B = ((kn * vn_abs)[..., None, None] * (_I3 - tt) + (kn * inv_vn)[..., None, None] * _outer(vn, vn)
         + (2.0 * kt * np.abs(vt))[..., None, None] * tt)
    return f, B


def segment_loads_np(sys, r, v) -> SegmentLoads:
    """Per-segment tangent, stretched length, quadratic drag, drag damping and added mass.

    Drag (model.md 2.3, vector normal form): the whole-segment drag ``f_d(v_r) = −k_n|v_n|v_n − k_t|v_t|v_t``
    (k = ½ρ C D l) is evaluated at the relative velocity v_r,e = ṙ_e − V_c(r_e) of *each* end node e with the
    segment tangent; node e receives ½ f_d(v_r,e) (trapezoidal rule along the segment, as the kernel does;
    the thesis's (3.10) uses the mean end velocity instead, which differs at second order in l).
    Added mass (2.2): Am = C_at ρ A l t tᵀ + C_an ρ A l (𝟙 − t tᵀ), A = πD²/4.
    A zero-length segment gets the tangent e_z.
    """
    r = np.asarray(r, float)
    v = np.asarray(v, float)
    lo, up = sys.seg_lo, sys.seg_up
    d = r[up] - r[lo]
    ell = np.linalg.norm(d, axis=1)
    safe = np.where(ell > 0.0, ell, 1.0)
    tang = np.where((ell > 0.0)[:, None], d / safe[:, None], np.array([0.0, 0.0, 1.0]))

    rho = float(sys.rho)
    vrel_node = v - current_np(r[:, 2], sys.cur_z, sys.cur_v)
    vr = np.stack([vrel_node[lo], vrel_node[up]], axis=1)                 # (S, 2, 3)
    kn = 0.5 * rho * sys.cn * sys.diam * sys.l0
    kt = 0.5 * rho * sys.ct * sys.diam * sys.l0
    drag, bmat = morison_drag_np(vr, tang[:, None, :], kn[:, None], kt[:, None])

    tt = _outer(tang, tang)
    area_l = 0.25 * math.pi * sys.diam ** 2 * sys.l0
    madd = (sys.cat * rho * area_l)[:, None, None] * tt + (sys.can * rho * area_l)[:, None, None] * (_I3 - tt)
    return SegmentLoads(tang, ell, drag, bmat, madd)


def node_assembly_np(sys, r, v, seg: SegmentLoads):
    """Node mass matrices M_a (dry + added), drag damping matrices B_a and non-tension forces F_o,a.

    Each segment gives half of its dry mass, added-mass tensor and wet weight to each end node, and to
    each end node half of the drag (and damping matrix) evaluated at that node's relative velocity
    (model.md 2.2–2.3, :func:`segment_loads_np`; scatter with ``np.add.at``). Point bodies (ball/clump) add
    (m + C_a ρV) 𝟙, their wet weight (m − ρV) g and isotropic drag −½ρ CdA |v_r| v_r with its damping
    matrix ½ρ CdA (|v_r| 𝟙 + v_r v_rᵀ/|v_r|). Returns (mnode, bnode, fnode).
    """
    r = np.asarray(r, float)
    v = np.asarray(v, float)
    nn = sys.node_kind.shape[0]
    rho, g = float(sys.rho), float(sys.g)
    mnode = np.zeros((nn, 3, 3))
    bnode = np.zeros((nn, 3, 3))
    fnode = np.zeros((nn, 3))

    half_mass = 0.5 * sys.mu * sys.l0
    half_wet = 0.5 * (sys.mu - rho * 0.25 * math.pi * sys.diam ** 2) * g * sys.l0
    seg_m = half_mass[:, None, None] * _I3 + 0.5 * seg.madd
    weight = half_wet[:, None] * np.array([0.0, 0.0, 1.0])
    for e, ends in enumerate((sys.seg_lo, sys.seg_up)):
        np.add.at(mnode, ends, seg_m)
        np.add.at(bnode, ends, 0.5 * seg.bmat[:, e])
        np.add.at(fnode, ends, 0.5 * seg.drag[:, e] - weight)

    # point bodies
    pb = np.nonzero(sys.pb_mass > 0.0)[0]
    if pb.size:
        mnode[pb] += ((sys.pb_mass[pb] + sys.pb_ca[pb] * rho * sys.pb_vol[pb])[:, None, None] * _I3)
        fnode[pb, 2] -= (sys.pb_mass[pb] - rho * sys.pb_vol[pb]) * g
        dr = pb[sys.pb_cda[pb] > 0.0]
        if dr.size:
            vrel = v[dr] - current_np(r[dr, 2], sys.cur_z, sys.cur_v)
            vm = np.linalg.norm(vrel, axis=1)
            kd = 0.5 * rho * sys.pb_cda[dr]
            fnode[dr] -= (kd * vm)[:, None] * vrel
            inv_vm = np.where(vm > 1e-12, 1.0 / np.where(vm > 1e-12, vm, 1.0), 0.0)
            bnode[dr] += (kd * vm)[:, None, None] * _I3 + (kd * inv_vm)[:, None, None] * _outer(vrel, vrel)
    return mnode, bnode, fnode


# ----------------------------------------------------------------------------------------------
# rigid towed bodies
# ----------------------------------------------------------------------------------------------
def _lookup(x, xs, ys):
    """Piecewise-linear table, end values held (np.interp)."""
    return float(np.interp(x, xs, ys))


def body_params(sys, b):
    """The packed parameters of rigid body ``b`` as a dict of named quantities (towenv.core.layout)."""
    p = sys.bp[b]

    def v3(c):
        return p[c:c + 3].copy()

    M_A = p[L.BP_ADDED_COUPLING:L.BP_ADDED_COUPLING + 36].reshape(6, 6).copy()
    M_A[np.diag_indices(6)] = np.r_[v3(L.BP_ADDED_MASS), v3(L.BP_ADDED_INERTIA)]
    return dict(mass=p[L.BP_MASS], volume=p[L.BP_VOLUME], area=p[L.BP_AREA], length=p[L.BP_LENGTH],
                r_G=v3(L.BP_CG), r_B=v3(L.BP_CB), I_G=v3(L.BP_INERTIA), rot_lin=v3(L.BP_ROT_DAMPING),
                rot_quad=v3(L.BP_QUAD_ROT_DAMPING), lift_slope=p[L.BP_LIFT_SLOPE], added_mass=v3(L.BP_ADDED_MASS),
                added_inertia=v3(L.BP_ADDED_INERTIA), r_aft=v3(L.BP_AFT_TOW_POINT), M_A=M_A,
                coriolis=bool(p[L.BP_ADDED_CORIOLIS] != 0.0), external=p[L.BP_EXTERNAL_FORCE:L.BP_EXTERNAL_FORCE + 3].copy())


def _coefficients_np(theta, inc, cd, cl, cm):
    """Table coefficients with the fore-aft fold for reverse flow beyond a ±90° table (see kernels)."""
    if abs(theta) > 90.0 and inc[-1] <= 90.0 and inc[0] >= -90.0 and not inc[0] <= theta <= inc[-1]:
        tf = np.copysign(180.0 - abs(theta), theta)
        return _lookup(tf, inc, cd), -_lookup(tf, inc, cl), _lookup(tf, inc, cm)
    return _lookup(theta, inc, cd), _lookup(theta, inc, cl), _lookup(theta, inc, cm)


def body_loads_np(sys, b, lam, vbody, omega, cur_global):
    """Body-axis force (at the tow point) and moment (about the tow point) on rigid body ``b`` (model.md 3.3).

    * weight m g_b at r_G and buoyancy −ρV g_b at r_B, g_b = Λ (0, 0, −g); a constant external force (global axes)
      at r_G (``external_force``, thrusters);
    * hydrodynamics from the relative velocity of the centroid v_r = v + ω×r_B − Λ V_c, |v_r| = V:
      incidences θ_v = atan2(w_r, u_r) and θ_h = atan2(v_r, u_r) (docs/scene-format.md); drag
      ½ρAV² (C_d,v(θ_v) + C_d,h(θ_h) − C_d,v(0))⁺ along −v_r; lift ½ρAV² C_L(θ_v) ⊥ v_r in x′z′ toward +z′;
      side force ½ρAV² C_Y(θ_h) ⊥ v_r in x′y′ toward +y′; weathervane moments ½ρAlV² C_m turning the nose
      toward v_r (θ_v > 0: v_r above the nose, nose-up = −M_y′; θ_h > 0: v_r to port, +M_z′);
    * rotational damping −½ρA l² V C_lin ω − ½ρA C_quad l³/32 ω|ω| per axis.

    Returns (f (3,), m (3,), bdiag) with ``bdiag = ½ρAV(2C_d + dC_L/dα)`` the isotropic drag-derivative
    estimate used for the implicit drag of the tow-point node.
    """
    P = body_params(sys, b)
    rho, g = float(sys.rho), float(sys.g)
    lam = np.asarray(lam, float)
    omega = np.asarray(omega, float)
    g_b = lam @ np.array([0.0, 0.0, -g])
    f = (P["mass"] - rho * P["volume"]) * g_b
    m = np.cross(P["r_G"], P["mass"] * g_b) + np.cross(P["r_B"], -rho * P["volume"] * g_b)
    f_ext = lam @ P["external"]                      # thrusters: a global force at the centre of gravity
    f = f + f_ext
    m = m + np.cross(P["r_G"], f_ext)

    v_r = np.asarray(vbody, float) + np.cross(omega, P["r_B"]) - lam @ np.asarray(cur_global, float)
    V = float(np.linalg.norm(v_r))
    qa = 0.5 * rho * P["area"]
    L = P["length"]
    bdiag = 0.0
    if V > 1e-9:
        u_r, vv_r, w_r = v_r
        th_v = math.degrees(math.atan2(w_r, u_r))
        th_h = math.degrees(math.atan2(vv_r, u_r))
        nv, nh = sys.btab_n[b]
        tab = sys.btab[b]
        inc_v, inc_h = tab[0, :nv], tab[4, :nh]
        cd_v, cl_v, cm_v = _coefficients_np(th_v, inc_v, tab[1, :nv], tab[2, :nv], tab[3, :nv])
        cd_h, cy_h, cm_h = _coefficients_np(th_h, inc_h, tab[5, :nh], tab[6, :nh], tab[7, :nh])
        cd = max(cd_v + cd_h - _lookup(0.0, inc_v, tab[1, :nv]), 0.0)
        q = qa * V * V
        tv, th = math.radians(th_v), math.radians(th_h)
        f = f - q * cd * v_r / V
        e_lift = np.array([-math.sin(tv), 0.0, math.cos(tv)])      # ⊥ (cos θ_v, 0, sin θ_v), toward +z′
        e_side = np.array([-math.sin(th), math.cos(th), 0.0])      # ⊥ (cos θ_h, sin θ_h, 0), toward +y′
        f = f + q * cl_v * e_lift + q * cy_h * e_side
        m = m + q * L * np.array([0.0, -cm_v, cm_h])
        bdiag = qa * V * (2.0 * cd + P["lift_slope"])
    m = m - (qa * L * L * V * P["rot_lin"] * omega + qa * P["rot_quad"] * L ** 3 / 32.0 * omega * np.abs(omega))
    if P["coriolis"]:
        # added mass in Fossen's form: −C_A(ν)ν = −[[0, −S(p)], [−S(p), −S(h)]] ν with (p, h) = M_A ν, ν = the tow
        # point's velocity relative to the water; plus M_A (ω × v, 0) because the mass matrix multiplies the
        # inertial acceleration v̇ + ω × v; minus the −ω × (A₂₂ ω) already in the gyroscopic term
        v = np.asarray(vbody, float) - lam @ np.asarray(cur_global, float)
        nu = np.r_[v, omega]
        ph = P["M_A"] @ nu
        pp, hh = ph[:3], ph[3:]
        C = np.block([[np.zeros((3, 3)), -_skew(pp)], [-_skew(pp), -_skew(hh)]])
        extra = -C @ nu + P["M_A"] @ np.r_[np.cross(omega, v), np.zeros(3)]
        f = f + extra[:3]
        m = m + extra[3:] + np.cross(omega, P["M_A"][3:, 3:] @ omega)
    return f, m, bdiag


def _skew(a):
    """S(a) with S(a) b = a × b."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def body_mass_blocks_np(sys, b):
    """(A_tt, A_tr, A_rr) of M_RB + M_A about the tow point (model.md 3.2); A_rt = A_trᵀ.

    M_RB = [[m𝟙, −m S(r_G)], [m S(r_G), I_o]], I_o = I_G + m(|r_G|²𝟙 − r_G r_Gᵀ); M_A the 6×6 added mass about
    the tow point (diagonal unless the scene gives a matrix)."""
    P = body_params(sys, b)
    m, rG = P["mass"], P["r_G"]
    M_A = P["M_A"]
    A_tt = m * _I3 + M_A[:3, :3]
    A_tr = -m * _skew(rG) + M_A[:3, 3:]
    I_o = np.diag(P["I_G"]) + m * (rG @ rG * _I3 - np.outer(rG, rG))
    A_rr = I_o + M_A[3:, 3:]
    return A_tt, A_tr, A_rr


# ----------------------------------------------------------------------------------------------
# tension system
# ----------------------------------------------------------------------------------------------
def constraint_gradient(sys, tang, free_only=True):
    """C (S × 3N, sparse): row s holds σ_{a,s} t_sᵀ in the columns of each end node a (FREE nodes only)."""
    ns = sys.l0.shape[0]
    nn = sys.node_kind.shape[0]
    rows, cols, vals = [], [], []
    for ends, sgn in ((sys.seg_lo, 1.0), (sys.seg_up, -1.0)):
        keep = sys.node_kind[ends] == FREE if free_only else np.ones(ns, bool)
        s_idx = np.nonzero(keep)[0]
        for k in range(3):
            rows.append(s_idx)
            cols.append(3 * ends[s_idx] + k)
            vals.append(sgn * tang[s_idx, k])
    rows, cols, vals = (np.concatenate(x) for x in (rows, cols, vals))
    return sp.csr_matrix((vals, (rows, cols)), shape=(ns, 3 * nn))


def tension_matrix_np(sys, tang, minv, dt, merged=()):
    """K = −J (CSR) of the unsquared length constraints g_s = ℓ_s − l_s(1 + T_s/EA_s) (model.md 5.3–5.6).

    From the general rule J[i, s] = −Σ_a σ_{a,i} σ_{a,s} t_i·(½Δt² M̃_a⁻¹ t_s) − δ_is l_i/EA_i over the
    FREE nodes a shared by segments i and s:  K = ½Δt² C M̃⁻¹ Cᵀ + diag(l/EA), with C from
    :func:`constraint_gradient` and ``minv`` (N, 3, 3) the inverses of the node matrices M̃ (only FREE
    nodes are used). The rows use the coefficient tangents, so K is symmetric (and positive definite)
    whenever every M̃ is symmetric positive definite (model.md 5.6); a non-symmetric M̃ (a rigid body's full
    hydrodynamic damping) gives the corresponding non-symmetric K.
    """
    nn = sys.node_kind.shape[0]
    ns = sys.l0.shape[0]
    C = constraint_gradient(sys, tang)
    Cf = C
    if len(merged):
        # monolithic series coupling: a segment s hanging from the aft point c of a body at node a has
        # ∂r_c/∂T = ∂r_a/∂T (row: σ t_s in a's columns) and pulls a through the condensed body (column: H σ t_s)
        rows, cols, vr, vf = [], [], [], []
        for a, c, H in merged:
            for k in range(sys.node_nseg[c]):
                s = sys.node_segs[c, k]
                st = sys.node_sgn[c, k] * tang[s]
                rows += [s] * 3
                cols += [3 * a + i for i in range(3)]
                vr += list(st)
                vf += list(H @ st)
        C = C + sp.csr_matrix((vr, (rows, cols)), shape=(ns, 3 * nn))
        Cf = Cf + sp.csr_matrix((vf, (rows, cols)), shape=(ns, 3 * nn))
    Minv = sp.block_diag([sp.csr_matrix(minv[a]) for a in range(nn)], format="csr")
    ea = sys.ea
    compliance = np.where(np.isinf(ea), 0.0, sys.l0 / np.where(np.isinf(ea), 1.0, ea))
    K = 0.5 * dt * dt * (C @ Minv @ Cf.T) + sp.diags(compliance)
    return sp.csr_matrix(K)


def blocks_to_sparse(sys, kd, kb):
    """The kernel's storage of K (diagonal ``kd``, node blocks ``kb``) as a CSR matrix (for the tests)."""
    ns = kd.shape[0]
    rows, cols, vals = list(range(ns)), list(range(ns)), list(kd)
    for a in range(sys.node_kind.shape[0]):
        n = sys.node_nseg[a]
        for k1 in range(n):
            for k2 in range(n):
                if k1 != k2 and kb[a, k1, k2] != 0.0:
                    rows.append(sys.node_segs[a, k1])
                    cols.append(sys.node_segs[a, k2])
                    vals.append(kb[a, k1, k2])
    return sp.csr_matrix((vals, (rows, cols)), shape=(ns, ns))


def solve_tension_np(K, rhs):
    """Solve K x = rhs with a sparse LU (scipy splu)."""
    return spla.splu(sp.csc_matrix(K)).solve(np.asarray(rhs, float))


def thesis_shooting_recursion(E, F, G, rhs):
    """The thesis's printed sweep (4.38)–(4.40), *as published*. Unstable: do not use (model.md 5.6).

    Solves the tridiagonal system  E_i δT_{i−1} − F_i δT_i + G_i δT_{i+1} = rhs_i  (i = 0 … n−1, segments
    numbered from the bottom, E_0 and G_{n−1} unused) by shooting from the bottom: δT_i = μ_i δT_0 + η_i with
    μ_0 = 1, η_0 = 0 and, from row i,
        μ_{i+1} = (F_i μ_i − E_i μ_{i−1})/G_i,   η_{i+1} = (rhs_i + F_i η_i − E_i η_{i−1})/G_i,
    then closing at the top row n−1 for δT_0. The homogeneous recurrence has a growing solution ~λ^i
    (λ + 1/λ = 2 + s), so round-off is amplified by about λ^n; with s = 200 and n = 40 the answer is
    garbage (relative error > 1e60). Kept only as a regression test of that fact.
    """
    E, F, G, rhs = (np.asarray(x, float) for x in (E, F, G, rhs))
    n = F.shape[0]
    mu = np.zeros(n)
    eta = np.zeros(n)
    mu[0] = 1.0
    for i in range(n - 1):
        mu_m = mu[i - 1] if i > 0 else 0.0
        eta_m = eta[i - 1] if i > 0 else 0.0
        e = E[i] if i > 0 else 0.0
        mu[i + 1] = (F[i] * mu[i] - e * mu_m) / G[i]
        eta[i + 1] = (rhs[i] + F[i] * eta[i] - e * eta_m) / G[i]
    i = n - 1
    e = E[i] if n > 1 else 0.0
    mu_m = mu[i - 1] if n > 1 else 0.0
    eta_m = eta[i - 1] if n > 1 else 0.0
    # E δ_{n−2} − F δ_{n−1} = rhs_{n−1}
    dT0 = (rhs[i] - e * eta_m + F[i] * eta[i]) / (e * mu_m - F[i] * mu[i])
    return mu * dT0 + eta


# ----------------------------------------------------------------------------------------------
# one Houbolt step
# ----------------------------------------------------------------------------------------------
@dataclass
class TwinStep:
    """Result of :func:`houbolt_step_np`; also usable as the ``sim_like`` input of the next step."""
    system: Any
    settings: Any
    hist_r: np.ndarray
    hist_ang: np.ndarray
    tens_hist: np.ndarray
    top_react: np.ndarray
    status: int = OK
    iterations: int = 0
    element: int = -1
    max_dT: float = 0.0
    body_chart: np.ndarray | None = None
    older: tuple | None = None      # the step's memory (Simulator.older: older_r, older_ang, older_tens, cubic_r,
    #                                 cubic_ang, quad_tens, pred_state, body_relax, body_damp)


def _settings_array(settings):
    if hasattr(settings, "array"):
        settings = settings.array()
    return np.asarray(settings, float)


def place_aft_nodes_np(sys, r, angs, chart=None):
    """Aft tow points ride on their body: r_aft = r_tp + Λᵀ r_t (model.md 3.5), Λ = Λ_f(angs) C.
    Returns a new array."""
    r = np.array(r, float)
    for b in range(sys.body_node.shape[0]):
        c = sys.body_aft_node[b]
        if c >= 0:
            lam = body_rotation_np(angs[b], None if chart is None else chart[b])
            r[c] = r[sys.body_node[b]] + lam.T @ sys.bp[b, BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3]
    return r


def tension_force_np(sys, tang, tens):
    """Σ_s σ_{a,s} T_s t_s on every node (N, 3)."""
    f = np.zeros((sys.node_kind.shape[0], 3))
    Tt = tens[:, None] * tang
    np.add.at(f, sys.seg_lo, Tt)
    np.add.at(f, sys.seg_up, -Tt)
    return f


def houbolt_acc(r_new, hist_r, dt):
    """R̈^{t+1} = (2R^{t+1} − 5R^t + 4R^{t−1} − R^{t−2})/Δt² (5.16)."""
    return (2.0 * r_new - 5.0 * hist_r[0] + 4.0 * hist_r[1] - hist_r[2]) / (dt * dt)


def houbolt_vel(r_new, hist, dt):
    """Ṙ^{t+1} = (11R^{t+1} − 18R^t + 9R^{t−1} − 2R^{t−2})/(6Δt) (4.9)."""
    return (11.0 * r_new - 18.0 * hist[0] + 9.0 * hist[1] - 2.0 * hist[2]) / (6.0 * dt)


def node_reaction_np(sys, c, r_new, hist_r, dt, tang, tens, mnode, fnode):
    """Force of the cable system on the support of prescribed node c: Σσ T t + F_o − M r̈ (model.md 2.6)."""
    return node_tension_np(sys, c, tang, tens) + fnode[c] - mnode[c] @ houbolt_acc(r_new[c], hist_r[:, c], dt)


def node_tension_np(sys, c, tang, tens):
    """Σ_{s at c} σ_{c,s} T_s t_s: the segments' pull on node c (its own list in the cable topology)."""
    f = np.zeros(3)
    for k in range(sys.node_nseg[c]):
        s = sys.node_segs[c, k]
        f += sys.node_sgn[c, k] * tens[s] * tang[s]
    return f


def geometric_stiffness_np(sys, seg: SegmentLoads, tens):
    """Node string stiffness K_g,a = Σ_{s at a} (T_s/ℓ_s)(𝟙 − t_s t_sᵀ) (N, 3, 3); segments with ℓ = 0 omitted."""
    nn = sys.node_kind.shape[0]
    ell = seg.stretched
    k = np.where(ell > 0.0, tens / np.where(ell > 0.0, ell, 1.0), 0.0)
    kg_seg = k[:, None, None] * (_I3 - _outer(seg.tang, seg.tang))
    kg = np.zeros((nn, 3, 3))
    np.add.at(kg, sys.seg_lo, kg_seg)
    np.add.at(kg, sys.seg_up, kg_seg)
    return kg


def rotational_stiffness_np(sys, b, ang, v_node, omega, cur_global, m0, eps_angle=1e-5, eps_rate=1e-4, chart_b=None):
    """Diagonal estimates k_i = max(−∂M_i/∂θ_i, 0) and c_i = max(−∂M_i/∂ω_i, 0) of the body-load moments
    (forward differences about the moment ``m0`` at (θ, ω)); returns [k_β, k_α, k_γ, c_p, c_q, c_r].
    The Euler angle θ_i is perturbed with the tow-point velocity ``v_node`` held in global axes."""
    out = np.zeros(6)
    lam0 = body_rotation_np(ang, chart_b)
    for i in range(3):
        ang2 = np.array(ang, float)
        ang2[i] += eps_angle
        lam2 = body_rotation_np(ang2, chart_b)
        _, m, _ = body_loads_np(sys, b, lam2, lam2 @ v_node, omega, cur_global)
        out[i] = max(-(m[i] - m0[i]) / eps_angle, 0.0)
        w2 = np.array(omega, float)
        w2[i] += eps_rate
        _, m, _ = body_loads_np(sys, b, lam0, lam0 @ v_node, w2, cur_global)
        out[3 + i] = max(-(m[i] - m0[i]) / eps_rate, 0.0)
    return out


def translational_damping_np(sys, b, lam, vbody, omega, cur_global, f0):
    """D = −∂F/∂v (3×3, body axes, generally non-symmetric: lift) of the body force about the force ``f0``
    at ``vbody``, by forward differences with step 1e-6 (1 + |v|)."""
    vbody = np.asarray(vbody, float)
    eps = 1e-6 * (1.0 + float(np.linalg.norm(vbody)))
    D = np.zeros((3, 3))
    for j in range(3):
        v2 = vbody.copy()
        v2[j] += eps
        f, _, _ = body_loads_np(sys, b, lam, v2, omega, cur_global)
        D[:, j] = -(f - f0) / eps
    return D


def aft_segment_stiffness_np(sys, s, m_tail, stretched, tens, dt):
    """(axial, geometric) stiffness of the taut tail segment ``s`` hanging from an aft tow point against the
    aft point's motion within one step: 1/(l/EA + ½Δt²/m_tail) and T/ℓ; (0, 0) when slack
    (kernels.aft_segment_stiffness)."""
    if tens[s] <= 0.0 or stretched[s] <= 0.0:
        return 0.0, 0.0
    comp = 0.0 if math.isinf(sys.ea[s]) else sys.l0[s] / sys.ea[s]
    if m_tail > 0.0 and not math.isinf(m_tail):
        comp += 0.5 * dt * dt / m_tail
    return (1.0 / comp if comp > 0.0 else 0.0), tens[s] / stretched[s]


def aft_relaxation_np(sys, b, rs, lam, seg, tens, dt, axial=True):
    """Relaxation of the body–tail (series tow) coupling for body ``b``: the translational stiffness
    Σ k_ax t tᵀ + T/ℓ (𝟙 − t tᵀ) (3×3, added to the body node's ½Δt²-scaled linearisation) and the
    rotational stiffness about the body axes e_i, K_i = Σ max(0, T (d·t − (e·d)(e·t)) + k_ax (t·u)²
    + T/ℓ (|u|² − (t·u)²)), u = e × d, d = aft point − body node, t the pull's direction
    (kernels.aft_rotational_stiffness). They change the convergence rate only."""
    a = int(sys.body_node[b])
    c = int(sys.body_aft_node[b])
    kt = np.zeros((3, 3))
    kr = np.zeros(3)
    if c < 0:
        return kt, kr
    d = rs[c] - rs[a]
    for k in range(int(sys.node_nseg[c])):
        s = int(sys.node_segs[c, k])
        kax, kgeo = aft_segment_stiffness_np(sys, s, sys.bp[b, BP_TAIL_MASS], seg.stretched, tens, dt)
        if kax == 0.0 and kgeo == 0.0:
            continue
        kax = kax if axial else 0.0     # monolithic coupling: the pull's change with the stretch is in the Newton step
        tt = np.outer(seg.tang[s], seg.tang[s])
        kt += kax * tt + kgeo * (_I3 - tt)
        t = -(1.0 if sys.seg_up[s] == c else -1.0) * seg.tang[s]
        for i in range(3):
            e = lam[i]
            u = np.cross(e, d)
            tu = t @ u
            kk = tens[s] * (d @ t - (e @ d) * (e @ t)) + kax * tu * tu + kgeo * (u @ u - tu * tu)
            kr[i] += max(kk, 0.0)
    return kt, kr


def aft_rotation_rows_np(sys, merged, body, reduced, angs, tang, minv, dt):
    """Monolithic series coupling: the correction of the tension matrix's rows for the segments hanging from a
    merged aft tow point c (sparse, S × S): their length depends on the tensions through r_c = r_a + Λᵀ r_aft,
    r_a moving as the node-local solve says and the body turning within the iteration as the relaxed
    angle update says — δφ = W D W⁻¹ ½Δt² δω̇ (body axes; D = 1, these bodies' angle update is not relaxed,
    0 for held roll/yaw),
    δω̇ = G δf_c − X Λ (2/Δt²) δr_a, δr_c = δr_a + Λᵀ(δφ × r_aft). K's rows as assembled hold σ t·∂r_a/∂T;
    this adds σ t·(∂r_c/∂T − ∂r_a/∂T) (kernels: ``houbolt.aft_point_influence``, ``tension_system``)."""
    ns = sys.l0.shape[0]
    hdt2 = 0.5 * dt * dt
    rows, cols, vals = [], [], []
    for b in np.nonzero(merged)[0]:
        a, c = int(sys.body_node[b]), int(sys.body_aft_node[b])
        lam, _, _, X, _, arr_diag, G, H = body[b]
        # ∂r_a/∂T (3 × S): the node's own segments directly, the tail's through H
        dra = np.zeros((3, ns))
        for k in range(sys.node_nseg[a]):
            s = sys.node_segs[a, k]
            dra[:, s] += hdt2 * minv[a] @ (sys.node_sgn[a, k] * tang[s])
        df = np.zeros((3, ns))          # ∂f_c/∂T, the tail's pull (global)
        for k in range(sys.node_nseg[c]):
            s = sys.node_segs[c, k]
            df[:, s] = sys.node_sgn[c, k] * tang[s]
            dra[:, s] += hdt2 * minv[a] @ (H @ df[:, s])
        d = np.ones(3)                  # the angle update of these bodies is not relaxed
        if reduced[b]:
            d[[0, 2]] = 0.0
        W = _euler_rate_matrix(angs[b])
        dphi = hdt2 * W @ np.diag(d) @ np.linalg.inv(W) @ (G @ df - X @ lam @ dra * (2.0 / (dt * dt)))
        drc_minus_dra = -lam.T @ _skew(sys.bp[b, BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3]) @ dphi
        cols_b = np.nonzero(np.any(dra != 0.0, axis=0) | np.any(df != 0.0, axis=0))[0]
        for k in range(sys.node_nseg[c]):
            s1 = sys.node_segs[c, k]
            row = sys.node_sgn[c, k] * tang[s1] @ drc_minus_dra
            rows += [s1] * cols_b.size
            cols += list(cols_b)
            vals += list(row[cols_b])
    return sp.csr_matrix((vals, (rows, cols)), shape=(ns, ns))


def houbolt_step_np(sim_like, dt, r_top_new, trace=None) -> TwinStep:
    """Twin of ``kernels.houbolt_step``: one Houbolt step (model.md 5.1–5.2) on copies of the state.

    ``sim_like`` provides ``system``, ``settings`` (SolverSettings or its ``array()``), ``hist_r`` (3, N, 3),
    ``hist_ang`` (3, B, 3), ``tens_hist`` (2, S) and optionally ``body_chart`` (B, 3, 3; identity if absent:
    the body attitude is Λ = Λ_f(hist_ang) C, :func:`body_rotation_np`) — a
    :class:`~towenv.core.simulator.Simulator` or a previous :class:`TwinStep`. Re-charting happens between
    steps (:func:`rechart_np`, as ``kernels.advance`` does). Reduced models as in the kernel: with
    ``settings[8]`` (``solver.planar``) the free nodes keep their lateral coordinate (y row of M̃⁻¹
    dropped) and every body pitches only; a body with ``bp[b, BP_REDUCED_DOF] = 1`` (``dof = "surge_heave_pitch"``)
    pitches only (A_rr⁻¹ → e_y e_yᵀ/A_rr,yy, roll and yaw held). Nothing of it is modified. The step
    starts from the predictor R* = 3R^t − 3R^{t−1} + R^{t−2} (tow point prescribed) and the tension guess
    max(2T^t − T^{t−1}, 0).
    Per iteration:

    1. coefficients at the iterate r*: Houbolt velocities, segment and node loads, body loads with the
       tail-cable reaction, Coriolis/centripetal terms, and the condensation of each rigid body onto its
       tow-point node: A_eff = A_tt − A_tr A_rr⁻¹ A_rt, f_eff = F − A_tr A_rr⁻¹ M, added as Λᵀ A_eff Λ and
       Λᵀ f_eff (model.md 3.4);
    2. the linearisation L = (11Δt/12) B + ½Δt² K_g (implicit drag, 5.2 — at a rigid body's node B also
       holds Λᵀ D Λ with the body's full damping D = −∂F/∂v, :func:`translational_damping_np`, evaluated at
       the first iterate, or kept from an earlier step as the kernel keeps it (``solver.body_derivative_refresh``:
       ``older[7:]``, refreshed when ``houbolt.body_derivatives_due`` says so) — plus the node's own string
       stiffness K_g, :func:`geometric_stiffness_np`),
       M̃ = M + L, and the node-local affine map
       r_a(T) = M̃⁻¹[M (2.5r^t − 2r^{t−1} + 0.5r^{t−2}) + L r* + ½Δt² (F_o + Σ σ T t)]
       (with ``solver.cable_jacobian_refresh`` > 1 the free nodes' M̃ and M̃⁻¹ of an earlier step, ``older[9:]``,
       and L = M̃ − M between refreshes, as ``houbolt.cable_jacobian_due`` decides);
    3. residuals g = ℓ − l(1 + T/EA) at r(T), the tension matrix K = −J (coefficient tangents), slack
       segments (T ≤ 0 and g < 0) held at T = 0 by identity rows, K δT = g, T ← max(T + δT, 0) (5.3–5.6, 9);
    4. positions at the new tensions; body angular accelerations ω̇ = A_rr⁻¹(M − A_rt Λ r̈) mapped to Euler
       accelerations, Houbolt (4.10) on the Euler angles, the update relaxed by the diagonal factor
       1 + (½Δt² k_θ + (11Δt/12) c_ω)/A_rr,ii (:func:`rotational_stiffness_np`, evaluated at the first
       iterate or kept with D above); aft nodes re-placed;
    5. converged when max|δT| ≤ tol_abs + tol_rel·max(T) and max|Δangle| ≤ angle_tol; with
       ``solver.newton_stop = "estimate"`` also, from the second iteration, when each criterion holds for
       its estimated remaining error |δ_k|ρ/(1 − ρ), ρ = |δ_k|/|δ_{k−1}| ≤ ½, and no segment is slack.
    Then the strain and finiteness checks, the vessel reaction and the history shift.

    The linearisations in 2 and the relaxation in 4 change the convergence rate only, not the converged
    solution; they are reproduced here so that the iterates match the kernel's.

    If ``trace`` is a list, a dict of the iterate (positions, tensions, angles, max|δT|, and the tension
    system: coefficient tangents, M̃⁻¹, K, right-hand side, δT) is appended to it after every iteration.
    """
    sys = sim_like.system
    settings = _settings_array(sim_like.settings)
    tol_abs, tol_rel, maxit, max_strain, ang_tol = (settings[S_TOLERANCE], settings[S_RELATIVE_TOLERANCE], int(settings[S_MAX_ITERATIONS]), settings[S_MAX_STRAIN],
                                                    settings[S_ANGLE_TOLERANCE])
    stop_estimate = settings.shape[0] > S_NEWTON_ESTIMATE and settings[S_NEWTON_ESTIMATE] != 0.0
    prev_d = prev_a = 0.0
    hist_r = np.array(sim_like.hist_r, float)
    hist_ang = np.array(sim_like.hist_ang, float)
    tens_hist = np.array(sim_like.tens_hist, float)
    old_react = np.array(getattr(sim_like, "top_react", np.zeros(3)), float)
    chart = getattr(sim_like, "body_chart", None)
    chart = np.tile(_I3, (sys.body_node.shape[0], 1, 1)) if chart is None else np.array(chart, float)
    # reduced models: vertical plane (settings[8]) and pitch-only bodies (bp[:, BP_REDUCED_DOF])
    planar = settings.shape[0] > S_PLANAR and settings[S_PLANAR] != 0.0
    reduced = planar | (sys.bp[:, BP_REDUCED_DOF] != 0.0) if sys.bp.shape[0] else np.zeros(0, bool)
    # series tows coupled monolithically (solver.series_coupling, system.tension_cliques): the aft tow point's
    # segments pull the body inside the tension solve
    merged = np.array([c >= 0 and getattr(sys, "series_coupling", "relaxed") == "monolithic"
                       for c in sys.body_aft_node], bool)

    adaptive = settings.shape[0] > S_PREDICTOR and settings[S_PREDICTOR] != 0.0
    older = getattr(sim_like, "older", None)
    if older is None:
        older = (np.zeros_like(hist_r[0]), np.zeros_like(hist_ang[0]), np.zeros_like(tens_hist[0]),
                 np.zeros(hist_r.shape[1]), np.zeros(hist_ang.shape[1]), np.zeros(tens_hist.shape[1]),
                 np.zeros(PRED_STATE_SIZE), np.zeros((hist_ang.shape[1], 6)), np.zeros((hist_ang.shape[1], 3, 3)),
                 np.zeros((hist_r.shape[1], 3, 3)), np.zeros((hist_r.shape[1], 3, 3)))
    older = tuple(np.array(a, float) for a in older)
    # the bodies' load derivatives: afresh on the first iteration, or the kept ones (solver.body_derivative_refresh;
    # houbolt.body_derivatives_due)
    refresh = settings[S_BODY_REFRESH] if settings.shape[0] > S_BODY_REFRESH else 1.0
    body_fresh = refresh <= 1.0 or older[6][PS_BODY_VALID] == 0.0 or older[6][PS_BODY_AGE] >= refresh
    kept_relax, kept_damp = older[7].copy(), older[8].copy()
    # the free nodes' Newton matrices: built at every iteration, or the kept ones (a modified Newton;
    # solver.cable_jacobian_refresh, houbolt.cable_jacobian_due — the twin has no compensator)
    cable_refresh = settings[S_CABLE_REFRESH] if settings.shape[0] > S_CABLE_REFRESH else 1.0
    cable_fresh = (cable_refresh <= 1.0 or bool(np.any(np.asarray(sys.body_aft_node) >= 0))
                   or older[6][PS_CABLE_VALID] == 0.0 or older[6][PS_CABLE_AGE] >= cable_refresh)
    kept_mt, kept_minv = older[9].copy(), older[10].copy()
    valid = older[6][PS_VALID] != 0.0
    up_r = (older[3] != 0.0) & valid         # one order higher, per node / body / segment
    up_ang = (older[4] != 0.0) & valid
    up_tens = (older[5] != 0.0) & valid

    def fail(status, it, elem, maxd):
        return TwinStep(sys, sim_like.settings, hist_r, hist_ang, tens_hist, old_react, status, it, elem, maxd,
                        chart, older)

    nb = sys.body_node.shape[0]
    top = sys.top_node
    free = sys.node_kind == FREE
    c11 = 11.0 * dt / 12.0
    hdt2 = 0.5 * dt * dt
    r_hist_term = 2.5 * hist_r[0] - 2.0 * hist_r[1] + 0.5 * hist_r[2]
    a_hist_term = 2.5 * hist_ang[0] - 2.0 * hist_ang[1] + 0.5 * hist_ang[2]

    # predictor (one order higher where the memory says so: solver.predictor = "adaptive", kernel's commit)
    rs = np.where(up_r[:, None], 4.0 * hist_r[0] - 6.0 * hist_r[1] + 4.0 * hist_r[2] - older[0],
                  3.0 * hist_r[0] - 3.0 * hist_r[1] + hist_r[2])
    rs[top] = r_top_new
    angs = np.where(up_ang[:, None], 4.0 * hist_ang[0] - 6.0 * hist_ang[1] + 4.0 * hist_ang[2] - older[1],
                    3.0 * hist_ang[0] - 3.0 * hist_ang[1] + hist_ang[2])
    rs = place_aft_nodes_np(sys, rs, angs, chart)
    tens = np.maximum(np.where(up_tens, 3.0 * tens_hist[0] - 3.0 * tens_hist[1] + older[2],
                               2.0 * tens_hist[0] - tens_hist[1]), 0.0)     # linear extrapolation, T ≥ 0
    ea = sys.ea
    compliance = np.where(np.isinf(ea), 0.0, sys.l0 / np.where(np.isinf(ea), 1.0, ea))

    relax = np.zeros((nb, 6))       # per body: rotational stiffness k_θ (3) and damping c_ω (3)
    bdamp = np.zeros((nb, 3, 3))    # per body: translational damping D = −∂F/∂v (body axes)
    status = FAIL_NEWTON
    it = 0
    maxd = 0.0
    elem = -1
    for it in range(1, maxit + 1):
        # 1. coefficients
        vs = houbolt_vel(rs, hist_r, dt)
        seg = segment_loads_np(sys, rs, vs)
        mnode, bnode, fnode = node_assembly_np(sys, rs, vs, seg)
        body = []
        for b in range(nb):
            a = sys.body_node[b]
            P = body_params(sys, b)
            dang = houbolt_vel(angs[b], hist_ang[:, b], dt)
            lam = body_rotation_np(angs[b], chart[b])
            w = euler_rates_to_omega_np(angs[b], dang)
            z_centroid = rs[a, 2] + (lam.T @ P["r_B"])[2]
            cur = current_np(z_centroid, sys.cur_z, sys.cur_v)
            F, M, _ = body_loads_np(sys, b, lam, lam @ vs[a], w, cur)
            if it == 1 and body_fresh:
                relax[b] = rotational_stiffness_np(sys, b, angs[b], vs[a], w, cur, M, chart_b=chart[b])
                bdamp[b] = translational_damping_np(sys, b, lam, lam @ vs[a], w, cur, F)
                if reduced[b]:
                    relax[b, [0, 2, 3, 5]] = 0.0       # roll and yaw are held: not needed
                if planar:
                    bdamp[b][:, 1] = 0.0                 # no lateral velocity
                kept_relax[b], kept_damp[b] = relax[b], bdamp[b]
            elif it == 1:
                relax[b], bdamp[b] = kept_relax[b], kept_damp[b]
            c = sys.body_aft_node[b]
            if c >= 0:
                tail = node_reaction_np(sys, c, rs, hist_r, dt, seg.tang, tens, mnode, fnode)
                if merged[b]:
                    # monolithic series coupling: the tail's pull enters the tension solve (H_b below); only
                    # the aft node's own loads and inertia are a load on the body here
                    tail = tail - node_tension_np(sys, c, seg.tang, tens)
                tail = lam @ tail
                F = F + tail
                M = M + np.cross(P["r_aft"], tail)
            A_tt, A_tr, A_rr = body_mass_blocks_np(sys, b)
            F = F - P["mass"] * np.cross(w, np.cross(w, P["r_G"]))
            M = M - np.cross(w, A_rr @ w)          # rigid + added rotational inertia (kernels.condense_body)
            arr_diag = np.diag(A_rr).copy()
            if merged[b]:
                # monolithic series coupling: the rotational stiffness/damping estimates inside the condensation,
                # (A_rr + P) ω̇ = M − A_rt a + P ω̇*, P = diag(½Δt² k + (11Δt/12) c), ω̇* of the iterate
                if it == 1:
                    _, kr = aft_relaxation_np(sys, b, rs, lam, seg, tens, dt, axial=False)
                    relax[b, :3] += kr
                prot = hdt2 * relax[b, :3] + c11 * relax[b, 3:]
                Wm = _euler_rate_matrix(angs[b])
                e0 = omega_dot_to_euler_acc_np(angs[b], dang, w, np.zeros(3))
                wdot = Wm @ (houbolt_acc(angs[b], hist_ang[:, b], dt) - e0)
                # the aft node's mass and drag damping ride on the aft point: a point mass P_m there,
                # ΔA = [[P_m, −P_m S(r)], [S(r) P_m, −S(r) P_m S(r)]] on both sides with the iterate's (a*, ω̇*)
                Mb = lam @ (mnode[c] + c11 * bnode[c]) @ lam.T
                Sr = _skew(P["r_aft"])
                astar = lam @ houbolt_acc(rs[a], hist_r[:, a], dt)
                dtt, dtr, drt, drr = Mb, -Mb @ Sr, Sr @ Mb, -Sr @ Mb @ Sr
                F = F + dtt @ astar + dtr @ wdot
                M = M + drt @ astar + drr @ wdot
                A_tt = A_tt + dtt
                A_tr = A_tr + dtr
                A_rr = A_rr + drr
                A_rr = A_rr + np.diag(prot)
                M = M + prot * wdot
            if reduced[b]:
                # pitch only: roll and yaw held by constraint moments, A_rr⁻¹ → e_y e_yᵀ / A_rr,yy
                e_y = np.array([0.0, 1.0, 0.0])
                A_rr_inv = np.outer(e_y, e_y) / A_rr[1, 1]
            else:
                A_rr_inv = np.linalg.inv(A_rr)
            X = A_rr_inv @ A_tr.T
            y = A_rr_inv @ M
            A_eff = A_tt - A_tr @ X
            f_eff = F - A_tr @ y
            mnode[a] += lam.T @ A_eff @ lam
            fnode[a] += lam.T @ f_eff
            bnode[a] += lam.T @ bdamp[b] @ lam
            # a global force f at the aft point: ω̇ += G f, node force += H f (the condensed body)
            G = A_rr_inv @ _skew(P["r_aft"]) @ lam
            H = _I3 - lam.T @ A_tr @ G
            body.append((lam, dang, w, X, y, arr_diag, G, H))
        # 2. node-local affine map r(T)
        lin = c11 * bnode + hdt2 * geometric_stiffness_np(sys, seg, tens)
        for b in range(nb):
            c = sys.body_aft_node[b]
            if c >= 0:      # series tow: relax the body–tail coupling (rate only)
                kt, kr = aft_relaxation_np(sys, b, rs, body[b][0], seg, tens, dt, axial=not merged[b])
                if merged[b]:
                    # the tail segments' string stiffness moves with the tow point: through H (the aft node's
                    # inertia and drag are in the condensation above)
                    lin[sys.body_node[b]] += body[b][7] @ (hdt2 * kt)
                else:
                    lin[sys.body_node[b]] += hdt2 * kt
                    if it == 1:
                        relax[b, :3] += kr
        if cable_fresh:
            Mt = mnode + lin
            minv = np.zeros_like(Mt)
            minv[free] = np.linalg.inv(Mt[free])
            kept_mt[free] = Mt[free]
            kept_minv[free] = minv[free]
        else:
            # the kept M̃ and its inverse; lin = M̃ − M of this iterate (the rate terms on both sides)
            minv = np.zeros_like(mnode)
            minv[free] = kept_minv[free]
            lin[free] = kept_mt[free] - mnode[free]
        if planar:
            # vertical plane: the lateral coordinate held (no y row; the accepted scenes have no x–y, y–z coupling)
            minv[:, 1, :] = 0.0
        rhs_node = (np.einsum("aij,aj->ai", mnode, r_hist_term) + np.einsum("aij,aj->ai", lin, rs)
                    + hdt2 * fnode)
        acon = np.einsum("aij,aj->ai", minv, rhs_node)
        if planar:
            acon[free, 1] = hist_r[0][free, 1]

        def pull(T):
            f = tension_force_np(sys, seg.tang, T)
            for b in np.nonzero(merged)[0]:
                f[sys.body_node[b]] += body[b][7] @ node_tension_np(sys, sys.body_aft_node[b], seg.tang, T)
            return f

        def positions(T):
            out = rs.copy()
            x = acon + hdt2 * np.einsum("aij,aj->ai", minv, pull(T))
            out[free] = x[free]
            return out

        rs = place_aft_nodes_np(sys, positions(tens), angs, chart)
        # 3. residuals and Newton update
        ell = np.linalg.norm(rs[sys.seg_up] - rs[sys.seg_lo], axis=1)
        gres = ell - sys.l0 - compliance * tens
        tmax = max(float(tens.max(initial=0.0)), 0.0)
        K = tension_matrix_np(sys, seg.tang, minv, dt, [(sys.body_node[b], sys.body_aft_node[b], body[b][7])
                                                        for b in np.nonzero(merged)[0]])
        if np.any(merged):
            K = K + aft_rotation_rows_np(sys, merged, body, reduced, angs, seg.tang, minv, dt)
        slack = (tens <= 0.0) & (gres < 0.0)
        keep = sp.diags((~slack).astype(float))
        K = keep @ K @ keep + sp.diags(slack.astype(float))
        rhs = np.where(slack, -tens, gres)
        try:
            dT = solve_tension_np(K, rhs)
        except RuntimeError:                      # singular factor
            return fail(FAIL_NEWTON, it, -1, 0.0)
        new = np.maximum(tens + dT, 0.0)
        change = np.abs(new - tens)
        if not np.all(np.isfinite(change)):
            bad = np.nonzero(~np.isfinite(change))[0]
            return fail(FAIL_NAN, it, int(bad[0]), float("nan"))
        elem = int(np.argmax(change))
        maxd = float(change[elem])
        tens = new
        rs = positions(tens)
        # 4. body rotations
        dang_max = 0.0
        new_angs = angs.copy()
        for b in range(nb):
            a = sys.body_node[b]
            lam, dang, w, X, y, arr_diag, G, _ = body[b]
            if merged[b]:
                y = y + G @ node_tension_np(sys, sys.body_aft_node[b], seg.tang, tens)    # at the new tensions
            a_body = lam @ houbolt_acc(rs[a], hist_r[:, a], dt)
            domega = y - X @ a_body
            eacc = omega_dot_to_euler_acc_np(angs[b], dang, w, domega)
            plain = a_hist_term[b] + hdt2 * eacc
            # relaxed fixed-point update (diagonal implicit rotational stiffness and damping; inside the
            # condensation for a body with a monolithically coupled tail)
            factor = 1.0 if merged[b] else 1.0 + (hdt2 * relax[b, :3] + c11 * relax[b, 3:]) / arr_diag
            new_angs[b] = angs[b] + (plain - angs[b]) / factor
            if reduced[b]:
                new_angs[b, [0, 2]] = hist_ang[0, b, [0, 2]]      # roll and yaw held
            dang_max = max(dang_max, float(np.max(np.abs(new_angs[b] - angs[b]))))
            if abs(new_angs[b, 1]) > 1.48:  # kernels.PITCH_LIMIT, kept literal: the twin is independent
                return fail(FAIL_ANGLE, it, b, maxd)
        if not math.isfinite(dang_max):
            return fail(FAIL_NAN, it, -1, maxd)
        angs = new_angs
        rs = place_aft_nodes_np(sys, rs, angs, chart)
        if trace is not None:
            trace.append(dict(r=rs.copy(), tens=tens.copy(), angs=angs.copy(), max_dT=maxd, dang_max=dang_max,
                              tang=seg.tang.copy(), minv=minv.copy(), K=K, rhs=rhs.copy(), dT=dT.copy()))
        # 5. convergence: on the last change, or (solver.newton_stop = "estimate", from the second
        # iteration) on the estimated remaining error last change·ρ/(1 − ρ) while ρ ≤ 1/2
        tol_t = tol_abs + tol_rel * tmax
        if maxd <= tol_t and dang_max <= ang_tol:
            status = OK
            break
        if stop_estimate and it >= 2 and not np.any(new <= 0.0):
            ok_t = maxd <= tol_t or (maxd <= 0.5 * prev_d and maxd * maxd / (prev_d - maxd) <= tol_t)
            ok_a = dang_max <= ang_tol or (dang_max <= 0.5 * prev_a
                                           and dang_max * dang_max / (prev_a - dang_max) <= ang_tol)
            if ok_t and ok_a:
                status = OK
                break
        if not cable_fresh and it >= older[6][PS_CABLE_ITERATIONS] + CABLE_REUSE_EXTRA_ITERATIONS:
            break                   # the kept matrices converge too slowly: the kernel's caller retries afresh
        prev_d = maxd
        prev_a = dang_max
    if status != OK:
        return fail(status, it, elem, maxd)
    strain = np.where(np.isinf(ea), 0.0, tens / np.where(np.isinf(ea), 1.0, ea))
    over = np.nonzero(strain > max_strain)[0]
    if over.size:
        return fail(FAIL_STRETCH, it, int(over[0]), maxd)
    if not np.all(np.isfinite(rs)):
        return fail(FAIL_NAN, it, int(np.nonzero(~np.all(np.isfinite(rs), axis=1))[0][0]), maxd)
    top_react = node_reaction_np(sys, top, rs, hist_r, dt, seg.tang, tens, mnode, fnode)
    new_hist_r = np.stack([rs, hist_r[0], hist_r[1]])
    new_hist_ang = np.stack([angs, hist_ang[0], hist_ang[1]])
    new_tens = np.stack([tens, tens_hist[0]])
    body_state = older[6].copy()
    if adaptive:
        older = choose_predictor_np(it, rs, angs, tens, hist_r, hist_ang, tens_hist, older)
    pred_state = older[6].copy()
    pred_state[PS_BODY_VALID] = 1.0 if body_fresh else body_state[PS_BODY_VALID]
    pred_state[PS_BODY_AGE] = 1.0 if body_fresh else body_state[PS_BODY_AGE] + 1.0
    pred_state[PS_CABLE_VALID] = 1.0 if cable_fresh else body_state[PS_CABLE_VALID]
    pred_state[PS_CABLE_AGE] = 1.0 if cable_fresh else body_state[PS_CABLE_AGE] + 1.0
    pred_state[PS_CABLE_ITERATIONS] = it if cable_fresh else body_state[PS_CABLE_ITERATIONS]
    if not cable_fresh and it > body_state[PS_CABLE_ITERATIONS]:
        pred_state[PS_CABLE_VALID] = 0.0        # the kept matrices slowed the iteration: built afresh next step
    older = older[:6] + (pred_state, kept_relax, kept_damp, kept_mt, kept_minv)
    return TwinStep(sys, sim_like.settings, new_hist_r, new_hist_ang, new_tens, top_react, OK, it, -1, maxd, chart,
                    older)


def choose_predictor_np(iterations, rs, angs, tens, hist_r, hist_ang, tens_hist, older):
    """Twin of ``houbolt.choose_predictor``: per node, body and segment, the extrapolation that would have
    predicted the converged (rs, angs, tens) better (nodes and bodies: the largest error over the three
    coordinates, q for the quadratic prediction and q + d for the cubic one, d their difference; segments: the
    clamped predictions' errors; a tie keeps the lower order; a step converged on its first iteration from the
    lower orders everywhere keeps them), then the oldest levels kept. Returns the new memory (``Simulator.older``'s
    layout)."""
    valid = older[6][PS_VALID] != 0.0
    kept = (hist_r[2].copy(), hist_ang[2].copy(), tens_hist[1].copy())
    if valid and iterations <= 1 and older[6][PS_HIGHER] == 0.0:     # converged at once from the lower orders
        return kept + (older[3].copy(), older[4].copy(), older[5].copy(), older[6].copy())

    def cubic_better(h, x, o):
        q = 3.0 * h[0] - 3.0 * h[1] + h[2] - x
        d = h[0] - 3.0 * h[1] + 3.0 * h[2] - o
        e2 = np.max(np.abs(q), axis=1, initial=0.0)
        e3 = np.max(np.abs(q + d), axis=1, initial=0.0)
        return ((e3 < e2) & valid).astype(float)

    cubic_r = cubic_better(hist_r, rs, older[0])
    cubic_ang = cubic_better(hist_ang, angs, older[1])
    e2 = np.abs(np.maximum(2.0 * tens_hist[0] - tens_hist[1], 0.0) - tens)
    e3 = np.abs(np.maximum(3.0 * tens_hist[0] - 3.0 * tens_hist[1] + older[2], 0.0) - tens)
    quad_tens = ((e3 < e2) & valid).astype(float)
    state = np.zeros(PRED_STATE_SIZE)
    state[PS_VALID] = 1.0
    state[PS_HIGHER] = cubic_r.sum() + cubic_ang.sum() + quad_tens.sum()
    return kept + (cubic_r, cubic_ang, quad_tens, state)
