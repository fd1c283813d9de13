"""ARS linear residual over the along-cable law (issue 14, agents/ars.py): θ = 0 is the along-cable law, the
deployable single-environment policy acts exactly as the batched training rollout, it is causal (acts on the
observations it was handed, not on the simulator), its file round-trips, training runs on the batched vector
env, and scripts/evaluate.py takes the policy file."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

import towenv  # noqa: E402,F401
from agents import ars  # noqa: E402
from agents.baselines import load_tuned, make_baseline  # noqa: E402
from agents.common import nearest_key  # noqa: E402
from agents.metrics import episode_metrics, rollout  # noqa: E402
from helpers import load_script  # noqa: E402

WINCH = "towenv/WinchPayout-v0"
SECONDS = 30.0
DISCARD = 10.0


#: the committed predictor of feature set v2q (package data of the installed ``agents``)
PREDICTOR = Path(ars.__file__).parent / "trained" / "predictor_WinchPayout-v0.npz"


def _policy(scale=0.02, seed=0, feature_set="v1"):
    """An ARS policy with random (small) weights on the tuned along-cable table (v2q: with the committed predictor)."""
    from agents.predictor import Predictor
    table = load_tuned()["along_cable"]
    rng = np.random.default_rng(seed)
    theta = {k: rng.normal(0.0, scale, ars.n_features(feature_set)) for k in table}
    pred = Predictor.load(PREDICTOR) if feature_set in ars.PREDICTED else None
    return ars.ARSPolicy(theta, table, meta={"seed": seed, "iterations": 0}, feature_set=feature_set, predictor=pred)


@pytest.fixture(scope="module")
def env():
    e = gym.make(WINCH, episode_seconds=SECONDS)
    yield e
    e.close()


def test_zero_weights_are_the_along_cable_law(env):
    pol = _policy(scale=0.0).bind_env(env)
    sea, seed = env.unwrapped.eval_sea_states()[5]
    a = rollout(env, pol, sea, seed + 123456)
    b = rollout(env, make_baseline("along_cable", env), sea, seed + 123456)
    assert np.array_equal(a.data["heave"], b.data["heave"])
    assert np.array_equal(a.data["winch_speed"], b.data["winch_speed"])


@pytest.mark.parametrize("feature_set", ["v1", "v2", "v3", "v2q", "v2qa"])
def test_single_env_policy_equals_the_batched_training_rollout(env, feature_set):
    """The policy trained on the vector env is the one evaluated on single envs: same σ to round-off (every
    feature set: v2 adds winch speed, last action, top tension, cable angle, fish pitch and its rate; v3 the
    policy's own earlier actions and the MRU velocity 2.4–4 s back; v2q the predicted along-cable motion; v2qa
    hinges of its predicted acceleration)."""
    from towenv.envs.vector import WinchPayoutVectorEnv
    pol = _policy(scale=0.02, feature_set=feature_set).bind_env(env)
    ev = env.unwrapped.eval_sea_states()
    picks = [0, 6, 11]                                  # one entry per sea state
    seas = [ev[i][0] for i in picks]
    seeds = [ev[i][1] + 123456 for i in picks]
    venv = WinchPayoutVectorEnv(num_envs=3, autoreset_mode="NextStep", batch_infos=True, episode_seconds=SECONDS)
    batch = ars._Batch(venv, pol.base_table, pol.scales, feature_set, pol.predictor)
    theta = np.array([pol.theta[nearest_key(pol.theta, s)] for s in seas])
    sh, sp = ars.rollout_batch(venv, batch, seas, seeds, theta, discard=DISCARD)
    venv.close()
    for i, (sea, s) in enumerate(zip(seas, seeds)):
        m = episode_metrics(rollout(env, pol, sea, s), DISCARD)
        assert m["rms_heave"] == pytest.approx(sh[i], rel=1e-9, abs=1e-12)
        assert m["rms_pitch_deg"] == pytest.approx(sp[i], rel=1e-9, abs=1e-12)
    # and the weights matter: the residual changes the heave
    al = episode_metrics(rollout(env, make_baseline("along_cable", env), seas[1], seeds[1]), DISCARD)
    assert abs(al["rms_heave"] - sh[1]) > 1e-6


def test_v2_features_are_the_observed_channels(env):
    """Each v2 extra feature is (channel − offset)/scale of the observation the policy was handed, in the
    channel's physical unit; the v1 block in front of them is the v1 feature vector unchanged."""
    from agents.common import ObsReader
    reader = ObsReader(env)
    sea, seed = env.unwrapped.eval_sea_states()[4]
    obs, _ = env.reset(seed=seed, options={"sea_state": sea, "sea_seed": seed})
    for _ in range(25):
        obs, *_ = env.step(np.array([0.4], np.float32))
    phi1, _ = ars.features_single(reader, obs, ars.FEATURE_SCALES, None, "v1")
    phi2, _ = ars.features_single(reader, obs, ars.FEATURE_SCALES, None, "v2")
    extra = ars.FEATURE_SETS["v2"]
    assert len(phi2) == len(phi1) + len(extra) == ars.n_features("v2")
    assert np.array_equal(phi2[:len(phi1) - 1], phi1[:-1]) and phi2[-1] == phi1[-1] == 1.0
    names = ars.feature_names("v2")
    for c in extra:
        off, sc = ars.EXTRA_SCALES[c]
        x = phi2[names.index(c)] * sc + off
        assert x == pytest.approx(float(np.asarray(reader(obs, c)).reshape(-1)[0]), rel=1e-12, abs=1e-12)
    # and last_action is the action handed to the last step (float32 round-off)
    assert phi2[names.index("last_action")] * ars.EXTRA_SCALES["last_action"][1] == pytest.approx(0.4, abs=1e-6)


def test_hinged_policy_warns_on_another_winch_and_training_refuses_it():
    """The v2qa hinge thresholds are physical values set for the standard winch's 1.5 m/s²: a committed v2qa policy
    bound to the high-performance winch (2.5 m/s²) warns, naming both limits; the batched training refuses that
    winch naming winch_max_acceleration; v2q (no hinges) and the standard winch pass silently."""
    import warnings

    from agents.predictor import Predictor
    from towenv.envs.vector import WinchPayoutVectorEnv
    assert towenv.envs.winch.WINCH_CLASSES["standard"]["max_acceleration"] == ars.HINGE_WINCH_ACCELERATION
    pol = ars.load_ars_policy(PREDICTOR.parent / "gnqa_WinchPayout-v0_s0.npz")
    fast = gym.make(WINCH, winch_class="high_performance")
    with pytest.warns(UserWarning, match=r"winch_max_acceleration is 2.5 m/s².*1.5 m/s²|1.5 m/s².*2.5 m/s²"):
        pol.bind_env(fast)
    std = gym.make(WINCH)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pol.bind_env(std)
    fast.close(), std.close()
    pred = Predictor.load(PREDICTOR)
    venv = WinchPayoutVectorEnv(num_envs=1, winch_class="high_performance")
    with pytest.raises(ValueError, match="winch_max_acceleration"):
        ars._Batch(venv, load_tuned()["along_cable"], dict(ars.FEATURE_SCALES), "v2qa", pred)
    ars._Batch(venv, load_tuned()["along_cable"], dict(ars.FEATURE_SCALES), "v2q", pred)     # no hinges: fine
    venv.close()


def test_v2qa_hinges_are_the_predicted_acceleration_beyond_each_threshold(env):
    """v2qa = the v2q vector with, before the constant, sign(a)·max(|a| − c, 0)/HINGE_SCALE of the predicted
    along-cable acceleration a (m/s², the v2q feature times the predictor's channel scale) at every lead, for each
    threshold c; in a code-5 sea some of them are active (nonzero) and each is zero exactly where |a| ≤ c."""
    from agents.common import ObsReader
    from agents.predictor import LEADS, Predictor
    pred = Predictor.load(PREDICTOR)
    reader = ObsReader(env)
    sea, seed = env.unwrapped.eval_sea_states()[8]
    key = nearest_key(pred.W, sea)
    obs, _ = env.reset(seed=seed, options={"sea_state": sea, "sea_seed": seed})
    hq = ha = None
    names, nq = ars.feature_names("v2qa"), ars.n_features("v2q")
    L, active = len(LEADS), 0
    for k in range(int(SECONDS / 0.1) - 1):
        phq, hq = ars.features_single(reader, obs, ars.FEATURE_SCALES, hq, "v2q", pred, key)
        pha, ha = ars.features_single(reader, obs, ars.FEATURE_SCALES, ha, "v2qa", pred, key)
        assert len(pha) == ars.n_features("v2qa") == nq + L * len(ars.HINGES["v2qa"])
        assert np.array_equal(pha[:nq - 1], phq[:-1]) and pha[-1] == 1.0
        first = names.index(f"tow_acc_along@+{LEADS[0] / 10:.1f}s(pred)")
        acc = phq[first:first + L] * pred.scales[1]
        for j, c in enumerate(ars.HINGES["v2qa"]):
            h = pha[nq - 1 + j * L: nq - 1 + (j + 1) * L] * ars.HINGE_SCALE
            assert np.allclose(h, np.sign(acc) * np.maximum(np.abs(acc) - c, 0.0), rtol=1e-12, atol=1e-12)
            assert np.all(h[np.abs(acc) <= c] == 0.0)
            active += int(np.count_nonzero(h))
        obs, *_ = env.step(np.array([0.0], np.float32))
    assert active > 0


def test_v3_long_history_features_are_the_lagged_channels(env):
    """v3 = the v2 vector with, before the constant, the policy's own earlier actions and the MRU along-cable
    velocity further back: feature ``c@-L s`` is channel c as observed L s (L/0.1 control steps) before the current
    observation, scaled as its instant/v1 feature, and the first observation fills the ring at episode start."""
    from agents.common import ObsReader
    reader = ObsReader(env)
    sea, seed = env.unwrapped.eval_sea_states()[7]
    obs, _ = env.reset(seed=seed, options={"sea_state": sea, "sea_seed": seed})
    names3, names2 = ars.feature_names("v3"), ars.feature_names("v2")
    hist = hist2 = None
    seen = []
    for k in range(45):
        phi3, hist = ars.features_single(reader, obs, ars.FEATURE_SCALES, hist, "v3")
        phi2, hist2 = ars.features_single(reader, obs, ars.FEATURE_SCALES, hist2, "v2")
        seen.append(obs.copy())
        assert names3[:len(names2) - 1] == names2[:-1] and len(names3) == ars.n_features("v3") == len(phi3)
        assert np.array_equal(phi3[:len(phi2) - 1], phi2[:-1]) and phi3[-1] == 1.0      # the v2 vector in front
        for c, lags in ars.LONG_HISTORY["v3"]:
            off, sc = ars._long_scale(c)
            for lag in lags:
                x = phi3[names3.index(f"{c}@-{lag / 10:.1f}s")] * sc + off
                want = float(np.asarray(reader(seen[max(k - lag, 0)], c)).reshape(-1)[0])
                assert x == pytest.approx(want, rel=1e-12, abs=1e-12)
        obs, *_ = env.step(np.array([0.6 * np.sin(0.3 * k)], np.float32))
    # last_action 0.1 s back is the action handed two steps before the current observation
    assert phi3[names3.index("last_action@-0.1s")] * ars.EXTRA_SCALES["last_action"][1] == pytest.approx(
        0.6 * np.sin(0.3 * 42), abs=1e-6)


@pytest.mark.parametrize("feature_set", ["v1", "v2q"])
def test_policy_is_causal(env, feature_set):
    """The actions depend only on the observations handed to predict() (and the sea-state estimate): replaying
    a recorded observation sequence to a fresh policy bound to another environment, whose simulator is in an
    unrelated state, gives the same actions; changing a *later* observation leaves earlier actions unchanged
    (v2q: its predicted future is computed from the past only)."""
    pol = _policy(scale=0.05, feature_set=feature_set).bind_env(env)
    sea, seed = env.unwrapped.eval_sea_states()[2]
    obs, _ = env.reset(seed=seed, options={"sea_state": sea, "sea_seed": seed})
    seq, acts = [], []
    for k in range(60):
        a, _ = pol.predict(obs, episode_start=np.array([k == 0]))
        seq.append(obs.copy())
        acts.append(a.copy())
        obs, *_ = env.step(a)
    other = gym.make(WINCH, episode_seconds=SECONDS)
    other.reset(seed=seed + 1, options={"sea_state": sea, "sea_seed": seed + 1})     # same sea state, other waves
    for _ in range(17):
        other.step(np.array([0.3], np.float32))
    replay = _policy(scale=0.05, feature_set=feature_set).bind_env(other)
    again = [replay.predict(o, episode_start=np.array([k == 0]))[0] for k, o in enumerate(seq)]
    assert all(np.array_equal(x, y) for x, y in zip(acts, again))
    changed = [o.copy() for o in seq]
    changed[40] = changed[40] + 1.0
    replay2 = _policy(scale=0.05, feature_set=feature_set).bind_env(other)
    alt = [replay2.predict(o, episode_start=np.array([k == 0]))[0] for k, o in enumerate(changed)]
    assert all(np.array_equal(x, y) for x, y in zip(acts[:40], alt[:40]))
    assert not np.array_equal(acts[40], alt[40])
    other.close()


@pytest.mark.parametrize("feature_set", ["v1", "v2", "v3", "v2q"])
def test_policy_file_round_trip_and_refusal(tmp_path, env, feature_set):
    pol = _policy(scale=0.01, seed=3, feature_set=feature_set)
    f = ars.save_policy(pol, tmp_path / "p.npz")
    back = ars.load_ars_policy(f)
    assert back.feature_set == feature_set
    assert sorted(back.theta) == sorted(pol.theta)
    assert all(np.array_equal(back.theta[k], pol.theta[k]) for k in pol.theta)
    assert back.base_table == json.loads(json.dumps(pol.base_table))
    assert back.meta["algo"] == "ars" and back.meta["env_id"] == WINCH
    if feature_set in ars.PREDICTED:                # the predictor travels inside the policy file
        assert sorted(back.predictor.W) == sorted(pol.predictor.W)
        assert all(np.array_equal(back.predictor.W[k], pol.predictor.W[k]) for k in pol.predictor.W)
        assert np.array_equal(back.predictor.scales, pol.predictor.scales)
        z = {k: v for k, v in np.load(f).items() if not k.startswith("predictor_")}
        np.savez(tmp_path / "nopred.npz", **z)
        with pytest.raises(ValueError, match="no readable predictor"):
            ars.load_ars_policy(tmp_path / "nopred.npz")
        with pytest.raises(ValueError, match="needs a predictor"):
            ars.ARSPolicy(pol.theta, pol.base_table, feature_set="v2q")
    else:
        assert back.predictor is None
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(ValueError, match="not an ARS policy"):
        ars.load_ars_policy(tmp_path / "other.npz")
    # damaged or foreign files: one ValueError naming the file, not a numpy/zipfile traceback
    raw = f.read_bytes()
    (tmp_path / "cut.npz").write_bytes(raw[: len(raw) // 2])
    (tmp_path / "text.npz").write_text("not a policy")
    np.save(tmp_path / "single.npy", np.zeros(3))
    for bad in ("cut.npz", "text.npz", "single.npy", "missing.npz"):
        with pytest.raises(ValueError, match=bad.replace(".", r"\.")):
            ars.load_ars_policy(tmp_path / bad)
    with pytest.raises(RuntimeError, match="bind_env"):
        _policy().predict(np.zeros(env.observation_space.shape, np.float32))
    with pytest.raises(ValueError, match="feature set"):
        ars.ARSPolicy({"hs0.88_tp4.03": np.zeros(ars.n_features("v1"))}, pol.base_table, feature_set="v2")
    with pytest.raises(ValueError, match="feature_set must be one of"):
        _policy(feature_set="v9")
    if feature_set == "v2":         # a v2 file whose feature scales are not this version's is refused
        z = dict(np.load(f))
        meta = json.loads(str(z["meta"]))
        meta["extra_scales"]["top_tension"] = [1.0, 0.2]
        z["meta"] = np.array(json.dumps(meta))
        np.savez(tmp_path / "scaled.npz", **z)
        with pytest.raises(ValueError, match="feature scales"):
            ars.load_ars_policy(tmp_path / "scaled.npz")
        # and it needs the v2 channels observed
        narrow = gym.make(WINCH, episode_seconds=SECONDS, observations=["tow_vel_along", "tow_acc_along",
                                                                         "tow_disp_along", "winch_length_dev",
                                                                         "fish_heave_dev", "fish_heave_rate"])
        with pytest.raises(KeyError, match="needs observation channels"):
            back.bind_env(narrow)
        narrow.close()


def test_committed_v1_policies_still_load():
    """Files written before feature sets existed (no ``feature_set`` entry) load as v1 with their 37 weights."""
    from pathlib import Path
    import agents
    files = sorted((Path(agents.__file__).parent / "trained").glob("ars_WinchPayout-v0_s*.npz"))
    assert len(files) == 3
    for f in files:
        meta = json.loads(str(np.load(f)["meta"]))
        pol = ars.load_ars_policy(f)
        assert pol.feature_set == meta.get("feature_set", "v1")
        assert all(v.shape == (ars.n_features(pol.feature_set),) for v in pol.theta.values())


def test_training_smoke_on_the_batched_env():
    """One ARS iteration (1 direction, 120 s episodes) on the batched vector env: the weights move, the curve is
    recorded, training wave seeds are not evaluation/final/validation/tuning seeds."""
    pol = ars.train(seed=7, minutes=30.0, max_iterations=1, directions=1, top=1, episode_seconds=120.0,
                    progress=False)
    assert pol.meta["iterations"] == 1 and len(pol.meta["curve"]) == 1
    assert pol.meta["curve"][0]["heave_ratio"] == pytest.approx(1.0)        # θ = 0 before the first step
    assert any(np.linalg.norm(v) > 0 for v in pol.theta.values())
    base = [s for _, s in gym.make(WINCH).unwrapped.eval_sea_states()]
    reserved = {b + off for b in base for off in list(range(0, 500, 100)) + [500, 700, 900, 20000, 20100, 30000]}
    used = {ars._train_seed(b, it, sd) for b in base for it in range(200) for sd in range(3)}
    assert not used & reserved


def test_parallel_training_gives_the_serial_result():
    """``parallel=True`` (``--parallel``) only changes the wall time: one ARS iteration with the batch stepped on all
    numba threads gives the serial run's weights and training curve bit for bit."""
    kw = dict(seed=7, minutes=30.0, max_iterations=1, directions=1, top=1, episode_seconds=120.0, progress=False)
    ser, par = ars.train(**kw), ars.train(**kw, parallel=True)
    assert par.meta["parallel"] is True and ser.meta["parallel"] is False
    assert all(np.array_equal(par.theta[k], ser.theta[k]) for k in ser.theta)
    assert any(np.linalg.norm(v) > 0 for v in ser.theta.values())
    drop = ("seconds",)
    assert ([{k: v for k, v in c.items() if k not in drop} for c in par.meta["curve"]]
            == [{k: v for k, v in c.items() if k not in drop} for c in ser.meta["curve"]])


def test_evaluate_takes_an_ars_policy_file(tmp_path, monkeypatch, capsys):
    evaluate = load_script("evaluate")
    f = ars.save_policy(_policy(scale=0.01), tmp_path / "ars_test_s0.npz")
    monkeypatch.chdir(tmp_path)
    assert evaluate.main([str(f), "--episodes", "0", "--baselines", "fixed_winch", "along_cable", "--no-plots",
                          "--env-kwargs", f"episode_seconds:{SECONDS}", "--discard", str(DISCARD)]) == 0
    summary = json.loads((tmp_path / "runs" / "reports" / "ars_test_s0" / "summary.json").read_text())
    assert "ars_test_s0" in json.dumps(summary)
    assert "ARS policy" in (tmp_path / "runs" / "reports" / "ars_test_s0" / "report.md").read_text()


def test_default_export_names_the_family_by_feature_set():
    """Without --export a v2 run writes the v2 family's name (ars2_, as the committed files), a v1 run the v1 name."""
    assert str(ars.default_export("v2", 1)) == "runs/ars2_WinchPayout-v0_s1.npz"
    assert str(ars.default_export("v1", 0)) == "runs/ars_WinchPayout-v0_s0.npz"
    with pytest.raises(ValueError, match="feature_set"):
        ars.default_export("v7", 0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_committed_v2_policies_ship_load_and_act(env, seed):
    """The three committed feature-set-v2 policies (docs/agents.md "Results") are package data of the installed
    ``agents``, load with their recipe (70 iterations, the along-cable table's sea states), use the v2 channels
    (non-zero weights on them) and act: inside the action box and not the along-cable law itself."""
    from pathlib import Path

    import agents
    pol = ars.load_ars_policy(Path(agents.__file__).parent / "trained" / f"ars2_WinchPayout-v0_s{seed}.npz")
    assert pol.feature_set == "v2" and (pol.meta["seed"], pol.meta["iterations"]) == (seed, 70)
    assert set(pol.theta) == set(pol.base_table) == set(load_tuned()["along_cable"])
    names = ars.feature_names("v2")
    extra = [names.index(c) for c in ars.FEATURE_SETS["v2"]]
    assert all(np.abs(th[extra]).max() > 0 for th in pol.theta.values())
    pol.bind_env(env)
    sea, s = env.unwrapped.eval_sea_states()[7]
    a = rollout(env, pol, sea, s + 123456)
    b = rollout(env, make_baseline("along_cable", env), sea, s + 123456)
    assert np.all(np.isfinite(a.data["winch_speed"])) and np.all(np.abs(a.data["winch_speed"]) <= env.unwrapped.winch_max_speed + 1e-9)
    assert not np.array_equal(a.data["winch_speed"], b.data["winch_speed"])


def test_compare_script_scores_policies_against_along_cable(tmp_path, capsys):
    """scripts/compare_winch_policies.py: θ = 0 is the along-cable law (+0.00 %), a policy of another feature set
    is scored in the same batch, and files that are not policies are refused with exit 2."""
    zero = ars.save_policy(_policy(scale=0.0, feature_set="v2"), tmp_path / "zero.npz")
    other = ars.save_policy(_policy(scale=0.02, feature_set="v3"), tmp_path / "v3.npz")
    compare = load_script("compare_winch_policies")
    assert compare.main([str(zero), str(other), "--replicates", "1", "--episode-seconds", "64"]) == 0
    out = capsys.readouterr().out
    line0 = next(x for x in out.splitlines() if x.startswith(str(zero)))
    assert "heave  +0.00 %" in line0 and line0.count("+0.00 %") == 5          # pooled, codes 3-5, pitch
    line1 = next(x for x in out.splitlines() if x.startswith(str(other)))
    assert "heave  +0.00 %" not in line1
    (tmp_path / "bad.npz").write_text("no")
    for bad in ([str(tmp_path / "bad.npz")], [str(zero), "--replicates", "9"], [str(zero), "--episode-seconds", "30"]):
        with pytest.raises(SystemExit) as ex:
            compare.main(bad)
        assert ex.value.code == 2


def test_v2q_predicted_features_are_the_coming_along_cable_motion(env):
    """The committed predictor's features are the along-cable motion 0.2–2.0 s *ahead*, from the past only: on an
    episode none of its fitting seeds (+123456) under along_cable, the feature "c@+L s(pred)" at step k matches
    channel c observed L s later with R² ≥ 0.9 for every channel and lead ≤ 1 s (held-out R² at fitting: ≥ 0.98),
    and it is worse against the same channel at other leads (the lead is where it should be)."""
    from agents.common import ObsReader
    from agents.predictor import LEADS
    pol = _policy(scale=0.0, feature_set="v2q")
    reader = ObsReader(env)
    base = make_baseline("along_cable", env)
    sea, seed = env.unwrapped.eval_sea_states()[6]
    obs, _ = env.reset(seed=seed, options={"sea_state": sea, "sea_seed": seed + 123456})
    base.reset()
    key = nearest_key(pol.predictor.W, sea)
    names = ars.feature_names("v2q")
    hist, feats, chans = None, [], []
    for _k in range(env.unwrapped.max_steps):
        phi, hist = ars.features_single(reader, obs, pol.scales, hist, "v2q", pol.predictor, key)
        feats.append(phi)
        chans.append([reader(obs, c) / ars.FEATURE_SCALES[c] for c in ars.HISTORY_CHANNELS])
        obs, _r, term, trunc, _i = env.step(base.act(obs))
        if term or trunc:
            break
    F, X = np.array(feats), np.array(chans)
    skip = 120                                    # past the start-up (the ring is filled with the first sample)
    for j, c in enumerate(ars.HISTORY_CHANNELS):
        for lead in LEADS[:5]:
            pred = F[skip:len(F) - 30, names.index(f"{c}@+{lead / 10:.1f}s(pred)")]
            r2 = lambda shift: 1 - np.mean((X[skip + shift:len(F) - 30 + shift, j] - pred) ** 2) / np.var(X[skip + shift:len(F) - 30 + shift, j])  # noqa: E731
            assert r2(lead) >= 0.9, (c, lead, r2(lead))
            assert r2(lead) > r2(lead + 6) and r2(lead) > r2(0), (c, lead)
