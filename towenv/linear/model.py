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

from .. import stats as S
from .harmonic import HarmonicSolution
from .linearise import Linearisation, LinearisationError

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


class Outputs(dict):
    """Output name → complex array; an unknown name raises a KeyError listing the available ones."""

    def __missing__(self, key):
        raise KeyError(f"unknown output {key!r}; available: {sorted(self)}")


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


class LinearModel(Linearisation, HarmonicSolution):
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


def _check_omega(omega):
    om = np.atleast_1d(np.asarray(omega, float))
    if om.ndim != 1 or len(om) == 0:
        raise ValueError("omega: must be a non-empty 1-D array of frequencies (rad/s)")
    if not np.all(np.isfinite(om)) or np.any(om <= 0.0):
        raise ValueError(f"omega: every frequency must be finite and > 0 rad/s (got min {np.min(om)!r})")
    return om
