"""Heave compensator and winch (issue 3): closed-form transfer functions, end stops, payout."""
import math

import numpy as np
import pytest

import towenv
from towenv.verification import closed_forms as cf

from conftest import RHO, peer_deck

M_EFF = 500.0 + RHO * 0.1


def _fit(t, x, omega):
    a = np.stack([np.cos(omega * t), np.sin(omega * t), np.ones_like(t)], axis=1)
    c, s, _ = np.linalg.lstsq(a, x, rcond=None)[0]
    return c - 1j * s


def _comp_deck(omega, k, b, mode="passive", mass=0.0, amplitude=0.2, stroke=20.0):
    period = 2 * math.pi / omega
    d = peer_deck(speed=0.0, dt=min(0.05, period / 100), cda=0.0, tolerance=1e-4, relative_tolerance=0.0)
    d["lines"][0].update(cn=0.0, ct=0.0)
    d["vessel"]["excitation"] = [dict(type="sinusoid", axis="z", amplitude=amplitude, period=period)]
    d["vessel"]["ramp"] = dict(type="half_cosine", duration=period)
    d["compensator"] = dict(mode=mode, stiffness=k, damping=b, mass=mass, stroke=stroke)
    return d, period


@pytest.mark.parametrize("k,b,mass", [(5e3, 2e3, 50.0), (2e4, 5e3, 0.0), (1e5, 1e3, 0.0), (None, None, 0.0)])
@pytest.mark.parametrize("omega", [0.1, 0.5, 1.0, 2.0])
def test_compensator_transfer_functions_match_hover(k, b, mass, omega):
    """V3 / Hover (27), (31)–(34) corrected: body heave and compensator stroke per unit vessel heave
    within 5 % of the closed form (vertical peer deck, no drag, 20 segments), locked included (k = ∞)."""
    locked = k is None
    d, period = _comp_deck(omega, 0.0 if locked else k, 0.0 if locked else b,
                           mode="locked" if locked else "passive", mass=mass)
    sim = towenv.Simulator(d)
    n_rec = 0
    ts, ship, body, stroke = [], [], [], []
    steps = int(round(7 * period / sim.dt))
    every = max(1, steps // 1400)
    for i in range(0, steps, every):
        sim.advance_steps(every)
        if sim.t >= 3 * period:
            ts.append(sim.t)
            ship.append(sim.positions[sim.system.top_node, 2])
            body.append(sim.body_state("ball")["position"][2])
            stroke.append(sim.compensator_state()["stroke"])
            n_rec += 1
    ts = np.array(ts)
    D = _fit(ts, np.array(ship), omega)
    p1 = _fit(ts, np.array(body), omega) / D
    R = _fit(ts, np.array(stroke), omega) / D
    tf = cf.compensator_tf(omega, 100.0, 1.0, 2e7, M_EFF, np.inf if locked else k, 0.0 if locked else b, mass)
    assert abs(p1) == pytest.approx(abs(tf.p1), rel=0.05)
    if locked:
        assert abs(R) < 1e-6
    else:
        assert abs(R) == pytest.approx(abs(tf.R), rel=0.05, abs=0.01)


def test_end_stops_count_hits_and_are_never_penetrated():
    """A soft compensator driven hard hits its end stops: hits are counted, and the stops are rigid
    (exact contact), so the stroke never leaves ±stroke/2 by more than round-off (documented: 1e-9 m)."""
    d, period = _comp_deck(1.0, 2e3, 0.0, stroke=0.4, amplitude=1.0)
    sim = towenv.Simulator(d)
    sim.advance(6 * period)
    st = sim.compensator_state()
    assert st["hits"] >= 2
    assert st["max_penetration"] < 1e-9


def test_compensator_runtime_gains_are_bounded():
    d, _ = _comp_deck(1.0, 2e4, 5e3)
    d["compensator"].update(stiffness_bounds=[1e3, 1e5], damping_bounds=[0.0, 1e4])
    sim = towenv.Simulator(d)
    sim.set_compensator(stiffness=5e4, damping=1e3)
    assert sim.compensator_state()["stiffness"] == 5e4
    with pytest.raises(ValueError, match="compensator.stiffness"):
        sim.set_compensator(stiffness=1e6)
    with pytest.raises(ValueError, match="compensator.mode"):
        sim.set_compensator(mode="magic")
