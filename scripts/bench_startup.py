"""Benchmark (issue 15, first use): `import towenv`, the first run of README command 1, and a cached run.

* ``import towenv``: wall time of ``python -P -c "import towenv"`` in fresh processes (``-P``: the current folder
  is not put on the path, as for the console script), median of ``--imports``;
* first run: ``towenv simulate two_part_tow_1 --duration 120 --out <tmp>`` (the console script next to this
  Python, plots included) with an empty numba cache (a fresh
  ``NUMBA_CACHE_DIR``), CPU time of the whole command (user + system of the child) — what a user pays once
  after installing — and the same command again with that cache filled; their difference is the compilation;
* the real-time factor the run's summary reports (it starts after compilation);
* with ``--env``, the batched environment's first use instead of command 1: ``gym.make_vec`` of WinchPayout-v0
  (2 copies), reset and one control step, in fresh processes sharing one empty numba cache — serial (the whole
  first use of an environment), then with ``parallel=True`` (what the parallel batch kernel adds), then serial again
  (cached); CPU of each process.

``--numba-opt N`` sets NUMBA_OPT for both runs (numba's LLVM optimisation level, default 3): with 0 it shows
how much of the compile time is optimisation, and what the run would lose (the cached run's RTF).

    python scripts/bench_startup.py                    # ~1 minute
    PYTHONPATH=../old python scripts/bench_startup.py  # the same for another checkout (run both at once: paired)
    python scripts/bench_startup.py --numba-opt 0
    python scripts/bench_startup.py --env              # ~3 minutes
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _child_cpu(cmd, env):
    """(CPU seconds of the child, wall seconds, completed process)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    w0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - w0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), wall, p


def _find(d, key):
    """The first value of ``key`` anywhere in a nested dict (None if absent)."""
    if isinstance(d, dict):
        if key in d:
            return d[key]
        for v in d.values():
            found = _find(v, key)
            if found is not None:
                return found
    return None


#: the environment's first use (``--env``): argv[1] "serial" or "parallel"
ENV_RUN = """
import sys
import numpy as np, gymnasium as gym, towenv.envs
v = gym.make_vec("towenv/WinchPayout-v0", num_envs=2, vectorization_mode="vector_entry_point",
                 parallel=sys.argv[1] == "parallel")
v.reset(seed=0)
v.step(np.zeros((2, 1), np.float32))
print("stepped")
"""


def env_first_use(env) -> dict:
    """CPU seconds of the environment's first use in fresh processes sharing ``env``'s (empty) numba cache:
    serial, then parallel, then serial cached (see the module docstring)."""
    out = {}
    for label, mode in (("serial, empty cache", "serial"), ("parallel=True after it", "parallel"),
                        ("serial, cached", "serial")):
        cpu, wall, p = _child_cpu([sys.executable, "-P", "-c", ENV_RUN, mode], env)
        if p.returncode != 0 or "stepped" not in p.stdout:
            sys.exit(f"bench_startup: the environment run ({label}) failed:\n{p.stderr[-2000:]}")
        out[label] = cpu
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--imports", type=int, default=7, help="import-time samples (default 7)")
    ap.add_argument("--numba-opt", type=int, choices=(0, 1, 2, 3), default=None)
    ap.add_argument("--env", action="store_true", help="time the batched environment's first use (serial and "
                                                       "parallel=True) instead of README command 1")
    a = ap.parse_args(argv)
    env = dict(os.environ)
    if a.numba_opt is not None:
        env["NUMBA_OPT"] = str(a.numba_opt)
    if a.env:
        with tempfile.TemporaryDirectory() as tmp:
            env["NUMBA_CACHE_DIR"] = str(Path(tmp) / "numba")
            t = env_first_use(env)
        print("# the batched environment's first use (make_vec WinchPayout-v0 x2, reset, one step), CPU per process:")
        for label, cpu in t.items():
            print(f"  {label:24s} {cpu:6.1f} s")
        print(f"  the parallel kernel's compile: {t['parallel=True after it'] - t['serial, cached']:.1f} s CPU")
        return
    imports = [_child_cpu([sys.executable, "-P", "-c", "import towenv"], env)[1] for _ in range(a.imports)]
    with tempfile.TemporaryDirectory() as tmp:
        env["NUMBA_CACHE_DIR"] = str(Path(tmp) / "numba")
        out = Path(tmp) / "out"
        # README command 1 as a user runs it (the console script, progress bar, plots), its output in the temporary
        # folder. Not ``python -m towenv``: measured on 2026-12-04, that way the same run makes ~2.2 million
        # mmap/munmap calls instead of ~0.23 million (strace -c) and spends ~18 s more CPU in the kernel
        script = Path(sys.executable).parent / "towenv"
        head = [str(script)] if script.exists() else [sys.executable, "-m", "towenv"]
        cmd = head + ["simulate", "two_part_tow_1", "--duration", "120", "--out", str(out)]
        cold_cpu, cold_wall, p = _child_cpu(cmd, env)
        if p.returncode != 0:
            sys.exit(f"bench_startup: the first run failed:\n{p.stderr}")
        rtf = _find(json.loads((out / "summary.json").read_text()), "real_time_factor")
        warm_cpu, warm_wall, p = _child_cpu(cmd, env)
    opt = f"NUMBA_OPT={a.numba_opt}" if a.numba_opt is not None else "numba's default optimisation"
    print(f"# towenv first use — Python {sys.version.split()[0]}, {os.cpu_count()} cores, {opt}")
    print(f"import towenv: median {statistics.median(imports):.2f} s wall (min {min(imports):.2f}, max "
          f"{max(imports):.2f}; {len(imports)} fresh processes; goal ≤ 1 s)")
    src = subprocess.run([sys.executable, "-P", "-c", "import towenv; print(towenv.__file__)"], env=env,
                         capture_output=True, text=True).stdout.strip()
    print(f"towenv measured: {src}")
    print("README command 1 (towenv simulate two_part_tow_1 --duration 120 --out ..., with its plots):")
    print(f"  empty numba cache:  {cold_cpu:6.1f} s CPU ({cold_wall:.1f} s wall)")
    print(f"  cache filled:       {warm_cpu:6.1f} s CPU ({warm_wall:.1f} s wall)")
    print(f"  compilation:        {cold_cpu - warm_cpu:6.1f} s CPU (goal ≤ 30 s)")
    print(f"  real-time factor in the first run's summary (after compilation): {rtf}")


if __name__ == "__main__":
    main()
