"""scripts/probe_command_iterations.py (issue 15, docs/environments.md "Where random actions' extra iterations come
from"): its command signals are what their names say, it counts the simulator's own Newton iterations over the steps
it ran, and bad options are refused by name."""
from __future__ import annotations

import numpy as np
import pytest

from helpers import load_script

pytest.importorskip("gymnasium")


def test_signals_are_in_range_and_held_where_named():
    probe = load_script("probe_command_iterations")
    sig = probe.signals(23, 2, np.random.default_rng(0))
    assert all(a.shape == (23, 2) and np.all(np.abs(a) <= 1.0) for a in sig.values())
    assert not sig["zero"].any() and np.all(sig["constant +0.05"] == 0.05) and np.all(sig["constant -0.05"] == -0.05)
    assert np.all(np.abs(sig["small random (±0.1)"]) <= 0.1)
    held2, held5, every = sig["random held 2 steps"], sig["random held 5 steps"], sig["random every step"]
    assert np.array_equal(held2[0:22:2], held2[1:23:2]) and np.all(held5[0:5] == held5[0])
    assert not np.array_equal(held5[4], held5[5]) and not np.array_equal(every[0], every[1])


def test_iterations_are_the_simulators_counts_over_the_steps_run():
    import gymnasium as gym
    import towenv.envs  # noqa: F401
    probe = load_script("probe_command_iterations")
    env = gym.make("towenv/WinchPayout-v0")
    its, n = probe.iterations_per_step(env, np.zeros((12, 1)), seed=3)
    u = env.unwrapped
    st = u.sim.stats
    assert n == 12 and st["steps"] == 12 * u.substeps          # counted from this episode's reset
    assert its == pytest.approx(st["iterations"] / st["steps"]) and its >= 1.0
    env.close()


@pytest.mark.parametrize("argv, field", [(["--steps", "0"], "--steps"), (["--sim-overrides", "[1]"], "--sim-overrides"),
                                         (["--sim-overrides", "{("], "--sim-overrides"), (["--env", "Pendulum"], "--env")])
def test_bad_options_are_refused_by_name(argv, field, capsys):
    probe = load_script("probe_command_iterations")
    with pytest.raises(SystemExit) as e:
        probe.main(argv)
    assert e.value.code == 2 and field in capsys.readouterr().err
