"""MoorDyn v2 as a code-to-code cross-check on the verification peer deck (verification.md).

The input-file translation is checked without MoorDyn; the runs are skipped when the optional ``peer``
extra (moordyn) is missing.
"""
import math
import sys

import numpy as np
import pytest

import towenv
from towenv.peer import moordyn_input, require_moordyn
from towenv.peer.moordyn_runner import MoorDynUnsupported, towenv_axial_damping_ratio

from helpers import G, RHO, peer_deck


def test_input_file_translates_the_deck():
    """LINE TYPES row: D, μ, EA, BA = −ζ, EI = 0, C_n, C_an, CdAx = C_t/π (towenv's C_t is on D·l), C_at;
    a Coupled tow point and a Free body point with the body's mass, volume, CdA and C_a."""
    text = moordyn_input(peer_deck(), dtM=4e-4, scheme="RK4", zeta=0.5)
    rows = text.splitlines()
    cable = next(r for r in rows if r.startswith("cable")).split()
    assert [float(v) for v in cable[1:]] == pytest.approx([0.02, 1.0, 2e7, -0.5, 0.0, 1.2, 1.0, 0.01, 0.0])
    coupled = next(r for r in rows if "Coupled" in r).split()
    free = next(r for r in rows if "Free" in r).split()
    assert [float(v) for v in coupled[2:5]] == [0.0, 0.0, 0.0]
    assert [float(v) for v in free[5:]] == pytest.approx([500.0, 0.1, 0.5, 1.0])
    line = next(r for r in rows if r.split()[:2] == ["1", "cable"]).split()
    assert (float(line[4]), int(line[5])) == (100.0, 20)
    opts = {r.split()[1]: r.split()[0] for r in rows if len(r.split()) > 1 and r.split()[1] in
            ("dtM", "tScheme", "WtrDnsty", "g", "WtrDpth")}
    assert (float(opts["dtM"]), opts["tScheme"], float(opts["WtrDnsty"]), float(opts["g"])) == (4e-4, "RK4", RHO, G)
    assert float(opts["WtrDpth"]) >= 1000.0            # no seabed contact
    # MoorDyn BA = -ζ gives ζ l √(EA μ) N·s; towenv's explicit damping ratio ζ' gives 2 ζ' l √(EA μ)
    assert towenv_axial_damping_ratio(1.0) == 0.5


def test_unsupported_scenes_are_refused():
    with pytest.raises(MoorDynUnsupported, match="lines"):
        moordyn_input("two_part_tow_1")
    with pytest.raises(MoorDynUnsupported, match="sea-state"):
        moordyn_input(towenv.load_scene("two_part_coastal_ss4"))


def test_missing_moordyn_gives_an_install_hint(monkeypatch):
    monkeypatch.setitem(sys.modules, "moordyn", None)
    with pytest.raises(ImportError, match="peer"):
        require_moordyn()


def test_vertical_hang_reaction_agrees_with_moordyn():
    """V1: the Step reaction of MoorDyn's static hang and towenv's top reaction both equal W_b + wL
    (4563.02 N) to 1e-6 — and each other."""
    pytest.importorskip("moordyn")
    from towenv.peer import run_moordyn
    w = (1.0 - RHO * math.pi * 0.02 ** 2 / 4) * G
    exact = (500.0 - RHO * 0.1) * G + w * 100.0
    md = run_moordyn(peer_deck(), 10.0, dtM=1e-3, scheme="RK4", zeta=0.5, dt_coupling=0.1)
    assert md.failed is None
    sim = towenv.Simulator(peer_deck())
    sim.advance(10.0)
    t_md, t_tw = md.top_tension[-1], sim.top_tension
    assert t_md == pytest.approx(exact, rel=1e-6)
    assert t_tw == pytest.approx(exact, rel=1e-6)
    assert t_md == pytest.approx(t_tw, rel=1e-6)
    # MoorDyn's force is the force of the cable on the ship: straight down
    np.testing.assert_allclose(md.top_force[-1], [0.0, 0.0, -exact], rtol=1e-6, atol=1e-6 * exact)


def test_steady_tow_tension_agrees_with_moordyn():
    """V7 at 2 m/s: MoorDyn settled for 300 s of towing (RK2, dtM = 0.9 ms, ζ = 0.5) and towenv's steady
    start agree within 0.1 % in top tension (measured 0.02 %: 4600.8 vs 4601.8 N; the ODE gives 4601.9 N)
    and within 0.1 % of L in body position (measured ~1 cm)."""
    pytest.importorskip("moordyn")
    from towenv.peer import run_moordyn, settled_state
    deck = peer_deck(speed=2.0)
    state, info = settled_state(deck, settle_time=300.0, dtM=9e-4, scheme="RK2", zeta=0.5, dt_coupling=0.1)
    sim = towenv.Simulator(deck)
    assert info["top_tension"] == pytest.approx(sim.top_tension, rel=1e-3)
    assert sim.top_tension == pytest.approx(4601.9, rel=1e-4)
    md = run_moordyn(deck, 1.0, dtM=9e-4, scheme="RK2", zeta=0.5, dt_coupling=0.1, initial_state=state)
    sim.advance(1.0)
    assert md.failed is None
    assert md.top_tension[-1] == pytest.approx(sim.top_tension, rel=1e-3)
    np.testing.assert_allclose(md.body_position[-1], sim.body_state("ball")["position"], atol=0.1)


def test_deck_builders_accept_every_solver_key():
    """``shared_deck`` / ``series_tow`` keyword overrides reach ``[solver]`` for every solver field
    (``rho_inf`` was missing from a hand-written list)."""
    from towenv.peer.decks import SOLVER_KEYS, series_tow, shared_deck
    assert {"rho_inf", "planar", "dt", "axial_damping_ratio"} <= set(SOLVER_KEYS)
    sc = shared_deck(segments=8, rho_inf=0.5, dt=0.01, method="generalized_alpha")
    assert (sc.solver.rho_inf, sc.solver.dt, sc.solver.method) == (0.5, 0.01, "generalized_alpha")
    assert series_tow(2, rho_inf=0.7).solver.rho_inf == 0.7
