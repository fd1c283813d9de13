"""scripts/probe_preview_bound.py: the linear residual class with perfect preview of the tow point's along-cable
motion (feature set "v2p", registered only inside the probe's context)."""
from __future__ import annotations

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import towenv  # noqa: E402,F401
from agents import ars  # noqa: E402
from agents.baselines import load_tuned  # noqa: E402
from agents.common import reset_copies  # noqa: E402
from helpers import load_script  # noqa: E402

SECONDS = 64.0


def test_preview_features_are_the_future_of_the_along_cable_run_and_restored_after():
    """Inside the context the v2p features are v2's features (same values) plus the along-cable channels 0.2-2.0 s
    ahead — exactly what the same episode shows later under the along-cable law (a preview that did not see the
    future would fail); outside it, agents.ars has no v2p and its batch class and rollout are the originals."""
    from towenv.envs.vector import WinchPayoutVectorEnv
    probe = load_script("probe_preview_bound")
    plain = (ars.feature_names, ars._Batch, ars.rollout_series)
    table = dict(load_tuned()["along_cable"])
    env = gym.make(ars.ENV_ID)
    sea, seed = env.unwrapped.eval_sea_states()[9]
    env.close()
    with probe.preview_feature_set() as m:
        assert m is ars and ars.n_features("v2p") == ars.n_features("v2") + 30
        names = ars.feature_names("v2p")
        assert names[-1] == "const" and names[:-1][:ars.n_features("v2") - 1] == ars.feature_names("v2")[:-1]
        venv = WinchPayoutVectorEnv(num_envs=1, autoreset_mode="NextStep", batch_infos=True, episode_seconds=SECONDS)
        bp = ars._Batch(venv, table, dict(ars.FEATURE_SCALES), "v2p")
        bv = plain[1](venv, table, dict(ars.FEATURE_SCALES), "v2")
        ars.rollout_series(venv, bp, [sea], [seed], np.zeros((1, len(names))))   # records bp.fut, runs along_cable
        fut = bp.fut[:, 0]                                                     # (T, 3) scaled channels
        obs = reset_copies(venv, [sea], [seed])
        bp.set_seas([sea])
        bv.set_seas([sea])
        nv = ars.n_features("v2") - 1
        for k in range(venv.envs[0].max_steps):
            now = np.array([bv.ch(obs, c) / bv.scales[c] for c in ars.HISTORY_CHANNELS]).ravel()
            assert np.array_equal(now, fut[k])                      # the recording is this very episode
            phi_p = bp.features(obs, k == 0)[0]
            phi_v = bv.features(obs, k == 0)[0]
            assert np.array_equal(phi_p[:nv], phi_v[:-1]) and phi_p[-1] == 1.0
            lead = np.minimum(k + np.array(probe.LEADS), fut.shape[0] - 1)
            assert np.array_equal(phi_p[nv:-1], fut[lead].T.ravel())
            obs, *_ = venv.step(bv.base_action(obs).astype(np.float32)[:, None])
        venv.close()
    assert "v2p" not in ars.FEATURE_SETS and "v2p" not in ars.LONG_HISTORY
    assert (ars.feature_names, ars._Batch, ars.rollout_series) == plain


@pytest.mark.slow
def test_evaluate_scores_zero_residual_as_along_cable(tmp_path, capsys):
    """θ = 0 (v2) is the along-cable law: +0.0 % in both codes; a bad replicate count exits 2."""
    probe = load_script("probe_preview_bound")
    table = dict(load_tuned()["along_cable"])
    zero = ars.save_policy(ars.ARSPolicy({k: np.zeros(ars.n_features("v2")) for k in table}, table,
                                         feature_set="v2"), tmp_path / "zero.npz")
    assert probe.main(["evaluate", str(zero), "--replicates", "1", "--episode-seconds", "64"]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.strip().startswith(str(zero)))
    assert line.count("+0.0 %") == 4                                   # heave and pitch, codes 4 and 5
    with pytest.raises(SystemExit) as ex:
        probe.main(["evaluate", str(zero), "--replicates", "9"])
    assert ex.value.code == 2


def test_evaluate_refuses_a_policy_whose_features_it_cannot_see(tmp_path, capsys):
    """A v3 policy (own past actions, longer history) does not nest in v2p: refused with exit 2 naming the feature
    set, rather than evaluated with its extra weights silently dropped."""
    probe = load_script("probe_preview_bound")
    table = dict(load_tuned()["along_cable"])
    v3 = ars.save_policy(ars.ARSPolicy({k: np.full(ars.n_features("v3"), 0.01) for k in table}, table,
                                       feature_set="v3"), tmp_path / "v3.npz")
    with pytest.raises(SystemExit) as ex:
        probe.main(["evaluate", str(v3), "--replicates", "1", "--episode-seconds", "64"])
    assert ex.value.code == 2 and "'v3'" in capsys.readouterr().err
    assert "v2p" not in ars.FEATURE_SETS                       # the context was left cleanly


def test_theta_rows_places_weights_by_feature_name():
    """agents.ars.theta_rows: a v1 policy's weights land on the v1 names inside the v2 list (the v2-only columns stay
    0), each row the weights of its sea state; a v2 policy does not fit the v1 list (ValueError)."""
    table = dict(load_tuned()["along_cable"])
    rng = np.random.default_rng(3)
    pol = ars.ARSPolicy({k: rng.normal(size=ars.n_features("v1")) for k in table}, table, feature_set="v1")
    names2, names1 = ars.feature_names("v2"), ars.feature_names("v1")
    env = gym.make(ars.ENV_ID)
    seas = [sea for sea, _s in env.unwrapped.eval_sea_states()]
    env.close()
    from agents.common import nearest_key
    rows = ars.theta_rows(pol, seas, names2)
    assert rows.shape == (len(seas), len(names2))
    for e, sea in enumerate(seas):
        w = pol.theta[nearest_key(pol.theta, sea)]
        assert np.array_equal(rows[e, [names2.index(nm) for nm in names1]], w)
        assert not rows[e, [i for i, nm in enumerate(names2) if nm not in names1]].any()
    with pytest.raises(ValueError, match="feature set 'v2'"):
        ars.theta_rows(ars.ARSPolicy({k: np.zeros(ars.n_features("v2")) for k in table}, table, feature_set="v2"),
                       seas, names1)
