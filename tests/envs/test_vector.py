"""The compiled batched environments (towenv.envs.stepper, towenv.envs.vector, towenv.envs.sb3).

The batched vector env must reproduce N single environments with the same seeds and actions BIT FOR BIT
(observations, rewards, flags and infos), including winch remeshes, numerical failures, sensor noise,
observation delay and copies of different node counts; the measurement gather must agree with the
Simulator's own API; the phase-recurrence tow-point path must agree with the exact path to round-off.
"""
from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import towenv.envs  # noqa: E402,F401  (registers the ids)
from gymnasium.utils.env_checker import data_equivalence  # noqa: E402
from gymnasium.vector import AutoresetMode  # noqa: E402
from towenv.envs import measurements as MS  # noqa: E402
from towenv.envs import stepper as ST  # noqa: E402
from towenv.envs.compensator import CompensatorGainsEnv  # noqa: E402
from towenv.envs.winch import WinchPayoutEnv  # noqa: E402

IDS = ("towenv/CompensatorGains-v0", "towenv/WinchPayout-v0")
CLASSES = {"towenv/CompensatorGains-v0": CompensatorGainsEnv, "towenv/WinchPayout-v0": WinchPayoutEnv}


def _compare(env_id, acts, seed=0, kw=None, vkw=None, reset_options=None):
    """Step a vector env and N single envs with the same seeds/actions; assert bit-identity. Returns
    the vector env and the list of single-env infos per step."""
    kw = dict(kw or {})
    n = acts.shape[1]
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kw, **(vkw or {}))
    singles = [CLASSES[env_id](**kw) for _ in range(n)]
    obs, info = venv.reset(seed=seed, options=reset_options)
    exp = {}
    for i, s in enumerate(singles):
        o, inf = s.reset(seed=seed + i, options=reset_options)
        np.testing.assert_array_equal(obs[i], o)
        exp = venv.unwrapped._add_info(exp, inf, i)
    assert data_equivalence(info, exp, exact=True)
    infos = []
    for t in range(acts.shape[0]):
        obs, rew, te, tr, vinfo = venv.step(acts[t])
        exp, step_infos = {}, []
        for i, s in enumerate(singles):
            o, r, e, u, inf = s.step(acts[t, i])
            np.testing.assert_array_equal(obs[i], o, err_msg=f"step {t}, copy {i}")
            assert (rew[i], te[i], tr[i]) == (r, e, u), (t, i)
            assert rew.dtype == np.float64 and np.isfinite(obs[i]).all()
            exp = venv.unwrapped._add_info(exp, inf, i)
            step_infos.append(inf)
        assert data_equivalence(vinfo, exp, exact=True), (t, vinfo, exp)
        infos.append(step_infos)
        if (te | tr).any():
            break
    return venv, singles, infos


def _check_tension_ratio(env):
    """The row's tension ratio against the breaking loads of the simulator's CURRENT segments."""
    sim = env.sim
    loads = {"primary": 160e3, "secondary": 20e3}
    _, top_inv, _ = env._tension_layout(sim)        # the tow point counts if a line starts at it (no sheave)
    ratio = sim.top_tension * top_inv
    for lm in sim.system.lines:
        ratio = max(ratio, float(sim.tensions[lm.segments].max()) / loads[lm.name])
    assert env._last_m["tension_ratio"] == pytest.approx(ratio, rel=1e-12)
    assert env._last_m["min_tension"] == sim.tensions.min()


def _random_actions(T, n, dim, seed=0):
    return np.random.default_rng(seed).uniform(-1, 1, (T, n, dim)).astype(np.float32)


@pytest.mark.parametrize("env_id", IDS)
def test_batched_equals_single_envs_bit_for_bit(env_id):
    dim = CLASSES[env_id].ACTION_DIM
    venv, _, _ = _compare(env_id, _random_actions(25, 3, dim), seed=3)
    assert type(venv).__module__ == "towenv.envs.vector"
    venv.close()


def test_batched_noise_delay_and_mixed_node_counts_bit_for_bit():
    # sensor noise (drawn per copy from its own np_random), a delay ring buffer per copy, and cable
    # lengths drawn per reset: the copies run different Simulators (configurations) in one typed List
    kw = {"sensor_noise": {"fish_heave_dev": 0.05, "top_tension": 0.02}, "obs_delay": 2,
          "cable_lengths": (70.0, 85.0, 100.0)}
    venv, singles, _ = _compare("towenv/CompensatorGains-v0", _random_actions(12, 4, 2, seed=1), seed=11, kw=kw)
    lengths = {round(float(s.sim.system.l0.sum()), 6) for s in singles}
    assert len(lengths) >= 2, lengths
    venv.close()


def test_batched_winch_remesh_bit_for_bit():
    # copy 0 pays out flat out, copy 1 hauls in, copy 2 holds: only some copies remesh
    T = 60
    acts = np.zeros((T, 3, 1), np.float32)
    acts[:, 0] = 1.0
    acts[:, 1] = -1.0
    venv, singles, _ = _compare("towenv/WinchPayout-v0", acts, seed=0)
    counts = [s.sim.remesh_count for s in singles]
    vcounts = [e.sim.remesh_count for e in venv.unwrapped.envs]
    assert counts == vcounts and counts[0] > 0 and counts[1] > 0 and counts[2] == 0, counts
    nodes = [e.sim.system.n_nodes for e in venv.unwrapped.envs]
    assert len(set(nodes)) == 3, nodes           # three node counts in one typed List
    # the row's winch length is the deployed length of the remeshed line
    for e in venv.unwrapped.envs:
        assert e._last_m["winch_length"] == pytest.approx(e.sim.winch_state()["length"], abs=1e-9)
        _check_tension_ratio(e)
    venv.close()


def test_batched_failure_truncates_with_failure_info_and_autoresets():
    # an absurd time step without step cuts: the Newton iteration fails some seconds in
    kw = {"dt": 0.5, "control_hz": 2.0, "sim_overrides": {"max_step_cuts": 0}}
    acts = np.zeros((200, 2, 2), np.float32)
    venv, singles, infos = _compare("towenv/CompensatorGains-v0", acts, seed=0, kw=kw,
                                    reset_options={"eval_index": 0})
    last = infos[-1]
    failed = [i for i, inf in enumerate(last) if "failure" in inf]
    assert failed, "expected a numerical failure"
    for i in failed:
        assert last[i]["solver_failure"] and "numerical failure" in last[i]["failure"]
        assert venv.unwrapped._trunc[i] and not venv.unwrapped._term[i]
        assert np.isfinite(venv.unwrapped._obs[i]).all()
        # the simulator stopped at the last good step, and the reported time is that step's
        assert singles[i].sim.t == venv.unwrapped.envs[i].sim.t == last[i]["t"]
    # NEXT_STEP autoreset: the next step returns the reset observation, reward 0 and the reset info
    obs, rew, te, tr, info = venv.step(np.zeros((2, 2), np.float32))
    for i in failed:
        o, inf = singles[i].reset()
        np.testing.assert_array_equal(obs[i], o)
        assert rew[i] == 0.0 and not te[i] and not tr[i] and info["_sea_seed"][i]
        assert info["t"][i] == 0.0
    venv.close()


@pytest.mark.parametrize("mode", [AutoresetMode.SAME_STEP, AutoresetMode.DISABLED])
def test_autoreset_modes(mode):
    kw = {"episode_seconds": 0.5}                   # 5 control steps
    venv = gym.make_vec("towenv/WinchPayout-v0", num_envs=2, vectorization_mode="vector_entry_point",
                        autoreset_mode=mode, **kw)
    assert venv.metadata["autoreset_mode"] == AutoresetMode(mode)
    single = WinchPayoutEnv(**kw)
    venv.reset(seed=4)
    single.reset(seed=4)
    a = np.full((2, 1), 0.3, np.float32)
    for t in range(5):
        obs, rew, te, tr, info = venv.step(a)
        o, r, e, u, inf = single.step(a[0])
        assert rew[0] == r
    assert tr.all() and u
    if mode == AutoresetMode.SAME_STEP:
        np.testing.assert_array_equal(info["final_obs"][0], o)         # the last observation of the episode
        assert info["_final_obs"].all() and info["final_info"]["t"][0] == inf["t"]
        o2, _ = single.reset()
        np.testing.assert_array_equal(obs[0], o2)                        # the reset observation, at once
        obs, rew, te, tr, info = venv.step(a)                            # and the new episode runs on
        assert not (te | tr).any() and np.isfinite(obs).all()
    else:
        with pytest.raises(RuntimeError, match="reset_mask"):
            venv.step(a)
        obs, info = venv.reset(options={"reset_mask": np.array([True, False])})
        with pytest.raises(RuntimeError, match="sub-environment 1"):
            venv.step(a)
        venv.reset(options={"reset_mask": np.array([False, True])})
        obs, rew, te, tr, info = venv.step(a)
        assert not (te | tr).any()
    venv.close()


def test_parallel_prange_is_bit_identical_to_serial():
    acts = _random_actions(8, 3, 1, seed=5)
    a = gym.make_vec("towenv/WinchPayout-v0", num_envs=3, vectorization_mode="vector_entry_point")
    b = gym.make_vec("towenv/WinchPayout-v0", num_envs=3, vectorization_mode="vector_entry_point", parallel=True)
    assert b.unwrapped.rows.stepper.parallel
    oa, _ = a.reset(seed=1)
    ob, _ = b.reset(seed=1)
    for t in range(8):
        ra = a.step(acts[t])
        rb = b.step(acts[t])
        for x, y in zip(ra, rb):
            assert data_equivalence(x, y, exact=True)


def test_measurement_row_matches_simulator_api():
    """The compiled gather reads the simulator's arrays directly; it must agree with the public API
    (guards against changes of the state layout, e.g. the body attitude representation)."""
    for cls in (CompensatorGainsEnv, WinchPayoutEnv):
        env = cls()
        env.reset(seed=2)
        for _ in range(15):
            env.step(env.action_space.sample())
        sim, m = env.sim, env._last_m
        b = sim.body_state("fish")
        tp = sim.tow_point_state()
        assert m["t"] == pytest.approx(sim.t)
        assert m["fish_heave"] == pytest.approx(b["position"][2] - env._z_ref, abs=1e-12)
        assert m["fish_heave_rate"] == pytest.approx(b["velocity"][2], abs=1e-12)
        assert m["fish_pitch"] == pytest.approx(b["euler"][1], abs=1e-12)
        assert m["fish_pitch_rate"] == pytest.approx(b["omega"][1], abs=1e-12)
        assert m["tow_vel_z"] == pytest.approx(tp["velocity"][2], abs=1e-9)
        assert m["tow_acc_z"] == pytest.approx(tp["acceleration"][2], abs=1e-9)
        assert m["top_tension"] == pytest.approx(sim.top_tension, rel=1e-12)
        assert m["min_tension"] == sim.tensions.min()
        _check_tension_ratio(env)
        if cls is CompensatorGainsEnv:
            cs = sim.compensator_state()
            assert m["comp_stroke"] == pytest.approx(cs["stroke"] / env._half_stroke, abs=1e-12)
            assert m["comp_stroke_vel"] == pytest.approx(cs["stroke_velocity"], abs=1e-9)
            assert (m["comp_stiffness"], m["comp_damping"]) == (cs["stiffness"], cs["damping"])
        else:
            ws = sim.winch_state()
            assert m["winch_speed"] == pytest.approx(ws["speed"] / env.winch_max_speed, abs=1e-15)
            assert m["winch_length"] == pytest.approx(ws["length"], abs=1e-9)


def test_single_env_matches_simulator_advance_to_round_off():
    """The environments step through the compiled stepper (phase-recurrence tow points); the physics
    must be that of ``Simulator.advance_steps`` to round-off."""
    env = CompensatorGainsEnv()
    env.reset(seed=0, options={"eval_index": 4})
    ref = CompensatorGainsEnv()
    ref.reset(seed=0, options={"eval_index": 4})
    a = np.array([0.2, -0.4], np.float32)
    for _ in range(100):
        env.step(a)
        k, b = ref.gains(a)
        ref.sim.set_compensator(stiffness=k, damping=b)
        ref.sim.advance_steps(ref.substeps)
    # after 20 s of coupled nonlinear dynamics, positions agree to micrometres (round-off in the tow-point
    # path amplified by the Newton tolerances of 0.5 N / 1e-5 relative)
    np.testing.assert_allclose(env.sim.positions, ref.sim.positions, rtol=0, atol=1e-6)


def test_tow_point_phase_recurrence_matches_exact_path():
    env = WinchPayoutEnv()
    env.reset(seed=0, options={"eval_index": 8})                    # code 5: the largest motions
    sim = env.sim
    buf = ST.TowPointBuffer(sim)
    assert buf._linear(0.0, 1.0) is not None                         # the fast path is really used
    for first in (0, 5, 128, 1000, 6000, 60_000):                   # up to 3000 s
        got = buf.block(first, 300)
        exact = sim.path.position((first + np.arange(300)) * sim.dt)
        # 128 complex multiplications of |E| ≤ amplitude: error ~ 128·eps·Σ|a G| ≪ 1e-9 m
        assert np.abs(got - exact).max() < 1e-9
        # chunking independence (recurrence restarted at every aligned block)
        np.testing.assert_array_equal(buf.block(first + 7, 100), got[7:107])


def test_pickled_env_continues_identically():
    env = WinchPayoutEnv(sensor_noise={"fish_heave_dev": 0.1})
    env.reset(seed=3)
    acts = _random_actions(40, 1, 1, seed=2)[:, 0]
    for a in acts[:20]:
        env.step(a)
    clone = pickle.loads(pickle.dumps(env))
    for a in acts[20:]:
        r1, r2 = env.step(a), clone.step(a)
        assert data_equivalence(r1, r2, exact=True)


def test_sb3_adapter_and_ppo_learns():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor
    from towenv.envs.sb3 import TowSB3VecEnv
    ve = TowSB3VecEnv("towenv/CompensatorGains-v0", 3, seed=0, episode_seconds=2.0)     # 20 steps
    o = ve.reset()
    assert o.shape == (3, CompensatorGainsEnv(episode_seconds=2.0).observation_space.shape[0]) and o.dtype == np.float32
    single = CompensatorGainsEnv(episode_seconds=2.0)
    so, _ = single.reset(seed=1)
    np.testing.assert_array_equal(o[1], so)                          # copy i seeded with seed + i
    for k in range(22):
        acts = np.full((3, 2), 0.1 * (k % 3), np.float32)
        o, r, d, infos = ve.step(acts)
        if k <= 19:                          # the single env's episode ends at k = 19 (then step raises)
            so, sr, *_ = single.step(acts[1])
        assert r.dtype == np.float32 and np.isfinite(o).all() and len(infos) == 3
        if k == 19:
            assert d.all() and all(i["TimeLimit.truncated"] and "terminal_observation" in i for i in infos)
            np.testing.assert_array_equal(infos[1]["terminal_observation"], so)
            assert np.float32(sr) == r[1]
        else:
            assert not d.any()
            if k < 19:
                np.testing.assert_array_equal(o[1], so)
    ve.close()
    ve = VecMonitor(TowSB3VecEnv("towenv/WinchPayout-v0", 4, seed=0, episode_seconds=3.0))
    model = PPO("MlpPolicy", ve, n_steps=64, batch_size=64, n_epochs=1, seed=0, device="cpu")
    model.learn(512)
    assert model.num_timesteps >= 512
    ve.close()


def test_registration_vector_entry_point():
    for env_id in IDS:
        spec = gym.spec(env_id)
        assert spec.vector_entry_point.startswith("towenv.envs.vector:")
        venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
        assert venv.num_envs == 2 and venv.single_action_space == CLASSES[env_id]().action_space
        venv.close()


def test_stepper_input_errors():
    with pytest.raises(ValueError, match="num_copies"):
        ST.BatchStepper(0)
    env = CompensatorGainsEnv()
    with pytest.raises(ValueError, match="n must be in"):
        env._rows.stepper.step(ST.BLOCK + 1, ST.ACT_NONE)
    st = ST.BatchStepper(2)
    st.set_copy(0, env.sim, "fish", env._tension_layout(env.sim)[0])
    with pytest.raises(RuntimeError, match="set_copy"):
        st.step(1, ST.ACT_NONE)
    other = CompensatorGainsEnv(dt=0.025, control_hz=20.0)
    with pytest.raises(ValueError, match="same physics step"):
        st.set_copy(1, other.sim, "fish", other._tension_layout(other.sim)[0])
    assert math.isfinite(env._rows.stepper.M[0, MS.M_TOP_T])


class _PlainReward:
    """A reward function with only the dict protocol (no compiled ``batch``)."""

    def __call__(self, m, action, prev_action):
        c = {"depth": (m["fish_depth"] - 40.0) ** 2, "act": float(np.sum(np.square(action - prev_action)))}
        return -sum(c.values()), c

    def terminal_cost(self, steps_left):
        return 1.0


class _PlainObserver:
    """An observer with only the dict protocol (no ``measure_rows``)."""

    def __init__(self):
        self.low = np.array([-100.0, -1.0], np.float32)
        self.high = np.array([100.0, 1.0], np.float32)

    def reset(self, m, rng):
        return self(m, rng)

    def __call__(self, m, rng):
        return np.clip(np.array([m["fish_heave"], m["last_action"][0]], np.float32), self.low, self.high)


def test_swapped_pieces_use_the_dict_path_bit_for_bit():
    kw = {"reward_fn": _PlainReward(), "observation_fn": _PlainObserver()}
    venv, singles, infos = _compare("towenv/WinchPayout-v0", _random_actions(10, 2, 1, seed=7), seed=1, kw=kw)
    assert set(infos[-1][0]["reward_components"]) == {"depth", "act"}
    assert venv.single_observation_space.shape == (2,)
    venv.close()


def test_parallel_kernel_has_its_own_cache_entry():
    # numba's disk cache is keyed by qualified name + line: the serial and the prange kernel must not be the
    # same function, or the "parallel" dispatcher silently loads the serial machine code from the cache
    assert ST._step_batch_parallel.py_func.__qualname__ != ST._step_batch.py_func.__qualname__
    assert ST._step_batch_parallel.targetoptions.get("parallel")
    assert not ST._step_batch.targetoptions.get("parallel")
