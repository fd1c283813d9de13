"""Batched environments: ``N`` TowEnv copies stepped by ONE compiled call per ``VectorEnv.step``.

Each copy keeps its own :class:`~towenv.envs.base.TowEnv` object (configuration, ``np_random``, sea
generator, observer ring buffer, simulators), but all copies share one :class:`~towenv.envs.base.EnvRows`:
a :class:`~towenv.envs.stepper.BatchStepper` holding every copy's kernel arguments in a ``numba.typed.List``.
One ``step`` maps all actions to actuator commands, advances all copies' physics sub-steps and gathers
their measurements in one numba call (serial loop over copies, or ``prange`` with ``parallel=True``),
then computes observations, rewards and flags vectorised over the copies. Copies that need a winch remesh
or fail numerically are finished in Python (a failure truncates that copy with ``info["failure"]``).
A copy's trajectory is bit-identical to a single environment's with the same seed and actions.

Registered as the ``vector_entry_point`` of both ids::

    gymnasium.make_vec("towenv/WinchPayout-v0", num_envs=8, vectorization_mode="vector_entry_point")

Autoreset follows Gymnasium 1.x (``metadata["autoreset_mode"]``): ``NEXT_STEP`` (default; the step
after an episode ends returns the reset observation with reward 0, both flags False, and the reset info),
``SAME_STEP`` (the reset observation is returned at once; the last one is in ``infos["final_obs"]`` and
its info in ``infos["final_info"]``) or ``DISABLED`` (reset finished copies yourself with
``reset(options={"reset_mask": mask})``; stepping a finished copy raises). Seeding: ``reset(seed=s)``
seeds copy i with ``s + i`` (or pass a list of seeds).

For stable-baselines3 use :class:`towenv.envs.sb3.TowSB3VecEnv` (SB3's own ``VecEnv`` API).
"""
from __future__ import annotations

import copy
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numba import njit

from ..core import kernels as K
from . import checks as C
from . import measurements as MS
from .base import EnvRows, step_copies
from .compensator import CompensatorGainsEnv
from .winch import WinchPayoutEnv


@njit(cache=True)
def _fill_info(M, idx, comps, slack_tension, vals, hits, slack, masks):
    """The batched info blocks of the stepped rows ``idx`` (zero / False elsewhere): ``vals`` = the reward
    components, then t, fish heave, fish pitch, top tension; ``hits`` end-stop hits; ``slack`` min tension ≤
    ``slack_tension``; ``masks`` True at the stepped rows."""
    nc = comps.shape[1]
    vals[:] = 0.0
    hits[:] = 0
    slack[:] = False
    masks[:] = False
    for k in range(idx.shape[0]):
        i = idx[k]
        for j in range(nc):
            vals[j, i] = comps[k, j]
        vals[nc, i] = M[i, MS.M_T]
        vals[nc + 1, i] = M[i, MS.M_HEAVE]
        vals[nc + 2, i] = M[i, MS.M_PITCH]
        vals[nc + 3, i] = M[i, MS.M_TOP_T]
        hits[i] = np.int64(M[i, MS.M_HITS])
        slack[i] = M[i, MS.M_MIN_T] <= slack_tension
        for j in range(masks.shape[0]):
            masks[j, i] = True


__all__ = ["TowVectorEnv", "CompensatorGainsVectorEnv", "WinchPayoutVectorEnv"]


class TowVectorEnv(VectorEnv):
    """``num_envs`` copies of ``env_class(**env_kwargs)`` (every copy gets the same keywords).

    ``batch_infos=False`` skips the per-step info arrays; episode-level keys (``failure``,
    ``solver_failure``, ``termination``, ``final_obs``/``final_info``) are still reported.
    ``parallel=True`` steps the copies with ``numba.prange`` over ``numba.get_num_threads()`` threads."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10, "autoreset_mode": AutoresetMode.NEXT_STEP}
    env_class: type | None = None

    def __init__(self, num_envs: int = 1, *, env_class: type | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP, render_mode: str | None = None,
                 batch_infos: bool = True, parallel: bool = False, **env_kwargs: Any):
        cls = env_class or self.env_class
        own = type(self).__name__
        if cls is None:
            raise C.ConfigError(f"{own}: give env_class (or use a subclass)")
        n = C.integer(own, "num_envs", num_envs, 1)
        C.choice(own, "render_mode", render_mode, ["rgb_array"], none="no rendering")
        modes = [m.value for m in AutoresetMode]
        if not (isinstance(autoreset_mode, AutoresetMode) or autoreset_mode in modes):
            raise C.ConfigError(f"{own}: autoreset_mode must be an AutoresetMode or one of {modes} "
                                f"(got {autoreset_mode!r})")
        for nm, v in (("batch_infos", batch_infos), ("parallel", parallel)):
            if not isinstance(v, (bool, np.bool_)):
                raise C.ConfigError(f"{own}: {nm} must be True or False (got {v!r})")
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self.num_envs = n
        self.envs = [cls(render_mode=render_mode, **env_kwargs) for _ in range(n)]
        e0 = self.envs[0]
        for e in self.envs[1:]:
            if e.observer is e0.observer:       # one observation_fn object given: each copy needs its own
                e.observer = copy.deepcopy(e0.observer)      # delay ring buffer
        self.rows = EnvRows(n, e0.ACTION_DIM, parallel=parallel)
        for i, e in enumerate(self.envs):
            e._rows, e._row = self.rows, i
            self.rows.envs[i] = e
            e._install_row()
        self.parallel = bool(parallel)
        self.single_observation_space = e0.observation_space
        self.single_action_space = e0.action_space
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self.metadata = dict(self.metadata, autoreset_mode=self.autoreset_mode,
                             render_fps=e0.metadata["render_fps"])
        self.render_mode = render_mode
        self.batch_infos = bool(batch_infos)
        self.dt = e0.dt
        self._obs = np.zeros((n,) + self.single_observation_space.shape, np.float32)
        self._rew = np.zeros(n)
        self._term = np.zeros(n, bool)
        self._trunc = np.zeros(n, bool)
        self._autoreset = np.zeros(n, bool)
        self._started = np.zeros(n, bool)
        self._all = np.arange(n)
        self._act_shape = (n,) + tuple(self.single_action_space.shape)

    # ------------------------------------------------------------------
    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        n = self.num_envs
        if seed is None:
            seeds = [None] * n
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n:
                raise ValueError(f"reset: {len(seeds)} seeds given for num_envs={n}")
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        if mask is None:
            mask = np.ones(n, bool)
        else:
            mask = np.asarray(mask)
            if mask.shape != (n,) or mask.dtype != np.bool_ or not mask.any():
                raise ValueError(f"options['reset_mask'] must be a bool array of shape ({n},) with a True entry")
        infos: dict[str, Any] = {}
        for i in np.flatnonzero(mask):
            self._obs[i], info = self.envs[i].reset(seed=seeds[i], options=options)
            infos = self._add_info(infos, info, int(i))
        self._term[mask] = False
        self._trunc[mask] = False
        self._autoreset[mask] = False
        self._started[mask] = True
        return self._obs.copy(), infos

    def _step_arrays(self, actions):
        """Step every copy: returns (StepResult or None, stepped row indices, {row: reset info} of copies
        auto-reset before stepping (NEXT_STEP), {row: (final obs, final info)} of copies auto-reset after
        (SAME_STEP)). Fills ``self._obs/_rew/_term/_trunc``."""
        n = self.num_envs
        shape = self._act_shape
        if not (type(actions) is np.ndarray and actions.shape == shape and actions.dtype.kind == "f"):
            actions = C.action_array(actions, shape, self._action_space_text, f"{type(self).__name__}.step: actions",
                                     also=((n,),) if shape[1] == 1 else ())
        actions = np.asarray(actions, dtype=np.float32)     # as before: the batched actions are float32
        if not self._started.all():
            raise C.ResetNeeded(f"{type(self).__name__}.step: reset copies {np.flatnonzero(~self._started).tolist()} "
                                f"first (call reset())")
        mode = self.autoreset_mode
        reset_before = {}
        if self._autoreset.any():
            if mode == AutoresetMode.DISABLED:
                i = int(np.flatnonzero(self._autoreset)[0])
                raise C.ResetNeeded(f"sub-environment {i} finished: reset it with options={{'reset_mask': ...}}")
            if mode == AutoresetMode.NEXT_STEP:
                for i in np.flatnonzero(self._autoreset):
                    self._obs[i], reset_before[int(i)] = self.envs[i].reset()
                    self._rew[i] = 0.0
                    self._term[i] = self._trunc[i] = False
        idx = self._all if not reset_before else np.flatnonzero(~self._autoreset)
        res = None
        if len(idx):
            at = idx if reset_before else slice(None)        # (a slice copies faster than an index array)
            self.rows.actions[at] = actions[at]
            res = step_copies([self.envs[i] for i in idx] if len(idx) < n else self.envs, self.rows, idx)
            self._obs[at] = res.obs
            self._rew[at] = res.rewards
            self._term[at] = res.terminated
            self._trunc[at] = res.truncated
        final = {}
        if mode == AutoresetMode.SAME_STEP and res is not None:
            done = res.terminated | res.truncated
            for k in np.flatnonzero(done):
                i = int(idx[k])
                final[i] = (self._obs[i].copy(), res.info(int(k)))
                self._obs[i], _ = self.envs[i].reset()
            self._autoreset[:] = False
        else:
            self._autoreset = self._term | self._trunc
        return res, idx, reset_before, final

    def _action_space_text(self) -> str:
        one = self.single_action_space.shape == (1,)
        return (f"{self.action_space!r} (num_envs = {self.num_envs} rows of the single action space "
                f"{self.single_action_space!r}{'; shape (num_envs,) is accepted too' if one else ''}; real numbers, "
                f"values outside [-1, 1] are clipped and NaN is read as 0)")

    def step(self, actions):
        res, idx, reset_before, final = self._step_arrays(actions)
        infos: dict[str, Any] = {}
        if res is not None:
            if self.batch_infos:
                infos = self._batched_infos(res, idx)
            else:
                for k in list(res.reasons) + [k for k, i in enumerate(idx) if int(i) in res.failures]:
                    full = res.info(int(k))
                    extra = {key: full[key] for key in ("failure", "solver_failure", "termination") if key in full}
                    infos = self._add_info(infos, extra, int(idx[k]))
        for i, info in reset_before.items():
            infos = self._add_info(infos, info, i)
        for i, (fo, fi) in final.items():
            infos = self._add_info(infos, {"final_obs": fo, "final_info": fi}, i)
        return self._obs.copy(), self._rew.copy(), self._term.copy(), self._trunc.copy(), infos

    def _batched_infos(self, res, idx) -> dict:
        """The Gymnasium batched form (arrays + ``_key`` masks) of the stepped copies' info dicts, built
        vectorised (equal to ``_add_info`` over the single-environment infos)."""
        n = self.num_envs
        if res.names is None:                   # a custom reward function: per-copy dicts
            infos: dict[str, Any] = {}
            for k, i in enumerate(idx):
                infos = self._add_info(infos, res.info(k), int(i))
            return infos
        # every per-step key in four block allocations filled by one compiled call, the dict's arrays being
        # the blocks' rows: equal to _add_info over the single infos (built one by one, the ~30 small arrays
        # cost 72 µs per step at N = 1, now 22 µs: scripts/bench_env_parts.py)
        names = res.names
        nc = len(names)
        vals = np.empty((nc + 4, n))
        hits = np.empty(n, np.int64)
        slack = np.empty(n, np.bool_)
        masks = np.empty((nc + 7, n), np.bool_)
        _fill_info(self.rows.stepper.M, idx, res.comps, float(self.envs[0]._slack()), vals, hits, slack, masks)
        v = list(vals)                          # the rows as arrays (views of the block)
        m = list(masks)
        rc: dict[str, Any] = {}
        for j, name in enumerate(names):
            rc[name] = v[j]
            rc["_" + name] = m[j]
        infos = {"t": v[nc], "_t": m[nc], "reward_components": rc, "_reward_components": m[nc + 1],
                 "fish_heave": v[nc + 1], "_fish_heave": m[nc + 2], "fish_pitch": v[nc + 2],
                 "_fish_pitch": m[nc + 3], "top_tension": v[nc + 3], "_top_tension": m[nc + 4],
                 "end_stop_hits": hits, "_end_stop_hits": m[nc + 5], "slack": slack, "_slack": m[nc + 6]}
        if res.terminal_costs:
            tc = np.zeros(n)
            tm = np.zeros(n, bool)
            for k, v in res.terminal_costs.items():
                tc[idx[k]] = v
                tm[idx[k]] = True
            rc["terminal"], rc["_terminal"] = tc, tm
        for k, reason in res.reasons.items():
            infos = self._add_info(infos, {"termination": reason}, int(idx[k]))
        for k, i in enumerate(idx):
            f = res.failures.get(int(i))
            if f is not None:
                full = res.info(k)
                infos = self._add_info(infos, {"failure": full["failure"], "solver_failure": True}, int(i))
        return infos

    def render(self):
        return tuple(env.render() for env in self.envs)

    def close_extras(self, **kwargs):
        for env in self.envs:
            env.close()

    # ------------------------------------------------------------------ copies continued from others
    def load_copies(self, source: "TowVectorEnv", src, dst) -> None:
        """Make copy ``dst[k]`` of this vector env continue exactly as copy ``src[k]`` of ``source`` (this env or
        another of the same class and keywords) would: after it, the same actions give copy ``dst[k]`` the
        observations, rewards, flags and infos that copy ``src[k]`` gets, bit for bit. Used to run a shared
        warm-up once and branch it into many copies (``agents.gn_compensator``'s shared warm-up).

        Both copies must have been reset into the same sea state, wave seed and configuration (speed, cable length)
        — the waves are the destination's own, only the dynamic state is copied: the Simulator (``snapshot`` /
        ``restore``, Newton memory and counters included), the stepper's rows (reference values and running
        means, measurement row, step count, tow-point buffer), the previous and last actions, the action map, the
        observer's delay ring (a deep copy of the source's observer), the env's random generator state and the
        vector env's last observation, reward and flags. Not for winch copies (a remesh changes the
        discretisation; ``ConfigError``). The reward function must keep no per-copy state (the standard
        ``HeavePitchReward`` keeps none)."""
        own = type(self).__name__
        if type(source) is not type(self):
            raise C.ConfigError(f"{own}.load_copies: source must be a {own} (got {type(source).__name__})")
        src = [int(i) for i in np.asarray(src, np.int64).reshape(-1)]
        dst = [int(i) for i in np.asarray(dst, np.int64).reshape(-1)]
        if len(src) != len(dst):
            raise C.ConfigError(f"{own}.load_copies: src and dst must have the same length (got {len(src)} "
                                f"and {len(dst)})")
        if len(set(dst)) != len(dst):
            raise C.ConfigError(f"{own}.load_copies: dst must not repeat a copy")
        for name, ids, n in (("src", src, source.num_envs), ("dst", dst, self.num_envs)):
            bad = [i for i in ids if not 0 <= i < n]
            if bad:
                raise C.ConfigError(f"{own}.load_copies: {name} entries must be in 0..{n - 1} (got {bad[:5]})")
        if source is self and set(src) & set(dst) - {s for s, d in zip(src, dst) if s == d}:
            raise C.ConfigError(f"{own}.load_copies: within one vector env a copy cannot be both a source and "
                                f"another copy's destination")
        for s, d in zip(src, dst):
            es, ed = source.envs[s], self.envs[d]
            if not (source._started[s] and self._started[d]) or es._needs_reset == "failed" or es.sim is None \
                    or ed.sim is None:
                raise C.ResetNeeded(f"{own}.load_copies: reset source copy {s} and destination copy {d} first")
            if es._sea != ed._sea or es._config != ed._config:
                raise C.ConfigError(f"{own}.load_copies: source copy {s} and destination copy {d} must be reset "
                                    f"into the same sea state, wave seed and configuration (got {es._sea!r}, "
                                    f"{es._config!r} and {ed._sea!r}, {ed._config!r})")
            if es.sim.winch[K.W_MODE] > 0 or ed.sim.winch[K.W_MODE] > 0:
                raise C.ConfigError(f"{own}.load_copies: copies with a winch cannot be loaded (a remesh changes the "
                                    f"discretisation)")
        rs, rd = source.rows, self.rows
        for s, d in zip(src, dst):
            if source is self and s == d:
                continue
            es, ed = source.envs[s], self.envs[d]
            ed.sim.restore(es.sim.snapshot())
            ed.sim.counters[:] = es.sim.counters
            rd.stepper.load_row(d, rs.stepper, s)
            for name in ("actions", "prev_action", "amap"):
                getattr(rd, name)[d] = getattr(rs, name)[s]
            if rs.preview is not None and rd.preview is not None:
                rd.preview[d] = rs.preview[s]
            ed.observer = copy.deepcopy(es.observer)
            ed.np_random.bit_generator.state = es.np_random.bit_generator.state
            ed._needs_reset = es._needs_reset
            ed._plan = None
            self._obs[d] = source._obs[s]
            self._rew[d] = source._rew[s]
            self._term[d] = source._term[s]
            self._trunc[d] = source._trunc[s]
            self._autoreset[d] = source._autoreset[s]

    # ------------------------------------------------------------------ SyncVectorEnv-style helpers
    def call(self, name: str, *args, **kwargs) -> tuple:
        out = []
        for env in self.envs:
            f = getattr(env, name)
            out.append(f(*args, **kwargs) if callable(f) else f)
        return tuple(out)

    def get_attr(self, name: str) -> tuple:
        return tuple(getattr(env, name) for env in self.envs)

    def set_attr(self, name: str, values) -> None:
        if not isinstance(values, (list, tuple)):
            values = [values] * self.num_envs
        for env, v in zip(self.envs, values, strict=True):
            setattr(env, name, v)


class CompensatorGainsVectorEnv(TowVectorEnv):
    """Vector entry point of ``towenv/CompensatorGains-v0``."""
    env_class = CompensatorGainsEnv


class WinchPayoutVectorEnv(TowVectorEnv):
    """Vector entry point of ``towenv/WinchPayout-v0``."""
    env_class = WinchPayoutEnv
