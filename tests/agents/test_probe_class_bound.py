"""scripts/probe_class_bound.py: the in-sample bound of the WinchPayout linear residual class — its search draws every
episode from the evaluation set's codes 4-5 entries (wave seeds +0 and +100), and its file never goes to agents/."""
from __future__ import annotations

from pathlib import Path

import numpy as np

import pytest

gym = pytest.importorskip("gymnasium")

import towenv  # noqa: E402,F401
from agents import ars, gn  # noqa: E402
from agents.evaluate import episode_seeds  # noqa: E402
from helpers import load_script  # noqa: E402

INIT = Path(ars.__file__).parent / "trained" / "gnqp2_WinchPayout-v0_s1.npz"


def _eval_bases():
    ev = gym.make(ars.ENV_ID).unwrapped.eval_sea_states()
    return [s for _sea, s in ev]


def test_search_episodes_are_exactly_the_scored_evaluation_episodes(tmp_path, monkeypatch):
    """Every Jacobian and line-search seed the patched search asks for is an evaluation-set seed of entries 4-11
    (replicates +0, +100), all 16 of them are used, and the file says it is a probe. A mapping that fell back to the search's own training seeds would fail the first assertion."""
    probe = load_script("probe_class_bound")
    bases = _eval_bases()
    asked = []

    def fake_train(seed, iterations, minutes, replicates, ridges, pitch_weight, feature_set, entries, init,
                   episode_seconds, wave_seed):
        assert (replicates, list(entries), feature_set, pitch_weight) == (2, list(range(4, 12)), "v2q", 0.1)
        # the fitted episodes are the scored ones whole: the evaluation's length (the environment's default)
        assert episode_seconds == gym.make(ars.ENV_ID).unwrapped.episode_seconds == 300.0
        for i in entries:                       # as agents/gn.py asks: base seed + 10·replicate, both searches
            for r in range(replicates):
                for ls in (False, True):
                    asked.append(wave_seed(bases[i] + 10 * r, 52, seed, ls))
        return init

    monkeypatch.setattr(gn, "train", fake_train)
    out = tmp_path / "fit.npz"
    assert probe.main(["--init", str(INIT), "--export", str(out)]) == 0
    assert set(asked) == set(episode_seeds([bases[i] for i in range(4, 12)], "eval", 2))
    assert len(set(asked)) == 16
    assert "not a policy" in ars.load_ars_policy(out).meta["probe"]


def test_refuses_agents_dir_bad_iterations_and_non_v2q_init(tmp_path, capsys):
    probe = load_script("probe_class_bound")
    agents_dir = Path(ars.__file__).parent / "trained" / "probe.npz"
    for argv, word in ((["--init", str(INIT), "--export", str(agents_dir)], "agents/"),
                       (["--init", str(INIT), "--export", str(tmp_path / "x.npz"), "--iterations", "0"], "--iterations"),
                       (["--init", str(INIT.with_name("gn5_WinchPayout-v0_s1.npz")), "--export",
                         str(tmp_path / "x.npz")], "v2q")):
        with pytest.raises(SystemExit) as ex:
            probe.main(argv)
        assert ex.value.code == 2 and word in capsys.readouterr().err
    with pytest.raises(ValueError, match="replicate"):
        probe.eval_seed(4000 + 20)


def test_features_v2qa_fits_the_richer_class_from_a_v2q_start(tmp_path, monkeypatch):
    """``--features v2qa`` hands the search the richer class (v2q + acceleration hinges) with the v2q start; the
    exported file is of that class."""
    probe = load_script("probe_class_bound")
    seen = {}

    def fake_train(seed, iterations, minutes, replicates, ridges, pitch_weight, feature_set, entries, init,
                   episode_seconds, wave_seed):
        seen["fs"], seen["init_fs"] = feature_set, init.feature_set
        th = {k: np.concatenate([v[:-1], np.zeros(ars.n_features("v2qa") - len(v)), v[-1:]])
              for k, v in init.theta.items()}
        return ars.ARSPolicy(th, init.base_table, meta=dict(init.meta), feature_set="v2qa", predictor=init.predictor)

    monkeypatch.setattr(gn, "train", fake_train)
    out = tmp_path / "fit.npz"
    assert probe.main(["--init", str(INIT), "--features", "v2qa", "--export", str(out)]) == 0
    assert seen == {"fs": "v2qa", "init_fs": "v2q"}
    assert ars.load_ars_policy(out).feature_set == "v2qa"
