"""towenv: fast, verified dynamic simulator of underwater towed systems, with Gymnasium environments.

Core API::

    import towenv
    res = towenv.simulate("two_part_tow_1", duration=120)      # -> towenv.Result
    sim = towenv.Simulator("two_part_tow_1"); sim.advance(10.0); snap = sim.snapshot(); sim.restore(snap)
"""
from __future__ import annotations

__version__ = "0.1.0"

from .errors import SimulationDivergence  # noqa: F401
from .core.result import Result  # noqa: F401
from .core.run import make_simulator, simulate  # noqa: F401
from .core.simulator import Simulator, Snapshot, time_step_guide  # noqa: F401
try:
    from .scene import Scene, SceneError, list_scenes, load_scene  # noqa: F401
except ImportError:  # pragma: no cover  (scene module being written)
    pass

import importlib.util as _ilu  # noqa: E402

if _ilu.find_spec("gymnasium") is not None:  # optional .[rl] extra: registers the towenv/* environments
    from . import envs  # noqa: F401,E402
