"""Explicit integrators on the same model (issue 5 groundwork): agreement at small steps, and detected
failure beyond the axial CFL limit (verification.md V4: MoorDyn RK2 runs at 0.8 ms, fails at 1.6 ms)."""
import numpy as np
import pytest

import towenv
from towenv.core.explicit import ExplicitSimulator

from helpers import peer_deck


@pytest.mark.parametrize("scheme,dt,zeta", [("euler", 8e-4, 0.1), ("rk2", 8e-4, 0.3), ("rk4", 1.6e-3, 0.1)])
def test_explicit_steady_tow_matches_implicit(scheme, dt, zeta):
    imp = towenv.Simulator(peer_deck(speed=2.0, dt=0.05))
    imp.advance(10.0)
    exp = ExplicitSimulator(peer_deck(speed=2.0, dt=dt), scheme=scheme, axial_damping_ratio=zeta)
    exp.advance(10.0)
    assert exp.top_tension == pytest.approx(imp.top_tension, rel=1e-4)
    np.testing.assert_allclose(exp.body_state("ball")["position"], imp.body_state("ball")["position"], atol=1e-3)


@pytest.mark.parametrize("scheme", ["euler", "rk2", "rk4"])
def test_explicit_beyond_cfl_fails_and_is_reported(scheme):
    """At Δt = 3 ms (> l/c_L = 1.1 ms for 5 m segments at c_L = 4472 m/s) every explicit scheme blows up;
    the failure is raised with time, element and cause, and the state stays finite. The implicit
    default runs the same case at 50 ms."""
    sim = ExplicitSimulator(peer_deck(speed=2.0, dt=3e-3), scheme=scheme, axial_damping_ratio=0.1)
    with pytest.raises(towenv.SimulationDivergence) as info:
        sim.advance(5.0)
    assert "explicit" in info.value.cause and info.value.time < 5.0
    imp = towenv.Simulator(peer_deck(speed=2.0, dt=0.05))
    imp.advance(5.0)
    assert np.isfinite(imp.top_tension)


def test_explicit_rejects_bad_options():
    with pytest.raises(ValueError, match="scheme"):
        ExplicitSimulator(peer_deck(), scheme="leapfrog")
    with pytest.raises(ValueError, match="axial_damping_ratio"):
        ExplicitSimulator(peer_deck(), axial_damping_ratio=-1.0)


def test_solver_method_selects_the_integrator():
    """One interface: the scene's solver.method picks Houbolt, generalized-α / Newmark, an explicit scheme or
    the quasi-static sequence; all agree on a steady tow (the quasi-static sequence exactly, the others to 1e-4)."""
    from towenv.core.alpha import AlphaScheme
    from towenv.core.explicit import ExplicitScheme
    from towenv.core.quasistatic import QuasiStaticScheme
    ref = towenv.simulate(peer_deck(speed=2.0, dt=0.05), duration=5.0).top_tension[-1]
    rk4 = towenv.make_simulator(peer_deck(speed=2.0, dt=1.6e-3), method="rk4", axial_damping_ratio=0.1)
    assert isinstance(rk4.scheme, ExplicitScheme) and rk4.scheme.name == "rk4" and type(rk4) is towenv.Simulator
    rk4.advance(5.0)
    assert rk4.top_tension == pytest.approx(ref, rel=1e-4)
    for method in ("generalized_alpha", "newmark"):
        ga = towenv.make_simulator(peer_deck(speed=2.0, dt=0.05), method=method)
        assert isinstance(ga.scheme, AlphaScheme) and ga.scheme.name == method
        ga.advance(5.0)
        assert ga.top_tension == pytest.approx(ref, rel=1e-4)
    qs = towenv.make_simulator(peer_deck(speed=2.0, dt=0.5), method="quasi_static")
    assert isinstance(qs.scheme, QuasiStaticScheme)
    qs.advance(5.0)
    assert qs.top_tension == pytest.approx(ref, rel=1e-6)
    with pytest.raises(towenv.SceneError, match="solver.method"):
        towenv.make_simulator(peer_deck(), method="leapfrog")
    # one factory: towenv.Simulator, make_simulator and the shorthand constructors give the same scheme
    for method in ("houbolt", "rk2", "newmark", "quasi_static"):
        assert towenv.Simulator(peer_deck(method=method)).scheme.name == method
        assert towenv.make_simulator(peer_deck(), method=method).scheme.name == method
    from towenv.core.explicit import ExplicitSimulator
    assert ExplicitSimulator(peer_deck(), scheme="euler").scheme.name == "euler"


def test_as_published_tension_recursion_fails_at_the_thesis_time_step_guide():
    """The thesis's recursion (4.38)–(4.40) as a solver variant. It works where
    s = 2(l/(c_L Δt))² is modest (10 segments at 0.5 ms: s = 40, same answer as the tree solve) but at the
    thesis's own guide Δt = l/(10 c_L) (s ≈ 200) it fails from n = 20 segments, where the default tree
    LDLᵀ is exact (model.md 5.6, erratum E15; measured: non-finite tensions in the first step)."""
    ok = towenv.Simulator(peer_deck(speed=2.0, segments=10, dt=5e-4, tension_solve="as_published"))
    ok.advance(0.05)
    ref = towenv.Simulator(peer_deck(speed=2.0, segments=10, dt=5e-4))
    ref.advance(0.05)
    assert ok.top_tension == pytest.approx(ref.top_tension, rel=1e-6)
    dt = 5.0 / (10 * np.sqrt(2e7))                      # thesis guide for 20 segments of 5 m
    bad = towenv.Simulator(peer_deck(speed=2.0, segments=20, dt=dt, tension_solve="as_published", max_step_cuts=0))
    with pytest.raises(towenv.SimulationDivergence):
        bad.advance(0.01)
    good = towenv.Simulator(peer_deck(speed=2.0, segments=20, dt=dt, max_step_cuts=0))
    good.advance(0.01)
    assert good.top_tension == pytest.approx(ref.top_tension, rel=1e-3)
    with pytest.raises(ValueError, match="single chain"):
        towenv.Simulator(towenv.load_scene("two_part_tow_1").with_overrides(**{"solver.tension_solve": "as_published"}))
