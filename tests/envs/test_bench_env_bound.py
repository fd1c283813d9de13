"""scripts/bench_env.py's zero-overhead bound under the episode's commands (issue 15): the compiled step driven by
each step's action mapped to commands exactly as ``TowEnv.step`` maps it. Two physical expectations, no timings:
the commanded run leaves the stepper with the commands of the last action (it is the env's command sequence, not a
fixed one), and a command that changes every control step costs the Newton solver more iterations than a fixed
one (the benchmark's reason for the bound; measured 3.55–3.62 against 2.46–2.58 per physics step)."""
from __future__ import annotations

import numpy as np
import pytest

from helpers import load_script

gym = pytest.importorskip("gymnasium")


@pytest.fixture(scope="module")
def bench():
    return load_script("bench_env")


@pytest.mark.parametrize("env_id", ["towenv/CompensatorGains-v0", "towenv/WinchPayout-v0"])
def test_commanded_run_follows_the_actions_and_costs_more_iterations(bench, env_id):
    import towenv.envs  # noqa: F401  (registers the ids)
    env = gym.make(env_id).unwrapped
    acts = np.random.default_rng(3).uniform(-1, 1, (300,) + env.action_space.shape).astype(np.float32)
    commanded = bench._commanded_kernel(env, acts)
    it_cmd = bench._iterations(env, commanded)
    st, row = env._rows.stepper, env._row
    # the commands the env itself writes for the last action
    got = st.U[row].copy()
    A = np.zeros_like(env._rows.actions)
    A[row] = acts[-1]
    U = np.zeros_like(st.U)
    env._commands(A, np.array([row]), U, env._rows.amap)
    np.testing.assert_array_equal(got, U[row])

    def fixed():
        env.reset(seed=0, options={"eval_index": 4})
        for _ in range(len(acts)):
            st.step(env.substeps, env.ACT_KIND)
    it_fixed = bench._iterations(env, fixed)
    # random commands every 0.1 s: at least 20 % more Newton iterations per physics step than a fixed command
    assert it_cmd > 1.2 * it_fixed, (it_cmd, it_fixed)
    env.close()
