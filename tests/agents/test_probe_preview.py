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
