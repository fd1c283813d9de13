"""``solver.predictor``: the Houbolt step's Newton predictor (issue 15, "a Newton iteration near the cost of its solve").

``"quadratic"`` is the predictor of every kernel before 2026-12-06 (positions and body angles extrapolated from
three time levels, tensions from two); ``"adaptive"`` (the default) keeps one more level and extrapolates a node,
body or segment one order higher in the next step when that would have predicted the step just converged
better. It changes where the Newton iteration starts, not what it converges to.

Checked here: the kernel and the numpy twin make the same choices and reach the same states; the adaptive
predictor converges to the quadratic one's solution (within what the Newton tolerances let accumulate) in fewer
iterations; ``"quadratic"`` never uses the memory (the bit-for-bit check against the pre-chart kernel,
tests/verification/test_attitude.py, runs with it); the memory travels with snapshots and is forgotten where the
time levels stop being a continuation (restore of a snapshot without it, step cuts, attitude re-charts); a bad
value is refused naming the field.
"""
import numpy as np
import pytest

from helpers import assert_same_solution_within_newton_tolerance, kernel_and_twin_step, run_and_record_fish
from towenv.core.layout import PS_HIGHER, PS_VALID
from towenv.core.simulator import Simulator, load

SEA = {"sea": {"code": 4, "convention": "coastal", "spectrum": "jonswap", "heading_deg": 165.0, "seed": 13},
       "vessel.model": "coastal_survey", "vessel.excitation": None, "vessel.speed": 3.0}


def _sim(predictor="adaptive", scene="two_part_tow_1", dt=0.05, extra=None):
    # the nodes' Newton matrices built at every iteration (solver.cable_jacobian_refresh = 1): the single steps
    # chained here have no retry, and a step reusing them may give up for advance to retry it
    # (tests/unit/test_cable_jacobian.py covers the reuse)
    ov = dict(SEA) if scene == "two_part_tow_1" else {}
    ov.update({"solver.dt": dt, "solver.predictor": predictor, "solver.cable_jacobian_refresh": 1}, **(extra or {}))
    return Simulator(load(scene).with_overrides(ov))


def _memory(state):
    return tuple(np.array(a) for a in state.older)


def test_adaptive_predictor_kernel_matches_twin():
    """30 chained steps from t = 20 s in a sea: on every step the kernel and the twin take the same number of
    iterations, reach the same state (to 1e-8 of its size) and choose the same orders for the next step (exactly);
    both orders are in use."""
    sim = _sim()
    sim.advance(20.0)
    state = sim
    higher = lower = 0
    for k in range(30):
        state, _, _ = kernel_and_twin_step(sim, state)
        for a, b in zip(_memory(state)[3:7], _memory(sim)[3:7]):
            assert np.array_equal(a, b), k
        for a, b in zip(_memory(state)[7:], _memory(sim)[7:]):       # the bodies' kept finite-difference derivatives
            assert np.max(np.abs(a - b)) <= 1e-6 * max(np.max(np.abs(b)), 1e-30), k
        for a, b in zip(_memory(state)[:3], _memory(sim)[:3]):
            assert np.max(np.abs(a - b)) <= 1e-8 * max(np.max(np.abs(b)), 1e-30), k
        flags = np.concatenate(_memory(sim)[3:6])
        higher += int(np.sum(flags == 1.0))
        lower += int(np.sum(flags == 0.0))
    assert higher > 0 and lower > 0


@pytest.mark.parametrize("scene", ["two_part_tow_1", "hover_deep_tow"])
def test_adaptive_predictor_reaches_the_same_solution_in_fewer_iterations(scene):
    """30 s with each predictor. The converged states differ only by what the Newton tolerances (0.5 N +
    1e-5·T, 1e-5 rad per step) let accumulate: tensions by less than the absolute tolerance, positions by
    < 2 mm, angles by < 1e-3 rad (measured 60 s: ≤ 0.04 N, 1.3 mm, 2.9e-4 rad over four scenes); the fish's
    heave history agrees to 1e-3 of its standard deviation. The adaptive predictor takes ≤ 0.85× the
    iterations (measured 0.66× two_part_tow_1 in this sea, 0.56× hover_deep_tow)."""
    quadratic, adaptive = (run_and_record_fish(_sim(p, scene)) for p in ("quadratic", "adaptive"))
    assert_same_solution_within_newton_tolerance(quadratic, adaptive)
    iq, ia = quadratic[4], adaptive[4]
    assert ia <= 0.85 * iq, (ia, iq)


def test_quadratic_predictor_keeps_no_memory():
    sim = _sim("quadratic")
    sim.advance(5.0)
    assert all(np.all(a == 0.0) for a in sim.older[:6])
    assert sim.older[6][PS_VALID] == sim.older[6][PS_HIGHER] == 0.0


def test_memory_travels_with_snapshots_and_is_forgotten_without_one():
    sim = _sim()
    sim.advance(10.0)
    assert sim.older[6][PS_VALID] == 1.0
    snap = sim.snapshot()
    sim.advance_steps(40)
    first = sim.hist_r.copy(), sim.tens_hist.copy(), sim.hist_ang.copy()
    sim.restore(snap)
    sim.advance_steps(40)
    for a, b in zip(first, (sim.hist_r, sim.tens_hist, sim.hist_ang)):
        assert np.array_equal(a, b)                 # bit for bit: the memory came back with the snapshot
    import dataclasses
    sim.restore(dataclasses.replace(snap, predictor=None))
    assert sim.older[6][PS_VALID] == 0.0
    sim.reset()
    assert sim.older[6][PS_VALID] == 0.0                  # the initial state has no step behind it
    sim.advance_steps(40)
    fresh = _sim()
    fresh.advance_steps(40)
    assert np.array_equal(fresh.hist_r, sim.hist_r) and np.array_equal(fresh.tens_hist, sim.tens_hist)


def test_a_step_cut_forgets_the_memory():
    """With two Newton iterations allowed, steps that need three are cut into sub-steps with the history
    re-interpolated: the memory does not continue that history, so it is marked invalid after such a step."""
    sim = _sim(extra={"solver.max_iterations": 2})
    sim.advance(5.0)
    seen = 0
    for _ in range(400):
        cuts = sim.stats["step_cuts"]
        sim.advance_steps(1)
        if sim.stats["step_cuts"] > cuts:
            seen += 1
            assert sim.older[6][PS_VALID] == 0.0
        if seen >= 3:
            break
    assert seen >= 3


def test_an_attitude_rechart_forgets_the_memory():
    """Re-charting every step (rechart_pitch = 0) re-expresses the stored angles in a new chart before each step,
    so the memory's older angles never continue them: no node, body or segment is ever extrapolated one order
    higher, and the run equals the quadratic predictor's bit for bit."""
    runs = []
    for p in ("adaptive", "quadratic"):
        sim = _sim(p)
        sim.settings.rechart_pitch = 0.0
        sim.advance(3.0)
        assert sim.stats["recharts"] > 0
        assert np.all(np.concatenate(sim.older[3:6]) == 0.0)
        runs.append((sim.hist_r.copy(), sim.hist_ang.copy(), sim.tens_hist.copy()))
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


def test_a_bad_predictor_is_refused_naming_the_field():
    with pytest.raises(Exception, match="predictor"):
        _sim("cubic")


def test_adaptive_predictor_keeps_houbolts_longest_steps():
    """The stability map's hardest Houbolt cell (shared deck, 80 segments, nominal EA, 8 s half-cosine ramp) at
    Δt = 0.755 s: the quadratic predictor covers the 16 s (~60 Newton iterations and ~20 step halvings along the
    way); the adaptive one, whose higher-order start made a step there fail even after four halvings (diverged at
    t = 10.6 s before the fall-back), must cover it too — a step whose higher-order start fails is taken again
    from the lower orders before it is cut, and its sub-steps start from the lower orders."""
    import towenv
    from towenv.peer.decks import shared_deck
    sc = shared_deck(segments=80, EA_factor=1.0, ramp=dict(type="half_cosine", duration=8.0))
    for p in ("quadratic", "adaptive"):
        sim = towenv.make_simulator(sc, method="houbolt", dt=0.755, predictor=p)
        sim.advance_steps(int(round(16.0 / 0.755)))
        assert sim.stats["step_cuts"] > 0          # the edge of the map: steps are cut there
        assert np.isfinite(sim.top_tension)
