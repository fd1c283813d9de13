"""towenv: fast, verified dynamic simulator of underwater towed systems, with Gymnasium environments."""
from __future__ import annotations

__version__ = "0.1.0"

from .errors import SimulationDivergence  # noqa: F401
