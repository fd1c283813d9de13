"""ARS linear residual over the skyhook law (issue 14, agents/ars_compensator.py): Θ = 0 is the skyhook law, the
deployable single-environment policy acts exactly as the batched training rollout, it is causal, its file
round-trips (and scripts/evaluate.py tells the ARS files apart by their metadata), the stroke-margin cost term of
the batched rollout is the single env's, the optional stop guard acts exactly where its condition holds (and the
same in both), training seeds are disjoint from every other seed set, and a tiny training runs on the batched
vector env."""
from __future__ import annotations

import json

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

pytest.importorskip("towenv")                  # registers the ids
from agents import ars, ars_compensator as AC  # noqa: E402
from agents.baselines import load_tuned, make_baseline  # noqa: E402
from agents.common import nearest_key  # noqa: E402
from agents.metrics import rollout  # noqa: E402
from helpers import load_script  # noqa: E402

COMP = "towenv/CompensatorGains-v0"
SECONDS = 30.0
DISCARD = 10.0


def _predictor():
    """The committed predictor of the compensator's tow-point motion (feature set hq)."""
    from pathlib import Path

    import agents
    from agents.predictor import Predictor
    return Predictor.load(Path(agents.__file__).parent / "trained" / "predictor_CompensatorGains-v0.npz")


def _policy(scale=0.05, seed=0, fs="h"):
    """A policy with random weights on the tuned skyhook table (scale 0.05 moves the gains noticeably); feature set
    ``fs`` (hq: with the committed predictor)."""
    table = load_tuned()["skyhook"]
    rng = np.random.default_rng(seed)
    theta = {k: rng.normal(0.0, scale, (AC.N_ACT, AC.n_features(fs))) for k in table}
    return AC.ARSCompensatorPolicy(theta, table, meta={"seed": seed, "iterations": 0, "feature_set": fs},
                                   predictor=_predictor() if fs in AC.PREDICTED else None)


@pytest.fixture(scope="module")
def env():
    e = gym.make(COMP, episode_seconds=SECONDS)
    yield e
    e.close()


def _actions(env, pol, sea, seed, steps=None, obs_hook=None):
    obs, _ = env.reset(seed=seed, options={"sea_state": sea, "sea_seed": seed})
    out = []
    for k in range(steps or env.unwrapped.max_steps):
        a, _ = pol.predict(obs, episode_start=np.array([k == 0]))
        out.append(np.array(a, np.float32))
        obs, _r, term, trunc, _ = env.step(a)
        if term or trunc:
            break
    return np.array(out)


def test_zero_weights_are_the_skyhook_law(env):
    pol = _policy(scale=0.0).bind_env(env)
    sea, seed = env.unwrapped.eval_sea_states()[9]
    a = rollout(env, pol, sea, seed + 123456)
    b = rollout(env, make_baseline("skyhook", env), sea, seed + 123456)
    for k in ("heave", "pitch", "stiffness", "damping", "stroke"):
        assert np.array_equal(a.data[k], b.data[k]), k


@pytest.mark.parametrize("fs", ["h", "hq", "hs", "hst", "hsf", "hsfo"])
def test_single_env_policy_equals_the_batched_training_rollout(env, fs):
    """The policy trained on the vector env is the one evaluated on single envs: same actions (1e-9), same σ, the
    same end-stop hits and the same stroke-margin term (from the ``comp_stroke`` observation, which is the true
    stroke / half stroke of the simulator to float32 precision); with the predicted features too (hq) and the
    skyhook-gated copy (hs)."""
    from towenv.envs.vector import CompensatorGainsVectorEnv
    pol = _policy(scale=0.05, fs=fs).bind_env(env)
    ev = env.unwrapped.eval_sea_states()
    picks = [0, 6, 11]                                  # one entry per sea state
    seas = [ev[i][0] for i in picks]
    seeds = [ev[i][1] + 123456 for i in picks]
    venv = CompensatorGainsVectorEnv(num_envs=3, autoreset_mode="NextStep", batch_infos=True,
                                     episode_seconds=SECONDS)
    batch = AC._Batch(venv, pol.base_table, pol.scales, fs, pol.predictor)
    theta = np.array([pol.theta[nearest_key(pol.theta, s)] for s in seas])
    m0 = 0.2                                            # low enough for a non-zero term in 30 s episodes
    sh, sp, hits, mg, acts = AC.rollout_batch(venv, batch, seas, seeds, theta, discard=DISCARD, record_actions=True,
                                              margin_start=m0)
    venv.close()
    assert np.all(mg > 0)
    reader = pol.reader
    for i, (sea, s) in enumerate(zip(seas, seeds)):
        single = _actions(env, pol, sea, s)
        assert single.shape == acts[:, i].shape
        np.testing.assert_allclose(single, acts[:, i], rtol=0, atol=1e-9)
        rec = rollout(env, pol, sea, s)
        w = rec.data["t"] >= DISCARD
        assert rec.data["heave"][w].std() == pytest.approx(sh[i], rel=1e-9, abs=1e-12)
        assert np.degrees(rec.data["pitch"][w].std()) == pytest.approx(sp[i], rel=1e-9, abs=1e-12)
        assert rec.data["hits"][-1] == hits[i]
        # the margin term from the single env's observations after every step, over the same window
        obs, _ = env.reset(seed=s, options={"sea_state": sea, "sea_seed": s})
        pol.reset()
        strokes, ts = [], []
        for k in range(env.unwrapped.max_steps):
            a, _ = pol.predict(obs, episode_start=np.array([k == 0]))
            obs, _r, term, trunc, info = env.step(a)
            strokes.append(reader(obs, "comp_stroke"))
            ts.append(info["t"])
        ts = np.array(ts)
        assert np.array_equal(ts, rec.data["t"])
        single_m = AC.margin_penalty(np.array(strokes)[ts >= DISCARD], m0).mean()
        assert single_m == pytest.approx(mg[i], rel=1e-9, abs=1e-15)
        true_m = AC.margin_penalty(rec.data["stroke"][w] / rec.half_stroke, m0).mean()
        assert true_m == pytest.approx(mg[i], rel=1e-4)
    # and the weights matter: the residual changes the actions away from skyhook
    sky = _actions(env, make_baseline("skyhook", env), seas[1], seeds[1])
    assert np.max(np.abs(sky - acts[:, 1])) > 1e-3


def test_stop_guard_acts_exactly_where_its_condition_holds(env):
    """With the guard on, Θ = 0 gives the skyhook action on every step where the guard condition (|s| > g, s·ṡ > 0,
    read from the observation) is false, and (1, 1) where it holds: it differs from skyhook exactly on the guarded
    steps where skyhook does not already command (1, 1). The batched rollout with the guard acts the same."""
    from towenv.envs.vector import CompensatorGainsVectorEnv
    g = 0.3                                             # low enough to act often in a 30 s code-5 episode
    table = load_tuned()["skyhook"]
    pol = AC.ARSCompensatorPolicy({k: np.zeros((AC.N_ACT, AC.N_FEATURES)) for k in table}, table,
                                  meta={"stop_guard": g}).bind_env(env)
    sky = make_baseline("skyhook", env)
    sea, seed = env.unwrapped.eval_sea_states()[11]
    seed += 123456
    obs, _ = env.reset(seed=seed, options={"sea_state": sea, "sea_seed": seed})
    A, S, M = [], [], []
    for k in range(env.unwrapped.max_steps):
        start = np.array([k == 0])
        a, _ = pol.predict(obs, episode_start=start)
        b, _ = sky.predict(obs, episode_start=start)
        s, sd = pol.reader(obs, "comp_stroke"), pol.reader(obs, "comp_stroke_vel")
        assert AC.stop_guard_mask(pol.reader, np.asarray(obs)[None], g)[0] == (abs(s) > g and s * sd > 0)
        A.append(np.array(a))
        S.append(np.array(b))
        M.append(abs(s) > g and s * sd > 0)
        obs, _r, term, trunc, _ = env.step(a)
        assert not term and (not trunc or k == env.unwrapped.max_steps - 1)
    A, S, M = np.array(A), np.array(S), np.array(M)
    assert 0 < M.sum() < len(M)
    assert np.array_equal(A[~M], S[~M])
    assert np.all(A[M] == 1.0)
    differs = np.any(A != S, axis=1)
    assert np.array_equal(differs, M & np.any(S != 1.0, axis=1)) and differs.any()
    # the batched rollout with the guard: the same actions
    venv = CompensatorGainsVectorEnv(num_envs=1, autoreset_mode="NextStep", batch_infos=True,
                                     episode_seconds=SECONDS)
    batch = AC._Batch(venv, table, pol.scales)
    *_, acts = AC.rollout_batch(venv, batch, [sea], [seed], np.zeros((1, AC.N_ACT, AC.N_FEATURES)),
                                discard=DISCARD, record_actions=True, stop_guard=g)
    venv.close()
    np.testing.assert_allclose(acts[:, 0], A, rtol=0, atol=1e-9)
    # off by default and for old files without the key
    assert AC.ARSCompensatorPolicy({k: np.zeros((AC.N_ACT, AC.N_FEATURES)) for k in table}, table).stop_guard == 0.0
    with pytest.raises(ValueError, match="stop_guard"):
        AC.ARSCompensatorPolicy({}, table, meta={"stop_guard": 1.5})


@pytest.mark.parametrize("fs", ["h", "hq", "hs", "hst", "hsf", "hsfo"])
def test_policy_is_causal(env, fs):
    """Actions depend only on the observations handed to predict() (and the sea-state estimate): a replay of the
    recorded observations to a fresh policy bound to an env in an unrelated state gives the same actions, and
    changing a *later* observation leaves the earlier actions unchanged (hq: its predicted preview too)."""
    pol = _policy(scale=0.05, fs=fs).bind_env(env)
    sea, seed = env.unwrapped.eval_sea_states()[6]
    obs, _ = env.reset(seed=seed, options={"sea_state": sea, "sea_seed": seed})
    seq, acts = [], []
    for k in range(60):
        a, _ = pol.predict(obs, episode_start=np.array([k == 0]))
        seq.append(obs.copy())
        acts.append(a.copy())
        obs, *_ = env.step(a)
    other = gym.make(COMP, episode_seconds=SECONDS)
    other.reset(seed=seed + 1, options={"sea_state": sea, "sea_seed": seed + 1})
    for _ in range(17):
        other.step(np.array([0.3, -0.2], np.float32))
    replay = _policy(scale=0.05, fs=fs).bind_env(other)
    again = [replay.predict(o, episode_start=np.array([k == 0]))[0] for k, o in enumerate(seq)]
    assert all(np.array_equal(x, y) for x, y in zip(acts, again))
    changed = [o.copy() for o in seq]
    changed[40] = changed[40] + 0.5
    replay2 = _policy(scale=0.05, fs=fs).bind_env(other)
    alt = [replay2.predict(o, episode_start=np.array([k == 0]))[0] for k, o in enumerate(changed)]
    assert all(np.array_equal(x, y) for x, y in zip(acts[:40], alt[:40]))
    assert not np.array_equal(acts[40], alt[40])
    other.close()


def test_policy_file_round_trip_and_refusal(tmp_path, env):
    pol = _policy(scale=0.01, seed=3)
    pol.meta["stop_guard"] = pol.stop_guard = 0.9
    f = AC.save_policy(pol, tmp_path / "p.npz")
    back = AC.load_policy(f)
    assert back.stop_guard == 0.9 and back.meta["stop_guard"] == 0.9
    assert sorted(back.theta) == sorted(pol.theta)
    assert all(np.array_equal(back.theta[k], pol.theta[k]) for k in pol.theta)
    assert back.base_table == json.loads(json.dumps(pol.base_table))
    assert back.scales == pol.scales
    assert back.meta["algo"] == AC.ALGO and back.meta["env_id"] == COMP
    # the same actions after the round trip
    sea, seed = env.unwrapped.eval_sea_states()[3]
    assert np.array_equal(_actions(env, pol.bind_env(env), sea, seed, 50),
                          _actions(env, back.bind_env(env), sea, seed, 50))
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(ValueError, match="not an ARS policy"):
        AC.load_policy(tmp_path / "other.npz")
    # a WinchPayout ARS file is refused by this loader, and this file by the WinchPayout one
    table = load_tuned()["along_cable"]
    wf = ars.save_policy(ars.ARSPolicy({k: np.zeros(ars.N_FEATURES) for k in table}, table), tmp_path / "w.npz")
    with pytest.raises(ValueError, match="skyhook-residual"):
        AC.load_policy(wf)
    with pytest.raises(ValueError):
        ars.load_ars_policy(f)
    with pytest.raises(RuntimeError, match="bind_env"):
        _policy().predict(np.zeros(env.observation_space.shape, np.float32))


def test_predicted_feature_set_round_trip_zero_start_and_refusals(tmp_path, env):
    """hq: its file carries the predictor (same actions after the round trip); with the predicted weights at 0 it acts
    as the h policy with the same other weights (to round-off: the sums run over more zero terms); it needs the
    compensator's predictor, and an h policy takes none."""
    from agents.predictor import Predictor
    pol = _policy(scale=0.02, seed=5, fs="hq")
    f = AC.save_policy(pol, tmp_path / "q.npz")
    back = AC.load_policy(f)
    assert back.feature_set == "hq" and back.meta["features"] == AC.feature_names("hq")
    assert back.predictor.channels == pol.predictor.channels and back.predictor.meta == pol.predictor.meta
    assert all(np.array_equal(back.predictor.W[k], pol.predictor.W[k]) for k in pol.predictor.W)
    sea, seed = env.unwrapped.eval_sea_states()[7]
    assert np.array_equal(_actions(env, pol.bind_env(env), sea, seed, 80),
                          _actions(env, back.bind_env(env), sea, seed, 80))
    h = _policy(scale=0.05, seed=6)
    names, hq_names = AC.feature_names("h"), AC.feature_names("hq")
    assert [n for n in hq_names if not n.endswith("(pred)")] == names and hq_names[-1] == "const"
    assert sum(n.endswith("(pred)") for n in hq_names) == 30
    cols = [hq_names.index(n) for n in names]
    theta = {}
    for k, v in h.theta.items():
        theta[k] = np.zeros((AC.N_ACT, AC.n_features("hq")))
        theta[k][:, cols] = v
    q = AC.ARSCompensatorPolicy(theta, h.base_table, meta={"feature_set": "hq"}, predictor=_predictor())
    a_h = _actions(env, h.bind_env(env), sea, seed, 200)
    a_q = _actions(env, q.bind_env(env), sea, seed, 200)
    np.testing.assert_allclose(a_q, a_h, rtol=0, atol=1e-6)        # float32 actions of equal-to-round-off sums
    with pytest.raises(ValueError, match="needs a predictor"):
        AC.ARSCompensatorPolicy(theta, h.base_table, meta={"feature_set": "hq"})
    with pytest.raises(ValueError, match="has no predictor"):
        AC.ARSCompensatorPolicy(h.theta, h.base_table, predictor=_predictor())
    with pytest.raises(ValueError, match="unknown feature set"):
        AC.ARSCompensatorPolicy(h.theta, h.base_table, meta={"feature_set": "v2q"})
    from pathlib import Path
    winch = Predictor.load(Path(AC.__file__).parent / "trained" / "predictor_WinchPayout-v0.npz")
    with pytest.raises(ValueError, match="not the towenv/CompensatorGains-v0 predictor's"):
        AC.ARSCompensatorPolicy(theta, h.base_table, meta={"feature_set": "hq"}, predictor=winch)
    wtable = load_tuned()["along_cable"]               # and the WinchPayout class refuses the compensator's predictor
    with pytest.raises(ValueError, match="not the towenv/WinchPayout-v0 predictor's"):
        ars.ARSPolicy({k: np.zeros(ars.n_features("v2q")) for k in wtable}, wtable, feature_set="v2q",
                      predictor=_predictor())


def test_evaluate_dispatches_policy_files_on_their_metadata(tmp_path):
    evaluate = load_script("evaluate")
    from agents.evaluate import load_policy_file
    f = AC.save_policy(_policy(scale=0.01), tmp_path / "a.npz")
    assert isinstance(load_policy_file(f), AC.ARSCompensatorPolicy)
    table = load_tuned()["along_cable"]
    wf = ars.save_policy(ars.ARSPolicy({k: np.zeros(ars.N_FEATURES) for k in table}, table), tmp_path / "w.npz")
    assert isinstance(load_policy_file(wf), ars.ARSPolicy)
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(ValueError, match="unknown policy file"):
        load_policy_file(tmp_path / "other.npz")
    assert evaluate is not None


def test_training_seeds_are_disjoint_from_every_other_set():
    """Training wave seeds never equal an evaluation (+0..400), tuning (+500), validation (+700), Hover (+900),
    final (+20000 + 100 r), clairvoyant-teacher (+30000 + 100 r) seed, nor a WinchPayout-ARS seed of its first 80
    iterations (the committed runs have 70; 100·Δiteration ≥ 8000 would be needed to meet), and never repeat
    within a sea state (the same number in another code's (Hs, Tp) is another sea, as in agents/ars.py)."""
    ev = gym.make(COMP).unwrapped.eval_sea_states()
    base = [s for _, s in ev]
    reserved = {b + off for b in base for off in
                list(range(0, 500, 100)) + [500, 700, 900] + [20000 + 100 * r for r in range(5)]
                + [30000 + 100 * r for r in range(100)]}
    winch_ars = {ars._train_seed(b, it, sd) for b in base for it in range(80) for sd in range(10)}
    used = {AC._train_seed(b, it, sd) for b in base for it in range(AC.MAX_ITERATIONS) for sd in range(10)}
    assert not used & reserved
    assert not used & winch_ars
    for hs in {sea.hs for sea, _ in ev}:
        same = [AC._train_seed(b, it, sd) for sea, b in ev if sea.hs == hs for it in range(AC.MAX_ITERATIONS)
                for sd in range(10)]
        assert len(set(same)) == len(same)
    with pytest.raises(ValueError):
        AC._train_seed(base[0], AC.MAX_ITERATIONS, 0)


def test_training_smoke_on_the_batched_env():
    """Two ARS iterations (1 direction, 120 s episodes) on the batched vector env: the weights move, the curve is
    recorded with the hits, the policy starts as skyhook."""
    pol = AC.train(seed=7, minutes=30.0, max_iterations=2, directions=1, top=1, episode_seconds=120.0,
                   progress=False)
    assert pol.meta["iterations"] == 2 and len(pol.meta["curve"]) == 2
    c0 = pol.meta["curve"][0]
    assert c0["heave_ratio"] == pytest.approx(1.0) and c0["hits"] == c0["hits_skyhook"]   # Θ = 0 at first
    assert all(v.shape == (AC.N_ACT, AC.N_FEATURES) for v in pol.theta.values())
    assert any(np.linalg.norm(v) > 0 for v in pol.theta.values())
    hp = pol.meta["hyperparameters"]
    assert hp["hit_weight"] == AC.DEFAULT_HIT_WEIGHT and hp["margin_weight"] == AC.DEFAULT_MARGIN_WEIGHT
    assert hp["margin_start"] == AC.DEFAULT_MARGIN_START and hp["stop_guard"] == 0.0 == pol.stop_guard
    assert c0["margin"] == pytest.approx(c0["margin_skyhook"])


def test_cli_refuses_bad_cost_options():
    for bad in (["--margin-start", "1.2"], ["--margin-weight", "-1"], ["--stop-guard", "1.5"],
                ["--hit-weight", "nan"]):
        with pytest.raises(SystemExit):
            AC.main(bad)


def test_per_sea_state_hit_weights_enter_the_cost(monkeypatch):
    """``hit_weights`` ({WMO code: w}) replaces the hit weight in the cost of that code's episodes. A fake batched
    rollout (σ ratios 1, margin 0) gives one end-stop hit to every '+' perturbation and to every episode of the
    current policy: with the weights 3: 1, 4: 0, 5: 0 only the code-3 search sees a reward difference and moves
    (codes 4 and 5 stay exactly at Θ = 0), and the recorded cost is the per-code weighted hit count (4 of 12
    episodes at weight 1 = 1/3); with the default (w_hit = 0.3 everywhere) all three move and the cost is 0.3."""
    def fake(venv, batch, seas, seeds, theta, **kw):
        n = len(seas)
        n_pert = n - 24                                  # 2 × 12 reference episodes at the end
        hits = np.zeros(n)
        # perturbations in blocks of 2 · K · n_entries (K = 1, 4 entries per sea state): '+' first, then '−'
        hits[:n_pert] = [(j // 4) % 2 == 0 for j in range(n_pert)]
        hits[n_pert:n_pert + 12] = 1.0                   # the current policy, not skyhook
        return np.ones(n), np.ones(n), hits, np.zeros(n)

    monkeypatch.setattr(AC, "rollout_batch", fake)
    ev = gym.make(COMP).unwrapped.eval_sea_states()
    table = load_tuned()["skyhook"]
    code_of = {nearest_key(table, sea): b // 1000 for sea, b in ev}
    kw = dict(seed=3, minutes=30.0, max_iterations=1, directions=1, top=1, episode_seconds=120.0, progress=False)
    per = AC.train(hit_weights={3: 1.0, 4: 0.0, 5: 0.0}, **kw)
    moved = {code_of[k]: bool(np.any(v != 0)) for k, v in per.theta.items()}
    assert moved == {3: True, 4: False, 5: False}
    assert per.meta["curve"][0]["cost"] == pytest.approx(4.0 / 12.0)
    assert per.meta["curve"][0]["hits_by_code"] == {"3": 4.0, "4": 4.0, "5": 4.0}
    assert per.meta["hyperparameters"]["hit_weights"] == {"3": 1.0, "4": 0.0, "5": 0.0}
    default = AC.train(**kw)
    assert all(np.any(v != 0) for v in default.theta.values())
    assert default.meta["curve"][0]["cost"] == pytest.approx(AC.DEFAULT_HIT_WEIGHT)
    assert default.meta["hyperparameters"]["hit_weights"] == {}
    # the helper, and a code outside the training set is refused
    w = AC.entry_hit_weights(ev, 0.3, {3: 1.0})
    assert [float(x) for x in w] == [1.0] * 4 + [0.3] * 8
    with pytest.raises(ValueError, match="codes"):
        AC.entry_hit_weights(ev, 0.3, {7: 1.0})
    assert AC.parse_hit_weights("3:1.0, 5:0.5") == {3: 1.0, 5: 0.5} and AC.parse_hit_weights("") == {}
    for bad in (["--hit-weights", "3:-1"], ["--hit-weights", "3"], ["--hit-weights", "x:1"]):
        with pytest.raises(SystemExit):
            AC.main(bad)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_committed_policies_ship_load_and_act(env, seed):
    """The three committed policies (docs/agents.md "Results") are package data of the installed ``agents``, load
    with the recipe they were trained with (55 iterations, stop guard 0.9, the skyhook table's sea states), and act:
    inside the action box and away from skyhook's own action (a trained residual, not Θ = 0)."""
    from pathlib import Path

    import agents
    path = Path(agents.__file__).parent / "trained" / f"ars_CompensatorGains-v0_s{seed}.npz"
    pol = AC.load_policy(path)
    assert (pol.meta["seed"], pol.meta["iterations"], pol.stop_guard) == (seed, 55, 0.9)
    assert set(pol.theta) == set(pol.base_table) == set(load_tuned()["skyhook"])
    assert all(np.abs(th).max() > 0 for th in pol.theta.values())
    pol.bind_env(env)
    sea, s = env.unwrapped.eval_sea_states()[5]
    acts = _actions(env, pol, sea, s + 123456)
    sky = _actions(env, make_baseline("skyhook", env), sea, s + 123456, steps=1)
    assert acts.shape[0] == env.unwrapped.max_steps and np.all(np.isfinite(acts))
    assert np.all(np.abs(acts) <= 1.0)
    assert not np.allclose(acts[0], sky[0], atol=1e-3)


def _skyhook_damps(r, obs) -> bool:
    """Skyhook's switching condition, computed here in float64 from the observation (ż_abs·ṡ > 0 and |ṡ| > 1e-6)."""
    sd = float(r(obs, "comp_stroke_vel"))
    return (float(r(obs, "tow_vel_z")) + sd) * sd > 0.0 and abs(sd) > 1e-6


def _fish_on(r, obs) -> bool:
    """The fish's switching condition, computed here in float64 from the observation (heave rate · ṡ > 0)."""
    return float(r(obs, "fish_heave_rate")) * float(r(obs, "comp_stroke_vel")) > 0.0


def _assert_gate_switches(env, gc, h, sea, seed, on_of):
    """``gc`` = the h policy ``h`` with one gated copy's weights = −(h's): on 200 steps its action is skyhook's where
    ``on_of(reader, obs)`` holds and ``h``'s elsewhere (1e-6), and both phases occur (> 20 steps each)."""
    from agents.classical import SkyhookCompensator
    gc.bind_env(env)
    sky = SkyhookCompensator(env, table=h.base_table)
    h.bind_env(env)
    r = gc.reader
    obs, _ = env.reset(seed=seed, options={"sea_state": sea, "sea_seed": seed})
    n_on = n_off = 0
    for k in range(200):
        first = np.array([k == 0])
        if k == 0:
            sky.reset()
        a_sky = np.asarray(sky.act(np.asarray(obs, float)), np.float32)
        a_h1, _ = h.predict(obs, episode_start=first)
        a_c, _ = gc.predict(obs, episode_start=first)
        if on_of(r, obs):
            n_on += 1
            np.testing.assert_allclose(a_c, np.clip(a_sky, -1, 1), rtol=0, atol=1e-6)
        else:
            n_off += 1
            np.testing.assert_allclose(a_c, a_h1, rtol=0, atol=1e-6)
        obs, _r, term, trunc, _ = env.step(a_c)
        assert not (term or trunc)
    assert n_on > 20 and n_off > 20                     # both phases were exercised


def test_gated_feature_set_switches_with_skyhook(env):
    """hs = h + every h feature times skyhook's switching state. Independently of the feature code: with the gated
    weights at 0 the policy acts as its h policy (to round-off), and with gated weights = −(the h weights) the
    residual vanishes exactly on the steps where skyhook damps (ż_abs·ṡ > 0 and |ṡ| > 1e-6, computed here in float64
    from the observation) — the action is then skyhook's — and is the h policy's on the others."""
    names, hs_names = AC.feature_names("h"), AC.feature_names("hs")
    assert hs_names[:len(names)] == names and hs_names[len(names):] == [AC.GATE_PREFIX + n for n in names]
    h = _policy(scale=0.05, seed=8)
    zero = {k: np.concatenate([v, np.zeros_like(v)], axis=1) for k, v in h.theta.items()}
    cancel = {k: np.concatenate([v, -v], axis=1) for k, v in h.theta.items()}
    g0 = AC.ARSCompensatorPolicy(zero, h.base_table, meta={"feature_set": "hs"})
    gc = AC.ARSCompensatorPolicy(cancel, h.base_table, meta={"feature_set": "hs"})
    sea, seed = env.unwrapped.eval_sea_states()[8]
    a_h = _actions(env, h.bind_env(env), sea, seed, 200)
    np.testing.assert_allclose(_actions(env, g0.bind_env(env), sea, seed, 200), a_h, rtol=0, atol=1e-6)
    _assert_gate_switches(env, gc, h, sea, seed, _skyhook_damps)


def _assert_new_copy_at_zero_acts_as_parent(env, parent, fs, sea, seed):
    """``parent`` with the 45 weights of feature set ``fs``'s newest gated copy appended at 0 acts as ``parent`` on
    200 steps (to round-off)."""
    zero = {k: np.concatenate([v, np.zeros((AC.N_ACT, 45))], axis=1) for k, v in parent.theta.items()}
    p0 = AC.ARSCompensatorPolicy(zero, parent.base_table, meta={"feature_set": fs})
    a_parent = _actions(env, parent.bind_env(env), sea, seed, 200)
    np.testing.assert_allclose(_actions(env, p0.bind_env(env), sea, seed, 200), a_parent, rtol=0, atol=1e-6)


def test_fish_gated_feature_set_switches_with_the_fish(env):
    """hsf = hs + every h feature times the fish's switching state (fish heave rate and stroke velocity of one sign).
    Independently of the feature code: with the fish-gated weights at 0 the policy acts as its hs policy (to
    round-off), and with fish-gated weights = −(the h weights) and no skyhook-gated weights the residual vanishes
    exactly on the steps where the fish's heave rate times the stroke velocity (read here in float64 from the
    observation) is positive — the action is then skyhook's — and is the h policy's on the others."""
    names, hs_names, hsf = AC.feature_names("h"), AC.feature_names("hs"), AC.feature_names("hsf")
    assert hsf == hs_names + [AC.FISH_GATE_PREFIX + n for n in names] and len(hsf) == 135
    assert AC.added_features("hsf", "fish")[1].sum() == 45 and AC.added_features("hsf", "gated")[1].sum() == 45
    assert not AC.added_features("hs", "fish")[1].any() and not AC.added_features("hst", "fish")[1].any()
    h = _policy(scale=0.05, seed=8)
    sea, seed = env.unwrapped.eval_sea_states()[8]
    _assert_new_copy_at_zero_acts_as_parent(env, _policy(scale=0.03, seed=9, fs="hs"), "hsf", sea, seed)
    cancel = {k: np.concatenate([v, np.zeros_like(v), -v], axis=1) for k, v in h.theta.items()}
    gc = AC.ARSCompensatorPolicy(cancel, h.base_table, meta={"feature_set": "hsf"})
    _assert_gate_switches(env, gc, h, sea, seed, _fish_on)


def _outward_on(r, obs) -> bool:
    """The stroke's outward condition, computed here in float64 from the observation (stroke · ṡ > 0)."""
    return float(r(obs, "comp_stroke")) * float(r(obs, "comp_stroke_vel")) > 0.0


def test_outward_gated_feature_set_switches_with_the_stroke_direction(env):
    """hsfo = hsf + every h feature times the stroke's direction of travel (stroke and stroke velocity of one sign:
    moving towards the nearer end stop). Independently of the feature code: with the outward-gated weights at 0 the
    policy acts as its hsf policy (to round-off), and with outward-gated weights = −(the h weights) and no other
    gated weights the residual vanishes exactly on the steps where stroke times stroke velocity (read here in
    float64 from the observation) is positive — the action is then skyhook's — and is the h policy's on the
    others."""
    names, hsf, hsfo = AC.feature_names("h"), AC.feature_names("hsf"), AC.feature_names("hsfo")
    assert hsfo == hsf + [AC.OUTWARD_GATE_PREFIX + n for n in names] and len(hsfo) == 180
    for kind in ("outward", "fish", "gated"):
        assert AC.added_features("hsfo", kind)[1].sum() == 45
    assert not AC.added_features("hsf", "outward")[1].any()
    h = _policy(scale=0.05, seed=8)
    sea, seed = env.unwrapped.eval_sea_states()[8]
    _assert_new_copy_at_zero_acts_as_parent(env, _policy(scale=0.02, seed=10, fs="hsf"), "hsfo", sea, seed)
    cancel = {k: np.concatenate([v, np.zeros_like(v), np.zeros_like(v), -v], axis=1) for k, v in h.theta.items()}
    gc = AC.ARSCompensatorPolicy(cancel, h.base_table, meta={"feature_set": "hsfo"})
    _assert_gate_switches(env, gc, h, sea, seed, _outward_on)


def test_cable_feature_set_reads_tension_and_along_cable_velocity(env):
    """hst = hs + the top tension's deviation and the along-cable velocity at the lags 0, 0.2, …, 2.0 s. Independently
    of the feature code: with the cable weights at 0 the policy acts as its hs policy (to round-off), and with one
    cable weight w on ``top_tension@-0.4s`` (log-damping row) the action differs from the hs policy's by exactly
    w·(T(t − 0.4 s)/T_static − 1)/scale before the clip, T read here from the recorded observations (the first
    steps see the first observation, as the other histories do)."""
    hs_names, names = AC.feature_names("hs"), AC.feature_names("hst")
    cable = [f"{c}@-{lag / 10:.1f}s" for c in AC.CABLE_CHANNELS for lag in AC.LAG_STEPS]
    assert names == hs_names + cable and len(names) == 112
    assert AC.added_features("hst")[0] == "cable" and AC.added_features("hst")[1].sum() == 22
    assert AC.added_features("hst", "gated")[1].sum() == 45 and not AC.added_features("hs", "cable")[1].any()
    hs = _policy(scale=0.03, seed=9, fs="hs")
    zero = {k: np.concatenate([v, np.zeros((AC.N_ACT, 22))], axis=1) for k, v in hs.theta.items()}
    p0 = AC.ARSCompensatorPolicy(zero, hs.base_table, meta={"feature_set": "hst"})
    sea, seed = env.unwrapped.eval_sea_states()[5]
    a_hs = _actions(env, hs.bind_env(env), sea, seed, 150)
    np.testing.assert_allclose(_actions(env, p0.bind_env(env), sea, seed, 150), a_hs, rtol=0, atol=1e-6)
    w, j = 0.02, names.index("top_tension@-0.4s")
    one = {k: v.copy() for k, v in zero.items()}
    for v in one.values():
        v[1, j] = w
    p1 = AC.ARSCompensatorPolicy(one, hs.base_table, meta={"feature_set": "hst"}).bind_env(env)
    hs.bind_env(env)
    obs, _ = env.reset(seed=seed, options={"sea_state": sea, "sea_seed": seed})
    seen, n_checked = [], 0
    for k in range(150):
        first = np.array([k == 0])
        a_ref, _ = hs.predict(obs, episode_start=first)
        a1, _ = p1.predict(obs, episode_start=first)
        seen.append(float(p1.reader(obs, "top_tension")))
        lagged = seen[max(k - 4, 0)]
        want = a_ref[1] + w * (lagged - 1.0) / AC.FEATURE_SCALES["top_tension"]
        if -0.999 < want < 0.999 and abs(a_ref[1]) < 0.999 and not AC.stop_guard_mask(p1.reader, obs[None], p1.stop_guard)[0]:
            assert a1[1] == pytest.approx(want, abs=1e-6)
            n_checked += 1
        assert a1[0] == pytest.approx(a_ref[0], abs=1e-6)
        obs, *_ = env.step(a1)
    assert n_checked > 50


def test_parallel_training_gives_the_serial_result():
    """``parallel=True`` (the batch stepped on all numba threads) only changes the wall time: every copy is an
    independent simulation, so two ARS iterations give the same weights bit for bit, and the file records it."""
    kw = dict(seed=7, minutes=30.0, max_iterations=2, directions=1, top=1, episode_seconds=120.0, progress=False)
    serial, par = AC.train(**kw), AC.train(parallel=True, **kw)
    assert par.meta["parallel"] is True and serial.meta["parallel"] is False
    assert sorted(par.theta) == sorted(serial.theta)
    assert all(np.array_equal(par.theta[k], serial.theta[k]) for k in serial.theta)
    assert any(np.any(v) for v in par.theta.values())
    assert par.meta["curve"] == [c | {"seconds": p["seconds"]} for c, p in zip(serial.meta["curve"], par.meta["curve"])]


def test_cable_state_probe_scores_a_known_linear_response():
    """scripts/probe_cable_state.py's leave-one-episode-out R²: a response that is a fixed FIR filter of the channel
    scores ≈ 1, a response independent of it ≈ 0 (≤ 0.05: the fold's out-of-sample fit cannot explain noise)."""
    script = load_script("probe_cable_state")
    rng = np.random.default_rng(0)
    eps, noise = [], []
    for _ in range(4):
        x = rng.standard_normal(1500)
        y = np.convolve(x, [0.5, 0.3, -0.2, 0.1])[:1500]
        eps.append({"u": x, "fish_heave_dev": y})
        noise.append({"u": x, "fish_heave_dev": rng.standard_normal(1500)})
    assert script.loo_r2(eps, ("u",), lags=20, start=100) > 0.999
    assert script.loo_r2(noise, ("u",), lags=20, start=100) < 0.05


def test_compiled_gain_to_action_map_is_the_single_envs_bit_for_bit(env):
    """The batched skyhook law's gain → action map (compiled, ``AC._to_action``) gives the single environment's
    ``_to_action`` (Python ``math.log``) and its plain twin bit for bit, on both maps: gains inside, at and beyond
    the ends, zero, negative and NaN."""
    rng = np.random.default_rng(4)
    e = env.unwrapped
    for mp in (e.stiffness_range, e.damping_range):
        lo, hi = mp[0], mp[1]
        g = np.concatenate([np.exp(rng.uniform(np.log(lo) - 1.0, np.log(hi) + 1.0, 5000)),
                            [lo, hi, 0.0, -3.0, np.nan, np.inf, lo * (1 + 1e-15), hi * (1 - 1e-15)]])
        got = AC._to_action(g, lo, hi)
        np.testing.assert_array_equal(got, AC._to_action_py(g, lo, hi))
        real = ~np.isnan(g)              # (a NaN gain: -1 in the batched map, NaN in the single env's; never given)
        single = np.array([type(e)._to_action(float(x), mp) for x in g[real]])
        np.testing.assert_array_equal(got[real], single)
        assert ((got > -1.0) & (got < 1.0)).sum() > 2000          # most gains map inside the action box
    np.testing.assert_array_equal(AC._to_action(np.array([5.0, 7.0]), 2.0, 2.0), [-1.0, -1.0])
