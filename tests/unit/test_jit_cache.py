"""Numba's cache checks only the compiled function's own file; towenv.core.jit drops the package's cached
kernels when any kernel module's source changed (a kernel compiled against an older callee must not load)."""
import pytest

from towenv.core import jit


def _package(tmp_path):
    for folder in jit.KERNEL_FOLDERS:
        (tmp_path / folder / "__pycache__").mkdir(parents=True)
        (tmp_path / folder / "mod.py").write_text(f"# {folder}\n")
    return tmp_path


def test_stale_caches_are_dropped_when_a_callee_changes(tmp_path):
    root = _package(tmp_path)
    cached = root / "core" / "__pycache__" / "houbolt.advance-1.py311.nbi"
    cached.write_text("x")
    assert jit.drop_stale_caches(root)                 # no stamp yet: unknown provenance, dropped
    assert not cached.exists()
    cached.write_text("x")                             # numba writes its cache for these sources
    (root / "envs" / "__pycache__" / "stepper.f-1.py311.nbc").write_text("y")
    assert not jit.drop_stale_caches(root)             # same sources: the cache stays
    assert cached.exists()
    (root / "core" / "mod.py").write_text("# core, edited\n")    # a callee's module changes
    assert jit.drop_stale_caches(root)
    assert not cached.exists() and not (root / "envs" / "__pycache__" / "stepper.f-1.py311.nbc").exists()
    assert (root / "core" / "__pycache__" / jit.STAMP_NAME).read_text().strip() == jit.kernel_sources_digest(root)


def test_the_installed_package_has_a_current_stamp():
    """Importing towenv ran the guard: the stamp matches the installed kernel sources (or the install is
    read-only and there is no stamp)."""
    from pathlib import Path
    import towenv  # noqa: F401
    root = Path(jit.__file__).resolve().parent.parent
    stamp = root / "core" / "__pycache__" / jit.STAMP_NAME
    if stamp.exists():
        assert stamp.read_text().strip() == jit.kernel_sources_digest(root)


_DIGEST_RUN = """
import hashlib, numpy as np, towenv
from towenv.core import body_dynamics, houbolt
sim = towenv.make_simulator("two_part_coastal_ss4", dt=0.05)
sim.advance_steps(200)
h = hashlib.sha1()
for a in (sim.positions, sim.velocities, sim.tensions):
    h.update(np.ascontiguousarray(a).tobytes())
towenv.Simulator("two_part_tow_1").advance(0.5)
towenv.Simulator("series_multitow").advance(0.5)
for fn in (houbolt.iterate_coefficients, houbolt.node_local_solve, body_dynamics.aft_rotational_stiffness):
    print(fn.__name__, len(fn.signatures))
print(h.hexdigest())
"""

PHASES = ("iterate_coefficients", "node_local_solve", "aft_rotational_stiffness")


def test_a_compiling_run_and_a_cached_run_give_the_same_bits_and_compile_each_phase_once(tmp_path):
    """Determinism across processes: a run that compiles the kernels (empty numba cache) and a run that loads
    them from the cache give the same trajectory bit for bit. With fast-math (reassociation) this failed once
    the Houbolt step was split into phase functions: numba links a callee's code into each caller and
    re-optimises it there, and which copy a call reached depended on compile-versus-load (jit.py).

    The compiling run also checks issue 15's first use: flags computed at run time, not literal ``True``/``False``,
    so numba compiles each phase of the Houbolt step once — a sea scene, a two-part tow and a series tow (aft tow
    point, both couplings' code paths) leave one signature each (a literal-typed flag used to add a second
    compilation of ~3–8 s). The cached run loads the callers compiled and never compiles a phase (0 signatures:
    the cache served them). One test for both because each compiling run costs over a minute of CPU."""
    import os
    import subprocess
    import sys
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_DISABLE_JIT"} | {"NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    runs = []
    for _ in range(2):
        p = subprocess.run([sys.executable, "-P", "-c", _DIGEST_RUN], env=env, capture_output=True, text=True,
                           timeout=900)
        assert p.returncode == 0, p.stderr[-2000:]
        lines = p.stdout.strip().splitlines()
        runs.append((lines[-1], dict(line.split() for line in lines[-4:-1])))
        if len(runs) == 1:                       # the first run compiled and wrote the cache
            assert list((tmp_path / "cache").rglob("*.nbi")), "the first run wrote no numba cache"
    assert runs[0][0] == runs[1][0]
    assert runs[0][1] == dict.fromkeys(PHASES, "1"), runs[0][1]
    assert runs[1][1] == dict.fromkeys(PHASES, "0"), runs[1][1]
    assert jit.FASTMATH is False


def test_kernels_use_the_numpy_error_model():
    """towenv.core.jit.njit compiles with error_model="numpy": a float division by zero gives the IEEE result
    (which the steps' finiteness checks turn into a reported numerical failure) instead of raising
    ZeroDivisionError from inside a kernel."""
    import math

    @jit.njit(cache=False)
    def ratio(a, b):
        return a / b

    assert ratio(1.0, 0.0) == math.inf
    assert ratio(-1.0, 0.0) == -math.inf
    assert math.isnan(ratio(0.0, 0.0))
    assert ratio(3.0, 2.0) == 1.5
