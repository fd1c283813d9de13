"""Wave spectra, spectral moments, directional spreading and sea-state presets.

Conventions (``shared/reference/sea-and-vessel.md`` section 0)
----------------------------------------------------------------
* Angular frequency ``omega`` in rad/s; spectral density ``S(omega)`` in
  m^2 s/rad.  ``S(f) = 2*pi*S(omega)`` for ``f`` in Hz.
* Moments ``m_n = int omega**n S(omega) d omega`` and ``Hs = Hm0 = 4*sqrt(m0)``.
* Wave direction is the direction the waves **propagate**, relative to the
  ship's forward axis: 180 deg = head seas, 0 deg = following seas
  (Faltinsen / MSS / capytaine convention, *not* the buoy "coming-from" one).

Only numpy is used at run time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Callable, Optional, Sequence

import numpy as np

__all__ = [
    "G",
    "PM_ALPHA",
    "PM_BETA",
    "SPECTRUM_KINDS",
    "SPREADING_KINDS",
    "peak_frequency",
    "pierson_moskowitz_wind",
    "pm_hs_from_wind",
    "pm_tp_from_wind",
    "pm_tp_from_hs",
    "pierson_moskowitz",
    "bretschneider",
    "bretschneider_coefficients",
    "tp_from_t1",
    "tp_from_tz",
    "dnv_gamma",
    "jonswap_normalisation",
    "jonswap",
    "jonswap_m0_ratio",
    "dnv_tz_over_tp",
    "jonswap_fetch_limited",
    "fetch_limited_parameters",
    "spectral_moments",
    "integrate_moments",
    "hm0_from_m0",
    "tz_from_moments",
    "t1_from_moments",
    "cos2s_spreading",
    "cos2s_halfplane_spreading",
    "spreading_function",
    "SeaState",
    "WMO_SEA_STATE",
    "LEE_OPEN_OCEAN",
    "COASTAL_TP_COEFF_RANGE",
    "COASTAL_TP_COEFF",
]

G = 9.81
"""Gravitational acceleration used throughout (m/s^2)."""

PM_ALPHA = 8.1e-3
PM_BETA = 0.74

SPECTRUM_KINDS = ("jonswap", "bretschneider", "pm")
SPREADING_KINDS = ("cos2s", "cos2s_halfplane")

_TWO_PI = 2.0 * math.pi
# Exact period ratios of the Bretschneider (PM-shape) spectrum, moments to infinity:
#   Tp/T1 = 1.25**0.25 * Gamma(3/4) = 1.2957,   Tp/Tz = (1.25*pi)**0.25 = 1.4077
_TP_OVER_T1 = 1.25**0.25 * math.gamma(0.75)
_TP_OVER_TZ = (1.25 * math.pi) ** 0.25


def _trapz(y: np.ndarray, x: np.ndarray, axis: int = -1) -> np.ndarray:
    """Trapezoidal rule (numpy-version independent)."""
    y = np.asarray(y, dtype=float)
    x = np.asarray(x, dtype=float)
    dx = np.diff(x)
    y0 = np.take(y, np.arange(y.shape[axis] - 1), axis=axis)
    y1 = np.take(y, np.arange(1, y.shape[axis]), axis=axis)
    shape = [1] * y.ndim
    shape[axis] = dx.size
    return np.sum(0.5 * (y0 + y1) * dx.reshape(shape), axis=axis)


def _positive(name: str, value: float, upper: Optional[float] = None) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0 or (upper is not None and v > upper):
        rng = f"(0, {upper:g}]" if upper is not None else "(0, inf)"
        raise ValueError(f"{name} must be in {rng}, got {value!r}")
    return v


def _nonneg(name: str, value: float, upper: Optional[float] = None) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(v) or v < 0.0 or (upper is not None and v > upper):
        rng = f"[0, {upper:g}]" if upper is not None else "[0, inf)"
        raise ValueError(f"{name} must be in {rng}, got {value!r}")
    return v


def _omega_array(omega) -> np.ndarray:
    w = np.asarray(omega, dtype=float)
    if np.any(w < 0):
        raise ValueError("omega must be >= 0 rad/s")
    return w


def _pm_shape(w: np.ndarray, A: float, B: float) -> np.ndarray:
    """A * w**-5 * exp(-B * w**-4), returning 0 at w == 0 (no warnings)."""
    w = np.asarray(w, dtype=float)
    out = np.zeros(w.shape, dtype=float)
    pos = w > 0
    wp = w[pos]
    inv4 = wp**-4
    with np.errstate(under="ignore"):
        out[pos] = A * inv4 / wp * np.exp(-B * inv4)
    return out


# --------------------------------------------------------------------------
# Pierson-Moskowitz and Bretschneider
# --------------------------------------------------------------------------
def peak_frequency(tp: float) -> float:
    """Peak angular frequency omega_p = 2 pi / Tp (rad/s)."""
    return _TWO_PI / _positive("tp", tp)


def pierson_moskowitz_wind(omega, u195: float, g: float = G) -> np.ndarray:
    """Fully developed Pierson-Moskowitz spectrum, wind form.

    ``S = alpha g^2 w^-5 exp[-beta (w0/w)^4]`` with alpha = 8.1e-3, beta = 0.74,
    ``w0 = g/U19.5`` and ``u195`` the wind speed at 19.5 m (m/s).
    """
    u = _positive("u195", u195)
    w = _omega_array(omega)
    w0 = g / u
    return _pm_shape(w, PM_ALPHA * g * g, PM_BETA * w0**4)


def pm_hs_from_wind(u195: float, g: float = G) -> float:
    """Hs of the fully developed PM sea, exactly ``2 sqrt(alpha/beta) U^2/g`` (~0.21 U^2/g)."""
    u = _positive("u195", u195)
    return 2.0 * math.sqrt(PM_ALPHA / PM_BETA) * u * u / g


def pm_tp_from_wind(u195: float, g: float = G) -> float:
    """Tp of the fully developed PM sea; ``omega_p = (4 beta/5)^(1/4) g/U`` (~0.877 g/U)."""
    u = _positive("u195", u195)
    wp = (4.0 * PM_BETA / 5.0) ** 0.25 * g / u
    return _TWO_PI / wp


def pm_tp_from_hs(hs: float, g: float = G) -> float:
    """Tp of a fully developed PM sea of given Hs (Tp ~ 4.99 sqrt(Hs)), from the wind form."""
    hs = _positive("hs", hs)
    u = math.sqrt(hs * g / (2.0 * math.sqrt(PM_ALPHA / PM_BETA)))
    return pm_tp_from_wind(u, g)


def tp_from_t1(t1: float) -> float:
    """Modal period of the Bretschneider spectrum from its mean period T1 (Tp = 1.296 T1)."""
    return _TP_OVER_T1 * _positive("t1", t1)


def tp_from_tz(tz: float) -> float:
    """Modal period of the Bretschneider spectrum from its zero-crossing period (Tp = 1.408 Tz)."""
    return _TP_OVER_TZ * _positive("tz", tz)


def bretschneider_coefficients(hs: float, tp: Optional[float] = None, *, t1: Optional[float] = None,
                               tz: Optional[float] = None) -> tuple[float, float]:
    """Constants (A, B) of ``S = A w^-5 exp(-B w^-4)``; exactly one period must be given.

    Matches the reference table: Tp -> (487 Hs^2/Tp^4, 1948/Tp^4),
    T1 -> (173 Hs^2/T1^4, 691/T1^4), Tz -> (124 Hs^2/Tz^4, 496/Tz^4) to rounding
    (the exact constants are 4 pi^3 and 16 pi^3 for Tz).
    """
    given = [p is not None for p in (tp, t1, tz)]
    if sum(given) != 1:
        raise ValueError("give exactly one of tp, t1, tz (periods in s)")
    hs = _nonneg("hs", hs, 50.0)
    if tp is None:
        tp = tp_from_t1(t1) if t1 is not None else tp_from_tz(tz)
    wp = peak_frequency(tp)
    B = 1.25 * wp**4
    A = 5.0 / 16.0 * hs * hs * wp**4
    return A, B


def bretschneider(omega, hs: float, tp: Optional[float] = None, *, t1: Optional[float] = None,
                  tz: Optional[float] = None) -> np.ndarray:
    """Bretschneider / modified PM / ISSC / ITTC two-parameter spectrum.

    ``S = (5/16) Hs^2 wp^4 w^-5 exp[-1.25 (wp/w)^4]`` with ``wp = 2 pi/Tp``; the
    period may instead be given as the mean period ``t1`` or zero-crossing ``tz``.
    """
    A, B = bretschneider_coefficients(hs, tp, t1=t1, tz=tz)
    return _pm_shape(_omega_array(omega), A, B)


def pierson_moskowitz(omega, hs: float, tp: Optional[float] = None, g: float = G) -> np.ndarray:
    """Pierson-Moskowitz spectrum in (Hs, Tp) form.

    With ``tp`` given this is the Bretschneider spectrum; with ``tp=None`` the
    fully developed relation ``Tp = pm_tp_from_hs(Hs)`` (~4.99 sqrt(Hs)) is used.
    """
    if tp is None:
        tp = pm_tp_from_hs(hs, g) if hs > 0 else 1.0
    return bretschneider(omega, hs, tp)


# --------------------------------------------------------------------------
# JONSWAP
# --------------------------------------------------------------------------
def dnv_gamma(hs: float, tp: float) -> float:
    """DNV default peak enhancement from steepness ``r = Tp/sqrt(Hs)``.

    gamma = 5 for r <= 3.6, exp(5.75 - 1.15 r) for 3.6 < r < 5, 1 for r >= 5.
    A calm sea (Hs = 0) returns 1.
    """
    hs = _nonneg("hs", hs)
    tp = _positive("tp", tp)
    if hs == 0.0:
        return 1.0
    r = tp / math.sqrt(hs)
    if r <= 3.6:
        return 5.0
    if r >= 5.0:
        return 1.0
    return float(math.exp(5.75 - 1.15 * r))


def _check_gamma(gamma: float) -> float:
    g_ = float(gamma)
    if not math.isfinite(g_) or g_ < 1.0 or g_ > 10.0:
        raise ValueError(f"gamma must be in [1, 10], got {gamma!r}")
    return g_


def jonswap_normalisation(gamma: float) -> float:
    """DNV normalising factor C(gamma) = 1 - 0.287 ln(gamma)."""
    return 1.0 - 0.287 * math.log(_check_gamma(gamma))


def _peak_factor(w: np.ndarray, wp: float, gamma: float, sigma_a: float, sigma_b: float) -> np.ndarray:
    if gamma == 1.0:
        return np.ones(np.shape(w))
    sig = np.where(w <= wp, sigma_a, sigma_b)
    r = np.exp(-((w - wp) ** 2) / (2.0 * sig**2 * wp**2))
    return gamma**r


@lru_cache(maxsize=256)
def _jonswap_unit_m0(gamma: float, sigma_a: float, sigma_b: float) -> float:
    """m0 / (Hs^2/16) of the DNV-normalised JONSWAP, integrated to infinity.

    Computed in x = w/wp: m0/(Hs^2/16) = 5 C(gamma) int x^-5 exp(-1.25 x^-4) gamma^r dx.
    """
    x = np.geomspace(0.15, 40.0, 40001)
    f = _pm_shape(x, 1.0, 1.25) * _peak_factor(x, 1.0, gamma, sigma_a, sigma_b)
    integral = float(_trapz(f, x))
    integral += float(f[-1]) * x[-1] / 4.0  # analytic x^-5 tail beyond x = 40
    return 5.0 * jonswap_normalisation(gamma) * integral


def jonswap_m0_ratio(gamma: float, sigma_a: float = 0.07, sigma_b: float = 0.09) -> float:
    """Ratio m0 / (Hs^2/16) of the DNV-normalised JONSWAP (1.000 for gamma <= 5, 0.982 at 7)."""
    return _jonswap_unit_m0(_check_gamma(gamma), float(sigma_a), float(sigma_b))


def jonswap(omega, hs: float, tp: float, gamma: Optional[float] = 3.3, *, sigma_a: float = 0.07,
            sigma_b: float = 0.09, exact_hs: bool = False) -> np.ndarray:
    """JONSWAP spectrum with DNV normalisation.

    ``S = C(gamma) S_PM(w; Hs, Tp) gamma^r``, ``r = exp[-(w-wp)^2/(2 sigma^2 wp^2)]``,
    sigma = ``sigma_a`` (0.07) for w <= wp and ``sigma_b`` (0.09) above,
    ``C = 1 - 0.287 ln gamma``.

    Parameters
    ----------
    gamma : float or None
        Peak enhancement (3.3 = mean JONSWAP). ``None`` selects the DNV default
        from steepness (:func:`dnv_gamma`).
    exact_hs : bool
        If True, rescale by ``(Hs/4)^2/m0`` (m0 integrated numerically to
        infinity) so that ``4 sqrt(m0) == Hs`` exactly, instead of relying on C(gamma).
    """
    hs = _nonneg("hs", hs, 50.0)
    tp = _positive("tp", tp, 60.0)
    gamma = dnv_gamma(hs, tp) if gamma is None else _check_gamma(gamma)
    w = _omega_array(omega)
    wp = _TWO_PI / tp
    C = jonswap_normalisation(gamma)
    S = C * bretschneider(w, hs, tp) * _peak_factor(w, wp, gamma, sigma_a, sigma_b)
    if exact_hs:
        S = S / _jonswap_unit_m0(gamma, float(sigma_a), float(sigma_b))
    return S


def dnv_tz_over_tp(gamma: float) -> float:
    """DNV-RP-C205 fit Tz/Tp = 0.6673 + 0.05037 g - 0.00623 g^2 + 0.0003341 g^3."""
    g_ = _check_gamma(gamma)
    return 0.6673 + 0.05037 * g_ - 0.00623 * g_**2 + 0.0003341 * g_**3


def fetch_limited_parameters(u10: float, fetch: float, gamma: float = 3.3, g: float = G) -> dict:
    """Parameters of the fetch-limited JONSWAP (Hasselmann 1973, via Ochi).

    ``x~ = g F/U10^2``, ``f_p = 3.5 (g/U10) x~^-0.33`` (Hz), ``alpha = 0.076 x~^-0.22``.
    ``fetch`` in metres, ``u10`` in m/s.  Returns a dict with ``x_tilde``, ``fp``
    (Hz), ``omega_p``, ``tp``, ``alpha``, ``gamma`` and ``hs`` (= 4 sqrt(m0), m0
    integrated numerically to infinity).
    """
    u = _positive("u10", u10)
    F = _positive("fetch", fetch)
    gamma = _check_gamma(gamma)
    xt = g * F / (u * u)
    fp = 3.5 * (g / u) * xt**-0.33
    alpha = 0.076 * xt**-0.22
    wp = _TWO_PI * fp
    # m0 = alpha g^2 wp^-4 * int x^-5 exp(-1.25 x^-4) gamma^r dx
    unit = _jonswap_unit_m0(gamma, 0.07, 0.09) / (5.0 * jonswap_normalisation(gamma))
    m0 = alpha * g * g / wp**4 * unit
    return {"x_tilde": xt, "fp": fp, "omega_p": wp, "tp": 1.0 / fp, "alpha": alpha,
            "gamma": gamma, "hs": 4.0 * math.sqrt(m0)}


def jonswap_fetch_limited(omega, u10: float, fetch: float, gamma: float = 3.3, g: float = G) -> np.ndarray:
    """Fetch-limited JONSWAP ``S = alpha g^2 w^-5 exp(-1.25 (wp/w)^4) gamma^r``.

    See :func:`fetch_limited_parameters`; ``fetch`` in m, ``u10`` in m/s.
    """
    p = fetch_limited_parameters(u10, fetch, gamma, g)
    w = _omega_array(omega)
    wp = p["omega_p"]
    return _pm_shape(w, p["alpha"] * g * g, 1.25 * wp**4) * _peak_factor(w, wp, p["gamma"], 0.07, 0.09)


# --------------------------------------------------------------------------
# Moments
# --------------------------------------------------------------------------
def spectral_moments(omega, S, orders: Sequence[int] = (0, 1, 2), tail: bool = False) -> np.ndarray:
    """Moments ``m_n = int w^n S dw`` of a sampled spectrum (trapezoidal rule).

    ``omega`` must be increasing.  With ``tail=True`` an analytic ``w^-5`` tail
    beyond the last frequency is added, ``S(W) W^(n+1)/(4-n)`` (valid for
    PM/JONSWAP-type spectra and n < 4), which approximates integration to infinity.
    """
    w = np.asarray(omega, dtype=float)
    s = np.asarray(S, dtype=float)
    if w.ndim != 1 or w.shape != s.shape or w.size < 2:
        raise ValueError("omega and S must be 1-D arrays of equal length >= 2")
    if np.any(np.diff(w) <= 0):
        raise ValueError("omega must be strictly increasing")
    out = []
    for n in orders:
        m = float(_trapz(w**n * s, w))
        if tail:
            if n >= 4:
                raise ValueError(f"tail correction diverges for moment order n={n} >= 4")
            m += float(s[-1]) * w[-1] ** (n + 1) / (4.0 - n)
        out.append(m)
    return np.asarray(out)


def integrate_moments(spectrum: Callable[[np.ndarray], np.ndarray], orders: Sequence[int] = (0, 1, 2),
                      omega_min: float = 0.05, omega_max: float = 60.0, n: int = 40001,
                      tail: bool = True) -> np.ndarray:
    """Moments of a spectrum callable on a geometric grid [omega_min, omega_max].

    ``tail=True`` adds the analytic ``w^-5`` tail (see :func:`spectral_moments`),
    so the result approximates integration to infinity.
    """
    w = np.geomspace(_positive("omega_min", omega_min), _positive("omega_max", omega_max), int(n))
    return spectral_moments(w, spectrum(w), orders, tail=tail)


def hm0_from_m0(m0: float) -> float:
    """Hm0 = 4 sqrt(m0)."""
    return 4.0 * math.sqrt(max(float(m0), 0.0))


def tz_from_moments(m0: float, m2: float) -> float:
    """Mean zero-crossing period Tz = 2 pi sqrt(m0/m2)."""
    return _TWO_PI * math.sqrt(m0 / m2)


def t1_from_moments(m0: float, m1: float) -> float:
    """Mean period T1 = 2 pi m0/m1."""
    return _TWO_PI * m0 / m1


# --------------------------------------------------------------------------
# Directional spreading
# --------------------------------------------------------------------------
def _wrap(theta):
    return (np.asarray(theta, dtype=float) + math.pi) % _TWO_PI - math.pi


def cos2s_spreading(theta, s: float, mean: float = 0.0) -> np.ndarray:
    """Longuet-Higgins cos-2s spreading over the full circle (1/rad).

    ``D = Gamma(s+1)/(2 sqrt(pi) Gamma(s+1/2)) cos^(2s)((theta-mean)/2)``; integrates to 1
    over (-pi, pi].  Angles in radians.
    """
    s = _positive("s", s, 1000.0)
    d = _wrap(np.asarray(theta) - mean)
    c = math.exp(math.lgamma(s + 1.0) - math.lgamma(s + 0.5)) / (2.0 * math.sqrt(math.pi))
    return c * np.abs(np.cos(d / 2.0)) ** (2.0 * s)


def cos2s_halfplane_spreading(theta, s: float, mean: float = 0.0) -> np.ndarray:
    """Cosine-power spreading ``D = C cos^(2s)(theta-mean)`` for ``|theta-mean| <= pi/2``, else 0.

    ``C = Gamma(s+1)/(sqrt(pi) Gamma(s+1/2))``; s = 1 gives the reference's
    ``(2/pi) cos^2(theta)`` (DNV cosine-power with n = 2s).  Angles in radians.
    """
    s = _positive("s", s, 1000.0)
    d = _wrap(np.asarray(theta) - mean)
    c = math.exp(math.lgamma(s + 1.0) - math.lgamma(s + 0.5)) / math.sqrt(math.pi)
    return np.where(np.abs(d) <= math.pi / 2, c * np.abs(np.cos(d)) ** (2.0 * s), 0.0)


def spreading_function(theta, s: float, kind: str = "cos2s", mean: float = 0.0) -> np.ndarray:
    """Dispatch to :func:`cos2s_spreading` (``kind='cos2s'``) or
    :func:`cos2s_halfplane_spreading` (``kind='cos2s_halfplane'``)."""
    if kind == "cos2s":
        return cos2s_spreading(theta, s, mean)
    if kind == "cos2s_halfplane":
        return cos2s_halfplane_spreading(theta, s, mean)
    raise ValueError(f"spreading kind must be one of {SPREADING_KINDS}, got {kind!r}")


# --------------------------------------------------------------------------
# Sea-state tables (shared/reference/sea-and-vessel.md section 2)
# --------------------------------------------------------------------------
WMO_SEA_STATE = {
    # code: (description, Hs_min, Hs_max) -- WMO-No. 306, code table 3700
    0: ("calm (glassy)", 0.0, 0.0),
    1: ("calm (rippled)", 0.0, 0.1),
    2: ("smooth", 0.1, 0.5),
    3: ("slight", 0.5, 1.25),
    4: ("moderate", 1.25, 2.5),
    5: ("rough", 2.5, 4.0),
    6: ("very rough", 4.0, 6.0),
    7: ("high", 6.0, 9.0),
    8: ("very high", 9.0, 14.0),
    9: ("phenomenal", 14.0, math.inf),
}

# Lee, Bales & Sowby (1985) via Faltinsen (1990) Table 2.3:
# code: (Hs_mean, (NA Tp 5%, NA Tp 95%), NA most-probable Tp, (NP Tp 5%, NP Tp 95%), NP most-probable Tp)
# None = empty cell in the source.  Code 9 uses the "> 8" row.
LEE_OPEN_OCEAN = {
    0: (0.05, None, None, None, None),
    1: (0.05, None, None, None, None),
    2: (0.3, (3.3, 12.8), 7.5, (5.1, 14.9), 6.3),
    3: (0.88, (5.0, 14.8), 7.5, (5.3, 16.1), 7.5),
    4: (1.88, (6.1, 15.2), 8.8, (6.1, 17.2), 8.8),
    5: (3.25, (8.3, 15.5), 9.7, (7.7, 17.8), 9.7),
    6: (5.0, (9.8, 16.2), 12.4, (10.0, 18.7), 12.4),
    7: (7.5, (11.8, 18.5), 15.0, (11.7, 19.8), 15.0),
    8: (11.5, (14.2, 18.6), 16.4, (14.5, 21.5), 16.4),
    9: (None, (18.0, 23.7), 20.0, (16.4, 22.5), 20.0),
}

# Not in the source (Hs mean of the "> 8" row is an empty cell; WMO 9 is open-ended):
_CODE9_HS_PRESET = 16.0   # deterministic preset Hs for code 9 (assumption)
_CODE9_HS_MAX = 20.0      # upper bound used when sampling code 9 (assumption)

COASTAL_TP_COEFF_RANGE = (3.6, 5.0)
"""Coastal sampler ``Tp = c sqrt(Hs)``, ``c ~ U(3.6, 5.0)`` (reference section 2)."""
COASTAL_TP_COEFF = 4.3
"""Deterministic coastal preset uses the centre of :data:`COASTAL_TP_COEFF_RANGE`."""

_CONVENTIONS = ("open_ocean", "coastal")
_OCEANS = ("north_atlantic", "north_pacific")
_MIN_TP = 0.5


def _check_code(code) -> int:
    if isinstance(code, (bool, np.bool_)):
        raise ValueError(f"code must be an integer sea-state code in 0..9, got {code!r}")
    try:
        c = int(code)
    except (TypeError, ValueError):
        raise ValueError(f"code must be an integer sea-state code in 0..9, got {code!r}") from None
    if c != code or not 0 <= c <= 9:
        raise ValueError(f"code must be an integer sea-state code in 0..9, got {code!r}")
    return c


@dataclass(frozen=True)
class SeaState:
    """A (possibly short-crested) irregular sea state.

    Attributes
    ----------
    hs : float
        Significant wave height Hm0 = 4 sqrt(m0) in m, allowed range [0, 30].
    tp : float
        Peak (modal) period in s, allowed range (0, 60].
    spectrum : str
        ``"jonswap"`` (default), ``"bretschneider"`` (ITTC/ISSC two-parameter) or
        ``"pm"`` (Pierson-Moskowitz in Hs/Tp form; identical to Bretschneider).
    gamma : float or None
        JONSWAP peak enhancement in [1, 10]; ``None`` = DNV default from
        steepness (:func:`dnv_gamma`).  Only valid with ``spectrum="jonswap"``.
    heading_deg : float
        Mean direction in which the waves **propagate**, relative to the ship's
        forward axis (and, in the synthesis, the earth x axis = initial ship
        heading): 180 = head seas, 0 = following seas, 90 = waves travelling to
        port (+y).
    spreading_s : float or None
        Spreading exponent s of the cos-2s distribution; ``None`` = long-crested.
    spreading : str
        ``"cos2s"`` (Longuet-Higgins, ``cos^(2s)(theta/2)`` over the full circle;
        typical wind sea s ~ 10-25, swell s > 50) or ``"cos2s_halfplane"``
        (``cos^(2s)(theta)`` for ``|theta| <= 90 deg``; s = 1 is ``(2/pi) cos^2``).
    exact_hs : bool
        JONSWAP only: rescale so that 4 sqrt(m0) == hs exactly.
    label : str
        Free-text label (e.g. ``"WMO 3, coastal"``); reports should still use (Hs, Tp).
    """

    hs: float
    tp: float
    spectrum: str = "jonswap"
    gamma: Optional[float] = None
    heading_deg: float = 180.0
    spreading_s: Optional[float] = None
    spreading: str = "cos2s"
    exact_hs: bool = False
    label: str = ""

    def __post_init__(self):
        object.__setattr__(self, "hs", _nonneg("hs", self.hs, 30.0))
        object.__setattr__(self, "tp", _positive("tp", self.tp, 60.0))
        if self.spectrum not in SPECTRUM_KINDS:
            raise ValueError(f"spectrum must be one of {SPECTRUM_KINDS}, got {self.spectrum!r}")
        if self.gamma is not None:
            if self.spectrum != "jonswap":
                raise ValueError(f"gamma only applies to spectrum='jonswap', got spectrum={self.spectrum!r}")
            object.__setattr__(self, "gamma", _check_gamma(self.gamma))
        h = float(self.heading_deg)
        if not math.isfinite(h):
            raise ValueError(f"heading_deg must be a finite angle in degrees, got {self.heading_deg!r}")
        object.__setattr__(self, "heading_deg", h)
        if self.spreading_s is not None:
            object.__setattr__(self, "spreading_s", _positive("spreading_s", self.spreading_s, 1000.0))
        if self.spreading not in SPREADING_KINDS:
            raise ValueError(f"spreading must be one of {SPREADING_KINDS}, got {self.spreading!r}")

    # ---- derived quantities ------------------------------------------------
    @property
    def omega_p(self) -> float:
        """Peak angular frequency 2 pi/Tp (rad/s)."""
        return _TWO_PI / self.tp

    @property
    def heading_rad(self) -> float:
        return math.radians(self.heading_deg)

    @property
    def long_crested(self) -> bool:
        return self.spreading_s is None

    @property
    def effective_gamma(self) -> float:
        """Peak enhancement actually used (1 for Bretschneider/PM)."""
        if self.spectrum != "jonswap":
            return 1.0
        return dnv_gamma(self.hs, self.tp) if self.gamma is None else self.gamma

    def density(self, omega) -> np.ndarray:
        """Spectral density S(omega) in m^2 s/rad."""
        if self.spectrum == "jonswap":
            return jonswap(omega, self.hs, self.tp, self.effective_gamma, exact_hs=self.exact_hs)
        return bretschneider(omega, self.hs, self.tp)

    __call__ = density

    def spreading_density(self, theta) -> np.ndarray:
        """Directional distribution D(theta) (1/rad) about the mean direction;
        ``theta`` is the absolute propagation direction in rad (same frame as heading)."""
        if self.spreading_s is None:
            raise ValueError("spreading_s is None: the sea is long-crested")
        return spreading_function(theta, self.spreading_s, self.spreading, self.heading_rad)

    def moments(self, orders: Sequence[int] = (0, 1, 2), omega_range: Optional[tuple] = None) -> np.ndarray:
        """Spectral moments.  Default: integrated to infinity (grid 0.1-20 wp plus
        analytic w^-5 tail).  With ``omega_range=(lo, hi)``: truncated, no tail."""
        if omega_range is None:
            return integrate_moments(self.density, orders, 0.1 * self.omega_p, 20.0 * self.omega_p)
        lo, hi = omega_range
        return integrate_moments(self.density, orders, lo, hi, tail=False)

    @property
    def tz(self) -> float:
        """Mean zero-crossing period 2 pi sqrt(m0/m2) (moments to infinity)."""
        m0, m2 = self.moments((0, 2))
        return tz_from_moments(m0, m2)

    @property
    def t1(self) -> float:
        m0, m1 = self.moments((0, 1))
        return t1_from_moments(m0, m1)

    def describe(self) -> str:
        s = f"Hs={self.hs:.2f} m, Tp={self.tp:.2f} s, {self.spectrum}"
        if self.spectrum == "jonswap":
            s += f" (gamma={self.effective_gamma:.2f})"
        s += f", heading {self.heading_deg:g} deg (propagation; 180 = head)"
        if self.spreading_s is not None:
            s += f", {self.spreading} s={self.spreading_s:g}"
        return s

    def with_(self, **kwargs) -> "SeaState":
        """Copy with fields replaced (validated)."""
        return replace(self, **kwargs)

    # ---- constructors ------------------------------------------------------
    @classmethod
    def from_wind(cls, u195: float, **kwargs) -> "SeaState":
        """Fully developed Pierson-Moskowitz sea from the wind speed at 19.5 m."""
        return cls(hs=pm_hs_from_wind(u195), tp=pm_tp_from_wind(u195), spectrum="pm", **kwargs)

    @classmethod
    def from_fetch(cls, u10: float, fetch: float, gamma: float = 3.3, **kwargs) -> "SeaState":
        """Fetch-limited JONSWAP (Hasselmann 1973) as an exact-Hs JONSWAP SeaState.

        With ``exact_hs=True`` the JONSWAP shape is identical to
        :func:`jonswap_fetch_limited`.
        """
        p = fetch_limited_parameters(u10, fetch, gamma)
        kwargs.setdefault("label", f"fetch-limited U10={u10:g} m/s, F={fetch / 1000:g} km")
        return cls(hs=p["hs"], tp=p["tp"], spectrum="jonswap", gamma=gamma, exact_hs=True, **kwargs)

    @classmethod
    def from_code(cls, code: int, convention: str = "open_ocean", *, rng: Optional[np.random.Generator] = None,
                  ocean: str = "north_atlantic", tp_coeff: Optional[float] = None, **kwargs) -> "SeaState":
        """Preset from the WMO sea-state code (0-9).

        Deterministic (``rng=None``):

        * Hs = Lee et al. (1985) mean Hs for the code (0.05 m for codes 0-1 except
          code 0 -> 0; code 9 -> 16 m, an assumption: that cell is empty).
        * ``convention="open_ocean"``: Tp = most-probable modal period of Lee et
          al. (Faltinsen Table 2.3), ``ocean="north_atlantic"`` (default) or
          ``"north_pacific"``.  Codes 0-1 have no Tp in the table; the fully
          developed PM period 4.99 sqrt(Hs) (of Hs = 0.05 m) is used.
        * ``convention="coastal"``: fetch-limited rule ``Tp = c sqrt(Hs)``, c =
          ``tp_coeff`` or 4.3 (centre of the U(3.6, 5.0) range); Tp >= 0.5 s.

        Random (``rng`` a ``numpy.random.Generator``): Hs ~ U(WMO range) (code 9:
        U(14, 20), an assumption); open ocean Tp ~ triangular(5 %, most probable,
        95 %) of Lee et al.; coastal Tp = c sqrt(Hs), c ~ U(3.6, 5.0).

        Other keyword arguments (``spectrum``, ``gamma``, ``heading_deg``,
        ``spreading_s``, ...) are passed to :class:`SeaState`.  The default
        spectrum is JONSWAP with the DNV gamma from steepness.
        """
        c = _check_code(code)
        if convention not in _CONVENTIONS:
            raise ValueError(f"convention must be one of {_CONVENTIONS}, got {convention!r}")
        if ocean not in _OCEANS:
            raise ValueError(f"ocean must be one of {_OCEANS}, got {ocean!r}")
        if tp_coeff is not None:
            tp_coeff = _positive("tp_coeff", tp_coeff, 10.0)
        if rng is not None and not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy.random.Generator or None, got {type(rng).__name__}")
        desc, hs_lo, hs_hi = WMO_SEA_STATE[c]
        hs_mean, na_rng, na_mp, np_rng, np_mp = LEE_OPEN_OCEAN[c]
        tp_rng, tp_mp = (na_rng, na_mp) if ocean == "north_atlantic" else (np_rng, np_mp)

        # --- Hs
        if c == 0:
            hs = 0.0
        elif rng is None:
            hs = hs_mean if hs_mean is not None else _CODE9_HS_PRESET
        else:
            hi = hs_hi if math.isfinite(hs_hi) else _CODE9_HS_MAX
            hs = float(rng.uniform(hs_lo, hi))

        # --- Tp
        if convention == "open_ocean" and tp_rng is not None:
            if rng is None:
                tp = tp_mp
            else:
                tp = float(rng.triangular(tp_rng[0], tp_mp, tp_rng[1]))
        elif convention == "open_ocean":  # codes 0-1: fully developed PM
            tp = pm_tp_from_hs(max(hs, 0.05))
        else:
            if tp_coeff is not None:
                coeff = tp_coeff
            elif rng is None:
                coeff = COASTAL_TP_COEFF
            else:
                coeff = float(rng.uniform(*COASTAL_TP_COEFF_RANGE))
            tp = max(coeff * math.sqrt(max(hs, 0.05)), _MIN_TP)

        kwargs.setdefault("label", f"WMO {c} ({desc}), {convention.replace('_', ' ')}")
        return cls(hs=hs, tp=tp, **kwargs)
