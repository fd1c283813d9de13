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


def test_fused_observation_reward_flags_equal_the_pieces_own_calls():
    """With the standard pieces, observation, reward and flags are one compiled call; an Observer subclass that
    overrides ``measure_rows`` (here: calls the parent) takes the pieces' own calls. Same numbers, noise and
    delay included."""
    from towenv.envs.base import step_copies  # noqa: F401  (the path under test)
    from towenv.envs.pieces import Observer

    class Own(Observer):
        def measure_rows(self, *a, **k):
            return super().measure_rows(*a, **k)

    base = gym.make("towenv/CompensatorGains-v0").unwrapped.observer

    def run(cls):
        obs_fn = cls(base.names, noise={base.names[0]: 0.05}, delay=1, action_dim=base.action_dim)
        env = gym.make("towenv/CompensatorGains-v0", episode_seconds=8.0, observation_fn=obs_fn).unwrapped
        obs, _ = env.reset(seed=9)
        out = [obs.astype(float)]
        for a in np.random.default_rng(2).uniform(-1, 1, (60, 2)):
            obs, r, te, tr, info = env.step(a)
            out.append(np.concatenate([obs.astype(float), [r, float(te), float(tr)],
                                       list(info["reward_components"].values())]))
            if te or tr:
                break
        return out

    fused, own = run(Observer), run(Own)
    assert len(fused) == len(own) > 10
    for a, b in zip(fused, own):
        np.testing.assert_array_equal(a, b)
