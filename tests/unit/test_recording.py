"""Compiled recording loop of ``simulate`` (towenv.core.recording): bit-identical to the per-record loop."""
import numpy as np
import pytest

import towenv
from towenv.core import kernels as K
from towenv.core import recording
from towenv.core.run import Recorder, simulate
from towenv.core.simulator import Simulator, load

from helpers import peer_deck

SEA = {"sea": {"code": 4, "convention": "coastal", "spectrum": "jonswap", "heading_deg": 180.0, "seed": 1},
       "vessel.model": "coastal_survey", "vessel.excitation": None, "vessel.speed": 2.0}


def _flat(res):
    out = {"t": res.t, "top_force": res.top_force, "top_tension": res.top_tension, "tow_point": res.tow_point}
    for name, d in res.bodies.items():
        out.update({f"bodies.{name}.{k}": v for k, v in d.items()})
    for name, d in res.lines.items():
        out.update({f"lines.{name}.{k}": v for k, v in d.items()})
    out.update({f"actuators.{k}": v for k, v in res.actuators.items()})
    return out


def _state(sim):
    return {"hist_r": sim.hist_r, "hist_ang": sim.hist_ang, "chart": sim.body_chart, "tens_hist": sim.tens_hist,
            "top_react": sim.top_react, "cstate": sim.cstate, "comp": sim.comp, "counters": sim.counters,
            "step_count": np.array(sim.step_count)}


def _assert_identical(ra, rb, a, b):
    fa, fb = _flat(ra), _flat(rb)
    assert fa.keys() == fb.keys()
    bad = [k for k in fa if not np.array_equal(fa[k], fb[k], equal_nan=True)]
    assert not bad, f"records differ: {bad}"
    sa, sb = _state(a), _state(b)
    bad = [k for k in sa if not np.array_equal(sa[k], sb[k])]
    assert not bad, f"final state differs: {bad}"
    assert a.stats == b.stats
    for key in ("steps", "iterations", "duration", "dt"):
        assert ra.meta[key] == rb.meta[key]
    for key in ("end_stop_hits", "max_end_stop_penetration"):
        assert ra.meta.get(key) == rb.meta.get(key)


def _compare(scene, duration, record_interval=None):
    a, b = Simulator(scene), Simulator(scene)
    assert recording.supports(b, Recorder(b, 1))
    ra = simulate(a, duration, record_interval, _compiled=False)
    rb = simulate(b, duration, record_interval)
    _assert_identical(ra, rb, a, b)
    return rb


@pytest.mark.parametrize("case", ["two_part_tow_1", "irregular_3d", "irregular_planar", "series_multitow",
                                  "compensator", "orbital"])
def test_compiled_recording_is_bit_identical(case):
    if case == "two_part_tow_1":                                  # sinusoid excitation, two bodies
        sc, dur, ri = load("two_part_tow_1"), 60.0, None
    elif case == "irregular_3d":                                  # vessel motion in a sea, record every 2 steps
        sc, dur, ri = load("conventional_tow").with_overrides({**SEA, "solver.dt": 0.05}), 60.0, 0.1
    elif case == "irregular_planar":                              # more than one chunk, record every step
        sc, dur, ri = load("conventional_tow").with_overrides({**SEA, "solver.dt": 0.05, "solver.planar": True}), \
            300.0, 0.05
    elif case == "series_multitow":
        sc, dur, ri = load("series_multitow"), 40.0, None
    elif case == "compensator":                                   # passive heave compensator in a sea
        sc, dur, ri = load("two_part_coastal_ss4"), 60.0, None
    else:                                                         # wave orbital velocities on the cable
        sc = load("conventional_tow").with_overrides({**SEA, "solver.dt": 0.1, "sea.orbital_velocities": True})
        dur, ri = 60.0, 0.3
    res = _compare(sc, dur, ri)
    if case == "compensator":
        assert np.ptp(res.actuators["stroke"]) > 0 and np.all(res.actuators["stiffness"] > 0)


def test_partial_last_record_and_odd_interval():
    """A duration that is not a whole number of records: the tail steps are run but not recorded."""
    _compare(load("two_part_tow_1").with_overrides({"solver.dt": 0.1}), 37.3, 0.7)


def test_results_do_not_depend_on_chunking():
    sc = load("conventional_tow").with_overrides({**SEA, "solver.dt": 0.1})
    ref_sim = Simulator(sc)
    ref = simulate(ref_sim, 30.0, 0.2, _compiled=False)
    for cap in (2, 14, 150):
        sim = Simulator(sc)
        rec = Recorder(sim, 151)
        rec.record()
        recording.advance_recorded(sim, rec, 150, 2, max_chunk_steps=cap)
        fa, fb = _flat(ref), _flat(rec.result())
        assert [k for k in fa if not np.array_equal(fa[k], fb[k])] == [], cap
        assert np.array_equal(sim.hist_r, ref_sim.hist_r) and sim.step_count == ref_sim.step_count


@pytest.mark.parametrize("record_interval", [None, 2.0])
def test_divergence_is_the_same(record_interval):
    """A run that fails (series tow at Δt 0.5 s, no step halvings, the relaxed series coupling — the default
    monolithic one runs this case): same error, same last good state and counters, whether the failing step
    ends a record or falls inside one (record every 4 steps)."""
    sc = load("series_multitow").with_overrides({"solver.dt": 0.5, "solver.max_step_cuts": 0,
                                                 "solver.series_coupling": "relaxed"})
    errs, sims = [], []
    for compiled in (False, True):
        sim = Simulator(sc)
        with pytest.raises(towenv.SimulationDivergence) as ei:
            simulate(sim, 120.0, record_interval, _compiled=compiled)
        errs.append(ei.value)
        sims.append(sim)
    a, b = errs
    assert (a.time, a.element, a.cause, a.iterations, a.residual) == (b.time, b.element, b.cause, b.iterations,
                                                                     b.residual)
    assert str(a) == str(b)
    sa, sb = _state(sims[0]), _state(sims[1])
    assert all(np.array_equal(sa[k], sb[k]) for k in sa)
    assert sims[0].stats == sims[1].stats
    assert sims[1].t < a.time


def test_divergence_keeps_the_records_before_it():
    sc = load("series_multitow").with_overrides({"solver.dt": 0.5, "solver.max_step_cuts": 0,
                                                 "solver.series_coupling": "relaxed"})
    sim = Simulator(sc)
    rec = Recorder(sim, 100)
    rec.record()
    with pytest.raises(towenv.SimulationDivergence) as ei:
        recording.advance_recorded(sim, rec, 99, 4)
    assert rec.n >= 2 and rec.t[rec.n - 1] <= ei.value.time - 0.5
    res = rec.result()
    assert len(res.t) == rec.n and np.all(np.isfinite(res.top_tension))


def test_winch_scene_uses_the_per_record_loop():
    d = peer_deck(speed=2.0, dt=0.05)
    d["winch"] = dict(speed=1.0, max_speed=1.0, max_acceleration=0.2, min_length=50.0, max_length=200.0)
    sim = Simulator(d)
    assert not recording.supports(sim, Recorder(sim, 1))
    res = simulate(sim, 40.0)
    assert getattr(sim, "remesh_count", 0) > 0
    assert res.actuators["deployed_length"][-1] > 130.0
    assert len(res.t) == 801 and np.all(np.isfinite(res.top_tension))


def test_other_solvers_use_the_per_record_loop():
    from towenv.core.run import make_simulator
    sim = make_simulator(peer_deck(speed=1.0, dt=0.05), method="generalized_alpha")
    assert not recording.supports(sim, Recorder(sim, 1))
    res = simulate(sim, 1.0)
    assert len(res.t) == 21


def test_progress_bar_counts_every_step(monkeypatch):
    pytest.importorskip("tqdm")
    import tqdm
    totals = []

    class Bar:
        def __init__(self, total, **kw):
            self.total, self.n = total, 0

        def update(self, k):
            self.n += k

        def close(self):
            totals.append((self.total, self.n))

    monkeypatch.setattr(tqdm, "tqdm", Bar)
    sim = Simulator("two_part_tow_1")
    simulate(sim, 10.03, 0.1, progress=True)
    n = int(round(10.03 / sim.dt))
    assert n % 5 and totals == [(n, n)] and sim.step_count == n


def test_meta_reports_wall_time():
    res = simulate("two_part_tow_1", 5.0)
    assert res.meta["wall_time_s"] > 0 and res.meta["real_time_factor"] > 0 and res.meta["steps"] > 0


def test_recording_and_plain_steps_share_one_compiled_advance():
    """Issue 15 (first use): the recorded run and ``advance_steps`` call the same ``kernels.advance`` with a
    Recording of the same numba type (``model.NO_RECORDING`` when not recording), so the kernel compiles once —
    a second type (another dtype or layout of a record array) would compile the whole step again."""
    import numba

    from towenv.core.model import NO_RECORDING
    simulate("two_part_tow_1", 2.0)
    sim = towenv.Simulator("two_part_tow_1")
    sim.advance(0.5)
    rec_types = {sig[-1] for sig in K.advance.signatures}
    assert rec_types == {numba.typeof(NO_RECORDING)}


def test_warm_up_compiles_before_the_clock_without_advancing():
    """Issue 15 (first use): simulate() compiles or loads the kernels before its clock and progress bar start
    (the summary's real-time factor then measures the simulation only); the warm-up calls record and advance
    nothing, so results are unchanged."""
    sim = towenv.Simulator("two_part_coastal_ss4")
    rec = Recorder(sim, 20)
    rec.record()
    before = [a.copy() for a in (sim.hist_r, sim.hist_ang, sim.tens_hist, sim.top_react, sim.counters)]
    recording.warm_up(sim, rec, 5)
    sim.scheme.warm_up()
    assert K.advance.signatures
    after = (sim.hist_r, sim.hist_ang, sim.tens_hist, sim.top_react, sim.counters)
    assert all(np.array_equal(a, b) for a, b in zip(before, after)) and rec.n == 1 and sim.step_count == 0
    a = simulate("two_part_coastal_ss4", duration=3.0)
    b = simulate("two_part_coastal_ss4", duration=3.0, _compiled=False)
    np.testing.assert_array_equal(a.top_tension, b.top_tension)
    np.testing.assert_array_equal(a.tow_point, b.tow_point)
    assert a.meta["real_time_factor"] > 0


