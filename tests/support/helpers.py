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
