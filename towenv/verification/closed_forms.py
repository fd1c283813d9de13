"""Closed-form and independent reference solutions for verifying towenv.

Every function here is written from first principles with numpy/scipy only and
imports nothing else from towenv, so that agreement between the lumped-mass
simulator and these references is evidence, not a tautology.

Case numbers (V1-V7) and the expected values refer to
``shared/reference/verification.md``; section numbers such as "model.md 8.1"
refer to ``shared/reference/model.md``.

Conventions
-----------
* SI units throughout: m, s, kg, N, rad (angles returned in degrees say so).
* Arc length ``s`` is the *unstretched* arc length, measured from the lower end
  (the body, s = 0) up to the top / tow point (s = L).
* ``z`` points up.  In the steady-tow reference the tow moves toward +x.
* "Wet weight" is weight minus buoyancy (positive sinks).

Contents
--------
Derived properties ........ :func:`wet_weight_per_length`, :func:`body_wet_weight`,
                            :func:`axial_wave_speed`, :func:`g_eff_cable`,
                            :func:`g_eff_body`, :data:`PEER_DECK`
V1 vertical hang .......... :func:`vertical_hang`, :func:`segment_midpoint_tensions`
V2 elastic catenary ....... :func:`elastic_catenary`
V3 axial string ........... :func:`axial_eigenfrequencies`,
                            :func:`axial_spring_mass_frequency`,
                            :func:`axial_string_tf`, :func:`axial_string_displacement_tf`,
                            :func:`axial_string_tension_tf`, :func:`compensator_tf`
V4 waves, lumped chain .... :func:`transverse_wave_speed`, :func:`taut_string_period`,
                            :func:`lumped_chain_dispersion`,
                            :func:`lumped_axial_chain_eigenfrequencies`,
                            :func:`lumped_axial_chain_tf`
V5 hanging chain .......... :func:`hanging_chain_periods`
V6 pendulum ............... :func:`pendulum_period`
V7 steady tow ............. :func:`steady_tow_ode`, :func:`critical_angle`
V9 / model.md 8.1 ......... :func:`houbolt_amplification_matrix`,
                            :func:`houbolt_spectral_radius`, :func:`houbolt_ad_pe`
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import integrate, linalg, optimize, special

__all__ = [
    "G_STANDARD",
    "RHO_SEAWATER",
    "PeerDeck",
    "PEER_DECK",
    "wet_weight_per_length",
    "body_wet_weight",
    "axial_wave_speed",
    "transverse_wave_speed",
    "taut_string_period",
    "g_eff_cable",
    "g_eff_body",
    "vertical_hang",
    "segment_midpoint_tensions",
    "CatenarySolution",
    "elastic_catenary",
    "AxialStringTF",
    "CompensatorTF",
    "axial_eigenfrequencies",
    "axial_spring_mass_frequency",
    "axial_string_tf",
    "axial_string_displacement_tf",
    "axial_string_tension_tf",
    "compensator_tf",
    "lumped_chain_dispersion",
    "lumped_axial_chain_eigenfrequencies",
    "lumped_axial_chain_tf",
    "hanging_chain_periods",
    "pendulum_period",
    "SteadyTowSolution",
    "steady_tow_ode",
    "critical_angle",
    "houbolt_amplification_matrix",
    "houbolt_spectral_radius",
    "houbolt_ad_pe",
]

G_STANDARD = 9.80665
"""Standard gravity (m/s^2), as used in the peer deck."""

RHO_SEAWATER = 1025.0
"""Sea-water density (kg/m^3), as used in the peer deck."""


# ---------------------------------------------------------------------------
# Derived properties and the standard test deck
# ---------------------------------------------------------------------------


def wet_weight_per_length(mu, D, rho=RHO_SEAWATER, g=G_STANDARD):
    """Wet weight per unit length of a cable, ``w = (mu - rho*pi*D^2/4) g`` (N/m).

    mu: mass per unit length (kg/m); D: diameter (m); rho: water density
    (kg/m^3); g: gravity (m/s^2).  Source: verification.md, peer deck.
    """
    return (mu - rho * np.pi * np.asarray(D) ** 2 / 4.0) * g


def body_wet_weight(M, V, rho=RHO_SEAWATER, g=G_STANDARD):
    """Wet weight of a body, ``W_b = (M - rho V) g`` (N); M in kg, V in m^3."""
    return (M - rho * V) * g


def axial_wave_speed(EA, mu):
    """Axial (longitudinal) wave speed ``c_L = sqrt(EA/mu)`` (m/s); thesis (5.179)."""
    return np.sqrt(EA / mu)


def transverse_wave_speed(T, mu, D, rho=RHO_SEAWATER, Can=1.0):
    """Transverse wave speed ``c_T = sqrt(T/(mu + mu_a))`` (m/s), verification.md V4.

    ``mu_a = Can rho pi D^2/4`` is the normal added mass per length (thesis
    (5.184) omits it).  T tension (N), mu (kg/m), D (m); ``rho=0`` in air.
    """
    mu_a = Can * rho * np.pi * np.asarray(D) ** 2 / 4.0
    return np.sqrt(np.asarray(T) / (mu + mu_a))


def taut_string_period(L, c_T):
    """Fundamental period ``2L/c_T`` (s) of a taut string fixed at both ends (V4)."""
    return 2.0 * L / c_T


def g_eff_cable(mu, D, rho=RHO_SEAWATER, g=G_STANDARD, Can=1.0):
    """Effective gravity for transverse motion of a submerged cable (m/s^2).

    ``g_eff = g (mu - rho A) / (mu + Can rho A)``, ``A = pi D^2/4`` (verification.md V5).
    Pass ``rho=0`` for a cable in air (then ``g_eff = g``).
    """
    A = np.pi * np.asarray(D) ** 2 / 4.0
    return g * (mu - rho * A) / (mu + Can * rho * A)


def g_eff_body(M, V, Ca, rho=RHO_SEAWATER, g=G_STANDARD):
    """Effective gravity of a submerged bob, ``g (M - rho V)/(M + Ca rho V)`` (m/s^2), V6."""
    return g * (M - rho * V) / (M + Ca * rho * V)


@dataclass(frozen=True)
class PeerDeck:
    """The standard "peer deck" of verification.md (also buildable in MoorDyn).

    Cable drag: ``Cn`` on D*l; the tangential coefficient ``CdAx`` is on pi*D*l
    (MoorDyn convention), i.e. ``Ct_dl = pi * CdAx`` on D*l.
    """

    L: float = 100.0  # unstretched cable length (m)
    D: float = 0.02  # cable diameter (m)
    mu: float = 1.0  # cable mass per length (kg/m)
    EA: float = 2.0e7  # axial stiffness (N)
    Cn: float = 1.2  # normal drag coefficient on D*l
    CdAx: float = 0.01  # tangential drag coefficient on pi*D*l (MoorDyn)
    Can: float = 1.0  # normal added-mass coefficient of the cable
    Cat: float = 0.0  # tangential added-mass coefficient of the cable
    M: float = 500.0  # body mass (kg)
    V: float = 0.10  # body volume (m^3)
    CdA: float = 0.5  # isotropic body drag area (m^2)
    Ca: float = 1.0  # body added-mass coefficient
    rho: float = RHO_SEAWATER
    g: float = G_STANDARD

    @property
    def w(self) -> float:
        """Cable wet weight per length (N/m); 6.6488 for the peer deck."""
        return float(wet_weight_per_length(self.mu, self.D, self.rho, self.g))

    @property
    def W_b(self) -> float:
        """Body wet weight (N); 3898.14 for the peer deck."""
        return float(body_wet_weight(self.M, self.V, self.rho, self.g))

    @property
    def Ct_dl(self) -> float:
        """Tangential cable drag coefficient on the D*l reference area (= pi*CdAx)."""
        return np.pi * self.CdAx

    @property
    def M_a(self) -> float:
        """Body added mass ``Ca rho V`` (kg)."""
        return self.Ca * self.rho * self.V

    @property
    def c_L(self) -> float:
        """Axial wave speed (m/s); 4472 for the peer deck."""
        return float(axial_wave_speed(self.EA, self.mu))


PEER_DECK = PeerDeck()


# ---------------------------------------------------------------------------
# V1. Vertical hang
# ---------------------------------------------------------------------------


def vertical_hang(w, L, W_b):
    """Static vertical hang of a cable with an end body (verification.md V1).

    Closed form, s measured up from the body: ``T(s) = W_b + w s``.

    Parameters: w cable wet weight per length (N/m); L unstretched length (m);
    W_b body wet weight (N).

    Returns a dict with ``top_reaction`` = W_b + w L (N, the force on the
    prescribed top node, i.e. the reaction on the ship), ``bottom_tension`` =
    W_b (N) and ``tension`` = a vectorised callable ``T(s)`` (N).
    """
    return {
        "top_reaction": W_b + w * L,
        "bottom_tension": W_b,
        "tension": lambda s: W_b + w * np.asarray(s, dtype=float),
    }


def segment_midpoint_tensions(w, L, W_b, n):
    """Segment tensions of an n-segment lumped chain in a vertical hang (V1).

    The lumped model reproduces the continuous tension exactly at each segment
    midpoint: ``T_i = W_b + w (i + 1/2) l``, ``l = L/n``, i = 0 (bottom, at the
    body) ... n-1 (top).  Hence the top segment tension is lower than the top
    reaction by ``w l/2``.  Returns an array of length n (N).
    """
    l = L / n
    return W_b + w * (np.arange(n) + 0.5) * l


# ---------------------------------------------------------------------------
# V2. Elastic catenary (Irvine), no seabed
# ---------------------------------------------------------------------------


def _asinh_diff(a, delta):
    """``asinh(a + delta) - asinh(a)`` without cancellation for small ``delta``.

    Uses ``asinh(b) - asinh(a) = asinh(b sqrt(1+a^2) - a sqrt(1+b^2))``; the
    argument is rationalised to ``delta (a+b) / (b sqrt(1+a^2) + a sqrt(1+b^2))``
    when a and b have the same sign, and summed directly otherwise.
    """
    b = a + delta
    ra, rb = np.sqrt(1 + a * a), np.sqrt(1 + b * b)
    same_sign = a * b > 0
    den = np.where(same_sign, b * ra + a * rb, 1.0)
    q = np.where(same_sign, delta * (a + b) / den, b * ra - a * rb)
    return np.arcsinh(q)


def _sqrt_diff(a, delta):
    """``sqrt(1 + (a+delta)^2) - sqrt(1 + a^2)`` without cancellation."""
    b = a + delta
    return delta * (a + b) / (np.sqrt(1 + b * b) + np.sqrt(1 + a * a))


@dataclass(frozen=True)
class CatenarySolution:
    """Solution of the elastic catenary between A = (0, 0) and B = (x_B, z_B).

    ``H`` is the horizontal tension (N); ``V_A`` the vertical force at A acting
    on the cable toward B (positive up; negative when the sag vertex lies inside
    the span); ``V_B = V_A + w L``.  Use :meth:`x`, :meth:`z`, :meth:`T` or
    :meth:`shape` to evaluate the profile at unstretched arc length s from A.
    """

    H: float
    V_A: float
    V_B: float
    T_top: float
    T_bottom: float
    L: float
    w: float
    EA: float

    def x(self, s):
        """Horizontal position (m) at arc length s (m), Irvine (V2)."""
        s = np.asarray(s, dtype=float)
        a, delta = self.V_A / self.H, self.w * s / self.H
        return (self.H / self.w) * _asinh_diff(a, delta) + self.H * s / self.EA

    def z(self, s):
        """Vertical position (m) at arc length s (m), Irvine (V2)."""
        s = np.asarray(s, dtype=float)
        a, delta = self.V_A / self.H, self.w * s / self.H
        stretch = (self.V_A * s + 0.5 * self.w * s**2) / self.EA
        return (self.H / self.w) * _sqrt_diff(a, delta) + stretch

    def T(self, s):
        """Tension (N) at arc length s (m): ``sqrt(H^2 + (V_A + w s)^2)``."""
        s = np.asarray(s, dtype=float)
        return np.hypot(self.H, self.V_A + self.w * s)

    def shape(self, s):
        """Return ``(x(s), z(s), T(s))``."""
        return self.x(s), self.z(s), self.T(s)


def _catenary_residual_and_jacobian(H, V_A, L, w, EA, x_B, z_B):
    """Residual [x(L)-x_B, z(L)-z_B] and its analytic Jacobian w.r.t. (H, V_A)."""
    a, delta = V_A / H, w * L / H
    b = a + delta
    ra, rb = np.sqrt(1 + a * a), np.sqrt(1 + b * b)
    asinh_diff = _asinh_diff(a, delta)  # asinh(b) - asinh(a), cancellation-free
    root_diff = _sqrt_diff(a, delta)  # rb - ra, cancellation-free
    residual = np.array(
        [
            (H / w) * asinh_diff + H * L / EA - x_B,
            (H / w) * root_diff + (V_A * L + 0.5 * w * L * L) / EA - z_B,
        ]
    )
    jacobian = np.array(
        [
            [(asinh_diff - (b / rb - a / ra)) / w + L / EA, (1 / rb - 1 / ra) / w],
            [(1 / rb - 1 / ra) / w, (b / rb - a / ra) / w + L / EA],
        ]
    )
    return residual, jacobian


def _catenary_initial_guess(L, w, EA, x_B, z_B):
    """Initial (H, V_A).

    Slack span (L > chord): Peyrot & Goulois (1979), as used by MAP++/MoorPy.
    Taut span (L <= chord): a straight elastic bar, ``T = EA (chord/L - 1)``,
    with half the weight carried at each end.
    """
    chord = np.hypot(x_B, z_B)
    if L < chord:
        T = EA * (chord / L - 1.0) if np.isfinite(EA) else w * L
        T = max(T, w * L)
        return T * x_B / chord, T * z_B / chord - 0.5 * w * L
    lam = np.sqrt(max(3.0 * ((L * L - z_B * z_B) / (x_B * x_B) - 1.0), 0.04))
    H = max(abs(w * x_B / (2.0 * lam)), 1e-6 * w * L)
    V_B = 0.5 * w * (z_B / np.tanh(lam) + L)
    return H, V_B - w * L


def elastic_catenary(L, w, EA, x_B, z_B, *, tol=1e-10, max_iter=100):
    """Solve the elastic (Irvine) catenary without seabed contact (verification.md V2).

    The lower end A is at the origin and the upper end B at ``(x_B, z_B)``;
    ``x_B > 0`` is required (use :func:`vertical_hang` for a vertical cable).
    Unstretched length L (m), wet weight per length w (N/m, > 0), axial
    stiffness EA (N; ``np.inf`` for an inextensible cable).  With H the
    horizontal tension and V_A the vertical force at A (up positive):

        x(s) = (H/w)[asinh((V_A + w s)/H) - asinh(V_A/H)] + H s/EA
        z(s) = (H/w)[sqrt(1 + ((V_A + w s)/H)^2) - sqrt(1 + (V_A/H)^2)] + (V_A s + w s^2/2)/EA
        T(s) = sqrt(H^2 + (V_A + w s)^2)

    (Irvine, *Cable Structures*, 1981.)  The bracketed differences are
    evaluated in cancellation-free form, so nearly straight (w s << H)
    cables keep full precision.  ``x(L) = x_B, z(L) = z_B`` is solved for
    (H, V_A) by a damped 2-D Newton iteration with the analytic Jacobian,
    started from the Peyrot-Goulois guess (a straight elastic bar when the
    span is taut), keeping H > 0; if that fails,
    scipy's hybrid Powell solver is tried on (log H, V_A).

    Returns a :class:`CatenarySolution`.
    """
    if not x_B > 0:
        raise ValueError("elastic_catenary needs x_B > 0; use vertical_hang for x_B = 0")
    if not w > 0:
        raise ValueError("elastic_catenary needs w > 0")
    H, V_A = _catenary_initial_guess(L, w, EA, x_B, z_B)
    res, jac = _catenary_residual_and_jacobian(H, V_A, L, w, EA, x_B, z_B)
    converged = False
    for _ in range(max_iter):
        step = np.linalg.solve(jac, -res)
        # Backtracking line search: keep H > 0 and reduce the residual norm.
        alpha, accepted = 1.0, False
        while alpha > 1e-10:
            H_new, V_new = H + alpha * step[0], V_A + alpha * step[1]
            if H_new > 0:
                res_new, jac_new = _catenary_residual_and_jacobian(H_new, V_new, L, w, EA, x_B, z_B)
                if np.all(np.isfinite(res_new)) and np.linalg.norm(res_new) < np.linalg.norm(res):
                    accepted = True
                    break
            alpha *= 0.5
        if not accepted:  # no further decrease possible: converged or stuck
            converged = np.linalg.norm(res) < 1e-8 * L
            break
        force_scale = max(w * L, np.hypot(H_new, V_new))
        small_step = np.hypot(*(alpha * step)) < tol * force_scale
        H, V_A, res, jac = H_new, V_new, res_new, jac_new
        if small_step or np.linalg.norm(res) < 1e-13 * L:
            converged = np.linalg.norm(res) < 1e-8 * L
            break
    if not converged:
        H, V_A = _catenary_fallback(L, w, EA, x_B, z_B)
    return CatenarySolution(
        H=float(H),
        V_A=float(V_A),
        V_B=float(V_A + w * L),
        T_top=float(np.hypot(H, V_A + w * L)),
        T_bottom=float(np.hypot(H, V_A)),
        L=float(L),
        w=float(w),
        EA=float(EA),
    )


def _catenary_fallback(L, w, EA, x_B, z_B):
    """Hybrid Powell on (log H, V_A); raises if it does not converge."""
    H0, V0 = _catenary_initial_guess(L, w, EA, x_B, z_B)

    def fun(u):
        H = np.exp(u[0])
        res, jac = _catenary_residual_and_jacobian(H, u[1], L, w, EA, x_B, z_B)
        jac = jac.copy()
        jac[:, 0] *= H
        return res, jac

    sol = optimize.root(fun, [np.log(H0), V0], jac=True, method="hybr", options={"xtol": 1e-13})
    if not sol.success or np.linalg.norm(sol.fun) > 1e-6 * L:
        raise RuntimeError(f"elastic_catenary did not converge: {sol.message}")
    return np.exp(sol.x[0]), sol.x[1]


# ---------------------------------------------------------------------------
# V3. Axial string with an end mass; passive heave compensator
# ---------------------------------------------------------------------------


def axial_eigenfrequencies(L, m, EA, M_end, n_modes=3):
    """Undamped axial eigenfrequencies of a string with a top fixed and an end mass (V3).

    Continuous string, top (s = L) fixed, mass ``M_end`` at the free lower end.
    ``M_end`` is the *effective* axial body mass, body mass plus its added mass
    in the cable direction (``M + M_a``).  The frequency equation is

        beta tan(beta) = m L / M_end,     omega_k = beta_k c_L / L,   c_L = sqrt(EA/m)

    The k-th root lies in ``((k-1) pi, (k-1) pi + pi/2)`` and is found by
    brentq on ``beta sin(beta) - (mL/M_end) cos(beta)`` (no poles).  With
    ``M_end = 0`` the roots are ``(k - 1/2) pi``.

    Parameters: L (m), m cable mass per length incl. axial added mass (kg/m),
    EA (N), M_end (kg), n_modes.
    Returns ``(beta, omega)``: arrays of length n_modes (omega in rad/s).
    """
    c_L = np.sqrt(EA / m)
    k = np.arange(n_modes)
    if M_end == 0:
        beta = (k + 0.5) * np.pi
    else:
        ratio = m * L / M_end

        def f(b):
            return b * np.sin(b) - ratio * np.cos(b)

        beta = np.array(
            [optimize.brentq(f, kk * np.pi, (kk + 0.5) * np.pi, xtol=1e-15, rtol=1e-15)
             for kk in k]
        )
    return beta, beta * c_L / L


def axial_spring_mass_frequency(L, m, EA, M_end):
    """Spring-mass estimate of the first axial mode, valid for ``m L << M_end`` (V3).

    ``omega_1 ~= sqrt(EA / (L (M_end + m L / 3)))`` (rad/s), Rayleigh's
    one-third-of-the-spring-mass correction.
    """
    return np.sqrt(EA / (L * (M_end + m * L / 3.0)))


def _sinhc(z):
    """sinh(z)/z for complex z, with the limit 1 at z = 0."""
    z = np.asarray(z, dtype=complex)
    small = np.abs(z) < 1e-4
    z_safe = np.where(small, 1.0, z)
    return np.where(small, 1.0 + z * z / 6.0 + z**4 / 120.0, np.sinh(z_safe) / z_safe)


def _axial_string_parts(omega, L, m, EA, M_end, B_Q, b_p):
    """gamma^2, Gamma and the denominator divided by gamma (finite at omega = 0)."""
    omega = np.asarray(omega, dtype=float)
    gamma2 = (-m * omega**2 + 1j * omega * b_p) / EA
    gamma = np.sqrt(gamma2 + 0j)  # any branch: all results are even in gamma
    Gamma = (-M_end * omega**2 + 1j * omega * B_Q) / EA
    den_over_gamma = np.cosh(gamma * L) + Gamma * L * _sinhc(gamma * L)
    return gamma, gamma2, Gamma, den_over_gamma


@dataclass(frozen=True)
class AxialStringTF:
    """Transfer functions per unit top displacement p_n (V3, Hover eq. 31-33 corrected).

    ``p1`` body motion / p_n (-); ``T1`` dynamic tension at the body (s = 0) / p_n
    (N/m); ``Tn`` dynamic tension at the top (s = L) / p_n (N/m).  Complex,
    with the shape of ``omega``.
    """

    p1: np.ndarray
    T1: np.ndarray
    Tn: np.ndarray


def axial_string_tf(omega, L, m, EA, M_end, B_Q=0.0, b_p=0.0):
    """Frequency response of a heaved axial string with an end mass (verification.md V3).

    Model (Hover 1994 appendix, eq. 28-30, with s from the body up):

        m p_tt + b_p p_t = EA p_ss,   p(L,t) = p_n(t),   M_end Q'' + B_Q Q' = EA p_s(0,t)

    With ``p = P(s) e^{j omega t}`` and the corrected forms of verification.md
    (Gamma to the first power; the printed T_1/T_n formulas swapped):

        gamma = sqrt((-m omega^2 + j omega b_p)/EA),  Gamma = (-M_end omega^2 + j omega B_Q)/EA
        den = gamma cosh(gamma L) + Gamma sinh(gamma L)
        p_1/p_n = gamma/den
        T_1/p_n = EA gamma Gamma/den                       (tension at the body)
        T_n/p_n = EA gamma (gamma sinh(gamma L) + Gamma cosh(gamma L))/den   (at the top)

    They are evaluated after dividing through by gamma, so omega = 0 is fine.

    Parameters: omega (rad/s, array-like), L (m), m cable mass per length incl.
    axial added mass (kg/m), EA (N), M_end effective body mass M + M_a (kg),
    B_Q linear body damping (N s/m), b_p linear axial cable damping per unit
    length (N s/m^2).  Returns an :class:`AxialStringTF`.
    """
    gamma, gamma2, Gamma, dg = _axial_string_parts(omega, L, m, EA, M_end, B_Q, b_p)
    gL = gamma * L
    p1 = 1.0 / dg
    T1 = EA * Gamma / dg
    Tn = EA * (gamma2 * L * _sinhc(gL) + Gamma * np.cosh(gL)) / dg
    return AxialStringTF(p1=p1, T1=T1, Tn=Tn)


def axial_string_displacement_tf(omega, s, L, m, EA, M_end, B_Q=0.0, b_p=0.0):
    """Axial displacement P(s)/p_n at arc length s (m) from the body (V3).

    ``P(s)/p_n = (gamma cosh(gamma s) + Gamma sinh(gamma s)) / den``; omega and s
    broadcast against each other.  See :func:`axial_string_tf` for the symbols.
    """
    s = np.asarray(s, dtype=float)
    gamma, _, Gamma, dg = _axial_string_parts(omega, L, m, EA, M_end, B_Q, b_p)
    gs = gamma * s
    return (np.cosh(gs) + Gamma * s * _sinhc(gs)) / dg


def axial_string_tension_tf(omega, s, L, m, EA, M_end, B_Q=0.0, b_p=0.0):
    """Dynamic tension T(s)/p_n = EA dP/ds at arc length s (m) from the body (V3), in N/m.

    ``T(s)/p_n = EA gamma (gamma sinh(gamma s) + Gamma cosh(gamma s)) / den``.
    Use s = l/2 and L - l/2 to compare with the first and last segment
    tensions of an n-segment lumped chain (segment tension = continuous
    tension at the segment midpoint, up to O(l^2)).  omega and s broadcast.
    """
    s = np.asarray(s, dtype=float)
    gamma, gamma2, Gamma, dg = _axial_string_parts(omega, L, m, EA, M_end, B_Q, b_p)
    gs = gamma * s
    return EA * (gamma2 * s * _sinhc(gs) + Gamma * np.cosh(gs)) / dg


@dataclass(frozen=True)
class CompensatorTF:
    """Transfer functions per unit vessel heave D (V3 compensator, Hover eq. 27, 31-34).

    ``pn`` cable-top motion / D; ``R`` compensator stroke / D (= pn - 1);
    ``p1`` body motion / D; ``T1`` tension at the body / D (N/m); ``Tn``
    tension at the cable top / D (N/m).
    """

    pn: np.ndarray
    R: np.ndarray
    p1: np.ndarray
    T1: np.ndarray
    Tn: np.ndarray


def compensator_tf(omega, L, m, EA, M_end, k_c, b_c=0.0, m_c=0.0, B_Q=0.0, b_p=0.0):
    """Frequency response of the string of V3 behind a passive heave compensator.

    A spring ``k_c`` (N/m) in parallel with a dashpot ``b_c`` (N s/m) sits
    between the vessel heave D and the cable top; an apparent mass ``m_c`` (kg)
    moves with the top.  Hover (1994) eq. (27) and (34):

        p_n/D = (k_c + j omega b_c) / (Delta_11 - omega^2 m_c + k_c + j omega b_c),
        Delta_11 = T_n/p_n   (top dynamic stiffness of the string, axial_string_tf)
        R/D = p_n/D - 1,    p_1/D = (p_1/p_n)(p_n/D),   T_1/D, T_n/D likewise.

    ``k_c = np.inf`` gives the locked compensator (p_n = D).  Other parameters
    as in :func:`axial_string_tf`.  Returns a :class:`CompensatorTF`.
    """
    omega = np.asarray(omega, dtype=float)
    string = axial_string_tf(omega, L, m, EA, M_end, B_Q=B_Q, b_p=b_p)
    if np.isinf(k_c):
        pn = np.ones_like(string.Tn)
    else:
        z_c = k_c + 1j * omega * b_c
        pn = z_c / (string.Tn - omega**2 * m_c + z_c)
    return CompensatorTF(pn=pn, R=pn - 1.0, p1=string.p1 * pn, T1=string.T1 * pn, Tn=string.Tn * pn)


# ---------------------------------------------------------------------------
# V4 / model.md 8.4. Lumped chain closed forms
# ---------------------------------------------------------------------------


def lumped_chain_dispersion(k, l, c):
    """Dispersion of an infinite uniform lumped-mass chain (V4, model.md 8.4).

    ``omega = (2 c / l) |sin(k l / 2)|`` (rad/s) for wavenumber k (rad/m),
    segment length l (m) and continuous wave speed c (m/s): c_L = sqrt(EA/mu)
    axially, sqrt(T/(mu + mu_a)) transversely.  Cut-off ``2c/l`` at k = pi/l.
    """
    return (2.0 * c / l) * np.abs(np.sin(0.5 * np.asarray(k) * l))


def _lumped_axial_chain_matrices(n, L, mu, EA, M_end, top_fixed):
    """Lumped mass (diagonal) and stiffness matrices; node 0 = body, node n = top."""
    l = L / n
    k = EA / l
    masses = np.full(n + 1, mu * l)
    masses[0] = mu * l / 2.0 + M_end
    masses[-1] = mu * l / 2.0
    K = np.zeros((n + 1, n + 1))
    for i in range(n):  # spring i joins nodes i and i+1
        K[i, i] += k
        K[i + 1, i + 1] += k
        K[i, i + 1] -= k
        K[i + 1, i] -= k
    if top_fixed:
        masses, K = masses[:-1], K[:-1, :-1]
    return masses, K


def lumped_axial_chain_eigenfrequencies(n, L, mu, EA, M_end, top_fixed=True):
    """Exact eigenfrequencies of the *discrete* n-segment lumped axial chain (rad/s).

    Nodes 0 (body) ... n (top); each carries half the mass ``mu l`` of its
    adjacent segments (``l = L/n``), node 0 also carries ``M_end`` (body mass
    plus axial added mass); segments are springs ``EA/l``.  With
    ``top_fixed=True`` node n is removed (prescribed), giving n modes; with
    ``top_fixed=False`` the top node is free (n + 1 modes, the first zero).
    Solved with ``scipy.linalg.eigh(K, M)``.  Compare with
    :func:`axial_eigenfrequencies` to isolate spatial discretisation error
    from integrator error.  Returns ascending omega (rad/s).
    """
    masses, K = _lumped_axial_chain_matrices(n, L, mu, EA, M_end, top_fixed)
    eigvals = linalg.eigh(K, np.diag(masses), eigvals_only=True)
    return np.sqrt(np.clip(eigvals, 0.0, None))


def lumped_axial_chain_tf(omega, n, L, mu, EA, M_end, B_Q=0.0, b_p=0.0):
    """Frequency response of the discrete n-segment lumped axial chain, top prescribed.

    The lumped counterpart of :func:`axial_string_tf` (same symbols), for one
    scalar omega (rad/s).  Node masses as in
    :func:`lumped_axial_chain_eigenfrequencies`; the cable damping ``b_p l`` is
    lumped like the mass and ``B_Q`` acts on node 0.  Node n moves with unit
    amplitude.  Returns ``(u, T)``: complex node displacements u_0..u_n per unit
    top motion and segment tensions ``T_i = EA (u_{i+1} - u_i)/l`` (N/m),
    i = 0 (bottom) ... n-1 (top), per unit top motion.
    """
    l = L / n
    k = EA / l
    node_mass = np.full(n, mu * l)
    node_damp = np.full(n, b_p * l)
    node_mass[0] = mu * l / 2.0 + M_end
    node_damp[0] = b_p * l / 2.0 + B_Q
    diag = -(omega**2) * node_mass + 1j * omega * node_damp + 2.0 * k
    diag[0] -= k  # the body node has one spring only
    ab = np.zeros((3, n), dtype=complex)
    ab[0, 1:] = -k
    ab[1, :] = diag
    ab[2, :-1] = -k
    rhs = np.zeros(n, dtype=complex)
    rhs[-1] = k  # coupling to the prescribed top node, u_n = 1
    u = np.append(linalg.solve_banded((1, 1), ab, rhs), 1.0)
    return u, k * np.diff(u)


# ---------------------------------------------------------------------------
# V5, V6. Hanging chain and pendulum
# ---------------------------------------------------------------------------


def hanging_chain_periods(L, g_eff, n=3):
    """Transverse periods of a uniform hanging chain, top fixed, free lower end (V5).

    ``omega_k = (j_{0,k}/2) sqrt(g_eff/L)``, with j_{0,k} the zeros of the Bessel
    function J_0 (scipy.special.jn_zeros).  Inextensible chain, no end mass.
    L in m, g_eff in m/s^2 (:func:`g_eff_cable` in water, g in air).
    Returns the first n periods ``2 pi/omega_k`` (s).
    """
    j0 = special.jn_zeros(0, n)
    omega = 0.5 * j0 * np.sqrt(g_eff / L)
    return 2.0 * np.pi / omega


def pendulum_period(L, M, V=0.0, Ca=0.0, rho=RHO_SEAWATER, g=G_STANDARD):
    """Small-amplitude period of a bob on a massless line (V6), in s.

    ``T = 2 pi sqrt(L/g_eff)``, ``g_eff = g (M - rho V)/(M + Ca rho V)``.  L (m),
    bob mass M (kg), volume V (m^3), added-mass coefficient Ca.  With V = 0
    (or rho = 0) this is the in-air period ``2 pi sqrt(L/g)``.
    """
    return 2.0 * np.pi * np.sqrt(L / g_eff_body(M, V, Ca, rho, g))


# ---------------------------------------------------------------------------
# V7. Steady tow: reference ODE and critical angle
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class SteadyTowSolution:
    """Steady towed-cable profile from :func:`steady_tow_ode`.

    Scalars: ``top_tension`` |F(L)| (N); ``top_angle_deg`` the cable angle at the
    tow point above the horizontal (deg, atan2(F_z, F_x)); ``body_behind`` and
    ``body_below`` the body position relative to the tow point (m, positive
    behind and below).  Arrays over the output grid: ``s`` unstretched arc
    length from the body (m); ``x``, ``z`` cable position relative to the body
    (m, x toward the tow point / forward, z up); ``T`` tension (N);
    ``angle_deg`` local cable angle above the horizontal (deg).
    ``F_top`` is the force vector (F_x, F_z) the tow point exerts on the cable (N).
    """

    top_tension: float
    top_angle_deg: float
    body_behind: float
    body_below: float
    s: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    z: np.ndarray = field(repr=False)
    T: np.ndarray = field(repr=False)
    angle_deg: np.ndarray = field(repr=False)
    F_top: np.ndarray = field(repr=False)


def steady_tow_ode(
    L,
    U,
    w,
    EA,
    *,
    D,
    Cn,
    Ct_dl,
    rho=RHO_SEAWATER,
    CdA=0.0,
    W_b=0.0,
    body_force=None,
    n_out=401,
    rtol=1e-10,
    atol=1e-9,
):
    """Independent steady-tow reference of verification.md V7 (2-D, vertical plane).

    A cable of unstretched length L runs from a point body (s = 0) to the tow
    point (s = L).  The cable moves at speed U along +x relative to the water
    (tow speed minus current).  ``F(s) = T t`` is the force the cable above s
    exerts on the cable below; equilibrium of an element gives

        dF/ds = -f(t),
        f = -1/2 rho Cn D |v_n| v_n - 1/2 rho Ct_dl D |v_t| v_t - w e_z,
        v_r = U e_x,  v_t = (v_r . t) t,  v_n = v_r - v_t,  t = F/|F|,
        dr/ds = t (1 + T/EA)         (geometry; factor 1 when EA = inf)

    with the fully known lower boundary condition (no shooting needed)

        F(0) = 1/2 rho CdA U|U| e_x + W_b e_z     (or F(0) = body_force).

    The drag law matches the dynamic model (model.md 2.3, vector normal form).
    The tangential coefficient ``Ct_dl`` is referred to the D*l area, like the
    thesis; MoorDyn's CdAx on pi*D*l corresponds to ``Ct_dl = pi*CdAx``
    (equivalently CdAx = Ct_dl/pi).  Integrated with scipy ``solve_ivp``
    (DOP853, rtol 1e-10).

    Parameters
    ----------
    L : unstretched length (m).  U : relative flow speed (m/s).
    w : cable wet weight per length (N/m).  EA : axial stiffness (N), np.inf
        for an inextensible cable.
    D : cable diameter (m).  Cn : normal drag coefficient on D*l.
    Ct_dl : tangential drag coefficient on D*l.  rho : water density (kg/m^3).
    CdA : point-body drag area (m^2).  W_b : body wet weight (N).
    body_force : optional (F_x, F_z) in N, the force the cable must apply to the
        body at s = 0 (equal and opposite to the body's hydrodynamic and
        net-gravity loads).  Overrides CdA and W_b; use it for lifting bodies
        whose static attitude has been solved separately.  Must be non-zero.

    Returns a :class:`SteadyTowSolution`.
    """
    if body_force is None:
        F0 = np.array([0.5 * rho * CdA * U * abs(U), W_b], dtype=float)
    else:
        F0 = np.asarray(body_force, dtype=float).reshape(2)
    if not np.any(F0):
        raise ValueError("the force at the body end must be non-zero (direction undefined)")
    v_r = np.array([U, 0.0])
    k_n = 0.5 * rho * Cn * D
    k_t = 0.5 * rho * Ct_dl * D
    compliance = 0.0 if np.isinf(EA) else 1.0 / EA

    def rhs(_s, y):
        F = y[:2]
        T = np.hypot(F[0], F[1])
        t = F / T
        v_t = np.dot(v_r, t) * t
        v_n = v_r - v_t
        dF = k_n * np.linalg.norm(v_n) * v_n + k_t * np.linalg.norm(v_t) * v_t
        dF[1] += w
        dr = t * (1.0 + T * compliance)
        return np.concatenate([dF, dr])

    s_eval = np.linspace(0.0, L, n_out)
    sol = integrate.solve_ivp(
        rhs, (0.0, L), np.concatenate([F0, [0.0, 0.0]]), method="DOP853",
        t_eval=s_eval, rtol=rtol, atol=atol,
    )
    if not sol.success:
        raise RuntimeError(f"steady_tow_ode integration failed: {sol.message}")
    Fx, Fz, x, z = sol.y
    T = np.hypot(Fx, Fz)
    return SteadyTowSolution(
        top_tension=float(T[-1]),
        top_angle_deg=float(np.degrees(np.arctan2(Fz[-1], Fx[-1]))),
        body_behind=float(x[-1]),
        body_below=float(z[-1]),
        s=sol.t,
        x=x,
        z=z,
        T=T,
        angle_deg=np.degrees(np.arctan2(Fz, Fx)),
        F_top=np.array([Fx[-1], Fz[-1]]),
    )


def critical_angle(w, rho, Cn, D, U):
    """Critical angle of a long bare towed cable (deg above the horizontal), V7.

    Far from the body the cable is straight where the normal drag balances the
    normal component of wet weight, ``w cos(phi) = R sin^2(phi)`` with
    ``R = 1/2 rho Cn D U^2``, so

        cos(phi_c) = (-w + sqrt(w^2 + 4 R^2)) / (2 R).

    Tangential drag does not change phi_c.  w (N/m), rho (kg/m^3), Cn on D*l,
    D (m), U (m/s); vectorised over U.  U = 0 gives 90 deg.
    """
    R = 0.5 * rho * Cn * D * np.asarray(U, dtype=float) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        # (-w + sqrt(w^2 + 4R^2)) / (2R), rationalised to be finite as R -> 0
        cos_phi = 2.0 * R / (w + np.sqrt(w * w + 4.0 * R * R))
    return np.degrees(np.arccos(cos_phi))


# ---------------------------------------------------------------------------
# model.md 8.1 / V9. Houbolt on the undamped SDOF oscillator
# ---------------------------------------------------------------------------


def houbolt_amplification_matrix(omega_dt):
    """Amplification matrix of Houbolt's method for ``x'' + omega^2 x = 0``.

    Houbolt's acceleration ``(2x_{n+1} - 5x_n + 4x_{n-1} - x_{n-2})/dt^2``
    inserted in the equation of motion at t_{n+1} gives

        (2 + Omega^2) x_{n+1} = 5 x_n - 4 x_{n-1} + x_{n-2},   Omega = omega dt,

    i.e. ``[x_{n+1}, x_n, x_{n-1}] = A [x_n, x_{n-1}, x_{n-2}]`` (thesis (5.117),
    state as three successive displacements).  Returns A (3x3).
    """
    c = 2.0 + omega_dt**2
    return np.array([[5.0 / c, -4.0 / c, 1.0 / c], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def _houbolt_principal_root(dt_over_T):
    eig = np.linalg.eigvals(houbolt_amplification_matrix(2.0 * np.pi * dt_over_T))
    return eig[np.argmax(eig.imag)]


def houbolt_spectral_radius(dt_over_T):
    """Spectral radius of the Houbolt amplification matrix (model.md 8.1), vectorised."""
    r = np.asarray(dt_over_T, dtype=float)
    out = [np.max(np.abs(np.linalg.eigvals(houbolt_amplification_matrix(2.0 * np.pi * x))))
           for x in r.ravel()]
    return np.reshape(out, r.shape)


def houbolt_ad_pe(dt_over_T):
    """Houbolt amplitude decay and period elongation per period (model.md 8.1).

    From the principal (complex) eigenvalue lambda of
    :func:`houbolt_amplification_matrix` at ``Omega = 2 pi dt/T``:

        AD = 1 - |lambda|^(T/dt)             (amplitude lost over one exact period)
        PE = 2 pi (dt/T) / arg(lambda) - 1   (relative period elongation)

    Both returned as fractions (0.265 = 26.5 %); vectorised over dt/T.
    Expected: 0.1 -> 26.5 % / 12.3 %, 0.02 -> 0.58 % / 0.70 %.
    """
    r = np.asarray(dt_over_T, dtype=float)
    lam = np.array([_houbolt_principal_root(x) for x in r.ravel()]).reshape(r.shape)
    ad = 1.0 - np.abs(lam) ** (1.0 / r)
    pe = 2.0 * np.pi * r / np.angle(lam) - 1.0
    return ad, pe
