"""Exceptions raised by the towenv simulator."""
from __future__ import annotations


class SimulationDivergence(RuntimeError):
    """The time integration failed: Newton iteration did not converge (after step cuts), a non-finite
    number appeared, a segment was stretched beyond the physical limit, or a body reached the Euler
    singularity. Carries the simulated time, the element (``"segment 12 (line 'primary')"``, ``"node 5"``,
    ``"body 'fish'"``) and the cause; the simulator state is left at the last good step."""

    def __init__(self, time: float, element: str, cause: str, iterations: int = 0, residual: float = float("nan")):
        self.time = time
        self.element = element
        self.cause = cause
        self.iterations = iterations
        self.residual = residual
        detail = f" (iterations {iterations}, last max|dT| = {residual:.3g} N)" if iterations > 0 else ""
        super().__init__(f"simulation diverged at t = {time:.4f} s in {element}: {cause}{detail}")
