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
    import sys
    spec = importlib.util.spec_from_file_location(f"towenv_script_{name}", REPO / "scripts" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod        # a script's dataclasses look their module up there while being defined
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


def run_and_record_fish(sim, pairs=300):
    """``pairs`` × 2 steps of ``sim``, recording the (last) fish node's heave after each pair. Returns (final node
    positions, tensions, body angles, heave history, mean Newton iterations per step, step cuts)."""
    import numpy as np
    fish = sim.system.body_node[-1]
    z = []
    for _ in range(pairs):
        sim.advance_steps(2)
        z.append(sim.hist_r[0, fish, 2])
    return (sim.hist_r[0].copy(), sim.tens_hist[0].copy(), sim.hist_ang[0].copy(), np.array(z),
            sim.stats["mean_iterations"], sim.stats["step_cuts"])


def assert_same_solution_within_newton_tolerance(a, b):
    """Two :func:`run_and_record_fish` results of runs that differ only in how the Newton iteration starts or is
    linearised (predictor, reused derivatives): no step cut in either, and final states apart by no more than what
    the Newton tolerances (0.5 N + 1e-5·T, 1e-5 rad per step) let accumulate over 30 s — tensions by less than the
    absolute tolerance, positions by < 2 mm, angles by < 1e-3 rad — and the fish heave histories within 1e-3 of
    their standard deviation."""
    import numpy as np
    (ra, ta, aa, za, _, ca), (rb, tb, ab, zb, _, cb) = a, b
    assert ca == cb == 0
    assert np.max(np.abs(ta - tb)) < 0.5
    assert np.max(np.abs(ra - rb)) < 2e-3
    assert np.max(np.abs(aa - ab)) < 1e-3
    assert np.max(np.abs(za - zb)) < 1e-3 * np.std(za)


def assert_memory_travels_with_snapshots(sim, make, age):
    """The Houbolt step's kept memory (reused body derivatives or node matrices) and snapshots: ``sim`` is mid-cycle
    (its memory valid and some steps old, ``age(sim)`` = (valid, age)); a snapshot of it continues bit for bit after
    restore (the memory restored with it); restored without the memory (``predictor=None``), or reset, the next step
    computes it afresh (age 1); and a reset run equals a fresh one from ``make()`` bit for bit (40 steps each)."""
    import dataclasses

    import numpy as np
    mid = age(sim)
    snap = sim.snapshot()
    sim.advance_steps(40)
    first = sim.hist_r.copy(), sim.tens_hist.copy(), sim.hist_ang.copy()
    sim.restore(snap)
    assert age(sim) == mid
    sim.advance_steps(40)
    for a, b in zip(first, (sim.hist_r, sim.tens_hist, sim.hist_ang)):
        assert np.array_equal(a, b)
    sim.restore(dataclasses.replace(snap, predictor=None))
    assert age(sim)[0] == 0.0
    sim.advance_steps(1)
    assert age(sim) == (1.0, 1.0)
    sim.reset()
    assert age(sim)[0] == 0.0
    sim.advance_steps(40)
    fresh = make()
    fresh.advance_steps(40)
    assert np.array_equal(fresh.hist_r, sim.hist_r) and np.array_equal(fresh.tens_hist, sim.tens_hist)
