"""``solver.body_derivative_refresh``: the rigid bodies' load derivatives reused across steps (issue 15, "analytic
or reused body derivatives").

On the first Newton iteration of a step the Houbolt kernel estimates, by finite differences of the body loads,
each rigid body's rotational stiffness and damping (which relax the body-angle update) and its translational
damping −∂F/∂v (the tow-point node's implicit damping). Both change the iteration's convergence rate, never the
solution it converges to. With ``body_derivative_refresh = N`` they are computed afresh every N steps and the
kept ones reused in between (``TimeLevels.body_relax``/``body_damp``; N = 1: every step, the kernel before this
setting; the default is 10).

Checked here: the kernel and the numpy twin reuse on the same steps and reach the same states; N = 1 computes
every step (and a scene without rigid bodies is the same for any N, bit for bit); reuse reaches the solution of
N = 1 within what the Newton tolerances let accumulate, with at most a few per cent more iterations; the kept
derivatives travel with snapshots and are dropped where a step is not a continuation (restore without them,
reset, attitude re-chart, failed step: the retry and the sub-steps compute them afresh); a bad value is refused
naming the field.
"""
import numpy as np
import pytest

from helpers import (assert_memory_travels_with_snapshots, assert_same_solution_within_newton_tolerance,
                     kernel_and_twin_step, run_and_record_fish)
from towenv import SceneError
from towenv.core.layout import PS_BODY_AGE, PS_BODY_VALID
from towenv.core.simulator import Simulator, load

SEA = {"sea": {"code": 4, "convention": "coastal", "spectrum": "jonswap", "heading_deg": 165.0, "seed": 13},
       "vessel.model": "coastal_survey", "vessel.excitation": None, "vessel.speed": 3.0}


def _sim(refresh, scene="two_part_tow_1", dt=0.05, extra=None):
    # the nodes' Newton matrices built at every iteration (solver.cable_jacobian_refresh = 1): a step that gives up
    # with reused ones is retried with fresh body derivatives too, which would move the counts checked here
    # (tests/unit/test_cable_jacobian.py covers that reuse)
    ov = dict(SEA) if scene == "two_part_tow_1" else {}
    ov.update({"solver.dt": dt, "solver.body_derivative_refresh": refresh, "solver.cable_jacobian_refresh": 1},
              **(extra or {}))
    return Simulator(load(scene).with_overrides(ov))


def _age(sim):
    return sim.older[6][PS_BODY_VALID], sim.older[6][PS_BODY_AGE]


def test_kernel_and_twin_reuse_on_the_same_steps():
    """12 chained steps with N = 4 from t = 20 s in a sea: the same iterations and states (to 1e-8 of their size)
    from the kernel and the twin, the same age count (fresh on the steps 4 apart), and the kept derivatives equal
    to round-off amplified by the finite differences (1e-6); on reusing steps the kept values are unchanged."""
    sim = _sim(4)
    sim.advance(20.0)
    state = sim
    ages = []
    for k in range(12):
        kept = [np.array(a) for a in sim.older[7:9]]
        state, _, _ = kernel_and_twin_step(sim, state)
        assert np.array_equal(state.older[6], sim.older[6]), k
        for a, b in zip(state.older[7:], sim.older[7:]):
            assert np.max(np.abs(a - b)) <= 1e-6 * max(np.max(np.abs(b)), 1e-30), k
        ages.append(_age(sim)[1])
        if ages[-1] > 1.0:
            for a, b in zip(kept, sim.older[7:9]):
                assert np.array_equal(a, b), k            # reused, not recomputed
    assert ages == [((ages[0] - 1 + k) % 4) + 1 for k in range(12)]
    assert 1.0 in ages


def test_refresh_one_computes_every_step_and_a_cable_only_scene_is_unaffected():
    sim = _sim(1)
    sim.advance(2.0)
    assert _age(sim) == (1.0, 1.0)
    runs = []
    for n in (1, 10):
        sim = _sim(n, scene="peer_deck")
        assert sim.system.n_rigid == 0
        sim.advance(10.0)
        runs.append((sim.hist_r.copy(), sim.tens_hist.copy()))
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


@pytest.mark.parametrize("scene", ["two_part_tow_1", "hover_deep_tow"])
def test_reuse_reaches_the_same_solution(scene):
    """30 s with N = 1 and N = 10. The converged states differ only by what the Newton tolerances (0.5 N +
    1e-5·T, 1e-5 rad per step) let accumulate: tensions by less than the absolute tolerance, positions by
    < 2 mm, angles by < 1e-3 rad; the fish's heave history agrees to 1e-3 of its standard deviation; no step cut,
    and the iterations at most 5 % more (measured +0.4 % two_part_tow_1 in calm water, +1.5 % in sea state 4)."""
    one, ten = (run_and_record_fish(_sim(n, scene)) for n in (1, 10))
    assert_same_solution_within_newton_tolerance(one, ten)
    i1, i10 = one[4], ten[4]
    assert i10 <= 1.05 * i1, (i10, i1)


def test_kept_derivatives_travel_with_snapshots_and_are_dropped_without_one():
    """A snapshot taken mid-cycle (N = 10; step 207 is the 7th of its cycle) continues bit for bit; restored without
    the memory, or reset, the next step computes the derivatives afresh."""
    sim = _sim(10)
    sim.advance_steps(200 + 7)
    assert _age(sim) == (1.0, 7.0)
    assert_memory_travels_with_snapshots(sim, lambda: _sim(10), _age)


def test_a_failed_step_computes_the_derivatives_afresh():
    """N = 1000 (reuse for the whole run) and two Newton iterations allowed: a step needing three fails, is
    retried with fresh derivatives and, failing again, cut into sub-steps. After every such step the kept
    derivatives are a few steps old at most (the retry or the first sub-step computed them), never the run's age."""
    sim = _sim(1000, extra={"solver.max_iterations": 2})
    sim.advance(5.0)
    seen = 0
    for _ in range(400):
        cuts = sim.stats["step_cuts"]
        age_before = _age(sim)[1]
        sim.advance_steps(1)
        if sim.stats["step_cuts"] > cuts:
            seen += 1
            valid, age = _age(sim)
            assert valid == 1.0 and age <= 2 ** sim.settings.max_step_cuts and age < age_before + 1.0
        if seen >= 3:
            break
    assert seen >= 3


def test_an_attitude_rechart_drops_the_kept_derivatives():
    """Re-charting every step (rechart_pitch = 0) drops the kept derivatives before each step: every step
    computes them, and the run equals N = 1's bit for bit."""
    runs = []
    for n in (10, 1):
        sim = _sim(n)
        sim.settings.rechart_pitch = 0.0
        sim.advance(3.0)
        assert sim.stats["recharts"] > 0 and _age(sim) == (1.0, 1.0)
        runs.append((sim.hist_r.copy(), sim.hist_ang.copy(), sim.tens_hist.copy()))
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


@pytest.mark.parametrize("bad", [0, -3, 1001, 2.5, True])
def test_a_bad_refresh_is_refused_naming_the_field(bad):
    """In a scene (schema) and set on a simulator's settings afterwards (checked when the kernel's array is made)."""
    with pytest.raises((SceneError, ValueError), match="body_derivative_refresh"):
        Simulator(load("two_part_tow_1").with_overrides({"solver.body_derivative_refresh": bad}))
    sim = Simulator("two_part_tow_1")
    sim.settings.body_derivative_refresh = bad
    with pytest.raises(ValueError, match=r"solver.body_derivative_refresh: must be an integer within \[1, 1000\]"):
        sim.advance_steps(1)
