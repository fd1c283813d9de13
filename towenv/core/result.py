"""Simulation results: time series of body motions, cable shapes and tensions, with save/load."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..atomic import atomic_savez


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
        """Write one ``.npz`` file (arrays) with the metadata embedded as JSON, atomically (a temporary
        name, then a rename: an interrupt never leaves a partial file at ``path``). Any body, line or
        actuator name round-trips (names live in a JSON table, not in the array keys)."""
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(".npz")
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays = {"t": self.t, "top_force": self.top_force, "top_tension": self.top_tension,
                  "tow_point": self.tow_point}
        names = {"bodies": list(self.bodies), "lines": list(self.lines), "actuators": list(self.actuators)}
        for i, (b, d) in enumerate(self.bodies.items()):
            for k, v in d.items():
                arrays[f"body::{i}::{k}"] = v
        for i, (ln, d) in enumerate(self.lines.items()):
            for k, v in d.items():
                arrays[f"line::{i}::{k}"] = v
        for i, (k, v) in enumerate(self.actuators.items()):
            arrays[f"actuator::{i}"] = v
        arrays["__names__"] = np.array(json.dumps(names))
        arrays["__meta__"] = np.array(json.dumps(self.meta, default=float))
        atomic_savez(path, {k: v for k, v in arrays.items() if v is not None})
        return path

    @classmethod
    def load(cls, path) -> "Result":
        """Read a file written by :meth:`save`. A file that is empty, not an ``.npz``, truncated/corrupt or
        that holds no record raises one ``ValueError`` naming the file and the problem (a missing file:
        ``FileNotFoundError``)."""
        path = Path(path)

        def bad(what):
            return ValueError(f"{path}: not a readable towenv result: {what}")

        with open(path, "rb") as f:       # FileNotFoundError / IsADirectoryError name the path themselves
            head = f.read(4)
        if not head:
            raise bad("the file is empty")
        if head != b"PK\x03\x04":
            raise bad("not an .npz (zip) file")
        try:
            with np.load(path, allow_pickle=False) as z:
                data = {key: z[key] for key in z.files}
        except Exception as exc:          # BadZipFile, zlib.error, EOFError, ValueError, OSError ...
            raise bad(f"truncated or corrupt ({type(exc).__name__}: {exc})") from None
        if "t" not in data:
            raise bad("no time vector 't'")
        try:
            names = json.loads(str(data.pop("__names__"))) if "__names__" in data else None
            meta = json.loads(str(data.pop("__meta__"))) if "__meta__" in data else {}
        except ValueError as exc:
            raise bad(f"corrupt metadata ({exc})") from None
        bodies: dict = {}
        lines: dict = {}
        actuators: dict = {}
        kw = {}
        try:
            for key, v in data.items():
                kind, _, rest = key.partition("::")
                if kind in ("body", "line"):
                    ident, _, k = rest.rpartition("::")
                    name = names["bodies" if kind == "body" else "lines"][int(ident)] if names else ident
                    (bodies if kind == "body" else lines).setdefault(name, {})[k] = v
                elif kind == "actuator":
                    actuators[names["actuators"][int(rest)] if names else rest] = v
                elif key in ("t", "top_force", "top_tension", "tow_point"):
                    kw[key] = v
                else:
                    raise KeyError(key)
        except (KeyError, IndexError, ValueError, TypeError) as exc:
            raise bad(f"unexpected array {exc}") from None
        if not bodies and not lines:
            raise bad("it holds no body or line records (only " + ", ".join(sorted(data)) + ")")
        n = len(kw["t"])
        for what, arr in ([("t", kw["t"])] + [(f"bodies[{b}].{k}", v) for b, d in bodies.items() for k, v in d.items()]
                          + [(f"lines[{ln}].{k}", v) for ln, d in lines.items() for k, v in d.items()]):
            if arr.ndim < 1 or len(arr) != n:
                raise bad(f"{what} has {arr.shape[0] if arr.ndim else 0} samples, the time vector {n}")
        return cls(bodies=bodies, lines=lines, meta=meta, actuators=actuators, **kw)

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
