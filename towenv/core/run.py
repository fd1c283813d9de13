"""``simulate``: run a scene for a duration and record a :class:`Result`."""
from __future__ import annotations

import time

import numpy as np

from .result import Result
from .simulator import Simulator


def simulate(scene, duration: float, record_interval: float | None = None, progress: bool = False,
             **overrides) -> Result:
    """Simulate ``scene`` (path, dict, embedded name or Scene) for ``duration`` seconds.

    ``record_interval`` defaults to the multiple of ``dt`` closest to 0.05 s. ``overrides`` are solver
    settings (``dt=0.01``) or dotted scene fields (``**{"vessel.speed": 2.0}``).
    Raises :class:`towenv.SimulationDivergence` on numerical failure (with time, element and cause).
    """
    if not (duration > 0):
        raise ValueError(f"duration: must be > 0 s (got {duration})")
    sim = scene if isinstance(scene, Simulator) else Simulator(scene, **overrides)
    dt = sim.dt
    if record_interval is None:
        every = max(1, int(round(0.05 / dt)))
    else:
        if not (record_interval > 0):
            raise ValueError(f"record_interval: must be > 0 s (got {record_interval})")
        every = max(1, int(round(record_interval / dt)))
    n_steps = int(round(duration / dt))
    n_rec = n_steps // every + 1
    rec = Recorder(sim, n_rec)
    rec.record()
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=round(n_steps * dt, 3), unit="s", desc="simulating", leave=False)
    wall0 = time.perf_counter()
    done = 0
    while done < n_steps:
        k = min(every, n_steps - done)
        sim.advance_steps(k)
        done += k
        if k == every:
            rec.record()
        if bar is not None:
            bar.update(round(k * dt, 3))
    wall = time.perf_counter() - wall0
    if bar is not None:
        bar.close()
    res = rec.result()
    res.meta.update({"scene": getattr(sim.scene, "name", None) if not isinstance(sim.scene, dict)
                     else sim.scene.get("name"), "dt": dt, "duration": n_steps * dt, "wall_time_s": wall,
                     "real_time_factor": n_steps * dt / wall if wall > 0 else float("inf"), **sim.stats})
    return res


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
        self.lines = {lm.name: {"positions": np.zeros((n, len(lm.nodes), 3)),
                                "tensions": np.zeros((n, len(lm.segments)))} for lm in s.lines}

    def record(self):
        i = self.n
        sim = self.sim
        self.t[i] = sim.t
        self.top_force[i] = sim.top_force
        self.tow_point[i] = sim.positions[sim.system.top_node]
        for name, d in self.bodies.items():
            st = sim.body_state(name)
            for k in d:
                d[k][i] = st[k]
        for name, d in self.lines.items():
            st = sim.line_state(name)
            d["positions"][i] = st["positions"]
            d["tensions"][i] = st["tensions"]
        self.n += 1

    def result(self) -> Result:
        n = self.n
        sim = self.sim
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
        return Result(t=t, bodies=bodies, lines=lines, top_force=tf, top_tension=np.linalg.norm(tf, axis=1),
                      tow_point=self.tow_point[:n], meta={})
