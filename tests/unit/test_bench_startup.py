"""scripts/bench_startup.py --env (issue 15, docs/environments.md "The parallel kernel's first compile"): the three
processes it times are the environment's first use in the modes named, sharing the caller's numba cache, and a
failing run stops the benchmark naming the run, not with a figure."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from helpers import load_script

pytest.importorskip("gymnasium")


def test_env_run_steps_the_batched_env_in_the_mode_named():
    bench = load_script("bench_startup")
    for mode in ("serial", "parallel"):
        p = subprocess.run([sys.executable, "-P", "-c", bench.ENV_RUN + "print(v.unwrapped.rows.stepper.parallel)",
                            mode], capture_output=True, text=True, timeout=900, env=dict(os.environ))
        assert p.returncode == 0, p.stderr[-2000:]
        assert p.stdout.split()[-2:] == ["stepped", str(mode == "parallel")]


def test_env_first_use_runs_serial_parallel_cached_in_one_cache_and_names_a_failure(monkeypatch):
    bench = load_script("bench_startup")
    calls = []

    class Done:
        returncode, stdout, stderr = 0, "stepped\n", ""

    def child(cmd, env):
        calls.append((cmd[-1], env["NUMBA_CACHE_DIR"]))
        return float(len(calls)), 0.0, Done()

    monkeypatch.setattr(bench, "_child_cpu", child)
    out = bench.env_first_use({"NUMBA_CACHE_DIR": "/tmp/x"})
    assert [c[0] for c in calls] == ["serial", "parallel", "serial"] and {c[1] for c in calls} == {"/tmp/x"}
    assert list(out.values()) == [1.0, 2.0, 3.0]

    class Failed:
        returncode, stdout, stderr = 1, "", "boom"

    monkeypatch.setattr(bench, "_child_cpu", lambda cmd, env: (1.0, 0.0, Failed()))
    with pytest.raises(SystemExit, match=r"environment run \(serial, empty cache\) failed:\nboom"):
        bench.env_first_use({"NUMBA_CACHE_DIR": "/tmp/x"})
