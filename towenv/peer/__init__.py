"""Cross-check peers for towenv (optional; test-only dependencies).

``towenv.peer.moordyn_runner`` builds and runs a MoorDyn v2 model of a single-line + point-body scene
(the verification "peer deck" and scenes of the same shape) with the same prescribed tow-point path as
towenv. MoorDyn is an optional dependency (``pip install towenv[peer]``); importing the runner works
without it, and :func:`~towenv.peer.moordyn_runner.require_moordyn` raises an ``ImportError`` with an
install hint when it is missing.
"""
from __future__ import annotations

from .moordyn_runner import (MoorDynResult, MoorDynUnsupported, moordyn_available, moordyn_input,  # noqa: F401
                             require_moordyn, run_moordyn, settled_state,
                             towenv_axial_damping_ratio)
