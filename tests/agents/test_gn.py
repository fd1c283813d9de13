"""Gauss–Newton policy search for the WinchPayout linear residual (issue 14, agents/gn.py): it trains on the batched
vector env from the along-cable law, its line search never keeps a step that loses on its own episodes, its wave seeds
are disjoint from every evaluation/final/tuning/validation seed and from the ARS trainings', bad settings are refused
with the field named, and its policy file is an ARS policy file that scripts/evaluate.py names as Gauss–Newton."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

import towenv  # noqa: E402,F401
from agents import ars, gn  # noqa: E402
from helpers import load_script  # noqa: E402

WINCH = "towenv/WinchPayout-v0"


@pytest.fixture(scope="module")
def trained():
    """Two iterations on one heading per sea state, 70 s episodes scored after 60 s (~30 s)."""
    return gn.train(seed=3, iterations=2, entries=[0, 4, 8], episode_seconds=70.0, discard=60.0, progress=False)


def test_search_runs_on_the_batched_env_and_keeps_only_improving_steps(trained):
    pol = trained
    assert pol.meta["method"] == "gauss-newton" and pol.meta["iterations"] == 2 and len(pol.meta["curve"]) == 2
    assert pol.meta["curve"][0]["heave_ratio"] == pytest.approx(1.0)        # θ = 0 (the along-cable law) first
    assert set(pol.theta) == set(pol.base_table) and pol.feature_set == "v2"
    assert all(np.all(np.isfinite(v)) for v in pol.theta.values())
    for rec in pol.meta["curve"]:
        for p in rec["picks"]:      # a step is kept only if it beats the current θ on the line-search episodes
            assert p["cost_after"] <= p["cost_current"]
            assert (p["ridge"] is None) == (p["step_norm"] == 0.0)
    moved = [p for rec in pol.meta["curve"] for p in rec["picks"] if p["ridge"] is not None]
    norms = {k: float(np.linalg.norm(v)) for k, v in pol.theta.items()}
    assert (sum(v > 0 for v in norms.values()) > 0) == bool(moved)
    assert pol.meta["num_timesteps"] == 2 * 3 * (ars.n_features("v2") + 1 + 5) * 700


def test_policy_file_is_an_ars_file_that_evaluate_names(trained, tmp_path, monkeypatch):
    f = ars.save_policy(trained, tmp_path / "gn_test_s3.npz")
    back = ars.load_ars_policy(f)
    assert back.meta["method"] == "gauss-newton"
    assert all(np.array_equal(back.theta[k], trained.theta[k]) for k in trained.theta)
    evaluate = load_script("evaluate")
    monkeypatch.chdir(tmp_path)
    assert evaluate.main([str(f), "--episodes", "0", "--baselines", "fixed_winch", "along_cable", "--no-plots",
                          "--env-kwargs", "episode_seconds:30", "--discard", "10"]) == 0
    text = (tmp_path / "runs" / "reports" / "gn_test_s3" / "report.md").read_text()
    assert "Gauss-Newton policy search" in text and "2 Gauss-Newton iterations" in text


def test_wave_seeds_are_disjoint_from_every_reserved_set():
    base = [s for _, s in gym.make(WINCH).unwrapped.eval_sea_states()]
    reserved = {b + off for b in base for off in list(range(0, 500, 100)) + [500, 700, 900]
                + list(range(20000, 20500, 100)) + [30000]}
    ars_training = {ars._train_seed(b, it, sd) for b in base for it in range(100) for sd in range(3)}
    probes = {b + off + 100 * r for b in base for off in (75000, 76000) for r in range(8)}
    used = set()
    for b in base:               # within a (sea state, heading) no two episodes of the search share a wave seed
        mine = {gn.train_seed(b + 10 * r, it, sd, ls) for r in range(3) for it in range(gn.MAX_ITERATIONS)
                for sd in range(3) for ls in (False, True)}
        assert len(mine) == 3 * gn.MAX_ITERATIONS * 3 * 2
        used |= mine
    assert not used & (reserved | ars_training | probes)
    with pytest.raises(ValueError, match="iteration"):
        gn.train_seed(base[0], gn.MAX_ITERATIONS, 0)
    with pytest.raises(ValueError, match="seed"):
        gn.train_seed(base[0], 0, 10)


def test_training_seed_must_be_an_integer_in_range():
    """A training seed of 1.5 (or "1", or True) is refused with the field named, not truncated to another run's
    block of wave seeds; numpy integers 0..9 pass."""
    for bad in (1.5, "1", True, -1, 10):
        with pytest.raises(ValueError, match="seed \\(the training seed\\)"):
            gn.check_training_seed(bad)
    gn.check_training_seed(np.int64(3))
    assert gn.train_seed(4000, 0, np.int64(3)) == gn.train_seed(4000, 0, 3)


def test_second_seed_block_is_above_every_other_training_set():
    """Iterations past the first block (continuations from iteration 49 on) take seeds of their own: above every
    first-block, ARS (winch and compensator) and compensator Gauss–Newton seed of any training seed 0..9, and
    still distinct per (sea state, replicate, iteration, line search)."""
    from agents import ars_compensator as arc, gn_compensator as gnc
    base = [s for _, s in gym.make(WINCH).unwrapped.eval_sea_states()]
    k = gn.ITERATIONS_PER_BLOCK
    first = [gn.train_seed(b + 10 * r, it, sd, ls) for b in base for r in range(10) for it in range(k)
             for sd in range(10) for ls in (False, True)]
    second = [gn.train_seed(b + 10 * r, it, sd, ls) for b in base for r in range(10)
              for it in range(k, gn.MAX_ITERATIONS) for sd in range(10) for ls in (False, True)]
    others = ([ars._train_seed(b, it, sd) for b in base for it in range(100) for sd in range(10)]
              + [arc._train_seed(b, it, sd) for b in base for it in range(arc.MAX_ITERATIONS) for sd in range(10)]
              + [gnc.train_seed(b + 10 * r, it, sd, ls) for b in base for r in range(10)
                 for it in range(gnc.MAX_ITERATIONS) for sd in range(10) for ls in (False, True)])
    assert min(second) >= gn.SECOND_BLOCK_OFFSET > max(first + others)
    for b in base:               # within a (sea state, heading) no two episodes share a wave seed
        mine = [gn.train_seed(b + 10 * r, it, sd, ls) for r in range(10) for it in range(k, gn.MAX_ITERATIONS)
                for sd in range(10) for ls in (False, True)]
        assert len(set(mine)) == len(mine)
    # the first block is unchanged: committed policies' iteration seeds (docs/agents.md) stay what they were
    assert gn.train_seed(5000, 48, 2, True) == 5000 + 80000 + 200 * 48 + 100 + 200000
    assert gn.train_seed(5000, 49, 2) == 5000 + 1_000_000 + 200000


@pytest.mark.parametrize("kw, field", [({"iterations": 0}, "iterations"), ({"eps": -1.0}, "eps"),
                                       ({"ridges": (0.1, 0.0)}, "ridge"), ({"replicates": 0}, "replicates"), ({"replicates": 11}, "replicates"),
                                       ({"episode_seconds": 60.0}, "episode_seconds"), ({"entries": [0, 12]}, "entries"),
                                       ({"entries": []}, "entries")])
def test_bad_settings_are_refused_naming_the_field(kw, field):
    with pytest.raises(ValueError, match=field):
        gn.train(**kw)


def test_replicates_per_sea_state_add_episodes_only_where_asked():
    """``replicates=(1, 1, 2)``: the third sea state's heading runs with replicates 0 and 1 (wave seed + 10), the others
    with replicate 0 only, and the Jacobian and line search use the same episodes; the file records the counts. A
    uniform count keeps one value and the historical replicate-major episode order (committed recipes' seeds)."""
    calls = []

    def recorded(base, it, seed, line_search=False):
        calls.append((base, line_search))
        return gn.train_seed(base, it, seed, line_search)

    pol = gn.train(seed=3, iterations=1, entries=[0, 4, 8], replicates=(1, 1, 2), episode_seconds=62.0,
                   discard=60.0, progress=False, wave_seed=recorded)
    # replicate-major, one episode per (replicate, entry): the Jacobian's and the line search's seeds in that order
    assert [b for b, ls in calls if not ls] == [b for b, ls in calls if ls] == [3000, 4000, 5000, 5010]
    assert pol.meta["hyperparameters"]["replicates"] == [1, 1, 2]
    import os
    assert pol.meta["blas_env"] == {v: os.environ.get(v) for v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    assert gn.replicates_per_sea_state(2, ["a", "b", "c"]) == [2, 2, 2]
    with pytest.raises(ValueError, match="replicates.*one per trained sea state"):
        gn.replicates_per_sea_state((1, 2), ["a", "b", "c"])
    with pytest.raises(ValueError, match="replicates must be in 1..10"):
        gn.replicates_per_sea_state((1, 11, 2), ["a", "b", "c"])
    with pytest.raises(ValueError, match="replicates"):
        gn.train(replicates=(1, 2))            # three sea states trained by default


def test_training_script_defaults_to_one_blas_thread_and_respects_the_user():
    """scripts/train_gn.py sets OPENBLAS_NUM_THREADS/OMP_NUM_THREADS to 1 *before numpy loads* (an import hook records
    the variables at numpy's first import; seeds run side by side, and two spinning threads per process made the
    predictor's products 4x slower), and leaves both alone when the user set either."""
    import os
    import subprocess
    import sys
    script = Path(__file__).resolve().parents[2] / "scripts" / "train_gn.py"
    probe = ("import os, runpy, sys\n"
             "seen = []\n"
             "class Hook:\n"
             "    def find_spec(self, name, path=None, target=None):\n"
             "        if name == 'numpy' and not seen:\n"
             "            seen.append((os.environ.get('OPENBLAS_NUM_THREADS'), os.environ.get('OMP_NUM_THREADS')))\n"
             "        return None\n"
             "sys.meta_path.insert(0, Hook())\n"
             "assert 'numpy' not in sys.modules\n"
             "sys.argv = ['train_gn.py', '--help']\n"
             f"try:\n    runpy.run_path({str(script)!r}, run_name='__main__')\nexcept SystemExit:\n    pass\n"
             "print(*seen[0])")
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    for extra, want in (({}, ["1", "1"]), ({"OPENBLAS_NUM_THREADS": "2"}, ["2", "None"]),
                        ({"OMP_NUM_THREADS": "2"}, ["None", "2"])):
        out = subprocess.run([sys.executable, "-P", "-c", probe], env=env | extra, capture_output=True, text=True,
                             timeout=300)
        assert out.returncode == 0, out.stderr[-2000:]
        assert out.stdout.split()[-2:] == want, (extra, out.stdout)


def test_initial_theta_copies_weights_by_feature_name(trained):
    """A warm start keeps the initial policy's weights on the features both sets have (by name: the v3 set inserts
    its long history before the constant) and starts the new ones at 0; no init is θ = 0 (the along-cable law)."""
    keys = sorted(trained.theta)
    assert not gn.initial_theta(None, keys, "v3").any()
    th = gn.initial_theta(trained, keys, "v3")
    n2, n3 = ars.feature_names("v2"), ars.feature_names("v3")
    for c, k in enumerate(keys):
        for i, nm in enumerate(n3):
            assert th[c, i] == (trained.theta[k][n2.index(nm)] if nm in n2 else 0.0)
    assert np.array_equal(gn.initial_theta(trained, keys, "v2"), np.array([trained.theta[k] for k in keys]))
    with pytest.raises(ValueError, match="no weights for sea states"):
        gn.initial_theta(trained, keys + ["hs9.99_tp9.99"], "v3")


def test_warm_start_continues_the_iteration_count_and_its_seeds(trained, monkeypatch):
    """Training from a Gauss-Newton policy continues its iteration count (fresh wave seeds: iteration 2 onwards
    after a 2-iteration policy) and records where it started; a start past the seed blocks is refused."""
    used = []
    real = gn.train_seed
    monkeypatch.setattr(gn, "train_seed", lambda b, it, sd, line_search=False: used.append(it) or real(b, it, sd,
                                                                                                       line_search))
    pol = gn.train(seed=3, iterations=1, entries=[4], episode_seconds=62.0, discard=60.0, progress=False,
                   feature_set="v3", init=trained)
    assert set(used) == {2} and pol.meta["first_iteration"] == 2 and pol.meta["iterations"] == 1
    assert pol.meta["curve"][0]["iteration"] == 2 and pol.feature_set == "v3"
    assert pol.meta["hyperparameters"]["init"] == trained.name and pol.meta["init_num_timesteps"] > 0
    with pytest.raises(ValueError, match="iterations"):
        gn.train(iterations=gn.MAX_ITERATIONS - 1, init=trained)


def test_v2q_search_carries_its_predictor_and_keeps_untrained_sea_states(trained, tmp_path):
    """A v2q search from a v2 policy on one entry: the policy carries the predictor it was given (and the file
    does), the trained sea state's predicted-feature weights start at 0 and only it can move, the other sea states
    keep the initial policy's weights (predicted features at 0); without a predictor it is refused."""
    from agents.predictor import Predictor
    from agents.common import nearest_key
    pred = Predictor.load(Path(ars.__file__).parent / "trained" / "predictor_WinchPayout-v0.npz")
    with pytest.raises(ValueError, match="needs a predictor"):
        gn.train(seed=3, iterations=1, entries=[4], feature_set="v2q", init=trained, progress=False)
    pol = gn.train(seed=3, iterations=1, entries=[4], episode_seconds=62.0, discard=60.0, progress=False,
                   feature_set="v2q", init=trained, predictor=pred)
    assert pol.predictor is pred and pol.feature_set == "v2q" and set(pol.theta) == set(trained.theta)
    ev = gym.make(WINCH).unwrapped.eval_sea_states()
    moved = nearest_key(trained.theta, ev[4][0])
    names, n2 = ars.feature_names("v2q"), ars.feature_names("v2")
    for k, row in pol.theta.items():
        if k != moved:
            assert np.array_equal(row, [trained.theta[k][n2.index(nm)] if nm in n2 else 0.0 for nm in names])
    back = ars.load_ars_policy(ars.save_policy(pol, tmp_path / "gnq.npz"))
    assert all(np.array_equal(back.predictor.W[k], pred.W[k]) for k in pred.W)


def test_command_line_refuses_out_of_range_arguments(capsys):
    for bad in (["--iterations", str(gn.MAX_ITERATIONS + 1)], ["--eps", "0"], ["--ridges", "-1"],
                ["--replicates", "0"], ["--replicates", "11"], ["--replicates", "1", "0", "2"], ["--seed", "10"]):
        with pytest.raises(SystemExit) as ex:
            gn.main(bad)
        assert ex.value.code == 2
    with pytest.raises(SystemExit) as ex:
        gn.main(["--init", "no_such_policy.npz"])
    assert ex.value.code == 2 and "--init" in capsys.readouterr().err
    assert str(gn.default_export(2)) == "runs/gn_WinchPayout-v0_s2.npz"
    assert str(gn.default_export(1, "v3")) == "runs/gn_v3_WinchPayout-v0_s1.npz"


#: Gauss-Newton iterations of the committed gnqa family (its time budget decides)
GNQA_ITERATIONS = 6


@pytest.mark.parametrize("family", ["gn", "gn2", "gn3", "gn4", "gn5", "gnq", "gnq2", "gnqp", "gnqp2", "gnqa"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_committed_policies_ship_load_and_act(seed, family):
    """The committed Gauss-Newton policies (docs/agents.md "Results") are package data of the installed ``agents``,
    load with their recipe (``gn``: 10 iterations; ``gn2``: 6 more, two replicates, ridges 0.01-100, continued
    from the ``gn`` file of the same seed; ``gn3``/``gn4``: 8 more each, three replicates, continued from ``gn2``/``gn3``;
    ``gn5``: 7 more (its time budget stopped it), three replicates, from ``gn4``; feature set
    v2, the along-cable table's sea states; ``gnq``: 4 more from ``gn5`` (budget) with feature set v2q and the
    committed predictor, on codes 4-5 only — code 3 keeps ``gn5``'s weights, predicted features at 0; ``gnq2``: 5 more
    from ``gnq`` (budget), the same settings, code 3 still ``gnq``'s weights; ``gnqp``: 1 more from ``gnq2`` with the
    cost's pitch weight 0.2 instead of 0.5; ``gnqp2``: 3 more from ``gnqp``, iterations 49-51 on the second block of
    wave seeds, with the pitch weight 0.1; ``gnqa``: GNQA_ITERATIONS more from ``gnqp2`` with feature set v2qa — the
    acceleration hinges added at 0 — the same settings, code 3 still ``gn5``'s weights) and act:
    inside the action box and not the along-cable law itself."""
    from pathlib import Path

    import agents
    from agents.baselines import load_tuned, make_baseline
    from agents.metrics import rollout
    pol = ars.load_ars_policy(Path(agents.__file__).parent / "trained" / f"{family}_WinchPayout-v0_s{seed}.npz")
    assert pol.meta["method"] == "gauss-newton" and pol.meta["seed"] == seed
    if family == "gn":
        assert pol.meta["iterations"] == 10
    else:
        hp = pol.meta["hyperparameters"]
        first, its, parent, reps = {"gn2": (10, 6, "gn", 2), "gn3": (16, 8, "gn2", 3), "gn4": (24, 8, "gn3", 3),
                                    "gn5": (32, 7, "gn4", 3), "gnq": (39, 4, "gn5", 3),
                                    "gnq2": (43, 5, "gnq", 3), "gnqp": (48, 1, "gnq2", 3),
                                    "gnqp2": (49, 3, "gnqp", 3), "gnqa": (52, GNQA_ITERATIONS, "gnqp2", 3)}[family]
        assert (pol.meta["first_iteration"], pol.meta["iterations"]) == (first, its)
        assert hp["init"] == f"{parent}_WinchPayout-v0_s{seed}" and hp["replicates"] == reps
        assert hp["ridges"] == [0.01, 0.1, 1.0, 10.0, 100.0]
        assert hp["pitch_weight"] == {"gnqp": 0.2, "gnqp2": 0.1, "gnqa": 0.1}.get(family, 0.5)
    fs = {"gnq": "v2q", "gnq2": "v2q", "gnqp": "v2q", "gnqp2": "v2q", "gnqa": "v2qa"}.get(family, "v2")
    assert pol.feature_set == fs
    assert set(pol.theta) == set(load_tuned()["along_cable"])
    if fs != "v2":
        from agents.predictor import Predictor
        pred = Predictor.load(Path(agents.__file__).parent / "trained" / "predictor_WinchPayout-v0.npz")
        assert all(np.array_equal(pol.predictor.W[k], pred.W[k]) for k in pred.W)
        parent = ars.load_ars_policy(Path(agents.__file__).parent / "trained" / f"gn5_WinchPayout-v0_s{seed}.npz")
        names, n2 = ars.feature_names(fs), ars.feature_names("v2")
        code3 = "hs0.88_tp4.03"
        assert np.array_equal(pol.theta[code3], [parent.theta[code3][n2.index(nm)] if nm in n2 else 0.0 for nm in names])
        assert pol.meta["hyperparameters"]["entries"] == [4, 5, 6, 7, 8, 9, 10, 11]
    env = gym.make(WINCH, episode_seconds=20.0)
    pol.bind_env(env)
    sea, s = env.unwrapped.eval_sea_states()[9]
    a = rollout(env, pol, sea, s + 123456)
    b = rollout(env, make_baseline("along_cable", env), sea, s + 123456)
    assert np.all(np.abs(a.data["winch_speed"]) <= env.unwrapped.winch_max_speed + 1e-9)
    assert not np.array_equal(a.data["winch_speed"], b.data["winch_speed"])


def test_training_cost_follows_the_init_chain(tmp_path, capsys):
    """scripts/training_cost.py sums each file's own iteration seconds and env steps along its --init chain: the
    committed gnq2 chain is gn → gn2 → gn3 → gn4 → gn5 → gnq → gnq2 and its totals are the sums of the files' own
    metadata; a file whose init is missing, and a file that is no policy, are refused with exit 2 naming them."""
    import json
    import shutil
    from pathlib import Path

    import agents
    from helpers import load_script
    tc = load_script("training_cost")
    trained = Path(agents.__file__).parent / "trained"
    runs = tc.chain(trained / "gnq2_WinchPayout-v0_s1.npz")
    assert [r[0] for r in runs] == [f"{f}_WinchPayout-v0_s1" for f in ("gn", "gn2", "gn3", "gn4", "gn5", "gnq", "gnq2")]
    for stem, sec, steps in runs:
        meta = tc.read_meta(trained / f"{stem}.npz")
        assert steps == meta["num_timesteps"] > 0
        assert sec == pytest.approx(sum(c["seconds"] for c in meta["curve"])) and 0 < sec <= meta["wall_seconds"]
    # a parent's own steps are what its child records as init_num_timesteps (the totals do not double count)
    for (_p, _s, n_parent), (child, _c, _n) in zip(runs, runs[1:]):
        assert tc.read_meta(trained / f"{child}.npz")["init_num_timesteps"] == n_parent
    assert tc.main([str(trained / "gnq2_WinchPayout-v0_s1.npz")]) == 0
    assert "chain" in capsys.readouterr().out
    lone = tmp_path / "gnq2_WinchPayout-v0_s1.npz"
    shutil.copy(trained / "gnq2_WinchPayout-v0_s1.npz", lone)
    bad = tmp_path / "not_a_policy.npz"
    bad.write_text(json.dumps({"x": 1}))
    for f, msg in ((lone, "--init"), (bad, "not_a_policy")):
        with pytest.raises(SystemExit) as ex:
            tc.main([str(f)])
        assert ex.value.code == 2 and msg in capsys.readouterr().err
    # --search: the lone file's chain found in the package folder, the same totals as there; a missing folder refused
    assert tc.chain(lone, search=[tmp_path / "nowhere", trained])[:-1] == runs[:-1]
    assert tc.chain(lone, search=[trained])[-1] == runs[-1]
    assert tc.main([str(lone), "--search", str(trained)]) == 0
    assert f"{runs[0][0]}" in capsys.readouterr().out
    with pytest.raises(SystemExit) as ex:
        tc.main([str(lone), "--search", str(tmp_path / "nowhere")])
    assert ex.value.code == 2 and "nowhere" in capsys.readouterr().err


#: Gauss-Newton iterations the one-hour recipes' 57-min budget allowed per seed (three side by side on two cores):
#: ``gna`` (two BLAS threads per process, the OpenBLAS default then) and ``gnr`` (one, scripts/train_gn.py's default)
RECIPE_ITERATIONS = {"gna": {0: 7, 1: 6, 2: 7}, "gnr": {0: 12, 1: 12, 2: 12}}
#: the recipes' replicates and pitch weight: ``gnr`` takes 1 / 2 / 3 replicates in codes 3 / 4 / 5
RECIPE_SETTINGS = {"gna": (2, 0.2), "gnr": ([1, 2, 3], 0.1)}


@pytest.mark.parametrize("family", ["gna", "gnr"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_one_hour_recipe_policies_ship_with_their_recipe(seed, family):
    """``gna``/``gnr`` (docs/agents.md "The one-hour recipe"): feature set v2qa trained from the along-cable law (no
    init) on all 12 entries with the recipe's replicates and pitch weight, a 57-min budget — its own wall time under
    an hour, the whole recipe (the committed predictor is an input, fitted once in ~1 min) — and it acts inside the
    action box."""
    from pathlib import Path

    import agents
    from agents.predictor import Predictor
    trained = Path(agents.__file__).parent / "trained"
    pol = ars.load_ars_policy(trained / f"{family}_WinchPayout-v0_s{seed}.npz")
    m, hp = pol.meta, pol.meta["hyperparameters"]
    assert (m["method"], m["seed"], m["first_iteration"], m["iterations"]) == ("gauss-newton", seed, 0,
                                                                                    RECIPE_ITERATIONS[family][seed])
    assert hp.get("init") is None and hp["entries"] == list(range(12))
    assert (hp["replicates"], hp["pitch_weight"]) == RECIPE_SETTINGS[family]
    assert hp["minutes"] == 57.0 and 0 < m["wall_seconds"] < 3600.0
    assert pol.feature_set == "v2qa"
    pred = Predictor.load(trained / "predictor_WinchPayout-v0.npz")
    assert all(np.array_equal(pol.predictor.W[k], pred.W[k]) for k in pred.W)
    env = gym.make(WINCH, episode_seconds=20.0)
    pol.bind_env(env)
    sea, s = env.unwrapped.eval_sea_states()[9]
    from agents.metrics import rollout
    a = rollout(env, pol, sea, s + 123456)
    assert np.all(np.abs(a.data["winch_speed"]) <= env.unwrapped.winch_max_speed + 1e-9)


def test_parallel_search_gives_the_serial_result():
    """``parallel=True`` (``--parallel``) only changes the wall time: one Gauss–Newton iteration on the WinchPayout
    batch stepped on all numba threads gives the serial run's weights and line-search picks bit for bit."""
    kw = dict(seed=3, iterations=1, entries=[4], episode_seconds=62.0, discard=60.0, progress=False)
    ser, par = gn.train(**kw), gn.train(**kw, parallel=True)
    assert par.meta["parallel"] is True and ser.meta["parallel"] is False
    assert all(np.array_equal(par.theta[k], ser.theta[k]) for k in ser.theta)
    assert [p["picks"] for p in par.meta["curve"]] == [p["picks"] for p in ser.meta["curve"]]
    assert any(np.any(ser.theta[k] != 0) for k in ser.theta)      # the iteration moved: the test can tell
