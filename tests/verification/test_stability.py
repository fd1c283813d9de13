"""Stability boundaries of the solvers (docs/stability.md, scripts/stability_map.py).

Shared deck: the peer deck towed at 2 m/s with a 1 m tow-point heave at 8 s (8 s ramp), 20 segments,
l/c_L = 1.118 ms. Explicit schemes (axial damping ratio 0.25 = MoorDyn BA −0.5) are bounded by the axial
CFL step: measured Δt_max/(l/c_L) = 0.62 (semi-implicit Euler; theory 2(√(1+ζ²) − ζ)/2 = 0.618 for the
highest chain mode's ζ = 0.5), 1.00 (RK2) and 1.29 (RK4) over 5–80 segments and EA ×0.1–×10. Beyond it
they either blow up — detected and raised as SimulationDivergence with time, element and cause — or,
just above it, keep running with a spurious axial ringing in the tension (caught here by a band check
against the reference). The implicit Houbolt scheme runs the same case at 45–900× the CFL step;
generalized-α and Newmark (implicit on the elastic model) far beyond it too, limited by their Newton iteration.
"""
import math

import numpy as np
import pytest

import towenv
from towenv.peer.decks import axial_cfl_step, series_tow, shared_deck

RAMP = dict(type="half_cosine", duration=8.0)
DECK = shared_deck(segments=20, ramp=RAMP)
CFL = axial_cfl_step(DECK)
ZETA = 0.25


def _run(method, dt, duration, window=None, scene=DECK, **kw):
    """(t, top tension, body z) sampled every ~0.02 s; raises SimulationDivergence on failure."""
    if method in ("euler", "rk2", "rk4"):
        kw.setdefault("axial_damping_ratio", ZETA)
    sim = towenv.make_simulator(scene, method=method, dt=dt, **kw)
    k = max(1, int(round(0.02 / dt)))
    n = int(round(duration / dt)) // k
    out = np.empty((n, 3))
    for i in range(n):
        sim.advance_steps(k)
        out[i] = sim.t, sim.top_tension, sim.body_state("ball")["position"][2]
    return out, sim


@pytest.fixture(scope="module")
def reference():
    """Houbolt at Δt = 2 ms (1.8 l/c_L) with a tight Newton tolerance: the accuracy reference."""
    return _run("houbolt", 0.002, 48.0, tolerance=0.05, relative_tolerance=1e-6)[0]


def _stats(rec, t0=24.0):
    m = rec[:, 0] >= t0 - 1e-9
    return 2 * np.std(rec[m, 2]), np.max(rec[m, 1])


def test_axial_cfl_step_of_the_deck():
    assert CFL == pytest.approx(5.0 / math.sqrt(2e7 / 1.0), rel=1e-12)   # l/c_L = 5 m / 4472 m/s


@pytest.mark.parametrize("scheme", ["euler", "rk2", "rk4"])
def test_explicit_beyond_bound_diverges_and_is_reported(scheme):
    """At 2.5 × l/c_L every explicit scheme blows up within a fraction of a second: SimulationDivergence
    names the time, the element and the cause, and the simulator stays at its last good (finite) step."""
    sim = towenv.make_simulator(DECK, method=scheme, dt=2.5 * CFL, axial_damping_ratio=ZETA)
    with pytest.raises(towenv.SimulationDivergence) as info:
        sim.advance(2.0)
    exc = info.value
    assert 0 < exc.time < 1.0
    assert "segment" in exc.element or "node" in exc.element
    assert "explicit" in exc.cause and scheme in exc.cause
    assert f"t = {exc.time:.4f} s" in str(exc)
    assert np.all(np.isfinite(sim.positions)) and np.isfinite(sim.top_tension)
    assert sim.t == pytest.approx(exc.time - 2.5 * CFL, abs=1e-9)


@pytest.mark.parametrize("scheme,ok,bad", [("euler", 0.55, 0.75), ("rk2", 0.9, 1.2), ("rk4", 1.2, 1.6)])
def test_explicit_bound_against_cfl(scheme, ok, bad, reference):
    """Just below its bound a scheme tracks the reference (top tension within 1 % all along); just above
    it the run fails — by divergence or by leaving a 10 % band around the reference tension (an explicit
    scheme can also go wrong without blowing up)."""
    tr = reference
    rec, _ = _run(scheme, ok * CFL, 16.0)
    dev = np.max(np.abs(rec[:, 1] - np.interp(rec[:, 0], tr[:, 0], tr[:, 1]))) / np.max(tr[:, 1])
    assert dev < 0.01
    try:
        rec, _ = _run(scheme, bad * CFL, 16.0)
    except towenv.SimulationDivergence:
        return
    dev = np.max(np.abs(rec[:, 1] - np.interp(rec[:, 0], tr[:, 0], tr[:, 1]))) / np.max(tr[:, 1])
    assert dev > 0.10


def test_reference_is_confirmed_by_an_explicit_scheme(reference):
    """The Houbolt reference and RK4 at 0.5 l/c_L (an independent integrator of the same model) agree on
    the body heave significant amplitude and the top-tension peak over t = 24–48 s within 0.05 %
    (measured +0.023 % and −0.012 %)."""
    rec, _ = _run("rk4", 0.5 * CFL, 48.0)
    (h, p), (h0, p0) = _stats(rec), _stats(reference)
    assert h == pytest.approx(h0, rel=5e-4)
    assert p == pytest.approx(p0, rel=5e-4)


@pytest.mark.parametrize("dt,tol_heave,tol_peak", [
    (0.05, 2e-3, 1e-3),     # 45 × l/c_L   measured −0.061 %, +0.006 %
    (0.2, 1e-2, 5e-3),      # 179 × l/c_L  measured −0.41 %,  +0.10 %
    (1.0, 0.10, 0.05),      # 894 × l/c_L  measured −4.8 %,   +2.8 %  (12 Newton iterations per step)
])
def test_houbolt_stable_far_beyond_the_explicit_bound(dt, tol_heave, tol_peak, reference):
    """Houbolt runs the case on which every explicit scheme fails at 2.5 l/c_L at 45–894 × l/c_L, with
    the accuracy stated: body heave significant amplitude and top-tension peak over t = 24–48 s against the
    2 ms reference. Tolerances are ~2× the measured errors; the error grows as Houbolt's numerical damping
    and period elongation do (model.md 8.1: ≤ 1 % per period needs Δt ≤ T/42 = 0.19 s for the 8 s heave,
    so the 1 s step is a deliberate over-stretch that stays stable)."""
    rec, sim = _run("houbolt", dt, 48.0)
    (h, p), (h0, p0) = _stats(rec), _stats(reference)
    assert sim.stats["step_cuts"] == 0
    assert h == pytest.approx(h0, rel=tol_heave)
    assert p == pytest.approx(p0, rel=tol_peak)
    assert dt / CFL > 40


def test_houbolt_newton_failure_is_reported_and_rescued_by_step_cuts():
    """Series tow with 4 cables solved together (series_multitow + one more cable and fish), with the relaxed
    series coupling (solver.series_coupling = "relaxed": the tails' pull a load inside the Newton loop): at
    Δt = 0.1 s the Newton iteration does not converge. Without step cuts that is a SimulationDivergence naming
    the segment and the Newton cause, the state finite at the last good step; with the default 4 halvings the
    run completes (with cuts). At 0.05 s — where it failed before the body–tail coupling was relaxed
    (kernels.aft_segment_stiffness) — it converges in a few iterations without cuts (measured: at most 3 over
    30 s). The default monolithic coupling runs the same tow at 0.1 s and 0.5 s without cuts (measured: at
    most 2 and 7 iterations a step over 30 s)."""
    sc = series_tow(4).with_overrides({"solver.series_coupling": "relaxed"})
    mono = towenv.Simulator(series_tow(4), dt=0.1, max_step_cuts=0)
    mono.advance(10.0)
    assert mono.stats["step_cuts"] == 0 and mono.stats["max_iterations"] <= 3
    sim = towenv.Simulator(sc, dt=0.1, max_step_cuts=0)
    with pytest.raises(towenv.SimulationDivergence) as info:
        sim.advance(10.0)
    exc = info.value
    assert "Newton" in exc.cause and "segment" in exc.element
    assert exc.iterations == sim.settings.max_iterations
    assert np.all(np.isfinite(sim.positions)) and sim.t == pytest.approx(exc.time - 0.1)
    ok = towenv.Simulator(sc, dt=0.1)
    ok.advance(10.0)
    assert ok.stats["step_cuts"] > 0 and np.isfinite(ok.top_tension)
    small = towenv.Simulator(sc, dt=0.05, max_step_cuts=0)
    small.advance(10.0)
    assert small.stats["max_iterations"] <= 4


@pytest.mark.parametrize("method,dt,tol_heave,tol_peak", [
    ("generalized_alpha", 2.5 * CFL, 1e-3, 2e-3),     # measured +0.029 %, +0.089 %
    ("generalized_alpha", 0.05, 2e-3, 1e-3),          # 45 × l/c_L   measured −0.061 %, +0.001 %
    ("generalized_alpha", 0.2, 1e-2, 1.5e-3),         # 179 × l/c_L  measured −0.39 %,  +0.055 %
    ("newmark", 2.5 * CFL, 1e-3, 1e-3),               # measured +0.026 %, +0.001 %
    ("newmark", 0.1, 4e-3, 1e-3),                     # 89 × l/c_L   measured −0.16 %,  −0.006 %
])
def test_alpha_schemes_stable_beyond_the_explicit_bound(method, dt, tol_heave, tol_peak, reference):
    """The implicit one-step schemes on the elastic model (generalized-α with the default ρ∞ = 0.2, and
    Newmark) run the case on which every explicit scheme fails at 2.5 l/c_L, and far beyond it, with the
    accuracy stated (body heave significant amplitude and top-tension peak over t = 24–48 s against the
    2 ms Houbolt reference; tolerances ~2× the measured errors, which grow with the period error of the
    8 s heave: (ωΔt)²/12 for Newmark, 0.13 % at 0.1 s)."""
    rec, sim = _run(method, dt, 48.0)
    (h, p), (h0, p0) = _stats(rec), _stats(reference)
    assert sim.stats["step_cuts"] == 0
    assert h == pytest.approx(h0, rel=tol_heave)
    assert p == pytest.approx(p0, rel=tol_peak)


@pytest.mark.parametrize("method,dt,scene", [("newmark", 0.2, "deck"), ("generalized_alpha", 0.5, "two_part_tow_1")])
def test_alpha_schemes_newton_limit_is_detected_and_reported(method, dt, scene):
    """Linearly the two schemes are unconditionally stable; their practical limit is the Newton iteration
    on the node positions (a step that rotates the stiff segments makes the linearised axial springs
    overshoot), even with the 4 step halvings: Newmark fails on this deck at 0.2 s (measured at t = 8.2 s;
    generalized-α with ρ∞ = 0.2 runs it at 1 s with step cuts), generalized-α on two_part_tow_1 at 0.5 s
    (t = 10 s; Houbolt runs both). The failure is a SimulationDivergence naming the node, the scheme and the
    Newton cause; the state stays finite at the last good step."""
    sc = DECK if scene == "deck" else towenv.load_scene(scene)
    sim = towenv.make_simulator(sc, method=method, dt=dt)
    with pytest.raises(towenv.SimulationDivergence) as info:
        sim.advance(16.0)
    exc = info.value
    assert "Newton" in exc.cause and method in exc.cause and "4 step halvings" in exc.cause
    assert "node" in exc.element
    assert np.all(np.isfinite(sim.positions)) and np.isfinite(sim.top_tension)
    assert sim.t == pytest.approx(exc.time - dt, abs=1e-9)
    towenv.make_simulator(sc, dt=dt).advance(16.0)
