"""Static and steady-tow verification of the simulator against closed forms (verification.md V1, V7)."""
import math

import numpy as np
import pytest

import towenv
from towenv.verification import closed_forms as cf

from helpers import G, RHO, peer_deck

W = (1.0 - RHO * math.pi * 0.01 ** 2) * G            # peer cable wet weight per metre
WB = (500.0 - RHO * 0.1) * G                          # peer body wet weight


@pytest.mark.parametrize("segments", [1, 7, 20])
def test_vertical_hang_top_reaction_and_segment_tensions(segments):
    """V1: the top reaction equals W_b + wL exactly (any N); segment i carries the midpoint tension."""
    sim = towenv.Simulator(peer_deck(segments=segments))
    sim.advance(20.0)
    top = W * 100.0 + WB
    # the lumped model reproduces the statics exactly; 1e-6 leaves room for the Newton tolerance
    assert sim.top_tension == pytest.approx(top, rel=1e-6)
    mid = cf.segment_midpoint_tensions(W, 100.0, WB, segments)[::-1]      # top first
    np.testing.assert_allclose(sim.line_state("cable")["tensions"], mid, rtol=1e-6)
    # node tensions without the half-segment bias: exact at every node, body end included
    nodes = sim.node_tensions("cable")
    s_nodes = np.linspace(100.0, 0.0, segments + 1)
    np.testing.assert_allclose(nodes, WB + W * s_nodes, rtol=1e-6)


@pytest.mark.parametrize("speed", [0.5, 1.0, 2.0, 3.0])
def test_steady_tow_matches_independent_ode(speed):
    """V7: settled tow of the peer deck vs the steady cable ODE (DOP853): tension and body position
    within 0.1 % (the target verification.md sets; the lumped discretisation error at 20 segments is
    ~1e-5 here, so the test does not hinge on the tolerance)."""
    ref = cf.steady_tow_ode(100.0, speed, W, 2e7, D=0.02, Cn=1.2, Ct_dl=0.01 * math.pi, rho=RHO, CdA=0.5, W_b=WB)
    sim = towenv.Simulator(peer_deck(speed=speed, dt=0.05))
    sim.advance(60.0)
    body = sim.body_state("ball")["position"]
    tow = sim.positions[sim.system.top_node]
    assert sim.top_tension == pytest.approx(ref.top_tension, rel=1e-3)
    assert tow[0] - body[0] == pytest.approx(ref.body_behind, abs=0.1)      # 0.1 % of L
    assert tow[2] - body[2] == pytest.approx(ref.body_below, abs=0.1)
    f = sim.top_force
    angle = math.degrees(math.atan2(-f[2], -f[0]))
    assert angle == pytest.approx(ref.top_angle_deg, abs=0.05)


@pytest.mark.parametrize("speed", [1.0, 2.0, 3.0])
def test_bare_cable_critical_angle(speed):
    """V7: a 1 km bare cable with a negligible end body settles at the critical angle within 0.2°."""
    d = peer_deck(speed=speed, segments=50, dt=0.05, cda=0.01)
    d["lines"][0]["length"] = 1000.0
    d["bodies"][0].update(mass=10.0, volume=0.0)
    sim = towenv.Simulator(d)
    sim.advance(5.0)
    phi_c = cf.critical_angle(W, RHO, 1.2, 0.02, speed)
    pos = sim.line_state("cable")["positions"]
    # straight part far from the body: the top 40 % of the cable
    seg = pos[0] - pos[20]
    angle = math.degrees(math.atan2(seg[2], -seg[0] if seg[0] < 0 else seg[0]))
    assert abs(abs(angle) - phi_c) < 0.2


def test_static_start_is_already_in_equilibrium():
    """The quasi-static start is the discrete equilibrium: a steady tow does not move when stepped."""
    sim = towenv.Simulator(peer_deck(speed=2.0, dt=0.05))
    r0 = sim.positions.copy()
    sim.advance(10.0)
    drift = sim.positions - r0 - np.array([2.0 * sim.t, 0.0, 0.0])
    assert np.abs(drift).max() < 1e-4


def test_elastic_catenary_end_forces():
    """V2: peer cable between an anchor at the origin and a fixed top at (80, 0, 40) m, settled
    dynamically from a straight start. End reactions vs Irvine's elastic catenary.

    The lumped model's end-force error is O(1/N²): measured −4.9e-4, −1.2e-4, −3.3e-5 at N = 20, 40, 80
    (MoorDyn: −4.4e-4, −8.4e-5, +7e-6, verification.md V2). The issue's 1e-4 at 20 segments is
    therefore not reachable by a lumped-mass model; we check 1e-3 at N = 20 and 1e-4 at N = 80."""
    ref = cf.elastic_catenary(100.0, W, 2e7, 80.0, 40.0)
    for segments, tol, settle in ((20, 1e-3, 300.0), (80, 1e-4, 700.0)):
        d = peer_deck(segments=segments, dt=0.05, tolerance=1e-5, relative_tolerance=0.0)
        d["vessel"]["tow_point"] = [80.0, 0.0, 40.0]
        d["lines"][0]["bottom"] = {"anchor": [0.0, 0.0, 0.0]}
        d["bodies"] = []
        sim = towenv.Simulator(d)
        sim.advance(settle)
        assert sim.top_tension == pytest.approx(ref.T_top, rel=tol)
        assert np.linalg.norm(sim.anchor_force("cable")) == pytest.approx(ref.T_bottom, rel=tol)
        # node tensions (no half-segment bias) follow T(s) of the closed form
        s_nodes = np.linspace(100.0, 0.0, segments + 1)[1:-1]
        np.testing.assert_allclose(sim.node_tensions("cable")[1:-1], ref.T(s_nodes), rtol=2 * tol)
