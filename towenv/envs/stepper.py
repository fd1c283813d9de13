"""The environments' control step: one compiled call advances B simulator copies by one control step.

:class:`BatchStepper` holds B :class:`~towenv.core.simulator.Simulator` copies (they may differ in node
count, scene and sea). Each copy's arguments for :func:`towenv.core.kernels.advance` come from the
simulator's one public accessor, :meth:`~towenv.core.simulator.Simulator.kernel_data` (the ONE place that
maps Simulator attributes to kernel arguments), and are kept in a ``numba.typed.List``, so a step costs one
dispatch for all B copies instead of unboxing ~70 arrays per copy per call (that unboxing alone was ~55 µs
of the ~130 µs environment step).

One call of :meth:`BatchStepper.step`:

1. writes each copy's actuator command (compensator gains k, b or winch payout speed) into its
   ``comp``/``winch`` parameter arrays;
2. advances every active copy ``n`` physics steps with ``kernels.advance`` (serial loop over copies, or
   ``prange`` with ``parallel=True``), reading the tow-point path from a per-copy buffer;
3. fills each copy's *measurement row* (:mod:`towenv.envs.measurements`: IMU, tension, body and actuator
   readings in SI units, effort and time left) into a (B, len(MEAS_COLUMNS)) array.

A copy whose kernel returns ``NEED_REMESH`` (winch node insertion/removal changes its array shapes) is
remeshed in Python (``KernelData.remesh``), its argument tuple rebuilt, and the rest of its control step
run by the same kernel; a copy that fails numerically gets a :class:`~towenv.errors.SimulationDivergence`
(``KernelData.divergence``: identical to what ``Simulator.advance_steps`` would raise) in the returned
``failures`` dict, with its state at the last good step and its measurement row still filled.

Tow-point path (:class:`TowPointBuffer`): the vessel motion is evaluated in blocks of ``BLOCK`` physics
steps aligned to absolute step indices. On a straight constant-speed leg with an RAO vessel model (the
environments' case) the wave phases advance linearly in time, so each block is computed with an exact
complex exponential at its first step and a phase recurrence ``E_{s+1} = E_s·exp(iΩΔt)`` after that
(Ω = encounter frequency); otherwise the exact ``TowPointPath.position``. The recurrence differs from the
exact evaluation by round-off only (≤ 1e-9 m, tested); because blocks are aligned to absolute steps the
result does not depend on how the caller chunks time, so single and batched environments are bit-identical. A copy's
buffer is refilled ``SPAN_BLOCKS`` blocks at a time (:meth:`TowPointBuffer.span`: the blocks' exact anchors in one
vectorised call, the same values as block by block).

Until issue 16 this module was ``towenv.core.batch``; the core is physics only now.
"""
from __future__ import annotations


import numpy as np
from numba import njit as _numba_njit
from numba import prange
from numba.typed import List as _TypedList

from ..core import kernels as K
from ..core.model import NO_RECORDING
from ..core.jit import njit, njit_internal
from ..core.tow_point import BLOCK, TowPointBuffer, _phase_recurrence  # noqa: F401  (re-exported)
from .measurements import MEAS_COLUMNS, NREF, R_HALF_STROKE, R_MAXSTEPS, R_STEPS, R_TREF, R_VMAX, gather_arrays, \
    measure_copy

__all__ = ["BatchStepper", "TowPointBuffer", "BLOCK", "ACT_NONE", "ACT_COMP_GAINS",
           "ACT_WINCH_SPEED", "ACT_COMP_COMMAND"]

#: actuator kinds: what the command columns U[:, 0:2] mean
ACT_NONE, ACT_COMP_GAINS, ACT_WINCH_SPEED, ACT_COMP_COMMAND = 0, 1, 2, 3
#: a copy's tow-point buffer holds two consecutive spans of SPAN_BLOCKS aligned blocks (SPAN physics steps
#: each), refilled a span at a time: one refill per 4 blocks instead of one per block, whose fixed Python cost
#: (~0.3 ms: the blocks' exact anchors, the mean track) was ~10 % of a batched environment step
SPAN_BLOCKS = 4
SPAN = SPAN_BLOCKS * BLOCK
#: status of a copy whose tow-point buffer does not cover the step (Python refills it and re-runs)
NEED_TOPS = -1


def _signature(kd, sim):
    """The objects whose identity decides whether a copy's kernel tuples must be rebuilt (a winch remesh or
    ``set_sea`` replaces them); ``kd`` = ``sim.kernel_data()``."""
    return (kd.args, kd.state, kd.work, kd.saved, kd.wave, kd.comp, kd.winch, sim.system)


@njit(cache=True, inline="always")
def _write_command(comp, winch, kind, u0, u1):
    """A copy's actuator command of this control step into its parameter arrays: compensator gains k, b, the
    compensator's command, or the winch's payout speed (``kind``; ``ACT_NONE`` writes nothing)."""
    if kind == ACT_COMP_GAINS:
        comp[K.C_K] = u0
        comp[K.C_B] = u1
    elif kind == ACT_COMP_COMMAND:
        comp[K.C_CMD] = u0
    elif kind == ACT_WINCH_SPEED:
        winch[K.W_VCMD] = u0


@njit(cache=True, inline="always")
def _copy_step(item, g, n, dt, blk, mblk, off, t0, kind, u0, u1, ref, step_count, out, res):
    """One copy's control step: its command, ``n`` physics steps, its measurement row. Inlined into the batch
    loop by numba (``inline="always"``): as a compiled function of its own it was one more level that links and
    generates again the machine code of the whole step below it (towenv.core.jit.njit_internal)."""
    _write_command(g.comp, g.winch, kind, u0, u1)
    st, k, el, md = K.advance(n, dt, blk[off:off + n], *item[0], t0, item[1], item[2])
    res[0] = st
    res[1] = k
    res[2] = el
    res[3] = md
    if st == K.OK:
        w3a = np.empty(3)
        w3b = np.empty(3)
        w3c = np.empty(3)
        measure_copy(g, ref, dt, (step_count + n) * dt, out, w3a, w3b, w3c, blk, mblk, off + n - 1, n)


@njit_internal
def _copy_physics(item, comp, winch, n, dt, tops, t0, kind, u0, u1, res):
    """A copy's command and ``n`` physics steps, without its measurement row: what the ``parallel=True`` loop calls
    per copy. A compiled function of its own (without reference counting: nothing here allocates) rather than
    :func:`_copy_step` inlined — numba generates again the machine code of everything a kernel inlines or links
    into it, and inside a ``prange`` region that cost 170–250 s of CPU at the first ``parallel=True`` step on the
    ``znver3`` host against 60–85 s this way (docs/environments.md "The parallel kernel's first compile"). Returns
    the status."""
    _write_command(comp, winch, kind, u0, u1)
    st, k, el, md = K.advance(n, dt, tops, *item[0], t0, item[1], item[2])
    res[0] = st
    res[1] = k
    res[2] = el
    res[3] = md
    return st


def _entry_point(kern, args, items, gathers):
    """``(kern, items, gathers, compiled entry point)`` of the overload of ``kern`` that ``args`` select, or None.

    Calling the overload's entry point skips the dispatcher's type resolution (measured 7.3 → 4.2 µs per call
    for the batch kernel, scripts/bench_env_parts.py; most of it the typed lists' Python-level ``typeof``):
    valid while the arguments keep their types — the stepper's own arrays never change type, the typed lists
    are checked by identity and ``kind`` must be a Python int (see :meth:`BatchStepper.step`)."""
    try:
        from numba import typeof
        cres = kern.overloads.get(tuple(typeof(a) for a in args))
    except Exception:                       # an unexpected numba internals change: keep the dispatcher
        return None
    if cres is None:
        return None
    return kern, items, gathers, cres.entry_point


#: :func:`_copy_offset`'s answers for a copy that does not step: inactive, or its tow-point buffer does not cover the steps
INACTIVE, NO_TOPS = -1, -2


@njit(cache=True, inline="always")
def _copy_offset(b, nsteps, count_step, base, end, count, refs, res):
    """Where copy b's control step starts in its tow-point buffer (row ``off`` ≥ 0; its control-step count advanced
    when ``count_step``), or ``INACTIVE`` (``nsteps[b] < 0``), or ``NO_TOPS`` (the buffer does not cover the steps:
    ``res[b, 0] = NEED_TOPS``, nothing done — the caller counts the copy as not OK)."""
    n = nsteps[b]
    if n < 0:
        return INACTIVE
    first = count[b] + 1
    off = first - base[b]
    if off < 0 or first + n > end[b]:
        res[b, 0] = NEED_TOPS
        return NO_TOPS
    if count_step:
        refs[b, R_STEPS] += 1.0
    return off


def _step_batch_py(items, gathers, nsteps, count_step, dt, blk, mblk, base, end, count, kind, U, refs, res, M):
    """Advance every copy b with ``nsteps[b] >= 0`` by that many steps from step ``count[b]`` (tow points
    from ``blk[b]``, whose first row is step ``base[b]``, valid up to step ``end[b]`` excluded); returns the
    number of copies not OK (``NEED_TOPS``: the buffer does not cover the steps — nothing done)."""
    B = len(items)
    nbad = 0
    for b in range(B):
        off = _copy_offset(b, nsteps, count_step, base, end, count, refs, res)
        if off < 0:
            if off == NO_TOPS:
                nbad += 1
            continue
        n = nsteps[b]
        _copy_step(items[np.int64(b)], gathers[np.int64(b)], n, dt, blk[b], mblk[b], off, count[b] * dt, kind,
                   U[b, 0], U[b, 1], refs[b], count[b], M[b], res[b])
        if res[b, 0] == K.OK:
            count[b] += n
        else:
            nbad += 1
    return nbad


def _step_batch_parallel_py(items, gathers, nsteps, count_step, dt, blk, mblk, base, end, count, kind, U, refs, res,
                            M):
    """:func:`_step_batch_py` with the copies on numba's threads (``prange``; compiled with ``parallel=True``): each
    copy's physics through :func:`_copy_physics`, then its measurement row — the same operations in the same order
    as the serial loop's, so the same bits (tested)."""
    B = len(items)
    nbad = 0
    for b in prange(B):
        off = _copy_offset(b, nsteps, count_step, base, end, count, refs, res)
        if off < 0:
            if off == NO_TOPS:
                nbad += 1
            continue
        n = nsteps[b]
        g = gathers[np.int64(b)]
        st = _copy_physics(items[np.int64(b)], g.comp, g.winch, n, dt, blk[b][off:off + n], count[b] * dt, kind,
                           U[b, 0], U[b, 1], res[b])
        if st == K.OK:
            w3a = np.empty(3)
            w3b = np.empty(3)
            w3c = np.empty(3)
            measure_copy(g, refs[b], dt, (count[b] + n) * dt, M[b], w3a, w3b, w3c, blk[b], mblk[b], off + n - 1, n)
            count[b] += n
        else:
            nbad += 1
    return nbad


# typed-List construction and item replacement as cached compiled functions: numba.typed.List's own
# Python-level append/setitem compile (~1.5 s per process for these large tuple types, not cached)
@_numba_njit(cache=True)
def _list_of(item):
    out = _TypedList()
    out.append(item)
    return out


@_numba_njit(cache=True)
def _list_append(lst, item):
    lst.append(item)


@_numba_njit(cache=True)
def _list_set(lst, i, item):
    lst[i] = item


_step_batch = njit(cache=True)(_step_batch_py)
#: (a function of its own: numba's disk cache is keyed by the function's qualified name and source line, so the same
#: function compiled serially and with ``parallel=True`` once shared one cache entry — the "parallel" kernel then
#: loaded the serial code)
_step_batch_parallel = njit(cache=True, parallel=True)(_step_batch_parallel_py)


# ----------------------------------------------------------------------------------------------------
# the stepper
# ----------------------------------------------------------------------------------------------------
class BatchStepper:
    """B Simulator copies advanced together by one compiled call (see the module docstring).

    ``set_copy(i, sim, body, inv_seg)`` (re)installs copy i (call it after ``sim.reset()``/``set_sea``);
    ``refs`` (B, NREF) holds the per-copy reference values the measurement row uses; ``step`` advances.
    ``parallel=True`` loops over copies with ``prange`` (numba threads; ``numba.set_num_threads``)."""

    def __init__(self, num_copies: int, parallel: bool = False):
        if int(num_copies) < 1:
            raise ValueError(f"BatchStepper: num_copies must be >= 1 (got {num_copies!r})")
        B = self.num_copies = int(num_copies)
        self.parallel = bool(parallel)
        self.sims = [None] * B
        self._sig = [None] * B
        self._body = [None] * B
        self._inv_seg = [None] * B
        self._inv_fn = [None] * B
        self._tp = [None] * B
        self.refs = np.zeros((B, NREF))
        self.refs[:, R_TREF] = 1.0
        self.refs[:, R_HALF_STROKE] = 1.0
        self.refs[:, R_VMAX] = 1.0
        self.refs[:, R_MAXSTEPS] = 1.0
        self.M = np.zeros((B, len(MEAS_COLUMNS)))
        self.U = np.zeros((B, 2))
        self._res = np.zeros((B, 4))
        self._nsteps = np.full(B, -1, np.int64)
        self._base = np.zeros(B, np.int64)
        self._end = np.zeros(B, np.int64)
        self._count = np.zeros(B, np.int64)
        self._blk = np.zeros((B, 2 * SPAN, 3))
        self._mblk = np.zeros((B, 2 * SPAN, 4))       # mean track x, y, z and heading of the same steps
        self._filled = np.zeros(B, bool)
        self._py = [None] * B
        self._items = None
        self._gathers = None
        self._entry = None

    # -------------------------------------------------------------- copies
    def set_copy(self, i: int, sim, body: str, inv_seg) -> None:
        """Install ``sim`` as copy i (argument tuples rebuilt only when its arrays changed) and restart its
        tow-point buffer at the simulator's current step. ``body`` is the towed body measured;
        ``inv_seg`` gives 1/breaking load per segment (0 = no limit): an array, or a callable
        ``inv_seg(sim)`` that is called again after each winch remesh (the segment count changes)."""
        dt = float(sim.settings.dt)
        if getattr(self, "_dt", dt) != dt:
            raise ValueError(f"BatchStepper: every copy needs the same physics step (copy {i}: dt = {dt:g} s, "
                             f"others {self._dt:g} s)")
        self._dt = dt
        self.sims[i] = sim
        self._body[i] = body
        self._inv_fn[i] = inv_seg if callable(inv_seg) else None
        self._inv_seg[i] = inv_seg(sim) if callable(inv_seg) else np.asarray(inv_seg, float)
        if self._inv_seg[i].shape != (sim.system.n_segments,):
            raise ValueError(f"BatchStepper.set_copy: inv_seg must have one entry per segment "
                             f"({sim.system.n_segments}), got shape {self._inv_seg[i].shape}")
        self._install(i)
        self._tp[i] = TowPointBuffer(sim)
        self._filled[i] = False
        self._count[i] = sim.step_count
        self._refill(i, sim.step_count + 1, 1)

    def load_row(self, i: int, source: "BatchStepper", j: int) -> None:
        """Copy i's per-copy rows (reference values, measurement row, commands, step count, tow-point buffer) set
        to ``source``'s copy j's. Copy i's Simulator must already hold copy j's state (``Simulator.restore``) and
        follow the same path and sea: the buffer's values are then copy i's own."""
        for name in ("refs", "M", "U", "_res", "_base", "_end", "_count", "_blk", "_mblk", "_filled"):
            getattr(self, name)[i] = getattr(source, name)[j]
        self._install(i)                                # (a no-op unless copy i's arrays were replaced)

    def _install(self, i):
        """(Re)build copy i's kernel tuples if its Simulator's arrays changed since the last install."""
        sim = self.sims[i]
        kd = sim.kernel_data()
        sig = _signature(kd, sim) + (self._inv_seg[i],)
        old = self._sig[i]
        if old is not None and len(old) == len(sig) and all(a is b for a, b in zip(old, sig)):
            return
        item = (kd.head, kd.wave, NO_RECORDING)       # kernels.advance(n, dt, tops, *head, t0, wave, rec)
        gat = gather_arrays(sim, self._body[i], self._inv_seg[i])
        self._py[i] = (item, gat)
        self._sig[i] = sig
        if self._items is not None:
            try:
                _list_set(self._items, i, item)
                _list_set(self._gathers, i, gat)
            except Exception as exc:       # numba typing: every copy's tuples must have one numba type
                raise TypeError(f"BatchStepper: copy {i}'s kernel arguments do not match the other copies' "
                                f"types (different array dtypes/dimensions?): {exc}") from None

    def _lists(self):
        if self._items is None:
            for j, p in enumerate(self._py):
                if p is None and self.sims[j] is not None:      # e.g. after unpickling
                    self._install(j)
            if any(p is None for p in self._py):
                missing = [j for j, p in enumerate(self._py) if p is None]
                raise RuntimeError(f"BatchStepper: install copies {missing} with set_copy first")
            its, gts = _list_of(self._py[0][0]), _list_of(self._py[0][1])
            for j, (item, gat) in enumerate(self._py[1:], 1):
                try:
                    _list_append(its, item)
                    _list_append(gts, gat)
                except Exception as exc:
                    raise TypeError(f"BatchStepper: copy {j}'s kernel arguments do not match copy 0's types "
                                    f"(different array dtypes/dimensions?): {exc}") from None
            self._items, self._gathers = its, gts
        return self._items, self._gathers

    def _refill(self, i, first, n):
        """Make copy i's tow-point buffer cover steps first … first+n−1 (n ≤ BLOCK). The buffer holds two
        consecutive spans of ``SPAN_BLOCKS`` aligned blocks, [base, base + 2·SPAN), base a multiple of BLOCK,
        filled span by span as they are needed (:meth:`TowPointBuffer.span`: the same values as block by block)."""
        base, end = int(self._base[i]), int(self._end[i])
        tp = self._tp[i]
        if not self._filled[i] or first < base or first >= end:
            base = (first // BLOCK) * BLOCK
            self._blk[i, :SPAN], self._mblk[i, :SPAN] = tp.span(base, SPAN_BLOCKS)
            end = base + SPAN
            self._filled[i] = True
        if first + n > end:
            if end == base + 2 * SPAN:                      # shift: the second span becomes the first
                self._blk[i, :SPAN] = self._blk[i, SPAN:]
                self._mblk[i, :SPAN] = self._mblk[i, SPAN:]
                base += SPAN
            self._blk[i, SPAN:], self._mblk[i, SPAN:] = tp.span(base + SPAN, SPAN_BLOCKS)
            end = base + 2 * SPAN
        self._base[i], self._end[i] = base, end

    # -------------------------------------------------------------- stepping
    def step(self, n: int, kind: int, active: np.ndarray | None = None):
        """Advance the active copies (bool mask; default all) by ``n`` physics steps with commands
        ``self.U`` of actuator ``kind``, adding 1 to their ``refs[:, R_STEPS]`` (control steps). Returns
        ``{copy: SimulationDivergence}`` for copies that failed (their row is still measured, at the last
        good state). ``self.M`` holds the measurement rows afterwards (rows of inactive copies untouched).
        The copies must be advanced only through the stepper (``set_copy`` again after changing a
        Simulator directly)."""
        items, gathers = self._lists()
        n = int(n)
        if not 0 <= n <= BLOCK:
            raise ValueError(f"BatchStepper.step: n must be in [0, {BLOCK}] physics steps per call (got {n})")
        ns = self._nsteps
        if active is None:
            ns.fill(n)
        else:
            ns.fill(-1)
            ns[active] = n
        kern = _step_batch_parallel if self.parallel else _step_batch
        args = (items, gathers, ns, 1, self._dt, self._blk, self._mblk, self._base, self._end, self._count, kind,
                self.U, self.refs, self._res, self.M)
        ep = self._entry
        if ep is not None and ep[0] is kern and ep[1] is items and ep[2] is gathers and type(kind) is int:
            nbad = ep[3](*args)
        else:
            nbad = kern(*args)
            self._entry = _entry_point(kern, args, items, gathers)
        failures = {}
        if nbad:
            res = self._res
            need = np.flatnonzero((ns >= 0) & (res[:, 0] == NEED_TOPS))
            if need.size:                    # copies in lockstep cross a block together: one re-run for all
                for i in need:
                    self._refill(int(i), int(self._count[i]) + 1, n)
                ns2 = np.full(self.num_copies, -1, np.int64)
                ns2[need] = n
                kern(items, gathers, ns2, 1, self._dt, self._blk, self._mblk, self._base, self._end, self._count, kind, self.U,
                     self.refs, res, self.M)
            for i in np.flatnonzero((ns >= 0) & (res[:, 0] != K.OK)):
                exc = self._finish_copy(int(i), n, kind)
                if exc is not None:
                    failures[int(i)] = exc
        cnt = self._count
        sims = self.sims
        if active is None:
            for sim, c in zip(sims, cnt.tolist()):         # (a third of the cost of indexing cnt per copy)
                sim.step_count = c
        else:
            for i in np.flatnonzero(active):
                sims[i].step_count = int(cnt[i])
        return failures

    def _finish_copy(self, i, n, kind):
        """Python handling of copy i after a non-OK status: refill its tow points, remesh and continue, or
        build the failure exactly as ``Simulator.advance_steps`` would (``KernelData.remesh`` / ``.divergence``)."""
        res = self._res
        if res[i, 0] == NEED_TOPS:                       # nothing was done yet: refill and run the step
            self._refill(i, int(self._count[i]) + 1, n)
            self._run_one(i, n, kind, 1)
        sim = self.sims[i]
        start = int(self._count[i])
        done = 0
        while True:
            st, k, el, md = int(res[i, 0]), int(res[i, 1]), int(res[i, 2]), float(res[i, 3])
            if st == K.OK:                               # the kernel has advanced _count[i]
                return None
            if st == K.NEED_REMESH:
                done += k + 1
                sim.kernel_data().remesh()
                if self._inv_fn[i] is not None:
                    self._inv_seg[i] = self._inv_fn[i](sim)
                elif self._inv_seg[i].shape != (sim.system.n_segments,):
                    raise ValueError("BatchStepper: a remeshed copy needs inv_seg as a callable (set_copy)")
                self._install(i)
                self._count[i] = start + done
                self._run_one(i, n - done, kind, 0)
                continue
            exc = sim.kernel_data().divergence(st, el, md, (start + done + k + 1) * self._dt)
            self._count[i] = start + done + k
            self._run_one(i, 0, kind, 0)                 # measure the last good state
            return exc

    def _run_one(self, i, n, kind, count_step):
        """Run the kernel for copy i alone (refilling its tow-point buffer if needed)."""
        items, gathers = self._lists()
        ns = np.full(self.num_copies, -1, np.int64)
        ns[i] = n
        for _ in range(2):
            _step_batch(items, gathers, ns, count_step, self._dt, self._blk, self._mblk, self._base, self._end, self._count, kind,
                        self.U, self.refs, self._res, self.M)
            if self._res[i, 0] != NEED_TOPS:
                return
            self._refill(i, int(self._count[i]) + 1, n)
        raise RuntimeError("BatchStepper: tow-point buffer refill failed")      # cannot happen

    def measure(self, i: int) -> np.ndarray:
        """Measure copy i at its current state (no step, no actuator write) into ``self.M[i]``."""
        self._run_one(i, 0, ACT_NONE, 0)
        return self.M[i]

    # -------------------------------------------------------------- pickling
    def __getstate__(self):
        st = self.__dict__.copy()
        st["_items"] = st["_gathers"] = st["_entry"] = None
        st["_sig"] = [None] * self.num_copies
        st["_py"] = [None] * self.num_copies
        return st

    def __setstate__(self, st):
        st.setdefault("_entry", None)      # pickles of earlier versions
        if st["_blk"].shape[1] != 2 * SPAN:      # buffers of another span length: refilled on the next step
            B = st["_blk"].shape[0]
            st["_blk"], st["_mblk"] = np.zeros((B, 2 * SPAN, 3)), np.zeros((B, 2 * SPAN, 4))
            st["_filled"] = np.zeros(B, bool)
            st["_base"], st["_end"] = np.zeros(B, np.int64), np.zeros(B, np.int64)   # the kernel asks for a refill
        self.__dict__.update(st)           # the kernel tuples are rebuilt on first use (see _lists)
