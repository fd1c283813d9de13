"""Compiled recording of :func:`towenv.core.run.simulate`.

``simulate`` used to advance the simulator record by record from Python (``Simulator.advance_steps`` then
``Recorder.record``): ~15–20 µs of Python and numba-dispatch overhead per record, a large share of the wall
time when the step is coarse (one kernel step per record). :func:`advance_recorded` instead advances many
records in ONE call of ``kernels.advance`` with a :class:`~towenv.core.model.Recording`: after every ``every``
steps the kernel copies what the fast :class:`~towenv.core.run.Recorder` keeps (``hist_r[0]``, the body nodes'
``hist_r`` levels, ``hist_ang``, ``body_chart``, ``tens_hist[0]``, ``top_react``; for a heave compensator the
sheave and ship heights and k, b) into the recorder's preallocated arrays (``houbolt.record_row``).

The results are bit-identical to the per-record loop (tested, ``tests/unit/test_recording.py``): the kernel
runs on the same arrays (``Simulator.kernel_data()``), the tow points come from ``Simulator._tow_points``
(aligned blocks: independent of the chunking) and each step's time is reckoned from its record's start,
``step_count * dt`` as in ``Simulator.advance_steps``. Chunks are sized to ~0.2 s of wall time (at most
``MAX_CHUNK_STEPS`` steps), which keeps the progress bar and Ctrl-C responsive.

Scope: the Houbolt :class:`~towenv.core.simulator.Simulator` without a winch (the fast recorder's scope;
a winch changes the array shapes mid-run). Other solvers and winch scenes use the per-record loop.

Until 2026-12-04 the recording was a compiled loop of its own around ``kernels.advance``; numba links a
callee's code into each caller and generates it again there, so that loop cost as much compilation as
``advance`` itself (~10 % of the first run's). It needed its cache stamped with ``kernels.py``'s hash; the
package's cache guard (``towenv.core.jit``) covers ``advance``.
"""
from __future__ import annotations

import time

import numpy as np

from . import kernels as K
from .model import Recording

#: largest chunk of physics steps advanced by one compiled call
MAX_CHUNK_STEPS = 1 << 15
#: wall time aimed at per compiled call (s): the progress bar and KeyboardInterrupt are served between calls
TARGET_CHUNK_WALL = 0.2
_FIRST_CHUNK_STEPS = 256


def _recording(rec, cnodes, every, row0, step0, n_comp):
    """The :class:`~towenv.core.model.Recording` of ``rec``'s arrays for records from row ``row0`` on (the call
    starts at step ``step0``); ``n_comp`` rows of compensator records (0 without one)."""
    return Recording(np.array([every, row0, step0], np.int64), np.ascontiguousarray(rec.bnodes, np.int64), cnodes,
                     rec.R, rec.RB, rec.A, rec.C, rec.T, rec.top_force, np.zeros((n_comp, 3, 2)),
                     np.zeros((n_comp, 2)))


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
    K.advance(0, sim.settings.dt, np.empty((0, 3)), *kd.head, sim.t, kd.wave,
              _recording(rec, cnodes, int(every), rec.n, sim.step_count, 0))


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
        i0 = rec.n
        out = _recording(rec, cnodes, every, i0, step0, m if has_comp else 0)
        CZ, CKB = out.CZ, out.CKB
        w0 = time.perf_counter()
        st, kk, el, md = K.advance(m * every, dt, tops, *kd.head, step0 * dt, kd.wave, out)
        wall = time.perf_counter() - w0
        st, kk = int(st), int(kk)
        # records complete: all of them, or those before the failed step kk (its record j, step k within it)
        j = m if st == K.OK else kk // every
        k = kk - j * every
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
