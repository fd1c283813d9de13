"""The suite tests what users install: with a regular (non-editable) install, ``towenv`` and ``agents`` must
be imported from site-packages, not from the checkout the tests sit in (``python -P -m pytest``, importlib
import mode). With an editable (development) install they are the checkout by design."""
import json
from importlib.metadata import PackageNotFoundError, distribution
from pathlib import Path

import pytest

from helpers import REPO


def _editable() -> bool | None:
    try:
        d = distribution("towenv")
    except PackageNotFoundError:
        return None
    text = d.read_text("direct_url.json")
    return bool(text and json.loads(text).get("dir_info", {}).get("editable"))


def test_tests_import_the_installed_package():
    import agents
    import towenv
    editable = _editable()
    if editable is None:
        pytest.fail("towenv is not installed: install it (pip install \".[rl,dev]\") and run python -P -m pytest")
    for mod in (towenv, agents):
        # the checkout's own package folder (a virtual environment may well sit inside the checkout)
        inside_checkout = Path(mod.__file__).resolve().parent == (REPO / mod.__name__).resolve()
        if editable:
            assert inside_checkout, f"{mod.__name__} from {mod.__file__} with an editable install of {REPO}"
        else:
            assert not inside_checkout, (f"{mod.__name__} was imported from the checkout ({mod.__file__}), not the "
                                         f"installed package: run the tests with python -P -m pytest")


def test_installed_package_carries_its_data():
    import agents.zoo as zoo
    import towenv
    from towenv.scene import list_scenes
    assert "two_part_tow_1" in list_scenes()
    assert (zoo.HYPERPARAMS_DIR / "ppo.yml").is_file() and (zoo.HYPERPARAMS_DIR / "baselines.yml").is_file()
    assert len(list(zoo.TRAINED_DIR.glob("*.zip"))) >= 6


def test_import_towenv_does_not_load_the_simulator():
    """``import towenv`` loads what a user touches (issue 15): the simulator's names are imported on first use,
    so numba (the larger part of the import time) is not loaded by the bare import; the names still work."""
    import subprocess
    import sys
    code = ("import sys, towenv; before = 'numba' in sys.modules; from towenv import Simulator, simulate; "
            "print(before, 'numba' in sys.modules, Simulator.__name__, callable(simulate), 'Simulator' in dir(towenv))")
    p = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    assert p.stdout.split() == ["False", "True", "Simulator", "True", "True"]
