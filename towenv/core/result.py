"""Simulation results: time series of body motions, cable shapes and tensions, with save/load."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


@dataclass
class Result:
    """Recorded time series of one run.

    * ``t`` (n,) s
    * ``bodies[name]``: ``position`` (n,3) m, ``euler`` (n,3) rad (roll, pitch (+ nose down), yaw),
      ``velocity`` (n,3) m/s, ``omega`` (n,3) rad/s (body axes), ``surge``/``sway``/``heave`` (n,) m —
      displacements relative to the mean tow-point path, along track, across track (to port) and up.
    * ``lines[name]``: ``positions`` (n, nodes, 3) top node first, ``tensions`` (n, segments) N, top first
    * ``top_force`` (n,3): force of the cable on the vessel at the tow point; ``top_tension`` (n,) its norm
    * ``tow_point`` (n,3): prescribed tow-point position
    * ``actuators``: compensator ``stroke``/``stroke_velocity``/``stiffness``/``damping`` and winch
      ``payout_speed``/``deployed_length`` (n,), when the scene has them (a winch line's node arrays are
      NaN-padded to a fixed capacity)
    * ``meta``: scene name, time step, solver statistics, wall time
    """
    t: np.ndarray
    bodies: dict = field(default_factory=dict)
    lines: dict = field(default_factory=dict)
    top_force: np.ndarray | None = None
    top_tension: np.ndarray | None = None
    tow_point: np.ndarray | None = None
    meta: dict = field(default_factory=dict)
    actuators: dict = field(default_factory=dict)

    def save(self, path) -> Path:
        """Write one ``.npz`` file (arrays) with the metadata embedded as JSON."""
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(".npz")
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays = {"t": self.t, "top_force": self.top_force, "top_tension": self.top_tension,
                  "tow_point": self.tow_point}
        for b, d in self.bodies.items():
            for k, v in d.items():
                arrays[f"body::{b}::{k}"] = v
        for ln, d in self.lines.items():
            for k, v in d.items():
                arrays[f"line::{ln}::{k}"] = v
        for k, v in self.actuators.items():
            arrays[f"actuator::{k}"] = v
        arrays["__meta__"] = np.array(json.dumps(self.meta, default=float))
        np.savez_compressed(path, **{k: v for k, v in arrays.items() if v is not None})
        return path

    @classmethod
    def load(cls, path) -> "Result":
        with np.load(Path(path), allow_pickle=False) as z:
            bodies: dict = {}
            lines: dict = {}
            kw = {}
            for key in z.files:
                if key.startswith("body::"):
                    _, b, k = key.split("::")
                    bodies.setdefault(b, {})[k] = z[key]
                elif key.startswith("line::"):
                    _, ln, k = key.split("::")
                    lines.setdefault(ln, {})[k] = z[key]
                elif key.startswith("actuator::"):
                    kw.setdefault("actuators", {})[key.split("::")[1]] = z[key]
                elif key == "__meta__":
                    kw["meta"] = json.loads(str(z[key]))
                else:
                    kw[key] = z[key]
        return cls(bodies=bodies, lines=lines, **kw)

    def window(self, t_start: float) -> "Result":
        """The part of the record from ``t_start`` on (e.g. to drop the start-up ramp)."""
        m = self.t >= t_start

        def cut(d):
            return {k: v[m] for k, v in d.items()}

        return Result(self.t[m], {b: cut(d) for b, d in self.bodies.items()},
                      {ln: cut(d) for ln, d in self.lines.items()},
                      None if self.top_force is None else self.top_force[m],
                      None if self.top_tension is None else self.top_tension[m],
                      None if self.tow_point is None else self.tow_point[m], dict(self.meta),
                      {k: v[m] for k, v in self.actuators.items()})
