"""A Gauss–Newton run's iterates and their average (issue 14, "a steadier end than the last iterate"):
``train_gn_compensator.py --save-iterates`` writes Θ after each step, the last equal to the run's file and the first
equal to a one-step run of the same seed; ``lift_policy`` writes a policy in a larger feature set without changing
what it does; ``average_compensator.py --features`` averages a chain's hsf and hsfo iterates; and
scripts/training_cost.py counts a run whose iterates are averaged once, with its latest member's iterations."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from agents import ars_compensator as arc  # noqa: E402
from agents import gn_compensator as gnc  # noqa: E402
from helpers import load_script  # noqa: E402

TRAINED = Path(arc.__file__).parent / "trained"


def _load(stem):
    return arc.load_policy(TRAINED / f"{stem}.npz")


@pytest.fixture(scope="module")
def iterates(tmp_path_factory):
    """Two steps from the committed gnws seed 0 on one entry with 62 s episodes, and a one-step run beside it."""
    d = tmp_path_factory.mktemp("iterates")
    init = str(TRAINED / "gnws_CompensatorGains-v0_s0.npz")
    kw = dict(entries=[4], episode_seconds=62.0, discard=60.0, progress=False, feature_set="hsf", free="fish",
              init=arc.load_policy(init))
    two = gnc.train(seed=3, iterations=2, **kw)
    one = gnc.train(seed=3, iterations=1, **kw)
    out = d / "gnx_CompensatorGains-v0_s3.npz"
    arc.save_policy(two, out)
    files = []
    for p in gnc.iterate_policies(two, out.stem):
        files.append(arc.save_policy(p, d / f"{p.name}.npz"))
    return d, two, one, files


def test_iterates_are_the_steps_of_the_run(iterates):
    _d, two, one, files = iterates
    first = two.meta["first_iteration"]
    assert first == 10 and [f.name for f in files] == ["gnx_CompensatorGains-v0_s3_it10.npz",
                                                        "gnx_CompensatorGains-v0_s3_it11.npz"]
    a, b = (arc.load_policy(f) for f in files)
    for k in two.theta:                    # the last is the run; the first is a one-step run of the same seed
        np.testing.assert_array_equal(b.theta[k], two.theta[k])
        np.testing.assert_array_equal(a.theta[k], one.theta[k])
    start = arc.lift_policy(_load("gnws_CompensatorGains-v0_s0"), "hsf")
    assert any(not np.array_equal(p.theta[k], start.theta[k]) for p in (a, b) for k in p.theta)   # steps were taken
    assert (a.meta["iterations"], b.meta["iterations"]) == (1, 2) and a.meta["iterate_of"] == files[0].stem[:-5]
    assert a.meta["curve"] == two.meta["curve"][:1] and b.meta["curve"] == two.meta["curve"]
    assert 2 * a.meta["num_timesteps"] == b.meta["num_timesteps"] == two.meta["num_timesteps"]
    with pytest.raises(ValueError, match="no iterates"):
        gnc.iterate_policies(_load("gnwsf_CompensatorGains-v0_s0"), "x")


def test_an_average_of_iterates_costs_their_run_once(iterates, tmp_path):
    d, two, _one, files = iterates
    import shutil
    for stem in ("arsp_CompensatorGains-v0_s0", "gnw_CompensatorGains-v0_s0", "gnws_CompensatorGains-v0_s0"):
        shutil.copy(TRAINED / f"{stem}.npz", d)
    out = d / "gnxa_CompensatorGains-v0_s3.npz"
    members = [str(f) for f in files[::-1]]          # the latest first: the run keeps its longest part, not the last seen
    assert load_script("average_compensator").main(["--seed", "3", "--export", str(out)] + members) == 0
    cost = load_script("training_cost")
    runs = cost.chain(out)
    run = cost.chain(d / "gnx_CompensatorGains-v0_s3.npz")
    assert [r[0] for r in runs[:-1]] == [r[0] for r in run[:-1]] + [files[1].stem]
    assert runs[:-2] == run[:-1] and runs[-2][1:] == run[-1][1:]     # the run once, with both steps (not 1 + 2)
    assert runs[-1][1:] == (0.0, 0)


def test_a_lifted_policy_acts_as_before_and_only_adds_features():
    pol = _load("gnwsf_CompensatorGains-v0_s0")
    up = arc.lift_policy(pol, "hsfo")
    assert up.feature_set == "hsfo" and up.meta["lifted_from"] == "hsf" and up.name == pol.name
    small, big = arc.feature_names("hsf"), arc.feature_names("hsfo")
    cols = [big.index(nm) for nm in small]
    extra = [i for i in range(len(big)) if i not in cols]
    rng = np.random.default_rng(1)
    phi = rng.normal(size=(7, len(big)))
    for k in pol.theta:
        assert not np.any(up.theta[k][:, extra])
        np.testing.assert_array_equal(up.theta[k][:, cols], pol.theta[k])
        r_small = arc._residual(np.repeat(pol.theta[k][None], len(phi), axis=0), phi[:, cols])
        r_big = arc._residual(np.repeat(up.theta[k][None], len(phi), axis=0), phi)
        np.testing.assert_allclose(r_big, r_small, rtol=0, atol=1e-12)
    assert arc.lift_policy(pol, "hsf") is pol
    with pytest.raises(ValueError, match="lacks .* features"):
        arc.lift_policy(_load("gnwsfo_CompensatorGains-v0_s0"), "hsf")


def test_cli_averages_a_chains_stages_in_the_larger_feature_set(tmp_path, capsys):
    a, b = _load("gnwsf_CompensatorGains-v0_s1"), _load("gnwsfo_CompensatorGains-v0_s1")
    script = load_script("average_compensator")
    files = [str(TRAINED / f"{p.name}.npz") for p in (a, b)]
    with pytest.raises(SystemExit):
        script.main(["--seed", "1", "--export", str(tmp_path / "m.npz")] + files)
    assert "feature_set differs" in capsys.readouterr().err
    assert script.main(["--seed", "1", "--features", "hsfo", "--export", str(tmp_path / "m.npz")] + files) == 0
    avg = arc.load_policy(tmp_path / "m.npz")
    assert avg.feature_set == "hsfo"
    lifted = arc.lift_policy(a, "hsfo")
    for k in avg.theta:
        np.testing.assert_array_equal(avg.theta[k], (lifted.theta[k] + b.theta[k]) / 2.0)
    with pytest.raises(SystemExit):
        script.main(["--seed", "1", "--features", "hsf", "--export", str(tmp_path / "n.npz")] + files)
    assert "lacks" in capsys.readouterr().err


def test_the_runs_own_file_stands_for_it_when_as_long_as_its_last_iterate(iterates):
    """A member continuing the run (its --init) brings the run's own file into the chain; the last iterate is as
    long, and the run's own file is the one counted (an iterate re-run from the same start carries its re-run's
    wall), whatever the members' order."""
    d, two, _one, files = iterates
    cont = arc.load_policy(d / "gnx_CompensatorGains-v0_s3.npz")
    meta = dict(cont.meta) | {"hyperparameters": dict(cont.meta["hyperparameters"]) | {"init": cont.name},
                              "curve": cont.meta["curve"][:1], "num_timesteps": 5}
    arc.save_policy(arc.ARSCompensatorPolicy(cont.theta, cont.base_table, cont.scales, meta, name="gny"),
                    d / "gny_CompensatorGains-v0_s3.npz")
    # the iterate's wall differs from the run's (as a re-run's would)
    kept = files[1].read_bytes()
    it = arc.load_policy(files[1])
    it.meta["curve"] = [dict(c) | {"seconds": c["seconds"] + 100.0} for c in it.meta["curve"]]
    arc.save_policy(it, files[1])
    cost = load_script("training_cost")
    for order in (1, -1):
        members = [arc.load_policy(files[1]), arc.load_policy(d / "gny_CompensatorGains-v0_s3.npz")][::order]
        avg = arc.average_policies(members, seed=3)
        out = arc.save_policy(avg, d / f"gnya{order + 1}_CompensatorGains-v0_s3.npz")
        names = [r[0] for r in cost.chain(out)]
        assert "gnx_CompensatorGains-v0_s3" in names and files[1].stem not in names
    files[1].write_bytes(kept)                  # the module's other tests read the iterate as trained
