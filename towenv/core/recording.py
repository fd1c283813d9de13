"""Compiled recording loop of :func:`towenv.core.run.simulate`.

``simulate`` used to advance the simulator record by record from Python (``Simulator.advance_steps`` then
``Recorder.record``): ~15–20 µs of Python and numba-dispatch overhead per record, a large share of the wall
time when the step is coarse (one kernel step per record). :func:`advance_recorded` instead advances many
records in ONE compiled call (:func:`_record_chunk`): for each record it runs ``kernels.advance`` for
``every`` steps and copies what the fast :class:`~towenv.core.run.Recorder` keeps (``hist_r[0]``, the body
nodes' ``hist_r`` levels, ``hist_ang``, ``body_chart``, ``tens_hist[0]``, ``top_react``; for a heave
compensator the sheave and ship heights and k, b) into the recorder's preallocated arrays.

The results are bit-identical to the per-record loop (tested, ``tests/unit/test_recording.py``): the kernel is
called with the same arguments (``Simulator.kernel_data()``), the tow points come from ``Simulator._tow_points``
(aligned blocks: independent of the chunking) and each record's start time is ``step_count * dt`` as in
``Simulator.advance_steps``. Chunks are sized to ~0.2 s of wall time (at most ``MAX_CHUNK_STEPS`` steps),
which keeps the progress bar and Ctrl-C responsive.

Scope: the Houbolt :class:`~towenv.core.simulator.Simulator` without a winch (the fast recorder's scope;
a winch changes the array shapes mid-run). Other solvers and winch scenes use the per-record loop.

Disk cache: numba keys a cached function by its own source file only, and would keep using stale machine
code of ``kernels.advance`` (compiled into :func:`_record_chunk`) after ``kernels.py`` changes. The cache
index of :func:`_record_chunk` is therefore stamped with a hash of ``kernels.py`` as well (see
:func:`_stamp_dependencies`). Its first compile (and the first after ``kernels.py`` changes) recompiles the
whole kernel call tree inside it: ~5 s on a 2-core Xeon with the kernels' own cache warm (on top of the
kernels' own recompile, ~25 s, when ``kernels.py`` changed), then it is loaded from the cache (~0.1 s).
"""
from __future__ import annotations

import hashlib
import time
from pathlib import Path

import numpy as np
from numba import njit

from . import kernels as K

#: largest chunk of physics steps advanced by one compiled call
MAX_CHUNK_STEPS = 1 << 15
#: wall time aimed at per compiled call (s): the progress bar and KeyboardInterrupt are served between calls
TARGET_CHUNK_WALL = 0.2
_FIRST_CHUNK_STEPS = 256


@njit(cache=True)
def _record_chunk(n_rec, every, dt, tops, t0s, head, wave, src, bnodes, cnodes, i0, R, RB, A, C, T, F, CZ, CKB):
    """Advance ``n_rec`` records of ``every`` steps; after record j write the state into row ``i0 + j`` of
    the record arrays (``CZ``/``CKB``, the compensator's, into row j; empty without one). ``tops`` holds the
    tow points of all ``n_rec * every`` steps, ``t0s[j]`` the time at the start of record j.
    Returns (records done, status, step index in the failed record, element, max|δT|) as ``kernels.advance``."""
    hist_r, hist_ang, chart, tens_hist, top_react, comp = src
    nn = hist_r.shape[1]
    nb = hist_ang.shape[1]
    ns = tens_hist.shape[1]
    nbn = bnodes.shape[0]
    has_comp = CZ.shape[0] > 0
    for j in range(n_rec):
        st, k, el, md = K.advance(every, dt, tops[j * every:(j + 1) * every], *head, t0s[j], wave)
        if st != K.OK:
            return j, st, k, el, md
        i = i0 + j
        for a in range(nn):
            for c in range(3):
                R[i, a, c] = hist_r[0, a, c]
        for lv in range(3):
            for b in range(nbn):
                for c in range(3):
                    RB[i, lv, b, c] = hist_r[lv, bnodes[b], c]
            for b in range(nb):
                for c in range(3):
                    A[i, lv, b, c] = hist_ang[lv, b, c]
        for b in range(nb):
            for r in range(3):
                for c in range(3):
                    C[i, b, r, c] = chart[b, r, c]
        for s in range(ns):
            T[i, s] = tens_hist[0, s]
        for c in range(3):
            F[i, c] = top_react[c]
        if has_comp:
            for lv in range(3):
                CZ[j, lv, 0] = hist_r[lv, cnodes[0], 2]
                CZ[j, lv, 1] = hist_r[lv, cnodes[1], 2]
            CKB[j, 0] = comp[K.C_K]
            CKB[j, 1] = comp[K.C_B]
    return n_rec, K.OK, -1, -1, 0.0


def _stamp_dependencies(dispatcher, *modules):
    """Make the on-disk cache entry of ``dispatcher`` depend on the source of ``modules`` too (numba checks
    only the defining file, so a change in a callee's file would silently reuse stale machine code)."""
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if cache_file is None or not hasattr(cache_file, "_source_stamp"):
        return          # caching disabled (or numba internals changed): nothing stale can be loaded
    digest = hashlib.sha256()
    for m in modules:
        digest.update(Path(m.__file__).read_bytes())
    cache_file._source_stamp = (cache_file._source_stamp, digest.hexdigest())


_stamp_dependencies(_record_chunk, K)


def supports(sim, rec) -> bool:
    """True when :func:`advance_recorded` reproduces the per-record loop for ``sim`` and ``rec``: the Houbolt
    scheme on a ``Simulator`` (``_run``, ``advance_steps`` and ``_tow_points`` not overridden) with the fast
    recorder."""
    from .schemes import HouboltScheme
    from .simulator import Simulator
    cls = type(sim)
    return (bool(rec.fast) and sim.winch[K.W_MODE] == 0 and type(sim.scheme) is HouboltScheme
            and cls._run is Simulator._run and cls.advance_steps is Simulator.advance_steps and cls._tow_points is Simulator._tow_points
            and cls._wave_arrays is Simulator._wave_arrays)


def warm_up(sim, rec, every: int) -> None:
    """Compile (or load from numba's cache) the recording loop for ``sim``'s and ``rec``'s argument types with
    a call that records nothing and leaves every array untouched — so that a caller can keep compilation out
    of its timing and its progress display."""
    kd = sim.kernel_data()
    s = sim.system
    cnodes = np.array([s.comp_node, s.top_node], np.int64)
    src = (sim.hist_r, sim.hist_ang, sim.body_chart, sim.tens_hist, sim.top_react, sim.comp)
    _record_chunk(0, int(every), sim.settings.dt, np.empty((0, 3)), np.empty(0), kd.head, kd.wave, src, rec.bnodes,
                  cnodes, rec.n, rec.R, rec.RB, rec.A, rec.C, rec.T, rec.top_force, np.zeros((0, 3, 2)),
                  np.zeros((0, 2)))


def advance_recorded(sim, rec, n_records: int, every: int, on_chunk=None, max_chunk_steps: int | None = None):
    """Advance ``sim`` by ``n_records * every`` steps, recording into ``rec`` after every ``every`` steps —
    what ``for _ in range(n_records): sim.advance_steps(every); rec.record()`` does, bit for bit, in compiled
    chunks. ``on_chunk(steps)`` is called after each chunk (progress). On numerical failure the records up
    to the last complete one are kept (``rec.n``), the simulator is left at the last good step with its step
    counter and ``counters`` as ``advance_steps`` leaves them, and the same
    :class:`~towenv.SimulationDivergence` is raised."""
    if not supports(sim, rec):
        raise ValueError("advance_recorded: needs the Houbolt Simulator without a winch (use the per-record loop)")
    every = int(every)
    dt = sim.settings.dt
    cap = max(every, int(max_chunk_steps or MAX_CHUNK_STEPS))
    s = sim.system
    cnodes = np.array([s.comp_node, s.top_node], np.int64)
    has_comp = bool(rec.has_comp)
    chunk = max(1, _FIRST_CHUNK_STEPS // every) if max_chunk_steps is None else max(1, cap // every)
    done = 0
    while done < n_records:
        m = min(chunk, n_records - done)
        step0 = sim.step_count
        tops = sim._tow_points(step0 + 1, m * every)
        t0s = (step0 + every * np.arange(m, dtype=np.int64)) * dt        # = Simulator.t at each record's start
        kd = sim.kernel_data()
        head, wave = kd.head, kd.wave
        src = (sim.hist_r, sim.hist_ang, sim.body_chart, sim.tens_hist, sim.top_react, sim.comp)
        CZ = np.zeros((m if has_comp else 0, 3, 2))
        CKB = np.zeros((m if has_comp else 0, 2))
        i0 = rec.n
        w0 = time.perf_counter()
        j, st, k, el, md = _record_chunk(m, every, dt, tops, t0s, head, wave, src, rec.bnodes, cnodes, i0,
                                         rec.R, rec.RB, rec.A, rec.C, rec.T, rec.top_force, CZ, CKB)
        wall = time.perf_counter() - w0
        j = int(j)
        rec.t[i0:i0 + j] = (step0 + every * np.arange(1, j + 1, dtype=np.int64)) * dt
        if has_comp and j:
            z = CZ[:j, :, 0] - CZ[:j, :, 1]
            act = rec.actuators
            act["stroke"][i0:i0 + j] = z[:, 0]
            act["stroke_velocity"][i0:i0 + j] = (3 * z[:, 0] - 4 * z[:, 1] + z[:, 2]) / (2 * dt)
            act["stiffness"][i0:i0 + j] = CKB[:j, 0]
            act["damping"][i0:i0 + j] = CKB[:j, 1]
        rec.n += j
        sim.step_count += j * every
        done += j
        if st != K.OK:
            if st == K.NEED_REMESH:         # cannot happen without a winch
                raise RuntimeError("advance_recorded: unexpected NEED_REMESH")
            t0 = float(t0s[j])
            exc = sim._divergence(int(st), int(el), float(md), t0 + (int(k) + 1) * dt)
            # as Simulator.advance_steps: the kernel stopped at the last good step
            sim.step_count += int(round((exc.time - t0) / dt)) - 1
            if on_chunk is not None and j:
                on_chunk(j * every)
            raise exc
        if on_chunk is not None:
            on_chunk(m * every)
        if max_chunk_steps is None:
            per_step = wall / (m * every)
            target = cap if per_step <= 0 else int(min(cap, TARGET_CHUNK_WALL / per_step))
            chunk = max(1, target // every)
