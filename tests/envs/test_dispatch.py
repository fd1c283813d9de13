"""Issue 15: the batch stepper calls the compiled kernel's entry point directly after the first step (skipping
numba's type resolution); the trajectory is the dispatcher's bit for bit, and the batched infos built in
blocks equal the single environments' infos (tests/envs/test_vector.py checks every key against
``_add_info``)."""
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest

import towenv.envs  # noqa: F401
from towenv.envs.base import _observe_reward_flags


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


# ------------------------------------------------------------------------------------------------------------
# The single environment's prepared step (TowEnv._step_planned): the general path's numbers, bit for bit
# ------------------------------------------------------------------------------------------------------------
def _general_plans(monkeypatch):
    """Make every TowEnv.step take the general path (step_copies), as before the prepared step."""
    from towenv.envs import base

    class General(base._StepPlan):
        def __init__(self, env):
            super().__init__(env)
            self.fast = False

    monkeypatch.setattr(base, "_StepPlan", General)


def _episode(make, actions, seed, options=None, change=None):
    env = make()
    obs, _ = env.reset(seed=seed, options=options)
    out = [(obs, None, None, None, None)]
    for k, a in enumerate(actions):
        if change is not None and k == len(actions) // 2:
            change(env)
        step = env.step(a)
        out.append(step)
        if step[2] or step[3]:
            break
    return env, out


def _assert_same(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x[0], y[0])
        assert x[0].dtype == y[0].dtype
        assert x[1:] == y[1:]                           # reward, flags and the whole info dict, exactly


CASES = {
    # out-of-range and NaN actions (cleaned), a time-limit truncation
    "winch_truncated": (lambda: gym.make("towenv/WinchPayout-v0", episode_seconds=6.0).unwrapped, 1, 1.4, {}),
    # noise and delay on the observation, a termination by a limit (its reason and terminal cost in info)
    "comp_noise_delay_limit": (lambda: gym.make(
        "towenv/CompensatorGains-v0", sensor_noise={"fish_heave_dev": 0.01, "top_tension": 0.02}, obs_delay=2,
        termination=__import__("towenv.envs.pieces", fromlist=["Limits"]).Limits(
            __import__("towenv.envs.pieces", fromlist=["Limit"]).Limit("t", ">=", 4.0, "long_enough"))).unwrapped,
        2, 1.0, {"eval_index": 3}),
    # a numerical failure (truncation with info["failure"])
    "comp_failure": (lambda: gym.make("towenv/CompensatorGains-v0", dt=0.5, control_hz=2.0,
                                      sim_overrides={"max_step_cuts": 0}).unwrapped, 2, 0.0, {"eval_index": 0}),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_prepared_step_equals_the_general_path_bit_for_bit(case, monkeypatch):
    make, dim, amp, options = CASES[case]
    acts = np.random.default_rng(3).uniform(-amp, amp, (120, dim)).astype(np.float32)
    if amp > 1.0:
        acts[5] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env, fast = _episode(make, acts, seed=4, options=options)
        assert env._plan.fast and env._plan.call is not _observe_reward_flags   # the compiled entry point
        with monkeypatch.context() as m:
            _general_plans(m)
            env2, slow = _episode(make, acts, seed=4, options=options)
            assert not env2._plan.fast
    _assert_same(fast, slow)
    last = fast[-1]
    assert last[2] or last[3]                            # each case reaches its end
    if case == "comp_noise_delay_limit":
        assert last[2] and last[4]["termination"].startswith("long_enough") and "terminal" in last[4]["reward_components"]
    if case == "comp_failure":
        assert last[3] and last[4]["solver_failure"]


def test_prepared_step_follows_a_new_reward_or_observer_mid_episode(monkeypatch):
    """The plan is checked by identity each step: a reward function or observer assigned mid-episode is used from
    the next step on, as by the general path; a custom observer (not the standard one) takes the general path."""
    from towenv.envs.pieces import HeavePitchReward, Observer

    class Own(Observer):
        def measure_rows(self, *a, **k):
            return super().measure_rows(*a, **k)

    def change(env):
        env.reward_fn = HeavePitchReward(weights={"heave": 3.0, "pitch": 0.5})

    make = lambda: gym.make("towenv/WinchPayout-v0", episode_seconds=4.0).unwrapped   # noqa: E731
    acts = np.random.default_rng(5).uniform(-1, 1, (60, 1)).astype(np.float32)
    env, fast = _episode(make, acts, seed=2, change=change)
    assert env._plan.reward_fn is env.reward_fn and env._plan.fast
    with monkeypatch.context() as m:
        _general_plans(m)
        _, slow = _episode(make, acts, seed=2, change=change)
    _assert_same(fast, slow)

    def own_observer(env):
        o = env.observer
        env.observer = Own(o.names, action_dim=o.action_dim)

    env, fast = _episode(make, acts, seed=2, change=own_observer)
    assert not env._plan.fast                          # the custom observer: the general path
    with monkeypatch.context() as m:
        _general_plans(m)
        _, slow = _episode(make, acts, seed=2, change=own_observer)
    _assert_same(fast, slow)


def test_prepared_step_is_not_pickled_and_is_made_again():
    env = gym.make("towenv/WinchPayout-v0", episode_seconds=4.0).unwrapped
    env.reset(seed=1)
    env.step(np.zeros(1, np.float32))
    assert env._plan.fast
    env2 = pickle.loads(pickle.dumps(env))
    assert "_plan" not in env2.__dict__
    a = np.full(1, 0.3, np.float32)
    r1, r2 = env.step(a), env2.step(a)
    np.testing.assert_array_equal(r1[0], r2[0])
    assert r1[1:] == r2[1:] and env2._plan.fast
