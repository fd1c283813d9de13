"""Linearised frequency-domain model of the lumped-mass tow (after Hover, Grosenbaugh & Triantafyllou 1994).

The SAME discrete model the time-domain simulator integrates (:func:`towenv.core.system.build_system`, loads
of :mod:`towenv.core.kernels`) is linearised about its steady tow (static) state, for any node tree: lines,
junctions, point bodies, rigid bodies (6 DOF), series tows (aft tow points carried by their body) and the
heave-compensator sheave.

Generalised coordinates ``q``: displacement of every free node (3 each), Euler-angle perturbation of every
rigid body (3 each), and the compensator stroke ``z`` when a passive compensator is inserted. The
prescribed ship tow point moves by ``u`` (3). Node positions are ``r(q, u)`` (aft tow points
``r_a + Λ(θ)ᵀ r_t``, the sheave ``r_ship + u + z e_z``). The equations are the virtual-work projection of the
node and body equations of the time-domain model:

    M q̈ + C q̇ + K q = −(M_u ü + C_u u̇ + K_u u)

* ``M``: node mass matrices of ``node_assembly`` (dry + added mass, point bodies) projected through
  ``∂r/∂q``, plus each rigid body's A = M_RB + M_A about its tow point,
  ``[[Λᵀ A_tt Λ, Λᵀ A_tr E], [Eᵀ A_rt Λ, Eᵀ A_rr E]]`` (E: Euler rates → body rates), plus the compensator's
  moving mass on the stroke.
* ``K = −∂Q/∂q`` by central differences of the generalised forces ``Q(q)`` of the nonlinear model at the
  steady velocity: elastic ``(EA/l0) t tᵀ``, geometric ``(T/ℓ)(I − t tᵀ)``, weight/buoyancy restoring and
  the incidence dependence of the body tables, the drag change with cable direction about the mean
  flow, the aft-tow-point lever, plus the compensator spring ``k``.
* ``C``: drag by equivalent linearisation (:mod:`towenv.linear.eqlin`) about the mean relative flow,
  harmonic (per frequency, at the computed amplitudes) or stochastic (Gaussian, at the computed
  covariances), iterated to convergence, plus the compensator damper ``b``.
* forcing: the same derivatives with respect to the ship tow-point motion ``u``.

Outputs are linear functions of ``(q, u)``: node displacements, Euler angles, segment tensions
``δT = (EA/l0) t·δ(r_up − r_lo)`` and the top reaction ``|F|`` (as the simulator's ``top_tension``).
See docs/linear.md for the formulas, the assumptions and where the model fails.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from ..core.layout import BP_AFT_TOW_POINT, BP_CB

from .. import stats as S
from ..core import kernels as K
from . import eqlin

OUTPUT_DOC = {
    "fish_heave": "z displacement of the fish tow point (m per m of top motion)",
    "fish_surge": "x displacement of the fish tow point (m/m)",
    "fish_sway": "y displacement of the fish tow point (m/m)",
    "fish_pitch": "pitch Euler angle of the fish (rad/m, nose down +)",
    "fish_roll": "roll Euler angle of the fish (rad/m)",
    "fish_yaw": "yaw Euler angle of the fish (rad/m)",
    "top_tension": "magnitude of the cable's force on the vessel (the simulator's top_tension) (N/m)",
    "top_segment_tension": "tension of the top segment (N/m)",
    "fish_tension": "tension of the segment ending at the fish (N/m)",
    "stroke": "compensator stroke (m/m; 0 when locked)",
}
BODY_OUTPUTS = ("heave", "surge", "sway", "pitch", "roll", "yaw", "tension")


class Outputs(dict):
    """Output name → complex array; an unknown name raises a KeyError listing the available ones."""

    def __missing__(self, key):
        raise KeyError(f"unknown output {key!r}; available: {sorted(self)}")


class LinearisationError(ValueError):
    """The scene cannot be linearised (slack static state, winch, rigid segments ...) or the equivalent
    linearisation did not converge. The message names the element and the reason."""


# -------------------------------------------------------------------------------------------------
# result containers
# -------------------------------------------------------------------------------------------------
@dataclass
class LinearResponse:
    """Complex responses over ``omega`` per metre of top motion (``top``: (nf, 3), rows normalised to unit length)."""
    omega: np.ndarray
    rao: dict
    top: np.ndarray
    drag: str
    compensator: dict | None
    iterations: int
    residual: float
    converged: bool
    seconds: float

    def amplitude(self, name: str) -> np.ndarray:
        return np.abs(self._get(name))

    def _get(self, name):
        if name not in self.rao:
            raise KeyError(f"unknown output {name!r}; available: {sorted(self.rao)}")
        return self.rao[name]


@dataclass
class SpectralResult:
    """Response spectra and statistics of a linearised tow in an irregular (long-crested) sea.

    ``std`` = √m0; ``significant`` = significant height 4√m0 (double amplitude, as Hover's X1/3 and the
    validation's D1/3, Q1/3); ``significant_amplitude`` = 2√m0; ``highest_1000`` = mean of the highest
    1/1000 amplitudes (Rayleigh, 3.966√m0, Hover's X_1/n); ``level_1000`` = amplitude exceeded by 1/1000
    of the amplitudes (3.717√m0). ``raos`` are per metre of wave amplitude over the wave frequencies
    ``omega``, evaluated at the encounter frequencies ``omega_e``."""
    omega: np.ndarray
    omega_e: np.ndarray
    wave_spectrum: np.ndarray
    raos: dict
    std: dict
    significant: dict
    significant_amplitude: dict
    highest_1000: dict
    level_1000: dict
    tow_point_model: str
    drag: str
    compensator: dict | None
    iterations: int
    residual: float
    converged: bool
    seconds: float


@dataclass
class CompensatorTuning:
    """Grid of a passive compensator's performance (stochastic linearisation in ``sea_state``).

    Arrays are (len(k), len(b)): fish heave significant height ``fish_heave`` (4σ, m), stroke significant
    height ``stroke`` (4σ), stroke 1/1000 exceedance amplitude ``stroke_1000`` (3.717σ) and ``feasible``
    (``stroke_1000 ≤ stroke_limit/2``: the stroke stays inside the travel but for 1 in 1000 amplitudes);
    ``locked`` holds the locked compensator's fish heave; ``best`` the feasible (k, b) with the smallest
    fish heave (None if none is feasible)."""
    k: np.ndarray
    b: np.ndarray
    fish_heave: np.ndarray
    stroke: np.ndarray
    stroke_1000: np.ndarray
    top_tension: np.ndarray
    feasible: np.ndarray
    locked: dict
    best: dict | None
    stroke_limit: float
    seconds: float
    table: list = field(default_factory=list)


# -------------------------------------------------------------------------------------------------
def _load(scene, segments):
    from ..core.simulator import load
    from ..scene import Scene
    if isinstance(scene, Scene) and segments is None:
        return scene
    sc = load(scene)
    if segments is None:
        return sc
    if isinstance(segments, bool) or not isinstance(segments, (int, np.integer)) or not 1 <= int(segments) <= 2000:
        raise ValueError(f"segments: must be an integer in [1, 2000] (segments on the longest line), got {segments!r}")
    d = sc.to_dict()
    lmax = max(float(ln["length"]) for ln in d["lines"])
    for ln in d["lines"]:
        ln["segments"] = max(1, int(round(int(segments) * float(ln["length"]) / lmax)))
    return load(d)


def _comp_param(comp, scene_comp):
    """Normalise the compensator argument to None (locked) or dict(stiffness, damping, mass)."""
    if comp is None:
        if scene_comp is None or scene_comp.mode != "passive":
            return None
        return {"stiffness": float(scene_comp.stiffness), "damping": float(scene_comp.damping),
                "mass": float(scene_comp.mass)}
    if isinstance(comp, str):
        if comp == "locked":
            return None
        raise ValueError(f"compensator: must be None, 'locked' or a dict/object with stiffness, damping, mass; "
                         f"got {comp!r}")
    out = {}
    for name, default in (("stiffness", None), ("damping", 0.0), ("mass", None)):
        v = comp.get(name, default) if isinstance(comp, dict) else getattr(comp, name, default)
        if v is None and name == "mass":
            v = float(scene_comp.mass) if scene_comp is not None else 0.0
        if v is None:
            raise ValueError(f"compensator.{name}: required (spring stiffness, N/m, >= 0)")
        v = float(v)
        if not (math.isfinite(v) and v >= 0.0):
            raise ValueError(f"compensator.{name}: must be finite and >= 0, got {v!r}")
        out[name] = v
    return out


class LinearModel:
    """Linearised frequency-domain model of a scene (statics solved once, in the constructor).

    >>> lm = LinearModel("hover_deep_tow")
    >>> r = lm.response(np.linspace(0.05, 2.0, 50), top=(0, 0, 1.0))
    >>> abs(r.rao["fish_heave"])

    ``fish`` names the body whose motions are the ``fish_*`` outputs (default: the first body of kind
    ``fish``, else the last rigid body, else the bottom node of the first line). Every body also gets
    ``<name>_heave`` … outputs. ``nphi`` (harmonic phases) and ``n_gauss`` (Gauss–Hermite points per axis)
    (16 for cable ends, ``nphi_cable``) set the equivalent-linearisation quadrature; ``tol`` the relative
    fixed-point residual at which the iterations stop, ``max_iter`` their limit (LinearisationError beyond).
    Wave orbital velocities ([sea] orbital_velocities) are not part of the linear model.
    """

    def __init__(self, scene, segments=None, fish: str | None = None, nphi: int = 32, nphi_cable: int = 16,
                 n_gauss: int = 10, tol: float = 1e-3, max_iter: int = 200):
        from ..core.simulator import Simulator
        t0 = time.perf_counter()
        self.scene = _load(scene, segments)
        sc = self.scene
        if getattr(sc, "winch", None) is not None:
            raise LinearisationError("scene.winch: the linear model has no winch (payout changes the mesh); "
                                     "remove the [winch] section")
        for name, v, lo in (("nphi", nphi, 8), ("nphi_cable", nphi_cable, 8), ("n_gauss", n_gauss, 3)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= int(v) <= 256:
                raise ValueError(f"{name}: must be an integer in [{lo}, 256], got {v!r}")
        if not (isinstance(tol, (int, float)) and 1e-12 <= tol <= 0.1):
            raise ValueError(f"tol: must be in [1e-12, 0.1], got {tol!r}")
        if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or not 1 <= max_iter <= 10000:
            raise ValueError(f"max_iter: must be an integer in [1, 10000], got {max_iter!r}")
        self.nphi = int(nphi)
        self.nphi_cable = int(nphi_cable)
        self.tol = float(tol)
        self.max_iter = int(max_iter)
        gx, gw = np.polynomial.hermite_e.hermegauss(int(n_gauss))
        self._gx, self._gw = gx, gw / gw.sum()
        sim = Simulator(sc, settle_time=0.0)
        self.sim = sim
        s = sim.system
        self.system = s
        for lm in s.lines:
            bad = [int(k) for k in lm.segments if not np.isfinite(s.ea[k])]
            if bad:
                raise LinearisationError(f"lines.{lm.name}.EA: the linear model needs a finite EA (rigid segments "
                                         "carry a tension that is not a function of the positions)")
        self.U = np.asarray(sim.path.initial_velocity(), float)
        r0 = sim.static_positions.copy()
        ang0 = sim.static_angles.copy()
        scomp = getattr(sc, "compensator", None)
        self.scene_compensator = scomp
        self.sheave = int(s.cable_top_node)
        self._setup_dofs()
        self.r0, self.ang0 = r0, ang0
        self._polish_statics()
        self._linearise()
        self._drag_elements()
        self._tree = {nb: self._tree_groups(nb) for nb in (self.n_base, self.n_base + 1)}
        self.use_tree = True          # False: dense batched solve (a cross-check)
        self.fish = self._pick_fish(fish)
        self.setup_seconds = time.perf_counter() - t0

    # ---- degrees of freedom ---------------------------------------------------------------------
    def _setup_dofs(self):
        s = self.system
        nn = s.n_nodes
        self.node_dof = -np.ones(nn, np.int64)
        k = 0
        for a in range(nn):
            if s.node_kind[a] == K.FREE:
                self.node_dof[a] = k
                k += 3
        self.ang_dof = np.arange(k, k + 3 * s.n_rigid).reshape(-1, 3) if s.n_rigid else np.zeros((0, 3), np.int64)
        k += 3 * s.n_rigid
        self.n_base = k            # without the stroke
        self.z_dof = k             # stroke, used only when a compensator is active
        self.aft = {int(s.body_aft_node[b]): b for b in range(s.n_rigid) if s.body_aft_node[b] >= 0}

    def _positions(self, q, u):
        """Node positions and Euler angles for generalised coordinates q (length n_base or n_base + 1)."""
        s = self.system
        r = self.r0.copy()
        free = self.node_dof >= 0
        idx = self.node_dof[free]
        r[free] += np.stack([q[idx], q[idx + 1], q[idx + 2]], axis=1)
        ang = self.ang0 + (q[self.ang_dof] if s.n_rigid else 0.0)
        r[s.top_node] += u
        if self.sheave != s.top_node:
            r[self.sheave] = self.r0[self.sheave] + u
        if len(q) > self.n_base:
            r[self.sheave, 2] += q[self.z_dof]
        lam = np.empty((3, 3))
        for c, b in self.aft.items():
            K.rotation_matrix(ang[b, 0], ang[b, 1], ang[b, 2], lam)
            r[c] = r[s.body_node[b]] + lam.T @ s.bp[b, BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3]
        return r, ang

    # ---- nonlinear generalised forces (steady velocities) ---------------------------------------
    def _forces(self, q, u, with_stroke=False):
        """Return (Q (n), segment tensions (S), top reaction (3)) at the steady tow velocity."""
        s = self.system
        r, ang = self._positions(q, u)
        ns, nn = s.n_segments, s.n_nodes
        v = np.tile(self.U, (nn, 1))
        tang = np.empty((ns, 3))
        stre = np.empty(ns)
        drag = np.empty((ns, 2, 3))
        bmat = np.empty((ns, 2, 3, 3))
        madd = np.empty((ns, 3, 3))
        mnode = np.empty((nn, 3, 3))
        bnode = np.empty((nn, 3, 3))
        fnode = np.empty((nn, 3))
        K.segment_loads(r, v, s.seg_lo, s.seg_up, s.l0, s.diam, s.mu, s.cn, s.ct, s.can, s.cat, s.rho, s.g,
                        s.cur_z, s.cur_v, tang, stre, drag, bmat, madd)
        K.node_assembly(r, v, s.node_kind, s.node_nseg, s.node_segs, s.node_sgn, s.l0, s.diam, s.mu, s.rho, s.g,
                        drag, bmat, madd, s.pb_mass, s.pb_vol, s.pb_cda, s.pb_ca, s.cur_z, s.cur_v, mnode, bnode,
                        fnode)
        T = s.ea * (stre / s.l0 - 1.0)
        F = fnode.copy()
        np.add.at(F, s.seg_lo, T[:, None] * tang)
        np.add.at(F, s.seg_up, -T[:, None] * tang)
        n = self.n_base + (1 if with_stroke else 0)
        Q = np.zeros(n)
        free = self.node_dof >= 0
        idx = self.node_dof[free]
        Ff = F[free]
        Q[idx] = Ff[:, 0]
        Q[idx + 1] = Ff[:, 1]
        Q[idx + 2] = Ff[:, 2]
        lam = np.empty((3, 3))
        E = np.empty((3, 3))
        fb = np.empty(3)
        mb = np.empty(3)
        bd = np.empty(1)
        cur = np.empty(3)
        w0 = np.zeros(3)
        for b in range(s.n_rigid):
            a = int(s.body_node[b])
            K.rotation_matrix(ang[b, 0], ang[b, 1], ang[b, 2], lam)
            _euler_matrix(ang[b], E)
            vb = lam @ v[a]
            zc = r[a, 2] + lam[0, 2] * s.bp[b, BP_CB] + lam[1, 2] * s.bp[b, BP_CB + 1] + lam[2, 2] * s.bp[b, BP_CB + 2]
            K.current_at(zc, s.cur_z, s.cur_v, cur)
            K.body_loads(b, lam, vb, w0, s.bp, s.btab_n, s.btab, s.rho, s.g, cur, fb, mb, bd)
            i = self.node_dof[a]
            Q[i:i + 3] += lam.T @ fb
            Q[self.ang_dof[b]] += E.T @ mb
        for c, b in self.aft.items():
            a = int(s.body_node[b])
            i = self.node_dof[a]
            Q[i:i + 3] += F[c]
            Jc = self._aft_jacobian(b, ang[b])
            Q[self.ang_dof[b]] += Jc.T @ F[c]
        if with_stroke:
            Q[self.z_dof] = F[self.sheave, 2]
        return Q, T, F[self.sheave].copy()

    def _aft_jacobian(self, b, ang):
        s = self.system
        lam = np.empty((3, 3))
        J = np.empty((3, 3))
        h = 1e-6
        rt = s.bp[b, BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3]
        for j in range(3):
            a1 = ang.copy()
            a1[j] += h
            K.rotation_matrix(a1[0], a1[1], a1[2], lam)
            p = lam.T @ rt
            a1[j] -= 2 * h
            K.rotation_matrix(a1[0], a1[1], a1[2], lam)
            J[:, j] = (p - lam.T @ rt) / (2 * h)
        return J

    def _polish_statics(self):
        """Newton iterations on Q(q) = 0 so the linearisation point is an exact equilibrium of the discrete
        dynamic model (the simulator's quasi-static march is consistent to O(segment drag) only)."""
        s = self.system
        q = np.zeros(self.n_base)
        u = np.zeros(3)
        scale = None
        for it in range(30):
            Q, T, _ = self._forces(q, u)
            if scale is None:
                scale = max(float(np.max(np.abs(T))), 1.0)
            res = float(np.max(np.abs(Q))) if len(Q) else 0.0
            if res < 1e-9 * scale:
                break
            Kq = self._fd_stiffness(q, u)[0]
            try:
                dq = np.linalg.solve(Kq, Q)
            except np.linalg.LinAlgError as exc:
                raise LinearisationError(f"statics: singular stiffness at the static state ({exc}); a free "
                                         "node or body has no restoring force") from None
            step = 1.0
            big = np.max(np.abs(dq)) if len(dq) else 0.0
            if big > 0.2 * float(np.min(s.l0)):
                step = 0.2 * float(np.min(s.l0)) / big
            q = q + step * dq
        else:
            raise LinearisationError(f"statics: the Newton polish of the static state did not converge "
                                     f"(max residual force {res:.3g} N)")
        self.static_residual = res
        r, ang = self._positions(q, u)
        self.r0 = r
        self.ang0 = ang
        _, T, F = self._forces(np.zeros(self.n_base), u)
        self.T0 = T
        self.F0_top = F
        tmax = float(np.max(T))
        for k in range(s.n_segments):
            if not T[k] > 1e-6 * tmax:
                raise LinearisationError(f"{self._seg_name(k)} is slack at the static state (T = {T[k]:.3g} N): "
                                         "the linear model needs a taut cable (snap loads are not linear)")

    def _seg_name(self, k):
        for lm in self.system.lines:
            if k in lm.segments:
                return f"segment {int(np.where(lm.segments == k)[0][0])} of line {lm.name!r}"
        return f"segment {k}"

    def _fd_stiffness(self, q, u, with_stroke=False):
        """Central differences of (Q, T, F_top) with respect to q and u."""
        n = len(q) + (1 if with_stroke else 0)
        qq = np.concatenate([q, [0.0]]) if with_stroke else q
        Kq = np.empty((n, n))
        Ku = np.empty((n, 3))
        ns = self.system.n_segments
        Tq = np.empty((ns, n))
        Tu = np.empty((ns, 3))
        Fq = np.empty((3, n))
        Fu = np.empty((3, 3))
        for j in range(n + 3):
            is_ang = j < n and j < self.n_base and j >= self.ang_dof.min(initial=n) and self.system.n_rigid > 0
            h = 1e-6 if is_ang else 1e-5
            outs = []
            for sg in (1.0, -1.0):
                q1 = qq.copy()
                u1 = u.copy()
                if j < n:
                    q1[j] += sg * h
                else:
                    u1[j - n] += sg * h
                outs.append(self._forces(q1, u1, with_stroke))
            dQ = -(outs[0][0] - outs[1][0]) / (2 * h)
            dT = (outs[0][1] - outs[1][1]) / (2 * h)
            dF = (outs[0][2] - outs[1][2]) / (2 * h)
            if j < n:
                Kq[:, j], Tq[:, j], Fq[:, j] = dQ, dT, dF
            else:
                Ku[:, j - n], Tu[:, j - n], Fu[:, j - n] = dQ, dT, dF
        return Kq, Ku, Tq, Tu, Fq, Fu

    # ---- linear matrices --------------------------------------------------------------------------
    def _linearise(self):
        s = self.system
        nb = self.n_base
        q0 = np.zeros(nb)
        u0 = np.zeros(3)
        # stiffness and forcing with the stroke DOF included (dropped when locked)
        self.Kq, self.Ku, self.Tq, self.Tu, self.Fq, self.Fu = self._fd_stiffness(q0, u0, with_stroke=True)
        # kinematic maps P = ∂r/∂q, S = ∂r/∂u (3N x n) at the static state (see _positions)
        n = nb + 1
        nn = s.n_nodes
        P = np.zeros((3 * nn, n))
        Sm = np.zeros((3 * nn, 3))
        for a in range(nn):
            d = self.node_dof[a]
            if d >= 0:
                P[3 * a:3 * a + 3, d:d + 3] = np.eye(3)
        Sm[3 * s.top_node:3 * s.top_node + 3] = np.eye(3)
        Sm[3 * self.sheave:3 * self.sheave + 3] = np.eye(3)
        P[3 * self.sheave + 2, self.z_dof] = 1.0
        for c, b in self.aft.items():
            a = int(s.body_node[b])
            P[3 * c:3 * c + 3] = P[3 * a:3 * a + 3]
            P[3 * c:3 * c + 3, self.ang_dof[b]] = self._aft_jacobian(b, self.ang0[b])
        self.P, self.S = P, Sm
        # mass: node masses (dry + added) at the static state, bodies, projected
        r = self.r0
        v = np.tile(self.U, (nn, 1))
        ns = s.n_segments
        tang = np.empty((ns, 3))
        stre = np.empty(ns)
        drag = np.empty((ns, 2, 3))
        bmat = np.empty((ns, 2, 3, 3))
        madd = np.empty((ns, 3, 3))
        mnode = np.empty((nn, 3, 3))
        bnode = np.empty((nn, 3, 3))
        fnode = np.empty((nn, 3))
        K.segment_loads(r, v, s.seg_lo, s.seg_up, s.l0, s.diam, s.mu, s.cn, s.ct, s.can, s.cat, s.rho, s.g,
                        s.cur_z, s.cur_v, tang, stre, drag, bmat, madd)
        K.node_assembly(r, v, s.node_kind, s.node_nseg, s.node_segs, s.node_sgn, s.l0, s.diam, s.mu, s.rho, s.g,
                        drag, bmat, madd, s.pb_mass, s.pb_vol, s.pb_cda, s.pb_ca, s.cur_z, s.cur_v, mnode, bnode,
                        fnode)
        self.tang0 = tang.copy()
        self.mnode = mnode.copy()
        Mall = np.zeros((3 * nn, 3 * nn))
        for a in range(nn):
            Mall[3 * a:3 * a + 3, 3 * a:3 * a + 3] = mnode[a]
        Mq = P.T @ Mall @ P
        Mu = P.T @ Mall @ Sm
        self.E0 = np.zeros((s.n_rigid, 3, 3))
        self.lam0 = np.zeros((s.n_rigid, 3, 3))
        att, atr, arr = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
        for b in range(s.n_rigid):
            lam = np.empty((3, 3))
            K.rotation_matrix(*self.ang0[b], lam)
            E = np.empty((3, 3))
            _euler_matrix(self.ang0[b], E)
            self.E0[b], self.lam0[b] = E, lam
            K.body_mass_blocks(b, s.bp, att, atr, arr)
            i = self.node_dof[int(s.body_node[b])]
            ia = np.arange(i, i + 3)
            ja = self.ang_dof[b]
            Mq[np.ix_(ia, ia)] += lam.T @ att @ lam
            Mq[np.ix_(ia, ja)] += lam.T @ atr @ E
            Mq[np.ix_(ja, ia)] += E.T @ atr.T @ lam
            Mq[np.ix_(ja, ja)] += E.T @ arr @ E
        self.Mq, self.Mu = Mq, Mu

    def _drag_elements(self):
        s = self.system
        r = self.r0
        cur = np.empty(3)
        ends_node, mean, tang, kn, kt = [], [], [], [], []
        for k in range(s.n_segments):
            for e, nd in ((0, int(s.seg_lo[k])), (1, int(s.seg_up[k]))):
                K.current_at(r[nd, 2], s.cur_z, s.cur_v, cur)
                ends_node.append(nd)
                mean.append(self.U - cur)
                tang.append(self.tang0[k])
                # the node receives half of the end's drag (segment_loads / node_assembly)
                kn.append(0.5 * 0.5 * s.rho * s.cn[k] * s.diam[k] * s.l0[k])
                kt.append(0.5 * 0.5 * s.rho * s.ct[k] * s.diam[k] * s.l0[k])
        self.c_node = np.array(ends_node, np.int64)
        self.c_mean = np.array(mean, float).reshape(-1, 3)
        self.c_tang = np.array(tang, float).reshape(-1, 3)
        self.c_kn = np.array(kn, float)
        self.c_kt = np.array(kt, float)
        pnodes = [a for a in range(s.n_nodes) if s.pb_mass[a] > 0 and s.pb_cda[a] > 0]
        self.p_node = np.array(pnodes, np.int64)
        pm = []
        for a in pnodes:
            K.current_at(r[a, 2], s.cur_z, s.cur_v, cur)
            pm.append(self.U - cur)
        self.p_mean = np.array(pm, float).reshape(-1, 3)
        self.p_kd = np.array([0.5 * s.rho * s.pb_cda[a] for a in pnodes], float)
        # per-node sparse rows of P: dofs and 3 x k block
        self.node_rows = []
        simple, other = [], []
        for a in range(s.n_nodes):
            blk = self.P[3 * a:3 * a + 3]
            cols = np.where(np.any(blk != 0.0, axis=0))[0]
            srow = self.S[3 * a:3 * a + 3]
            self.node_rows.append((cols, blk[:, cols], srow))
            if len(cols) == 3 and np.allclose(blk[:, cols], np.eye(3), rtol=0, atol=1e-8) and not np.any(srow) \
                    and cols[0] < self.n_base:
                simple.append(a)
            elif len(cols) or np.any(srow):
                other.append(a)
        self.simple_nodes = np.array(simple, np.int64)
        self.other_nodes = other
        d0 = self.node_dof[self.simple_nodes] if simple else np.zeros(0, np.int64)
        self._sI = (d0[:, None, None] + np.arange(3)[None, :, None] + np.zeros((1, 1, 3), np.int64))
        self._sJ = (d0[:, None, None] + np.zeros((1, 3, 1), np.int64) + np.arange(3)[None, None, :])

    def _tree_groups(self, n):
        """Groups of coordinates for the block-tree solve (None if the coupling is not a tree)."""
        s = self.system
        groups = []
        body_of_node = {int(s.body_node[b]): b for b in range(s.n_rigid)}
        for a in range(s.n_nodes):
            d = self.node_dof[a]
            if d < 0:
                continue
            g = [d, d + 1, d + 2]
            if a in body_of_node:
                g += list(self.ang_dof[body_of_node[a]])
            groups.append(g)
        if n > self.n_base:
            groups.append([self.z_dof])
        gid = -np.ones(n, np.int64)
        for k, g in enumerate(groups):
            gid[g] = k
        if np.any(gid < 0):
            return None
        pat = (np.abs(self.Kq[:n, :n]) + np.abs(self.Mq[:n, :n])) > 0
        ng = len(groups)
        adj = np.zeros((ng, ng), bool)
        ii, jj = np.nonzero(pat)
        adj[gid[ii], gid[jj]] = True
        np.fill_diagonal(adj, False)
        if not np.array_equal(adj, adj.T) or adj.sum() // 2 != ng - 1:
            return None
        parent = -np.ones(ng, np.int64)
        seen = np.zeros(ng, bool)
        bfs = [0]
        seen[0] = True
        for g in bfs:
            for h in np.nonzero(adj[g])[0]:
                if not seen[h]:
                    seen[h] = True
                    parent[h] = g
                    bfs.append(int(h))
        if not seen.all():
            return None
        smax = max(len(g) for g in groups)
        gd = np.zeros((ng, smax), np.int64)
        for k, g in enumerate(groups):
            gd[k, :len(g)] = g
        return (gd, np.array([len(g) for g in groups], np.int64), parent, np.array(bfs[::-1], np.int64))

    def _pick_fish(self, fish):
        s = self.system
        if fish is not None:
            try:
                return s.body(fish)
            except KeyError as exc:
                raise ValueError(f"fish: {exc.args[0]}") from None
        fishes = [b for b in s.bodies if b.kind == "fish"]
        if fishes:
            return fishes[0]
        rigid = [b for b in s.bodies if b.rigid_index >= 0]
        if rigid:
            return rigid[-1]
        return s.bodies[-1] if s.bodies else None

    # ---- frequency-domain solution ----------------------------------------------------------------
    def _system_for(self, comp):
        nb = self.n_base
        if comp is None:
            sel = np.arange(nb)
        else:
            sel = np.arange(nb + 1)
        Kq = self.Kq[np.ix_(sel, sel)].copy()
        Ku = self.Ku[sel].copy()
        Mq = self.Mq[np.ix_(sel, sel)].copy()
        Mu = self.Mu[sel].copy()
        Cadd = np.zeros((len(sel), len(sel)))
        if comp is not None:
            z = nb
            Kq[z, z] += comp["stiffness"]
            Cadd[z, z] += comp["damping"]
            Mq[z, z] += comp["mass"]
            Mu[z, 2] += comp["mass"]
        return sel, Kq, Ku, Mq, Mu, Cadd

    def _maps(self, sel):
        key = len(sel)
        if getattr(self, "_map_cache", (None,))[0] != key:
            self._map_cache = (key, np.ascontiguousarray(self.P[:, sel].T).astype(complex),
                               np.ascontiguousarray(self.S.T).astype(complex))
        return self._map_cache[1], self._map_cache[2]

    def _node_velocity(self, X, U, omega, sel):
        """Complex node velocity amplitudes (nf, N, 3) and body (velocity, Euler-rate) amplitudes."""
        PT, ST = self._maps(sel)
        x_all = X @ PT + U @ ST                                # (nf, 3N)
        return (1j * omega[:, None] * x_all).reshape(len(omega), -1, 3), x_all

    def _damping(self, mode, Vn, X, omega, sel, Sig=None):
        """Assemble C (nf or 1, n, n) and C_u from the element equivalent damping."""
        s = self.system
        n = len(sel)
        nf = Vn.shape[0] if mode == 0 else 1
        ne = len(self.c_node)
        Cel = np.zeros((nf, ne, 3, 3))
        if mode == 0:
            Vc = np.ascontiguousarray(Vn[:, self.c_node, :])
            eqlin.cable_equivalent(0, self.c_mean, self.c_tang, self.c_kn, self.c_kt, Vc, np.zeros((1, 3, 3)),
                                   self.nphi_cable, self._gx, self._gw, Cel)
        else:
            eqlin.cable_equivalent(1, self.c_mean, self.c_tang, self.c_kn, self.c_kt,
                                   np.zeros((1, 1, 3), complex), np.ascontiguousarray(Sig["cable"]), self.nphi,
                                   self._gx, self._gw, Cel)
        Cn = np.zeros((nf, s.n_nodes, 3, 3))
        np.add.at(Cn, (slice(None), self.c_node), Cel)
        if len(self.p_node):
            Cp = np.zeros((nf, len(self.p_node), 3, 3))
            if mode == 0:
                eqlin.point_equivalent(0, self.p_mean, self.p_kd, np.ascontiguousarray(Vn[:, self.p_node, :]),
                                       np.zeros((1, 3, 3)), self.nphi, self._gx, self._gw, Cp)
            else:
                eqlin.point_equivalent(1, self.p_mean, self.p_kd, np.zeros((1, 1, 3), complex),
                                       np.ascontiguousarray(Sig["point"]), self.nphi, self._gx, self._gw, Cp)
            np.add.at(Cn, (slice(None), self.p_node), Cp)
        C = np.zeros((nf, n, n))
        Cu = np.zeros((nf, n, 3))
        pos = -np.ones(self.n_base + 1, np.int64)
        pos[sel] = np.arange(n)
        if len(self.simple_nodes):
            C[:, self._sI, self._sJ] += Cn[:, self.simple_nodes]
        for a in self.other_nodes:
            cols, blk, srow = self.node_rows[a]
            cols_ok = pos[cols] >= 0
            cl = pos[cols[cols_ok]]
            bk = blk[:, cols_ok]
            if len(cl) == 0 or not np.any(Cn[:, a]):
                continue
            Ca = Cn[:, a]
            C[:, cl[:, None], cl[None, :]] += np.einsum("ik,fij,jl->fkl", bk, Ca, bk)
            Cu[:, cl, :] += np.einsum("ik,fij,jl->fkl", bk, Ca, srow)
        # rigid bodies
        for b in range(s.n_rigid):
            a = int(s.body_node[b])
            i = self.node_dof[a]
            dofs = np.concatenate([np.arange(i, i + 3), self.ang_dof[b]])
            Cb = np.zeros((nf, 6, 6))
            if mode == 0:
                Vb = np.concatenate([Vn[:, a, :], 1j * omega[:, None] * X[:, pos[self.ang_dof[b]]]], axis=1)
                eqlin.body_equivalent(0, b, self.ang0[b], self.E0[b], self.U, self.r0[a, 2], s.bp, s.btab_n, s.btab,
                                      s.rho, s.g, s.cur_z, s.cur_v, np.ascontiguousarray(Vb), np.zeros((6, 6)),
                                      self.nphi, self._gx, self._gw, Cb)
            else:
                eqlin.body_equivalent(1, b, self.ang0[b], self.E0[b], self.U, self.r0[a, 2], s.bp, s.btab_n, s.btab,
                                      s.rho, s.g, s.cur_z, s.cur_v, np.zeros((1, 6), complex),
                                      np.ascontiguousarray(Sig["body"][b]), self.nphi, self._gx, self._gw, Cb)
            d = pos[dofs]
            C[:, d[:, None], d[None, :]] += Cb
        return C, Cu, Cn

    def _solve(self, omega, Utop, Kq, Ku, Mq, Mu, C, Cu, Cadd):
        w = omega[:, None, None]
        B = Ku[None] - w ** 2 * Mu[None] + 1j * w * Cu
        rhs = -np.einsum("fij,fj->fi", B, Utop)
        tree = self._tree.get(len(Kq)) if self.use_tree else None
        if tree is not None:
            X = np.empty(rhs.shape, complex)
            ok = eqlin.tree_solve(omega, Kq, Mq, np.ascontiguousarray(C), Cadd, rhs, *tree, X)
            if not ok:
                raise LinearisationError("the linear system is singular at some frequency (an undamped mode "
                                         "exactly at an excitation frequency)")
        else:
            A = Kq[None] - w ** 2 * Mq[None] + 1j * w * (C + Cadd[None])
            try:
                X = np.ascontiguousarray(np.linalg.solve(A, rhs[..., None])[..., 0])
            except np.linalg.LinAlgError:
                raise LinearisationError("the linear system is singular at some frequency (an undamped mode "
                                         "exactly at an excitation frequency)") from None
        if not np.all(np.isfinite(X)):
            raise LinearisationError("non-finite response of the linear system")
        return X

    def _iterate_harmonic(self, omega, Utop, comp):
        sel, Kq, Ku, Mq, Mu, Cadd = self._system_for(comp)
        nf, n = len(omega), len(sel)
        # initial guess: every node follows the tow point (quasi-static rigid motion), bodies do not rotate
        X = np.zeros((nf, n), complex)
        Vn = (1j * omega[:, None, None]) * Utop[:, None, :] * np.ones((1, self.system.n_nodes, 1))
        C, Cu, _ = self._damping(0, Vn, X, omega, sel)
        X = self._solve(omega, Utop, Kq, Ku, Mq, Mu, C, Cu, Cadd)
        X, it, rel_f, CN = self._anderson(omega, Utop, X, sel, Kq, Ku, Mq, Mu, Cadd)
        rel = float(np.max(rel_f))
        return sel, X, it, rel, CN

    def _anderson(self, omega, Utop, X, sel, Kq, Ku, Mq, Mu, Cadd, depth: int = 4, beta: float = 0.5):
        """Solve the harmonic fixed point X = G(X) (G: response with the damping C_eq(X)) per frequency.

        Anderson acceleration (type II, depth ``depth``, mixing ``beta``, real coefficients on the real and
        imaginary parts). A frequency whose residual stops decreasing for 3 iterations (or doubles) switches
        to damped iteration on the damping itself, C ← (1 − α) C + α C_eq(X) with α halved whenever the
        change grows: the Anderson step may cycle where the map is non-smooth (a body whose incidence flips
        through ±90°, e.g. the heaving fish at U = 0). Converged when |G(X) − X| ≤ tol |G(X)|."""
        nf, n = X.shape
        m2 = 2 * n
        active = np.ones(nf, bool)
        rel_f = np.full(nf, np.inf)
        best = np.full(nf, np.inf)
        since = np.zeros(nf, np.int64)
        plain = np.zeros(nf, bool)
        alpha = np.full(nf, 0.5)
        last = np.full(nf, np.inf)
        hF = np.zeros((nf, depth + 1, m2))       # ring buffers of residuals and iterates (real form)
        hX = np.zeros((nf, depth + 1, m2))
        cnt = np.zeros(nf, np.int64)
        CN = Cst = Cust = None
        it = 0
        for it in range(1, self.max_iter + 1):
            ia = np.where(active)[0]
            Xa = X[ia]
            Vn, _ = self._node_velocity(Xa, Utop[ia], omega[ia], sel)
            C, Cu, CNa = self._damping(0, Vn, Xa, omega[ia], sel)
            if CN is None:
                CN = np.zeros((nf,) + CNa.shape[1:])
                Cst = np.zeros((nf,) + C.shape[1:])
                Cust = np.zeros((nf,) + Cu.shape[1:])
            pl = plain[ia]
            if pl.any():
                fp = ia[pl]
                al = alpha[fp][:, None, None]
                Cst[fp] = (1 - al) * Cst[fp] + al * C[pl]
                Cust[fp] = (1 - al) * Cust[fp] + al * Cu[pl]
                C[pl], Cu[pl] = Cst[fp], Cust[fp]
            CN[ia] = CNa
            G = self._solve(omega[ia], Utop[ia], Kq, Ku, Mq, Mu, C, Cu, Cadd)
            F = G - Xa
            rel = np.linalg.norm(F, axis=1) / np.maximum(np.linalg.norm(G, axis=1), 1e-300)
            rel_f[ia] = rel
            done = rel < self.tol
            # plain-mode bookkeeping
            grow = pl & (rel > last[ia])
            alpha[ia[grow]] = np.maximum(0.5 * alpha[ia[grow]], 0.02)
            last[ia[pl]] = rel[pl]
            # Anderson-mode stall detection
            am = ~pl & ~done
            better = rel < best[ia]
            since[ia[am & better]] = 0
            since[ia[am & ~better]] += 1
            best[ia] = np.minimum(best[ia], rel)
            stall = am & ((since[ia] >= 3) | (rel > 2.0 * best[ia]))
            if stall.any():
                fs = ia[stall]
                plain[fs] = True
                Cst[fs], Cust[fs] = C[stall], Cu[stall]
            am = am & ~stall
            Xn = G.copy()                            # converged, plain and first Anderson steps: X ← G
            if am.any():
                fa = ia[am]
                fr = np.concatenate([F[am].real, F[am].imag], axis=1)
                xr0 = np.concatenate([Xa[am].real, Xa[am].imag], axis=1)
                slot = cnt[fa] % (depth + 1)
                hF[fa, slot] = fr
                hX[fa, slot] = xr0
                cnt[fa] += 1
                xr = xr0 + beta * fr
                h = np.minimum(cnt[fa], depth + 1)
                use = h >= 2
                if use.any():
                    fu = fa[use]
                    # order the ring buffer oldest → newest, differences of consecutive entries
                    k = np.arange(depth + 1)
                    start = np.where(cnt[fu] > depth + 1, cnt[fu] % (depth + 1), 0)
                    idx = (start[:, None] + k[None, :]) % (depth + 1)
                    Fo = np.take_along_axis(hF[fu], idx[:, :, None], axis=1)
                    Xo = np.take_along_axis(hX[fu], idx[:, :, None], axis=1)
                    dF = np.diff(Fo, axis=1)                      # (m, depth, 2n)
                    dX = np.diff(Xo, axis=1)
                    valid = (k[None, 1:] < h[use][:, None])     # difference j valid if j + 1 < h
                    dF = dF * valid[..., None]
                    dX = dX * valid[..., None]
                    A = np.einsum("mij,mkj->mik", dF, dF)
                    tr = np.trace(A, axis1=1, axis2=2)
                    A = A + (1e-12 * tr[:, None, None] + 1e-300) * np.eye(depth)[None] \
                        + np.eye(depth)[None] * (~valid)[:, :, None] * (1.0 + tr[:, None, None])
                    rhs = np.einsum("mij,mj->mi", dF, fr[use])
                    gam = np.linalg.solve(A, rhs[..., None])[..., 0]
                    xr[use] = xr[use] - np.einsum("mij,mi->mj", dX + beta * dF, gam)
                Xn[am] = xr[:, :n] + 1j * xr[:, n:]
            X[ia] = Xn
            active[ia[done]] = False
            if not active.any():
                break
        return X, it, rel_f, CN

    def _outputs(self, X, U, omega, sel, CN):
        """Complex output amplitudes for responses X (nf, n) to top motions U (nf, 3)."""
        s = self.system
        n = len(sel)
        x_all = (X @ self.P[:, sel].T + U @ self.S.T).reshape(len(omega), -1, 3)
        T = X @ self.Tq[:, sel].T + U @ self.Tu.T
        out = {}
        # top reaction: the simulator's node_reaction at the cable's top node (tension + own loads − inertia)
        ct = self.sheave
        Cn = np.broadcast_to(CN, (len(omega),) + CN.shape[1:])
        xt = x_all[:, ct, :]
        dF = X @ self.Fq[:, sel].T + U @ self.Fu.T
        dF = dF - np.einsum("fij,fj->fi", Cn[:, ct], 1j * omega[:, None] * xt) \
            + (omega ** 2)[:, None] * (xt @ self.mnode[ct].T)
        F0 = self.F0_top
        out["top_tension"] = dF @ F0 / max(np.linalg.norm(F0), 1e-300)
        top_seg = int(s.node_segs[ct, 0])
        out["top_segment_tension"] = T[:, top_seg]
        out["stroke"] = X[:, n - 1] if n > self.n_base else np.zeros(len(omega), complex)
        for bm in s.bodies:
            a = bm.node
            out[f"{bm.name}_surge"] = x_all[:, a, 0]
            out[f"{bm.name}_sway"] = x_all[:, a, 1]
            out[f"{bm.name}_heave"] = x_all[:, a, 2]
            if bm.rigid_index >= 0:
                ad = self.ang_dof[bm.rigid_index]
                out[f"{bm.name}_roll"] = X[:, ad[0]]
                out[f"{bm.name}_pitch"] = X[:, ad[1]]
                out[f"{bm.name}_yaw"] = X[:, ad[2]]
            seg = int(s.node_up_seg[a])
            if seg >= 0:
                out[f"{bm.name}_tension"] = T[:, seg]
        f = self.fish
        if f is not None:
            for k in BODY_OUTPUTS:
                if f"{f.name}_{k}" in out:
                    out[f"fish_{k}"] = out[f"{f.name}_{k}"]
        else:
            bottom = int(s.lines[0].nodes[-1])
            out["fish_surge"], out["fish_sway"], out["fish_heave"] = (x_all[:, bottom, i] for i in range(3))
            out["fish_tension"] = T[:, int(s.lines[0].segments[-1])]
        out["_T"] = T
        return out

    # ---- public API -------------------------------------------------------------------------------------
    def response(self, omega, top=(0.0, 0.0, 1.0), drag: str = "harmonic", compensator=None) -> LinearResponse:
        """Complex RAOs over ``omega`` (rad/s) for a tow-point sinusoid of complex amplitude ``top``
        (surge, sway, heave in m, global axes; one row per frequency, or one for all); RAOs are per metre
        of |top| at each frequency (the harmonic linearisation uses the actual amplitude).

        ``drag``: ``"harmonic"`` (describing function at the computed amplitude of ``top``, per frequency;
        the RAO then depends on |top|) or ``"tangent"`` (drag linearised about the mean flow only: no
        damping from the oscillation, zero drag damping at U = 0). The stochastic linearisation needs a sea
        state: :meth:`spectral`. ``compensator``: None (the scene's: its passive k, b, mass, else locked),
        ``"locked"``, or a dict/object with ``stiffness`` (N/m), ``damping`` (N s/m, default 0) and ``mass``
        (kg, default the scene compensator's, else 0)."""
        t0 = time.perf_counter()
        omega = _check_omega(omega)
        top = np.asarray(top, complex)
        if top.shape == (3,):
            top = np.tile(top, (len(omega), 1))
        if top.shape != (len(omega), 3) or not np.all(np.isfinite(top)):
            raise ValueError(f"top: must be 3 finite (complex) amplitudes (surge, sway, heave) in m, or one such "
                             f"row per frequency ({len(omega)}, 3); got shape {top.shape}")
        amp = np.linalg.norm(top, axis=1)
        if np.any(amp == 0.0):
            raise ValueError("top: the tow-point amplitude must not be zero at any frequency")
        comp = _comp_param(compensator, self.scene_compensator)
        Utop = np.ascontiguousarray(top)
        if drag == "harmonic":
            # frequencies in chunks so the per-frequency damping matrices stay below ~32 MB
            n = self.n_base + (0 if comp is None else 1)
            chunk = max(1, int(4e6 // (n * n)))
            parts = [self._iterate_harmonic(omega[i:i + chunk], Utop[i:i + chunk], comp)
                     for i in range(0, len(omega), chunk)]
            sel = parts[0][0]
            X = np.concatenate([p_[1] for p_ in parts])
            it = max(p_[2] for p_ in parts)
            rel = max(p_[3] for p_ in parts)
            CN = np.concatenate([p_[4] for p_ in parts])
        elif drag == "tangent":
            sel, Kq, Ku, Mq, Mu, Cadd = self._system_for(comp)
            X0 = np.zeros((len(omega), len(sel)), complex)
            Vn = np.zeros((len(omega), self.system.n_nodes, 3), complex)
            C, Cu, CN = self._damping(0, Vn, X0, omega, sel)
            X = self._solve(omega, Utop, Kq, Ku, Mq, Mu, C, Cu, Cadd)
            it, rel = 1, 0.0
        elif drag == "stochastic":
            raise ValueError("drag='stochastic' needs a sea state: use LinearModel.spectral(sea_state, ...)")
        else:
            raise ValueError(f"drag: must be 'harmonic', 'stochastic' (spectral) or 'tangent', got {drag!r}")
        converged = rel < self.tol
        if not converged:
            raise LinearisationError(f"harmonic equivalent linearisation did not converge in {self.max_iter} "
                                     f"iterations (relative change {rel:.3g} > {self.tol:g})")
        out = self._outputs(X, Utop, omega, sel, CN)
        out.pop("_T")
        rao = Outputs({k: v / amp for k, v in out.items()})
        return LinearResponse(omega=omega, rao=rao, top=top / amp[:, None], drag=drag, compensator=comp, iterations=it,
                              residual=rel, converged=converged, seconds=time.perf_counter() - t0)

    def tow_point_rao(self, omega, sea_state, tow_point="auto"):
        """Tow-point motion per metre of wave amplitude (global axes, (nf, 3) complex) and a description.

        ``tow_point``: ``"auto"`` (the scene's vessel model / RAO table if it has one, else
        ``"wave_heave"``), ``"vessel"`` (require the scene's vessel model), ``"wave_heave"`` (the tow point
        heaves with the wave elevation at the ship, RAO (0, 0, 1)) or a callable ``rao(omega) -> (nf, 3)``."""
        from .. import vessel as V
        omega = np.asarray(omega, float)
        if callable(tow_point):
            H = np.asarray(tow_point(omega), complex).reshape(len(omega), 3)
            return H, "user tow-point RAO"
        if tow_point not in ("auto", "vessel", "wave_heave"):
            raise ValueError(f"tow_point: must be 'auto', 'vessel', 'wave_heave' or a callable, got {tow_point!r}")
        vessel = getattr(self.scene, "vessel", None)
        src = None
        if tow_point != "wave_heave" and vessel is not None:
            if getattr(vessel, "rao_file", None) is not None:
                p = vessel.rao_file
                base = getattr(self.scene, "source_dir", None)
                from pathlib import Path
                cand = [Path(p)] + ([Path(base) / p] if base else []) + \
                    [Path(__file__).resolve().parent.parent / "scenes" / "data" / p]
                path = next((c for c in cand if c.exists()), Path(p))
                src = V.RAOTable.from_csv(path)
            elif getattr(vessel, "model", None) is not None:
                src = V.ClosedFormRAO(vessel.model)
        if src is None:
            if tow_point == "vessel":
                raise ValueError("tow_point='vessel': the scene has no vessel model (vessel.model or vessel.rao_file)")
            return np.tile(np.array([0.0, 0.0, 1.0], complex), (len(omega), 1)), \
                "tow point heaves with the wave elevation (RAO (0, 0, 1)); the scene has no vessel RAO"
        lever = vessel.lever_arm if vessel.lever_arm is not None else getattr(src, "default_lever_arm", (0, 0, 0))
        speed = float(np.linalg.norm(self.U[:2]))
        H = np.asarray(src(omega, sea_state.heading_rad, speed), complex) @ V.lever_arm_matrix(lever).T
        psi = math.radians(float(getattr(vessel, "heading_deg", 0.0) or 0.0))
        c, s_ = math.cos(psi), math.sin(psi)
        Hg = H.copy()
        Hg[:, 0] = c * H[:, 0] - s_ * H[:, 1]
        Hg[:, 1] = s_ * H[:, 0] + c * H[:, 1]
        return Hg, f"vessel RAO ({type(src).__name__}) at the tow point, lever arm {tuple(float(x) for x in lever)}"

    def spectral(self, sea_state, compensator=None, drag: str = "stochastic", tow_point="auto", n_omega: int = 60,
                 omega_range=None) -> SpectralResult:
        """Response statistics in a long-crested irregular sea (``towenv.sea.SeaState``, mean heading).

        The tow point moves by the vessel RAO (see :meth:`tow_point_rao`) at the encounter frequency
        ``ω_e = |ω − ω² U cos β / g|``; response variances ``m0 = Σ |H(ω)|² S(ω) Δω``. ``drag``:
        ``"stochastic"`` (Gaussian equivalent linearisation, iterated on the response covariances) or
        ``"tangent"``. Short-crested spreading is ignored (the mean direction is used)."""
        from ..sea import SeaState
        t0 = time.perf_counter()
        if not isinstance(sea_state, SeaState):
            raise ValueError(f"sea_state: must be a towenv.sea.SeaState, got {type(sea_state).__name__}")
        if drag not in ("stochastic", "tangent"):
            raise ValueError(f"drag: must be 'stochastic' or 'tangent' for spectral(), got {drag!r}")
        if not (isinstance(n_omega, (int, np.integer)) and 10 <= n_omega <= 2000):
            raise ValueError(f"n_omega: must be an integer in [10, 2000], got {n_omega!r}")
        comp = _comp_param(compensator, self.scene_compensator)
        wp = sea_state.omega_p
        lo, hi = omega_range if omega_range is not None else (0.3 * wp, 4.0 * wp)
        if not (0 < lo < hi):
            raise ValueError(f"omega_range: must be 0 < lo < hi (rad/s), got {omega_range!r}")
        w = np.linspace(lo, hi, int(n_omega))
        dw = np.full_like(w, (hi - lo) / (len(w) - 1))
        dw[0] = dw[-1] = 0.5 * dw[0]
        Sw = sea_state.density(w)
        H, desc = self.tow_point_rao(w, sea_state, tow_point)
        speed = float(np.linalg.norm(self.U[:2]))
        we = np.abs(w - w * w / self.system.g * speed * math.cos(sea_state.heading_rad))
        if np.any(we < 1e-3):
            raise LinearisationError("spectral: an encounter frequency is (close to) zero (following sea at the "
                                     "wave speed); narrow omega_range")
        weight = Sw * dw                                      # variance per unit |H|^2
        sel, Kq, Ku, Mq, Mu, Cadd = self._system_for(comp)
        nf, n = len(w), len(sel)
        s = self.system
        it, rel = 0, 0.0
        Xold = None
        # initial covariances: every node follows the tow point
        Vn = (1j * we[:, None, None]) * H[:, None, :] * np.ones((1, s.n_nodes, 1))
        X = np.zeros((nf, n), complex)
        Sig = self._covariances(Vn, X, we, weight, sel)
        mode = 1
        if drag == "tangent":
            Sig = {k: np.zeros_like(v) for k, v in Sig.items()}
        C, Cu, CN = self._damping(mode, Vn, X, we, sel, Sig)
        # fixed point on the covariances: C ← (1 − α) C + α C_eq(Σ(X(C))), α = ½ halved whenever the change grows
        alpha, alpha_used, last = 0.5, 0.5, np.inf
        for it in range(1, self.max_iter + 1):
            X = self._solve(we, H, Kq, Ku, Mq, Mu, C, np.broadcast_to(Cu, (nf, n, 3)),
                            Cadd)
            if drag == "tangent":
                rel = 0.0
                break
            Vn, _ = self._node_velocity(X, H, we, sel)
            Sig = self._covariances(Vn, X, we, weight, sel)
            Cn, Cun, CNn = self._damping(mode, Vn, X, we, sel, Sig)
            if Xold is not None:
                # change per unit relaxation ≈ the fixed-point residual |X(C_eq(X)) − X|
                chg = float(np.sqrt(np.sum(np.abs(X - Xold) ** 2 * weight[:, None]) /
                                    max(np.sum(np.abs(X) ** 2 * weight[:, None]), 1e-300)))
                if chg > last:
                    alpha = max(0.5 * alpha, 0.02)
                last = chg
                rel = chg / alpha_used
                if rel < self.tol:
                    break
            Xold = X
            alpha_used = alpha
            C = (1 - alpha) * C + alpha * Cn
            Cu = (1 - alpha) * Cu + alpha * Cun
            CN = (1 - alpha) * CN + alpha * CNn
        converged = rel < self.tol
        if not converged:
            raise LinearisationError(f"stochastic equivalent linearisation did not converge in {self.max_iter} "
                                     f"iterations (relative change {rel:.3g} > {self.tol:g})")
        out = self._outputs(X, H, we, sel, CN)
        out.pop("_T")
        std, sig, siga, h1000, l1000 = {}, {}, {}, {}, {}
        for k, v in out.items():
            m0 = float(np.sum(np.abs(v) ** 2 * weight))
            std[k] = math.sqrt(m0)
            sig[k] = S.significant_height(m0=m0)
            siga[k] = S.significant_amplitude(m0=m0)
            h1000[k] = S.rayleigh_mean_of_highest(1 / 1000, m0)
            l1000[k] = S.rayleigh_exceedance_level(1 / 1000, m0)
        for k in ("top_surge", "top_sway", "top_heave"):
            i = ("top_surge", "top_sway", "top_heave").index(k)
            out[k] = H[:, i]
            m0 = float(np.sum(np.abs(H[:, i]) ** 2 * weight))
            std[k], sig[k], siga[k] = math.sqrt(m0), S.significant_height(m0=m0), S.significant_amplitude(m0=m0)
            h1000[k], l1000[k] = S.rayleigh_mean_of_highest(1 / 1000, m0), S.rayleigh_exceedance_level(1 / 1000, m0)
        return SpectralResult(omega=w, omega_e=we, wave_spectrum=Sw, raos=Outputs(out), std=Outputs(std),
                              significant=Outputs(sig), significant_amplitude=Outputs(siga),
                              highest_1000=Outputs(h1000), level_1000=Outputs(l1000),
                              tow_point_model=desc, drag=drag, compensator=comp, iterations=it, residual=rel,
                              converged=converged, seconds=time.perf_counter() - t0)

    def _covariances(self, Vn, X, we, weight, sel):
        s = self.system
        pos = -np.ones(self.n_base + 1, np.int64)
        pos[sel] = np.arange(len(sel))
        Vc = Vn[:, self.c_node, :]
        cab = np.einsum("f,fei,fej->eij", weight, Vc, Vc.conj()).real
        pnt = np.einsum("f,fei,fej->eij", weight, Vn[:, self.p_node, :], Vn[:, self.p_node, :].conj()).real \
            if len(self.p_node) else np.zeros((0, 3, 3))
        body = []
        for b in range(s.n_rigid):
            a = int(s.body_node[b])
            Vb = np.concatenate([Vn[:, a, :], 1j * we[:, None] * X[:, pos[self.ang_dof[b]]]], axis=1)
            body.append(np.einsum("f,fi,fj->ij", weight, Vb, Vb.conj()).real)
        # a one-sided spectrum of amplitude |H| per unit wave amplitude: variance = Σ |H|^2 S Δω
        return {"cable": cab, "point": pnt, "body": body}

    def tune_compensator(self, sea_state, k_grid, b_grid, stroke_limit, mass=None, tow_point="auto",
                         n_omega: int = 60) -> CompensatorTuning:
        """Passive compensator over a (k, b) grid in ``sea_state`` (stochastic linearisation): fish heave
        and stroke significant heights, the 1/1000 stroke amplitude and feasibility against the travel
        ``stroke_limit`` (m, full travel; feasible if the 1/1000 exceedance amplitude ≤ stroke_limit/2)."""
        t0 = time.perf_counter()
        k_grid = np.atleast_1d(np.asarray(k_grid, float))
        b_grid = np.atleast_1d(np.asarray(b_grid, float))
        for name, g in (("k_grid", k_grid), ("b_grid", b_grid)):
            if g.ndim != 1 or len(g) == 0 or not np.all(np.isfinite(g)) or np.any(g < 0):
                raise ValueError(f"{name}: must be a non-empty 1-D array of finite values >= 0")
        if not (math.isfinite(float(stroke_limit)) and float(stroke_limit) > 0):
            raise ValueError(f"stroke_limit: must be > 0 (full travel, m), got {stroke_limit!r}")
        m = mass if mass is not None else (float(self.scene_compensator.mass) if self.scene_compensator else 0.0)
        locked = self.spectral(sea_state, "locked", tow_point=tow_point, n_omega=n_omega)
        shape = (len(k_grid), len(b_grid))
        fh, st, st1000, tt = (np.full(shape, np.nan) for _ in range(4))
        rows = []
        for i, k in enumerate(k_grid):
            for j, b in enumerate(b_grid):
                try:
                    r = self.spectral(sea_state, {"stiffness": k, "damping": b, "mass": m}, tow_point=tow_point,
                                      n_omega=n_omega)
                except LinearisationError as exc:
                    rows.append((k, b, None, None, None, False, str(exc)))
                    continue
                fh[i, j] = r.significant["fish_heave"]
                st[i, j] = r.significant["stroke"]
                st1000[i, j] = r.level_1000["stroke"]
                tt[i, j] = r.highest_1000["top_tension"]
                rows.append((k, b, fh[i, j], st[i, j], st1000[i, j], bool(st1000[i, j] <= 0.5 * stroke_limit), ""))
        feas = st1000 <= 0.5 * float(stroke_limit)
        best = None
        if np.any(feas):
            cand = np.where(feas, fh, np.inf)
            i, j = np.unravel_index(int(np.argmin(cand)), shape)
            best = {"k": float(k_grid[i]), "b": float(b_grid[j]), "fish_heave": float(fh[i, j]),
                    "stroke": float(st[i, j]), "stroke_1000": float(st1000[i, j]),
                    "reduction": 1.0 - float(fh[i, j]) / locked.significant["fish_heave"]}
        return CompensatorTuning(k=k_grid, b=b_grid, fish_heave=fh, stroke=st, stroke_1000=st1000, top_tension=tt,
                                 feasible=feas, locked={"fish_heave": locked.significant["fish_heave"],
                                                        "top_tension_1000": locked.highest_1000["top_tension"],
                                                        "deck_heave": locked.significant["top_heave"]},
                                 best=best, stroke_limit=float(stroke_limit), seconds=time.perf_counter() - t0,
                                 table=rows)

    def natural_frequencies(self, compensator=None):
        """Undamped natural frequencies (rad/s, ascending) of the linearised model."""
        from scipy.linalg import eig
        comp = _comp_param(compensator, self.scene_compensator)
        sel, Kq, Ku, Mq, Mu, Cadd = self._system_for(comp)
        w2 = eig(Kq, Mq, right=False)
        w2 = np.sort(w2.real[np.isfinite(w2)])
        return np.sqrt(np.clip(w2, 0.0, None))

    def damped_modes(self, compensator=None):
        """Eigenvalues of the linearised free motion about the static state, with the drag linearised about
        the mean flow (the tangent damping ``−∂f/∂v`` at zero oscillation amplitude): ``λ = σ + iω`` (1/s),
        sorted by decreasing growth rate σ, and for each mode the fraction of its displacement energy in the
        lateral plane (node sway, body roll and yaw). ``σ > 0`` is an unstable mode: it grows from any
        perturbation, round-off included (tests/unit/test_linear.py compares σ with the nonlinear simulator's
        growth rate)."""
        comp = _comp_param(compensator, self.scene_compensator)
        sel, Kq, Ku, Mq, Mu, Cadd = self._system_for(comp)
        n = len(sel)
        omega = np.array([1e-6])
        C, _, _ = self._damping(0, np.zeros((1, self.system.n_nodes, 3), complex), np.zeros((1, n), complex),
                                omega, sel)
        Minv = np.linalg.inv(Mq)
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -Minv @ Kq
        A[n:, n:] = -Minv @ (C[0].real + Cadd)
        lam, vec = np.linalg.eig(A)
        lateral = np.zeros(n, bool)
        pos = -np.ones(self.n_base + 1, np.int64)
        pos[sel] = np.arange(n)
        for d in self.node_dof[self.node_dof >= 0]:
            lateral[pos[d + 1]] = True
        for b in range(len(self.ang_dof)):
            lateral[pos[self.ang_dof[b][0]]] = True
            lateral[pos[self.ang_dof[b][2]]] = True
        v = np.abs(vec[:n]) ** 2
        frac = v[lateral].sum(axis=0) / np.maximum(v.sum(axis=0), 1e-300)
        order = np.argsort(-lam.real, kind="stable")
        return lam[order], frac[order]


def _euler_matrix(ang, E):
    """E with ω = E θ̇ (``euler_rates_to_omega``, linear in the rates)."""
    e = np.zeros(3)
    w = np.empty(3)
    for j in range(3):
        e[:] = 0.0
        e[j] = 1.0
        K.euler_rates_to_omega(ang, e, w)
        E[:, j] = w


def _check_omega(omega):
    om = np.atleast_1d(np.asarray(omega, float))
    if om.ndim != 1 or len(om) == 0:
        raise ValueError("omega: must be a non-empty 1-D array of frequencies (rad/s)")
    if not np.all(np.isfinite(om)) or np.any(om <= 0.0):
        raise ValueError(f"omega: every frequency must be finite and > 0 rad/s (got min {np.min(om)!r})")
    return om
