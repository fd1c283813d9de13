"""Heave compensator and winch (issue 3): closed-form transfer functions, end stops, payout."""
import math

import numpy as np
import pytest

import towenv
from towenv.verification import closed_forms as cf

from helpers import RHO, peer_deck

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
        assert abs(R) == pytest.approx(abs(tf.R), rel=0.05)


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


def _winch_deck(dt):
    d = peer_deck(speed=2.0, dt=dt)
    d["winch"] = dict(speed=0.0, max_speed=1.0, max_acceleration=0.2, min_length=50.0, max_length=200.0)
    return d


def _payout_cycle(dt):
    """Pay out 100 → ≥150 m at 1 m/s under tow, stop, haul back to ≤100 m. Returns the simulator,
    the top-tension record (every step) and the largest per-step top-tension change at a remesh."""
    sim = towenv.Simulator(_winch_deck(dt))
    sim.advance(5.0)
    tens = []
    jumps = []

    def run(cond):
        while cond():
            before = getattr(sim, "remesh_count", 0)
            t_prev = sim.top_tension
            sim.advance_steps(1)
            tens.append(sim.top_tension)
            if getattr(sim, "remesh_count", 0) != before:
                jumps.append(abs(sim.top_tension - t_prev) / t_prev)

    sim.set_winch(speed=1.0)
    run(lambda: sim.winch_state()["length"] < 150.0)
    sim.set_winch(speed=0.0)
    run(lambda: abs(sim.winch_state()["speed"]) > 0.0)
    peak = max(tens)
    sim.set_winch(speed=-1.0)
    run(lambda: sim.winch_state()["length"] > 100.0)
    sim.set_winch(speed=0.0)
    run(lambda: abs(sim.winch_state()["speed"]) > 0.0)
    return sim, peak, jumps


def test_winch_payout_and_haul_in_conserve_mass_and_match_fine_step():
    """Payout 100 → 150 m and back under tow: nodes are inserted and removed at the top, the cable mass
    in the water equals μ·(L₀ + paid out) to 1e-9 relative, the peak top tension during payout agrees
    with a Δt/4 reference within 2 %, and an insertion/removal changes the top tension by < 1 % per step."""
    sim, peak, jumps = _payout_cycle(0.05)
    st = sim.winch_state()
    assert getattr(sim, "remesh_count", 0) >= 18 and st["segments"] in (19, 20, 21)
    mass = float((sim.system.mu * sim.system.l0).sum())
    assert mass == pytest.approx(1.0 * (100.0 + st["paid_out"]), rel=1e-9)
    assert st["length"] == pytest.approx(100.0 + st["paid_out"], rel=1e-9)
    _, peak_ref, _ = _payout_cycle(0.0125)
    assert peak == pytest.approx(peak_ref, rel=0.02)
    assert jumps and max(jumps) < 0.01


def test_constant_tension_winch_pays_out_above_set_tension():
    d = _winch_deck(0.05)
    d["winch"].update(mode="constant_tension", set_tension=4000.0, gain=1e-3)
    sim = towenv.Simulator(d)
    sim.advance(20.0)
    assert sim.winch_state()["paid_out"] > 0.5          # tension ~4.6 kN > 4 kN: pays out
    d["winch"].update(set_tension=5500.0)
    sim = towenv.Simulator(d)
    sim.advance(20.0)
    assert sim.winch_state()["paid_out"] < -0.5         # below the set tension: hauls in


def test_active_position_mode_follows_command_with_lag_and_rate_limit():
    """Active sheave-position mode: first-order lag τ and rate limit on the commanded stroke."""
    d, _ = _comp_deck(1.0, 0.0, 0.0, mode="position", amplitude=0.0)
    d["compensator"].update(actuator_time_constant=0.5, rate_limit=0.2)
    sim = towenv.Simulator(d)
    sim.set_compensator(command=0.5)
    sim.advance(1.0)
    z1 = sim.compensator_state()["stroke"]
    assert z1 == pytest.approx(0.2 * 1.0, abs=0.011)          # rate-limited ramp: 0.2 m/s
    sim.advance(10.0)
    assert sim.compensator_state()["stroke"] == pytest.approx(0.5, abs=1e-3)   # settled on the command


def test_active_force_mode_moves_the_sheave_by_force_over_stiffness():
    """Force mode adds the (lagged) commanded force to the passive law: a static extra force F on a
    spring k moves the sheave by F/k."""
    d, _ = _comp_deck(1.0, 2e4, 2e4, mode="force", amplitude=0.0)
    d["compensator"].update(rate_limit=1e4)             # N/s in force mode
    sim = towenv.Simulator(d)
    sim.set_compensator(command=2000.0)
    sim.advance(60.0)
    assert sim.compensator_state()["stroke"] == pytest.approx(2000.0 / 2e4, rel=0.02)


def test_winch_respects_length_limits():
    d = _winch_deck(0.05)
    d["winch"].update(max_length=104.0, min_length=98.0)
    sim = towenv.Simulator(d)
    sim.set_winch(speed=1.0)
    sim.advance(30.0)
    assert sim.winch_state()["length"] == pytest.approx(104.0, abs=1e-9)
    sim.set_winch(speed=-1.0)
    sim.advance(30.0)
    assert sim.winch_state()["length"] == pytest.approx(98.0, abs=1e-9)
    with pytest.raises(ValueError, match="winch.speed"):
        sim.set_winch(speed=5.0)
