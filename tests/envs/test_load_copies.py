"""TowVectorEnv.load_copies: a copy loaded from another continues as that copy would, bit for bit.

The shared warm-up of agents.gn_compensator runs the first minute of each training episode once and branches it
into many copies with load_copies; the Jacobian it takes is only what it claims if a loaded copy is the source's
continuation exactly. The copies below are driven apart first (other actions: other running means, previous
actions, observer delay ring, sensor-noise draws, Newton memory), so a piece of state the load missed would show.
"""
from __future__ import annotations

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import towenv.envs  # noqa: E402,F401  (registers the ids)
from towenv.envs import checks as C  # noqa: E402
from towenv.envs.vector import CompensatorGainsVectorEnv, WinchPayoutVectorEnv  # noqa: E402

# sensor noise (drawn from each copy's np_random), an observation delay ring, the MRU delay buffer
KW = {"sensor_noise": {"fish_heave_dev": 0.05, "top_tension": 0.02}, "obs_delay": 2, "mru_delay": 0.3}


def _sea():
    e = gym.make("towenv/CompensatorGains-v0").unwrapped
    return e.eval_sea_states()[4]


def _reset(venv, sea, wseed, seeds):
    return venv.reset(seed=list(seeds), options={"sea_state": sea, "sea_seed": wseed})


def _rows(out, i):
    obs, rew, term, trunc, info = out
    return obs[i], rew[i], term[i], trunc[i], {k: v[i] for k, v in info.items() if isinstance(v, np.ndarray)}


def _equal(a, b):
    (oa, ra, ta, ua, ia), (ob, rb, tb, ub, ib) = a, b
    assert np.array_equal(oa, ob) and ra == rb and ta == tb and ua == ub
    assert ia.keys() == ib.keys()
    for k in ia:
        assert np.array_equal(ia[k], ib[k], equal_nan=True), k


def test_a_loaded_copy_continues_as_its_source_and_as_an_uninterrupted_run_bit_for_bit():
    sea, wseed = _sea()
    rng = np.random.default_rng(3)
    warm, cont = 25, 40
    a_src = rng.uniform(-1, 1, (warm + cont, 2)).astype(np.float32)
    a_other = rng.uniform(-1, 1, (warm, 2)).astype(np.float32)
    # the reference: one copy run without interruption
    ref = CompensatorGainsVectorEnv(num_envs=1, **KW)
    _reset(ref, sea, wseed, [7])
    ref_out = [ref.step(a_src[k][None]) for k in range(warm + cont)]
    # copy 0 runs the same episode; copy 1 the same sea but other actions and another reset seed (other noise)
    venv = CompensatorGainsVectorEnv(num_envs=3, **KW)
    _reset(venv, sea, wseed, [7, 8, 9])
    for k in range(warm):
        out = venv.step(np.stack([a_src[k], a_other[k], a_other[k]]))
    before = [_rows(out, 0), _rows(out, 1)]
    assert not np.array_equal(before[0][0], before[1][0])          # driven apart
    venv.load_copies(venv, [0], [1])
    for k in range(warm, warm + cont):
        out = venv.step(np.stack([a_src[k], a_src[k], a_other[0]]))
        _equal(_rows(out, 0), _rows(out, 1))
        _equal(_rows(out, 1), _rows(ref_out[k], 0))
    ref.close()
    venv.close()


def test_copies_loaded_from_another_vector_env_branch_its_state():
    sea, wseed = _sea()
    rng = np.random.default_rng(5)
    warm, cont = 20, 30
    a = rng.uniform(-1, 1, (warm + cont, 2)).astype(np.float32)
    b = rng.uniform(-1, 1, (cont, 2)).astype(np.float32)
    ref = CompensatorGainsVectorEnv(num_envs=2, **KW)                 # both copies from the start
    _reset(ref, sea, wseed, [4, 4])
    ref_out = []
    for k in range(warm + cont):
        second = a[k] if k < warm else b[k - warm]
        ref_out.append(ref.step(np.stack([a[k], second])))
    src = CompensatorGainsVectorEnv(num_envs=1, **KW)                 # the warm-up, once
    _reset(src, sea, wseed, [4])
    for k in range(warm):
        src.step(a[k][None])
    dst = CompensatorGainsVectorEnv(num_envs=2, **KW)
    _reset(dst, sea, wseed, [11, 12])
    dst.load_copies(src, [0, 0], [0, 1])
    for k in range(warm, warm + cont):
        out = dst.step(np.stack([a[k], b[k - warm]]))
        for i in range(2):
            _equal(_rows(out, i), _rows(ref_out[k], i))
    for v in (ref, src, dst):
        v.close()


def test_load_copies_refuses_other_seas_winch_copies_and_bad_indices():
    sea, wseed = _sea()
    venv = CompensatorGainsVectorEnv(num_envs=2)
    venv.reset(seed=[1, 2], options={"sea_state": sea, "sea_seed": wseed})
    venv.reset(seed=[3, 3], options={"sea_state": sea, "sea_seed": wseed + 1, "reset_mask": np.array([False, True])})
    with pytest.raises(C.ConfigError, match="same sea state, wave seed"):
        venv.load_copies(venv, [0], [1])
    with pytest.raises(C.ConfigError, match="same length"):
        venv.load_copies(venv, [0, 1], [1])
    with pytest.raises(C.ConfigError, match=r"dst entries must be in 0\.\.1"):
        venv.load_copies(venv, [0], [2])
    other = CompensatorGainsVectorEnv(num_envs=2)
    with pytest.raises(C.ResetNeeded):
        other.load_copies(venv, [0], [1])
    w = WinchPayoutVectorEnv(num_envs=2)
    w.reset(seed=[1, 1], options={"sea_state": sea, "sea_seed": wseed})
    with pytest.raises(C.ConfigError, match="winch"):
        w.load_copies(w, [0], [1])
    with pytest.raises(C.ConfigError, match="must be a CompensatorGainsVectorEnv"):
        venv.load_copies(w, [0], [1])
    for v in (venv, other, w):
        v.close()
