"""Gymnasium / SB3 environment tests (towenv.envs). Skipped when the ``.[rl]`` extra is not installed.

Physics is tested elsewhere; these check the RL contract: checkers, seeding determinism, pickling,
registration, finiteness under random actions, failure handling, vector envs and SB3 integration.
"""
from __future__ import annotations

import importlib
import math
import pickle
import warnings

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import towenv.envs  # noqa: E402  (registers the ids)
from gymnasium.utils.env_checker import check_env, data_equivalence  # noqa: E402
from towenv.envs.compensator import CompensatorGainsEnv  # noqa: E402
from towenv.envs.pieces import FixedSeas, HeaveOnlyReward, default_eval_sea_states  # noqa: E402
from towenv.envs.winch import WinchPayoutEnv  # noqa: E402

IDS = list(towenv.envs.ENV_IDS)
CLASSES = {"towenv/CompensatorGains-v0": CompensatorGainsEnv, "towenv/WinchPayout-v0": WinchPayoutEnv}


def _actions(env, n, seed=123):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1, 1, (n,) + env.action_space.shape).astype(np.float32)


def _rollout(env, actions, seed=None, options=None):
    obs, info = env.reset(seed=seed, options=options)
    out = [(obs, 0.0, False, False, info)]
    for a in actions:
        out.append(env.step(a))
        if out[-1][2] or out[-1][3]:
            break
    return out


# ---------------------------------------------------------------------------------------- registration
def test_registration_idempotent_and_all_ids_constructible():
    before = [k for k in gym.registry if k.startswith("towenv/")]
    importlib.reload(towenv.envs)                                   # re-registration is a no-op
    after = [k for k in gym.registry if k.startswith("towenv/")]
    assert sorted(before) == sorted(after) and set(IDS) <= set(after)
    for env_id in after:
        spec = gym.spec(env_id)
        assert isinstance(spec.entry_point, str) and isinstance(spec.vector_entry_point, str)
        assert spec.max_episode_steps is None                      # the envs truncate themselves
        env = gym.make(env_id)
        obs, _ = env.reset(seed=0)
        assert env.observation_space.contains(obs)
        obs, r, te, tr, info = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs) and math.isfinite(r)
        assert env.unwrapped.dt == pytest.approx(0.1) and env.unwrapped.max_steps == 3000
        env.close()


@pytest.mark.parametrize("env_id", IDS)
def test_gymnasium_checker(env_id):
    env = gym.make(env_id, render_mode="rgb_array").unwrapped      # also runs the render checks
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        check_env(env)
    assert not w, [str(x.message) for x in w]


@pytest.mark.parametrize("env_id", IDS)
def test_sb3_checker(env_id):
    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    env = gym.make(env_id).unwrapped
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        sb3_checker.check_env(env, warn=True)
    assert not w, [str(x.message) for x in w]                      # symmetric float32 [-1, 1] Box etc.


# ---------------------------------------------------------------------------------------- determinism
@pytest.mark.parametrize("env_id", IDS)
def test_same_seed_same_rollout(env_id):
    kw = dict(sensor_noise={"fish_heave_dev": 0.05, "tow_acc_z": 0.1}, obs_delay=1)   # noise must be seeded too
    a, b = gym.make(env_id, **kw), gym.make(env_id, **kw)
    acts = _actions(a, 150)
    ra, rb = _rollout(a, acts, seed=7), _rollout(b, acts, seed=7)
    assert len(ra) == len(rb) == 151
    for x, y in zip(ra, rb):
        assert data_equivalence(x, y, exact=True)
    rc = _rollout(a, acts, seed=8)                                  # another seed: another episode
    assert not np.array_equal(ra[50][0], rc[50][0])
    # reseeding the same env reproduces it, too
    assert all(data_equivalence(x, y, exact=True) for x, y in zip(ra, _rollout(a, acts, seed=7)))


def test_eval_set_is_common_random_numbers():
    ev1, ev2 = default_eval_sea_states(), CompensatorGainsEnv().eval_sea_states()
    assert len(ev1) == 12 and [(s, k) for s, k in ev1] == [(s, k) for s, k in ev2]
    assert {s.label.split()[1] for s, _ in ev1} == {"3", "4", "5"}
    env = CompensatorGainsEnv()
    acts = np.zeros((40, 2), np.float32)
    r1 = _rollout(env, acts, seed=1, options={"eval_index": 5})
    r2 = _rollout(env, acts, seed=999, options={"eval_index": 5})  # the rng does not matter
    assert all(np.array_equal(x[0], y[0]) for x, y in zip(r1, r2))
    assert r1[0][4]["sea_seed"] == ev1[5][1]
    fixed = CompensatorGainsEnv(sea_generator=FixedSeas(ev1[:2]))
    seeds = [fixed.reset(seed=s)[1]["sea_seed"] for s in (0, 0, 0)]
    assert seeds == [ev1[0][1], ev1[1][1], ev1[0][1]]


# ---------------------------------------------------------------------------------------- pickling
@pytest.mark.parametrize("cls", [CompensatorGainsEnv, WinchPayoutEnv])
def test_pickle_round_trip(cls):
    env = cls(render_mode="rgb_array")
    acts = _actions(env, 80)
    env.reset(seed=3)
    for a in acts[:40]:
        env.step(a)
    env.render()                                                    # a live figure must not break pickling
    clone = pickle.loads(pickle.dumps(env))
    for a in acts[40:]:                                             # continues mid-episode identically
        assert data_equivalence(env.step(a), clone.step(a), exact=True)
    fresh = pickle.loads(pickle.dumps(cls()))
    assert data_equivalence(_rollout(fresh, acts[:20], seed=5), _rollout(cls(), acts[:20], seed=5), exact=True)
    assert clone.render().shape[-1] == 3


# ---------------------------------------------------------------------------------------- behaviour
def test_compensator_action_map_is_log_scale_within_bounds():
    env = CompensatorGainsEnv()
    (k_lo, k_hi), (b_lo, b_hi) = env.sim.scene.compensator.stiffness_bounds, env.sim.scene.compensator.damping_bounds
    assert b_lo == 0.0                                              # -> log floor 1e-3 * b_hi
    assert env.gains([-1, -1]) == pytest.approx((k_lo, 1e-3 * b_hi))
    assert env.gains([1, 1]) == pytest.approx((k_hi, b_hi))
    assert env.gains([0, 0]) == pytest.approx((math.sqrt(k_lo * k_hi), math.sqrt(1e-3 * b_hi * b_hi)))
    np.testing.assert_allclose(env.action_of(*env.gains([0.3, -0.7])), [0.3, -0.7], atol=1e-12)
    env.reset(seed=0)
    assert env.observer.names[-1] == "last_action"
    np.testing.assert_allclose(env._prev_action, env.action_of(20e3, 5e3))   # the scene's passive setting
    env.step(np.array([1.0, 1.0], np.float32))
    cs = env.sim.compensator_state()
    assert (cs["stiffness"], cs["damping"]) == pytest.approx((k_hi, b_hi))


def test_winch_env_scene_and_payout():
    env = WinchPayoutEnv()
    sc = env.sim.scene
    assert sc.compensator is None and sc.winch is not None and sc.winch.max_speed == 1.5
    env.reset(seed=0, options={"eval_index": 0})
    for _ in range(30):
        obs, r, te, tr, info = env.step(np.array([1.0], np.float32))
    ws = env.sim.winch_state()
    assert 0 < ws["speed"] <= 1.5 and ws["length"] > 85.0
    assert env._last_m["winch_length_dev"] == pytest.approx(ws["length"] - 85.0)


def test_sensor_delay_is_a_ring_buffer():
    kw = dict(observations=("fish_heave", "tow_vel_z", "last_action"))
    now, late = WinchPayoutEnv(**kw), WinchPayoutEnv(obs_delay=3, **kw)
    acts = _actions(now, 30)
    ra, rb = _rollout(now, acts, seed=2), _rollout(late, acts, seed=2)
    for k in range(len(rb)):
        np.testing.assert_array_equal(rb[k][0], ra[max(k - 3, 0)][0])


def test_termination_floor_and_breaking_load():
    env = CompensatorGainsEnv(floor_depth=30.0)                     # the fish tows at ~40 m
    env.reset(seed=0)
    _, r, te, tr, info = env.step(env.action_space.sample())
    assert te and not tr and info["termination"].startswith("fish_below_floor")
    assert info["reward_components"]["terminal"] == pytest.approx(2.0 * env.max_steps)
    env = WinchPayoutEnv(breaking_load=1000.0)                      # top tension ~4 kN
    env.reset(seed=0)
    _, r, te, tr, info = env.step(env.action_space.sample())
    assert te and "cable_parted" in info["termination"] and "primary" in info["termination"]
    env = CompensatorGainsEnv(breaking_load=None, floor_depth=None, episode_seconds=0.5)
    env.reset(seed=0)
    out = [env.step(env.action_space.sample()) for _ in range(5)]
    assert [o[3] for o in out] == [False] * 4 + [True] and not any(o[2] for o in out)


def test_forced_numerical_failure_truncates_with_finite_observation():
    # an absurd time step without step cuts: the Newton iteration fails about 13 s in
    env = CompensatorGainsEnv(dt=0.5, control_hz=2.0, sim_overrides={"max_step_cuts": 0})
    env.reset(seed=0, options={"eval_index": 0})
    for _ in range(env.max_steps):
        obs, r, te, tr, info = env.step(env._prev_action)
        if tr or te:
            break
    assert tr and "failure" in info and info["solver_failure"] and info["t"] < 60.0
    assert "numerical failure" in info["failure"] and np.all(np.isfinite(obs)) and math.isfinite(r)
    assert env.observation_space.contains(obs)
    # and a solver that cannot converge at all fails on the first steps, never raising
    env = WinchPayoutEnv(dt=0.1, sim_overrides={"max_iterations": 1, "max_step_cuts": 0})
    env.reset(seed=0)
    res = []
    for _ in range(3):                      # stepping after truncation raises ResetNeeded (issue 17)
        res.append(env.step(env.action_space.sample()))
        if res[-1][2] or res[-1][3]:
            break
    assert any(o[3] and "failure" in o[4] for o in res)
    assert all(np.all(np.isfinite(o[0])) for o in res)


def test_randomised_speed_and_length_cache_simulators():
    env = CompensatorGainsEnv(vessel_speeds=(2.5, 3.0), cable_lengths=(80.0, 90.0), reward_fn=HeaveOnlyReward())
    seen = set()
    for s in range(12):
        _, info = env.reset(seed=s)
        seen.add((info["vessel_speed"], info["cable_length"]))
        obs, r, *_ = env.step(env.action_space.sample())
        assert np.all(np.isfinite(obs)) and math.isfinite(r)
        junction = env.sim.scene.line("secondary").top.distance
        assert info["cable_length"] - junction == pytest.approx(20.0)  # junction kept 20 m above the depressor
    assert seen <= {(2.5, 80.0), (2.5, 90.0), (3.0, 80.0), (3.0, 90.0)} and len(seen) >= 3
    assert len(env._sims) <= 5


def test_config_errors():
    with pytest.raises(ValueError, match="unknown observation channel"):
        CompensatorGainsEnv(observations=("fish_heave", "nope"))
    with pytest.raises(ValueError, match="render_mode"):
        CompensatorGainsEnv(render_mode="ascii")
    with pytest.raises(ValueError, match="no \\[compensator\\]"):
        CompensatorGainsEnv(scene="two_part_tow_1")
    with pytest.raises(ValueError, match="unknown reward weight"):
        WinchPayoutEnv(reward_weights={"heaving": 1.0})


def test_wave_preview_channel():
    env = CompensatorGainsEnv(observations=("fish_heave", "wave_preview"), preview_distances=(0.0, 20.0, 40.0))
    assert env.observation_space.shape == (4,)
    env.reset(seed=0, options={"eval_index": 4})
    for _ in range(300):                                            # past the 20 s start-up ramp
        obs, *_ = env.step(np.zeros(2, np.float32))
    x = env.sim.path.mean_path(np.array([env.sim.t]))[0][0, 0]           # mean tow-point track, heading 0
    eta = env.sim.wave.elevation(np.full(3, env.sim.t), x + np.array([0.0, 20.0, 40.0]), np.zeros(3))
    np.testing.assert_allclose(obs[1:], eta, atol=1e-5)
    assert np.ptp(obs[1:]) > 0


# ---------------------------------------------------------------------------------------- soak
@pytest.mark.parametrize("cls", [CompensatorGainsEnv, WinchPayoutEnv])
def test_random_policy_soak_stays_finite(cls):
    """Random actions over many sea states (up to code 7, Hs ≈ 6–9 m), with sensor noise: every
    observation/reward finite and inside the space, nothing raised (failures may only truncate)."""
    env = cls(sea_codes=(3, 4, 5, 6, 7), sensor_noise={"fish_heave_dev": 0.02}, episode_seconds=100.0)
    env.action_space.seed(0)
    steps = 0
    for ep in range(12):
        obs, _ = env.reset(seed=100 + ep)
        done = False
        while not done:
            obs, r, te, tr, info = env.step(env.action_space.sample())
            assert env.observation_space.contains(obs) and math.isfinite(r)
            assert all(math.isfinite(v) for v in info["reward_components"].values())
            done = te or tr
            steps += 1
    assert steps >= 10000


# ---------------------------------------------------------------------------------------- vector / SB3
@pytest.mark.parametrize("env_id", IDS)
def test_vector_env_matches_single_envs_and_autoresets(env_id):
    n, T = 3, 14
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", episode_seconds=1.0)
    assert type(venv).__module__ == "towenv.envs.vector"
    obs, info = venv.reset(seed=10)
    acts = np.stack([_actions(venv.envs[0], T, seed=i) for i in range(n)], axis=1)
    singles = [CLASSES[env_id](episode_seconds=1.0) for _ in range(n)]
    sobs = [s.reset(seed=10 + i)[0] for i, s in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(sobs))
    for t in range(T):
        obs, rew, te, tr, info = venv.step(acts[t])
        for i, s in enumerate(singles):
            if t == 10:                       # NEXT_STEP autoreset: the step after the end returns a reset
                o, r, e, u = s.reset()[0], 0.0, False, False
            else:
                o, r, e, u, _ = s.step(acts[t, i])
            np.testing.assert_array_equal(obs[i], o)
            assert (rew[i], te[i], tr[i]) == (r, e, u)
        assert tr.all() == (t == 9) and not te.any()
    venv.close()


def test_sb3_make_vec_env_and_short_training():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    for env_id in IDS:
        ve = make_vec_env(env_id, n_envs=2, seed=0, env_kwargs={"episode_seconds": 3.0})
        o = ve.reset()
        assert o.shape == (2,) + ve.observation_space.shape
        for k in range(32):                                         # crosses an episode end (30 steps)
            o, r, d, infos = ve.step(np.stack([ve.action_space.sample() for _ in range(2)]))
            assert np.all(np.isfinite(o)) and np.all(np.isfinite(r))
            if k == 29:
                assert d.all() and all(i["TimeLimit.truncated"] and "terminal_observation" in i for i in infos)
        ve.close()
    ve = make_vec_env("towenv/CompensatorGains-v0", n_envs=2, seed=0, env_kwargs={"episode_seconds": 3.0})
    model = PPO("MlpPolicy", ve, n_steps=32, batch_size=32, n_epochs=1, seed=0, device="cpu")
    model.learn(64)
    ve.close()
