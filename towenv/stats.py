"""Motion statistics: amplitudes, extremes, spectra, transfer functions, rate limits.

Conventions (``shared/reference/sea-and-vessel.md`` sections 0 and 6)
----------------------------------------------------------------------
* ``m0`` is the variance of the (zero-mean) response, ``m_n = int w^n S(w) dw``
  with ``w`` in rad/s and one-sided ``S`` in units^2 s/rad.
* **Amplitude** means a single amplitude (crest above the mean).  **Height**
  means a double amplitude (crest-to-trough).  ``significant_amplitude`` is
  ``2 sqrt(m0)``; ``significant_height`` (= Hs for waves) is ``4 sqrt(m0)``.
* Closed forms assume a narrow-band Gaussian process, whose amplitudes are
  Rayleigh distributed with ``P(A > a) = exp(-a^2/(2 m0))``.

numpy only, except :func:`welch_psd` and :func:`estimate_rao`, which use
``scipy.signal`` (imported lazily).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Optional, Sequence

import numpy as np

__all__ = [
    "RATE_LIMITS",
    "rms",
    "variance",
    "significant_amplitude",
    "significant_height",
    "rayleigh_exceedance_level",
    "rayleigh_mean_of_highest",
    "rayleigh_mean_amplitude",
    "amplitude_statistics",
    "most_probable_maximum",
    "zero_crossing_period",
    "ZeroCrossingResult",
    "zero_crossing_analysis",
    "mean_of_highest",
    "empirical_amplitude_statistics",
    "welch_psd",
    "psd_moments",
    "hm0_from_psd",
    "RAOEstimate",
    "estimate_rao",
    "RateLimitResult",
    "rate_limit_check",
]

_TWO_PI = 2.0 * math.pi

# Sonar motion-rate limits used to score the full-scale trials.
# Source: thesis Table 6.1, ranmuthugala-2000 L6275-6280
# (shared/reference/data/table_6_1_rate_limits.csv).
RATE_LIMITS: dict[str, tuple[float, str]] = {
    "surge": (1.0, "m/s"),     # L6275
    "sway": (1.0, "m/s"),      # L6276
    "heave": (1.0, "m/s"),     # L6277
    "roll": (6.28, "deg/s"),   # L6278
    "pitch": (6.28, "deg/s"),  # L6279
    "yaw": (1.05, "deg/s"),    # L6280
}


def _as_1d(x, name: str = "x") -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array")
    return a


def _m0_arg(x, m0) -> float:
    if (x is None) == (m0 is None):
        raise ValueError("give exactly one of x (a record) or m0 (a variance)")
    if m0 is None:
        return variance(x)
    m0 = float(m0)
    if not math.isfinite(m0) or m0 < 0:
        raise ValueError(f"m0 must be a finite variance >= 0, got {m0!r}")
    return m0


def _fraction(fraction) -> float:
    p = float(fraction)
    if not 0.0 < p <= 1.0:
        raise ValueError(f"fraction must be in (0, 1], got {fraction!r}")
    return p


# --------------------------------------------------------------------------
# moments of a record and Rayleigh closed forms
# --------------------------------------------------------------------------
def rms(x, demean: bool = False, axis=None) -> np.ndarray:
    """Root-mean-square of ``x`` (about zero, or about the mean with ``demean=True``)."""
    a = np.asarray(x, dtype=float)
    if demean:
        a = a - np.mean(a, axis=axis, keepdims=True)
    return np.sqrt(np.mean(a * a, axis=axis))


def variance(x) -> float:
    """m0 of a record: its variance about the mean."""
    a = _as_1d(x)
    return float(np.var(a))


def significant_amplitude(x=None, *, m0: Optional[float] = None) -> float:
    """Significant (single) amplitude ``2 sqrt(m0)``; ``m0`` from the record's variance
    or given directly.  (The exact Rayleigh mean of the 1/3 highest amplitudes is
    2.0026 sqrt(m0); see :func:`rayleigh_mean_of_highest`.)"""
    return 2.0 * math.sqrt(_m0_arg(x, m0))


def significant_height(x=None, *, m0: Optional[float] = None) -> float:
    """Significant height (double amplitude) ``4 sqrt(m0)`` = Hm0 for waves."""
    return 4.0 * math.sqrt(_m0_arg(x, m0))


def rayleigh_exceedance_level(fraction: float, m0: float = 1.0) -> float:
    """Amplitude exceeded by ``fraction`` of Rayleigh amplitudes: ``sqrt(2 m0 ln(1/p))``
    (3.72 sqrt(m0) for p = 1/1000)."""
    p = _fraction(fraction)
    return math.sqrt(2.0 * float(m0) * math.log(1.0 / p))


def rayleigh_mean_of_highest(fraction: float, m0: float = 1.0) -> float:
    """Mean of the highest ``fraction`` of Rayleigh amplitudes (exact closed form).

    With ``a_p = sqrt(2 m0 ln(1/p))``::

        E[A | A > a_p] = a_p + sqrt(2 m0) (sqrt(pi)/2) erfc(sqrt(ln(1/p))) / p

    giving 2.0026, 2.5450, 3.3360, 3.9662 sqrt(m0) for p = 1/3, 1/10, 1/100, 1/1000,
    and 1.2533 sqrt(m0) (the mean amplitude) for p = 1.
    """
    p = _fraction(fraction)
    m0 = float(m0)
    L = math.log(1.0 / p)
    return math.sqrt(2.0 * m0) * (math.sqrt(L) + 0.5 * math.sqrt(math.pi) * math.erfc(math.sqrt(L)) / p)


def rayleigh_mean_amplitude(m0: float = 1.0) -> float:
    """Mean Rayleigh amplitude ``sqrt(pi m0/2)`` = 1.2533 sqrt(m0)."""
    return math.sqrt(math.pi * float(m0) / 2.0)


def amplitude_statistics(m0: float) -> dict:
    """Closed-form narrow-band statistics of a response with variance ``m0``.

    Keys: ``rms``, ``significant_amplitude`` (2 sqrt m0), ``significant_height``
    (4 sqrt m0), ``mean_amplitude``, ``mean_1_3``, ``mean_1_10``, ``mean_1_100``,
    ``mean_1_1000`` (means of the highest fractions of amplitudes) and
    ``level_1_1000`` (amplitude exceeded by 1/1000 of amplitudes).
    """
    m0 = _m0_arg(None, m0)
    return {
        "rms": math.sqrt(m0),
        "significant_amplitude": 2.0 * math.sqrt(m0),
        "significant_height": 4.0 * math.sqrt(m0),
        "mean_amplitude": rayleigh_mean_amplitude(m0),
        "mean_1_3": rayleigh_mean_of_highest(1 / 3, m0),
        "mean_1_10": rayleigh_mean_of_highest(1 / 10, m0),
        "mean_1_100": rayleigh_mean_of_highest(1 / 100, m0),
        "mean_1_1000": rayleigh_mean_of_highest(1 / 1000, m0),
        "level_1_1000": rayleigh_exceedance_level(1 / 1000, m0),
    }


def zero_crossing_period(m0: float, m2: float) -> float:
    """Mean zero-crossing period ``Tz = 2 pi sqrt(m0/m2)`` (s)."""
    return _TWO_PI * math.sqrt(float(m0) / float(m2))


def most_probable_maximum(m0: float, n_cycles: Optional[float] = None, *, duration: Optional[float] = None,
                          tz: Optional[float] = None) -> float:
    """Most probable largest amplitude ``sqrt(2 m0 ln N)``.

    Give either ``n_cycles`` (N) or ``duration`` and ``tz`` (N = duration/Tz).
    For Rayleigh amplitudes this level is the ``(1 - 1/N)^N ~ e^-1`` quantile of
    the maximum (37 % of episodes stay below it).
    """
    m0 = _m0_arg(None, m0)
    if n_cycles is None:
        if duration is None or tz is None:
            raise ValueError("give n_cycles, or both duration and tz")
        n_cycles = float(duration) / float(tz)
    elif duration is not None or tz is not None:
        raise ValueError("give n_cycles, or duration and tz, not both")
    N = float(n_cycles)
    if not N >= 1.0:
        raise ValueError(f"number of cycles must be >= 1, got {N!r}")
    return math.sqrt(2.0 * m0 * math.log(N))


# --------------------------------------------------------------------------
# empirical, from a record
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class ZeroCrossingResult:
    """Per-wave quantities between consecutive zero up-crossings (about the mean).

    ``crests`` (max above the mean, the single amplitudes), ``troughs``
    (depth of the min below the mean, positive), ``heights`` (crest-to-trough),
    ``periods`` (s, interpolated crossing times) and mean period ``tz`` (s).
    """

    crests: np.ndarray
    troughs: np.ndarray
    heights: np.ndarray
    periods: np.ndarray
    mean: float

    @property
    def n_waves(self) -> int:
        return self.crests.size

    @property
    def tz(self) -> float:
        return float(np.mean(self.periods)) if self.periods.size else math.nan


def zero_crossing_analysis(x, dt: float = 1.0, demean: bool = True) -> ZeroCrossingResult:
    """Split a record into zero-up-crossing waves and return their crests,
    troughs, heights and periods.  Incomplete waves at the ends are dropped."""
    a = _as_1d(x)
    mean = float(np.mean(a)) if demean else 0.0
    a = a - mean
    up = np.flatnonzero((a[:-1] < 0.0) & (a[1:] >= 0.0))
    if up.size < 2:
        e = np.empty(0)
        return ZeroCrossingResult(e, e, e, e, mean)
    # interpolated crossing times
    tc = (up + a[up] / (a[up] - a[up + 1])) * float(dt)
    starts = up + 1
    crests = np.maximum.reduceat(a, starts)[:-1]
    troughs = -np.minimum.reduceat(a, starts)[:-1]
    return ZeroCrossingResult(crests, troughs, crests + troughs, np.diff(tc), mean)


def mean_of_highest(values, fraction: float) -> float:
    """Mean of the highest ``fraction`` of ``values`` (the top ``floor(n p)``).

    Raises ValueError if fewer than ``1/fraction`` values are available."""
    v = _as_1d(values, "values")
    p = _fraction(fraction)
    k = int(math.floor(v.size * p + 1e-9))
    if k < 1:
        raise ValueError(f"need at least {math.ceil(1 / p)} values for fraction {p:g}, got {v.size}")
    return float(np.mean(np.partition(v, v.size - k)[v.size - k:]))


def empirical_amplitude_statistics(x, dt: float = 1.0, fractions: Sequence[float] = (1 / 3, 1 / 10, 1 / 1000),
                                   amplitude: str = "crest") -> dict:
    """Empirical amplitude statistics of a record from zero-crossing waves.

    ``amplitude="crest"`` uses the crest of each wave (default),
    ``"half_height"`` half its crest-to-trough height.  Returns ``rms``
    (about the mean), ``significant_amplitude`` (2 sqrt(variance)), ``n_waves``,
    ``tz`` and ``mean_1_<n>`` for each fraction (NaN when the record has fewer
    than 1/fraction waves), plus ``max_amplitude``.
    """
    zc = zero_crossing_analysis(x, dt)
    if amplitude == "crest":
        amps = zc.crests
    elif amplitude == "half_height":
        amps = 0.5 * zc.heights
    else:
        raise ValueError(f"amplitude must be 'crest' or 'half_height', got {amplitude!r}")
    out = {"rms": float(rms(x, demean=True)), "significant_amplitude": significant_amplitude(x),
           "n_waves": zc.n_waves, "tz": zc.tz,
           "max_amplitude": float(amps.max()) if amps.size else math.nan}
    for p in fractions:
        key = f"mean_1_{round(1 / p)}"
        try:
            out[key] = mean_of_highest(amps, p)
        except ValueError:
            out[key] = math.nan
    return out


# --------------------------------------------------------------------------
# spectra
# --------------------------------------------------------------------------
def _default_nperseg(n: int) -> int:
    """Largest power of two giving >= 8 half-overlapping segments (>= 16 samples)."""
    target = max(16, (2 * n) // 9)
    return max(16, min(n, 1 << int(math.floor(math.log2(target)))))


def welch_psd(x, dt: float, nperseg: Optional[int] = None, noverlap: Optional[int] = None,
              window: str = "hann", detrend: str = "constant") -> tuple[np.ndarray, np.ndarray]:
    """One-sided Welch PSD in angular-frequency units.

    Returns ``(omega, S)`` with ``omega = 2 pi f`` in rad/s and ``S(omega) =
    P(f)/(2 pi)`` in units^2 s/rad, so ``int S d omega = variance`` (m0).
    Wraps ``scipy.signal.welch(x, fs=1/dt, window, nperseg, noverlap=nperseg//2,
    detrend, scaling="density")``.  Default ``nperseg``: the largest power of two
    that still gives >= 8 half-overlapping segments; the reference advises
    ``nperseg*dt >= ~20 Tp``.
    """
    from scipy import signal

    a = _as_1d(x)
    dt = float(dt)
    if not dt > 0:
        raise ValueError(f"dt must be > 0 s, got {dt!r}")
    if nperseg is None:
        nperseg = _default_nperseg(a.size)
    nperseg = int(min(nperseg, a.size))
    if noverlap is None:
        noverlap = nperseg // 2
    f, P = signal.welch(a, fs=1.0 / dt, window=window, nperseg=nperseg, noverlap=noverlap,
                        detrend=detrend, scaling="density")
    return _TWO_PI * f, P / _TWO_PI


def psd_moments(omega, S, orders: Sequence[int] = (0, 1, 2)) -> np.ndarray:
    """Moments ``int w^n S dw`` of a one-sided PSD (trapezoidal rule)."""
    w = _as_1d(omega, "omega")
    s = _as_1d(S, "S")
    if w.shape != s.shape:
        raise ValueError("omega and S must have the same length")
    out = []
    for n in orders:
        y = w**n * s
        out.append(float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(w))))
    return np.asarray(out)


def hm0_from_psd(omega, S) -> float:
    """Hm0 = 4 sqrt(m0) of a one-sided PSD in rad/s units."""
    return 4.0 * math.sqrt(max(psd_moments(omega, S, (0,))[0], 0.0))


@dataclass(frozen=True)
class RAOEstimate:
    """H1 transfer-function estimate.

    ``omega`` (rad/s); complex ``rao`` = ``P_io/P_ii``; ``gain`` = ``|rao|``;
    ``phase`` = ``angle(rao)`` (rad, positive = output leads: input
    ``cos(w t)`` -> output ``gain cos(w t + phase)``); ``coherence`` in [0, 1];
    ``psd_in``, ``psd_out`` in units^2 s/rad.
    """

    omega: np.ndarray
    rao: np.ndarray
    coherence: np.ndarray
    psd_in: np.ndarray
    psd_out: np.ndarray

    @property
    def gain(self) -> np.ndarray:
        return np.abs(self.rao)

    @property
    def phase(self) -> np.ndarray:
        return np.angle(self.rao)

    def reliable(self, min_coherence: float = 0.9) -> np.ndarray:
        """Boolean mask of frequencies with coherence >= ``min_coherence``."""
        return self.coherence >= min_coherence


def estimate_rao(x_in, y_out, dt: float, nperseg: Optional[int] = None, noverlap: Optional[int] = None,
                 window: str = "hann", detrend: str = "constant") -> RAOEstimate:
    """Estimate the transfer function from input ``x_in`` to output ``y_out``.

    H1 estimator ``H = P_io/P_ii`` (``scipy.signal.csd`` over ``scipy.signal.welch``),
    with magnitude-squared coherence ``|P_io|^2/(P_ii P_oo)`` to flag noise or
    nonlinearity.  Welch settings as in :func:`welch_psd`.  Frequencies where
    the input has no power give NaN.
    """
    from scipy import signal

    x = _as_1d(x_in, "x_in")
    y = _as_1d(y_out, "y_out")
    if x.shape != y.shape:
        raise ValueError("x_in and y_out must have the same length")
    dt = float(dt)
    if not dt > 0:
        raise ValueError(f"dt must be > 0 s, got {dt!r}")
    if nperseg is None:
        nperseg = _default_nperseg(x.size)
    nperseg = int(min(nperseg, x.size))
    if noverlap is None:
        noverlap = nperseg // 2
    kw = dict(fs=1.0 / dt, window=window, nperseg=nperseg, noverlap=noverlap, detrend=detrend, scaling="density")
    f, Pxx = signal.welch(x, **kw)
    _, Pyy = signal.welch(y, **kw)
    _, Pxy = signal.csd(x, y, **kw)  # conj(X) * Y
    with np.errstate(divide="ignore", invalid="ignore"):
        H = np.where(Pxx > 0, Pxy / Pxx, np.nan + 0j)
        coh = np.where((Pxx > 0) & (Pyy > 0), np.abs(Pxy) ** 2 / (Pxx * Pyy), np.nan)
    return RAOEstimate(_TWO_PI * f, H, np.clip(coh, 0.0, 1.0), Pxx / _TWO_PI, Pyy / _TWO_PI)


# --------------------------------------------------------------------------
# rate limits (thesis Table 6.1)
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class RateLimitResult:
    """Outcome of a rate-limit check for one motion, in the table's unit
    (m/s for surge/sway/heave, deg/s for roll/pitch/yaw)."""

    motion: str
    limit: float
    unit: str
    max_abs: float
    fraction_over: float  # fraction of samples with |rate| > limit

    @property
    def exceeded(self) -> bool:
        return self.max_abs > self.limit

    @property
    def ok(self) -> bool:
        return not self.exceeded


def rate_limit_check(rates: Mapping[str, object], *, angular_unit: str = "rad/s",
                     limits: Optional[Mapping[str, tuple[float, str]]] = None) -> dict[str, RateLimitResult]:
    """Check motion rates against the sonar limits of thesis Table 6.1.

    Parameters
    ----------
    rates : mapping
        Keys from ``surge, sway, heave, roll, pitch, yaw`` (case-insensitive);
        values are a scalar or a time series of rates.  Translational rates in
        m/s; angular rates in ``angular_unit``.
    angular_unit : "rad/s" (default, SI as used by the simulator) or "deg/s".
    limits : mapping, optional
        Override of :data:`RATE_LIMITS` (``motion -> (limit, unit)``).

    Returns ``{motion: RateLimitResult}`` with the peak ``|rate|`` and the
    fraction of samples over the limit (the "percentage of time over the rate
    limits" metric, as a fraction).
    """
    if angular_unit not in ("rad/s", "deg/s"):
        raise ValueError(f"angular_unit must be 'rad/s' or 'deg/s', got {angular_unit!r}")
    table = dict(RATE_LIMITS if limits is None else limits)
    out: dict[str, RateLimitResult] = {}
    for key, value in rates.items():
        motion = str(key).lower()
        if motion not in table:
            raise ValueError(f"rates key {key!r} is not one of {tuple(table)}")
        limit, unit = table[motion]
        r = np.abs(np.asarray(value, dtype=float)).ravel()
        if r.size == 0 or not np.all(np.isfinite(r)):
            raise ValueError(f"rates[{key!r}] must be a non-empty array of finite values")
        if unit == "deg/s" and angular_unit == "rad/s":
            r = np.degrees(r)
        out[motion] = RateLimitResult(motion, float(limit), unit, float(r.max()), float(np.mean(r > limit)))
    return out
