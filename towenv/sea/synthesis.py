"""Random-phase synthesis of irregular sea surfaces and their kinematics.

The surface is a sum of ``M`` regular components (Faltinsen eqs. 2.22-2.23)::

    eta(t, x, y) = sum_j a_j cos(omega_j t - k_j (x cos th_j + y sin th_j) + phi_j)

in an **earth frame** with x along the ship's initial heading, y to port, z up
(``shared/reference/sea-and-vessel.md`` section 0).  ``th_j`` is the direction in
which component j *propagates*; a :class:`~towenv.sea.spectra.SeaState` with
``heading_deg = 180`` therefore propagates towards -x: head seas for a ship
steaming along +x.

Frequencies are jittered inside uniform bins, so the record has no
``2 pi/d omega`` repetition (its exact repetition period is infinite).  The
amplitude of each component carries the spectral energy of its whole bin
(``a_j = sqrt(2 int_bin S d omega)``, "DAS": deterministic amplitudes, so every
realisation has exactly the target variance over the band) or, with
``amplitudes="ras"``, a Rayleigh-distributed random amplitude with the same
mean energy.

Moving observers: the encounter frequency is *not* built into a grid; it lives
in the phase.  A ship at earth position ``(x_s(t), y_s(t))`` sees
``phase_j(t) = omega_j t - k_j (x_s cos th_j + y_s sin th_j) + phi_j``; with
``x_s`` the integrated ship position this is continuous when speed or heading
change and contains the Doppler shift ``omega_e = omega - k U cos(beta)`` exactly.

All randomness comes from a ``numpy.random.Generator`` (``seed`` may be an int,
a SeedSequence or a Generator such as an environment's ``np_random``).  Only
numpy is used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional, Sequence, Union

import numpy as np

from .spectra import G, SeaState

__all__ = [
    "WaveRecord",
    "GriddedWave",
    "synthesize",
    "wavenumber",
    "integrate_track",
    "default_omega_range",
]

_TWO_PI = 2.0 * math.pi
_CHUNK_ELEMS = 1 << 20  # rows*components per evaluation chunk (~8 MB of float64)

# 8-point Gauss-Legendre rule used to integrate S over each frequency bin.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)

Track = Union[tuple, Callable[[np.ndarray], tuple]]


# --------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------
def wavenumber(omega, depth: Optional[float] = None, g: float = G) -> np.ndarray:
    """Wavenumber from the linear dispersion relation ``omega^2 = g k tanh(k h)``.

    ``depth=None`` (or inf) gives deep water ``k = omega^2/g``.  Finite depth is
    solved by vectorised Newton iteration (relative accuracy ~1e-13).
    """
    w = np.asarray(omega, dtype=float)
    k_deep = w * w / g
    if depth is None or not math.isfinite(depth):
        return k_deep
    h = float(depth)
    if h <= 0:
        raise ValueError(f"depth must be > 0 m (or None for deep water), got {depth!r}")
    with np.errstate(divide="ignore", invalid="ignore"):
        # Eckart (1952) approximation as the starting guess (error < 5 %)
        k = np.where(w > 0, k_deep / np.sqrt(np.tanh(k_deep * h)), 0.0)
    for _ in range(50):
        th = np.tanh(k * h)
        f = g * k * th - w * w
        df = g * th + g * k * h * (1.0 - th * th)
        dk = np.where(df > 0, f / np.where(df > 0, df, 1.0), 0.0)
        k = k - dk
        if np.all(np.abs(dk) <= 1e-14 * np.maximum(k, 1e-30)):
            break
    return k


def default_omega_range(sea_state: SeaState) -> tuple[float, float]:
    """Default synthesis band ``[0.3 omega_p, 5 omega_p]`` (rad/s).

    For PM/JONSWAP spectra the energy outside it is < 0.2 % of m0 (the
    ``omega^-5`` tail above ``5 omega_p`` holds ``1.25/5^4 = 0.2 %`` of a PM m0).
    """
    wp = sea_state.omega_p
    return 0.3 * wp, 5.0 * wp


def integrate_track(t, speed, heading, x0: float = 0.0, y0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Integrate a ship's earth-frame position from speed and heading histories.

    Parameters
    ----------
    t : array (n,)
        Increasing times (s).
    speed : float or array (n,)
        Speed over ground (m/s).
    heading : float or array (n,)
        Ship heading psi in **radians**, measured from the earth x axis towards
        +y (right-handed about z up).  ``psi = 0`` is the initial ship axis.
    x0, y0 : float
        Position at ``t[0]``.

    Returns ``(x, y)`` by the cumulative trapezoidal rule; the positions are
    continuous whatever the speed/heading history, which is what keeps the
    encountered wave phase continuous.
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 1:
        raise ValueError("t must be a 1-D array")
    U = np.broadcast_to(np.asarray(speed, dtype=float), t.shape)
    psi = np.broadcast_to(np.asarray(heading, dtype=float), t.shape)
    vx, vy = U * np.cos(psi), U * np.sin(psi)
    dt = np.diff(t)
    x = np.concatenate(([0.0], np.cumsum(0.5 * (vx[1:] + vx[:-1]) * dt))) + x0
    y = np.concatenate(([0.0], np.cumsum(0.5 * (vy[1:] + vy[:-1]) * dt))) + y0
    return x, y


def _as_generator(seed) -> np.random.Generator:
    if isinstance(seed, np.random.Generator):
        return seed
    if isinstance(seed, np.random.RandomState):
        raise ValueError("seed must be an int, SeedSequence or numpy.random.Generator (not the legacy RandomState)")
    return np.random.default_rng(seed)


def _flat(*arrays):
    arrs = np.broadcast_arrays(*[np.asarray(a, dtype=float) for a in arrays])
    return arrs[0].shape, [np.ascontiguousarray(a).ravel() for a in arrs]


# --------------------------------------------------------------------------
# the record
# --------------------------------------------------------------------------
class WaveRecord:
    """A realisation of an irregular sea as ``M`` regular components.

    Arrays (read-only, shape ``(M,)``): ``omega`` (rad/s), ``k`` (rad/m),
    ``amplitude`` (m), ``phase`` (rad), ``direction`` (propagation direction
    in the earth frame, rad).  All evaluation methods are vectorised over time
    and accept observer positions that are scalars or arrays broadcastable to
    ``t``; work is chunked so memory stays bounded for hours-long records.
    """

    def __init__(self, omega, amplitude, phase, direction, *, depth: Optional[float] = None, g: float = G,
                 duration: float = math.inf, repeat_period: float = math.inf,
                 sea_states: Sequence[SeaState] = (), seed=None):
        omega = np.asarray(omega, dtype=float).ravel()
        M = omega.size
        amplitude = np.broadcast_to(np.asarray(amplitude, dtype=float), (M,)).copy()
        phase = np.broadcast_to(np.asarray(phase, dtype=float), (M,)).copy()
        direction = np.broadcast_to(np.asarray(direction, dtype=float), (M,)).copy()
        if np.any(omega <= 0) or not np.all(np.isfinite(omega)):
            raise ValueError("omega must be finite and > 0")
        if np.any(amplitude < 0) or not np.all(np.isfinite(amplitude)):
            raise ValueError("amplitude must be finite and >= 0")
        self.depth = None if depth is None or not math.isfinite(depth) else float(depth)
        self.g = float(g)
        k = wavenumber(omega, self.depth, self.g)
        self.omega, self.amplitude, self.phase, self.direction, self.k = omega, amplitude, phase, direction, k
        self.kx = k * np.cos(direction)
        self.ky = k * np.sin(direction)
        for a in (self.omega, self.amplitude, self.phase, self.direction, self.k, self.kx, self.ky):
            a.setflags(write=False)
        self.duration = float(duration)
        self.repeat_period = float(repeat_period)
        self.sea_states = tuple(sea_states)
        self.seed = seed

    # ---- summary -----------------------------------------------------------
    @property
    def n_components(self) -> int:
        return self.omega.size

    @property
    def variance(self) -> float:
        """Ensemble variance of eta, ``sum a_j^2 / 2`` (m^2) = m0 of the band."""
        return float(0.5 * np.sum(self.amplitude**2))

    @property
    def hm0(self) -> float:
        """4 sqrt(variance): the Hs this realisation carries (DAS: the band's Hm0)."""
        return 4.0 * math.sqrt(self.variance)

    def __add__(self, other: "WaveRecord") -> "WaveRecord":
        """Superpose two records (e.g. wind sea + swell); depth and g must match."""
        if not isinstance(other, WaveRecord):
            return NotImplemented
        if self.depth != other.depth or self.g != other.g:
            raise ValueError("cannot add WaveRecords with different depth or g")
        return WaveRecord(np.concatenate((self.omega, other.omega)),
                          np.concatenate((self.amplitude, other.amplitude)),
                          np.concatenate((self.phase, other.phase)),
                          np.concatenate((self.direction, other.direction)),
                          depth=self.depth, g=self.g, duration=min(self.duration, other.duration),
                          repeat_period=min(self.repeat_period, other.repeat_period),
                          sea_states=self.sea_states + other.sea_states, seed=None)

    def __repr__(self) -> str:
        return (f"WaveRecord(M={self.n_components}, Hm0={self.hm0:.3f} m, duration={self.duration:g} s, "
                f"depth={self.depth}, seed={self.seed!r})")

    # ---- encounter ---------------------------------------------------------
    def relative_direction(self, heading: float = 0.0) -> np.ndarray:
        """Per-component relative wave direction ``beta_j = th_j - psi`` (rad, wrapped to
        (-pi, pi]); ``psi`` = ship heading in the earth frame (rad).  pi = head seas."""
        return (self.direction - heading + math.pi) % _TWO_PI - math.pi

    def encounter_frequency(self, speed: float, heading: float = 0.0) -> np.ndarray:
        """Signed encounter frequencies ``omega_e = omega - k U cos(beta)`` (rad/s).

        Use these for quasi-steady RAO look-up; the phase itself should come from
        :meth:`phases` with the integrated ship position.  Do not take ``|omega_e|``
        if RAO phases are applied (see reference section 3)."""
        return self.omega - self.k * speed * np.cos(self.direction - heading)

    # ---- core kernels ------------------------------------------------------
    def _rows(self) -> int:
        return max(1, _CHUNK_ELEMS // max(self.n_components, 1))

    def _phase_block(self, t, x, y) -> np.ndarray:
        P = np.multiply.outer(t, self.omega)
        if np.any(x):
            P -= np.multiply.outer(x, self.kx)
        if np.any(y):
            P -= np.multiply.outer(y, self.ky)
        P += self.phase
        return P

    def phases(self, t, x=0.0, y=0.0) -> np.ndarray:
        """Component phases, shape ``broadcast(t, x, y).shape + (M,)``.

        ``phase_j = omega_j t - kx_j x - ky_j y + phi_j``.  Not chunked: use for
        modest sizes (e.g. a single step or a short window)."""
        shape, (t, x, y) = _flat(t, x, y)
        return self._phase_block(t, x, y).reshape(shape + (self.n_components,))

    def elevation(self, t, x=0.0, y=0.0) -> np.ndarray:
        """Free-surface elevation eta (m) at times ``t`` and earth positions ``(x, y)``.

        ``x``/``y`` may be arrays matching ``t`` (an observer's track); see also
        :meth:`elevation_along`.  Returns an array of the broadcast shape
        (a 0-d array for scalar input)."""
        shape, (t, x, y) = _flat(t, x, y)
        out = np.empty(t.size)
        r = self._rows()
        for i in range(0, t.size, r):
            sl = slice(i, i + r)
            out[sl] = np.cos(self._phase_block(t[sl], x[sl], y[sl])) @ self.amplitude
        return out.reshape(shape)

    def elevation_rate(self, t, x=0.0, y=0.0, vx=0.0, vy=0.0) -> np.ndarray:
        """Time derivative of eta seen by an observer at ``(x, y)`` moving with
        earth-frame velocity ``(vx, vy)``: ``-sum a (omega - kx vx - ky vy) sin(phase)``."""
        shape, (t, x, y, vx, vy) = _flat(t, x, y, vx, vy)
        out = np.empty(t.size)
        aw, akx, aky = self.amplitude * self.omega, self.amplitude * self.kx, self.amplitude * self.ky
        r = self._rows()
        for i in range(0, t.size, r):
            sl = slice(i, i + r)
            S = np.sin(self._phase_block(t[sl], x[sl], y[sl]))
            v = -(S @ aw)
            if np.any(vx[sl]):
                v += vx[sl] * (S @ akx)
            if np.any(vy[sl]):
                v += vy[sl] * (S @ aky)
            out[sl] = v
        return out.reshape(shape)

    def elevation_along(self, t, track: Track) -> np.ndarray:
        """Elevation seen by a moving observer.

        ``track`` is either ``(x, y)`` arrays matching ``t`` (earth-frame positions,
        e.g. from :func:`integrate_track`) or a callable ``track(t) -> (x, y)``.
        """
        x, y = _resolve_track(t, track)
        return self.elevation(t, x, y)

    def elevation_at(self, t: float, x: float = 0.0, y: float = 0.0) -> float:
        """Scalar fast path of :meth:`elevation` (one physics step; ~5 us for M = 300)."""
        return float(np.cos(self.omega * t - self.kx * x - self.ky * y + self.phase) @ self.amplitude)

    def elevation_and_rate_at(self, t: float, x: float = 0.0, y: float = 0.0, vx: float = 0.0,
                              vy: float = 0.0) -> tuple[float, float]:
        """Scalar fast path returning ``(eta, d eta/dt)`` for an observer moving at ``(vx, vy)``."""
        P = self.omega * t - self.kx * x - self.ky * y + self.phase
        a = self.amplitude
        return (float(np.cos(P) @ a),
                float(-(np.sin(P) @ (a * (self.omega - self.kx * vx - self.ky * vy)))))

    def _depth_factors(self, z: np.ndarray):
        """Horizontal and vertical decay factors, shape (rows, M), for z <= 0."""
        kz = np.multiply.outer(z, self.k)
        if self.depth is None:
            f = np.exp(kz)
            return f, f
        h = self.depth
        kh = self.k * h
        e2h = np.exp(-2.0 * kh)
        e2zh = np.exp(-2.0 * (kz + kh))  # exp(-2k(z+h)), z >= -h
        base = np.exp(kz) / (1.0 - e2h)
        return base * (1.0 + e2zh), base * (1.0 - e2zh)

    def kinematics(self, t, x=0.0, y=0.0, z=0.0) -> tuple[np.ndarray, np.ndarray]:
        """Linear (Airy) orbital velocity and local acceleration ``du/dt`` at ``(x, y, z)``.

        ``z`` (m, up, 0 = mean free surface) is clipped to ``[-depth, 0]``:
        points above the mean surface get the surface value (no stretching).
        Deep water uses ``exp(k z)`` decay; finite depth uses
        ``cosh(k(z+h))/sinh(kh)`` (horizontal) and ``sinh(k(z+h))/sinh(kh)``
        (vertical).  Returns ``(velocity, acceleration)``, each of shape
        ``broadcast(t, x, y, z).shape + (3,)`` in earth axes (x, y, z up).
        """
        shape, (t, x, y, z) = _flat(t, x, y, z)
        z = np.minimum(z, 0.0)
        if self.depth is not None:
            z = np.maximum(z, -self.depth)
        vel = np.empty((t.size, 3))
        acc = np.empty((t.size, 3))
        aw = self.amplitude * self.omega
        aw2 = aw * self.omega
        cth, sth = np.cos(self.direction), np.sin(self.direction)
        r = self._rows()
        for i in range(0, t.size, r):
            sl = slice(i, i + r)
            P = self._phase_block(t[sl], x[sl], y[sl])
            C, S = np.cos(P), np.sin(P)
            fh, fv = self._depth_factors(z[sl])
            Ch, Sh = C * fh, S * fh
            vel[sl, 0] = Ch @ (aw * cth)
            vel[sl, 1] = Ch @ (aw * sth)
            vel[sl, 2] = -((S * fv) @ aw)
            acc[sl, 0] = -(Sh @ (aw2 * cth))
            acc[sl, 1] = -(Sh @ (aw2 * sth))
            acc[sl, 2] = -((C * fv) @ aw2)
        return vel.reshape(shape + (3,)), acc.reshape(shape + (3,))

    def linear_response(self, t, transfer, x=0.0, y=0.0, vx=0.0, vy=0.0, order: int = 0) -> np.ndarray:
        """Response of a linear system driven by the encountered waves.

        ``r(t) = Re sum_j a_j H_j (i omega_e,j)^order exp(i phase_j(t))`` with
        ``omega_e = omega - kx vx - ky vy`` (signed).  ``transfer`` is a complex
        array ``(M,)`` or ``(M, n_out)`` of RAOs evaluated at the components
        (e.g. at :meth:`encounter_frequency` and :meth:`relative_direction`);
        ``order`` = 1 / 2 gives velocity / acceleration.  Positions and velocities
        may be arrays matching ``t``.  Output shape ``t.shape`` or ``t.shape + (n_out,)``.
        """
        H = np.asarray(transfer, dtype=complex)
        if H.shape[0] != self.n_components or H.ndim not in (1, 2):
            raise ValueError(f"transfer must have shape (M,) or (M, n_out) with M={self.n_components}")
        if order not in (0, 1, 2):
            raise ValueError(f"order must be 0, 1 or 2, got {order!r}")
        squeeze = H.ndim == 1
        H2 = H.reshape(self.n_components, -1) * self.amplitude[:, None]
        shape, (t, x, y, vx, vy) = _flat(t, x, y, vx, vy)
        out = np.empty((t.size, H2.shape[1]))
        r = self._rows()
        moving = bool(np.any(vx) or np.any(vy))
        for i in range(0, t.size, r):
            sl = slice(i, i + r)
            E = np.exp(1j * self._phase_block(t[sl], x[sl], y[sl]))
            if order:
                if moving:
                    We = self.omega - np.multiply.outer(vx[sl], self.kx) - np.multiply.outer(vy[sl], self.ky)
                else:
                    We = np.broadcast_to(self.omega, E.shape)
                E *= (1j * We) ** order
            out[sl] = (E @ H2).real
        out = out.reshape(shape + (H2.shape[1],))
        return out[..., 0] if squeeze else out

    # ---- precomputation ----------------------------------------------------
    def _uniform_sums(self, t_start: float, dt: float, n: int, we: np.ndarray, weights: np.ndarray,
                      block: int = 512) -> np.ndarray:
        """``Re sum_j W_jq exp(i (we_j t_m + phase_j))`` on ``t_m = t_start + m dt``.

        Exact factorisation ``exp(i we (t_b + m dt)) = exp(i we m dt) exp(i we t_b)``
        turns the sum into one complex matrix product per chunk of blocks (BLAS),
        ~10x faster than evaluating n*M cosines.  Returns shape (n, q)."""
        M, q = weights.shape
        B = min(block, n)
        nb = -(-n // B)
        T = np.exp(1j * np.multiply.outer(dt * np.arange(B), we))  # (B, M)
        out = np.empty((nb * B, q))
        per = max(1, _CHUNK_ELEMS // (M * q))  # blocks per chunk
        for b0 in range(0, nb, per):
            b1 = min(nb, b0 + per)
            tb = t_start + dt * B * np.arange(b0, b1)
            Cb = np.exp(1j * (np.multiply.outer(we, tb) + self.phase[:, None]))  # (M, nbc)
            R = T @ (weights[:, :, None] * Cb[:, None, :]).reshape(M, q * (b1 - b0))  # (B, q*nbc)
            R = R.real.reshape(B, q, b1 - b0).transpose(2, 0, 1).reshape((b1 - b0) * B, q)
            out[b0 * B:b1 * B] = R
        return out[:n]

    def precompute(self, dt: float, t_end: Optional[float] = None, t_start: float = 0.0,
                   track: Optional[Track] = None, velocity: Optional[tuple] = None,
                   z: Optional[float] = None) -> "GriddedWave":
        """Evaluate the record on a uniform time grid for fast look-up.

        Parameters
        ----------
        dt : float
            Grid step (s), e.g. the physics step (0.02-0.05 s).
        t_end : float, optional
            Last time; defaults to ``duration``.
        track : ``(x, y)`` arrays on the grid, or callable ``t -> (x, y)``, optional
            Observer track (a prescribed ship path, earth frame).
        velocity : ``(vx, vy)``, optional
            Without ``track``: a constant observer velocity; the observer is at
            ``(vx t, vy t)`` (origin at t = 0; default at rest at the origin).
            This case uses an exact BLAS factorisation (3 h at 50 Hz with
            M = 300 in well under a second).  With ``track``: arrays of the
            observer velocity for ``eta_rate`` (default ``np.gradient`` of the track).
        z : float, optional
            If given, also store orbital velocity and acceleration at height ``z``
            (<= 0) at the observer.

        The result stores ``eta`` and ``eta_rate`` (16 bytes per step: 3 h at
        50 Hz = 8.6 MB; with ``z`` another 48 bytes per step) and interpolates
        with cubic Hermite polynomials.
        """
        dt = float(dt)
        if not math.isfinite(dt) or dt <= 0:
            raise ValueError(f"dt must be > 0 s, got {dt!r}")
        if t_end is None:
            t_end = self.duration
        if not math.isfinite(t_end) or t_end <= t_start:
            raise ValueError("t_end must be finite and > t_start (set duration or pass t_end)")
        n = int(math.floor((t_end - t_start) / dt + 1e-9)) + 1

        if track is None:
            vx, vy = (0.0, 0.0) if velocity is None else (float(velocity[0]), float(velocity[1]))
            we = self.omega - self.kx * vx - self.ky * vy
            a = self.amplitude
            cols = [a.astype(complex), 1j * we * a]
            if z is not None:
                zz = min(float(z), 0.0)
                if self.depth is not None:
                    zz = max(zz, -self.depth)
                fh, fv = self._depth_factors(np.array([zz]))
                fh, fv = fh[0], fv[0]
                aw, aw2 = a * self.omega, a * self.omega**2
                cth, sth = np.cos(self.direction), np.sin(self.direction)
                cols += [aw * fh * cth, aw * fh * sth, 1j * aw * fv,
                         1j * aw2 * fh * cth, 1j * aw2 * fh * sth, -aw2 * fv]
            R = self._uniform_sums(float(t_start), dt, n, we, np.stack(cols, axis=1).astype(complex))
            vel = acc = None
            if z is not None:
                vel, acc = np.ascontiguousarray(R[:, 2:5]), np.ascontiguousarray(R[:, 5:8])
            return GriddedWave(float(t_start), dt, np.ascontiguousarray(R[:, 0]),
                               np.ascontiguousarray(R[:, 1]), vel, acc)

        t = t_start + dt * np.arange(n)
        x, y = _resolve_track(t, track)
        x = np.broadcast_to(np.asarray(x, dtype=float), t.shape)
        y = np.broadcast_to(np.asarray(y, dtype=float), t.shape)
        if velocity is not None:
            vx, vy = velocity
        elif n > 1:
            vx, vy = np.gradient(x, dt), np.gradient(y, dt)
        else:
            vx = vy = 0.0
        eta = self.elevation(t, x, y)
        eta_rate = self.elevation_rate(t, x, y, vx, vy)
        vel = acc = None
        if z is not None:
            vel, acc = self.kinematics(t, x, y, z)
        return GriddedWave(float(t_start), dt, eta, eta_rate, vel, acc)


def _resolve_track(t, track):
    if callable(track):
        x, y = track(np.asarray(t, dtype=float))
    else:
        try:
            x, y = track
        except (TypeError, ValueError):
            raise ValueError("track must be a (x, y) pair of arrays or a callable t -> (x, y)") from None
    return np.asarray(x, dtype=float), np.asarray(y, dtype=float)


@dataclass(frozen=True)
class GriddedWave:
    """Elevation (and optionally kinematics) precomputed on ``t = t0 + i*dt``.

    ``eta[i]``, ``eta_rate[i]`` (m, m/s), optional ``velocity[i]``,
    ``acceleration[i]`` (shape (n, 3)).  Call the object (or :meth:`eta_at`)
    for cubic-Hermite interpolation between grid points (error ~ (omega dt)^4/384
    of the amplitude), or index arrays directly when the simulator's clock is
    the grid.
    """

    t0: float
    dt: float
    eta: np.ndarray
    eta_rate: np.ndarray
    velocity: Optional[np.ndarray] = None
    acceleration: Optional[np.ndarray] = None

    @property
    def times(self) -> np.ndarray:
        return self.t0 + self.dt * np.arange(self.eta.size)

    @property
    def t_end(self) -> float:
        return self.t0 + self.dt * (self.eta.size - 1)

    def _locate(self, t):
        t = np.asarray(t, dtype=float)
        s = (t - self.t0) / self.dt
        n = self.eta.size
        if np.any(s < -1e-9) or np.any(s > n - 1 + 1e-9):
            raise ValueError(f"t outside the precomputed grid [{self.t0:g}, {self.t_end:g}] s")
        i = np.clip(np.floor(s).astype(np.int64), 0, max(n - 2, 0))
        u = np.clip(s - i, 0.0, 1.0)
        return i, u

    def eta_at(self, t) -> np.ndarray:
        """Cubic Hermite interpolation of eta (uses eta and eta_rate)."""
        i, u = self._locate(t)
        if self.eta.size == 1:
            return np.broadcast_to(self.eta[0], np.shape(u)).copy()
        p0, p1 = self.eta[i], self.eta[i + 1]
        m0, m1 = self.eta_rate[i] * self.dt, self.eta_rate[i + 1] * self.dt
        u2, u3 = u * u, u * u * u
        return ((2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * m0
                + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * m1)

    __call__ = eta_at

    def eta_rate_at(self, t) -> np.ndarray:
        """Linear interpolation of eta_rate."""
        i, u = self._locate(t)
        if self.eta.size == 1:
            return np.broadcast_to(self.eta_rate[0], np.shape(u)).copy()
        return (1 - u) * self.eta_rate[i] + u * self.eta_rate[i + 1]


# --------------------------------------------------------------------------
# synthesis
# --------------------------------------------------------------------------
def _bin_energy(sea_state: SeaState, edges: np.ndarray) -> np.ndarray:
    """int_bin S d omega for each bin (8-point Gauss-Legendre per bin)."""
    lo, hi = edges[:-1], edges[1:]
    half = 0.5 * (hi - lo)
    mid = 0.5 * (hi + lo)
    w = mid[:, None] + half[:, None] * _GL_X[None, :]
    return half * (sea_state.density(w) @ _GL_W)


def _sample_directions(sea_state: SeaState, n: int, rng: np.random.Generator) -> np.ndarray:
    """Draw n directions from D(theta) by inverse CDF on a fine grid."""
    th = np.linspace(-math.pi, math.pi, 4097) + sea_state.heading_rad
    d = sea_state.spreading_density(th)
    cdf = np.concatenate(([0.0], np.cumsum(0.5 * (d[1:] + d[:-1]) * np.diff(th))))
    cdf /= cdf[-1]
    keep = np.concatenate(([True], np.diff(cdf) > 0))
    return np.interp(rng.random(n), cdf[keep], th[keep])


def synthesize(sea_state: Union[SeaState, Sequence[SeaState]], duration: float, seed=None,
               n_components: int = 300, omega_range: Optional[tuple] = None, *, jitter: bool = True,
               amplitudes: str = "das", n_directions: Optional[int] = None, depth: Optional[float] = None,
               g: float = G, allow_repetition: bool = False) -> WaveRecord:
    """Synthesise a random-phase realisation of one or more sea states.

    Parameters
    ----------
    sea_state : SeaState or sequence of SeaState
        Several states (e.g. wind sea + swell) are superposed, each with its own
        frequency bins and independent random phases.
    duration : float
        Episode length (s).  The record is analytic and may be evaluated at any
        time; ``duration`` is checked against the repetition period and is the
        default end of :meth:`WaveRecord.precompute`.
    seed : int, SeedSequence, numpy.random.Generator or None
        Same seed -> bit-identical record.  Pass the environment's ``np_random``
        to draw from it (it is advanced).  Never touches numpy's global RNG.
    n_components : int
        Frequency bins per sea state (default 300; reference: 200-400).
    omega_range : (lo, hi) rad/s, optional
        Band to synthesise; default :func:`default_omega_range` = [0.3, 5] omega_p.
    jitter : bool
        Draw each component frequency uniformly inside its bin (default).  With
        ``jitter=False`` the bin centres are used and the record repeats after
        ``2 pi / d omega``; a ValueError is raised if that is shorter than
        ``duration`` unless ``allow_repetition=True``.
    amplitudes : "das" or "ras"
        Deterministic amplitudes ``sqrt(2 E_bin)`` (default: exact band variance
        every realisation) or random Rayleigh amplitudes with ``E[a^2] = 2 E_bin``
        (natural wave-group variability, for domain randomisation).
    n_directions : int, optional
        Short-crested seas only (``sea_state.spreading_s`` set).  ``None``: one
        random direction per component drawn from D(theta) (single summation,
        M = n_components).  An int: a grid of that many direction bins per
        frequency bin with energy ``E_bin * int_bin D d theta`` (M = n_components
        * n_directions), each component with its own jittered frequency and phase.
    depth : float, optional
        Water depth (m) for the dispersion relation and kinematics; None = deep.

    Random draws per sea state, in order: frequency jitter, phases,
    [RAS amplitudes], [directions].
    """
    states = [sea_state] if isinstance(sea_state, SeaState) else list(sea_state)
    if not states or not all(isinstance(s, SeaState) for s in states):
        raise ValueError("sea_state must be a SeaState or a non-empty sequence of SeaState")
    duration = float(duration)
    if not math.isfinite(duration) or duration <= 0:
        raise ValueError(f"duration must be a finite number > 0 s, got {duration!r}")
    n = int(n_components)
    if n != n_components or n < 1:
        raise ValueError(f"n_components must be an integer >= 1, got {n_components!r}")
    if amplitudes not in ("das", "ras"):
        raise ValueError(f"amplitudes must be 'das' or 'ras', got {amplitudes!r}")
    if n_directions is not None and (int(n_directions) != n_directions or n_directions < 1):
        raise ValueError(f"n_directions must be None or an integer >= 1, got {n_directions!r}")
    rng = _as_generator(seed)
    seed_label = seed if isinstance(seed, (int, np.integer)) else None

    omegas, amps, phis, dirs = [], [], [], []
    repeat = math.inf
    for st in states:
        lo, hi = default_omega_range(st) if omega_range is None else map(float, omega_range)
        if not (0 < lo < hi and math.isfinite(hi)):
            raise ValueError(f"omega_range must satisfy 0 < lo < hi (rad/s), got {(lo, hi)!r}")
        edges = np.linspace(lo, hi, n + 1)
        dw = (hi - lo) / n
        energy = _bin_energy(st, edges)  # (n,)

        if st.spreading_s is not None and n_directions is not None:
            nd = int(n_directions)
            lim = math.pi if st.spreading == "cos2s" else math.pi / 2
            th_edges = np.linspace(-lim, lim, nd + 1) + st.heading_rad
            th_fine = np.linspace(-lim, lim, 64 * nd + 1) + st.heading_rad
            d_fine = st.spreading_density(th_fine)
            cum = np.concatenate(([0.0], np.cumsum(0.5 * (d_fine[1:] + d_fine[:-1]) * np.diff(th_fine))))
            wdir = np.diff(np.interp(th_edges, th_fine, cum))
            wdir /= wdir.sum()
            th_c = 0.5 * (th_edges[1:] + th_edges[:-1])
            E = (energy[:, None] * wdir[None, :]).ravel()
            base = np.repeat(edges[:-1], nd)
            th = np.tile(th_c, n)
            keep = E > 0
            E, base, th = E[keep], base[keep], th[keep]
        else:
            E, base, th = energy, edges[:-1], None
        m = E.size
        if jitter:
            w = base + rng.random(m) * dw
        else:
            w = base + 0.5 * dw
            repeat = min(repeat, _TWO_PI / dw)
        phi = rng.uniform(0.0, _TWO_PI, m)
        if amplitudes == "das":
            a = np.sqrt(2.0 * E)
        else:
            a = np.sqrt(2.0 * E * rng.standard_exponential(m))
        if th is None:
            if st.spreading_s is None:
                th = np.full(m, st.heading_rad)
            else:
                th = _sample_directions(st, m, rng)
        omegas.append(w)
        amps.append(a)
        phis.append(phi)
        dirs.append(th)

    if repeat <= duration and not allow_repetition:
        raise ValueError(
            f"with jitter=False the record repeats every 2*pi/d_omega = {repeat:.1f} s, shorter than "
            f"duration = {duration:g} s; use jitter=True, more n_components, or allow_repetition=True")
    return WaveRecord(np.concatenate(omegas), np.concatenate(amps), np.concatenate(phis), np.concatenate(dirs),
                      depth=depth, g=g, duration=duration, repeat_period=repeat, sea_states=states,
                      seed=seed_label)
