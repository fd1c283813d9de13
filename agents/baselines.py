"""Baseline controllers for the towenv environments, with SB3's ``predict`` signature.

Every baseline is built for one environment instance (``make_baseline(name, env)``) and is called as an
SB3 policy: ``action, state = policy.predict(obs, state=None, episode_start=None, deterministic=True)``.
Pass ``episode_start`` truthy on the first step of every episode (as SB3's ``evaluate_policy`` and
:func:`agents.metrics.rollout` do): baselines that configure the simulator or look up per-sea-state
gains do it then. ``acts_on`` says what a baseline uses:

* ``"observations"`` — only the observation vector (decoded with :class:`agents.common.ObsReader`);
* ``"env"`` — it also reads or sets ``env.unwrapped`` at episode start: the simulator's actuator mode
  (``sim.set_compensator(mode="locked")``, ``sim.set_winch(mode="constant_tension", ...)``) and/or
  the episode's sea state (``env.unwrapped.sea``: a *gain-scheduled* baseline that knows Hs and Tp).

``towenv/CompensatorGains-v0`` (action = log-mapped stiffness and damping):

==================  ======  ====================================================================
``locked``          env     compensator locked (no compensation; the reference of the CRs)
``default_passive`` obs     the scene's fixed setting k = 20 kN/m, b = 5 kN s/m
``best_passive``    env     best fixed (k, b) per sea state from a grid search with no end-stop hits
``hover``           env     Hover et al. (1994) rules: min stiffness + damping for the travel, or lock
``skyhook``         obs     skyhook semi-active law, gains per sea state (``agents.classical``)
``clairvoyant_active`` env  bound: active stroke trajectory with perfect foresight (``agents.clairvoyant``)
==================  ======  ====================================================================

``towenv/WinchPayout-v0`` (action = payout speed / max speed):

====================  ======  ==================================================================
``fixed_winch``       obs     winch stopped (no compensation; the reference of the CRs)
``pd_ff``             env     tuned feed-forward (tow-point velocity, acceleration) + PD on the fish
                              heave + length centring, gains per sea state (grid/coordinate search)
``constant_tension``  env     the simulator's constant-tension winch (set tension = static top-segment
                              tension, gain per sea state)
``along_cable``       obs     along-cable feed-forward + feedback, gains per sea state (``agents.classical``);
                              the strongest causal classical baseline
``clairvoyant``       env     reference: length trajectory planned with perfect foresight within the same
                              limits (``agents.clairvoyant``)
====================  ======  ==================================================================

Tuned values live in ``agents/hyperparams/baselines.yml`` (written by ``python -m agents.tuning``).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from .common import ObsReader, env_kind, nearest_key, sea_key

__all__ = ["STRONGEST", "CLAIRVOYANT", "Baseline", "LockedCompensator", "FixedPassive", "TabulatedPassive", "FixedWinch", "PDFeedForwardWinch",
           "ConstantTensionWinch", "BASELINES", "make_baseline", "baseline_names", "load_tuned", "TUNED_PATH",
           "DEFAULT_PD_GAINS", "DEFAULT_CT_GAIN"]

TUNED_PATH = Path(__file__).resolve().parent / "hyperparams" / "baselines.yml"

#: PD/FF gains used when no tuned table is available (hand-tuned on coastal SS4, see docs/agents.md)
DEFAULT_PD_GAINS = {"g_ff": 0.5, "g_acc": 0.0, "kp": 0.5, "kd": 0.5, "kl": 0.02}
#: constant-tension winch gain (m/s per N) used when no tuned table is available (the scene default)
DEFAULT_CT_GAIN = 1.0e-4


def load_tuned(path: str | Path | None = None) -> dict:
    """The tuned-baseline tables ({} if the file does not exist)."""
    p = Path(path) if path else TUNED_PATH
    if not p.exists():
        return {}
    import yaml
    with open(p) as f:
        return yaml.safe_load(f) or {}


def _first(flag) -> bool:
    if flag is None:
        return False
    return bool(np.any(flag))


class Baseline:
    """Base class: SB3-like ``predict`` + an episode-start hook."""
    name = "baseline"
    kind = "any"               # "compensator" | "winch"
    acts_on = "observations"

    def __init__(self, env):
        self.env = env
        self.u = env.unwrapped
        k = env_kind(self.u)
        if self.kind != "any" and k != self.kind:
            raise ValueError(f"baseline {self.name!r} drives the {self.kind} environment, not {type(self.u).__name__}")
        self.reader = ObsReader(env)
        self._started = False

    def reset(self) -> None:
        """Called at the start of every episode (after ``env.reset``)."""

    def act(self, obs) -> np.ndarray:
        raise NotImplementedError

    def predict(self, obs, state=None, episode_start=None, deterministic: bool = True):
        if _first(episode_start) or not self._started:
            self._started = True
            self.reset()
        o = np.asarray(obs, dtype=float)
        if o.ndim == 2:                  # a batch of one (VecEnv): act on the first row
            return np.asarray(self.act(o[0]), np.float32)[None, :], state
        return np.asarray(self.act(o), np.float32), state

    def describe(self) -> str:
        return self.name


# ============================================================================ CompensatorGains
class LockedCompensator(Baseline):
    """No compensation: the compensator is locked at mid-stroke (``sim.set_compensator(mode="locked")``
    at every episode start; ``sim.reset()`` restores passive mode). The action (gains) is irrelevant."""
    name = "locked"
    kind = "compensator"
    acts_on = "env"

    def reset(self):
        self.u.sim.set_compensator(mode="locked")
        cs = self.u.sim.compensator_state()
        self._a = self.u.action_of(cs["stiffness"], cs["damping"])

    def act(self, obs):
        return self._a

    def describe(self):
        return "locked compensator (no compensation)"


class FixedPassive(Baseline):
    """A fixed passive setting (k N/m, b N s/m) for every sea state (acts on nothing)."""
    name = "fixed_passive"
    kind = "compensator"
    acts_on = "observations"

    def __init__(self, env, stiffness: float | None = None, damping: float | None = None, name: str | None = None):
        super().__init__(env)
        c = self.u.sim.scene.compensator
        self.k = float(c.stiffness if stiffness is None else stiffness)
        self.b = float(c.damping if damping is None else damping)
        self._a = self.u.action_of(self.k, self.b)
        if name:
            self.name = name

    def act(self, obs):
        return self._a

    def describe(self):
        return f"fixed passive k = {self.k:.4g} N/m, b = {self.b:.4g} N s/m"


class TabulatedPassive(Baseline):
    """Per-sea-state (k, b) or "locked" from a table keyed by :func:`agents.common.sea_key` (nearest
    (Hs, Tp) entry); the episode's sea state is read from ``env.unwrapped.sea`` at episode start."""
    kind = "compensator"
    acts_on = "env"

    def __init__(self, env, table: dict[str, dict], name: str, label: str):
        super().__init__(env)
        if not table:
            raise ValueError(f"baseline {name!r}: empty table (run `python -m agents.tuning`)")
        self.table = table
        self.name = name
        self.label = label
        self.entry: dict = {}

    def reset(self):
        sea = self.u.sea[0]
        self.entry = self.table[nearest_key(self.table, sea)]
        if self.entry.get("mode", "passive") == "locked":
            self.u.sim.set_compensator(mode="locked")
            cs = self.u.sim.compensator_state()
            self._a = self.u.action_of(cs["stiffness"], cs["damping"])
        else:
            self._a = self.u.action_of(float(self.entry["stiffness"]), float(self.entry["damping"]))

    def act(self, obs):
        return self._a

    def describe(self):
        parts = []
        for k, e in self.table.items():
            if e.get("mode", "passive") == "locked":
                parts.append(f"{k}: locked")
            else:
                parts.append(f"{k}: k={float(e['stiffness']):.4g}, b={float(e['damping']):.4g}")
        return f"{self.label} ({'; '.join(parts)})"


# ============================================================================ WinchPayout
class FixedWinch(Baseline):
    """No compensation: payout speed 0 (the winch holds the initial length)."""
    name = "fixed_winch"
    kind = "winch"
    acts_on = "observations"

    def act(self, obs):
        return np.zeros(1)

    def describe(self):
        return "fixed winch (no compensation)"


class PDFeedForwardWinch(Baseline):
    """Active heave compensation with the winch (perfect sensing of the observed channels)::

        v = g_ff·(w_tow + g_acc·a_tow) + kp·h + kd·ḣ − kl·ΔL        (m/s, payout > 0),  a = v / v_max

    w_tow, a_tow = tow-point vertical velocity and acceleration (feed-forward: pay out as the stern
    rises), h, ḣ = fish heave (+ up; about its running mean when ``fish_heave_dev`` is observed) and heave rate (PD: pay out when the fish is above its steady-tow
    depth), ΔL = winch-line length change (keeps the winch inside its travel). Gains per sea state from
    ``baselines.yml`` (``pd_ff``), or one set for all (``gains=``)."""
    name = "pd_ff"
    kind = "winch"
    acts_on = "observations"

    def __init__(self, env, gains: dict | None = None, table: dict[str, dict] | None = None, name: str | None = None):
        super().__init__(env)
        for ch in ("tow_vel_z", "fish_heave_rate"):
            if not self.reader.has(ch):
                raise ValueError(f"pd_ff needs the observation channel {ch!r}")
        self._h = "fish_heave_dev" if self.reader.has("fish_heave_dev") else "fish_heave"
        if not self.reader.has(self._h):
            raise ValueError("pd_ff needs the observation channel 'fish_heave_dev' (or 'fish_heave')")
        self.table = table or None
        if self.table:
            self.acts_on = "env"          # reads env.unwrapped.sea to pick the gains
        self.fixed = dict(DEFAULT_PD_GAINS | (gains or {}))
        self.g = dict(self.fixed)
        self.vmax = float(self.u.winch_max_speed)
        if name:
            self.name = name

    def reset(self):
        if self.table:
            self.g = dict(DEFAULT_PD_GAINS | self.table[nearest_key(self.table, self.u.sea[0])])

    def act(self, obs):
        r, g = self.reader, self.g
        v = (g["g_ff"] * (r(obs, "tow_vel_z") + g["g_acc"] * r(obs, "tow_acc_z", 0.0))
             + g["kp"] * r(obs, self._h) + g["kd"] * r(obs, "fish_heave_rate")
             - g["kl"] * r(obs, "winch_length_dev", 0.0))
        return np.array([min(max(v / self.vmax, -1.0), 1.0)])

    def describe(self):
        if self.table:
            parts = [f"{k}: " + ", ".join(f"{n}={float(v):.3g}" for n, v in e.items() if n in DEFAULT_PD_GAINS)
                     for k, e in self.table.items()]
            return "PD + feed-forward winch, gains per sea state (" + "; ".join(parts) + ")"
        return "PD + feed-forward winch (" + ", ".join(f"{n}={v:.3g}" for n, v in self.g.items()) + ")"


class ConstantTensionWinch(Baseline):
    """The simulator's constant-tension winch: ``sim.set_winch(mode="constant_tension", set_tension=T0)``
    at episode start, T0 = the static tension of the top segment of the winch line; payout speed =
    gain × (T − T0) inside the winch's speed/acceleration/travel limits (``set_winch(gain=...)``). The action
    is ignored."""
    name = "constant_tension"
    kind = "winch"
    acts_on = "env"

    def __init__(self, env, gain: float | None = None, table: dict[str, dict] | None = None):
        super().__init__(env)
        self.table = table or None
        self.fixed_gain = float(gain if gain is not None else DEFAULT_CT_GAIN)
        self.gain = self.fixed_gain

    def reset(self):
        from towenv.core import kernels as K
        sim = self.u.sim
        if self.table:
            self.gain = float(self.table[nearest_key(self.table, self.u.sea[0])]["gain"])
        seg = int(sim.winch[K.W_SEG])
        sim.set_winch(mode="constant_tension", set_tension=float(sim.tensions[seg]), gain=self.gain)

    def act(self, obs):
        return np.zeros(1)

    def describe(self):
        if self.table:
            return "constant-tension winch, gain per sea state (" + "; ".join(
                f"{k}: {float(e['gain']):.3g} m/s/N" for k, e in self.table.items()) + ")"
        return f"constant-tension winch (gain {self.gain:.3g} m/s/N)"


# ============================================================================ registry
def _best_passive(env, tuned):
    return TabulatedPassive(env, tuned.get("best_passive", {}), "best_passive",
                            "best fixed passive (k, b) per sea state, grid search, no end-stop hits")


def _hover(env, tuned):
    return TabulatedPassive(env, tuned.get("hover", {}), "hover", "Hover et al. (1994) tuning rules per sea state")


def _along_cable(env, tuned):
    from .classical import AlongCableWinch
    return AlongCableWinch(env, table=tuned.get("along_cable") or None)


def _skyhook(env, tuned):
    from .classical import SkyhookCompensator
    return SkyhookCompensator(env, table=tuned.get("skyhook") or None)


def _clairvoyant(env, tuned):
    from .clairvoyant import ClairvoyantWinch
    return ClairvoyantWinch(env)


def _clairvoyant_active(env, tuned):
    from .clairvoyant import ClairvoyantActiveCompensator
    return ClairvoyantActiveCompensator(env)


BASELINES: dict[str, tuple[str, Any]] = {
    "locked": ("compensator", lambda env, tuned: LockedCompensator(env)),
    "default_passive": ("compensator", lambda env, tuned: FixedPassive(env, name="default_passive")),
    "best_passive": ("compensator", _best_passive),
    "hover": ("compensator", _hover),
    "fixed_winch": ("winch", lambda env, tuned: FixedWinch(env)),
    "pd_ff": ("winch", lambda env, tuned: PDFeedForwardWinch(env, table=tuned.get("pd_ff") or None)),
    "constant_tension": ("winch", lambda env, tuned: ConstantTensionWinch(env, table=tuned.get("constant_tension") or None)),
    "along_cable": ("winch", _along_cable),
    "skyhook": ("compensator", _skyhook),
    "clairvoyant": ("winch", _clairvoyant),
    "clairvoyant_active": ("compensator", _clairvoyant_active),
}

#: the strongest causal classical baseline of each environment kind (the goals compare against it) and the
#: clairvoyant reference / bound (docs/agents.md)
STRONGEST = {"compensator": "skyhook", "winch": "along_cable"}
CLAIRVOYANT = {"compensator": "clairvoyant_active", "winch": "clairvoyant"}

#: the no-compensation reference of each environment kind (denominator of the compensation ratios)
REFERENCE = {"compensator": "locked", "winch": "fixed_winch"}


def baseline_names(kind: str | None = None) -> list[str]:
    """Names of the baselines (of one environment kind: ``"compensator"`` / ``"winch"``)."""
    return [n for n, (k, _) in BASELINES.items() if kind is None or k == kind]


def make_baseline(name: str, env, tuned: dict | None = None) -> Baseline:
    """Build baseline ``name`` for ``env`` (tuned tables from ``agents/hyperparams/baselines.yml``)."""
    if name not in BASELINES:
        raise KeyError(f"unknown baseline {name!r}; known: {sorted(BASELINES)}")
    kind, factory = BASELINES[name]
    if env_kind(env) != kind:
        raise ValueError(f"baseline {name!r} is for the {kind} environment")
    return factory(env, load_tuned() if tuned is None else tuned)
