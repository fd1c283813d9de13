"""Time schemes: how a :class:`~towenv.core.simulator.Simulator` advances in time.

The Simulator owns the scene, the discretisation, the tow-point path, the actuators and the outputs (its
history arrays ``hist_r``, ``hist_ang``, ``tens_hist``, ``top_react``); its scheme — one object, chosen
from ``solver.method`` by :func:`make_scheme`, the one factory behind ``towenv.Simulator``,
``towenv.make_simulator``, ``towenv.simulate``, the CLI, the environments and the scripts — owns the
scheme's own state and writes the outputs back after every call:

========================  ==========================================  ===============================
``solver.method``         scheme                                      module
========================  ==========================================  ===============================
``houbolt`` (default)     :class:`HouboltScheme` (implicit, Newton)    :mod:`towenv.core.houbolt`
``generalized_alpha``,    :class:`~towenv.core.alpha.AlphaScheme`      :mod:`towenv.core.alpha`
``newmark``
``euler``, ``rk2``,       :class:`~towenv.core.explicit.ExplicitScheme` :mod:`towenv.core.explicit`
``rk4``
``quasi_static``          :class:`~towenv.core.quasistatic.QuasiStaticScheme` :mod:`towenv.core.quasistatic`
========================  ==========================================  ===============================

What a scheme cannot simulate is refused by the scene's validation (a :class:`towenv.SceneError` naming
``solver.method``), the same way wherever the scene is loaded.
"""
from __future__ import annotations

import numpy as np

from . import kernels as K
from .model import NO_RECORDING

METHODS = ("houbolt", "generalized_alpha", "newmark", "euler", "rk2", "rk4", "quasi_static")


class TimeScheme:
    """Base class and the interface: ``run`` advances the simulator over the tow-point positions ``tops``
    (one per step) and raises :class:`towenv.SimulationDivergence` on failure, leaving the last good step;
    ``start`` is called once the Simulator's initial state exists; ``reset``/``snapshot``/``restore``/
    ``stats`` extend the Simulator's."""

    name = "houbolt"

    def __init__(self, sim):
        self.sim = sim

    def start(self) -> None:
        pass

    def run(self, tops, dt: float, t_start: float) -> None:
        raise NotImplementedError

    def warm_up(self) -> None:
        """Compile (or load from numba's cache) what ``run`` calls, without advancing: callers keep
        compilation out of their timings and progress displays."""

    def reset(self) -> None:
        pass

    def snapshot(self, snap) -> None:
        pass

    def restore(self, snap) -> None:
        pass

    def stats(self, out: dict) -> dict:
        return out

    def __repr__(self):
        return f"{type(self).__name__}({self.name!r})"


class HouboltScheme(TimeScheme):
    """Houbolt's implicit three-level scheme with the Newton iteration on segment tensions (model.md §§ 3–5):
    the compiled :func:`towenv.core.houbolt.advance` on the Simulator's own arrays; winch remeshing between
    calls."""

    name = "houbolt"

    def run(self, tops, dt, t_start):
        sim = self.sim
        done = 0
        settings = sim.settings.array()
        while done < len(tops):
            st, k, el, md = K.advance(len(tops) - done, dt, tops[done:], *sim._args, settings, sim._state,
                                      sim._ws, sim._saved, sim.counters, sim.comp, sim.winch, sim.wstate,
                                      t_start + done * dt, sim._wave_arrays(), NO_RECORDING)
            if st == K.OK:
                return
            if st == K.NEED_REMESH:
                done += k + 1
                sim._remesh()
                continue
            raise sim._divergence(st, el, md, t_start + (done + k + 1) * dt)

    def warm_up(self):
        kd = self.sim.kernel_data()
        K.advance(0, self.sim.settings.dt, np.empty((0, 3)), *kd.head, self.sim.t, kd.wave, NO_RECORDING)


def make_scheme(sim) -> TimeScheme:
    """The scheme ``sim.scene.solver.method`` names, bound to ``sim`` (the one factory)."""
    from ..scene import scene_field
    solver = scene_field(sim.scene, "solver")
    method = scene_field(solver, "method", "houbolt")
    if method == "houbolt":
        return HouboltScheme(sim)
    if method in ("euler", "rk2", "rk4"):
        from .explicit import ExplicitScheme
        return ExplicitScheme(sim, method, scene_field(solver, "axial_damping_ratio", 0.0))
    if method in ("generalized_alpha", "newmark"):
        from .alpha import AlphaScheme
        return AlphaScheme(sim, method, scene_field(solver, "rho_inf", 0.2),
                           scene_field(solver, "axial_damping_ratio", 0.0))
    if method == "quasi_static":
        from .quasistatic import QuasiStaticScheme
        return QuasiStaticScheme(sim)
    from ..scene import SceneError
    raise SceneError([("solver.method", f"must be one of {', '.join(METHODS)} (got {method!r})")])
