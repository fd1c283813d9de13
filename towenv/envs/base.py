"""``TowEnv``: the Gymnasium base environment around one :class:`towenv.Simulator` per configuration.

The physics core knows nothing about Gymnasium; this module only calls the public ``Simulator`` API
(``set_sea``/``reset``/``advance_steps``/``body_state``/``tensions``/``top_tension``/``compensator_state``/
``set_compensator``/``winch_state``/``set_winch``/``line_state``) plus the prescribed tow-point history
``sim.hist_r[:, sim.system.top_node]`` for the IMU channels (see ``docs/environments.md``).

Control: every ``step`` applies the action once and advances ``substeps = round(1/(control_hz·dt))``
physics steps of ``dt`` (action repetition = sub-stepping); ``env.dt = dt·substeps`` is the control period.
"""
from __future__ import annotations

import math
import warnings
from typing import Any, Mapping, Sequence

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from ..errors import SimulationDivergence
from .pieces import FixedSeas, HeavePitchReward, Observer, RandomCodeSeas, default_eval_sea_states

__all__ = ["TowEnv", "DEFAULT_BREAKING_LOAD"]

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
    breaking_load, floor_depth
        Breaking loads (N; float for every line or ``{line: N}``) and the floor depth (m) of the towed
        body: exceeding either *terminates* the episode. ``None`` disables.
    body, sim_overrides, render_mode
        Towed body scored (default ``"fish"``), solver overrides passed to ``Simulator`` (e.g.
        ``{"max_step_cuts": 0}``), ``"rgb_array"`` or ``"human"``.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 10}

    #: default observation channels (subclasses override)
    DEFAULT_OBSERVATIONS: tuple[str, ...] = ("tow_vel_z", "tow_acc_z", "top_tension", "fish_heave", "fish_pitch",
                                             "fish_heave_rate", "fish_pitch_rate", "last_action")
    ACTION_DIM = 1
    DEFAULT_SCENE = "two_part_coastal_ss4"

    def __init__(self, *, scene: Any = None, scene_overrides: Mapping[str, Any] | None = None,
                 control_hz: float = 10.0, dt: float = 0.05, episode_seconds: float = 300.0,
                 sea_codes: Sequence[int] = (3, 4, 5), sea_convention: str = "coastal",
                 heading_deg: float = 180.0, heading_spread_deg: float = 30.0, sea_generator=None,
                 vessel_speeds: Sequence[float] | None = None, cable_lengths: Sequence[float] | None = None,
                 cable_line: str = "primary",
                 observations: Sequence[str] | None = None, sensor_noise: Mapping[str, float] | None = None,
                 obs_delay: int = 0, preview_distances: Sequence[float] = (), observation_fn=None,
                 reward_weights: Mapping[str, float] | None = None, reward_fn=None,
                 slack_tension: float = 1.0, over_tension_fraction: float = 0.5,
                 breaking_load: float | Mapping[str, float] | None = None, floor_depth: float | None = 80.0,
                 body: str = "fish", sim_overrides: Mapping[str, Any] | None = None,
                 render_mode: str | None = None):
        super().__init__()
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None "
                             f"(got {render_mode!r})")
        if not (math.isfinite(control_hz) and control_hz > 0):
            raise ValueError(f"control_hz must be > 0 (got {control_hz!r})")
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be > 0 s (got {dt!r})")
        if not (math.isfinite(episode_seconds) and episode_seconds > 0):
            raise ValueError(f"episode_seconds must be > 0 (got {episode_seconds!r})")
        self.render_mode = render_mode
        self.control_hz = float(control_hz)
        self.physics_dt = float(dt)
        self.substeps = max(1, int(round(1.0 / (control_hz * dt))))
        if abs(self.substeps * dt * control_hz - 1.0) > 1e-6:
            warnings.warn(f"TowEnv: 1/(control_hz·dt) = {1.0 / (control_hz * dt):g} is not a whole number; "
                          f"using {self.substeps} physics steps per control step (control period "
                          f"{self.substeps * dt:g} s)", stacklevel=2)
        self.dt = self.substeps * self.physics_dt           # control period (MuJoCo frame_skip convention)
        self.episode_seconds = float(episode_seconds)
        self.max_steps = max(1, int(round(episode_seconds / self.dt)))
        self.metadata = dict(self.metadata, render_fps=max(1, int(round(1.0 / self.dt))))

        self.sea_codes = tuple(int(c) for c in sea_codes)
        self.sea_convention = sea_convention
        self.sea_generator = sea_generator if sea_generator is not None else RandomCodeSeas(
            self.sea_codes, sea_convention, heading_deg, heading_spread_deg)
        self.vessel_speeds = None if vessel_speeds is None else tuple(float(v) for v in vessel_speeds)
        self.cable_lengths = None if cable_lengths is None else tuple(float(v) for v in cable_lengths)
        for nm, vals in (("vessel_speeds", self.vessel_speeds), ("cable_lengths", self.cable_lengths)):
            if vals is not None and (len(vals) == 0 or not all(math.isfinite(v) and v > 0 for v in vals)):
                raise ValueError(f"{nm} must be a non-empty sequence of positive numbers (got {vals!r})")
        self.cable_line = cable_line
        self.body = body
        self.floor_depth = None if floor_depth is None else float(floor_depth)
        if breaking_load is None:
            breaking_load = DEFAULT_BREAKING_LOAD
        self.breaking_load = breaking_load
        self.sim_overrides = dict(sim_overrides or {})

        self.reward_fn = reward_fn if reward_fn is not None else HeavePitchReward(
            reward_weights, slack_tension=slack_tension, over_tension_fraction=over_tension_fraction)
        self.observer = observation_fn if observation_fn is not None else Observer(
            observations if observations is not None else self.DEFAULT_OBSERVATIONS, sensor_noise, obs_delay,
            action_dim=self.ACTION_DIM, preview_distances=preview_distances)

        from ..scene import load_scene
        base = load_scene(scene if scene is not None else self.DEFAULT_SCENE)
        if scene_overrides:
            base = base.with_overrides(dict(scene_overrides))
        self.base_scene = self._prepare_scene(base)
        if cable_lengths is not None and cable_line not in [ln.name for ln in self.base_scene.lines]:
            raise ValueError(f"cable_line {cable_line!r} is not a line of scene {self.base_scene.name!r} "
                             f"(lines: {[ln.name for ln in self.base_scene.lines]})")
        self._sims: dict[tuple, Any] = {}
        self._config = (None, None)
        self.sim = self._get_sim(None, None)           # the default configuration, built eagerly
        try:
            self.sim.body_state(self.body)
        except KeyError as exc:
            raise ValueError(f"body {body!r}: {exc.args[0]}") from None
        self._check_actuator(self.sim)

        self._wants_preview = bool(getattr(self.observer, "wants_preview", False))
        self.action_space = spaces.Box(-1.0, 1.0, (self.ACTION_DIM,), np.float32)
        self.observation_space = spaces.Box(self.observer.low, self.observer.high, dtype=np.float32)
        self._steps = 0
        self._prev_action = np.zeros(self.ACTION_DIM)
        self._z_ref = 0.0
        self._T_ref = 1.0
        self._sea = None
        self._tension_cache = (None, None)
        self._viewer = None
        self._last_m: dict | None = None

    # ------------------------------------------------------------------ subclass hooks
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

    def _apply_action(self, a: np.ndarray) -> None:
        raise NotImplementedError

    def _reset_action(self) -> np.ndarray:
        """The action equivalent of the actuator's state after reset (reported as ``last_action``)."""
        return np.zeros(self.ACTION_DIM)

    def _measure_actuator(self, m: dict, action: np.ndarray) -> None:
        """Add the actuator's measurements (and ``effort``, ``end_stop_hits``) to ``m``."""

    def _actuator_reset(self) -> None:
        """Per-episode actuator bookkeeping after ``sim.reset()``."""

    # ------------------------------------------------------------------ configuration
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
        super().reset(seed=seed)
        options = dict(options or {})
        rng = self.np_random
        speed = options.get("vessel_speed")
        if speed is None and self.vessel_speeds is not None:
            speed = self.vessel_speeds[int(rng.integers(len(self.vessel_speeds)))]
        length = options.get("cable_length")
        if length is None and self.cable_lengths is not None:
            length = self.cable_lengths[int(rng.integers(len(self.cable_lengths)))]
        if "sea_state" in options:
            sea, wseed = options["sea_state"], int(options.get("sea_seed", 0))
        elif "eval_index" in options:
            ev = self.eval_sea_states()
            sea, wseed = ev[int(options["eval_index"]) % len(ev)]
        else:
            sea, wseed = self.sea_generator(rng)
        self._config = (speed, length)
        sim = self.sim = self._get_sim(speed, length)
        sim.set_sea(sea, int(wseed))
        sim.reset()
        self._sea = (sea, int(wseed))
        self._steps = 0
        self._z_ref = float(sim.body_state(self.body)["position"][2])
        self._T_ref = max(float(sim.top_tension), 1e-9)
        self._actuator_reset()
        self._prev_action = self._reset_action()
        m = self._measure(self._prev_action)
        obs = self.observer.reset(m, rng)
        info = {"sea_state": {"hs": float(sea.hs), "tp": float(sea.tp), "heading_deg": float(sea.heading_deg)},
                "sea_seed": int(wseed), "vessel_speed": float(sim.path.initial_speed), "t": 0.0}
        if self.cable_line in self._line_names(sim):
            info["cable_length"] = float(sim.scene.line(self.cable_line).length)
        if self.render_mode == "human":
            self.render()
        return obs, info

    def step(self, action):
        a = np.array(action, dtype=float).reshape(self.ACTION_DIM)      # a copy: the caller's array is kept
        if not np.isfinite(a).all():
            a = np.nan_to_num(a, nan=0.0)
        np.minimum(np.maximum(a, -1.0, out=a), 1.0, out=a)
        sim = self.sim
        self._apply_action(a)
        failure = None
        try:
            sim.advance_steps(self.substeps)
        except SimulationDivergence as exc:
            failure = exc
        self._steps += 1
        m = self._measure(a)
        obs = self.observer(m, self.np_random)
        reward, comps = self.reward_fn(m, a, self._prev_action)
        self._prev_action = a
        terminated, reason = self._terminal(m)
        if terminated:
            tc = float(self.reward_fn.terminal_cost(self.max_steps - self._steps))
            comps["terminal"] = tc
            reward -= tc
        truncated = failure is not None or self._steps >= self.max_steps
        info = {"t": float(m["t"]), "reward_components": comps, "fish_heave": float(m["fish_heave"]),
                "fish_pitch": float(m["fish_pitch"]), "top_tension": float(m["top_tension"]),
                "end_stop_hits": int(m.get("end_stop_hits", 0)), "slack": bool(m["min_tension"] <= self._slack())}
        if terminated:
            info["termination"] = reason
        if failure is not None:
            info["failure"] = (f"numerical failure at t = {failure.time:.4g} s in {failure.element}: "
                               f"{failure.cause}")
            info["solver_failure"] = True
        if not math.isfinite(reward):          # cannot happen by construction; belt and braces
            reward = -1e6
        if self.render_mode == "human":
            self.render()
        return obs, float(reward), bool(terminated), bool(truncated), info

    # ------------------------------------------------------------------ measurement
    def _slack(self):
        return getattr(self.reward_fn, "slack_tension", 1.0)

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

    def _measure(self, action) -> dict:
        sim = self.sim
        dt = sim.dt
        hr = sim.hist_r
        top = sim.system.top_node
        z0, z1, z2 = float(hr[0, top, 2]), float(hr[1, top, 2]), float(hr[2, top, 2])
        b = sim.body_state(self.body)
        T = sim.tensions
        t_top = sim.top_tension
        inv_seg, top_inv, _ = self._tension_layout(sim)
        ratio = max(t_top * top_inv, float((T * inv_seg).max()))
        pos, vel = b["position"], b["velocity"]
        z = float(pos[2])
        m = {
            "t": sim.t,
            "tow_vel_z": (3.0 * z0 - 4.0 * z1 + z2) / (2.0 * dt),
            "tow_acc_z": (z0 - 2.0 * z1 + z2) / (dt * dt),
            "top_tension": t_top,
            "top_tension_ratio": t_top / self._T_ref,
            "fish_heave": z - self._z_ref,
            "fish_depth": -z,
            "fish_pitch": float(b["euler"][1]),
            "fish_heave_rate": float(vel[2]),
            "fish_pitch_rate": float(b["omega"][1]),
            "min_tension": float(T.min()),
            "tension_ratio": ratio,
            "last_action": action,
            "time_left": 1.0 - self._steps / self.max_steps,
        }
        self._measure_actuator(m, action)
        if self._wants_preview:
            m["wave_preview"] = self._wave_preview(sim)
        self._last_m = m
        return m

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

    def _terminal(self, m):
        if m["tension_ratio"] >= 1.0:
            _, top_inv, lines = self._tension_layout(self.sim)
            T = self.sim.tensions
            which = [n for n, segs, k in lines if segs.size and float(T[segs].max()) * k >= 1.0]
            if self.sim.top_tension * top_inv >= 1.0:
                which.append("tow point")
            return True, f"cable_parted: tension above the breaking load ({', '.join(dict.fromkeys(which))})"
        if self.floor_depth is not None and m["fish_depth"] > self.floor_depth:
            return True, f"{self.body}_below_floor: depth {m['fish_depth']:.1f} m > {self.floor_depth:g} m"
        return False, None

    # ------------------------------------------------------------------ rendering / pickling
    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' or 'human'")
            return None
        if self._viewer is None:
            from .render import SideViewer
            self._viewer = SideViewer(human=self.render_mode == "human", fps=self.metadata["render_fps"])
        return self._viewer.draw(self)

    def close(self):
        if self._viewer is not None:
            self._viewer.close()
            self._viewer = None

    def __getstate__(self):
        st = self.__dict__.copy()
        st["_viewer"] = None           # matplotlib figures are not pickled; re-created on demand
        return st

    def __setstate__(self, st):
        self.__dict__.update(st)

    # ------------------------------------------------------------------ convenience
    @property
    def sea(self):
        """``(SeaState, wave_seed)`` of the current episode."""
        return self._sea

    @property
    def steps(self) -> int:
        return self._steps
