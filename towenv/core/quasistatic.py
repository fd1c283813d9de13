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
from .simulator import Simulator
from .statics import quasi_static


class QuasiStaticSimulator(Simulator):
    """Same interface as :class:`Simulator`; each step re-solves the static equilibrium."""

    def __init__(self, scene, **overrides):
        super().__init__(scene, **overrides)
        if self.comp[K.C_MODE] > 0 or self.winch[K.W_MODE] > 0:
            raise ValueError("QuasiStaticSimulator: scenes with a compensator or winch are not supported")

    def _run(self, tops, dt, t_start):
        s = self.system
        times = t_start + dt * (np.arange(len(tops)) + 1)
        _, heading, speed = self.path.mean_path(times)
        for k in range(len(tops)):
            # drag from the mean-path velocity: the wave-frequency tow-point motion has no quasi-static
            # meaning (using it made the bodies fly in a seaway)
            u = np.array([speed[k] * np.cos(heading[k]), speed[k] * np.sin(heading[k]), 0.0])
            r, T, ang = quasi_static(s, tops[k], u)
            self.hist_r[2] = self.hist_r[1]
            self.hist_r[1] = self.hist_r[0]
            self.hist_r[0] = r
            self.hist_ang[2] = self.hist_ang[1]
            self.hist_ang[1] = self.hist_ang[0]
            self.hist_ang[0] = ang
            self.tens_hist[1] = self.tens_hist[0]
            self.tens_hist[0] = T
            self.counters[N_STEPS] += 1
            self.counters[N_ITERATIONS] += 1
            self._static_reaction(u)
