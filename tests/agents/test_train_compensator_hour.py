"""scripts/train_compensator_hour.py, the CompensatorGains one-hour recipe in one command (issue 14; docs/agents.md
"The headline's stages within the hour"): its four stages are the committed ``gnw…`` files' recipes, stage 4 gets
what the hour leaves (at most 12 min) and is not started when the hour is spent, the chain ends with the mean of
the last half of stages 3-4's iterates (stage 3's alone without stage 4), bad options are refused by name."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from agents import ars_compensator as arc
from helpers import load_script

TRAINED = Path(arc.__file__).parent / "trained"


def _options(args):
    """``--name value…`` pairs of a command line as {name: [values]} (flags map to [])."""
    out, key = {}, None
    for tok in args:
        if tok.startswith("--"):
            key = tok[2:]
            out[key] = []
        else:
            out[key].append(tok)
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_stages_are_the_committed_chains_recipes(seed, tmp_path):
    hour = load_script("train_compensator_hour")
    start = TRAINED / "arsp_CompensatorGains-v0_s0.npz"
    for k, family in enumerate(["gnw", "gnws", "gnwsf", "gnwsfo"]):
        meta = arc.load_policy(TRAINED / f"{family}_CompensatorGains-v0_s{seed}.npz").meta
        hp = meta["hyperparameters"]
        opt = _options(hour.stage_args(seed, k, 7.5, start, tmp_path))
        assert int(opt["seed"][0]) == meta["seed"] == seed
        assert int(opt["iterations"][0]) == hp["iterations"] and int(opt["replicates"][0]) == hp["replicates"]
        assert [float(r) for r in opt["ridges"]] == hp["ridges"]
        assert "parallel" in opt and meta["parallel"] is True and "shared-warmup" in opt and hp["shared_warmup"]
        assert opt.get("features", [meta["feature_set"]])[0] == meta["feature_set"]
        assert opt.get("free", ["all"])[0] == hp["free"]
        assert Path(opt["init"][0]).stem == hp["init"]
        assert opt["export"][0] == str(tmp_path / f"{family}_CompensatorGains-v0_s{seed}.npz")
        if k < 3:     # capped stages: their own cap; stage 4: the budget handed in
            assert hour.STAGES[k][2] == hp["minutes"]
        else:
            assert float(opt["minutes"][0]) == 7.5
        assert ("save-iterates" in opt) == (k in (2, 3))     # the averaged stages write their iterates
        assert not set(opt) - {"seed", "iterations", "minutes", "replicates", "ridges", "parallel", "shared-warmup",
                               "features", "free", "init", "export", "save-iterates"}


def test_the_last_stage_gets_what_the_hour_leaves(monkeypatch, tmp_path, capsys):
    """Stages that 'take' 15 min each leave stage 4 57.5 - start - 45 min; 16 min each leave less than a minute, and
    stage 4 is not started (exit 1)."""
    hour = load_script("train_compensator_hour")
    import agents.gn_compensator as gnc
    start = TRAINED / "arsp_CompensatorGains-v0_s0.npz"
    spent = hour.start_minutes(start)
    assert 9.0 < spent < 9.6              # the committed ARS start: 55 iterations, 9.3 min on both cores

    import shutil
    averaged = []
    real_script = hour._script
    monkeypatch.setattr(hour, "_script", lambda name: type("Fake", (), {"main": staticmethod(
        lambda argv: averaged.append(argv) or 0)}) if name == "average_compensator" else real_script(name))
    for per_stage, expect_calls in ((15.0, 4), (16.0, 3)):
        clock, calls = [0.0], []

        def fake_stage(argv, clock=clock, calls=calls, per_stage=per_stage):
            calls.append(_options(argv))        # "trains" by copying the committed seed-0 file of its family
            out = Path(calls[-1]["export"][0])
            shutil.copy(TRAINED / f"{out.stem.split('_')[0]}_CompensatorGains-v0_s0.npz", out)
            clock[0] += per_stage * 60.0
            return 0

        monkeypatch.setattr(gnc, "main", fake_stage)
        monkeypatch.setattr(hour.time, "monotonic", lambda clock=clock: clock[0])
        rc = hour.main(["--seed", "0", "--start", str(start), "--out-dir", str(tmp_path)])
        assert len(calls) == expect_calls and rc == 0
        assert [float(c["minutes"][0]) for c in calls[:3]] == [90.0, 62.0, 22.0]
        if expect_calls == 4:
            assert float(calls[3]["minutes"][0]) == pytest.approx(min(12.0, 57.5 - spent - 45.0), abs=0.006)
            # then the tail average: seed 0's 8 fish-gated + 5 outward iterates -> the last 7 (iterations 16-22)
            assert averaged[-1][:6] == ["--seed", "0", "--features", "hsfo", "--export",
                                        str(tmp_path / "gnwt_CompensatorGains-v0_s0.npz")]
            assert averaged[-1][6:] == ([str(tmp_path / f"gnwsf_CompensatorGains-v0_s0_it{i}.npz") for i in (16, 17)]
                                        + [str(tmp_path / f"gnwsfo_CompensatorGains-v0_s0_it{i}.npz")
                                           for i in range(18, 23)])
        else:       # stage 4 not started: the chain still ends with the tail mean, of stage 3's iterates alone
            assert "gnwsfo not started" in capsys.readouterr().out and len(averaged) == 2
            assert averaged[-1][6:] == [str(tmp_path / f"gnwsf_CompensatorGains-v0_s0_it{i}.npz")
                                        for i in (14, 15, 16, 17)]
    assert hour.last_budget(9.3, 20.0) == 12.0 and hour.last_budget(9.3, 40.0) == pytest.approx(8.2)
    assert [hour.tail_count(n) for n in (9, 10, 11, 13)] == [5, 5, 6, 7]


@pytest.mark.parametrize("argv, field", [(["--seed", "-1"], "--seed"), (["--hour", "nan"], "--hour"),
                                         (["--hour", "5"], "--hour"), (["--start", "missing.npz"], "--start")])
def test_bad_options_are_refused_by_name(argv, field, capsys):
    hour = load_script("train_compensator_hour")
    with pytest.raises(SystemExit) as e:
        hour.main(argv + ["--dry-run"])
    assert e.value.code == 2 and field in capsys.readouterr().err


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_committed_tail_averages_are_the_chains_last_half(seed):
    """``gnwt`` seed k (docs/agents.md "A steadier end: the mean of the chain's last iterates") is the mean of the last
    ceil(n/2) of the committed ``gnw`` chain's n fish-gated and outward-gated iterates, written in hsfo: the members
    the script would pick from the committed stage files, each stage's last iterate bit-identical to its stage file."""
    hour = load_script("train_compensator_hour")
    args = hour.average_args(seed, TRAINED)
    opt = _options(args[:6])
    assert opt["features"] == ["hsfo"] and Path(opt["export"][0]).name == f"gnwt_CompensatorGains-v0_s{seed}.npz"
    avg = arc.load_policy(TRAINED / f"gnwt_CompensatorGains-v0_s{seed}.npz")
    members = [arc.load_policy(p) for p in args[6:]]
    n = sum(arc.load_policy(TRAINED / f"{f}_CompensatorGains-v0_s{seed}.npz").meta["iterations"]
            for f in ("gnwsf", "gnwsfo"))
    assert len(members) == hour.tail_count(n) and avg.meta["averaged_from"] == [m.name for m in members]
    lifted = [arc.lift_policy(m, "hsfo") for m in members]
    for k in avg.theta:
        np.testing.assert_array_equal(avg.theta[k], np.mean([m.theta[k] for m in lifted], axis=0))
    for family in ("gnwsf", "gnwsfo"):
        stage = arc.load_policy(TRAINED / f"{family}_CompensatorGains-v0_s{seed}.npz")
        last = [m for m in members if m.meta["iterate_of"] == stage.name][-1]
        assert last.meta["iterations"] == stage.meta["iterations"]
        assert all(np.array_equal(last.theta[k], stage.theta[k]) for k in stage.theta)
    runs = load_script("training_cost").chain(TRAINED / f"gnwt_CompensatorGains-v0_s{seed}.npz")
    assert [r[0] for r in runs[:4]] == ["arsp_CompensatorGains-v0_s0"] + [f"{f}_CompensatorGains-v0_s{seed}"
                                                                          for f in ("gnw", "gnws", "gnwsf")]
    assert runs[-2][0].startswith(f"gnwsfo_CompensatorGains-v0_s{seed}_it") and len(runs) == 6


@pytest.mark.parametrize("seed, outward", [(0, 7), (1, 6), (2, 5)])
def test_committed_gnw5t_is_the_mean_of_its_chains_last_half(seed, outward):
    """``gnw5t`` seed k (docs/agents.md "Fewer fish-gated steps, more outward ones"): the committed chain's fish-gated
    stage cut at 5 steps (its iterate 14, as a 5-step stage), then ``outward`` outward-gated steps from it; the policy
    is the mean of the last ceil(n/2) of those n = 5 + outward iterates (all outward-gated here), the last of them
    the outward stage's file, and scripts/training_cost.py follows the chain back to the ARS start."""
    hour = load_script("train_compensator_hour")
    cut = arc.load_policy(TRAINED / f"gnwsf_CompensatorGains-v0_s{seed}_it14.npz")
    assert cut.meta["iterations"] == 5 and cut.meta["first_iteration"] == 10
    assert cut.meta["iterate_of"] == f"gnwsf_CompensatorGains-v0_s{seed}"
    stage = arc.load_policy(TRAINED / f"gnw5sfo_CompensatorGains-v0_s{seed}.npz")
    hp = stage.meta["hyperparameters"]
    assert stage.meta["iterations"] == outward and stage.meta["first_iteration"] == 15
    assert hp["init"] == cut.name and hp["free"] == "outward" and stage.meta["feature_set"] == "hsfo"
    n = hour.tail_count(5 + outward)
    members = [arc.load_policy(TRAINED / f"gnw5sfo_CompensatorGains-v0_s{seed}_it{i}.npz")
               for i in range(15 + outward - n, 15 + outward)]
    avg = arc.load_policy(TRAINED / f"gnw5t_CompensatorGains-v0_s{seed}.npz")
    assert avg.meta["averaged_from"] == [m.name for m in members]
    for k in avg.theta:
        np.testing.assert_array_equal(avg.theta[k], np.mean([m.theta[k] for m in members], axis=0))
        np.testing.assert_array_equal(members[-1].theta[k], stage.theta[k])
    runs = load_script("training_cost").chain(TRAINED / f"gnw5t_CompensatorGains-v0_s{seed}.npz")
    assert [r[0] for r in runs] == (["arsp_CompensatorGains-v0_s0"]
                                    + [f"{f}_CompensatorGains-v0_s{seed}" for f in ("gnw", "gnws")]
                                    + [cut.name, members[-1].name, avg.name])
    assert sum(r[1] for r in runs) / 60.0 < 57.5          # the iterations' minutes; the chain's wall is documented


def test_dry_run_prints_the_four_stages_and_the_average(capsys, tmp_path):
    hour = load_script("train_compensator_hour")
    assert hour.main(["--seed", "1", "--out-dir", str(tmp_path), "--dry-run"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 5 and all("train_gn_compensator.py" in x for x in lines[:4])
    assert "average_compensator.py" in lines[4] and lines[4].endswith("of stages 3-4>")
    assert f"--export {tmp_path / 'gnwt_CompensatorGains-v0_s1.npz'}" in lines[4] and "--features hsfo" in lines[4]
