"""Weight averages of CompensatorGains policies (issue 14, agents.ars_compensator.average_policies,
scripts/average_compensator.py): the average's weights are its members' mean, so its log-gain residual is the mean
of theirs before the action clip; members of different classes are refused with the field named; the file keeps
what it averages, the report names it, and scripts/training_cost.py adds up its members' chains with their shared
start counted once."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from agents import ars_compensator as arc
from agents.evaluation import trained_description
from helpers import load_script

TRAINED = Path(arc.__file__).parent / "trained"


def _load(stem):
    return arc.load_policy(TRAINED / f"{stem}.npz")


def _members():
    return [_load("gnsp_CompensatorGains-v0_s0"), _load("gnsp_CompensatorGains-v0_s1")]


def test_average_is_the_mean_of_the_weights_and_of_the_residuals():
    a, b = _members()
    avg = arc.average_policies([a, b], seed=7)
    rng = np.random.default_rng(0)
    nf = arc.n_features("hs")
    for k in a.theta:
        np.testing.assert_array_equal(avg.theta[k], (a.theta[k] + b.theta[k]) / 2.0)
        phi = rng.normal(size=(5, nf))
        r = [arc._residual(np.repeat(p.theta[k][None], len(phi), axis=0), phi) for p in (a, b, avg)]
        np.testing.assert_allclose(r[2], (r[0] + r[1]) / 2.0, rtol=0, atol=1e-12)
    assert avg.feature_set == "hs" and avg.stop_guard == a.stop_guard and avg.base_table.keys() == a.base_table.keys()
    assert avg.meta["method"] == "weight-average" and avg.meta["seed"] == 7
    assert avg.meta["averaged_from"] == [a.name, b.name]
    assert [m["init"] for m in avg.meta["members"]] == ["gnp_CompensatorGains-v0_s0", "gnp_CompensatorGains-v0_s1"]
    # averaging the same weights changes nothing; the members are not touched
    copy = arc.ARSCompensatorPolicy(a.theta, a.base_table, a.scales, dict(a.meta), name="copy")
    same = arc.average_policies([a, copy], seed=0)
    assert all(np.array_equal(same.theta[k], a.theta[k]) for k in a.theta)
    assert not all(np.array_equal(a.theta[k], b.theta[k]) for k in a.theta)


def test_members_of_different_classes_are_refused_with_the_field_named():
    a, b = _members()
    with pytest.raises(ValueError, match="feature_set differs"):
        arc.average_policies([a, _load("gnp_CompensatorGains-v0_s1")], seed=0)
    guarded = arc.ARSCompensatorPolicy(b.theta, b.base_table, b.scales, dict(b.meta) | {"stop_guard": 0.5}, name="g")
    with pytest.raises(ValueError, match="stop_guard differs"):
        arc.average_policies([a, guarded], seed=0)
    other_keys = arc.ARSCompensatorPolicy({k: v for k, v in list(b.theta.items())[:-1]}, b.base_table, b.scales,
                                          dict(b.meta), name="k")
    with pytest.raises(ValueError, match="sea-state keys"):
        arc.average_policies([a, other_keys], seed=0)
    with pytest.raises(ValueError, match="at least 2"):
        arc.average_policies([a], seed=0)
    with pytest.raises(ValueError, match="appears twice"):
        arc.average_policies([a, a], seed=0)


def test_cli_writes_a_file_that_reports_and_costs_name_its_members(tmp_path, capsys):
    for stem in ("arsp_CompensatorGains-v0_s0", "gnp_CompensatorGains-v0_s0", "gnp_CompensatorGains-v0_s1",
                 "gnsp_CompensatorGains-v0_s0", "gnsp_CompensatorGains-v0_s1"):
        shutil.copy(TRAINED / f"{stem}.npz", tmp_path)
    out = tmp_path / "gnsm_CompensatorGains-v0_s0.npz"
    script = load_script("average_compensator")
    assert script.main(["--seed", "0", "--export", str(out), str(tmp_path / "gnsp_CompensatorGains-v0_s0.npz"),
                        str(tmp_path / "gnsp_CompensatorGains-v0_s1.npz")]) == 0
    assert "--search" not in capsys.readouterr().out      # members next to it: no note
    avg = arc.load_policy(out)
    assert avg.meta["averaged_from"] == ["gnsp_CompensatorGains-v0_s0", "gnsp_CompensatorGains-v0_s1"]
    desc = trained_description(avg.meta)
    assert desc.startswith("Mean of the weights of 2 policies") and "gnsp_CompensatorGains-v0_s1" in desc
    cost = load_script("training_cost")
    runs = cost.chain(out)
    assert [r[0] for r in runs] == ["arsp_CompensatorGains-v0_s0", "gnp_CompensatorGains-v0_s0",
                                    "gnsp_CompensatorGains-v0_s0", "gnp_CompensatorGains-v0_s1",
                                    "gnsp_CompensatorGains-v0_s1", "gnsm_CompensatorGains-v0_s0"]
    singles = [cost.chain(tmp_path / f"gnsp_CompensatorGains-v0_s{s}.npz") for s in (0, 1)]
    ars_steps = singles[0][0][2]
    assert sum(r[2] for r in runs) == sum(r[2] for c in singles for r in c) - ars_steps   # the start once
    (tmp_path / "gnp_CompensatorGains-v0_s1.npz").unlink()
    with pytest.raises(ValueError, match="not next to it"):
        cost.chain(out)
    with pytest.raises(SystemExit):
        script.main(["--seed", "0", "--export", str(tmp_path / "x.npz"), str(out)])
    assert "at least 2" in capsys.readouterr().err


@pytest.mark.parametrize("k", [0, 1, 2])
def test_committed_gnsm_is_the_mean_of_two_gnsp_chains_from_one_ars_start(k):
    """`gnsm` seed k (docs/agents.md "Averaging two chains within the hour") is the mean of the committed `gnsp`
    seeds 2k and 2k + 1, both the `gns` recipe (Gauss–Newton 6, then 4 gated) from `arsp` seed 0 with disjoint
    Gauss–Newton seeds; its cost chain holds the ARS start once and both chains."""
    avg = _load(f"gnsm_CompensatorGains-v0_s{k}")
    members = [_load(f"gnsp_CompensatorGains-v0_s{s}") for s in (2 * k, 2 * k + 1)]
    assert avg.meta["averaged_from"] == [m.name for m in members] and avg.meta["seed"] == k
    for k_sea in avg.theta:
        np.testing.assert_array_equal(avg.theta[k_sea], (members[0].theta[k_sea] + members[1].theta[k_sea]) / 2.0)
    for m in members:
        gn = _load(m.meta["hyperparameters"]["init"])
        assert (m.meta["first_iteration"], m.meta["iterations"], m.feature_set) == (6, 4, "hs")
        assert gn.meta["iterations"] == 6 and gn.meta["hyperparameters"]["init"] == "arsp_CompensatorGains-v0_s0"
        assert m.meta["parallel"] is True and gn.meta["parallel"] is True
    assert members[0].meta["seed"] != members[1].meta["seed"]
    runs = load_script("training_cost").chain(TRAINED / f"gnsm_CompensatorGains-v0_s{k}.npz")
    assert [r[0] for r in runs][0] == "arsp_CompensatorGains-v0_s0" and len(runs) == 6


def test_an_average_cannot_take_a_members_name_or_list_itself(tmp_path, capsys):
    """The CLI refuses an --export with a member's name (it would overwrite the member); training_cost refuses an
    average that lists itself (a file renamed over a member) instead of recursing without end."""
    for stem in ("gnsp_CompensatorGains-v0_s0", "gnsp_CompensatorGains-v0_s1"):
        shutil.copy(TRAINED / f"{stem}.npz", tmp_path)
    member = tmp_path / "gnsp_CompensatorGains-v0_s0.npz"
    before = member.read_bytes()
    script = load_script("average_compensator")
    with pytest.raises(SystemExit):
        script.main(["--seed", "0", "--export", str(member), str(member),
                     str(tmp_path / "gnsp_CompensatorGains-v0_s1.npz")])
    assert "has the name of a member" in capsys.readouterr().err and member.read_bytes() == before
    avg = arc.average_policies(_members(), seed=0)
    avg.meta["averaged_from"] = ["loop_s0", "gnsp_CompensatorGains-v0_s1"]
    arc.save_policy(avg, tmp_path / "loop_s0.npz")
    with pytest.raises(ValueError, match="lists itself"):
        load_script("training_cost").chain(tmp_path / "loop_s0.npz")


def test_members_with_a_predictor_average_when_their_predictors_are_equal(tmp_path):
    """The predicted-preview policies (feature set hq) average like the others when they store the same predictor:
    the average keeps it, its weights are the members' mean and it survives its file; a member whose predictor
    differs (here one weight changed) is refused with the field named."""
    a, b = _load("gnq_CompensatorGains-v0_s0"), _load("gnq_CompensatorGains-v0_s1")
    assert a.predictor is not None
    avg = arc.average_policies([a, b], seed=3)
    assert avg.predictor is a.predictor and avg.feature_set == "hq"
    for k in a.theta:
        np.testing.assert_array_equal(avg.theta[k], (a.theta[k] + b.theta[k]) / 2.0)
    back = arc.load_policy(arc.save_policy(avg, tmp_path / "avg.npz"))
    assert arc._predictor_digest(back) == arc._predictor_digest(a)
    from agents.predictor import Predictor
    w = {k: v.copy() for k, v in b.predictor.W.items()}
    key = sorted(w)[0]
    w[key].flat[0] += 1e-6
    other = arc.ARSCompensatorPolicy(b.theta, b.base_table, b.scales, dict(b.meta), name="other",
                                     predictor=Predictor(w, b.predictor.scales, b.predictor.meta))
    with pytest.raises(ValueError, match="predictor"):
        arc.average_policies([a, other], seed=0)
    with pytest.raises(ValueError, match="feature_set differs"):
        arc.average_policies([a, _load("gnsp_CompensatorGains-v0_s0")], seed=0)


def test_cli_default_output_goes_under_runs_in_the_current_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    script = load_script("average_compensator")
    assert script.main(["--seed", "5", str(TRAINED / "gnsp_CompensatorGains-v0_s0.npz"),
                        str(TRAINED / "gnsp_CompensatorGains-v0_s1.npz")]) == 0
    out = tmp_path / "runs" / "average_CompensatorGains-v0_s5.npz"
    assert out.is_file() and arc.load_policy(out).meta["seed"] == 5
    printed = capsys.readouterr().out
    assert str(Path("runs") / "average_CompensatorGains-v0_s5.npz") in printed
    assert f"training_cost.py adds up its cost with --search {TRAINED}" in printed   # the members lie in agents/trained
    cost = load_script("training_cost")
    with pytest.raises(SystemExit) as ex:                               # not next to it: refused, naming --search
        cost.main([str(out)])
    assert ex.value.code == 2 and "--search" in capsys.readouterr().err
    assert cost.main([str(out), "--search", str(TRAINED)]) == 0        # the command the note gives
    line = capsys.readouterr().out
    assert "gnsp_CompensatorGains-v0_s0" in line and "gnsp_CompensatorGains-v0_s1" in line
