"""The causal predictor of feature set v2q (agents/predictor.py): fitted on its own wave seeds, it predicts the
along-cable motion ahead better than persistence, round-trips through its file, and bad settings are refused."""
from __future__ import annotations

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import towenv  # noqa: E402,F401
from agents import predictor as P  # noqa: E402


def test_fit_on_short_episodes_beats_persistence_and_round_trips(tmp_path, capsys):
    """Two 100 s episodes of one entry (one fitted, one held out): the held-out R² at +0.2 s is near 1 and every
    channel's R² at +1.0 s is above what "no change" (the current value) would give — the autocorrelation at
    1 s of a wave-driven motion with Tp 5.9 s is far below 1; the file written by the CLI loads equal."""
    pred = P.fit_predictor(replicates=2, episode_seconds=100.0, discard=60.0, entries=[4], log=print)
    out = capsys.readouterr().out
    assert "held-out R²" in out and list(pred.W) == ["hs1.88_tp5.90"]
    r2 = np.array(pred.meta["r2_heldout"]["hs1.88_tp5.90"])            # (3 channels, 10 leads)
    assert r2.shape == (3, len(P.LEADS)) and np.all(r2[:, 0] > 0.99)
    sea, base = gym.make("towenv/WinchPayout-v0").unwrapped.eval_sea_states()[4]
    X = P.record_channels([sea], [P.predictor_seed(base, 1)], P.PRED_CHANNELS[:3], episode_seconds=100.0)[600:, 0]
    persistence = [1 - np.mean((x[10:] - x[:-10]) ** 2) / np.var(x[10:]) for x in X.T]
    assert np.all(r2[:, P.LEADS.index(10)] > np.array(persistence) + 0.2), (r2[:, 4], persistence)
    f = pred.save(tmp_path / "p.npz")
    back = P.Predictor.load(f)
    assert np.array_equal(back.W["hs1.88_tp5.90"], pred.W["hs1.88_tp5.90"]) and back.meta == pred.meta
    with pytest.raises(ValueError, match="not a predictor file"):
        P.Predictor.load(tmp_path / "missing.npz")


def test_compensator_predictor_fits_the_vertical_motion_and_beats_persistence():
    """The compensator's predictor (feature set hq): the MRU's vertical channels, all three predicted; held-out R² at
    +0.2 s near 1 and at +1.0 s above persistence, as the along-cable one; an unknown environment is refused."""
    pred = P.fit_predictor(replicates=2, episode_seconds=100.0, discard=60.0, entries=[4], log=lambda *_: None,
                           env_id="towenv/CompensatorGains-v0")
    assert pred.channels == P.COMP_PRED_CHANNELS and pred.meta["env_id"] == "towenv/CompensatorGains-v0"
    assert pred.feature_names()[0] == "tow_vel_z@+0.2s(pred)" and len(pred.feature_names()) == 30
    r2 = np.array(pred.meta["r2_heldout"]["hs1.88_tp5.90"])
    assert r2.shape == (3, len(P.LEADS)) and np.all(r2[:, 0] > 0.99)
    sea, base = gym.make("towenv/CompensatorGains-v0").unwrapped.eval_sea_states()[4]
    X = P.record_compensator_channels([sea], [P.predictor_seed(base, 1)], P.COMP_PRED_CHANNELS,
                                      episode_seconds=100.0)[600:, 0]
    persistence = [1 - np.mean((x[10:] - x[:-10]) ** 2) / np.var(x[10:]) for x in X.T]
    assert np.all(r2[:, P.LEADS.index(10)] > np.array(persistence) + 0.2), (r2[:, 4], persistence)
    with pytest.raises(ValueError, match="env_id"):
        P.fit_predictor(entries=[4], env_id="towenv/Pendulum")
    with pytest.raises(ValueError, match="channels"):
        P.Predictor(pred.W, pred.scales, {"channels": ["tow_vel_z", "tow_heave", "tow_acc_z"]})


@pytest.mark.parametrize("kw, field", [({"replicates": 1}, "replicates"), ({"replicates": 11}, "replicates"),
                                       ({"ridge": 0.0}, "ridge"), ({"episode_seconds": 70.0}, "episode_seconds")])
def test_bad_settings_are_refused_naming_the_field(kw, field):
    with pytest.raises(ValueError, match=field):
        P.fit_predictor(**({"entries": [4]} | kw))


def test_closed_loop_script_measures_the_predictor_under_a_v2q_policy(capsys):
    """scripts/predictor_closed_loop.py: under the committed gnq policy (its own payout, so its own cable angle) the
    predicted along-cable motion 1 s ahead still matches what follows (R² ≥ 0.9, as under the along-cable law it was
    fitted on: ≥ 0.98); a policy without a predictor is refused with exit 2."""
    from pathlib import Path

    from agents import ars
    from helpers import load_script
    script = load_script("predictor_closed_loop")
    trained = Path(ars.__file__).parent / "trained"
    res = script.closed_loop_r2(trained / "gnq_WinchPayout-v0_s1.npz", replicates=(9,), episode_seconds=80.0)
    assert set(res) == {4, 5}
    for row in res.values():
        assert all(r1 >= 0.9 for r1, _r2 in row.values()), row
    with pytest.raises(SystemExit) as ex:
        script.main([str(trained / "gn5_WinchPayout-v0_s0.npz"), "--episode-seconds", "80"])
    assert ex.value.code == 2 and "no predictor" in capsys.readouterr().err


def test_shared_predictor_is_the_one_all_v2q_policies_carry():
    """Policies carrying equal predictors share one (v2 policies carry none); different ones are refused."""
    from pathlib import Path
    from types import SimpleNamespace

    from agents import ars
    pred = P.Predictor.load(Path(ars.__file__).parent / "trained" / "predictor_WinchPayout-v0.npz")
    other = P.Predictor({k: w + 1e-3 for k, w in pred.W.items()}, pred.scales)
    same = P.Predictor(dict(pred.W), pred.scales)
    pols = [SimpleNamespace(predictor=pred), SimpleNamespace(predictor=same), SimpleNamespace(predictor=None)]
    assert P.shared_predictor(pols) is not None and P.shared_predictor(pols[2:]) is None
    with pytest.raises(ValueError, match="different predictors"):
        P.shared_predictor(pols + [SimpleNamespace(predictor=other)])


def test_design_is_the_gathered_lags_of_the_ring_and_a_constant():
    """The regressors are exactly ring[:, :, PRED_LAGS] flattened channel-major with a trailing 1 (the strided copy
    changes only the speed), for contiguous, strided (a column of a bigger array) and float32 rings; C-contiguous."""
    rng = np.random.default_rng(5)
    for shape in [(1, 7, P.RING), (5, 4, P.RING), (40, 7, P.RING)]:
        r = rng.standard_normal((shape[0], 3) + shape[1:])[:, 1]
        for ring in (r, np.ascontiguousarray(r), r.astype(np.float32)):
            X = P.Predictor.design(ring)
            want = np.concatenate([np.asarray(ring, float)[:, :, list(P.PRED_LAGS)].reshape(shape[0], -1),
                                   np.ones((shape[0], 1))], axis=1)
            assert X.dtype == np.float64 and X.flags.c_contiguous and np.array_equal(X, want)
