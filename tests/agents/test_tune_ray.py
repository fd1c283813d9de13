"""scripts/tune_ray.py: a real (tiny) Ray Tune sweep on a local Ray instance when ray is installed, and the
messages without the extras (no ray needed). The sweep runs the script in a subprocess from a temporary
directory, as a user would (relative --log-dir), and takes about half a minute on 2 cores."""
from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import REPO

SCRIPT = REPO / "scripts" / "tune_ray.py"
#: the smallest sensible sweep: 256 steps on 2 env copies, one 20 s validation episode at the end
TINY = ["--algo", "ppo", "--env", "towenv/WinchPayout-v0", "--sea-codes", "3", "--n-timesteps", "256",
        "--eval-freq", "256", "--n-envs", "2", "--eval-episodes", "1", "--env-kwargs", "episode_seconds:20.0",
        "--param", "n_steps", "64", "--param", "batch_size", "64", "--param", "n_epochs", "1"]


def _env():
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}   # never a cluster of the caller's
    env["PYTHONUNBUFFERED"] = "1"
    return env


def _run_blocked(blocked: list[str], args: list[str], cwd) -> subprocess.CompletedProcess:
    """Run the script with the given modules made unimportable (sys.modules[name] = None)."""
    code = ("import runpy, sys\n"
            f"for m in {blocked!r}: sys.modules[m] = None\n"
            f"sys.argv = ['tune_ray.py'] + {args!r}\n"
            f"runpy.run_path({str(SCRIPT)!r}, run_name='__main__')\n")
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, env=_env(), capture_output=True, text=True,
                          timeout=120)


def test_without_ray_names_the_extra(tmp_path):
    p = _run_blocked(["ray"], TINY + ["--seeds", "0"], tmp_path)
    assert p.returncode == 2, p.stdout + p.stderr
    assert "Traceback" not in p.stderr and "ModuleNotFoundError" not in p.stderr, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1, p.stderr
    assert re.search(r'pip install "towenv\[[a-z,]*ray\]"', lines[0]) and re.search(r'"\.\[[a-z,]*ray\]"', lines[0])
    assert not (tmp_path / "runs").exists()


def test_without_rl_names_the_extra(tmp_path):
    p = _run_blocked(["stable_baselines3"], TINY + ["--seeds", "0"], tmp_path)
    assert p.returncode == 2, p.stdout + p.stderr
    assert "Traceback" not in p.stderr, p.stderr
    assert re.search(r'pip install "towenv\[rl[a-z,]*\]"', p.stderr), p.stderr


def test_dry_run_without_ray_resolves_paths_from_cwd(tmp_path):
    p = _run_blocked(["ray"], TINY + ["--seeds", "0", "1", "--num-samples", "2", "--log-dir", "sweep/out",
                                      "--dry-run"], tmp_path)
    assert p.returncode == 0, p.stderr
    cmds = [ln for ln in p.stdout.splitlines() if ln.startswith("python scripts/train.py ")]
    assert len(cmds) == 4
    assert all(f"--log-dir {tmp_path / 'sweep' / 'out'} " in c for c in cmds)
    names = [c.split("--name ")[1].split()[0] for c in cmds]
    assert len(set(names)) == 4 and sum(n.endswith("_r1") for n in names) == 2   # repeats: own folders
    assert sorted(c.split("--seed ")[1].split()[0] for c in cmds) == ["0", "0", "1", "1"]


@pytest.mark.slow
def test_tiny_sweep_on_local_ray(tmp_path):
    pytest.importorskip("ray")
    pytest.importorskip("stable_baselines3")
    # seeds 0, 1, each run twice (--num-samples 2): four trials on a new 2-CPU local Ray instance
    p = subprocess.run([sys.executable, str(SCRIPT), *TINY, "--seeds", "0", "1", "--num-samples", "2",
                        "--cpus", "2", "--log-dir", "runs/tune"], cwd=tmp_path, env=_env(), capture_output=True,
                       text=True, timeout=600)
    out = p.stdout + p.stderr
    assert p.returncode == 0, out[-6000:]
    assert len(re.findall(r"^\[tune\] done  \d/4: ", p.stdout, re.M)) == 4, p.stdout[-3000:]
    log_dir = tmp_path / "runs" / "tune"                     # relative to where the command was run
    res = json.loads((log_dir / "tune_results.json").read_text())
    assert not list(log_dir.glob(".tune_results.json*"))    # atomic write left no temp file
    trials = {t["name"]: t for t in res["trials"]}
    assert len(trials) == 4 and res["ray_address"] == "local"
    for t in trials.values():
        assert t["error"] is None
        assert isinstance(t["best_validation_reward"], float) and math.isfinite(t["best_validation_reward"])
        assert t["num_timesteps"] >= 256
        pol = Path(t["policy"])
        assert pol.is_file() and pol.suffix == ".zip" and log_dir in pol.parents
        assert (Path(t["run_dir"]) / "run_info.json").is_file()
    assert res["best"] == max(trials.values(), key=lambda t: t["best_validation_reward"])["name"]
    # a trial's seed fixes its run: the repeat of each seed gives the same validation reward
    for seed in (0, 1):
        pair = [t for t in trials.values() if t["seed"] == seed]
        assert sorted(t["repeat"] for t in pair) == [0, 1]
        assert pair[0]["best_validation_reward"] == pair[1]["best_validation_reward"]
    assert (log_dir / "ray").is_dir() and Path(res["experiment"]).parent == log_dir / "ray"
