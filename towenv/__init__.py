"""towenv: fast, verified dynamic simulator of underwater towed systems, with Gymnasium environments.

Core API::

    import towenv
    res = towenv.simulate("two_part_tow_1", duration=120)      # -> towenv.Result
    sim = towenv.Simulator("two_part_tow_1"); sim.advance(10.0); snap = sim.snapshot(); sim.restore(snap)
"""
from __future__ import annotations

__version__ = "0.1.0"

from .errors import SimulationDivergence  # noqa: F401

#: the simulator's names, imported on first use (issue 15: ``import towenv`` loads what a user touches — the
#: simulator pulls in numba, ~0.6 s of a 1.4 s import on a slow machine)
_LAZY = {"Result": ".core.result", "make_simulator": ".core.run", "simulate": ".core.run",
         "Simulator": ".core.simulator", "Snapshot": ".core.simulator", "time_step_guide": ".core.simulator"}


def __getattr__(name):
    if name in _LAZY:
        import importlib
        value = getattr(importlib.import_module(_LAZY[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'towenv' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


try:
    from .scene import Scene, SceneError, list_scenes, load_scene  # noqa: F401
except ImportError:  # pragma: no cover  (scene module being written)
    pass

import importlib.util as _ilu  # noqa: E402

if _ilu.find_spec("gymnasium") is not None:  # optional .[rl] extra: registers the towenv/* environments
    from . import envs  # noqa: F401,E402
