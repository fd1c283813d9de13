"""``TowEnv``: the Gymnasium base environment around one :class:`towenv.Simulator` per configuration.

The physics core knows nothing about Gymnasium. A step runs through :class:`towenv.envs.stepper.BatchStepper`
(one compiled call: actuator command, all physics sub-steps of ``kernels.advance``, measurement row) — the
same code as the batched vector environment (:mod:`towenv.envs.vector`), here with one row; the episode's
reference values, previous action and measurement live in that row (:class:`EnvRows`). Reset uses the public
``Simulator`` API (``set_sea``/``reset``/``body_state``/``top_tension``/``compensator_state``/``winch_state``).
The IMU channels are differences of the prescribed tow-point history ``sim.hist_r[:, top_node]``.

Control: every ``step`` applies the action once and advances ``substeps = round(1/(control_hz·dt))``
physics steps of ``dt`` (action repetition = sub-stepping); ``env.dt = dt·substeps`` is the control period.
"""
from __future__ import annotations

import math
import numbers
import warnings
from typing import Any, Mapping, Sequence

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numba import njit

from ..sea import SeaState
from ..sea.spectra import _CONVENTIONS as SEA_CONVENTIONS
from . import checks as C
from . import measurements as MS
from . import stepper as ST
from .pieces import (CHANNELS, HEAVE_RATE_LIMIT, LIMIT_OPS, PITCH_RATE_LIMIT, HeavePitchReward, Limit, Observer,
                     PartedOrGrounded, RandomCodeSeas, _heave_pitch_rows, _NO_PREVIEW, _observe_rows,
                     default_eval_sea_states)

__all__ = ["TowEnv", "DEFAULT_BREAKING_LOAD", "EnvRows", "RESET_OPTIONS", "MAX_OBS_DELAY"]

#: the keys ``reset(options=...)`` accepts (anything else raises :class:`~towenv.envs.checks.ConfigError`)
RESET_OPTIONS = ("eval_index", "sea_state", "sea_seed", "vessel_speed", "cable_length")
#: largest observation delay (control steps) the constructor accepts
MAX_OBS_DELAY = 1000

#: ASSUMED breaking loads (N) of the default scene's cables (neither the thesis nor the scene gives
#: them): primary = 0.68-inch double-armoured electro-mechanical cable (Hover et al. 1994's cable class),
#: ~160 kN; secondary = 12 mm jacketed aramid cable, ~20 kN. Lines not listed have no limit.
DEFAULT_BREAKING_LOAD = {"primary": 160.0e3, "secondary": 20.0e3}


class TowEnv(gym.Env):
    """Base class of the towenv environments (not registered itself: use a subclass).

    Keyword configuration (every parameter is a constructor keyword; see ``docs/environments.md``):

    scene, scene_overrides
        Scene (name/path/dict/Scene) and dotted overrides (``{"vessel.speed": 2.5}``).
    control_hz, dt, episode_seconds
        Control rate (Hz), physics step (s) and episode length (s); the env truncates itself at
        ``round(episode_seconds / env.dt)`` steps (no ``TimeLimit`` wrapper is registered).
    sea_codes, sea_convention, heading_deg, heading_spread_deg, sea_generator
        Sea-state distribution: by default :class:`~towenv.envs.pieces.RandomCodeSeas` over WMO codes 3–5,
        coastal periods, head seas ±30°, drawn from ``self.np_random``. ``sea_generator`` replaces it.
    vessel_speeds, cable_lengths, cable_line
        Optional discrete sets drawn uniformly at each reset (default ``None`` = the scene's values). One
        Simulator is built (lazily) and cached per (speed, length) pair.
    observations, sensor_noise, obs_delay, preview_distances, observation_fn
        Observation channel names (:data:`~towenv.envs.pieces.CHANNELS`), noise std per channel (physical
        units), delay in control steps, wave-preview distances (m ahead), or a whole custom observer.
    reward_weights, reward_fn, slack_tension, over_tension_fraction
        Weights of :class:`~towenv.envs.pieces.HeavePitchReward` or a replacement ``RewardFn``.
    breaking_load, floor_depth, termination
        Breaking loads (N; float for every line or ``{line: N or None}``; the ``tension_ratio`` measurement)
        and the floor depth (m) of the towed body: by default (:class:`~towenv.envs.pieces.PartedOrGrounded`)
        exceeding either *terminates* the episode. ``breaking_load=None`` means :data:`DEFAULT_BREAKING_LOAD`
        (``{}`` = no limit); ``floor_depth=None`` disables the floor. ``termination`` replaces the default
        piece (a :class:`~towenv.envs.pieces.Termination`; ``floor_depth`` is then unused).
    body, sim_overrides, render_mode, renderer
        Towed body scored (default ``"fish"``), solver overrides passed to ``Simulator`` (e.g.
        ``{"max_step_cuts": 0}``), ``"rgb_array"`` or ``"human"``, and what draws the frames: a callable
        ``renderer(env) -> frame`` (an (H, W, 3) uint8 array for ``"rgb_array"``), with an optional ``close()``;
        default :class:`~towenv.envs.render.SideViewer`.

    Every keyword and every ``reset`` option is checked (:class:`~towenv.envs.checks.ConfigError`, naming it);
    a malformed action raises :class:`~towenv.envs.checks.ActionError` and ``step`` without a live episode
    :class:`~towenv.envs.checks.ResetNeeded` (docs/environments.md "Errors and validation").
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 10}

    #: default observation channels (subclasses override)
    DEFAULT_OBSERVATIONS: tuple[str, ...] = ("tow_vel_z", "tow_acc_z", "top_tension", "fish_heave", "fish_pitch",
                                             "fish_heave_rate", "fish_pitch_rate", "last_action")
    ACTION_DIM = 1
    DEFAULT_SCENE = "two_part_coastal_ss4"

    def __init__(self, *, scene: Any = None, scene_overrides: Mapping[str, Any] | None = None,
                 control_hz: float = 10.0, dt: float | None = None, episode_seconds: float = 300.0,
                 sea_codes: Sequence[int] = (3, 4, 5), sea_convention: str = "coastal",
                 heading_deg: float = 180.0, heading_spread_deg: float = 30.0, sea_generator=None,
                 vessel_speeds: Sequence[float] | None = None, cable_lengths: Sequence[float] | None = None,
                 cable_line: str = "primary",
                 observations: Sequence[str] | None = None, sensor_noise: Mapping[str, float] | None = None,
                 obs_delay: int = 0, preview_distances: Sequence[float] = (), observation_fn=None,
                 reward_weights: Mapping[str, float] | None = None, reward_fn=None,
                 slack_tension: float = 1.0, over_tension_fraction: float = 0.5,
                 breaking_load: float | Mapping[str, float] | None = None, floor_depth: float | None = 80.0,
                 termination=None,
                 body: str = "fish", sim_overrides: Mapping[str, Any] | None = None,
                 fidelity: float | None = None, render_mode: str | None = None, renderer=None,
                 mru_delay: float = 0.0, mean_time_constant: float | None = 30.0):
        super().__init__()
        own = type(self).__name__
        # ---- every keyword checked before anything is built (ConfigError naming the keyword)
        self.mru_delay = C.real(own, "mru_delay", mru_delay, 0.0, 5.0, unit="s")
        self.mean_time_constant = C.real(own, "mean_time_constant", mean_time_constant, 0.0, lo_open=True, unit="s",
                                         none="deviations about the steady tow")
        C.choice(own, "render_mode", render_mode, self.metadata["render_modes"], none="no rendering")
        if renderer is not None and not callable(renderer):
            raise C.ConfigError(f"{own}: renderer must be callable, renderer(env) -> frame (an (H, W, 3) uint8 array "
                                f"for render_mode 'rgb_array'), or None (the SideViewer) (got {renderer!r})")
        control_hz = C.real(own, "control_hz", control_hz, 0.0, lo_open=True, unit="Hz")
        dt = C.real(own, "dt", dt, 1e-5, 1.0, unit="s", none="the scene's solver.dt or automatic")
        fidelity = C.real(own, "fidelity", fidelity, 0.0, 1.0, lo_open=True, hi_open=True,
                          none="the scene's setting")
        episode_seconds = C.real(own, "episode_seconds", episode_seconds, 0.0, lo_open=True, unit="s")
        if isinstance(sea_codes, (str, bytes, Mapping)) or not C._iterable(sea_codes) or len(list(sea_codes)) == 0:
            raise C.ConfigError(f"{own}: sea_codes must be a non-empty sequence of WMO sea-state codes "
                                f"(integers 0..9) (got {sea_codes!r})")
        sea_codes = tuple(C.integer(own, "sea_codes entry", c, 0, 9) for c in sea_codes)
        C.choice(own, "sea_convention", sea_convention, SEA_CONVENTIONS)
        heading_deg = C.real(own, "heading_deg", heading_deg, unit="deg")
        heading_spread_deg = C.real(own, "heading_spread_deg", heading_spread_deg, 0.0, 180.0, unit="deg")
        if sea_generator is not None and not callable(sea_generator):
            raise C.ConfigError(f"{own}: sea_generator must be callable, gen(rng) -> (SeaState, wave_seed), or None "
                                f"(RandomCodeSeas over sea_codes) (got {sea_generator!r})")
        vessel_speeds = C.real_seq(own, "vessel_speeds", vessel_speeds, 0.0, lo_open=True, empty=False, unit="m/s",
                                   none="the scene's speed")
        cable_lengths = C.real_seq(own, "cable_lengths", cable_lengths, 0.0, lo_open=True, empty=False, unit="m",
                                   none="the scene's length")
        if not isinstance(cable_line, str):
            raise C.ConfigError(f"{own}: cable_line must be a line name (str) (got {cable_line!r})")
        if observations is not None and (isinstance(observations, (str, bytes, Mapping))
                                         or not C._iterable(observations)
                                         or not all(isinstance(n, str) for n in observations)):
            raise C.ConfigError(f"{own}: observations must be a sequence of channel names, or None (the defaults) "
                                f"(got {observations!r}); channels: {sorted(CHANNELS)}")
        noise = C.mapping(own, "sensor_noise", sensor_noise, none="no noise")
        for k, v in noise.items():
            noise[k] = C.real(own, f"sensor_noise[{k!r}]", v, 0.0)
        obs_delay = C.integer(own, "obs_delay", obs_delay, 0, MAX_OBS_DELAY, whole_floats=True)
        preview_distances = C.real_seq(own, "preview_distances", preview_distances, unit="m")
        if observation_fn is not None and not (
                callable(observation_fn) and callable(getattr(observation_fn, "reset", None))
                and hasattr(observation_fn, "low") and hasattr(observation_fn, "high")):
            raise C.ConfigError(f"{own}: observation_fn must be an Observer-like object (callable, with reset(m, rng) "
                                f"and low/high bound arrays), or None (got {observation_fn!r})")
        weights = C.mapping(own, "reward_weights", reward_weights, none="the defaults")
        for k, v in weights.items():
            if k not in HeavePitchReward.DEFAULTS:
                raise C.ConfigError(f"{own}: unknown reward weight {k!r} in reward_weights; known: "
                                    f"{sorted(HeavePitchReward.DEFAULTS)}")
            weights[k] = C.real(own, f"reward_weights[{k!r}]", v, 0.0)
        if reward_fn is not None and not callable(reward_fn):
            raise C.ConfigError(f"{own}: reward_fn must be callable, fn(m, action, prev_action) -> (reward, "
                                f"components), or None (HeavePitchReward) (got {reward_fn!r})")
        slack_tension = C.real(own, "slack_tension", slack_tension, 0.0, unit="N")
        over_tension_fraction = C.real(own, "over_tension_fraction", over_tension_fraction, 0.0, 1.0, hi_open=True)
        if breaking_load is not None and not isinstance(breaking_load, Mapping):
            C.real(own, "breaking_load", breaking_load, 0.0, lo_open=True, unit="N")
        elif breaking_load is not None:
            for k, v in breaking_load.items():
                if not isinstance(k, str):
                    raise C.ConfigError(f"{own}: breaking_load keys must be line names (got {k!r})")
                C.real(own, f"breaking_load[{k!r}]", v, 0.0, lo_open=True, unit="N", none="no limit for that line")
        floor_depth = C.real(own, "floor_depth", floor_depth, 0.0, lo_open=True, unit="m", none="no floor")
        if not isinstance(body, str):
            raise C.ConfigError(f"{own}: body must be a body name (str) (got {body!r})")
        sim_overrides = C.mapping(own, "sim_overrides", sim_overrides, none="the scene's solver settings")
        scene_overrides = C.mapping(own, "scene_overrides", scene_overrides, none="no overrides")

        self.render_mode = render_mode
        self.renderer = renderer
        self.control_hz = float(control_hz)

        self.sea_codes = sea_codes
        self.sea_convention = sea_convention
        self.sea_generator = sea_generator if sea_generator is not None else RandomCodeSeas(
            self.sea_codes, sea_convention, heading_deg, heading_spread_deg)
        self.vessel_speeds = vessel_speeds
        self.cable_lengths = cable_lengths
        self.cable_line = cable_line
        self.body = body
        self.floor_depth = floor_depth
        self.termination = termination if termination is not None else PartedOrGrounded(floor_depth, body)
        if breaking_load is None:
            breaking_load = DEFAULT_BREAKING_LOAD
        self.breaking_load = breaking_load
        self.sim_overrides = sim_overrides

        self.reward_fn = reward_fn if reward_fn is not None else HeavePitchReward(
            weights or None, slack_tension=slack_tension, over_tension_fraction=over_tension_fraction)
        try:
            self.observer = observation_fn if observation_fn is not None else Observer(
                observations if observations is not None else self.DEFAULT_OBSERVATIONS, noise or None, obs_delay,
                action_dim=self.ACTION_DIM, preview_distances=preview_distances)
        except C.ConfigError:
            raise
        except ValueError as exc:
            raise C.ConfigError(f"{own}: observations / sensor_noise / preview_distances: {exc}") from None

        from ..scene import load_scene
        try:
            base = load_scene(scene if scene is not None else self.DEFAULT_SCENE)
        except (ValueError, TypeError, OSError) as exc:
            raise C.ConfigError(f"{own}: scene {scene!r}: {exc}") from exc
        if scene_overrides:
            try:
                base = base.with_overrides(scene_overrides)
            except (ValueError, TypeError) as exc:
                raise C.ConfigError(f"{own}: scene_overrides: {exc}") from exc
        try:
            self.base_scene = self._prepare_scene(base)
        except C.ConfigError:
            raise
        except ValueError as exc:
            raise C.ConfigError(f"{own}: scene: {exc}") from exc
        lines = [ln.name for ln in self.base_scene.lines]
        if isinstance(breaking_load, Mapping):
            unknown = [k for k in breaking_load if k not in lines]
            if unknown:
                raise C.ConfigError(f"{own}: breaking_load names line(s) {unknown} that scene "
                                    f"{self.base_scene.name!r} does not have (lines: {lines})")
        self.fidelity = None
        dt = self._resolve_time_step(dt, fidelity, heading_deg,
                                     planar_ok=heading_spread_deg == 0 and sea_generator is None)
        self.physics_dt = float(dt)
        ratio = 1.0 / (control_hz * dt)
        if not ratio < ST.BLOCK + 0.5:
            raise C.ConfigError(f"{own}: control_hz and dt must give at most {ST.BLOCK} physics steps per control step "
                                f"(1/(control_hz·dt) = 1/({control_hz:g} Hz · {dt:g} s) = {ratio:g})")
        self.substeps = max(1, int(round(ratio)))
        if abs(self.substeps * dt * control_hz - 1.0) > 1e-6:
            warnings.warn(f"TowEnv: 1/(control_hz·dt) = {1.0 / (control_hz * dt):g} is not a whole number; "
                          f"using {self.substeps} physics steps per control step (control period "
                          f"{self.substeps * dt:g} s)", stacklevel=2)
        self.dt = self.substeps * self.physics_dt           # control period (MuJoCo frame_skip convention)
        if round(self.mru_delay / self.physics_dt) > ST.BLOCK // 2:
            raise C.ConfigError(f"{own}: mru_delay must be at most {ST.BLOCK // 2} physics steps "
                                f"({ST.BLOCK // 2 * self.physics_dt:g} s at dt = {self.physics_dt:g} s; "
                                f"got {self.mru_delay!r})")
        self.episode_seconds = float(episode_seconds)
        self.max_steps = max(1, int(round(episode_seconds / self.dt)))
        self.metadata = dict(self.metadata, render_fps=max(1, int(round(1.0 / self.dt))))
        if cable_lengths is not None and cable_line not in lines:
            raise C.ConfigError(f"{own}: cable_line {cable_line!r} is not a line of scene {self.base_scene.name!r} "
                                f"(lines: {lines})")
        # every configuration of the sets must make a valid scene (the simulators are built lazily)
        for v in vessel_speeds or ():
            self._checked_config_scene(v, None, "vessel_speeds")
        for v in cable_lengths or ():
            self._checked_config_scene(None, v, "cable_lengths")
        self._sims: dict[tuple, Any] = {}
        self._config = (None, None)
        try:
            self.sim = self._get_sim(None, None)           # the default configuration, built eagerly
        except C.ConfigError:
            raise
        except (ValueError, TypeError) as exc:
            raise C.ConfigError(f"{own}: the simulator cannot be built from scene / scene_overrides / "
                                f"sim_overrides: {exc}") from exc
        try:
            self.sim.body_state(self.body)
        except KeyError as exc:
            raise C.ConfigError(f"{own}: body {body!r}: {exc.args[0]}") from None
        self._check_actuator(self.sim)

        self._wants_preview = bool(getattr(self.observer, "wants_preview", False))
        self.action_space = spaces.Box(-1.0, 1.0, (self.ACTION_DIM,), np.float32)
        self.observation_space = spaces.Box(self.observer.low, self.observer.high, dtype=np.float32)
        self._sea = None
        self._tension_cache = (None, None)
        self._viewer = None
        self._rows = EnvRows(1, self.ACTION_DIM)       # the vector env re-points this at its shared rows
        self._rows.envs[0] = self
        self._row = 0
        self._act_shape = (self.ACTION_DIM,)
        self._needs_reset = "before"                    # step() raises ResetNeeded until reset()
        self._install_row()

    def _install_row(self) -> None:
        """Install the current simulator in this env's row of the batch stepper (as it is: a new env's
        simulator is at its initial state)."""
        self._rows.stepper.refs[self._row, MS.R_MAXSTEPS] = self.max_steps
        self._rows.stepper.set_copy(self._row, self.sim, self.body, self._inv_seg)

    # ------------------------------------------------------------------ per-episode state (in the rows)
    @property
    def _steps(self) -> int:
        return int(self._rows.stepper.refs[self._row, MS.R_STEPS])

    @property
    def _prev_action(self) -> np.ndarray:
        return self._rows.prev_action[self._row].copy()

    @property
    def _z_ref(self) -> float:
        return float(self._rows.stepper.refs[self._row, MS.R_ZREF])

    @property
    def _T_ref(self) -> float:
        return float(self._rows.stepper.refs[self._row, MS.R_TREF])

    @property
    def _last_m(self) -> dict:
        """The last measurement as a dict (keys of :data:`~towenv.envs.pieces.MEASUREMENTS`)."""
        return self._row_dict(self._rows.stepper.M[self._row], self._rows.prev_action[self._row])

    # ------------------------------------------------------------------ subclass hooks
    def _resolve_time_step(self, dt, fidelity, heading_deg, planar_ok=False):
        """Physics Δt: ``dt`` if given; else automatic fidelity selection (towenv.fidelity, docs/fidelity.md)
        over the divisors of the control period — Δt, segments and 2-D/3-D with ``fidelity`` (or the scene's
        ``solver.fidelity``), Δt alone when the scene does not set ``solver.dt``; else the scene's Δt. The
        choice is made once, for the middle sea state of ``sea_codes`` (``self.fidelity`` records it); 2-D only
        with a fixed head/following heading (``heading_spread_deg = 0``) and the default sea generator."""
        if dt is not None:
            return float(dt)
        sc = self.base_scene
        if fidelity is None and sc.solver.fidelity is None and "dt" in sc.solver.model_fields_set:
            return float(sc.solver.dt)
        from ..fidelity import configure
        from ..sea import SeaState
        period = 1.0 / self.control_hz
        cands = tuple(period / k for k in (1, 2, 4, 5, 10, 20) if 0.005 <= period / k <= 0.2)
        code = sorted(self.sea_codes)[len(self.sea_codes) // 2] if self.sea_codes else 4
        sea = SeaState.from_code(code, self.sea_convention, heading_deg=heading_deg)
        # the linearised predictor has no winch (payout remeshes): choose on the scene without it
        probe = sc.with_overrides({"winch": None}) if getattr(sc, "winch", None) is not None else sc
        try:
            _, choice = configure(probe, sea, fidelity, dt_candidates=cands or (period,), allow_planar=planar_ok)
        except ValueError:
            if fidelity is not None:
                raise
            choice = None
        if choice is None:
            return float(sc.solver.dt)
        self.base_scene = sc.with_overrides({k: v for k, v in choice.overrides().items() if k != "solver.dt"})
        self.fidelity = choice
        return float(choice.dt)

    def _prepare_scene(self, scene):
        """Turn the user's scene into the environment's scene (e.g. add the actuator). Default: as is."""
        return scene

    def _check_actuator(self, sim):
        """Raise ValueError if the scene lacks the actuator the environment drives."""

    def _config_scene(self, speed, length):
        """The scene of one (speed, cable length) configuration (``None`` = the base scene's value)."""
        from ..scene import JunctionAttachment
        sc = self.base_scene
        ov: dict[str, Any] = {}
        if speed is not None:
            ov["vessel.speed"] = float(speed)
        if length is not None:
            ln = sc.line(self.cable_line)
            d_len = float(length) - ln.length
            ov[f"lines.{ln.name}.length"] = float(length)
            for other in sc.lines:     # keep junctions on that line at their distance from its bottom end
                if isinstance(other.top, JunctionAttachment) and other.top.line == ln.name:
                    ov[f"lines.{other.name}.top.distance"] = other.top.distance + d_len
        return sc.with_overrides(ov) if ov else sc

    @staticmethod
    def _line_names(sim):
        return [ln.name for ln in sim.scene.lines]

    #: what the command columns mean (``towenv.envs.stepper.ACT_*``)
    ACT_KIND = ST.ACT_NONE
    #: measurement columns that belong to the actuator (reported in ``_last_m``)
    ACTUATOR_KEYS: tuple[str, ...] = ()

    def _commands(self, A: np.ndarray, rows: np.ndarray, U: np.ndarray, amap: np.ndarray) -> None:
        """Write the actuator commands of clipped actions ``A[rows]`` into ``U[rows]`` (vectorised;
        ``amap[rows]`` holds each copy's action-map parameters). Must first clean ``A[rows]`` in place:
        NaN -> 0, clip to [-1, 1] — and return the number of entries that changed (0 if none)."""
        return _clean_actions(A, rows)

    def _reset_action(self) -> np.ndarray:
        """The action equivalent of the actuator's state after reset (reported as ``last_action``)."""
        return np.zeros(self.ACTION_DIM)

    def _actuator_refs(self, refs: np.ndarray, amap: np.ndarray) -> None:
        """Per-episode actuator reference values of this copy (``refs``: its row of ``MS.R_*``; ``amap``:
        its row of action-map parameters used by :meth:`_commands`)."""

    # ------------------------------------------------------------------ configuration
    def _checked_config_scene(self, speed, length, what):
        """``_config_scene(speed, length)``, with a scene error re-raised as a ConfigError naming ``what``."""
        try:
            return self._config_scene(speed, length)
        except C.ConfigError:
            raise
        except (ValueError, TypeError, KeyError) as exc:
            val = speed if length is None else length
            raise C.ConfigError(f"{type(self).__name__}: {what} = {val!r} does not give a valid scene: "
                                f"{exc}") from exc

    def _get_sim(self, speed, length):
        key = (speed, length)
        sim = self._sims.get(key)
        if sim is None:
            from ..core.simulator import Simulator
            sim = Simulator(self._config_scene(speed, length), dt=self.physics_dt, **self.sim_overrides)
            self._sims[key] = sim
        return sim

    def eval_sea_states(self):
        """The fixed evaluation set: a list of ``(SeaState, wave_seed)`` (common random numbers: every
        controller sees the same wave realisations). Use with ``reset(options={"eval_index": i})`` or
        ``sea_generator=FixedSeas(env.eval_sea_states())``."""
        return default_eval_sea_states(self.sea_codes, self.sea_convention)

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        options = self._check_options(options)          # before anything changes (ConfigError)
        if seed is not None:                            # numpy integers too (gymnasium wants a Python int)
            seed = C.integer(type(self).__name__, "reset seed", seed, 0)
        super().reset(seed=seed)
        self._needs_reset = "failed"                    # until this reset has completed
        rng = self.np_random
        own = type(self).__name__
        speed = options.get("vessel_speed")
        if speed is None and self.vessel_speeds is not None:
            speed = self.vessel_speeds[int(rng.integers(len(self.vessel_speeds)))]
        length = options.get("cable_length")
        if length is None and self.cable_lengths is not None:
            length = self.cable_lengths[int(rng.integers(len(self.cable_lengths)))]
        if "sea_state" in options:
            sea, wseed = options["sea_state"], int(options.get("sea_seed", 0))
        elif "eval_index" in options:
            sea, wseed = self.eval_sea_states()[options["eval_index"]]
        else:
            drawn = self.sea_generator(rng)
            if not (isinstance(drawn, tuple) and len(drawn) == 2 and isinstance(drawn[0], SeaState)
                    and isinstance(drawn[1], numbers.Integral) and not isinstance(drawn[1], (bool, np.bool_))
                    and int(drawn[1]) >= 0):
                raise C.ConfigError(f"{own}: sea_generator must return (SeaState, wave_seed >= 0) "
                                    f"(got {drawn!r})")
            sea, wseed = drawn
        if (speed, length) in self._sims:
            sim = self._sims[(speed, length)]
        else:
            what = " / ".join(n for n, v in (("vessel_speed", speed), ("cable_length", length)) if v is not None)
            self._checked_config_scene(speed, length, what)
            try:
                sim = self._get_sim(speed, length)
            except (ValueError, TypeError, KeyError) as exc:
                raise C.ConfigError(f"{own}: {what} = {(speed, length)!r}: the simulator cannot be built: "
                                    f"{exc}") from exc
        self._config = (speed, length)
        self.sim = sim
        sim.set_sea(sea, int(wseed))
        sim.reset()
        self._sea = (sea, int(wseed))
        self._plan = None                               # step()'s prepared arrays and entry point: made anew
        obs = self._start_episode(sim, rng)
        info = {"sea_state": {"hs": float(sea.hs), "tp": float(sea.tp), "heading_deg": float(sea.heading_deg)},
                "sea_seed": int(wseed), "vessel_speed": float(sim.path.initial_speed), "t": 0.0}
        if self.cable_line in self._line_names(sim):
            info["cable_length"] = float(sim.scene.line(self.cable_line).length)
        self._needs_reset = False
        if self.render_mode == "human":
            self.render()
        return obs, info

    def _check_options(self, options) -> dict:
        """The ``reset`` options as a dict, every key and value checked (:data:`RESET_OPTIONS`)."""
        own = type(self).__name__
        if options is None:
            return {}
        if not isinstance(options, Mapping):
            raise C.ConfigError(f"{own}: reset options must be a dict or None (got {options!r}); "
                                f"keys: {list(RESET_OPTIONS)}")
        options = dict(options)
        unknown = [k for k in options if k not in RESET_OPTIONS]
        if unknown:
            raise C.ConfigError(f"{own}: unknown reset option(s) {unknown}; allowed: {list(RESET_OPTIONS)}")
        if "eval_index" in options:
            if "sea_state" in options:
                raise C.ConfigError(f"{own}: reset options eval_index and sea_state exclude each other "
                                    f"(got both)")
            n = len(self.eval_sea_states())
            options["eval_index"] = C.integer(own, "reset option eval_index", options["eval_index"], 0, n - 1)
        if "sea_state" in options and not isinstance(options["sea_state"], SeaState):
            raise C.ConfigError(f"{own}: reset option sea_state must be a towenv.sea.SeaState, e.g. "
                                f"SeaState.from_code(4, 'coastal') (got {options['sea_state']!r})")
        if "sea_seed" in options:
            if "sea_state" not in options:
                raise C.ConfigError(f"{own}: reset option sea_seed needs sea_state (the seed of that sea's wave "
                                    f"realisation); got sea_seed without sea_state")
            options["sea_seed"] = C.integer(own, "reset option sea_seed", options["sea_seed"], 0)
        if options.get("vessel_speed") is not None:
            options["vessel_speed"] = C.real(own, "reset option vessel_speed", options["vessel_speed"], 0.0,
                                             lo_open=True, unit="m/s")
        if options.get("cable_length") is not None:
            options["cable_length"] = C.real(own, "reset option cable_length", options["cable_length"], 0.0,
                                             lo_open=True, unit="m")
            lines = [ln.name for ln in self.base_scene.lines]
            if self.cable_line not in lines:
                raise C.ConfigError(f"{own}: reset option cable_length needs cable_line {self.cable_line!r} to be "
                                    f"a line of scene {self.base_scene.name!r} (lines: {lines})")
        return options

    def _start_episode(self, sim, rng) -> np.ndarray:
        """Install ``sim`` (just reset) in this env's row of the batch stepper, set the row's reference
        values and return the first observation."""
        rows, i = self._rows, self._row
        st = rows.stepper
        inv_seg, top_inv, _ = self._tension_layout(sim)
        ref = st.refs[i]
        ref[:] = 0.0
        ref[MS.R_ZREF] = float(sim.body_state(self.body)["position"][2])
        ref[MS.R_TREF] = max(float(sim.top_tension), 1e-9)
        ref[MS.R_TOPINV] = top_inv
        ref[MS.R_HALF_STROKE] = ref[MS.R_VMAX] = 1.0
        ref[MS.R_MAXSTEPS] = self.max_steps
        ref[MS.R_MRU_DELAY] = round(self.mru_delay / self.physics_dt)
        ref[MS.R_MEAN_TAU] = 0.0 if self.mean_time_constant is None else self.mean_time_constant
        ref[MS.R_PITCH0] = float(sim.body_state(self.body)["euler"][1])
        self._actuator_refs(ref, rows.amap[i])
        st.set_copy(i, sim, self.body, self._inv_seg)
        rows.prev_action[i] = self._reset_action()
        M = st.measure(i)
        P = self._preview_rows([i]) if self._wants_preview else None
        obs_fn = self.observer
        if hasattr(obs_fn, "measure_rows"):
            first = obs_fn.measure_rows(st.M, rows.prev_action, np.array([i]), [rng], P)[0]
            return obs_fn.start(first)
        return obs_fn.reset(self._row_dict(M, rows.prev_action[i], P[0] if P is not None else None), rng)

    def step(self, action):
        if self._needs_reset:
            raise C.ResetNeeded(self._reset_needed_text())
        # fast path: a float array of the action shape (what policies and action_space.sample() give)
        if not (type(action) is np.ndarray and action.shape == self._act_shape and action.dtype.kind == "f"):
            action = C.action_array(action, self._act_shape, self._action_space_text,
                                    f"{type(self).__name__}.step: action", also=((),) if self.ACTION_DIM == 1 else ())
        rows = self._rows
        i = self._row
        rows.actions[i] = action                        # a copy (float64): the caller's array is kept
        plan = self.__dict__.get("_plan")
        if plan is None or plan.rows is not rows or plan.row != i or plan.observer is not self.observer \
                or plan.reward_fn is not self.reward_fn or plan.limits is not self._limits:
            plan = self._plan = _StepPlan(self)
        if plan.fast:
            return self._step_planned(plan)
        idx = self.__dict__.get("_idx")
        if idx is None or idx[0] != i:                  # this copy's row, as the index array step_copies takes
            idx = self._idx = np.array([i])
        res = step_copies([self], rows, idx)
        obs, reward, terminated, truncated = res.obs[0], float(res.rewards[0]), bool(res.terminated[0]), \
            bool(res.truncated[0])
        info = res.info(0)
        if terminated or truncated:
            self._needs_reset = "ended"
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, truncated, info

    def _step_planned(self, plan):
        """:meth:`step` for the standard observation / reward / termination pieces without a wave preview (what
        :func:`step_copies` does for one row, with its arrays and the compiled call's entry point prepared once
        per episode in ``plan``): the same arithmetic in the same order, bit for bit (tested); an episode's end
        or a numerical failure is handed to :func:`_finish` as there."""
        rows = self._rows
        st = rows.stepper
        A = rows.actions
        idx = plan.idx
        if self._commands(A, idx, st.U, rows.amap):     # also cleans A[idx] (NaN -> 0, clip to [-1, 1])
            _warn_cleaned(self, rows)
        failures = st.step(self.substeps, self.ACT_KIND, plan.active)
        obs_fn = plan.observer
        args = plan.args
        if obs_fn._noisy:
            args = list(args)
            args[plan.noise_slot], args[plan.noise_slot + 1] = obs_fn.noise_rows([self.np_random], 1)
        nterm = plan.call(*args)
        O, R, term, trunc = plan.O, plan.R, plan.term, plan.trunc
        if obs_fn.delay:
            O[0] = obs_fn.push(O[0])
        obs = O[0].copy()
        if nterm or failures:
            res = _finish([self], rows, idx, st.M, A, None, st.refs, O, R, plan.C, plan.names, plan.limits, term,
                          trunc, nterm, failures)
            reward, terminated, truncated = float(R[0]), bool(term[0]), bool(trunc[0])
            info = res.info(0)
            if terminated or truncated:
                self._needs_reset = "ended"
        else:
            reward, truncated = float(R[0]), bool(trunc[0])
            terminated = False
            info = _info_dict(st.M[plan.row].tolist(), dict(zip(plan.names, plan.C[0].tolist())), plan.slack)
            if truncated:
                self._needs_reset = "ended"
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, truncated, info

    def _reset_needed_text(self) -> str:
        own = type(self).__name__
        if self._needs_reset == "ended":
            return (f"{own}.step called after the episode ended (terminated or truncated at t = "
                    f"{float(self._rows.stepper.M[self._row, MS.M_T]):g} s): call reset() to start a new episode")
        if self._needs_reset == "failed":
            return f"{own}.step called after a reset() that raised: call reset() again"
        return f"{own}.step called before reset(): call reset() first"

    def _action_space_text(self) -> str:
        return (f"{self.action_space!r} (shape {self.action_space.shape}, real numbers; values outside "
                f"[-1, 1] are clipped and NaN is read as 0)")

    # ------------------------------------------------------------------ measurement
    def _slack(self):
        return getattr(self.reward_fn, "slack_tension", 1.0)

    def _inv_seg(self, sim):
        """1/breaking load of every segment of ``sim``'s current system (re-evaluated after a remesh)."""
        return self._tension_layout(sim)[0]

    def _tension_layout(self, sim):
        """(per-segment 1/breaking load, 1/breaking load at the tow point, [(line, segments, 1/load)]) for
        ``sim.system`` (rebuilt when the winch remeshes the system)."""
        system = sim.system
        if self._tension_cache[0] is system:
            return self._tension_cache[1]
        bl = self.breaking_load
        inv_seg = np.zeros(system.n_segments)
        lines = []
        top_inv = 0.0
        for ln in system.lines:
            load = bl.get(ln.name) if isinstance(bl, Mapping) else bl
            if load is None:
                continue
            segs = np.asarray(ln.segments, int)
            inv_seg[segs] = 1.0 / float(load)
            lines.append((ln.name, segs, 1.0 / float(load)))
            if len(ln.nodes) and int(ln.nodes[0]) == int(system.top_node):
                top_inv = max(top_inv, 1.0 / float(load))
        lay = (inv_seg, top_inv, lines)
        self._tension_cache = (system, lay)
        return lay

    _BASE_KEYS = ("t", "tow_vel_z", "tow_acc_z", "top_tension", "top_tension_ratio", "fish_heave", "fish_depth",
                  "fish_pitch", "fish_heave_rate", "fish_pitch_rate", "min_tension", "tension_ratio", "time_left",
                  "tow_surge", "tow_sway", "tow_heave", "tow_vel_x", "tow_vel_y", "tow_acc_x", "tow_acc_y",
                  "cable_angle", "cable_azimuth", "tow_disp_along", "tow_vel_along", "tow_acc_along",
                  "fish_heave_dev", "fish_pitch_dev")

    def _row_dict(self, row, action, preview=None) -> dict:
        """A measurement row as the dict ``m`` of :data:`~towenv.envs.pieces.MEASUREMENTS` (for custom
        observers / reward functions and the renderer)."""
        m = {k: float(row[MS.COL[k]]) for k in self._BASE_KEYS + self.ACTUATOR_KEYS}
        m["last_action"] = np.array(action, float)
        if preview is not None:
            m["wave_preview"] = np.asarray(preview, float)
        elif self._wants_preview:
            m["wave_preview"] = self._wave_preview(self.sim)
        return m

    def _preview_rows(self, idx):
        """(len(rows) of the stepper, n_distances) wave-preview array with rows ``idx`` filled."""
        st = self._rows.stepper
        P = getattr(self._rows, "preview", None)
        nd = len(self.observer.preview_distances)
        if P is None or P.shape != (st.num_copies, nd):
            P = self._rows.preview = np.zeros((st.num_copies, nd))
        for i in idx:
            P[i] = self._rows.envs_of(i, self)._wave_preview(st.sims[i])
        return P

    def _wave_preview(self, sim):
        """Wave elevation now at ``preview_distances`` ahead of the tow point along the ship's heading
        (a bow wave radar / lidar), scaled by the start-up ramp like the vessel motion it causes."""
        d = np.asarray(self.observer.preview_distances, float)
        if sim.wave is None:
            return np.zeros(d.size)
        t = sim.t
        pos, psi, _ = sim.path.mean_path(np.array([t]))
        x = pos[0, 0] + d * math.cos(psi[0])
        y = pos[0, 1] + d * math.sin(psi[0])
        # the wave record's x axis is the ship's initial heading (TowPointMotion.wave_direction_offset)
        h0 = float(getattr(sim.path, "initial_heading", 0.0))
        xr, yr = math.cos(h0) * x + math.sin(h0) * y, -math.sin(h0) * x + math.cos(h0) * y
        ramp = float(sim.path.ramp(np.array([t]))[0])
        return ramp * np.asarray(sim.wave.elevation(np.full(d.size, t), xr, yr), float).reshape(d.size)

    # ------------------------------------------------------------------ termination
    @property
    def termination(self):
        """The termination piece (:class:`~towenv.envs.pieces.Termination`); assigning one checks it."""
        return self._termination

    @termination.setter
    def termination(self, piece):
        self._termination, self._limits = piece, _limit_arrays(type(self).__name__, piece)

    def _overloaded(self, sim) -> tuple:
        """Names of the lines (and ``"tow point"``) of ``sim`` at or above their breaking load."""
        _, top_inv, lines = self._tension_layout(sim)
        T = sim.tensions
        which = [n for n, segs, k in lines if segs.size and float(T[segs].max()) * k >= 1.0]
        if sim.top_tension * top_inv >= 1.0:
            which.append("tow point")
        return tuple(dict.fromkeys(which))

    def _termination_dict(self, row, action, preview=None) -> dict:
        """The measurement dict handed to the termination piece: :meth:`_row_dict`, every other column of the
        row (what a compiled limit can read) and ``overloaded``."""
        m = self._row_dict(row, action, preview)
        for k, j in MS.COL.items():
            if k not in m:
                m[k] = float(row[j])
        m["overloaded"] = self._overloaded(self.sim) if row[MS.M_T_RATIO] >= 1.0 else ()
        return m

    def _ended(self, row, action, preview=None):
        """The termination piece's verdict on a measurement row: the reason (str) or None."""
        piece = self._termination
        r = piece(self._termination_dict(row, action, preview))
        if r is None or r is False:
            return None
        if isinstance(r, str):
            return r
        if not r:
            return None
        return getattr(piece, "__name__", None) or type(piece).__name__

    # ------------------------------------------------------------------ rendering / pickling
    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' or 'human'")
            return None
        if self._viewer is None:
            if self.renderer is not None:
                self._viewer = self.renderer
            else:
                from .render import SideViewer
                self._viewer = SideViewer(human=self.render_mode == "human", fps=self.metadata["render_fps"])
        return self._viewer(self)

    def close(self):
        if self._viewer is not None:
            close = getattr(self._viewer, "close", None)
            if callable(close):
                close()
            self._viewer = None

    def __getstate__(self):
        st = self.__dict__.copy()
        st["_viewer"] = None           # matplotlib figures are not pickled; re-created on demand (a given
        st.pop("_plan", None)          # compiled entry point: re-made on the next step
        return st                      # ``renderer`` is pickled with the environment)

    def __setstate__(self, st):
        st.setdefault("_needs_reset", False)     # pickles of earlier versions
        st.setdefault("_act_shape", (type(self).ACTION_DIM,))
        st.setdefault("renderer", None)
        self.__dict__.update(st)

    # ------------------------------------------------------------------ convenience
    @property
    def sea(self):
        """``(SeaState, wave_seed)`` of the current episode."""
        return self._sea

    @property
    def steps(self) -> int:
        return self._steps


# =====================================================================================================
# batched stepping shared by TowEnv (one row) and the vector environments (B rows)
# =====================================================================================================
class EnvRows:
    """Per-copy arrays of ``n`` environment copies stepped together: the :class:`~towenv.envs.stepper.BatchStepper`
    (simulators, reference values ``refs``, measurement rows ``M``, commands ``U``), the actions, the
    previous actions, per-copy action maps ``amap`` and the environment object of each row (``envs``)."""

    def __init__(self, n: int, action_dim: int, parallel: bool = False):
        self.stepper = ST.BatchStepper(n, parallel=parallel)
        self.actions = np.zeros((n, action_dim))
        self.prev_action = np.zeros((n, action_dim))
        self.amap = np.zeros((n, 8))
        self.preview = None
        self.action_warned = False          # the clipping / NaN warning has been shown (once per env)
        self.envs: list = [None] * n
        self._all = np.ones(n, bool)

    def envs_of(self, i, default):
        e = self.envs[i]
        return default if e is None else e


class _StepPlan:
    """What :meth:`TowEnv.step` needs per step for one row with the standard pieces, prepared once: the row's index
    array and activity mask, the reused output arrays (rewards, components, flags, the observation row — the
    observation handed out is a copy), the argument tuple of :func:`_observe_reward_flags` and its compiled
    entry point (numba's type dispatch of 25 arguments skipped: valid while the arguments are these same
    objects, which the plan checks by identity — a new plan is made when the row, the observer, the reward
    function or the termination limits change, and at every reset; the reward's parameters — weights, slack and
    over-tension thresholds — are read then, being constructor parameters, as :meth:`HeavePitchReward.weight_vector`
    already assumes). ``fast`` is False for other pieces (a
    custom observer or reward, a termination without limits, a wave preview): :func:`step_copies` then."""

    __slots__ = ("rows", "row", "observer", "reward_fn", "limits", "fast", "idx", "active", "O", "R", "C", "term",
                 "trunc", "names", "slack", "args", "noise_slot", "call")

    def __init__(self, env):
        self.rows, self.row = env._rows, env._row
        self.observer, self.reward_fn, self.limits = obs_fn, rew_fn, lim = env.observer, env.reward_fn, env._limits
        self.fast = (lim is not None and not env._wants_preview
                     and getattr(type(obs_fn), "measure_rows", None) is _MEASURE_ROWS
                     and getattr(type(rew_fn), "batch", None) is _REWARD_BATCH)
        if not self.fast:
            return
        st = self.rows.stepper
        self.idx = np.array([self.row])
        if st.num_copies == 1:
            self.active = None
        else:
            self.active = np.zeros(st.num_copies, bool)
            self.active[self.row] = True
        self.O = np.empty((1, obs_fn.size), np.float32)
        self.R = np.empty(1)
        self.names = rew_fn.COMPONENTS
        self.C = np.empty((1, len(self.names)))
        self.term = np.empty(1, bool)
        self.trunc = np.empty(1, bool)
        self.slack = env._slack()
        noise, noisy = obs_fn.noise_rows(None, 1)
        arrays = obs_fn.rows_arrays()
        self.noise_slot = 5 + len(arrays)
        self.args = (st.M, self.rows.actions, self.rows.prev_action, _NO_PREVIEW, self.idx, *arrays, noise, noisy,
                     self.O, rew_fn.weight_vector(), rew_fn.slack_tension, rew_fn.over_tension_fraction, self.C,
                     self.R, *lim, st.refs, self.term, self.trunc)
        self.call = _observe_reward_flags
        try:                                   # (a drawn noise array has the type of the placeholder: float64 2-D C)
            from numba import typeof
            sig = tuple(typeof(a) for a in self.args)
            cres = _observe_reward_flags.overloads.get(sig)
            if cres is None:                   # first use in this process: compile (or load from the cache)
                _observe_reward_flags.compile(sig)
                cres = _observe_reward_flags.overloads.get(sig)
        except Exception:                      # an unexpected numba internals change: keep the dispatcher
            cres = None
        if cres is not None:
            self.call = cres.entry_point


def _info_dict(row, comps, slack) -> dict:
    """The single-environment ``info`` keys every step has, from a measurement row as Python floats (``M[i].tolist()``,
    one numpy call), the reward components and the reward's slack threshold (N); the one definition both step paths
    use (:meth:`StepResult.info`, :meth:`TowEnv._step_planned`)."""
    return {"t": row[MS.M_T], "reward_components": comps, "fish_heave": row[MS.M_HEAVE], "fish_pitch": row[MS.M_PITCH],
            "top_tension": row[MS.M_TOP_T], "end_stop_hits": int(row[MS.M_HITS]),
            "slack": bool(row[MS.M_MIN_T] <= slack)}


class StepResult:
    """Outcome of :func:`step_copies` for rows ``idx`` (arrays indexed by position k in ``idx``)."""

    __slots__ = ("envs", "rows", "idx", "obs", "rewards", "terminated", "truncated", "comps", "names",
                 "failures", "reasons", "terminal_costs")

    def info(self, k: int) -> dict:
        """The single-environment ``info`` dict of row position k."""
        e = self.envs[k]
        i = self.idx[k]
        comps = dict(zip(self.names, self.comps[k].tolist())) if self.names is not None else self.comps[k]
        if k in self.terminal_costs:
            comps["terminal"] = self.terminal_costs[k]
        info = _info_dict(self.rows.stepper.M[i].tolist(), comps, e._slack())
        if k in self.reasons:
            info["termination"] = self.reasons[k]
        f = self.failures.get(int(i))
        if f is not None:
            info["failure"] = (f"numerical failure at t = {f.time:.4g} s in {f.element}: {f.cause}")
            info["solver_failure"] = True
        return info


def step_copies(envs, rows: EnvRows, idx: np.ndarray) -> StepResult:
    """Advance the copies ``envs`` (rows ``idx`` of ``rows``; all of one class and configuration) by one
    control step with the actions in ``rows.actions[idx]``: actions cleaned and mapped to commands, ONE
    compiled call for all physics sub-steps and measurements, then observations, rewards, termination
    and truncation (vectorised when the observer / reward function offer ``measure_rows`` / ``batch``)."""
    e0 = envs[0]
    st = rows.stepper
    A = rows.actions
    if e0._commands(A, idx, st.U, rows.amap):      # also cleans A[idx] (NaN -> 0, clip to [-1, 1])
        _warn_cleaned(e0, rows)
    refs = st.refs                                  # the kernel adds 1 to refs[idx, R_STEPS]
    if len(idx) == st.num_copies:
        act = None
    else:
        act = np.zeros(st.num_copies, bool)
        act[idx] = True
    failures = st.step(e0.substeps, e0.ACT_KIND, act)
    M = st.M
    P = e0._preview_rows(idx) if e0._wants_preview else None
    obs_fn = e0.observer
    rew_fn = e0.reward_fn
    lim = e0._limits                                # compiled limits of the termination piece, or None
    if (lim is not None and getattr(type(obs_fn), "measure_rows", None) is _MEASURE_ROWS
            and getattr(type(rew_fn), "batch", None) is _REWARD_BATCH):
        # the standard pieces: observation, reward and flags in one compiled call (the same arithmetic as
        # Observer.measure_rows, HeavePitchReward.batch and _post_rows, in that order)
        n = len(idx)
        noise, noisy = obs_fn.noise_rows([e.np_random for e in envs] if obs_fn._noisy else None, n)
        O = np.empty((n, obs_fn.size), np.float32)
        R = np.empty(n)
        C = np.empty((n, len(rew_fn.COMPONENTS)))
        term = np.empty(n, bool)
        trunc = np.empty(n, bool)
        nterm = _observe_reward_flags(M, A, rows.prev_action, _NO_PREVIEW if P is None else P, idx,
                                      *obs_fn.rows_arrays(), noise, noisy, O, rew_fn.weight_vector(),
                                      rew_fn.slack_tension, rew_fn.over_tension_fraction, C, R, *lim, refs, term,
                                      trunc)
        if obs_fn.delay:
            for k, e in enumerate(envs):
                O[k] = e.observer.push(O[k])
        return _finish(envs, rows, idx, M, A, P, refs, O, R, C, rew_fn.COMPONENTS, lim, term, trunc, nterm,
                       failures)
    if hasattr(obs_fn, "measure_rows"):
        rngs = [e.np_random for e in envs] if obs_fn._noisy else None
        O = obs_fn.measure_rows(M, A, idx, rngs, P)
        if obs_fn.delay:
            for k, e in enumerate(envs):
                O[k] = e.observer.push(O[k])
    else:
        O = np.stack([e.observer(e._row_dict(M[i], A[i], None if P is None else P[i]), e.np_random)
                      for e, i in zip(envs, idx)])
    if hasattr(rew_fn, "batch"):
        R, C = rew_fn.batch(M, A, rows.prev_action, idx)
        names = rew_fn.COMPONENTS
    else:
        R = np.empty(len(idx))
        C = []
        for k, (e, i) in enumerate(zip(envs, idx)):
            r, c = e.reward_fn(e._row_dict(M[i], A[i], None if P is None else P[i]), A[i].copy(),
                               rows.prev_action[i].copy())
            R[k] = r
            C.append(c)
        names = None
    term = np.empty(len(idx), bool)
    trunc = np.empty(len(idx), bool)
    nterm = _post_rows(M, refs, A, rows.prev_action, idx, *(lim if lim is not None else _NO_LIMITS), R, term, trunc)
    return _finish(envs, rows, idx, M, A, P, refs, O, R, C, names, lim, term, trunc, nterm, failures)


def _finish(envs, rows, idx, M, A, P, refs, O, R, C, names, lim, term, trunc, nterm, failures) -> StepResult:
    """The rest of :func:`step_copies`: termination reasons and terminal costs, failures, the result."""
    reasons, tcs = {}, {}
    if lim is None:                                 # a piece without limits: asked for every copy
        for k, (e, i) in enumerate(zip(envs, idx)):
            why = e._ended(M[i], A[i], None if P is None else P[i])
            if why is not None:
                term[k] = True
                reasons[k] = why
        nterm = len(reasons)
    if nterm:
        for k in np.flatnonzero(term):
            e = envs[k]
            if int(k) not in reasons:               # met a compiled limit: the piece names the reason
                i = idx[k]
                pv = None if P is None else P[i]
                reasons[int(k)] = e._ended(M[i], A[i], pv) or _limit_reason(e.termination,
                                                                              e._termination_dict(M[i], A[i], pv))
            tc = float(e.reward_fn.terminal_cost(e.max_steps - int(refs[idx[k], MS.R_STEPS])))
            tcs[int(k)] = tc
            R[k] -= tc
            if not math.isfinite(R[k]):
                R[k] = -1e6
    if failures:
        for k, i in enumerate(idx):
            if int(i) in failures:
                trunc[k] = True
    res = StepResult()
    res.envs, res.rows, res.idx, res.obs, res.rewards = envs, rows, idx, O, R
    res.terminated, res.truncated, res.comps, res.names = term, trunc, C, names
    res.failures, res.reasons, res.terminal_costs = failures, reasons, tcs
    return res


def _limit_arrays(owner, piece):
    """``(columns, ops, values)`` arrays of a termination piece's ``limits`` (None without limits); checks the
    piece (:class:`~towenv.envs.checks.ConfigError`)."""
    if not callable(piece):
        raise C.ConfigError(f"{owner}: termination must be callable, term(m) -> reason (str) or None (a "
                            f"towenv.envs.pieces.Termination), or None (PartedOrGrounded(floor_depth)) "
                            f"(got {piece!r})")
    lims = getattr(piece, "limits", None)
    if lims is None:
        return None
    if isinstance(lims, (str, bytes, Mapping)) or not C._iterable(lims) \
            or not all(isinstance(x, Limit) for x in lims):
        raise C.ConfigError(f"{owner}: termination.limits must be None or a sequence of towenv.envs.pieces.Limit "
                            f"(got {lims!r})")
    lims = tuple(lims)
    return (np.array([MS.COL[x.key] for x in lims], np.int64), np.array([LIMIT_OPS.index(x.op) for x in lims], np.int64),
            np.array([x.value for x in lims], float))


_NO_LIMITS = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))


def _limit_reason(piece, m) -> str:
    """The first met limit of ``piece`` as a reason (when the piece's own call gives none)."""
    for x in getattr(piece, "limits", None) or ():
        if x.met(float(m[x.key])):
            return f"{x.reason}: {x.key} = {float(m[x.key]):g} {x.op} {x.value:g}"
    return type(piece).__name__


_MEASURE_ROWS = Observer.measure_rows
_REWARD_BATCH = HeavePitchReward.batch


@njit(cache=True)
def _observe_reward_flags(M, A, PA, P, idx, okind, oidx, oscale, ostd, olo, ohi, noise, noisy, O, wv, slack, frac, C,
                          R, lcol, lop, lval, refs, term, trunc):
    """Observation rows (``pieces._observe_rows``), rewards (``pieces._heave_pitch_rows``) and flags
    (:func:`_post_rows`) of rows ``idx`` in one compiled call: one dispatch instead of three. Returns the number
    of terminated rows."""
    _observe_rows(M, A, P, idx, okind, oidx, oscale, ostd, noise, noisy, olo, ohi, O)
    _heave_pitch_rows(M, A, PA, idx, wv, slack, frac, HEAVE_RATE_LIMIT, PITCH_RATE_LIMIT, C, R)
    return _post_rows(M, refs, A, PA, idx, lcol, lop, lval, R, term, trunc)


@njit(cache=True)
def _post_rows(M, refs, A, PA, idx, lcol, lop, lval, R, term, trunc):
    """Termination flags of rows idx from the limits (column lcol[j] compared by lop[j] — an index of
    ``LIMIT_OPS`` — to lval[j]; NaN meets none), time-limit flags, non-finite rewards -> -1e6, previous
    action <- action."""
    nterm = 0
    for k in range(idx.shape[0]):
        b = idx[k]
        t = False
        for j in range(lcol.shape[0]):
            x = M[b, lcol[j]]
            o = lop[j]
            v = lval[j]
            if (o == 0 and x >= v) or (o == 1 and x > v) or (o == 2 and x <= v) or (o == 3 and x < v):
                t = True
                break
        term[k] = t
        nterm += t
        trunc[k] = refs[b, MS.R_STEPS] >= refs[b, MS.R_MAXSTEPS]
        if not math.isfinite(R[k]):           # cannot happen by construction; belt and braces
            R[k] = -1e6
        for j in range(A.shape[1]):
            PA[b, j] = A[b, j]
    return nterm


def _clean_actions(A, idx):
    a = A[idx]
    bad = int(np.count_nonzero(~((a >= -1.0) & (a <= 1.0))))     # NaN, ±inf and |a| > 1
    if bad:
        a = np.nan_to_num(a, nan=0.0)
        np.minimum(np.maximum(a, -1.0, out=a), 1.0, out=a)
        A[idx] = a
    return bad


def _warn_cleaned(env, rows) -> None:
    """Warn once per environment (per vector environment) that actions were clipped / NaN read as 0."""
    if getattr(rows, "action_warned", False):
        return
    rows.action_warned = True
    warnings.warn(f"{type(env).__name__}: action values outside {env.action_space!r} were clipped to [-1, 1] "
                  f"(NaN read as 0), as documented; this warning is shown once per environment", stacklevel=4)
