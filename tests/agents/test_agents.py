"""Smoke tests of agents/ (baselines, metrics, policy zip) and scripts/train.py, scripts/evaluate.py.

A tiny PPO run (a few thousand steps, short episodes), a checkpoint resume, and a short evaluation on two
sea states that writes a report. Kept well under ~90 s on a 2-core machine. The long version is
scripts/soak_env.py.
"""
from __future__ import annotations

import json
import os
import math

import numpy as np
import pytest

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")
pytest.importorskip("yaml")          # rl-zoo YAML hyperparameters (PyYAML; should be in the `rl` extra)

from helpers import load_script

import gymnasium as gym  # noqa: E402

import towenv.envs  # noqa: E402,F401

COMP = "towenv/CompensatorGains-v0"
WINCH = "towenv/WinchPayout-v0"

#: a tuned-baseline table for the tests (keys of the coastal code 3 and 4 presets)
TUNED = {
    "best_passive": {"hs0.88_tp4.03": {"mode": "passive", "stiffness": 1000.0, "damping": 1500.0},
                     "hs1.88_tp5.90": {"mode": "passive", "stiffness": 1000.0, "damping": 5000.0}},
    "hover": {"hs0.88_tp4.03": {"mode": "passive", "stiffness": 1000.0, "damping": 1256.0},
              "hs1.88_tp5.90": {"mode": "locked"}},
    "pd_ff": {"hs0.88_tp4.03": {"g_ff": 0.6, "g_acc": 0.0, "kp": 0.5, "kd": 0.5, "kl": 0.02},
              "hs1.88_tp5.90": {"g_ff": 0.3, "g_acc": 0.0, "kp": 0.5, "kd": 0.5, "kl": 0.02}},
    "constant_tension": {"hs0.88_tp4.03": {"gain": 1e-4}, "hs1.88_tp5.90": {"gain": 2e-4}},
}



# ---------------------------------------------------------------------------------------- baselines
@pytest.mark.parametrize("env_id", [COMP, WINCH])
def test_baselines_run_and_act_within_bounds(env_id, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)                  # the clairvoyant baselines cache their plans under runs/
    from agents.baselines import baseline_names, make_baseline
    from agents.common import env_kind
    from agents.metrics import episode_metrics, metric_columns, rollout
    env = gym.make(env_id, episode_seconds=6.0)
    sea, seed = env.unwrapped.eval_sea_states()[4]
    for name in baseline_names(env_kind(env_id)):
        pol = make_baseline(name, env, TUNED)
        rec = rollout(env, pol, sea, seed)
        assert rec.steps == env.unwrapped.max_steps
        m = episode_metrics(rec, discard=2.0)
        assert all(math.isfinite(v) for v in m.values()), (name, m)
        assert tuple(m) == metric_columns(env_kind(env_id))      # the columns --reuse checks before running
        a, state = pol.predict(np.zeros(env.observation_space.shape, np.float32), episode_start=np.array([False]))
        assert a.shape == env.action_space.shape and np.all(np.abs(a) <= 1.0) and state is None
        assert pol.describe()


def test_locked_and_constant_tension_configure_the_simulator():
    from agents.baselines import make_baseline
    from towenv.core import kernels as K
    env = gym.make(COMP, episode_seconds=2.0)
    env.reset(options={"eval_index": 4})
    pol = make_baseline("locked", env, TUNED)
    pol.predict(env.observation_space.sample(), episode_start=np.array([True]))
    assert env.unwrapped.sim.comp[K.C_MODE] == K.COMP_LOCKED
    env.reset(options={"eval_index": 4})           # sim.reset() restores passive mode
    assert env.unwrapped.sim.comp[K.C_MODE] == K.COMP_PASSIVE
    wenv = gym.make(WINCH, episode_seconds=2.0)
    wenv.reset(options={"eval_index": 4})
    ct = make_baseline("constant_tension", wenv, TUNED)
    ct.predict(wenv.observation_space.sample(), episode_start=np.array([True]))
    sim = wenv.unwrapped.sim
    assert sim.winch[K.W_MODE] == K.WINCH_TENSION and sim.winch[K.W_GAIN] == pytest.approx(2e-4)


def test_obs_reader_decodes_physical_units():
    from agents.common import ObsReader
    env = gym.make(WINCH, episode_seconds=3.0, observations=("fish_heave", "fish_pitch", "winch_length_dev"))
    r = ObsReader(env)
    obs, _ = env.reset(options={"eval_index": 8})
    for _ in range(15):
        obs, _, _, _, info = env.step(np.array([0.2], np.float32))
    assert r(obs, "fish_heave") == pytest.approx(info["fish_heave"], abs=1e-5)
    assert r(obs, "fish_pitch") == pytest.approx(info["fish_pitch"], abs=1e-5)
    assert r(obs, "winch_length_dev") == pytest.approx(env.unwrapped.sim.winch_state()["length"] - env.unwrapped._L0,
                                                       abs=1e-4)


def test_hover_design_follows_the_rules():
    from agents.hover import hover_design
    from towenv.scene import load_scene
    from towenv.sea import SeaState
    sc = load_scene("two_part_coastal_ss4")
    d = hover_design(sc, SeaState.from_code(4, "coastal"), seed=4900, n_grid=21)
    assert d["k_crit"] > 0
    if d["mode"] == "passive":
        assert d["stiffness"] == pytest.approx(sc.compensator.stiffness_bounds[0])
        assert d["R_ratio"] <= d["R_max"] + 1e-12
        assert d["p1_ratio"] < 1.0
    # a much smaller travel than the deck motion needs more damping, or a lock
    d2 = hover_design(sc.with_overrides({"compensator.stroke": 0.2}), SeaState.from_code(4, "coastal"), seed=4900,
                      n_grid=21)
    assert d2["mode"] == "locked" or d2["damping"] >= d.get("damping", 0.0)


# ---------------------------------------------------------------------------------------- metrics
def test_metrics_on_a_sine_and_bootstrap():
    from agents.metrics import EpisodeRecord, bootstrap_mean_ci, episode_metrics, paired_reduction_ci
    t = np.arange(1, 3001) * 0.1
    A = 0.5
    h = A * np.sin(2 * np.pi * t / 8.0) + 0.3
    z = np.zeros_like(t)
    data = {"t": t, "heave": h, "pitch": 0.01 * np.sin(t), "heave_rate": np.gradient(h, t), "pitch_rate": 0.01 * np.cos(t),
            "tow_z": np.sin(t), "top_tension": 4000 + 10 * np.sin(t), "min_tension": 100 + z, "reward": z,
            "winch_speed": z, "winch_dev": z}
    rec = EpisodeRecord("winch", None, 0, 0.1, data, steps=t.size, winch_travel=10.0)
    m = episode_metrics(rec, discard=60.0)
    assert m["sig_heave"] == pytest.approx(2 * A / math.sqrt(2), rel=2e-3)
    assert m["mean_heave"] == pytest.approx(0.3, abs=2e-3)
    assert m["frac_heave_rate_over"] == 0.0
    mean, lo, hi = bootstrap_mean_ci([1.0, 2.0, 3.0, 4.0])
    assert lo <= mean <= hi and mean == 2.5
    v, lo, hi = paired_reduction_ci([0.5, 1.0], [1.0, 2.0])
    assert v == pytest.approx(0.5) and lo == pytest.approx(0.5) and hi == pytest.approx(0.5)


def test_hyperparameter_files_parse():
    from agents.zoo import HYPERPARAMS_DIR, load_hyperparams
    for algo in ("ppo", "sac"):
        for env_id in (COMP, WINCH):
            hp = load_hyperparams(HYPERPARAMS_DIR / f"{algo}.yml", env_id)
            assert hp["n_envs"] >= 1 and hp["n_timesteps"] > 0 and hp["policy"] == "MlpPolicy"
            assert isinstance(hp["algo_kwargs"].get("policy_kwargs", {}), dict)
            gym.make(env_id, **hp["env_kwargs"])          # the YAML's env_kwargs are valid keywords


# ---------------------------------------------------------------------------------------- train + evaluate
@pytest.mark.slow
def test_smoke_train_resume_and_evaluate(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    train = load_script("train")
    evaluate = load_script("evaluate")
    log = tmp_path / "runs"
    export = tmp_path / "ppo_winch.zip"
    common = ["--algo", "ppo", "--env", WINCH, "--seed", "1", "--log-dir", str(log), "--env-kwargs",
              "episode_seconds:20.0", "--hyperparams", "n_steps:256", "batch_size:128", "n_epochs:2",
              "--n-envs", "4", "--no-progress-bar", "--save-freq", "1024"]
    assert train.main(common + ["--n-timesteps", "2048", "--eval-freq", "1024", "--eval-episodes", "1",
                                "--eval-seconds", "10"]) == 0
    run = log / "ppo_WinchPayout-v0_s1"
    assert (run / "final.zip").exists() and list((run / "tb").iterdir())
    assert (run / "best" / "best_model.zip").exists()
    # resume continues from the newest checkpoint up to the new target
    assert train.main(common + ["--n-timesteps", "3072", "--eval-freq", "0", "--resume", "--export", str(export)]) == 0
    info = json.loads((run / "run_info.json").read_text())
    assert info["num_timesteps"] == 3072 and export.exists()

    from agents.zoo import load_policy, read_meta
    meta = read_meta(export)
    assert meta["algo"] == "ppo" and meta["env_id"] == WINCH and meta["num_timesteps"] == 3072
    pol = load_policy(export)
    assert pol.vecnormalize is not None
    a, _ = pol.predict(np.zeros(gym.make(WINCH).observation_space.shape, np.float32))
    assert a.shape == (1,)

    tuned = tmp_path / "tuned.yml"
    import yaml
    tuned.write_text(yaml.safe_dump(TUNED))
    out = tmp_path / "reports"
    assert evaluate.main([str(export), "--episodes", "0", "4", "--env-kwargs", "episode_seconds:30.0",
                          "--out-dir", str(out), "--name", "smoke", "--html", "--boot", "200",
                          "--tuned", str(tuned)]) == 0
    rep = out / "smoke"
    md = (rep / "report.md").read_text()
    for f in ("summary.png", "psd.png", "timeseries.png", "metrics.csv", "summary.json", "report.html"):
        assert (rep / f).exists(), f
    assert "## Goals" in md and "along_cable" in md and "clairvoyant" in md and "compensation ratio" in md
    assert "code 3" in md and "code 4" in md
    summ = json.loads((rep / "summary.json").read_text())
    assert set(summ["summary"]) == {"ppo_winch", "fixed_winch", "pd_ff", "constant_tension", "along_cable",
                                    "clairvoyant"}
    # compensator baselines-only report (no trained policy)
    assert evaluate.main(["best_passive", "--episodes", "4", "--env-kwargs", "episode_seconds:20.0",
                          "--out-dir", str(out), "--name", "comp", "--no-plots", "--boot", "100",
                          "--tuned", str(tuned)]) == 0
    assert "best_passive" in (out / "comp" / "report.md").read_text()


def test_scripts_have_help():
    for name in ("soak_env", "tune_ray"):
        mod = load_script(name)
        with pytest.raises(SystemExit) as e:
            mod.main(["--help"])
        assert e.value.code == 0


def test_scripts_loaded_in_process_leave_numba_threads_alone(monkeypatch):
    """A script loaded into a process that has already loaded numba (a test) must not set NUMBA_NUM_THREADS: numba
    re-reads its configuration at every compilation and raises when the count differs from its launched pool, so
    the next compilation anywhere in the process would fail (it did in the test suite once the kernels' caches were
    partly warm)."""
    import numba  # noqa: F401
    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    for name in ("soak_env", "bench_linear", "tune_ray", "bench_env"):
        load_script(name)
        assert "NUMBA_NUM_THREADS" not in os.environ, name


def test_soak_quick(tmp_path):
    soak = load_script("soak_env")
    assert soak.main(["--env", COMP, "--minutes", "0.03", "--episode-seconds", "10", "--out",
                      str(tmp_path / "soak.json")]) == 0
    s = json.loads((tmp_path / "soak.json").read_text())[0]
    assert s["steps"] > 0 and s["nonfinite"] == 0
