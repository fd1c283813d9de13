"""Issue 15: the batch stepper calls the compiled kernel's entry point directly after the first step (skipping
numba's type resolution); the trajectory is the dispatcher's bit for bit, and the batched infos built in
blocks equal the single environments' infos (tests/envs/test_vector.py checks every key against
``_add_info``)."""
import pickle

import gymnasium as gym
import numpy as np

import towenv.envs  # noqa: F401


def _run(force_dispatcher, steps=40):
    env = gym.make("towenv/WinchPayout-v0", episode_seconds=10.0).unwrapped
    obs, _ = env.reset(seed=5)
    st = env._rows.stepper
    acts = np.random.default_rng(1).uniform(-1, 1, (steps, 1))
    out = [obs]
    for a in acts:
        if force_dispatcher:
            st._entry = None
        obs, r, te, tr, info = env.step(a)
        out.append(np.concatenate([obs, [r, info["t"], info["fish_heave"]]]).astype(float))
    return env, out


def test_entry_point_path_equals_the_dispatcher_bit_for_bit():
    env, fast = _run(False)
    assert env._rows.stepper._entry is not None           # the entry point was found and used
    _, slow = _run(True)
    for a, b in zip(fast, slow):
        np.testing.assert_array_equal(a, b)


def test_entry_point_is_not_pickled_and_is_found_again():
    env, _ = _run(False, steps=3)
    env2 = pickle.loads(pickle.dumps(env))
    assert env2._rows.stepper._entry is None
    env2.step(np.zeros(1))
    assert env2._rows.stepper._entry is not None
