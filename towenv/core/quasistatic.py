"""Quasi-static sequence: at every step the system takes the static equilibrium for the current tow-point
position and the mean-path velocity (no inertia, no added mass; drag from the mean tow velocity). The cheapest
"solver" behind the common interface, for slow manoeuvres and for charting what dynamics adds.

Bodies, junctions and series tows are handled by the same discrete static march as the start
configuration (:mod:`towenv.core.statics`); vessel oscillations enter only through the tow-point
velocity in the drag. Compensator and winch are not supported.
"""
from __future__ import annotations

import numpy as np

from .layout import N_ITERATIONS, N_STEPS

from . import kernels as K
from .schemes import TimeScheme
from .simulator import Simulator
from .statics import quasi_static


class QuasiStaticScheme(TimeScheme):
    """``solver.method = "quasi_static"``: each step re-solves the static equilibrium."""

    name = "quasi_static"

    def start(self):
        sim = self.sim
        if sim.comp[K.C_MODE] > 0 or sim.winch[K.W_MODE] > 0:
            raise ValueError("solver.method = 'quasi_static': scenes with a compensator or winch are not supported")

    def run(self, tops, dt, t_start):
        sim = self.sim
        s = sim.system
        times = t_start + dt * (np.arange(len(tops)) + 1)
        _, heading, speed = sim.path.mean_path(times)
        for k in range(len(tops)):
            # drag from the mean-path velocity: the wave-frequency tow-point motion has no quasi-static
            # meaning (using it made the bodies fly in a seaway)
            u = np.array([speed[k] * np.cos(heading[k]), speed[k] * np.sin(heading[k]), 0.0])
            r, T, ang = quasi_static(s, tops[k], u)
            sim.hist_r[2] = sim.hist_r[1]
            sim.hist_r[1] = sim.hist_r[0]
            sim.hist_r[0] = r
            sim.hist_ang[2] = sim.hist_ang[1]
            sim.hist_ang[1] = sim.hist_ang[0]
            sim.hist_ang[0] = ang
            sim.tens_hist[1] = sim.tens_hist[0]
            sim.tens_hist[0] = T
            sim.forget_step_memory()
            sim.counters[N_STEPS] += 1
            sim.counters[N_ITERATIONS] += 1
            sim._static_reaction(u)


def QuasiStaticSimulator(scene, **overrides) -> Simulator:
    """A :class:`~towenv.core.simulator.Simulator` with ``solver.method = "quasi_static"``."""
    return Simulator(scene, **{**overrides, "solver.method": "quasi_static"})
