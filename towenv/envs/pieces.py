"""Swappable pieces of the towenv environments (Jumanji-style strategy objects).

A :class:`~towenv.envs.base.TowEnv` is assembled from four small, picklable objects, each replaceable
through a constructor keyword:

* ``sea_generator`` — a :class:`SeaGenerator`: ``gen(rng) -> (SeaState, wave_seed)``, the initial-state
  distribution of an episode (the sea state and the random seed of its wave realisation);
* ``reward_fn`` — a :class:`RewardFn`: ``fn(m, action, prev_action) -> (reward, components)``;
* ``observation_fn`` — an :class:`Observer`: named sensor channels with noise and delay;
* ``termination`` — a :class:`Termination`: ``term(m) -> reason or None``, when an episode ends for good
  (default :class:`PartedOrGrounded`: the cable parts or the towed body goes below the floor).

(The fifth, ``renderer``, draws frames: :class:`towenv.envs.render.SideViewer` by default.)

None of these imports gymnasium; they only see plain floats and numpy arrays.

``m`` is the *measurement* dict the environment builds once per control step (all SI units, see
:data:`MEASUREMENTS`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np
from numba import njit

from .measurements import COL, MEAS_COLUMNS
from ..sea import SeaState
from ..stats import RATE_LIMITS

__all__ = [
    "MEASUREMENTS", "Channel", "CHANNELS", "Observer",
    "SeaGenerator", "RandomCodeSeas", "FixedSeas", "default_eval_sea_states",
    "RewardFn", "HeavePitchReward", "HeaveOnlyReward",
    "Termination", "Limit", "Limits", "PartedOrGrounded", "LIMIT_OPS",
    "HEAVE_RATE_LIMIT", "PITCH_RATE_LIMIT",
]

#: Table 6.1 (thesis) sonar motion-rate limits in SI units: heave 1 m/s, pitch 6.28 deg/s (in rad/s).
HEAVE_RATE_LIMIT = float(RATE_LIMITS["heave"][0])
PITCH_RATE_LIMIT = math.radians(float(RATE_LIMITS["pitch"][0]))

#: Keys of the per-control-step measurement dict ``m`` (SI units; z up, pitch + nose down).
MEASUREMENTS = {
    "t": "simulated time (s)",
    "tow_vel_z": "MRU: tow-point vertical velocity (m/s), from the prescribed tow-point history",
    "tow_acc_z": "MRU: tow-point vertical acceleration (m/s^2), backward second difference",
    "top_tension": "tow-point cable force magnitude (N)",
    "top_tension_ratio": "top tension / its static (steady-tow) value",
    "fish_heave": "towed-body z minus its steady-tow z (m, + up; depth deviation = -heave)",
    "fish_depth": "towed-body depth below the mean free surface (m, + down)",
    "fish_pitch": "towed-body pitch (rad, + nose down)",
    "fish_heave_rate": "towed-body vertical velocity (m/s)",
    "fish_pitch_rate": "towed-body pitch rate q (rad/s)",
    "min_tension": "smallest segment tension of all lines (N)",
    "tension_ratio": "largest (tension / breaking load) over all lines and the tow point",
    "comp_stroke": "compensator stroke / half stroke (0 = mid-stroke, +-1 = end stops)  [compensator]",
    "comp_stroke_vel": "compensator stroke velocity (m/s)  [compensator]",
    "end_stop_hits": "compensator end-stop hits during this control step  [compensator]",
    "winch_speed": "winch payout speed / max speed (payout > 0)  [winch]",
    "winch_length_dev": "winch-line length minus its initial length (m)  [winch]",
    "winch_power": "winch mechanical power -T·v (W; > 0 hauling in against the top tension)  [winch]",
    "tow_surge": "MRU: tow-point displacement along the mean heading, relative to the mean track (m)",
    "tow_sway": "MRU: tow-point displacement to port, relative to the mean track (m)",
    "tow_heave": "MRU: tow-point vertical displacement from its mean height (m, + up)",
    "tow_vel_x": "MRU: tow-point velocity along the mean heading, relative to the mean track (m/s)",
    "tow_vel_y": "MRU: tow-point velocity to port (m/s)",
    "tow_acc_x": "MRU: tow-point acceleration along the mean heading (m/s^2)",
    "tow_acc_y": "MRU: tow-point acceleration to port (m/s^2)",
    "cable_angle": "sheave angle sensor: top-cable depression angle below the horizontal (rad)",
    "cable_azimuth": "sheave angle sensor: top-cable azimuth from dead astern (rad, + to port)",
    "tow_disp_along": "MRU displacement projected on the top cable, payout-positive (m)",
    "tow_vel_along": "MRU velocity projected on the top cable, payout-positive (m/s): the payout that cancels it",
    "tow_acc_along": "MRU acceleration projected on the top cable, payout-positive (m/s^2)",
    "fish_heave_dev": "fish heave about its running mean (m; about 0 with no running mean)",
    "fish_pitch_dev": "fish pitch about its running mean (rad; about the steady-tow trim with no running mean)",
}


# =====================================================================================================
# Observations
# =====================================================================================================
@dataclass(frozen=True)
class Channel:
    """An observation channel: ``obs = clip(value / scale, low, high)``. ``source`` is the measurement
    key (or a special source: ``last_action``, ``time_left``, ``wave_preview``)."""
    name: str
    source: str
    unit: str
    scale: float
    low: float
    high: float
    doc: str = ""


_D = math.radians
CHANNELS: dict[str, Channel] = {c.name: c for c in [
    Channel("tow_vel_z", "tow_vel_z", "m/s", 1.0, -10.0, 10.0, "tow-point vertical velocity (IMU)"),
    Channel("tow_acc_z", "tow_acc_z", "m/s^2", 1.0, -30.0, 30.0, "tow-point vertical acceleration (IMU)"),
    Channel("tow_surge", "tow_surge", "m", 1.0, -20.0, 20.0, "MRU tow-point surge displacement"),
    Channel("tow_sway", "tow_sway", "m", 1.0, -20.0, 20.0, "MRU tow-point sway displacement"),
    Channel("tow_heave", "tow_heave", "m", 1.0, -20.0, 20.0, "MRU tow-point heave displacement"),
    Channel("tow_vel_x", "tow_vel_x", "m/s", 1.0, -10.0, 10.0, "MRU tow-point surge velocity"),
    Channel("tow_vel_y", "tow_vel_y", "m/s", 1.0, -10.0, 10.0, "MRU tow-point sway velocity"),
    Channel("tow_acc_x", "tow_acc_x", "m/s^2", 1.0, -30.0, 30.0, "MRU tow-point surge acceleration"),
    Channel("tow_acc_y", "tow_acc_y", "m/s^2", 1.0, -30.0, 30.0, "MRU tow-point sway acceleration"),
    Channel("cable_angle", "cable_angle", "rad", 1.0, -2.0, 2.0, "top-cable depression angle at the sheave"),
    Channel("cable_azimuth", "cable_azimuth", "rad", 1.0, -4.0, 4.0, "top-cable azimuth from astern"),
    Channel("tow_disp_along", "tow_disp_along", "m", 1.0, -20.0, 20.0, "MRU displacement along the top cable"),
    Channel("tow_vel_along", "tow_vel_along", "m/s", 1.0, -10.0, 10.0, "MRU velocity along the top cable"),
    Channel("tow_acc_along", "tow_acc_along", "m/s^2", 1.0, -30.0, 30.0, "MRU acceleration along the top cable"),
    Channel("top_tension", "top_tension_ratio", "-", 1.0, 0.0, 20.0, "top tension / static top tension"),
    Channel("comp_stroke", "comp_stroke", "-", 1.0, -1.5, 1.5, "compensator stroke / half stroke"),
    Channel("comp_stroke_vel", "comp_stroke_vel", "m/s", 1.0, -10.0, 10.0, "compensator stroke velocity"),
    Channel("winch_speed", "winch_speed", "-", 1.0, -1.5, 1.5, "winch payout speed / max speed"),
    Channel("winch_length_dev", "winch_length_dev", "m", 10.0, -10.0, 10.0,
            "winch-line length deviation from its initial length, in units of 10 m"),
    Channel("fish_heave", "fish_heave", "m", 1.0, -20.0, 20.0, "fish heave (m, + up): depth deviation = -heave"),
    Channel("fish_pitch", "fish_pitch", "rad", 0.1, -15.0, 15.0, "fish pitch in units of 0.1 rad (+ nose down)"),
    Channel("fish_depth", "fish_depth", "m", 10.0, 0.0, 50.0, "fish depth (pressure sensor) in units of 10 m"),
    Channel("fish_heave_dev", "fish_heave_dev", "m", 1.0, -20.0, 20.0, "fish heave about its running mean"),
    Channel("fish_pitch_dev", "fish_pitch_dev", "rad", 0.1, -15.0, 15.0,
            "fish pitch about its running mean, in units of 0.1 rad"),
    Channel("fish_heave_rate", "fish_heave_rate", "m/s", HEAVE_RATE_LIMIT, -20.0, 20.0,
            "fish heave rate / Table 6.1 limit (1 m/s)"),
    Channel("fish_pitch_rate", "fish_pitch_rate", "rad/s", PITCH_RATE_LIMIT, -100.0, 100.0,
            "fish pitch rate / Table 6.1 limit (6.28 deg/s)"),
    Channel("last_action", "last_action", "-", 1.0, -1.0, 1.0, "the previous action (one entry per action dim)"),
    Channel("time_left", "time_left", "-", 1.0, 0.0, 1.0, "fraction of the episode left"),
    Channel("wave_preview", "wave_preview", "m", 1.0, -30.0, 30.0,
            "wave elevation now at preview_distances ahead of the tow point (one entry per distance)"),
]}


class Observer:
    """Named sensor channels -> a finite float32 vector, with per-channel Gaussian noise and a delay.

    Parameters
    ----------
    names : sequence of channel names (keys of :data:`CHANNELS`).
    noise : ``{name: std}`` in the channel's *physical* unit (m, m/s, rad, …; for ``top_tension`` a
        fraction of the static tension). Drawn from the environment's ``np_random`` at measurement time.
    delay : whole control steps between measurement and observation (ring buffer; at reset the buffer
        is filled with the initial measurement).
    action_dim, preview_distances : sizes of the vector channels ``last_action`` / ``wave_preview``.
    """

    def __init__(self, names: Sequence[str], noise: Mapping[str, float] | None = None, delay: int = 0,
                 action_dim: int = 1, preview_distances: Sequence[float] = ()):
        names = list(names)
        unknown = [n for n in names if n not in CHANNELS]
        if unknown:
            raise ValueError(f"unknown observation channel(s) {unknown}; known: {sorted(CHANNELS)}")
        if len(set(names)) != len(names):
            raise ValueError(f"observation channels repeated: {names}")
        noise = dict(noise or {})
        bad = [n for n in noise if n not in names]
        if bad:
            raise ValueError(f"sensor noise given for channel(s) not observed: {bad}")
        if any(not (math.isfinite(float(s)) and float(s) >= 0) for s in noise.values()):
            raise ValueError(f"sensor noise std must be finite and >= 0 (got {noise})")
        if (isinstance(delay, bool) or not isinstance(delay, (int, float, np.integer, np.floating))
                or not math.isfinite(delay) or int(delay) != delay or delay < 0):
            raise ValueError(f"observation delay must be a whole number of control steps >= 0 (got {delay!r})")
        if "wave_preview" in names and len(preview_distances) == 0:
            raise ValueError("the wave_preview channel needs preview_distances (m ahead of the tow point)")
        self.names = names
        self.noise = noise
        self.delay = int(delay)
        self.action_dim = int(action_dim)
        self.preview_distances = tuple(float(d) for d in preview_distances)
        lows, highs, scales, stds, self.layout = [], [], [], [], []
        for n in names:
            c = CHANNELS[n]
            width = {"last_action": self.action_dim, "wave_preview": len(self.preview_distances)}.get(n, 1)
            self.layout.append((c.source, len(lows), width))
            lows += [c.low] * width
            highs += [c.high] * width
            scales += [c.scale] * width
            stds += [float(noise.get(n, 0.0)) / c.scale] * width
        self.low = np.array(lows, np.float32)
        self.high = np.array(highs, np.float32)
        self._lo64, self._hi64 = self.low.astype(float), self.high.astype(float)
        self._inv_scale = 1.0 / np.array(scales)
        self._std = np.array(stds)
        self._noisy = bool(np.any(self._std > 0))
        self.size = len(lows)
        self._plan = [(src, src not in ("last_action", "wave_preview")) for src, _, _ in self.layout]
        # compiled row path: element k reads measurement column / action entry / preview entry src_idx[k]
        kind, idx = [], []
        for src, _, width in self.layout:
            for j in range(width):
                if src == "last_action":
                    kind.append(1)
                    idx.append(j)
                elif src == "wave_preview":
                    kind.append(2)
                    idx.append(j)
                else:
                    kind.append(0)
                    idx.append(COL[src])
        self._src_kind = np.array(kind, np.int64)
        self._src_idx = np.array(idx, np.int64)
        self._ring = np.zeros((self.delay + 1, self.size), np.float32)
        self._head = 0

    @property
    def wants_preview(self) -> bool:
        return "wave_preview" in self.names

    def measure(self, m: Mapping[str, float], rng: np.random.Generator | None) -> np.ndarray:
        """The (undelayed) observation vector of measurement ``m``: scaled, noisy, finite, clipped."""
        vals: list = []
        for src, scalar in self._plan:
            if scalar:
                vals.append(m.get(src, 0.0))
            else:
                vals.extend(m[src])
        raw = np.array(vals, dtype=float)
        raw *= self._inv_scale
        if self._noisy and rng is not None:
            raw += self._std * rng.standard_normal(self.size)
        if not np.isfinite(raw).all():           # finite by construction: NaN -> 0, ±inf -> the bounds
            np.nan_to_num(raw, copy=False, nan=0.0, posinf=1e30, neginf=-1e30)
        np.minimum(np.maximum(raw, self._lo64, out=raw), self._hi64, out=raw)
        return raw.astype(np.float32)

    def measure_rows(self, M: np.ndarray, A: np.ndarray, rows: np.ndarray, rngs=None,
                     preview: np.ndarray | None = None) -> np.ndarray:
        """Undelayed observations (len(rows), size) float32 of measurement rows ``M[rows]`` (columns
        :data:`~towenv.envs.measurements.MEAS_COLUMNS`) with actions ``A[rows]`` — the compiled, batched form of
        :meth:`measure` (same scaling, noise, NaN handling and clipping). ``rngs[i]`` draws row i's noise."""
        noise, noisy = self.noise_rows(rngs, len(rows))
        P = _NO_PREVIEW if preview is None else preview
        out = np.empty((len(rows), self.size), np.float32)
        _observe_rows(M, A, P, rows, self._src_kind, self._src_idx, self._inv_scale, self._std, noise, noisy,
                      self._lo64, self._hi64, out)
        return out

    def noise_rows(self, rngs, n: int):
        """``(noise (n, size), noisy)`` for :meth:`measure_rows`: row k drawn from ``rngs[k]`` (none without noise
        channels or without generators)."""
        noisy = self._noisy and rngs is not None
        if not noisy:
            return _NO_NOISE, False
        noise = np.zeros((n, self.size))
        for k, rng in enumerate(rngs):
            if rng is not None:
                noise[k] = rng.standard_normal(self.size)
        return noise, True

    def rows_arrays(self) -> tuple:
        """The compiled row path's arrays (``kind, idx, inv_scale, std, lo, hi`` of :func:`_observe_rows`)."""
        return self._src_kind, self._src_idx, self._inv_scale, self._std, self._lo64, self._hi64

    def push(self, obs: np.ndarray) -> np.ndarray:
        """Push an undelayed observation into the delay ring; return the one ``delay`` steps old."""
        if self.delay == 0:
            return obs
        self._head = (self._head + 1) % (self.delay + 1)
        self._ring[self._head] = obs
        return self._ring[(self._head + 1) % (self.delay + 1)].copy()

    def start(self, obs: np.ndarray) -> np.ndarray:
        """Fill the delay ring with the first observation of an episode."""
        self._ring[:] = obs
        self._head = 0
        return obs.copy()

    def reset(self, m, rng) -> np.ndarray:
        first = self.measure(m, rng)
        self._ring[:] = first
        self._head = 0
        return first.copy()

    def __call__(self, m, rng) -> np.ndarray:
        """Push this step's measurement and return the one taken ``delay`` control steps ago."""
        obs = self.measure(m, rng)
        if self.delay == 0:
            return obs
        self._head = (self._head + 1) % (self.delay + 1)
        self._ring[self._head] = obs
        return self._ring[(self._head + 1) % (self.delay + 1)].copy()


_NO_NOISE = np.zeros((1, 1))
_NO_PREVIEW = np.zeros((1, 1))


@njit(cache=True)
def _observe_rows(M, A, P, rows, kind, idx, inv_scale, std, noise, noisy, lo, hi, out):
    for k in range(rows.shape[0]):
        b = rows[k]
        for j in range(kind.shape[0]):
            if kind[j] == 0:
                v = M[b, idx[j]]
            elif kind[j] == 1:
                v = A[b, idx[j]]
            else:
                v = P[b, idx[j]]
            v = v * inv_scale[j]
            if noisy:
                v = v + std[j] * noise[k, j]
            if v != v:
                v = 0.0
            elif v > 1e30:
                v = 1e30
            elif v < -1e30:
                v = -1e30
            if v < lo[j]:
                v = lo[j]
            if v > hi[j]:
                v = hi[j]
            out[k, j] = v


# =====================================================================================================
# Sea-state generators (initial-state distribution)
# =====================================================================================================
class SeaGenerator:
    """Protocol: ``gen(rng) -> (SeaState, wave_seed)`` drawing only from ``rng`` (the env's np_random)."""

    def __call__(self, rng: np.random.Generator) -> tuple[SeaState, int]:  # pragma: no cover
        raise NotImplementedError


class RandomCodeSeas(SeaGenerator):
    """WMO sea-state ``codes`` drawn uniformly; Hs ~ U(code range) and Tp by the ``convention``
    (``SeaState.from_code(code, convention, rng=rng)``: coastal Tp = c·sqrt(Hs), c ~ U(3.6, 5.0));
    mean wave heading ~ U(heading_deg ± heading_spread_deg) (180 = head seas); wave seed ~ U[0, 2^31)."""

    def __init__(self, codes: Sequence[int] = (3, 4, 5), convention: str = "coastal", heading_deg: float = 180.0,
                 heading_spread_deg: float = 30.0, spectrum: str = "jonswap", spreading_s: float | None = None):
        if len(codes) == 0:
            raise ValueError("RandomCodeSeas: codes must not be empty")
        for c in codes:
            SeaState.from_code(int(c), convention)          # validates code and convention
        if not (math.isfinite(heading_spread_deg) and heading_spread_deg >= 0):
            raise ValueError(f"heading_spread_deg must be >= 0 (got {heading_spread_deg!r})")
        self.codes = tuple(int(c) for c in codes)
        self.convention = convention
        self.heading_deg = float(heading_deg)
        self.heading_spread_deg = float(heading_spread_deg)
        self.spectrum = spectrum
        self.spreading_s = spreading_s

    def __call__(self, rng):
        code = self.codes[int(rng.integers(len(self.codes)))]
        heading = self.heading_deg + self.heading_spread_deg * float(rng.uniform(-1.0, 1.0))
        sea = SeaState.from_code(code, self.convention, rng=rng, heading_deg=heading, spectrum=self.spectrum,
                                 spreading_s=self.spreading_s)
        return sea, int(rng.integers(2 ** 31))


class FixedSeas(SeaGenerator):
    """A fixed list of ``(SeaState, wave_seed)``: ``order="cycle"`` visits them in turn (episode i gets
    entry i mod n, whatever the rng), ``"random"`` picks one uniformly from ``rng``."""

    def __init__(self, seas: Sequence[tuple[SeaState, int]], order: str = "cycle"):
        if len(seas) == 0:
            raise ValueError("FixedSeas: the list of sea states is empty")
        if order not in ("cycle", "random"):
            raise ValueError(f"FixedSeas: order must be 'cycle' or 'random' (got {order!r})")
        self.seas = [(s, int(seed)) for s, seed in seas]
        self.order = order
        self._next = 0

    def __call__(self, rng):
        if self.order == "random":
            return self.seas[int(rng.integers(len(self.seas)))]
        s = self.seas[self._next % len(self.seas)]
        self._next += 1
        return s


#: headings (deg, 180 = head seas) of the evaluation set, cycled per code
EVAL_HEADINGS = (180.0, 160.0, 200.0, 180.0)


def default_eval_sea_states(codes: Sequence[int] = (3, 4, 5), convention: str = "coastal",
                            headings: Sequence[float] = EVAL_HEADINGS, spectrum: str = "jonswap"):
    """The fixed evaluation set (common random numbers): for every code the deterministic preset
    ``SeaState.from_code(code, convention)`` (coastal: Lee et al. mean Hs, Tp = 4.3·sqrt(Hs)) at each of
    ``headings``, with wave seed ``1000·code + j`` (j = index of the heading). Same list on every call."""
    out = []
    for code in codes:
        for j, h in enumerate(headings):
            out.append((SeaState.from_code(int(code), convention, heading_deg=float(h), spectrum=spectrum),
                        1000 * int(code) + j))
    return out


# =====================================================================================================
# Rewards
# =====================================================================================================
class RewardFn:
    """Protocol: ``fn(m, action, prev_action) -> (reward, components)``; ``components`` maps names to the
    (weighted, positive) costs; ``reward = -sum(components)``. ``terminal_cost(steps_left)`` is added by
    the environment when an episode terminates (not when it is truncated)."""

    def __call__(self, m, action, prev_action):  # pragma: no cover
        raise NotImplementedError

    def terminal_cost(self, steps_left: int) -> float:
        return 0.0


class HeavePitchReward(RewardFn):
    """Motion cost plus penalties, per control step, consistent with the evaluation metrics::

        cost = w_heave·h'² + w_pitch·θ'² + w_heave_rate·(ḣ/1 m/s)² + w_pitch_rate·(q/6.28 °/s)²
             + w_rate_over·(max(0, |ḣ|/1 m/s − 1)² + max(0, |q|/6.28 °/s − 1)²)
             + w_end_stop·(end-stop hits this step) + w_slack·[min tension ≤ slack_tension]
             + w_over_tension·max(0, (T/T_break − f)/(1 − f)) + w_effort·mean(effort²) + w_action_rate·mean(Δa²)

    h' = fish heave about its running mean and θ' = fish pitch about its running mean (the environment's
    ``mean_time_constant``, default 30 s; with ``None`` about the steady-tow depth and trim): the metrics
    score σ about the episode mean, so a constant offset (the fish rises by 0.9–1.8 m in waves) is not a
    cost. Rates are normalised by the thesis Table 6.1 sonar limits; ``rate_over`` charges only what
    exceeds them (the metrics' "fraction of time over the limit"). ``effort`` is the actuator's own effort
    measure (winch: speed / max speed; compensator: 0 — a semi-active gain change costs no power), ``Δa``
    the action change. On termination (cable parted, fish below the floor) a cost
    ``w_terminal × (steps left + 1)`` is added so that ending an episode early never pays.
    """

    #: Defaults (docs/environments.md "Reward"): heave dominates — 1 per step at 0.32 m RMS heave deviation,
    #: the fixed winch's level in coastal code 4; pitch 10 per rad² (0.1 at 5.7° RMS); the quadratic rate
    #: terms are small shaping terms, the Table 6.1 exceedance is charged by ``rate_over``. ``slack`` = 0.1 per
    #: control step with a slack segment: a controller that leaves the secondary slack 40 % of the time (the
    #: fixed winch) pays 0.04 per step, as much as 6 cm of RMS heave — enough to prefer taut cables
    #: (slack precedes the snap loads, Hover et al. 1994 §IV), too little to trade heave for tension.
    DEFAULTS = dict(heave=10.0, pitch=10.0, heave_rate=0.1, pitch_rate=0.003, rate_over=0.1, end_stop=1.0,
                    slack=0.1, over_tension=10.0, effort=0.001, action_rate=0.01, terminal=2.0)

    def __init__(self, weights: Mapping[str, float] | None = None, slack_tension: float = 1.0,
                 over_tension_fraction: float = 0.5):
        w = dict(self.DEFAULTS)
        for k, v in (weights or {}).items():
            if k not in w:
                raise ValueError(f"unknown reward weight {k!r}; known: {sorted(w)}")
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(float(v)) and float(v) >= 0):
                raise ValueError(f"reward weight {k!r} must be finite and >= 0 (got {v!r})")
            w[k] = float(v)
        if isinstance(over_tension_fraction, bool) or not (
                isinstance(over_tension_fraction, (int, float)) and 0.0 <= over_tension_fraction < 1.0):
            raise ValueError(f"over_tension_fraction must be in [0, 1) (got {over_tension_fraction!r})")
        self.weights = w
        self.slack_tension = float(slack_tension)
        self.over_tension_fraction = float(over_tension_fraction)

    def __call__(self, m, action, prev_action):
        """Reward and components of one measurement dict ``m`` (:data:`MEASUREMENTS`; ``fish_heave_dev`` /
        ``fish_pitch_dev`` fall back to ``fish_heave`` / ``fish_pitch``, ``end_stop_hits`` and ``effort`` to 0,
        an ``effort`` array counts by its mean square) — computed by the same compiled arithmetic as
        :meth:`batch`, the one definition of the cost."""
        row = np.zeros((1, len(MEAS_COLUMNS)))
        row[0, _C_HEAVE] = m.get("fish_heave_dev", m["fish_heave"])
        row[0, _C_PITCH] = m.get("fish_pitch_dev", m["fish_pitch"])
        row[0, _C_HR] = m["fish_heave_rate"]
        row[0, _C_PR] = m["fish_pitch_rate"]
        row[0, _C_HITS] = float(m.get("end_stop_hits", 0))
        row[0, _C_MINT] = m["min_tension"]
        row[0, _C_RATIO] = m["tension_ratio"]
        eff = m.get("effort", 0.0)
        row[0, _C_EFF] = float(eff) if np.ndim(eff) == 0 else math.sqrt(float(np.mean(np.square(eff))))
        a = np.atleast_1d(np.asarray(action, float))[None, :]
        ap = np.atleast_1d(np.asarray(prev_action, float))[None, :]
        R, C = self.batch(row, a, ap, np.zeros(1, np.int64))
        return float(R[0]), dict(zip(self.COMPONENTS, (float(v) for v in C[0])))

    def terminal_cost(self, steps_left):
        return self.weights["terminal"] * (int(steps_left) + 1)

    #: names of the components, in the order of the columns of :meth:`batch`'s component array
    COMPONENTS = ("heave", "pitch", "heave_rate", "pitch_rate", "rate_over", "end_stop", "slack", "over_tension",
                  "effort", "action_rate")

    def weight_vector(self) -> np.ndarray:
        """The weights in the order of :attr:`COMPONENTS` (those of :func:`_heave_pitch_rows`)."""
        wv = self.__dict__.get("_wv")
        if wv is None:                # the weights are constructor parameters: fixed after __init__
            wv = self._wv = np.array([self.weights[k] for k in self.COMPONENTS])
        return wv

    def batch(self, M: np.ndarray, A: np.ndarray, A_prev: np.ndarray, rows: np.ndarray):
        """Compiled batched form of ``__call__`` for measurement rows ``M[rows]`` (columns
        :data:`~towenv.envs.measurements.MEAS_COLUMNS`): ``(rewards (n,), components (n, 10))`` with the columns in
        the order of :attr:`COMPONENTS`."""
        wv = self.weight_vector()
        R = np.empty(len(rows))
        C = np.empty((len(rows), len(self.COMPONENTS)))
        _heave_pitch_rows(M, A, A_prev, rows, wv, self.slack_tension, self.over_tension_fraction,
                          HEAVE_RATE_LIMIT, PITCH_RATE_LIMIT, C, R)
        return R, C


_MC = {n: i for i, n in enumerate(MEAS_COLUMNS)}
_C_HEAVE, _C_PITCH = _MC["fish_heave_dev"], _MC["fish_pitch_dev"]
_C_HR, _C_PR = _MC["fish_heave_rate"], _MC["fish_pitch_rate"]
_C_HITS, _C_MINT, _C_RATIO, _C_EFF = _MC["end_stop_hits"], _MC["min_tension"], _MC["tension_ratio"], _MC["effort"]


@njit(cache=True)
def _heave_pitch_rows(M, A, AP, rows, w, slack, f, hrl, prl, C, R):
    na = A.shape[1]
    nc = C.shape[1]
    for k in range(rows.shape[0]):
        b = rows[k]
        hr = M[b, _C_HR] / hrl
        pr = M[b, _C_PR] / prl
        da2 = 0.0
        for j in range(na):
            d = A[b, j] - AP[b, j]
            da2 += d * d
        da2 = da2 / max(na, 1)
        eff = M[b, _C_EFF]
        h = M[b, _C_HEAVE]
        th = M[b, _C_PITCH]
        ho = max(0.0, abs(hr) - 1.0)
        po = max(0.0, abs(pr) - 1.0)
        C[k, 0] = w[0] * (h * h)
        C[k, 1] = w[1] * (th * th)
        C[k, 2] = w[2] * hr * hr
        C[k, 3] = w[3] * pr * pr
        C[k, 4] = w[4] * (ho * ho + po * po)
        C[k, 5] = w[5] * M[b, _C_HITS]
        C[k, 6] = w[6] * (1.0 if M[b, _C_MINT] <= slack else 0.0)
        C[k, 7] = w[7] * max(0.0, (M[b, _C_RATIO] - f) / (1.0 - f))
        C[k, 8] = w[8] * (eff * eff)
        C[k, 9] = w[9] * da2
        tot = 0.0
        for j in range(nc):
            tot += C[k, j]
        if not math.isfinite(tot):          # never hand NaN to a learner
            tot = 0.0
            for j in range(nc):
                if not math.isfinite(C[k, j]):
                    C[k, j] = 1e6
                tot += C[k, j]
        R[k] = -tot


class HeaveOnlyReward(HeavePitchReward):
    """Heave (and heave-rate) cost only, with the same safety penalties."""

    def __init__(self, weights=None, **kw):
        base = dict(pitch=0.0, pitch_rate=0.0, rate_over=0.0)
        base.update(weights or {})
        super().__init__(base, **kw)


# =====================================================================================================
# Termination
# =====================================================================================================
#: comparison operators of a :class:`Limit` (``measurement <op> value`` ends the episode)
LIMIT_OPS = (">=", ">", "<=", "<")


@dataclass(frozen=True)
class Limit:
    """One terminal condition on a measurement column: the episode ends when ``m[key] <op> value`` (a NaN
    reading meets no limit). ``key`` is a column of :data:`~towenv.envs.measurements.MEAS_COLUMNS`, ``op``
    one of :data:`LIMIT_OPS`, ``reason`` the name reported in ``info["termination"]``."""
    key: str
    op: str
    value: float
    reason: str

    def __post_init__(self):
        if self.key not in COL:
            raise ValueError(f"Limit: key {self.key!r} is not a measurement column; columns: {sorted(COL)}")
        if self.op not in LIMIT_OPS:
            raise ValueError(f"Limit: op must be one of {list(LIMIT_OPS)} (got {self.op!r})")
        v = self.value
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)) \
                or not math.isfinite(float(v)):
            raise ValueError(f"Limit: value must be a finite number (got {v!r})")
        if not isinstance(self.reason, str) or not self.reason:
            raise ValueError(f"Limit: reason must be a non-empty str (got {self.reason!r})")
        object.__setattr__(self, "value", float(v))

    def met(self, x: float) -> bool:
        v = self.value
        return {">=": x >= v, ">": x > v, "<=": x <= v, "<": x < v}[self.op]


class Termination:
    """Protocol: ``term(m) -> reason or None``: why the episode ends for good at measurement ``m`` (a str,
    reported as ``info["termination"]``; the reward function's ``terminal_cost`` is charged), or None while
    it goes on. Truncation (``episode_seconds``, numerical failure) is the environment's, not the piece's.

    ``limits``: None, or a tuple of :class:`Limit` making the same decision as thresholds on measurement
    columns. The environment then evaluates them compiled, for all copies of a vector environment at once,
    and calls ``term(m)`` only for a copy that ends (for its reason); without limits it calls ``term(m)``
    for every copy at every step (``m`` as for the reward, plus every column of the measurement row and
    ``m["overloaded"]``: the lines, and ``"tow point"``, at or above their breaking load). A piece is shared
    by the copies of a vector environment: keep it stateless."""

    limits: tuple[Limit, ...] | None = None

    def __call__(self, m) -> str | None:  # pragma: no cover
        raise NotImplementedError


class Limits(Termination):
    """The episode ends when any of ``limits`` (:class:`Limit`) is met; the reason is the first met limit's
    ``reason: key = reading``. ``Limits()`` never terminates."""

    def __init__(self, *limits: Limit):
        for lim in limits:
            if not isinstance(lim, Limit):
                raise ValueError(f"Limits: every entry must be a towenv.envs.pieces.Limit (got {lim!r})")
        self.limits = tuple(limits)

    def __call__(self, m):
        for lim in self.limits:
            x = float(m[lim.key])
            if lim.met(x):
                return f"{lim.reason}: {lim.key} = {x:g} {lim.op} {lim.value:g}"
        return None


class PartedOrGrounded(Limits):
    """The default termination: the cable parts — the largest tension / breaking load over all lines and
    the tow point reaches 1 (``tension_ratio >= 1``; the loads are the environment's ``breaking_load``) — or
    the towed body goes below the floor (``fish_depth > floor_depth``; ``floor_depth=None``: no floor).
    ``body`` names the body in the reason (``"fish_below_floor: depth 39.9 m > 30 m"``)."""

    def __init__(self, floor_depth: float | None = 80.0, body: str = "fish"):
        if floor_depth is not None and (isinstance(floor_depth, bool) or not isinstance(floor_depth, (int, float))
                                        or not math.isfinite(floor_depth) or floor_depth <= 0):
            raise ValueError(f"PartedOrGrounded: floor_depth must be a finite number > 0 m or None (no floor) "
                             f"(got {floor_depth!r})")
        self.floor_depth = None if floor_depth is None else float(floor_depth)
        self.body = str(body)
        lims = [Limit("tension_ratio", ">=", 1.0, "cable_parted")]
        if self.floor_depth is not None:
            lims.append(Limit("fish_depth", ">", self.floor_depth, f"{self.body}_below_floor"))
        super().__init__(*lims)

    def __call__(self, m):
        if m["tension_ratio"] >= 1.0:
            which = m.get("overloaded")
            where = f" ({', '.join(which)})" if which is not None else ""
            return f"cable_parted: tension above the breaking load{where}"
        if self.floor_depth is not None and m["fish_depth"] > self.floor_depth:
            return f"{self.body}_below_floor: depth {m['fish_depth']:.1f} m > {self.floor_depth:g} m"
        return None
