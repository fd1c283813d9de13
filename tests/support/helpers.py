"""Shared constants and scene builders of the test suite (importable as ``helpers``: pytest's
``pythonpath = ["tests/support"]`` in pyproject.toml; the towenv package under test is the *installed* one)."""
from __future__ import annotations

import math
from pathlib import Path

#: the repository checkout the tests live in (scripts/, docs/, README.md are read from here)
REPO = Path(__file__).resolve().parents[2]
#: reference data of the tests
DATA = REPO / "tests" / "data"

RHO = 1025.0
G = 9.80665


def peer_deck(speed=0.0, segments=20, dt=0.05, cda=0.5, **solver):
    """The verification.md standard deck: 100 m cable + 500 kg point body (as a scene dict)."""
    return dict(
        name="peer_deck",
        water=dict(density=RHO, gravity=G),
        vessel=dict(speed=speed),
        lines=[dict(name="cable", length=100.0, segments=segments, diameter=0.02, mass_per_length=1.0, EA=2e7,
                    cn=1.2, ct=0.01 * math.pi, can=1.0, cat=0.0, top="vessel", bottom={"body": "ball"})],
        bodies=[dict(name="ball", kind="ball", mass=500.0, volume=0.1, drag_area=cda, added_mass_coefficient=1.0)],
        solver=dict(dt=dt, **solver),
    )


def load_script(name: str):
    """A command line of the project as a module: ``agents.train`` / ``agents.evaluate`` (their code lives in
    the installed agents package), else ``scripts/<name>.py`` loaded from the checkout."""
    import importlib
    import importlib.util
    if name in ("train", "evaluate"):
        return importlib.import_module(f"agents.{name}")
    spec = importlib.util.spec_from_file_location(f"towenv_script_{name}", REPO / "scripts" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def kernel_and_twin_step(sim, state, rel=1e-8):
    """One Houbolt step of the compiled kernel on ``sim`` (``houbolt_step_entry`` on its arrays, in place) and of the
    numpy twin from ``state`` (``sim`` itself, or the previous :class:`~towenv.verification.twin.TwinStep`), to the
    same new tow point. Asserts that both converged, in the same number of iterations, to the same time levels
    (``hist_r``, ``tens_hist``, ``hist_ang`` within ``rel`` of their size). Returns (twin step, iterations, tow
    point) — the tests of the Newton stop, the predictor and the reused body derivatives chain it step by step."""
    import numpy as np

    from towenv.core import kernels as K
    from towenv.verification import twin
    top = sim.path.position(np.array([sim.t + sim.dt]))[0]
    new = twin.houbolt_step_np(state, sim.dt, top)
    st, it, _, _ = K.houbolt_step_entry(sim.dt, top, *sim._args, sim.settings.array(), sim._state, sim._ws, sim.comp)
    sim.step_count += 1
    assert st == K.OK and new.status == twin.OK, (st, new.status)
    assert it == new.iterations, (it, new.iterations)
    for key in ("hist_r", "tens_hist", "hist_ang"):
        a, b = getattr(new, key), getattr(sim, key)
        assert np.max(np.abs(a - b)) <= rel * max(np.max(np.abs(b)), 1e-30), key
    return new, it, top
