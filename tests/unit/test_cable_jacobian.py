"""``solver.cable_jacobian_refresh``: the free nodes' Newton matrices reused across steps (issue 15, "reuse of drag
Jacobians and node-local inverses ... a modified Newton").

Every Newton iteration of the Houbolt step solves, per free node, M̃ r = M h + (M̃ − M) r* + ½Δt² F with
M̃ = M + (11Δt/12) B + ½Δt² K_g (drag Jacobians, string stiffness) built at the iterate r* and inverted. Only the
rate of the iteration depends on M̃: with ``cable_jacobian_refresh = N`` the matrices (and their inverses) are built
every N steps and the kept ones serve in between (``TimeLevels.node_matrix``/``node_inverse``); a step that needs more
iterations than the one that built them drops them (the next step builds). N = 1 is the kernel before this setting;
the default is 10. A heave compensator's sheave node keeps its vertical drag damping (a rate-only term of its own
law) with them. Not with a series tow's aft tow point: those steps build them always.

Checked here: the kernel and the numpy twin reuse on the same steps and reach the same states; N = 1 builds every
step; reuse reaches the solution of N = 1 within what the Newton tolerances let accumulate, with at most a few per
cent more iterations; the kept matrices travel with snapshots and are dropped where a step is not a continuation;
the scenes it does not apply to build every step; a bad value is refused naming the field.
"""
import numpy as np
import pytest

from helpers import (assert_memory_travels_with_snapshots, assert_same_solution_within_newton_tolerance,
                     kernel_and_twin_step, run_and_record_fish)
from towenv import SceneError
from towenv.core.layout import PS_CABLE_AGE, PS_CABLE_VALID
from towenv.core.simulator import Simulator, load

SEA = {"sea": {"code": 4, "convention": "coastal", "spectrum": "jonswap", "heading_deg": 165.0, "seed": 13},
       "vessel.model": "coastal_survey", "vessel.excitation": None, "vessel.speed": 3.0}


def _sim(refresh, scene="two_part_tow_1", dt=0.05, extra=None):
    ov = dict(SEA) if scene == "two_part_tow_1" else {}
    ov.update({"solver.dt": dt, "solver.cable_jacobian_refresh": refresh}, **(extra or {}))
    return Simulator(load(scene).with_overrides(ov))


def _age(sim):
    return sim.older[6][PS_CABLE_VALID], sim.older[6][PS_CABLE_AGE]


def test_kernel_and_twin_reuse_on_the_same_steps():
    """16 chained steps with N = 4 from t = 20 s in a sea: the same iterations and states (to 1e-8 of their size)
    from the kernel and the twin, the same memory (validity, age, the building step's iterations), the kept matrices
    equal to round-off; each step either builds (age 1: after 4 steps, or after a reusing step needed more iterations
    than the building one) or reuses them unchanged (age + 1); both happen."""
    sim = _sim(4)
    sim.advance(20.0)
    state = sim
    ages = [_age(sim)[1]]
    free = sim.system.node_kind == 0
    for k in range(16):
        kept = [np.array(a) for a in sim.older[9:]]
        due = _age(sim)[0] == 0.0 or _age(sim)[1] >= 4.0
        state, _, _ = kernel_and_twin_step(sim, state)
        assert np.array_equal(state.older[6], sim.older[6]), k
        for a, b in zip(state.older[9:], sim.older[9:]):
            assert np.max(np.abs(a[free] - b[free])) <= 1e-9 * np.max(np.abs(b[free])), k
        age = _age(sim)[1]
        if due:
            assert age == 1.0, k
        else:
            assert age == ages[-1] + 1.0, k
            for a, b in zip(kept, sim.older[9:]):
                assert np.array_equal(a, b), k            # reused, not rebuilt
        ages.append(age)
    assert 1.0 in ages[1:] and max(ages[1:]) >= 3.0


def test_refresh_one_builds_every_step():
    sim = _sim(1)
    sim.advance(2.0)
    assert _age(sim) == (1.0, 1.0)


@pytest.mark.parametrize("scene", ["two_part_tow_1", "hover_deep_tow"])
def test_reuse_reaches_the_same_solution(scene):
    """30 s with N = 1 and N = 10 (two_part_tow_1 in a coastal SS4 sea): final states within what the Newton
    tolerances let accumulate (positions < 2 mm, tensions < 0.5 N, angles < 1e-3 rad, fish heave history within 1e-3
    of its σ; no step cut), and the iterations at most 10 % more (measured: +6.9 % in the sea, none more for
    hover_deep_tow; without the drop after a slower step +11.7 % and the heave 3.5e-3 σ apart)."""
    one, ten = (run_and_record_fish(_sim(n, scene)) for n in (1, 10))
    assert_same_solution_within_newton_tolerance(one, ten)
    assert ten[4] <= 1.10 * one[4], (ten[4], one[4])


@pytest.mark.parametrize("scene,dt", [("peer_deck", 0.05), ("ablow_turn_1km", 0.1)])
def test_reuse_reaches_the_same_solution_on_bare_cables(scene, dt):
    """The cable-only scenes of issue 15's speed goals (the MoorDyn deck, the 1 km turn), 60 s: node positions
    within 2 mm and tensions within the 0.5 N absolute Newton tolerance of N = 1's, no step cut, at most 5 % more
    iterations (measured: none more)."""
    runs = []
    for n in (1, 10):
        sim = _sim(n, scene=scene, dt=dt)
        sim.advance(60.0)
        runs.append((sim.hist_r[0].copy(), sim.tens_hist[0].copy(), sim.stats["mean_iterations"],
                     sim.stats["step_cuts"]))
    (r1, t1, i1, c1), (r10, t10, i10, c10) = runs
    assert c1 == c10 == 0
    assert np.max(np.abs(r1 - r10)) < 2e-3
    assert np.max(np.abs(t1 - t10)) < 0.5
    assert i10 <= 1.05 * i1, (i10, i1)


def test_kept_matrices_travel_with_snapshots_and_are_dropped_without_one():
    """A snapshot taken mid-cycle (N = 10, matrices 2–9 steps old) continues bit for bit; restored without the memory,
    or reset, the next step builds the matrices afresh, and a reset run equals a fresh one."""
    sim = _sim(10)
    sim.advance_steps(200)
    while not (_age(sim)[0] == 1.0 and 2.0 <= _age(sim)[1] <= 9.0):
        sim.advance_steps(1)
    assert_memory_travels_with_snapshots(sim, lambda: _sim(10), _age)


def test_a_failed_step_builds_the_matrices_afresh():
    """N = 1000 (reuse for the whole run) and two Newton iterations allowed: a step needing three fails, is
    retried with fresh matrices and, failing again, cut into sub-steps, each of which builds them (a full Newton, as
    before the setting). After every such step the kept matrices are the last sub-step's (age 1); the run goes on."""
    sim = _sim(1000, extra={"solver.max_iterations": 2})
    sim.advance(5.0)
    seen = 0
    for _ in range(400):
        cuts = sim.stats["step_cuts"]
        age_before = _age(sim)[1]
        sim.advance_steps(1)
        if sim.stats["step_cuts"] > cuts:
            seen += 1
            assert _age(sim) == (1.0, 1.0), age_before
        if seen >= 3:
            break
    assert seen >= 3


def test_a_series_tow_builds_every_step():
    """With a series tow's aft tow point (series_multitow) every step builds the matrices whatever N (age stays 1),
    and the run equals N = 1's bit for bit."""
    runs = []
    for n in (10, 1):
        sim = _sim(n, scene="series_multitow")
        sim.advance(3.0)
        assert _age(sim) == (1.0, 1.0)
        runs.append((sim.hist_r.copy(), sim.tens_hist.copy()))
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


def test_a_compensated_tow_reuses_them_and_reaches_the_same_solution():
    """two_part_coastal_ss4 (a passive heave compensator at the sheave, coastal SS4), 30 s: the matrices are reused
    (the sheave's drag damping kept with them), the compensator's stroke and the fish's state within the Newton
    tolerances of N = 1's (as test_reuse_reaches_the_same_solution), at most 10 % more iterations, no step cut."""
    one, ten = _sim(1, "two_part_coastal_ss4"), _sim(10, "two_part_coastal_ss4")
    strokes, ages = [], []
    for sim in (one, ten):
        z = []
        for _ in range(300):
            sim.advance_steps(2)
            z.append(sim.compensator_state()["stroke"])
            ages.append(_age(sim)[1])
        strokes.append(np.array(z))
    assert max(ages[300:]) > 1.0 and max(ages[:300]) == 1.0       # reused with N = 10, never with N = 1
    assert ten.stats["step_cuts"] == one.stats["step_cuts"] == 0
    assert np.max(np.abs(one.hist_r[0] - ten.hist_r[0])) < 2e-3
    assert np.max(np.abs(one.tens_hist[0] - ten.tens_hist[0])) < 0.5
    assert np.max(np.abs(strokes[0] - strokes[1])) < 1e-3 * np.std(strokes[0])
    assert ten.stats["mean_iterations"] <= 1.10 * one.stats["mean_iterations"]


@pytest.mark.parametrize("bad", [0, -3, 1001, 2.5, True])
def test_a_bad_refresh_is_refused_naming_the_field(bad):
    """In a scene (schema) and set on a simulator's settings afterwards (checked when the kernel's array is made)."""
    with pytest.raises((SceneError, ValueError), match="cable_jacobian_refresh"):
        Simulator(load("two_part_tow_1").with_overrides({"solver.cable_jacobian_refresh": bad}))
    sim = Simulator("two_part_tow_1")
    sim.settings.cable_jacobian_refresh = bad
    with pytest.raises(ValueError, match=r"solver.cable_jacobian_refresh: must be an integer within \[1, 1000\]"):
        sim.advance_steps(1)


def test_a_step_reusing_slow_matrices_gives_up_early():
    """400 steps of two_part_tow_1 in the coastal SS4 sea with N = 10: no attempt runs longer than the full Newton's
    longest step (6 iterations here, with N = 1 too): a reusing step that needs 3 iterations more than the step that
    built its matrices gives up and is retried with fresh ones. (Without that rule one step ran to the 25-iteration
    limit before its retry converged in 4.)"""
    full, reuse = _sim(1), _sim(10)
    full.advance_steps(400)
    reuse.advance_steps(400)
    assert reuse.stats["step_cuts"] == 0
    assert reuse.stats["max_iterations"] <= full.stats["max_iterations"], (reuse.stats, full.stats)
