"""``simulate``: run a scene for a duration and record a :class:`Result`."""
from __future__ import annotations

import math
import os
import time
from pathlib import Path

import numpy as np

from .result import Result
from .simulator import Simulator


def make_simulator(scene, **overrides) -> Simulator:
    """A simulator for ``scene`` using the time integration named by its ``solver.method``
    (overridable: ``make_simulator(scene, method="rk2")``): ``towenv.Simulator(scene, **overrides)`` with
    every scene solver setting also accepted by its short name."""
    from .simulator import load
    from ..scene import Solver
    solver_keys = tuple(Solver.model_fields)          # the scene schema is the one list of solver settings
    sc = load(scene, {("solver." + k if k in solver_keys else k): v for k, v in overrides.items()}
              if overrides else None)
    return Simulator(sc)       # the scheme is the one solver.method names (towenv.core.schemes.make_scheme)


def simulate(scene, duration: float, record_interval: float | None = None, progress: bool = False, *,
             _compiled: bool = True, **overrides) -> Result:
    """Simulate ``scene`` (path, dict, embedded name or Scene) for ``duration`` seconds.

    ``record_interval`` defaults to the multiple of ``dt`` closest to 0.05 s. ``overrides`` are solver
    settings (``dt=0.01``) or dotted scene fields (``**{"vessel.speed": 2.0}``).
    Raises :class:`towenv.SimulationDivergence` on numerical failure (with time, element and cause).

    With the Houbolt solver and no winch, the run is advanced and recorded in compiled chunks
    (:mod:`towenv.core.recording`: one numba call per ~0.2 s of wall time instead of a Python round trip per
    record), bit-identical to the per-record loop used otherwise (other solvers, winch scenes; and
    ``_compiled=False``, kept for the tests). The first run after installing or after ``kernels.py``
    changes compiles the recording loop (~5 s, then cached on disk).
    """
    duration = _finite_positive("duration", duration)
    if record_interval is not None:
        record_interval = _finite_positive("record_interval", record_interval)
    sim = scene if isinstance(scene, Simulator) else make_simulator(scene, **overrides)
    dt = sim.dt
    every = max(1, int(round((0.05 if record_interval is None else record_interval) / dt)))
    n_steps, n_rec = plan_records(sim, duration, every)
    rec = Recorder(sim, n_rec)
    rec.record()
    from . import recording
    fast = _compiled and n_steps >= every and recording.supports(sim, rec)
    # compile (first run) or load the kernels before the clock and the progress bar start: the real-time
    # factor and the progress display measure the simulation only
    recording.warm_up(sim, rec, every) if fast else sim.scheme.warm_up()
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=n_steps, unit="step", desc=f"simulating {n_steps * dt:g} s", leave=False,
                   unit_scale=False, dynamic_ncols=True)
    wall0 = time.perf_counter()
    done = 0
    if fast:
        n_full = n_steps // every
        recording.advance_recorded(sim, rec, n_full, every, on_chunk=bar.update if bar is not None else None)
        done = n_full * every
    while done < n_steps:
        k = min(every, n_steps - done)
        sim.advance_steps(k)
        done += k
        if k == every:
            rec.record()
        if bar is not None:
            bar.update(k)
    wall = time.perf_counter() - wall0
    if bar is not None:
        bar.close()
    res = rec.result()
    res.meta.update({"scene": getattr(sim.scene, "name", None) if not isinstance(sim.scene, dict)
                     else sim.scene.get("name"), "dt": dt, "duration": n_steps * dt, "wall_time_s": wall,
                     "real_time_factor": n_steps * dt / wall if wall > 0 else float("inf"), **sim.stats})
    return res


def kernels_compiled() -> bool:
    """Whether numba's on-disk cache already holds the compiled time-step kernel (``houbolt.advance``) for
    this Python; False on the first run after an install or an update, when compiling takes 20 s to 1.5 min of CPU (by machine)
    (numba caches next to the sources, or under ``NUMBA_CACHE_DIR``)."""
    import sys
    from . import kernels
    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    dirs = [Path(kernels.__file__).resolve().parent / "__pycache__"]
    if os.environ.get("NUMBA_CACHE_DIR"):
        dirs.append(Path(os.environ["NUMBA_CACHE_DIR"]))
    return any(any(d.rglob(f"houbolt.advance-*.{tag}.nbi")) for d in dirs if d.is_dir())


def _finite_positive(name, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: must be a finite number of seconds > 0 (got {value!r})") from None
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name}: must be a finite number of seconds > 0 (got {value!r})")
    return v


def available_memory() -> int:
    """Bytes of memory available now (Linux ``SC_AVPHYS_PAGES``; elsewhere 8 GiB is assumed)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_AVPHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-Linux
        return 8 << 30


def plan_records(sim, duration: float, every: int) -> tuple[int, int]:
    """``(n_steps, n_records)`` of a run of ``duration`` s recorded every ``every`` steps, refusing (with a
    ``ValueError`` naming ``duration``) a run shorter than one step or one whose record would not fit in
    half of the memory available now."""
    dt = sim.dt
    steps = duration / dt
    if steps < 0.5:
        raise ValueError(f"duration: {duration:g} s is shorter than one time step (dt = {dt:g} s)")
    n_rec_f = steps / every + 1
    need = n_rec_f * Recorder.bytes_per_record(sim)
    avail = available_memory()
    if need > 0.5 * avail:
        size = f"{n_rec_f:.3g} samples (~{need / 2**30:.3g} GiB)" if math.isfinite(need) else "more than 1e300 samples"
        raise ValueError(f"duration: {duration:g} s at dt = {dt:g} s would record {size}, more than half of the memory available "
                         f"({avail / 2**30:.3g} GiB): shorten the run or record less often (record_interval)")
    n_steps = int(round(steps))
    return n_steps, n_steps // every + 1


class Recorder:
    """Collects the state of a Simulator into preallocated arrays."""

    def __init__(self, sim: Simulator, n: int):
        self.sim = sim
        self.n = 0
        s = sim.system
        self.t = np.zeros(n)
        self.top_force = np.zeros((n, 3))
        self.tow_point = np.zeros((n, 3))
        self.bodies = {b.name: {k: np.zeros((n, 3)) for k in ("position", "euler", "velocity", "omega")}
                       for b in s.bodies}
        # with a winch the number of nodes of its line changes: pad with NaN up to the capacity
        cap = {lm.name: len(lm.nodes) for lm in s.lines}
        self.has_winch = sim.winch[0] > 0
        self.has_comp = sim.comp[0] > 0
        if self.has_winch:
            import towenv.core.kernels as K
            lm = s.line(sim.winch_line)
            extra = (sim.winch[K.W_LMAX] - float(s.l0[lm.segments].sum())) / (0.5 * sim.winch[K.W_LNOM])
            cap[lm.name] += int(np.ceil(max(extra, 0.0))) + 2
        self.lines = {lm.name: {"positions": np.full((n, cap[lm.name], 3), np.nan),
                                "tensions": np.full((n, cap[lm.name] - 1), np.nan)} for lm in s.lines}
        self.actuators = {}
        if self.has_comp:
            self.actuators.update({k: np.zeros(n) for k in ("stroke", "stroke_velocity", "stiffness", "damping")})
        if self.has_winch:
            self.actuators.update({k: np.zeros(n) for k in ("payout_speed", "deployed_length")})
        self._fast_init(n)

    @staticmethod
    def bytes_per_record(sim) -> int:
        """Upper estimate of the memory one record takes (raw buffers, the time series and the copies
        ``result()`` makes)."""
        s = sim.system
        nb, nr = len(s.bodies), s.n_rigid
        cap = s.n_nodes + (64 if sim.winch[0] > 0 else 0)
        per = (1 + 6 + 3 * s.n_nodes + 9 * nb + 18 * nr + s.n_segments     # t, forces, raw state buffers
               + nb * (12 + 3) + 2 * (4 * cap) + 6)                          # series + line arrays + actuators
        return 8 * 2 * per

    def _fast_init(self, n):
        s = self.sim.system
        self.fast = not self.has_winch
        if self.fast:
            self.R = np.zeros((n, s.n_nodes, 3))
            self.bnodes = np.array([b.node for b in s.bodies], int)
            self.RB = np.zeros((n, 3, len(self.bnodes), 3))
            self.A = np.zeros((n, 3, s.n_rigid, 3))
            self.C = np.zeros((n, s.n_rigid, 3, 3))
            self.T = np.zeros((n, s.n_segments))

    def record(self):
        i = self.n
        sim = self.sim
        if self.fast:
            self.t[i] = sim.t
            self.R[i] = sim.hist_r[0]
            self.RB[i] = sim.hist_r[:, self.bnodes]
            self.A[i] = sim.hist_ang
            self.C[i] = sim.body_chart
            self.T[i] = sim.tens_hist[0]
            self.top_force[i] = sim.top_react
            if self.actuators:
                self._record_actuators(i)
            self.n += 1
            return
        self.t[i] = sim.t
        self.top_force[i] = sim.top_force
        self.tow_point[i] = sim.positions[sim.system.top_node]
        for name, d in self.bodies.items():
            st = sim.body_state(name)
            for k in d:
                d[k][i] = st[k]
        for name, d in self.lines.items():
            st = sim.line_state(name)
            k = min(len(st["positions"]), d["positions"].shape[1])
            d["positions"][i, :k] = st["positions"][:k]
            d["tensions"][i, :k - 1] = st["tensions"][:k - 1]
        self._record_actuators(i)
        self.n += 1

    def _record_actuators(self, i):
        sim = self.sim
        if self.has_comp:
            c = sim.compensator_state()
            for key in ("stroke", "stroke_velocity", "stiffness", "damping"):
                self.actuators[key][i] = c[key]
        if self.has_winch:
            w = sim.winch_state()
            self.actuators["payout_speed"][i] = w["speed"]
            self.actuators["deployed_length"][i] = w["length"]

    def _fast_finish(self):
        """Turn the raw state records into body and line time series (vectorised)."""
        from .kernels import euler_rates_to_omega_series
        from .simulator import physical_attitude
        n = self.n
        s = self.sim.system
        dt = self.sim.dt
        for k, bm in enumerate(s.bodies):
            d = self.bodies[bm.name]
            rb = self.RB[:n, :, k]
            d["position"][:n] = rb[:, 0]
            d["velocity"][:n] = (3 * rb[:, 0] - 4 * rb[:, 1] + rb[:, 2]) / (2 * dt)
            if bm.rigid_index >= 0:
                a = self.A[:n, :, bm.rigid_index]
                d["euler"][:n] = physical_attitude(self.C[:n, bm.rigid_index], a[:, 0])[0]
                dang = (3 * a[:, 0] - 4 * a[:, 1] + a[:, 2]) / (2 * dt)
                euler_rates_to_omega_series(np.ascontiguousarray(a[:, 0]), dang, d["omega"][:n])
        for lm in s.lines:
            d = self.lines[lm.name]
            d["positions"][:n] = self.R[:n][:, lm.nodes]
            d["tensions"][:n] = self.T[:n][:, lm.segments]
        self.tow_point[:n] = self.R[:n, s.top_node]

    def result(self) -> Result:
        n = self.n
        sim = self.sim
        if self.fast:
            self._fast_finish()
        t = self.t[:n]
        mean, heading, _ = sim.path.mean_path(t)
        e_along = np.stack([np.cos(heading), np.sin(heading), np.zeros_like(heading)], axis=1)
        e_across = np.stack([-np.sin(heading), np.cos(heading), np.zeros_like(heading)], axis=1)
        bodies = {}
        for name, d in self.bodies.items():
            dd = {k: v[:n] for k, v in d.items()}
            rel = dd["position"] - mean
            dd["surge"] = np.einsum("ij,ij->i", rel, e_along)
            dd["sway"] = np.einsum("ij,ij->i", rel, e_across)
            dd["heave"] = rel[:, 2]
            bodies[name] = dd
        lines = {name: {k: v[:n] for k, v in d.items()} for name, d in self.lines.items()}
        tf = self.top_force[:n]
        meta = {}
        if self.has_comp:
            c = sim.compensator_state()
            meta.update(end_stop_hits=c["hits"], max_end_stop_penetration=c["max_penetration"])
        res = Result(t=t, bodies=bodies, lines=lines, top_force=tf, top_tension=np.linalg.norm(tf, axis=1),
                     tow_point=self.tow_point[:n], meta=meta)
        res.actuators = {k: v[:n] for k, v in self.actuators.items()}
        return res
