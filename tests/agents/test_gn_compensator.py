"""Gauss–Newton policy search for the CompensatorGains linear residual over skyhook (issue 14,
agents/gn_compensator.py): it trains on the batched vector env from skyhook or from a policy file (keeping its
weights and stop guard), its line search never keeps a step that loses on its own episodes, its wave seeds are
disjoint from every other seed set, bad settings are refused with the field named, and its policy file is an ARS
compensator file that scripts/evaluate.py names as Gauss–Newton."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

import towenv  # noqa: E402,F401
from agents import ars, gn  # noqa: E402
from agents import ars_compensator as arc  # noqa: E402
from agents import gn_compensator as gnc  # noqa: E402
from helpers import load_script  # noqa: E402

COMP = "towenv/CompensatorGains-v0"


def _committed(seed=0):
    import agents
    return arc.load_policy(Path(agents.__file__).parent / "trained" / f"ars_CompensatorGains-v0_s{seed}.npz")


@pytest.fixture(scope="module")
def trained():
    """One iteration from skyhook on one heading of two sea states, 62 s episodes scored after 60 s (~10 s)."""
    return gnc.train(seed=3, iterations=1, entries=[0, 4], episode_seconds=62.0, discard=60.0, progress=False)


def test_search_runs_on_the_batched_env_and_keeps_only_improving_steps(trained):
    pol = trained
    assert pol.meta["method"] == "gauss-newton" and pol.meta["algo"] == arc.ALGO
    assert pol.meta["iterations"] == 1 and pol.meta["first_iteration"] == 0 and pol.stop_guard == 0.0
    rec = pol.meta["curve"][0]
    assert rec["heave_ratio"] == pytest.approx(1.0) and rec["hits"] == rec["hits_skyhook"]   # Θ = 0 is skyhook
    for p in rec["picks"]:          # a step is kept only if it beats the current Θ on the line-search episodes
        assert p["cost_after"] <= p["cost_current"]
        assert (p["ridge"] is None) == (p["step_norm"] == 0.0)
    moved = {p["sea_state"] for p in rec["picks"] if p["ridge"] is not None}
    assert {k for k, v in pol.theta.items() if np.any(v != 0)} == moved
    assert all(v.shape == (arc.N_ACT, arc.N_FEATURES) and np.all(np.isfinite(v)) for v in pol.theta.values())
    assert pol.meta["num_timesteps"] == 2 * (arc.N_ACT * arc.N_FEATURES + 1 + 5) * 620


def test_warm_start_keeps_the_initial_policy(monkeypatch):
    """From a committed ARS policy: its weights (for sea states without a kept step or not trained on), base table
    and stop guard;
    an ARS start begins at Gauss–Newton iteration 0, a Gauss–Newton start continues its count."""
    init = _committed(0)
    used = []
    real = gnc.train_seed
    monkeypatch.setattr(gnc, "train_seed", lambda b, it, sd, line_search=False: used.append(it) or real(
        b, it, sd, line_search))
    pol = gnc.train(seed=4, iterations=1, entries=[8], episode_seconds=62.0, discard=60.0, progress=False, init=init)
    assert set(used) == {0} and pol.stop_guard == init.stop_guard == 0.9 and pol.base_table == init.base_table
    pick = pol.meta["curve"][0]["picks"][0]
    k = pick["sea_state"]
    assert sorted(pol.theta) == sorted(init.theta)           # the sea states not trained on keep their weights
    assert all(np.array_equal(pol.theta[x], init.theta[x]) for x in pol.theta if x != k)
    if pick["ridge"] is None:
        assert np.array_equal(pol.theta[k], init.theta[k])
    else:
        assert np.linalg.norm(pol.theta[k] - init.theta[k]) == pytest.approx(pick["step_norm"])
    used.clear()
    again = gnc.train(seed=4, iterations=1, entries=[8], episode_seconds=62.0, discard=60.0, progress=False, init=pol)
    assert set(used) == {1} and again.meta["first_iteration"] == 1
    assert again.meta["hyperparameters"]["init"] == pol.name


def test_predicted_features_start_at_zero_and_free_predicted_moves_only_them():
    """From a committed Gauss–Newton policy to feature set hq: its weights copied by feature name, the predicted ones
    start at 0; with free="predicted" only those move (and the Jacobian has one column per predicted weight); the
    sea states not trained on keep the initial weights; free="predicted" needs a predicted feature set."""
    from agents.predictor import Predictor
    import agents
    trained = Path(agents.__file__).parent / "trained"
    init = arc.load_policy(trained / "gn_CompensatorGains-v0_s1.npz")
    pred = Predictor.load(trained / "predictor_CompensatorGains-v0.npz")
    pol = gnc.train(seed=5, iterations=1, entries=[4], episode_seconds=62.0, discard=60.0, progress=False,
                    init=init, feature_set="hq", predictor=pred, free="predicted")
    assert pol.feature_set == "hq" and pol.predictor is pred and pol.meta["hyperparameters"]["free"] == "predicted"
    names, old = arc.feature_names("hq"), arc.feature_names("h")
    keep = [names.index(n) for n in old]
    moved = [i for i, n in enumerate(names) if n.endswith("(pred)")]
    assert len(moved) == 30 and sorted(keep + moved) == list(range(len(names)))
    assert sorted(pol.theta) == sorted(init.theta)
    for k in pol.theta:
        assert np.array_equal(pol.theta[k][:, keep], init.theta[k])
    (pick,) = pol.meta["curve"][0]["picks"]
    k = pick["sea_state"]
    others = [x for x in pol.theta if x != k]
    assert all(not np.any(pol.theta[x][:, moved]) for x in others)
    assert np.linalg.norm(pol.theta[k][:, moved]) == pytest.approx(pick["step_norm"])
    # 1 episode x (60 moved weights + 1) Jacobian copies + (3 ridges + 2) line-search copies, 62 s each
    assert pol.meta["num_timesteps"] == (2 * 30 + 1 + 5) * 620
    mask = gnc.free_mask("hq", "predicted")
    assert mask.shape == (arc.N_ACT * len(names),) and mask.sum() == 60
    assert np.all(gnc.free_mask("h", "all"))
    with pytest.raises(ValueError, match="free='predicted' needs"):
        gnc.free_mask("h", "predicted")
    with pytest.raises(ValueError, match="free must be"):
        gnc.free_mask("hq", "some")
    gated = gnc.free_mask("hs", "gated")                # hs: only the skyhook-gated copy moves
    hs_names = arc.feature_names("hs")
    assert gated.sum() == arc.N_ACT * 45 and all(
        hs_names[i % len(hs_names)].startswith(arc.GATE_PREFIX) == bool(m) for i, m in enumerate(gated))
    with pytest.raises(ValueError, match="free='gated' needs"):
        gnc.free_mask("hq", "gated")
    cable = gnc.free_mask("hst", "cable")              # hst: only the top-tension and along-cable histories move
    hst_names = arc.feature_names("hst")
    assert cable.sum() == arc.N_ACT * 22 and all(
        (hst_names[i % len(hst_names)].split("@")[0] in arc.CABLE_CHANNELS) == bool(m) for i, m in enumerate(cable))
    assert gnc.free_mask("hst", "gated").sum() == arc.N_ACT * 45
    with pytest.raises(ValueError, match="free='cable' needs"):
        gnc.free_mask("hs", "cable")
    # hsf: only the fish-gated copy moves; hsfo: only the outward-gated copy (or the fish-gated one) moves
    for fs, free, prefix, other, lacking in (("hsf", "fish", arc.FISH_GATE_PREFIX, "gated", "hst"),
                                              ("hsfo", "outward", arc.OUTWARD_GATE_PREFIX, "fish", "hsf")):
        mask = gnc.free_mask(fs, free)
        names = arc.feature_names(fs)
        assert mask.sum() == arc.N_ACT * 45 and all(
            names[i % len(names)].startswith(prefix) == bool(m) for i, m in enumerate(mask))
        assert gnc.free_mask(fs, other).sum() == arc.N_ACT * 45
        with pytest.raises(ValueError, match=f"free='{free}' needs"):
            gnc.free_mask(lacking, free)
    with pytest.raises(ValueError, match="needs a predictor"):
        gnc.train(seed=5, iterations=1, entries=[4], episode_seconds=62.0, feature_set="hq", progress=False)


def test_gated_features_start_at_zero_and_free_gated_moves_only_them(capsys):
    """From a committed Gauss–Newton policy to feature set hs: the h weights copied exactly and kept (free="gated"),
    the gated copy starts at 0 and only it moves, in the sea state trained on (the Jacobian has one column per gated
    weight); the residual-split probe names the gated part and refuses a missing file with exit 2."""
    import agents
    trained = Path(agents.__file__).parent / "trained"
    init = arc.load_policy(trained / "gn_CompensatorGains-v0_s1.npz")
    pol = gnc.train(seed=5, iterations=1, entries=[4], episode_seconds=62.0, discard=60.0, progress=False,
                    init=init, feature_set="hs", free="gated")
    assert pol.feature_set == "hs" and pol.predictor is None and pol.meta["hyperparameters"]["free"] == "gated"
    kind, moved = arc.added_features("hs")
    nh = arc.n_features("h")
    assert kind == "gated" and not moved[:nh].any() and moved[nh:].all()
    for k in pol.theta:
        assert np.array_equal(pol.theta[k][:, :nh], init.theta[k])
    (pick,) = pol.meta["curve"][0]["picks"]
    others = [x for x in pol.theta if x != pick["sea_state"]]
    assert all(not np.any(pol.theta[x][:, nh:]) for x in others)
    assert np.linalg.norm(pol.theta[pick["sea_state"]][:, nh:]) == pytest.approx(pick["step_norm"])
    # 1 episode x (90 moved weights + 1) Jacobian copies + (3 ridges + 2) line-search copies, 62 s each
    assert pol.meta["num_timesteps"] == (2 * 45 + 1 + 5) * 620
    assert arc.added_features("h")[0] == "" and not arc.added_features("h")[1].any()
    script = load_script("probe_residual_split")
    with pytest.raises(SystemExit) as ex:
        script.main(["no_such_policy.npz"])
    assert ex.value.code == 2 and "no_such_policy" in capsys.readouterr().err


def test_random_columns_move_only_the_drawn_weights():
    """``columns=K``: each iteration's Jacobian has K + 1 copies, not one per moved weight + 1, and the step moves only
    the K weights drawn for that (seed, iteration) — sorted, distinct, inside the moved set, the same draw every time,
    another draw at the next iteration; K = all moved weights is the full step."""
    sub = gnc.column_subset(90, 7, seed=5, iteration=3)
    assert len(sub) == len(set(sub)) == 7 and np.all(np.diff(sub) > 0) and 0 <= sub[0] and sub[-1] < 90
    assert np.array_equal(sub, gnc.column_subset(90, 7, seed=5, iteration=3))
    assert not np.array_equal(sub, gnc.column_subset(90, 7, seed=5, iteration=4))
    assert not np.array_equal(sub, gnc.column_subset(90, 7, seed=6, iteration=3))
    assert np.array_equal(gnc.column_subset(90, None, 5, 3), np.arange(90))
    assert np.array_equal(gnc.column_subset(90, 90, 5, 3), np.arange(90))
    import agents
    init = arc.load_policy(Path(agents.__file__).parent / "trained" / "gn_CompensatorGains-v0_s1.npz")
    pol = gnc.train(seed=5, iterations=1, entries=[4], episode_seconds=62.0, discard=60.0, progress=False,
                    init=init, feature_set="hs", free="gated", columns=5)
    assert pol.meta["hyperparameters"]["columns"] == 5
    # 1 episode x (5 drawn weights + 1) Jacobian copies + (3 ridges + 2) line-search copies, 62 s each
    assert pol.meta["num_timesteps"] == (5 + 1 + 5) * 620
    (pick,) = pol.meta["curve"][0]["picks"]
    nh = arc.n_features("h")
    moved = np.flatnonzero(gnc.free_mask("hs", "gated"))
    drawn = moved[gnc.column_subset(len(moved), 5, seed=5, iteration=pol.meta["first_iteration"])]
    for k in pol.theta:
        assert np.array_equal(pol.theta[k][:, :nh], init.theta[k])
        changed = np.flatnonzero(pol.theta[k].reshape(-1) != initial_flat(init, k, nh))
        assert set(changed) <= set(drawn)
        if k == pick["sea_state"] and pick["ridge"] is not None:
            assert len(changed) >= 1
    for bad in (0, 91, True, 5.0):
        with pytest.raises(ValueError, match="columns"):
            gnc.train(seed=5, iterations=1, entries=[4], episode_seconds=62.0, progress=False, columns=bad)
    with pytest.raises(SystemExit) as ex:
        gnc.main(["--columns", "0"])
    assert ex.value.code == 2


def initial_flat(init, key, nh):
    """``init``'s weights of sea state ``key`` in the hs layout (the gated copy at 0), flat as Θ.reshape(-1)."""
    out = np.zeros((arc.N_ACT, 2 * nh))
    out[:, :nh] = init.theta[key]
    return out.reshape(-1)


def _seed_sets():
    """(evaluation base seeds, the reserved evaluation/tuning/validation/Hover/final/teacher seeds, the ARS
    (winch, compensator), probe and WinchPayout Gauss–Newton training seeds), value by value."""
    base = [s for _, s in gym.make(COMP).unwrapped.eval_sea_states()]
    reserved = {b + off for b in base for off in list(range(0, 500, 100)) + [500, 700, 900]
                + list(range(20000, 20500, 100)) + [30000 + 100 * r for r in range(100)]}
    others = ({ars._train_seed(b, it, sd) for b in base for it in range(100) for sd in range(3)}
              | {arc._train_seed(b, it, sd) for b in base for it in range(arc.MAX_ITERATIONS) for sd in range(3)}
              | {b + off + 100 * r for b in base for off in (75000, 76000) for r in range(8)}
              | {gn.train_seed(b + 10 * r, it, sd, ls) for b in base for r in range(10)
                 for it in range(gn.MAX_ITERATIONS) for sd in range(3) for ls in (False, True)})
    return base, reserved, others


def test_wave_seeds_are_disjoint_from_every_reserved_set():
    """As agents/gn.py's test, value by value: never an evaluation, tuning, validation, Hover, final,
    clairvoyant-teacher, ARS (winch or compensator), probe or WinchPayout Gauss–Newton seed."""
    base, reserved, others = _seed_sets()
    used = set()
    for b in base:
        mine = {gnc.train_seed(b + 10 * r, it, sd, ls) for r in range(10) for it in range(gnc.MAX_ITERATIONS)
                for sd in range(3) for ls in (False, True)}
        assert len(mine) == 10 * gnc.MAX_ITERATIONS * 3 * 2
        used |= mine
    assert not used & (reserved | others)
    with pytest.raises(ValueError, match="iteration"):
        gnc.train_seed(base[0], gnc.MAX_ITERATIONS, 0)


@pytest.mark.parametrize("kw, field", [({"iterations": 0}, "iterations"), ({"eps": 0.0}, "eps"),
                                       ({"ridges": (1.0, -1.0)}, "ridge"), ({"replicates": 11}, "replicates"),
                                       ({"episode_seconds": 60.0}, "episode_seconds"), ({"entries": [12]}, "entries"),
                                       ({"hit_weight": -1.0}, "hit_weight"), ({"stop_guard": 1.5}, "stop_guard")])
def test_bad_settings_are_refused_naming_the_field(kw, field):
    with pytest.raises(ValueError, match=field):
        gnc.train(**kw)


def test_command_line_refuses_bad_arguments(capsys):
    for bad in (["--iterations", "0"], ["--eps", "-1"], ["--ridges", "0"], ["--replicates", "11"],
                ["--margin-weight", "-2"], ["--stop-guard", "2"], ["--init", "no_such_policy.npz"]):
        with pytest.raises(SystemExit) as ex:
            gnc.main(bad)
        assert ex.value.code == 2
    assert "--init" in capsys.readouterr().err
    assert str(gnc.default_export(1)) == "runs/gn_CompensatorGains-v0_s1.npz"


def test_policy_file_is_a_compensator_file_that_evaluate_names(trained, tmp_path, monkeypatch):
    f = arc.save_policy(trained, tmp_path / "gnc_test_s3.npz")
    back = arc.load_policy(f)
    assert back.meta["method"] == "gauss-newton"
    assert all(np.array_equal(back.theta[k], trained.theta[k]) for k in trained.theta)
    evaluate = load_script("evaluate")
    monkeypatch.chdir(tmp_path)
    assert evaluate.main([str(f), "--episodes", "0", "--baselines", "locked", "skyhook", "--no-plots",
                          "--env-kwargs", "episode_seconds:30", "--discard", "10"]) == 0
    text = (tmp_path / "runs" / "reports" / "gnc_test_s3" / "report.md").read_text()
    assert "Gauss-Newton policy search (the ARS compensator policy class)" in text
    assert "1 Gauss-Newton iterations" in text


def test_semiactive_clairvoyant_probe_never_keeps_a_worse_plan(capsys):
    """scripts/probe_semiactive_clairvoyant.py on a short episode: the plan starts as skyhook (0 % at the start),
    keeps a candidate only if its cost beats the current plan's on the same (deterministic) episode, so the final
    plan is never worse than skyhook in that cost; bad arguments exit 2."""
    import re
    probe = load_script("probe_semiactive_clairvoyant")
    assert probe.main(["--entries", "4", "--episode-seconds", "100", "--block", "2", "--iterations", "2"]) == 0
    out = capsys.readouterr().out
    assert len(re.findall(r"entry 4 it \d: σ_h", out)) == 2
    final = re.search(r"skyhook ([0-9.]+) m \((\d+) hits\), clairvoyant semi-active ([0-9.]+) m \((\d+) hits\): "
                      r"(-?[0-9.]+) % below skyhook", out)
    sky, sky_hits, plan, plan_hits, red = (float(x) for x in final.groups())
    # cost = ln σ + 0.3·hits + margin: the kept plan is not worse than skyhook in it
    assert math.log(plan) + 0.3 * plan_hits <= math.log(sky) + 0.3 * sky_hits + 0.01
    assert red == pytest.approx(100 * (1 - plan / sky), abs=0.11)
    for bad in (["--iterations", "0"], ["--ridges", "-1"], ["--entries", "12"], ["--episode-seconds", "65"]):
        with pytest.raises(SystemExit) as ex:
            probe.main(bad)
        assert ex.value.code == 2


def test_teacher_seeds_are_disjoint_from_every_other_set():
    """The clairvoyant teacher plans' wave seeds (+92000 + 10·replicate) are never an evaluation, final, tuning,
    validation, ARS, probe or Gauss–Newton (winch or compensator) seed, value by value; replicate 10 is refused."""
    probe = load_script("probe_semiactive_clairvoyant")
    base, reserved, others = _seed_sets()
    others |= {gnc.train_seed(b + 10 * r, it, sd, ls) for b in base for r in range(10)
               for it in range(gnc.MAX_ITERATIONS) for sd in range(3) for ls in (False, True)}
    mine = {probe.teacher_seed(b, r) for b in base for r in range(probe.MAX_REPLICATES)}
    assert len(mine) == len(base) * probe.MAX_REPLICATES
    assert not mine & (reserved | others)
    with pytest.raises(ValueError, match="replicate"):
        probe.teacher_seed(base[0], probe.MAX_REPLICATES)


def test_imitation_probe_replays_saved_plans_and_writes_an_evaluable_policy(tmp_path, capsys, monkeypatch):
    """Two short teacher plans saved by the clairvoyant probe replay to the same σ bit for bit (the replay is the
    plan), the imitation fit explains more of the plans' corrections on its own data with less ridge, and the
    written policy is an ARS compensator policy file with the picked ridge."""
    import re
    probe = load_script("probe_semiactive_clairvoyant")
    imit = load_script("probe_semiactive_imitation")
    for e in ("4", "5"):
        assert probe.main(["--entries", e, "--episode-seconds", "40", "--discard", "20", "--block", "2", "--iterations", "1",
                           "--seed-set", "teacher", "--replicate", "9", "--save-plans", str(tmp_path)]) == 0
    files = sorted(tmp_path.glob("plan_*.npz"))
    assert [f.name for f in files] == ["plan_96090.npz", "plan_96091.npz"]
    plan = probe.load_plan(files[0])
    assert plan["U"].shape == (15, 2) and plan["block"] == 20 and plan["sea"].hs == pytest.approx(1.88)
    capsys.readouterr()
    out_file = tmp_path / "imitation.npz"
    assert imit.main(["--plans", str(tmp_path), "--entries", "4", "--ridges", "0.01", "1",
                      "--out", str(out_file)]) == 0
    out = capsys.readouterr().out
    assert "reproduces the plans' σ to 0.0e+00" in out
    fit = [float(x) for x in re.findall(r"λ [0-9.]+: R² (-?[0-9.]+)", out)]
    assert len(fit) == 2 and fit[0] >= fit[1] > 0.0
    pol = arc.load_policy(out_file)
    assert pol.meta["trainer"] == "probe_semiactive_imitation" and pol.meta["ridge"] in (0.01, 1.0)
    assert set(pol.theta) == {"hs1.88_tp5.90"}
    evaluate = load_script("evaluate")
    monkeypatch.chdir(tmp_path)
    assert evaluate.main([str(out_file), "--episodes", "0", "--baselines", "locked", "--no-plots",
                          "--env-kwargs", "episode_seconds:30", "--discard", "10"]) == 0
    text = (tmp_path / "runs" / "reports" / "imitation" / "report.md").read_text()
    assert "imitation of clairvoyant semi-active teacher plans (the ARS compensator policy class" in text
    assert "2 plans" in text
    capsys.readouterr()
    # a plan on top of the imitation policy stores its residual and replays to the same σ as well
    assert probe.main(["--entries", "6", "--episode-seconds", "40", "--discard", "20", "--block", "2", "--iterations", "1",
                       "--seed-set", "teacher", "--replicate", "8", "--save-plans", str(tmp_path),
                       "--base-policy", str(out_file)]) == 0
    assert "below base policy" in capsys.readouterr().out
    np.testing.assert_array_equal(probe.load_plan(tmp_path / "plan_96082.npz")["theta_base"],
                                  pol.theta["hs1.88_tp5.90"])
    assert imit.main(["--plans", str(tmp_path), "--entries", "4", "--ridges", "1"]) == 0
    assert "reproduces the plans' σ to 0.0e+00" in capsys.readouterr().out
    for bad in (["--plans", str(tmp_path / "none")], ["--ridges", "0"]):
        with pytest.raises(SystemExit) as ex:
            imit.main(bad)
        assert ex.value.code == 2


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_committed_gauss_newton_policies_ship_load_and_act(seed):
    """The three committed Gauss–Newton compensator policies (docs/agents.md) are package data of the installed
    ``agents``, carry their recipe (6 iterations, 2 replicates, ridges 0.01…100, from ARS seed 0, its stop guard
    0.9), differ from their ARS start in every sea state (the line search kept steps everywhere) and act inside the
    action box, not as the ARS policy does."""
    import agents
    from agents.baselines import load_tuned
    pol = arc.load_policy(Path(agents.__file__).parent / "trained" / f"gn_CompensatorGains-v0_s{seed}.npz")
    hp = pol.meta["hyperparameters"]
    assert pol.meta["method"] == "gauss-newton" and (pol.meta["seed"], pol.meta["iterations"]) == (seed, 6)
    assert (hp["replicates"], hp["ridges"], hp["init"]) == (2, [0.01, 0.1, 1.0, 10.0, 100.0],
                                                            "ars_CompensatorGains-v0_s0")
    init = _committed(0)
    assert pol.stop_guard == init.stop_guard == 0.9 and pol.base_table == init.base_table
    assert set(pol.theta) == set(load_tuned()["skyhook"])
    assert all(np.abs(pol.theta[k] - init.theta[k]).max() > 1e-3 for k in pol.theta)
    _assert_acts_in_box_and_unlike(pol, init)


def _assert_acts_in_box_and_unlike(pol, other):
    """``pol`` run on a 20 s code-5 episode gives finite gains inside the action box's map, and not those of
    ``other`` on the same episode."""
    from agents.metrics import rollout
    env = gym.make(COMP, episode_seconds=20.0)
    try:
        sea, s = env.unwrapped.eval_sea_states()[9]
        rec = [rollout(env, p.bind_env(env), sea, s + 123456) for p in (pol, other)]
        k_lo, k_hi = env.unwrapped.stiffness_range[:2]
        b_lo, b_hi = env.unwrapped.damping_range[:2]
    finally:
        env.close()
    k, b = rec[0].data["stiffness"], rec[0].data["damping"]
    assert np.all(np.isfinite(k)) and np.all(np.isfinite(b)) and len(k) == len(rec[1].data["stiffness"])
    assert np.all((k >= k_lo * (1 - 1e-9)) & (k <= k_hi * (1 + 1e-9)))       # inside the action box's map
    assert np.all((b >= b_lo * (1 - 1e-9)) & (b <= b_hi * (1 + 1e-9)))
    assert not (np.allclose(k, rec[1].data["stiffness"]) and np.allclose(b, rec[1].data["damping"]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_continued_gauss_newton_policies_carry_their_recipe_and_act(seed):
    """The continued compensator policies (``gn2``, docs/agents.md) are package data, record their recipe (6 more
    iterations, numbered 6-11, 2 replicates, ridges 0.01…100, from the ``gn`` file of the same seed, its stop guard
    0.9) and act inside the action box, not as the policy they continue."""
    import agents
    base = Path(agents.__file__).parent / "trained"
    pol = arc.load_policy(base / f"gn2_CompensatorGains-v0_s{seed}.npz")
    init = arc.load_policy(base / f"gn_CompensatorGains-v0_s{seed}.npz")
    hp = pol.meta["hyperparameters"]
    assert pol.meta["method"] == "gauss-newton" and pol.meta["seed"] == seed
    assert (pol.meta["first_iteration"], pol.meta["iterations"]) == (6, 6)
    assert (hp["replicates"], hp["ridges"], hp["init"]) == (2, [0.01, 0.1, 1.0, 10.0, 100.0],
                                                            f"gn_CompensatorGains-v0_s{seed}")
    assert pol.stop_guard == init.stop_guard == 0.9 and pol.base_table == init.base_table
    _assert_acts_in_box_and_unlike(pol, init)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_predicted_preview_policies_carry_their_recipe_and_act(seed):
    """The compensator policies with the predicted preview (``gnq``, feature set hq, docs/agents.md) are package data,
    record their recipe (iterations from 6 on, 2 replicates, ridges 0.01…100, only the predicted features' weights
    moved, from the ``gn`` file of the same seed), carry the committed compensator predictor, keep every other weight
    of ``gn`` exactly, and act inside the action box, not as ``gn`` does."""
    import agents
    from agents.predictor import COMP_PRED_CHANNELS, Predictor
    base = Path(agents.__file__).parent / "trained"
    pol = arc.load_policy(base / f"gnq_CompensatorGains-v0_s{seed}.npz")
    init = arc.load_policy(base / f"gn_CompensatorGains-v0_s{seed}.npz")
    pred = Predictor.load(base / "predictor_CompensatorGains-v0.npz")
    hp = pol.meta["hyperparameters"]
    assert pol.meta["method"] == "gauss-newton" and pol.meta["seed"] == seed and pol.feature_set == "hq"
    assert pol.meta["first_iteration"] == 6 and pol.meta["iterations"] >= 1
    assert (hp["replicates"], hp["ridges"], hp["init"], hp["free"]) == (
        2, [0.01, 0.1, 1.0, 10.0, 100.0], f"gn_CompensatorGains-v0_s{seed}", "predicted")
    assert pol.predictor.channels == COMP_PRED_CHANNELS
    assert all(np.array_equal(pol.predictor.W[k], pred.W[k]) for k in pred.W) and sorted(pol.predictor.W) == sorted(pred.W)
    names = arc.feature_names("hq")
    keep = [names.index(n) for n in arc.feature_names("h")]
    assert all(np.array_equal(pol.theta[k][:, keep], init.theta[k]) for k in init.theta)
    assert pol.stop_guard == init.stop_guard == 0.9 and pol.base_table == init.base_table
    _assert_acts_in_box_and_unlike(pol, init)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_skyhook_gated_policies_carry_their_recipe_and_act(seed):
    """The compensator policies with the skyhook-gated copy of the features (``gns``, feature set hs, docs/agents.md)
    are package data, record their recipe (4 iterations from 6 on, 2 replicates, ridges 0.01…100, only the gated
    copy's weights moved, from the ``gn`` file of the same seed), keep every ``gn`` weight exactly (the ungated copy),
    moved some gated weights, and act inside the action box, not as ``gn`` does."""
    import agents
    base = Path(agents.__file__).parent / "trained"
    pol = arc.load_policy(base / f"gns_CompensatorGains-v0_s{seed}.npz")
    init = arc.load_policy(base / f"gn_CompensatorGains-v0_s{seed}.npz")
    hp = pol.meta["hyperparameters"]
    assert pol.meta["method"] == "gauss-newton" and pol.meta["seed"] == seed and pol.feature_set == "hs"
    assert pol.meta["first_iteration"] == 6 and pol.meta["iterations"] == 4 and pol.predictor is None
    assert (hp["replicates"], hp["ridges"], hp["init"], hp["free"]) == (
        2, [0.01, 0.1, 1.0, 10.0, 100.0], f"gn_CompensatorGains-v0_s{seed}", "gated")
    nh = arc.n_features("h")
    assert all(np.array_equal(pol.theta[k][:, :nh], init.theta[k]) for k in init.theta)
    assert any(np.any(pol.theta[k][:, nh:] != 0) for k in pol.theta)
    assert pol.stop_guard == init.stop_guard == 0.9 and pol.base_table == init.base_table
    _assert_acts_in_box_and_unlike(pol, init)


def test_predictor_fit_seeds_are_disjoint_from_every_other_set():
    """The predictors' fitting episodes (WinchPayout and CompensatorGains: the same values) (agents/predictor.py, +97000 + 10·replicate) are never an
    evaluation, final, tuning, validation, ARS, probe, Gauss–Newton (winch or compensator) or teacher seed, value by
    value; replicate 10 is refused."""
    from agents import predictor
    probe = load_script("probe_semiactive_clairvoyant")
    base, reserved, others = _seed_sets()
    others |= {gnc.train_seed(b + 10 * r, it, sd, ls) for b in base for r in range(10)
               for it in range(gnc.MAX_ITERATIONS) for sd in range(3) for ls in (False, True)}
    others |= {probe.teacher_seed(b, r) for b in base for r in range(probe.MAX_REPLICATES)}
    mine = {predictor.predictor_seed(b, r) for b in base for r in range(predictor.MAX_REPLICATES)}
    assert len(mine) == len(base) * predictor.MAX_REPLICATES
    assert not mine & (reserved | others)
    with pytest.raises(ValueError, match="replicate"):
        predictor.predictor_seed(base[0], predictor.MAX_REPLICATES)


def test_residual_split_probe_separates_the_predicted_part():
    """scripts/probe_residual_split.py: on a committed hq policy it reports, per sea state, a finite RMS of the
    predicted features' part of the residual (non-zero somewhere: the search moved some of those weights) and a
    non-zero one of the rest (the gn weights); the same for the gated copy of a committed hs policy; a policy without
    added features is refused naming the sets."""
    import agents
    script = load_script("probe_residual_split")
    base = Path(agents.__file__).parent / "trained"
    res = script.residual_split(base / "gnq_CompensatorGains-v0_s1.npz", episode_seconds=64.0, discard=60.0)
    assert sorted(res) == [3, 4, 5]
    for p, r in res.values():
        assert p.shape == r.shape == (2,) and np.all(np.isfinite(p)) and np.all(r > 0)
    assert any(np.any(p > 0) for p, _r in res.values())          # the search moved some predicted weights
    gated = script.residual_split(base / "gns_CompensatorGains-v0_s1.npz", episode_seconds=64.0, discard=60.0)
    assert sorted(gated) == [3, 4, 5] and any(np.any(p > 0) for p, _r in gated.values())
    with pytest.raises(ValueError, match="need hq or hs"):
        script.residual_split(base / "gn_CompensatorGains-v0_s1.npz", episode_seconds=64.0)


@pytest.mark.parametrize("argv, msg", [
    (["--features", "hq"], "needs a predictor"),
    (["--free", "predicted"], "free='predicted' needs"),
    (["--predictor", "no/such/predictor.npz"], "--predictor: no/such/predictor.npz: not a predictor file"),
    (["--features", "hq", "--predictor", "WINCH"], "not the towenv/CompensatorGains-v0 predictor's"),
    (["--features", "hq", "--predictor", "COMP", "--entries", "12"], "entries must be indices in 0..11"),
])
def test_cli_refuses_bad_preview_options_naming_the_field(argv, msg, capsys):
    """Bad feature-set / predictor / free / entries options end in a usage error (exit 2) naming the field, before
    any episode runs."""
    import agents
    trained = Path(agents.__file__).parent / "trained"
    files = {"WINCH": str(trained / "predictor_WinchPayout-v0.npz"),
             "COMP": str(trained / "predictor_CompensatorGains-v0.npz")}
    argv = [files.get(x, x) for x in argv]
    with pytest.raises(SystemExit) as ex:
        gnc.main(argv + ["--iterations", "1"])
    assert ex.value.code == 2
    assert msg in capsys.readouterr().err


def test_parallel_search_gives_the_serial_result(trained):
    """``parallel=True`` only changes the wall time: the same Gauss–Newton iteration gives the same weights bit for
    bit (the committed chain re-run with --parallel reproduces its files; docs/agents.md)."""
    par = gnc.train(seed=3, iterations=1, entries=[0, 4], episode_seconds=62.0, discard=60.0, progress=False,
                    parallel=True)
    assert par.meta["parallel"] is True and trained.meta["parallel"] is False
    assert all(np.array_equal(par.theta[k], trained.theta[k]) for k in trained.theta)
    assert [p["picks"] for p in par.meta["curve"]] == [p["picks"] for p in trained.meta["curve"]]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rerun_chain_files_carry_the_gns_recipe(seed):
    """The `gns` chain re-run with --parallel (``arsp`` → ``gnp`` → ``gnsp``, docs/agents.md "The same chain within the
    hour") is package data under its renamed family names: the recipe of ARS seed 0 (55 iterations, stop guard 0.9),
    Gauss–Newton (6 iterations from it) and the gated continuation (4 from 6 on) recorded, each run parallel, the
    ``--init`` chain resolvable by scripts/training_cost.py, the gated step on top of the ``gnp`` weights, and
    different weights from the committed ``gns`` chain (another ARS start)."""
    import agents
    base = Path(agents.__file__).parent / "trained"
    ars = arc.load_policy(base / "arsp_CompensatorGains-v0_s0.npz")
    gn = arc.load_policy(base / f"gnp_CompensatorGains-v0_s{seed}.npz")
    gns = arc.load_policy(base / f"gnsp_CompensatorGains-v0_s{seed}.npz")
    assert ars.meta["iterations"] == 55 and ars.stop_guard == 0.9 and ars.meta["parallel"] is True
    assert gn.meta["iterations"] == 6 and gn.meta["hyperparameters"]["init"] == "arsp_CompensatorGains-v0_s0"
    assert (gns.meta["first_iteration"], gns.meta["iterations"], gns.feature_set) == (6, 4, "hs")
    assert gns.meta["hyperparameters"]["init"] == f"gnp_CompensatorGains-v0_s{seed}"
    assert gn.meta["parallel"] is True and gns.meta["parallel"] is True and gns.meta["seed"] == seed
    assert gns.meta["renamed_from"] == f"gns_CompensatorGains-v0_s{seed}"
    nh = arc.n_features("h")
    assert all(np.array_equal(gns.theta[k][:, :nh], gn.theta[k]) for k in gn.theta)
    committed = arc.load_policy(base / "ars_CompensatorGains-v0_s0.npz")
    assert not all(np.array_equal(ars.theta[k], committed.theta[k]) for k in ars.theta)
    cost = load_script("training_cost")
    runs = cost.chain(base / f"gnsp_CompensatorGains-v0_s{seed}.npz")
    assert [r[0] for r in runs] == ["arsp_CompensatorGains-v0_s0", f"gnp_CompensatorGains-v0_s{seed}",
                                    f"gnsp_CompensatorGains-v0_s{seed}"]
    assert sum(r[2] for r in runs) == 63_720_000


@pytest.mark.parametrize("family, parent, fs, free", [("gnsf", "gns", "hsf", "fish"), ("gnspf", "gnsp", "hsf", "fish"),
                                                      ("gnsfo", "gnsf", "hsfo", "outward"),
                                                      ("gnspfr", "gnspf", "hsfo", "outward")])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_gated_continuations_carry_their_recipe_and_act(seed, family, parent, fs, free):
    """The compensator headline since 2026-12-07 (``gnsfo``, feature set hsfo, docs/agents.md "A third gate"), the one
    before it (``gnsf``, hsf, "A second gate"), the one-hour recipe's fish-gated stage (``gnspf``, from ``gnsp``) and
    its outward-gated stage of 30 random Jacobian columns per iteration (``gnspfr``, chain under an hour) are
    package data: the recipe recorded (the parent's iteration count continued, 2 replicates, ridges 0.01…100, only
    the newest gated copy's weights moved, from the parent file of the same seed, its stop guard 0.9), every parent
    weight kept exactly, some new weights moved, and the policy acts inside the action box, not as its parent does."""
    import agents
    base = Path(agents.__file__).parent / "trained"
    pol = arc.load_policy(base / f"{family}_CompensatorGains-v0_s{seed}.npz")
    init = arc.load_policy(base / f"{parent}_CompensatorGains-v0_s{seed}.npz")
    hp = pol.meta["hyperparameters"]
    assert pol.meta["method"] == "gauss-newton" and pol.meta["seed"] == seed and pol.feature_set == fs
    assert pol.meta["first_iteration"] == init.meta["first_iteration"] + init.meta["iterations"]
    assert pol.meta["iterations"] >= 1
    assert (hp["replicates"], hp["ridges"], hp["init"], hp["free"]) == (
        2, [0.01, 0.1, 1.0, 10.0, 100.0], f"{parent}_CompensatorGains-v0_s{seed}", free)
    n_parent = arc.n_features(init.feature_set)
    assert arc.feature_names(fs)[:n_parent] == arc.feature_names(init.feature_set)
    assert np.array_equal(gnc.free_mask(fs, free).reshape(arc.N_ACT, -1)[0], np.arange(arc.n_features(fs)) >= n_parent)
    assert all(np.array_equal(pol.theta[k][:, :n_parent], init.theta[k]) for k in init.theta)
    assert any(np.any(pol.theta[k][:, n_parent:] != 0.0) for k in pol.theta)
    assert pol.stop_guard == init.stop_guard == 0.9 and pol.base_table == init.base_table
    _assert_acts_in_box_and_unlike(pol, init)
    # the 30-random-column stage (docs/agents.md "Cheaper Gauss–Newton steps within the hour"): its chain, from the
    # shared ARS start, fits in the hour of iterations (scripts/training_cost.py)
    assert hp.get("columns") == (30 if family == "gnspfr" else None)
    if family == "gnspfr":
        runs = load_script("training_cost").chain(base / f"{family}_CompensatorGains-v0_s{seed}.npz")
        assert [r[0].split("_")[0] for r in runs] == ["arsp", "gnp", "gnsp", "gnspf", "gnspfr"]
        assert sum(r[1] for r in runs) < 3600.0


def _shared_setup(n_w, reps, seconds=8.0):
    from towenv.envs.vector import CompensatorGainsVectorEnv
    import agents
    pol = arc.load_policy(Path(agents.__file__).parent / "trained" / "gnspfr_CompensatorGains-v0_s1.npz")
    kw = dict(autoreset_mode="NextStep", batch_infos=True, episode_seconds=seconds)
    ev = gym.make(COMP).unwrapped.eval_sea_states()
    ents = [ev[4], ev[9]][:n_w]
    seas, seeds = [s for s, _ in ents], [int(w) + 77 for _, w in ents]
    theta = np.array([pol.theta[arc.nearest_key(pol.theta, s)] for s in seas])
    envs = [CompensatorGainsVectorEnv(num_envs=n, **kw) for n in (n_w, n_w * reps, n_w * reps)]
    batches = [arc._Batch(v, pol.base_table, pol.scales, pol.feature_set) for v in envs]
    return pol, seas, seeds, theta, envs, batches


def test_a_shared_warmup_rollout_is_the_plain_rollout_under_the_warmup_weights_bit_for_bit():
    """``arc.rollout_series_shared``: with every copy keeping its episode's warm-up weights the result is
    ``rollout_series`` of all copies from the start, bit for bit (fish heave, pitch, stroke, times, hits, ended) —
    the warm-up loaded into the copies (env state and the features' history rings, here the `hsfo` policy's) is
    their own continuation; with other weights after the warm-up, the shared rows are the warm-up's and the rest
    differs."""
    pol, seas, seeds, theta, (vw, vs, vp), (bw, bs, bp) = _shared_setup(2, 3)
    T, warm = vw.envs[0].max_steps, 37
    tiled = np.concatenate([theta] * 3)
    plain = arc.rollout_series(vp, bp, seas * 3, seeds * 3, tiled, stop_guard=pol.stop_guard)
    shared = arc.rollout_series_shared(vw, bw, vs, bs, seas, seeds, theta, tiled, warm, stop_guard=pol.stop_guard)
    for a, b in zip(plain[:6], shared[:6]):
        assert np.array_equal(a, b)
    other = tiled.copy()
    other[2:] += 0.05                                   # copies 2-5 (both episodes) another policy after the warm-up
    br = arc.rollout_series_shared(vw, bw, vs, bs, seas, seeds, theta, other, warm, stop_guard=pol.stop_guard)
    H, Hp = br[0], plain[0]
    assert np.array_equal(H[:, :2], Hp[:, :2])         # copies 0, 1 kept the warm-up weights
    assert np.array_equal(H[:warm], Hp[:warm])          # the shared rows
    assert not np.array_equal(H[warm + 5:, 2:], Hp[warm + 5:, 2:])
    assert T > warm
    with pytest.raises(ValueError, match="warm_steps"):
        arc.rollout_series_shared(vw, bw, vs, bs, seas, seeds, theta, tiled, T)
    with pytest.raises(ValueError, match="one \\(sea, seed\\) per warm-up copy"):
        arc.rollout_series_shared(vw, bw, vs, bs, seas[:1], seeds[:1], theta, tiled, warm)
    for v in (vw, vs, vp):
        v.close()


def test_shared_warmup_search_shares_only_unscored_rows_and_counts_its_steps():
    """``shared_warmup=True``: the Jacobian episodes' first ``warmup_steps`` control steps (every row before the
    scored window — 599 of 620 at 62 s scored after 60 s) run once per episode; the step count says so, the recipe is
    in the metadata, and the line search still keeps only improving steps."""
    assert gnc.warmup_steps(620, 0.1, 60.0) == 599
    assert gnc.warmup_steps(1800, 0.1, 60.0) == 599
    assert gnc.warmup_steps(620, 0.1, 0.0) == 0 and gnc.warmup_steps(620, 0.1, 100.0) == 619
    pol = gnc.train(seed=3, iterations=1, entries=[4], episode_seconds=62.0, discard=60.0, progress=False,
                    shared_warmup=True, columns=4)
    hp = pol.meta["hyperparameters"]
    assert hp["shared_warmup"] is True and hp["warmup_steps"] == 599
    # 1 episode: 599 shared steps once + (4 + 1) copies x 21 steps, and (3 ridges + 2) line-search copies x 620
    assert pol.meta["num_timesteps"] == 599 + 5 * 21 + 5 * 620
    for p in pol.meta["curve"][0]["picks"]:
        assert p["cost_after"] <= p["cost_current"]
    with pytest.raises(SystemExit) as ex:
        gnc.main(["--shared-warmup", "--iterations", "0"])
    assert ex.value.code == 2


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_shared_warmup_chains_carry_their_recipe_and_fit_the_hour(seed):
    """``gnw`` → ``gnws`` → ``gnwsf`` → ``gnwsfo`` seeds 0, 1 and 2 (docs/agents.md "The headline's stages within the hour"): the
    headline ``gnsfo``'s stage structure from the shared ARS start (``arsp`` seed 0), every stage with the shared
    warm-up (599 shared control steps), each gated stage keeping its parent's weights and moving only its own copy's,
    the chain under an hour of iterations (scripts/training_cost.py), and the last stage acting in the action box."""
    import agents
    base = Path(agents.__file__).parent / "trained"
    stages = [("gnw", "arsp", "h", "all"), ("gnws", "gnw", "hs", "gated"), ("gnwsf", "gnws", "hsf", "fish"),
              ("gnwsfo", "gnwsf", "hsfo", "outward")]
    for family, parent, fs, free in stages:
        pol = arc.load_policy(base / f"{family}_CompensatorGains-v0_s{seed}.npz")
        parent_stem = f"{parent}_CompensatorGains-v0_s{0 if parent == 'arsp' else seed}"
        init = arc.load_policy(base / f"{parent_stem}.npz")
        hp = pol.meta["hyperparameters"]
        assert pol.meta["method"] == "gauss-newton" and pol.meta["seed"] == seed and pol.feature_set == fs
        assert (hp["shared_warmup"], hp["warmup_steps"], hp["free"], hp["replicates"], hp["columns"]) == (
            True, 599, free, 2, None)
        assert hp["init"] == parent_stem and pol.meta["parallel"] is True
        assert pol.stop_guard == init.stop_guard == 0.9
        if free != "all":
            n_parent = arc.n_features(init.feature_set)
            assert all(np.array_equal(pol.theta[k][:, :n_parent], init.theta[k]) for k in init.theta)
            assert any(np.any(pol.theta[k][:, n_parent:] != 0.0) for k in pol.theta)
    runs = load_script("training_cost").chain(base / f"gnwsfo_CompensatorGains-v0_s{seed}.npz")
    assert [r[0].split("_")[0] for r in runs] == ["arsp", "gnw", "gnws", "gnwsf", "gnwsfo"]
    assert sum(r[1] for r in runs) < 3600.0
    _assert_acts_in_box_and_unlike(pol, init)
