"""Compatibility shim (issue 16, item 5): the batched environment stepper and its measurement rows moved to
:mod:`towenv.envs.stepper` and :mod:`towenv.envs.measurements` (the core is physics only). Only
:func:`kernel_args` is left here, for :mod:`towenv.core.recording`; new code calls
:meth:`towenv.core.simulator.Simulator.kernel_data` directly. Delete this module once nothing imports it.
"""
from __future__ import annotations

__all__ = ["kernel_args"]


def kernel_args(sim):
    """``(head, wave)`` for ``kernels.advance(n, dt, tops, *head, t0, wave)``: ``sim.kernel_data()``'s
    ``head`` and ``wave``."""
    kd = sim.kernel_data()
    return kd.head, kd.wave
