"""The project's numba decorator, and a guard that keeps numba's on-disk cache consistent.

``njit`` is numba's with ``fastmath`` off for every kernel (exact IEEE arithmetic: LLVM may not reassociate
or fuse floating-point operations) and ``cache=True`` at the call sites. Fast-math used to be on; it was
turned off (2026-12-02, issue 16) because it made the last bits of a trajectory depend on how LLVM happened to
inline and re-optimise a kernel: numba links a callee's optimised code into every caller and re-optimises it
there, and with reassociation/contraction allowed those copies differ in the last bits; which copy a call
reaches depends on whether the kernels were compiled in the process or loaded from numba's cache. Measured on
the phase-split Houbolt step: with fast-math, a first (compiling) run and a second (cached) run of the same
code on the same machine gave different trajectories (~1e-11 relative); without it both gave the same bits,
and the same bits as the unsplit step. Without fast-math the compiled results do not depend on the code's
structure at all (refactors can be checked bit for bit), at no measurable cost (paired runs in
docs/architecture.md).

Every kernel compiled through :func:`njit` (the Houbolt step and its phases, the loads, the environments' stepper
and measurement row; the modules that import numba's own ``njit`` — the explicit schemes, the tow-point
recurrence, the environments' action/observation/reward kernels — keep numba's defaults) also compiles with
numba's ``error_model="numpy"`` (since 2026-12-05): a float division by zero
gives ±inf/NaN, which the steps' finiteness checks report as a numerical failure (time, element, cause), instead
of a compiled zero test before every division and a ``ZeroDivisionError`` raised from deep inside a kernel. The
arithmetic of every other division is the same IEEE operation, so results are bit for bit those of the Python
error model (``scripts/trajectory_digest.py``); the step ran 4–8 % faster without the tests (docs/architecture.md).

Numba's cache checks only the source file of the function it compiled, not the files of the kernels that
function calls: the Houbolt step in ``houbolt.py`` compiled against an older ``cable_loads.py`` would be
loaded from the cache after ``cable_loads.py`` changed (an upgrade, or a developer's edit). The guard below
hashes the sources of every module that holds compiled kernels; when the hash differs from the one stored
next to the cache, the package's cached kernels are dropped before anything is loaded (they recompile on
first use). It costs about a millisecond per import.
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

from numba import njit as _njit

#: the fast-math flags every kernel compiles with: none (see the module docstring)
FASTMATH = False
#: numba's error model for every kernel: IEEE results for a division by zero, no compiled zero tests
ERROR_MODEL = "numpy"

#: the package's folders that hold compiled kernels (their ``__pycache__`` holds numba's cache files)
KERNEL_FOLDERS = ("core", "envs", "linear", "verification")
STAMP_NAME = "towenv-kernel-sources.sha1"


def njit(*args, **kw):
    kw.setdefault("fastmath", FASTMATH)
    kw.setdefault("error_model", ERROR_MODEL)
    return _njit(*args, **kw)


def njit_internal(fn):
    """:func:`njit` for a kernel that only compiled code calls: cached, without numba's reference counting
    (it must not allocate) and without the Python and C entry points numba builds for every compiled
    function. Those wrappers unbox or box every array of the kernels' large argument structures (the
    Houbolt step's ~100 arrays): measured, they were about a third of the compile time of ``houbolt._step``.
    Calling such a kernel from Python raises; tests go through a compiled entry (``houbolt_step_entry``)."""
    return njit(cache=True, _nrt=False, no_cpython_wrapper=True, no_cfunc_wrapper=True)(fn)


def kernel_sources_digest(package_root: Path | None = None) -> str:
    """SHA-1 over the sources of every module in :data:`KERNEL_FOLDERS` (names and contents)."""
    root = package_root or Path(__file__).resolve().parent.parent
    h = hashlib.sha1()
    for folder in KERNEL_FOLDERS:
        for p in sorted((root / folder).glob("*.py")):
            h.update(f"{folder}/{p.name}\0".encode())
            h.update(p.read_bytes())
    return h.hexdigest()


def drop_stale_caches(package_root: Path | None = None) -> bool:
    """Delete the package's numba cache files if the kernel sources changed since they were written.
    Returns True if files were deleted. Read-only installs are left alone (numba then caches under its
    user-wide folder, keyed by the source path; ``NUMBA_CACHE_DIR`` users clear that folder themselves)."""
    root = package_root or Path(__file__).resolve().parent.parent
    stamp = root / "core" / "__pycache__" / STAMP_NAME
    digest = kernel_sources_digest(root)
    try:
        if stamp.read_text().strip() == digest:
            return False
    except OSError:
        pass
    dropped = False
    try:
        for folder in KERNEL_FOLDERS:
            cache = root / folder / "__pycache__"
            if not cache.is_dir():
                continue
            for f in list(cache.glob("*.nbi")) + list(cache.glob("*.nbc")):
                f.unlink(missing_ok=True)
                dropped = True
        stamp.parent.mkdir(exist_ok=True)
        tmp = stamp.with_name(f"{STAMP_NAME}.{os.getpid()}.tmp")
        tmp.write_text(digest + "\n")
        os.replace(tmp, stamp)
    except OSError:
        pass
    return dropped


if os.environ.get("TOWENV_KEEP_NUMBA_CACHE") != "1":
    drop_stale_caches()
